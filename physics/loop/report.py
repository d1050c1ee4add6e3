"""The report of the measured-data loops (:mod:`physics.loop`): one type for bundles and feature
tables, its markdown and figures. What it reports was decided before it is written (the
adoption rule: :mod:`physics.loop.judge.adoption`)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from physics.arguments import argument, path_argument
from physics.files import atomic_write, pyplot
from physics.loop.judge.verdict import summary_line, unexplained_figure
from physics.signals.order_analysis import line_amplitudes

#: the keys every report.json leads with, in this order (docs/loop.md)
STABLE_KEYS = ("mode", "verdict", "unexplained", "partial", "chosen_effect", "chosen_option",
               "chosen_parameters", "error_before", "error_after", "error_unit",
               "feature_error_before_pct", "feature_error_after_pct",
               "wear_error_before_pct", "wear_error_after_pct", "calibration", "calibrated_on",
               "nuisance_after", "null_bic", "ranking", "decision_rule")


#: residuals.png shows this many signature entries per group: those the model misses most
RESIDUALS_SHOWN = 25
#: how a verdict writes each condition: its value, then its bound
CONDITION_WORDS = {"gain": ("held-out error cut by {value:.0%}", "needs >= {bound:.0%}"),
                   "delta_bic": ("dBIC {value:.4g}", "needs <= {bound:g}"),
                   "explained": ("explained {value:.1f}", "needs > {bound:.1f}"),
                   "whole": ("whole signature cut by {value:.1f} standard errors",
                             "needs >= {bound:g}")}

#: how a verdict writes which model reads the wear after an adopted effect, by the measure of
#: :func:`physics.loop.bundle_loop.wear_check` (``error`` where the skill is undefined)
WEAR_WORDS = {"skill": "its leave-one-out skill on the train records {before:.2f} -> {value:.2f}"
                       " (the adopted effect reads it if >= {bound:.2f})",
              "error": "its leave-one-out error on the train records {before:.1f} -> "
                       "{value:.1f} % (the adopted effect reads it if <= {bound:.1f} %)"}


def condition_text(name: str, c: dict) -> str:
    """One condition of a verdict: its value, its bound and whether it held."""
    value, bound = CONDITION_WORDS[name]
    return f"{value.format(**c)} ({bound.format(**c)}: {'yes' if c['holds'] else 'no'})"


def verdict_line(v: dict) -> str:
    """One round's verdict as a sentence: each condition, its value against its bound, and,
    after an adoption, which model reads the wear and why."""
    parts = [condition_text(k, c) for k, c in v["checks"].items()]
    rank = v.get("rank", 0)
    who = ("Best candidate" if rank == 0 else
           f"Candidate {rank + 1} by held-out error (the first that passes)")
    line = (f"{who} {v['effect']}: {'; '.join(parts)}: "
            f"{'adopted' if v['adopted'] else 'not adopted'}.")
    also = v.get("also_passing")
    if also:
        others = ", ".join(f"{c['effect']}{' ' + str(c['option']) if c['option'] else ''} "
                           f"(held-out error {c['heldout_error']:.3f})" for c in also)
        line += (f" Also passing the null test: {others}; the records do not single out "
                 f"{v['effect']}, which leads by held-out error.")
    w = v.get("wear_reading")
    if w:
        line += (f" The wear estimate is read with {w['reads_with']}: "
                 f"{WEAR_WORDS[w['measure']].format(**w)}.")
    return line


@dataclass
class LoopReport:
    """What a loop found. ``report.json`` holds the stable keys (:data:`STABLE_KEYS`) followed
    by ``details``, the mode's own entries (records and residuals of a bundle, feature tables
    of a table); ``signals`` feeds the figures and is not written."""

    mode: str  # "bundle" or "feature_table"
    chosen_effect: str | None
    chosen_option: dict | None
    chosen_parameters: dict | None
    error_before: float  # held-out error of the calibrated declared model
    error_after: float  # ... with the chosen effect (the same when none is chosen)
    error_unit: str
    feature_error_before_pct: float
    feature_error_after_pct: float
    wear_error_before_pct: float | None
    wear_error_after_pct: float | None
    calibration: dict
    calibrated_on: str
    nuisance_after: dict
    null_bic: float
    ranking: list[dict]
    decision_rule: dict
    details: dict = field(default_factory=dict)
    signals: Any = field(default=None, repr=False, compare=False)
    # "effect", "unexplained_residual", "none" or, stopped in the first round, "not_judged"
    # (:data:`physics.loop.judge.verdict.VERDICTS`); where
    # the residual is unexplained, its groups, entries, lines and the closest candidates
    verdict: str | None = None
    unexplained: dict | None = None
    # a run stopped after its first round: why and after which round (None: complete)
    partial: dict | None = None

    def __post_init__(self):
        if self.verdict is None:
            self.verdict = "effect" if self.chosen_effect else "none"

    @classmethod
    def stopped(cls, mode: str, stop: BaseException, time_limit_s: float, missing: str,
                calibration: dict | None, calibrated_on: str, error: float | None,
                error_unit: str, null_bic: float | None, ranking: list[dict],
                decision_rule: dict, details: dict) -> LoopReport:
        """The report of a run stopped (``stop``: the time limit, :class:`TimeLimit`, or an
        interrupt) in its first round, before every candidate was judged: ``partial`` after
        round 0 saying why and what is ``missing``, verdict ``not_judged``, no effect named;
        the ``calibration`` fitted on ``calibrated_on`` (None: the stop came during it), the
        declared model's held-out ``error`` if it was judged, the ``ranking`` of the
        candidates fitted by then."""
        return cls(
            verdict="not_judged", unexplained=None, mode=mode,
            partial={**stop_entries(stop, time_limit_s), "after_round": 0, "missing": missing},
            chosen_effect=None, chosen_option=None, chosen_parameters=None,
            error_before=error, error_after=error, error_unit=error_unit,
            feature_error_before_pct=None, feature_error_after_pct=None,
            wear_error_before_pct=None, wear_error_after_pct=None,
            calibration=dict(calibration or {}),
            calibrated_on=(calibrated_on if calibration is not None
                           else "not calibrated: stopped during the calibration"),
            nuisance_after=dict(calibration or {}), null_bic=null_bic, ranking=ranking,
            decision_rule=decision_rule, details=details)

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in STABLE_KEYS} | self.details

    def __getitem__(self, key: str) -> Any:
        """``report[key]`` is the entry ``key`` of report.json."""
        return self.to_dict()[key]


def stop_entries(stop: BaseException, time_limit_s: float) -> dict:
    """The report's ``partial`` entries of a stop: why (the time limit of ``time_limit_s`` s, or
    an interrupt: Ctrl-C or SIGTERM)."""
    interrupted = isinstance(stop, KeyboardInterrupt)
    return {"stopped": "interrupted" if interrupted else f"time limit of {time_limit_s:g} s",
            "interrupted": interrupted}


def first_round_markdown(r: dict) -> str:
    """report.md of a run stopped in its first round: why, the calibration if finished, the
    candidates fitted by then (train residual sum, the lower the better), nothing judged."""
    p = r["partial"]
    lines = ["# Measured-data loop", "",
             f"**Partial report:** the run stopped ({p['stopped']}) in its first round; "
             f"{p['missing']}. Run it again, with a longer loop.time_limit_s if one was set, "
             "for a verdict.", ""]
    cal = ", ".join(f"{k} = {v:.4g}" for k, v in r["calibration"].items())
    lines.append(f"Calibrated nuisance parameters ({r['calibrated_on']}): {cal or 'none'}.")
    if r.get("error_before") is not None:
        lines.append(f"The declared model's held-out error: {r['error_before']:.3f} "
                     f"({r['error_unit']}).")
    if r["ranking"]:
        held = all("heldout_error" in c for c in r["ranking"])
        lines += ["", "## Candidates fitted by then (no effect named from them)", "",
                  "| effect | option | fit | train residual sum |"
                  + (" held-out error |" if held else "") + " parameters |",
                  "|---|---|---|---|" + ("---|" if held else "") + "---|"]
        for c in r["ranking"]:
            par = ", ".join(f"{k}={v:.3g}" for k, v in c["parameters"].items()
                            if isinstance(v, float))
            lines.append(f"| {c['effect']} | {c['option'] or ''} | "
                         f"{'refined' if c['refined'] else 'screened'} | {c['train_rss']:.4g} |"
                         + (f" {c['heldout_error']:.3f} |" if held else "") + f" {par} |")
    return "\n".join(lines) + "\n"


def markdown(r: dict) -> str:
    if (r.get("partial") or {}).get("after_round") == 0:
        return first_round_markdown(r)
    lines = ["# Measured-data loop", ""]
    if r.get("partial"):
        p = r["partial"]
        lines += [f"**Partial report:** the run stopped ({p['stopped']}) after round "
                  f"{p['after_round']}; {p['missing']}.", ""]
    if r.get("verdict"):
        lines += [summary_line(r), ""]
    chosen = r["chosen_effect"]
    lines.append(f"**Chosen effect:** {chosen or 'none (no candidate passes the null test)'}")
    if chosen:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in r["chosen_parameters"].items()
                           if isinstance(v, float))
        lines.append(f"  fitted: {params}")
    table = r.get("mode") == "feature_table"
    lead = ("features [RMS log ratio, cross-validated over the rows]" if table
            else "signature [RMS standardised residual]")
    lines += ["", "| held-out error | before | after |", "|---|---|---|",
              f"| {lead} | {r['error_before']:.3f} | {r['error_after']:.3f} |",
              f"| Table 13 features [% mean rel.] | {r['feature_error_before_pct']:.2f} | "
              f"{r['feature_error_after_pct']:.2f} |"]
    for name, e in (r.get("feature_errors") or {}).get("before", {}).items():
        lines.append(f"| {name} [RMS log ratio, held out] | {e:.3f} | "
                     f"{r['feature_errors']['after'][name]:.3f} |")
    if not table:
        lines.append(f"| signature with model discrepancy [RMS standardised residual] | "
                     f"{r['error_before_with_discrepancy']:.3f} | "
                     f"{r['error_after_with_discrepancy']:.3f} |")
        lines.append(f"| signature [dB RMS] | {r['error_before_db']:.2f} | "
                     f"{r['error_after_db']:.2f} |")
    if r.get("wear_error_before_pct") is not None:
        lines.append(f"| wear estimate [% mean rel.] | {r['wear_error_before_pct']:.2f} | "
                     f"{r['wear_error_after_pct']:.2f} |")
        if r.get("wear_skill_before") is not None:
            lines.append(f"| wear estimate's skill [1 - MAE / MAE of the train records' mean "
                         f"wear] | {r['wear_skill_before']:.2f} | {r['wear_skill_after']:.2f} |")
    if r.get("wear_skill_before") is not None and r["wear_skill_before"] <= 0:
        lines += ["", "The model-based wear estimate reads these records no better than the "
                  "train records' mean wear (skill <= 0): its change, and the null test's wear "
                  "check on it, rest on noise."]
    cal = ", ".join(f"{k} = {v:.4g}" for k, v in r["calibration"].items())
    lines += ["", f"Calibrated nuisance parameters ({r['calibrated_on']}): {cal}."]
    for fit, where in (r.get("at_bound") or {}).items():
        if where:
            lines.append(f"At a bound of its search range ({fit}): " + ", ".join(
                f"{k} at its {b} bound {v:.4g}" for k, (b, v) in where.items())
                + ": the range, not the data, set the value.")
    ref = r.get("form_reference")
    if ref:
        per = ", ".join(f"{g}: {ref['records'][g]} records, {v:.2f} dB"
                        for g, v in ref["rms_offset_db"].items())
        lines.append(f"Read against {ref.get('source', 'a reference gearbox')}: the declared "
                     f"model's mean residual there (RMS per group: {per}) was removed from the "
                     "measured signatures" + ("; its calibration there is held for these records."
                                              if ref.get("calibration_held") else
                                              " before the calibration."))
    for name, why in (r.get("not_searched") or {}).items():
        lines.append(f"Not searched: {name} ({why}).")
    known = r.get("assumed") or {}
    if "torque_Nm" in known:
        t = known["torque_Nm"]
        who = (t["records"] if isinstance(t["records"], str) else
               f"{len(t['records'])} records")
        lines.append(f"Torque unknown for {who}: calibrated as a nuisance "
                     f"within {t['prior'][0]:.3g}-{t['prior'][1]:.3g} N m around the configured "
                     f"{t['configured']:.3g} N m, at {t['calibrated']:.3g} N m (worn teeth of "
                     f"{t['worn_teeth_at']:.3g} N m).")
    n = known.get("n1_rpm")
    if n and "read_rpm" in n:  # a bundle's records: read off their spectra
        used = sorted(set(n["used_rpm"].values()))
        lines.append(f"Speed unknown for {len(n['records'])} records: read off each one's "
                     f"spectrum by its mesh comb ({min(n['comb_db'].values()):.1f}-"
                     f"{max(n['comb_db'].values()):.1f} dB over the floor), used at "
                     f"{', '.join(f'{v:.6g}' for v in used)} r/min.")
    elif n:  # a feature table's: calibrated
        lines.append(f"Speed unknown for {n['records']}: calibrated as a nuisance within "
                     f"{n['prior'][0]:.4g}-{n['prior'][1]:.4g} r/min around the configured "
                     f"{n['configured']:.4g} r/min, at {n['calibrated']:.4g} r/min (worn teeth "
                     f"of {n['worn_teeth_at']:.4g} r/min).")
    if "gear" in known:
        lines.append(f"Gear data stated unknown, the configured pair's used: "
                     f"{', '.join(f'{k} = {v:g}' for k, v in known['gear'].items())}.")
    if r.get("not_identifiable"):
        lines.append(f"Not identifiable from these records (held at the declared value): "
                     f"{', '.join(r['not_identifiable'])}.")
    if chosen and r.get("nuisance_after"):
        after = ", ".join(f"{k} = {v:.4g}" for k, v in r["nuisance_after"].items())
        lines.append(f"Refitted with the chosen effect: {after}.")
    staged = any("refined" in c for c in r["ranking"])  # bundles: screened, then refined
    lines += ["", "## Ranking (held-out error, with the model discrepancy for records; BIC "
              "relative to the calibrated model; separable: the share of the candidate's "
              "change that no free nuisance parameter mimics)", "",
              "| effect | option | held-out error | dBIC | parameters |"
              + (" fit | separable |" * staged), "|---|---|---|---|---|" + ("---|---|" * staged)]
    for c in r["ranking"]:
        p = ", ".join(f"{k}={v:.3g}" for k, v in c["parameters"].items() if isinstance(v, float))
        fit = (f" {'refined' if c['refined'] else 'screened'} | {c['separable']:.2f} |"
               if staged else "")
        lines.append(f"| {c['effect']} | {c['option'] or ''} | {c['heldout_error']:.3f} | "
                     f"{c['delta_bic']:.1f} | {p} |{fit}")
    limits = r.get("detection_limits")
    if limits:
        lines += ["", "## Detection limits (not named: the smallest size the rule would name "
                  "on these records, injected into the calibrated model, the other parameters "
                  "at their typical values; physics/loop/search/detection.py)", "",
                  "| effect | option | detection limit | typical size |", "|---|---|---|---|"]
        lines += [f"| {d['effect']} | {d['option'] or ''} | {limit_text(d)} | "
                  f"{d['typical']:.3g} |" for d in limits]
    rule = r["decision_rule"]
    own = " (in its own signature entries)" if "allowed" in rule else ""
    which = ("the best (by held-out error) of the candidates that cut the held-out error"
             if "allowed" in rule else "the best candidate only if it cuts the held-out error")
    lines += ["", f"Decision rule: adopt {which}{own} by at least {rule['min_gain']:.0%} "
              f"and the BIC by at least {rule['min_delta_bic']:g}"]
    if "allowed" in rule:
        lines[-1] += (f", and explains more than {rule['allowed']:.1f} (standardised sum of "
                      f"squares per held-out record, in every group of the quantities it acts "
                      f"on), what the discrepancy "
                      f"allows at a false-add rate of {rule['false_add_rate']:.0%}, and cuts "
                      f"each such group's held-out error over all its entries by at least one "
                      f"standard error")
    lines[-1] += "."
    if "max_wear_loss" in rule:
        lines[-1] += (f" An adopted effect reads the wear unless it lowers the wear estimate's "
                      f"leave-one-out skill on the train records of known wear by more than "
                      f"{rule['max_wear_loss']:g}; the held-out records' wear only scores it.")
    lines += ["", *[f"Round {k + 1}. {verdict_line(v)}" for k, v in enumerate(r["verdicts"])]]
    second = r.get("second_round")
    if second:
        top = second["ranking"][second["rank"]]
        lines += ["", f"Greedy second round on the residual of {second['on']}: judged "
                  f"{top['effect']} (held-out error {top['heldout_error']:.3f}, explained "
                  f"{_least(top['explained'])} against {second['allowed']:.1f} allowed): "
                  f"{'adopted' if second['adopted'] else 'not adopted'}."]
    if table:
        lines += ["", "## Rise of each feature from the first to the last row", "",
                  "| feature | measured | model before | model after |", "|---|---|---|---|"]
        lines += [f"| {k} | {v:.3g} | {r['rise_before'][k]:.3g} | {r['rise_after'][k]:.3g} |"
                  for k, v in r["rise_measured"].items()]
    else:
        lines += ["", "## Groups (held-out error with discrepancy; noise only in brackets)",
                  "", "| group | records | before | after | discrepancy [dB, median] |",
                  "|---|---|---|---|---|"]
        for label, g in r["groups"].items():
            lines.append(f"| {label} | {len(g['records'])} | {_num(g['error_before'])} "
                         f"({_num(g['error_before_noise_only'])}) | {_num(g['error_after'])} "
                         f"({_num(g['error_after_noise_only'])}) | "
                         f"{float(np.median(list(g['discrepancy_db'].values()))):.2f} |")
        lines += ["", "## Largest residuals before (measured minus model, dB, mean over "
                  "held-out records)", ""]
        flat = _flat(r["residual_before"])
        res = sorted(flat.items(), key=lambda kv: -abs(kv[1]))[:10]
        after = _flat(r["residual_after"])
        lines += [f"- {k}: {v:+.2f} dB (after: {after[k]:+.2f})" for k, v in res]
    return "\n".join(lines) + "\n"


def limit_text(d: dict) -> str:
    """A detection limit in words: the smallest size named, or the largest tried."""
    unit = "" if d["unit"] == "1" else f" {d['unit']}"
    if d["limit"] is None:
        return f"not named up to {d['parameter']} = {d['not_named_at']:.3g}{unit}"
    return f"{d['parameter']} {'<= ' * (d['not_named_at'] is None)}{d['limit']:.3g}{unit}"


def _num(x: float | None) -> str:
    return "-" if x is None else f"{x:.3f}"


def _least(explained: dict[str, float]) -> str:
    return f"{min(explained.values()):.1f}" if explained else "nothing"


def _flat(per_group: dict[str, dict[str, float]]) -> dict[str, float]:
    """``{group: {entry: value}}`` as ``{entry: value}`` for one group, else ``{group entry:
    value}``."""
    if len(per_group) == 1:
        return next(iter(per_group.values()))
    return {f"{g} {k}": v for g, entries in per_group.items() for k, v in entries.items()}


def figures(report: LoopReport, out: Path) -> None:
    """order_spectra.png (one held-out record) and residuals.png (the signature entries the
    model misses most, before and after), or feature_trends.png for a feature table."""
    plt = pyplot()
    if report.mode == "feature_table":
        _feature_trends(report.to_dict(), out)
        return
    sig = report.signals
    rec, i = sig["rec"], int(sig["test"][0])
    man = rec.bundle.manifest
    fs = float(man.fs_hz.iloc[i])
    f1 = float(man.n1_rpm.iloc[i]) / 60
    z1 = rec.scenarios[i].gear.z1
    orders = np.arange(0.25, 3.5 * z1, 0.25)
    fig, ax = plt.subplots(figsize=(10, 4.5))
    n = int(rec.settings.segment_s * fs)
    meas = rec.bundle.signals[rec.bundle.records[i]][:n]
    for x, label in ((meas, "measured"), (sig["before"][0], "calibrated model"),
                     (sig["after"][0], "extended model")):
        ax.semilogy(orders, line_amplitudes(x, fs, orders * f1) + 1e-30, label=label, lw=0.9)
    ax.set(xlabel="pinion order", ylabel=f"amplitude [{man.quantity.iloc[i]}]",
           title=f"order spectrum of held-out record {rec.bundle.records[i]}")
    ax.legend()
    atomic_write(out / "order_spectra.png", lambda p: fig.savefig(p, dpi=110, format="png"))
    plt.close(fig)
    groups = list(report["residual_before"])
    fig, axes = plt.subplots(1, len(groups), figsize=(6.5 * len(groups), 6.5), squeeze=False)
    for ax, g in zip(axes[0], groups, strict=True):
        before, after = report["residual_before"][g], report["residual_after"][g]
        names = sorted(before, key=lambda k: -max(abs(before[k]), abs(after[k])))[:RESIDUALS_SHOWN]
        pos = np.arange(len(names))[::-1]  # the largest on top
        ax.barh(pos + 0.2, [before[k] for k in names], 0.4, label="before")
        ax.barh(pos - 0.2, [after[k] for k in names], 0.4, label="after")
        ax.axvline(0.0, color="k", lw=0.6)
        ax.set_yticks(pos, names, fontsize=7)
        ax.set(xlabel="measured - model [dB]",
               title=f"largest {len(names)} of {len(before)} signature residuals\n"
                     f"held-out records, {g}")
        ax.legend(fontsize=8)
    fig.tight_layout()
    atomic_write(out / "residuals.png", lambda p: fig.savefig(p, dpi=110, format="png"))
    plt.close(fig)
    if report["wear_estimates"]:
        _wear_parity(report.to_dict(), out)
    if report.unexplained:
        unexplained_figure(report, out)


def _wear_parity(report: dict, out: Path) -> None:
    """wear_estimates.png: the model-based wear estimate of each held-out record against its
    known wear, with the calibrated and with the extended model."""
    plt = pyplot()
    w = report["wear_estimates"]
    um = {k: np.array(w[k]) * 1e3 for k in ("true_mm", "before_mm", "after_mm")}
    top = 1.1 * max(float(v.max()) for v in um.values()) or 1.0
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot([0, top], [0, top], "k:", lw=1, label="exact")
    for key, style, label in (("before", "C0s", "calibrated model"),
                              ("after", "C1^", "extended model")):
        ax.plot(um["true_mm"], um[f"{key}_mm"], style, ms=6, alpha=0.8,
                label=f"{label} (skill {_num(report[f'wear_skill_{key}'])})")
    ax.set(xlim=(0, top), ylim=(0, top), xlabel="known root wear [um]",
           ylabel="model-based estimate [um]",
           title=f"held-out wear; chosen effect: {report['chosen_effect']}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    atomic_write(out / "wear_estimates.png", lambda p: fig.savefig(p, dpi=110, format="png"))
    plt.close(fig)


def _feature_trends(report: dict, out: Path) -> None:
    plt = pyplot()
    wear = np.array(report["wear_mm"])
    names = list(report["features_measured"])
    fig, axes = plt.subplots(1, len(names), figsize=(max(2.6 * len(names), 6.0), 3.6))
    for ax, n in zip(np.atleast_1d(axes), names, strict=True):
        for key, style, label in (("features_measured", "ko-", "measured"),
                                  ("features_before", "C0s--", "calibrated model"),
                                  ("features_after", "C1^-", "extended model")):
            ax.plot(wear, report[key][n], style, label=label, ms=4, lw=1)
        ax.set(title=n, xlabel="wear depth [mm]")
        ax.set_yscale("log")
    np.atleast_1d(axes)[0].legend(fontsize=7)
    fig.suptitle(f"features against wear; chosen effect: {report['chosen_effect']}")
    fig.tight_layout()
    atomic_write(out / "feature_trends.png", lambda p: fig.savefig(p, dpi=110, format="png"))
    plt.close(fig)


def write_report(report: LoopReport, out: Path, with_figures: bool = True) -> None:
    """report.json, report.md and (unless ``with_figures`` is false) the figures into ``out``."""
    argument(report, "write_report(report)", LoopReport,
             "a LoopReport (physics.loop.run_loop or run_feature_table)")
    out = path_argument(out, "write_report(out)", "the report's folder")
    plain = report.to_dict()
    text = json.dumps(plain, indent=2, default=float)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write(out / "report.json", lambda p: p.write_text(text + "\n"))
    atomic_write(out / "report.md", lambda p: p.write_text(markdown(plain)))
    if with_figures and report.signals is not None:  # a first round stopped has none
        figures(report, out)
