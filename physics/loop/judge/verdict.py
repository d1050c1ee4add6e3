"""The loop's verdict (:func:`verdict`): an effect named; an *unexplained residual*, where no
candidate passes the null test but the held-out records keep what the declared model cannot
explain; or nothing. And the figure of the unexplained entries (:func:`unexplained_figure`).

What the model cannot explain is looked for in two places:

- **signature entries** (:func:`unexplained_entries`): each group's held-out residual per
  entry against what the model discrepancy allows on clean records. Under the discrepancy model
  (:func:`~physics.loop.model.discrepancy.discrepancy_sd`: a Gaussian offset of sd ``d`` per entry,
  noise of sd ``sd``) a record's residual over ``sqrt(d^2 + sd^2)`` is standard normal; an
  entry is unexplained where it exceeds the upper ``rate / (2 N)`` quantile of the normal in
  every held-out record of the group with one sign, ``N`` the entries of all groups
  (Bonferroni; a residual in dB of a line near the noise is heavy-tailed, one record alone can
  lie far out, so the entry must persist as the lines must). With a reference (a sister
  unit's clean records or this unit's first ones) the discrepancy is the reference records',
  about their mean (:meth:`physics.loop.search.form_error.FormReference.judging`): the declared
  model's scatter on clean records of the gearbox type. Without one it is the bundle's own
  train records', where an effect present in all of them raises its family's and is not found
  here (it cannot be told from form error on these records).
- **spectral lines** no declared order explains (:mod:`physics.loop.judge.lines`), in every record.

The candidates that came closest are the first three by held-out error, each with the null
test's conditions.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from physics.files import atomic_write, pyplot
from physics.loop.judge.lines import record_spectrum, unexplained_lines
from physics.loop.measured.records import Records, by_group, shaft_rates
from physics.loop.model.comparison import residuals_db
from physics.signals.order_analysis import band_edges, line_frequencies

#: what a loop can say; ``not_judged``: the run stopped in its first round, before any
#: candidate was judged (:func:`physics.loop.bundle_loop.first_round_partial`)
VERDICTS = ("effect", "unexplained_residual", "none", "not_judged")
#: candidates reported as closest beside an unexplained residual
CLOSEST = 3


def entry_kind(name: str) -> str:
    """What a signature entry is: a mesh harmonic, a pinion or gear sideband, a shaft order, a
    band or a statistic."""
    if re.fullmatch(r"line_mesh\d+", name):
        return "mesh harmonic"
    if name.startswith("line_mesh"):
        return "gear sideband" if name.endswith("g") else "pinion sideband"
    if name.startswith("line_shaft"):
        return "shaft order"
    return "band" if name.startswith("band") else "statistic"


def _where(name: str, f1: float, f2: float, z1: int, fs: float) -> dict:
    """The frequency [Hz] and pinion order of a line entry, the edges of a band's."""
    if name.startswith("line_"):
        f = line_frequencies(f1, f2, z1, fs)[name[5:]]
        return {"frequency_hz": f, "order": f / f1}
    if name.startswith("band"):
        edges = band_edges(z1 * f1, fs)
        i = int(name[4:])
        return {"band_hz": [float(edges[i]), float(edges[i + 1])]}
    return {}


def unexplained_entries(judged: Records, idx: np.ndarray, signals: list[np.ndarray],
                        rate: float) -> dict[str, list[dict]]:
    """Per group label, the signature entries whose held-out residual (records ``idx``, model
    ``signals``) the discrepancy does not allow at false-alarm ``rate`` in any of the group's
    held-out records (module text), largest first: entry, kind, mean residual [dB], z (the
    median over the records of the residual over its allowed scatter), its bound, and where the
    entry lies."""
    from scipy.stats import norm  # imported on first use: a refusal need not wait for it
    res = residuals_db(judged, idx, signals)
    pos = by_group(judged, idx)
    n = sum(len(judged.groups[k].names) for k in pos)
    crit = float(norm.isf(rate / (2 * max(n, 1))))
    out = {}
    for k, mine in pos.items():
        g = judged.groups[k]
        r = np.array([res[j] for j in mine])
        z = r / g.sd
        beyond = np.all(z > crit, axis=0) | np.all(z < -crit, axis=0)
        scn = judged.scenarios[g.records[0]]
        f1, f2 = shaft_rates(scn)
        hits = [{"entry": g.names[e], "kind": entry_kind(g.names[e]),
                 "residual_db": float(r[:, e].mean()), "z": float(np.median(z[:, e])),
                 "bound_z": crit, "allowed_db": float(crit * g.sd[e]),
                 **_where(g.names[e], f1, f2, scn.gear.z1, g.key[3])}
                for e in np.flatnonzero(beyond)]
        if hits:
            out[g.label] = sorted(hits, key=lambda h: -abs(h["z"]))
    return out


def group_lines(rec: Records, rate: float) -> dict[str, list[dict]]:
    """Per group label, the measured records' persistent lines that no declared order explains
    (:func:`physics.loop.judge.lines.unexplained_lines`; all the group's records, no model)."""
    out = {}
    for g in rec.groups:
        scn = rec.scenarios[g.records[0]]
        f1, f2 = shaft_rates(scn)
        xs = [rec.bundle.signals[rec.bundle.records[i]] for i in g.records]
        found = unexplained_lines(xs, g.key[3], f1, f2, scn.gear.z1, rate, len(rec.groups))
        if found:
            out[g.label] = found
    return out


def closest(ranking: list, checks: list[dict]) -> list[dict]:
    """The first :data:`CLOSEST` candidates by held-out error with the null test's
    conditions (value, bound, held)."""
    return [{"effect": c.name, "option": c.option, "heldout_error": c.heldout,
             "checks": ch} for c, ch in list(zip(ranking, checks, strict=True))[:CLOSEST]]


def judge(adopted: bool, entries: dict, lines: dict, near: list[dict]
            ) -> tuple[str, dict | None]:
    """The verdict and, for an unexplained residual, where it lives: per group its entries and
    lines, and the candidates that came closest (``near``)."""
    if adopted:
        return "effect", None
    if not entries and not lines:
        return "none", None
    groups = {label: {"entries": entries.get(label, []), "lines": lines.get(label, [])}
              for label in dict.fromkeys([*entries, *lines])}
    return "unexplained_residual", {"groups": groups, "closest": near}


def summary_line(r: dict) -> str:
    """The verdict as the report's first sentence."""
    v = r.get("verdict")
    if v == "effect":
        return f"**Verdict: effect named** ({r['chosen_effect']})."
    if v != "unexplained_residual":
        if r.get("form_reference"):
            return ("**Verdict: none.** No candidate passes the null test and the held-out "
                    "records keep nothing beyond what the model discrepancy allows on the clean "
                    "reference records, and no spectral line that no declared order explains.")
        if r.get("mode") != "bundle":
            return "**Verdict: none.** No candidate passes the null test on the table's rows."
        return ("**Verdict: none.** No candidate passes the null test, and the held-out records "
                "keep nothing beyond the scatter of this bundle's own train records and no "
                "spectral line that no declared order explains. Without a reference that "
                "scatter is not that of clean records: an effect present in every record is "
                "part of it and cannot be told from the declared model's form error (held-out "
                f"error {r['error_before']:.3g}, {r['error_unit']}). Read the bundle against "
                "clean records (reference=first:N, this unit's first records, or a sister "
                "unit's bundle) to test for one.")
    parts = []
    for label, g in r["unexplained"]["groups"].items():
        lines = "; ".join(f"{x['frequency_hz']:.1f} Hz (pinion order {x['order']:.3f}, "
                          f"{x['level_db']:+.1f} dB over the floor, in {x['records']} of "
                          f"{x['of']} records)" for x in g["lines"][:6])
        offsets: dict[float, int] = {}
        for x in g["lines"]:
            key = round(abs(x["offset_order"]) * 20) / 20  # to 0.05 order
            offsets[key] = offsets.get(key, 0) + 1
        common = ", ".join(f"{o:g} ({c} lines)" for o, c in
                           sorted(offsets.items(), key=lambda kv: -kv[1])[:3])
        if lines:
            lines += f"; offsets from the nearest mesh harmonic, in pinion orders: {common}"
        ent = ", ".join(f"{e['entry']} ({e['residual_db']:+.1f} dB, z {e['z']:+.1f})"
                        for e in g["entries"][:6])
        parts.append(f"{label}: " + "; ".join(s for s in (
            f"lines no declared order explains at {lines}" if lines else "",
            f"entries beyond the discrepancy {ent}" if ent else "") if s))
    near = ", ".join(f"{c['effect']}{' ' + str(c['option']) if c['option'] else ''} (held-out "
                     f"{c['heldout_error']:.2f}; fails "
                     f"{', '.join(k for k, ch in c['checks'].items() if not ch['holds'])})"
                     for c in r["unexplained"]["closest"])
    ref = r.get("form_reference") or {}
    caveat = ""
    if ref.get("calibration_held"):
        caveat = (" Against this unit's own earliest records the residual also holds the "
                  "declared model's error in how the signature changes with the wear since "
                  "them, which those records cannot show: it may be that misprediction rather "
                  "than an undeclared effect.")
    elif ref:
        caveat = (" Against a sister unit the residual also holds the two units' difference "
                  "beyond what the calibrated nuisance takes up: it may be that difference "
                  "rather than an undeclared effect.")
    return ("**Verdict: unexplained residual.** No candidate of the library passes the null test, "
            "but the records carry what the declared model cannot explain. "
            + " ".join(parts) + (f". Closest candidates: {near}." if near else ".")
            + caveat)


def unexplained_figure(report, out: Path) -> None:
    """unexplained.png: per group with an unexplained residual, its unexplained entries (held-out
    mean residual against the allowed scatter) and the spectrum of its first record with the
    lines no declared order explains."""
    plain = report.to_dict()
    groups = plain["unexplained"]["groups"]
    rec = report.signals["rec"]
    labels = {g.label: g for g in rec.groups}
    plt = pyplot()
    fig, axes = plt.subplots(len(groups), 2, figsize=(13, 4.2 * len(groups)), squeeze=False)
    for (left, right), (label, found) in zip(axes, groups.items(), strict=True):
        ent = found["entries"]
        if ent:
            pos = np.arange(len(ent))
            left.bar(pos, [e["residual_db"] for e in ent], 0.6,
                     label="held-out mean residual")
            allowed = [e["allowed_db"] for e in ent]
            left.plot(pos, allowed, "k_", ms=14, label="allowed (+)")
            left.plot(pos, [-a for a in allowed], "k_", ms=14, label="allowed (-)")
            left.set_xticks(pos, [e["entry"] for e in ent], rotation=90, fontsize=7)
            left.legend(fontsize=7)
        else:
            left.text(0.5, 0.5, "no signature entry beyond the discrepancy", ha="center",
                      transform=left.transAxes)
        left.set(ylabel="measured - model [dB]", title=f"unexplained entries, {label}")
        g = labels[label]
        i = int(g.records[0])
        f, p, floor = record_spectrum(rec.bundle.signals[rec.bundle.records[i]], g.key[3])
        keep = f < 0.45 * g.key[3]
        right.semilogy(f[keep], p[keep], lw=0.5, label=f"record {rec.bundle.records[i]}")
        right.semilogy(f[keep], floor[keep], "k", lw=0.8, label="local floor")
        if found["lines"]:
            t = 10 ** (found["lines"][0]["threshold_db"] / 10)
            right.semilogy(f[keep], t * floor[keep], "k:", lw=0.8, label="threshold")
        for x in found["lines"]:
            right.axvline(x["frequency_hz"], color="C3", lw=0.8, alpha=0.6)
        right.set_xscale("log")
        right.set(xlabel="frequency [Hz]", ylabel="power per bin",
                  title=f"lines no declared order explains (red), {label}")
        right.legend(fontsize=7)
    fig.tight_layout()
    atomic_write(out / "unexplained.png", lambda p: fig.savefig(p, dpi=110, format="png"))
    plt.close(fig)
