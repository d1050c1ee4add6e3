"""What a bundle lets the loop do, decided before any work: the rules a bundle the loop cannot
use breaks (:func:`check_usable`, each refusal one line naming the record, the value, the rule
and the fix), and each candidate effect's parameter range clipped to what the records can show
(:func:`shown_candidates`); a command-line setting the data's sidecars would silently override
(:func:`check_stated_once`) and a ``reference=`` of no known form (:func:`check_reference_folder`).

A bundle that passes the format's rules (:mod:`physics.loop.measured.bundle`) and these runs to the
end.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np

from physics.arguments import argument
from physics.loop.config import LoopSettings
from physics.loop.effects import Effect, Param
from physics.loop.measured.bundle import Bundle, FeatureTable
from physics.loop.measured.records import split_records
from physics.loop.measured.worn_states import tip_thickness_mm
from physics.params import Scenario

#: the highest line the signature reads, as a share of the sampling rate
TOP_SHARE = 0.45
#: a line is resolved in an analysis segment of ``segment_s`` if it lies this many frequency
#: bins (``1 / segment_s``) from its neighbour (the Hann window's main lobe is +-2 bins)
RESOLVED_BINS = 2.0
#: the most pinion load cycles a record may state: a pinion at 20 000 r/min without a stop for
#: 95 years (ISO 6336-2's life curves end at 1e10 cycles); below the wear run's own limit
#: (:data:`~physics.loop.measured.worn_states.MAX_CYCLES`), which it searched up to for minutes
MAX_LIFE_CYCLES = 1e12


def check_usable(bundle: Bundle, base: Scenario, settings: LoopSettings) -> None:
    """Refuse, before any work, a bundle the loop cannot use: a stated wear at or beyond the
    thinner tooth's tip thickness (:func:`~physics.loop.measured.worn_states.tip_thickness_mm`:
    no tip left to mesh) or stated cycles beyond a gear's life (:data:`MAX_LIFE_CYCLES`; both
    else found by the wear run after minutes of work), a record whose analysis segment
    (``loop.segment_s``) holds less than one pinion revolution (the synchronous average needs
    one), a record shorter than two segments (their scatter is the comparison's noise), a
    constant segment (a sensor that dropped out: its statistics are undefined), or a split
    without a train and a test record."""
    argument(bundle, "check_usable(bundle)", Bundle, "a Bundle (physics.loop.read_bundle)")
    argument(base, "check_usable(base)", Scenario, "a physics.params.Scenario")
    argument(settings, "check_usable(settings)", LoopSettings, "a LoopSettings")
    man = bundle.manifest
    seg = settings.segment_s
    gear = dataclasses.replace(base.gear, **bundle.gear)
    tip = tip_thickness_mm(dataclasses.replace(base, gear=gear))
    for row in man.itertuples(index=False):
        if row.wear_mm >= tip:  # NaN (not stated) compares False
            raise ValueError(f"bundle {bundle.path}: record {row.record!r}: wear_mm = "
                             f"{row.wear_mm:g} reaches the {tip:.3g} mm the thinner tooth is "
                             "thick at its tip (along its flank's normal; module "
                             f"{gear.module_mm:g} mm): a flank worn that deep has no tip left "
                             "to mesh; check that wear_mm is the pinion's root wear in mm "
                             "(um are 1e-3 mm), or leave the cell empty")
        if row.cycles > MAX_LIFE_CYCLES:
            raise ValueError(f"bundle {bundle.path}: record {row.record!r}: cycles = "
                             f"{row.cycles:.3g} lies beyond {MAX_LIFE_CYCLES:.0e} pinion load "
                             "cycles, more than any gear's life (20 000 r/min for 95 years), "
                             "which the wear model cannot run to; give the pinion's load "
                             "cycles (revolutions) at the record, or leave the cell empty")
    for row in man.itertuples(index=False):
        revs = seg * row.n1_rpm / 60
        if revs < 1:
            raise ValueError(f"bundle {bundle.path}: record {row.record!r}: an analysis segment "
                             f"of loop.segment_s = {seg:g} s holds {revs:.2f} pinion "
                             f"revolutions at n1_rpm = {row.n1_rpm:g}; the signature's "
                             f"synchronous average needs one: set loop.segment_s >= "
                             f"{60 / row.n1_rpm:.3g}")
        seconds = bundle.signals[row.record].size / row.fs_hz
        if seconds < 2 * seg:
            raise ValueError(f"bundle {bundle.path}: record {row.record!r} holds {seconds:.3g} s, "
                             f"less than two analysis segments of loop.segment_s = {seg:g} s "
                             "(their scatter is the comparison's noise): set loop.segment_s <= "
                             f"{seconds / 2:.3g} (and >= {60 / row.n1_rpm:.3g}, one revolution) "
                             "or give longer records")
        _check_segments(bundle, row.record, row.fs_hz, seg)
    try:
        split_records(man, settings.test_fraction, settings.seed)
    except ValueError as err:
        raise ValueError(f"bundle {bundle.path}: {err}") from None


def _check_segments(bundle: Bundle, rec: str, fs_hz: float, segment_s: float) -> None:
    """Refuse a record with a constant analysis segment (as
    :func:`physics.signals.features.features` tells one: its range within 1e-12 of its
    magnitude), naming the segment's time span."""
    x = bundle.signals[rec]
    n = round(segment_s * fs_hz)
    if n < 2 or x.size < n:
        return
    seg = x[:x.size // n * n].reshape(-1, n)
    top, low = seg.max(axis=1), seg.min(axis=1)
    scale = np.maximum(np.maximum(np.abs(top), np.abs(low)), np.finfo(float).tiny)
    flat = np.flatnonzero(top - low <= 1e-12 * scale)
    if flat.size:
        k = int(flat[0])
        raise ValueError(f"bundle {bundle.path}: record {rec!r}: its analysis segment {k + 1} "
                         f"of {len(seg)} ({k * segment_s:g}-{(k + 1) * segment_s:g} s, "
                         f"loop.segment_s = {segment_s:g}) is constant at {float(seg[k, 0]):g}: "
                         "a sensor that dropped out or a gap filled in; its kurtosis and "
                         "crest are undefined: cut the record before the gap, or leave it out")


def _clipped(p: Param, high: float) -> Param:
    """``p`` with its upper bound ``high``, its typical size inside."""
    typical = p.typical if p.typical < high else (math.sqrt(p.low * high) if p.log
                                                  else 0.5 * (p.low + high))
    return dataclasses.replace(p, high=high, typical=typical)


def shown_candidates(candidates: list[tuple[Effect, dict]], bundle: Bundle, base: Scenario,
                     settings: LoopSettings) -> tuple[list[tuple[Effect, dict]], dict[str, str]]:
    """The candidates with each parameter range clipped to what the bundle's records can show,
    and those left out with the reason: a transfer path's mode below ``0.45 fs`` of the records
    it acts on (the signature's top; the filter needs ``fs / 2``), a torque ripple's order and
    a gear run-out's sidebands resolved in an analysis segment (:data:`RESOLVED_BINS` bins of
    ``1 / loop.segment_s`` from their neighbour) at the slowest record's speed."""
    man = bundle.manifest
    if not candidates:
        raise ValueError(f"bundle {bundle.path}: no candidate effects to search in its "
                         f"{sorted(set(man.quantity))} records; give loop.candidates that act "
                         "on them")
    z1, z2 = (bundle.gear.get(k, getattr(base.gear, k)) for k in ("z1", "z2"))
    f1 = float(man.n1_rpm.min()) / 60
    resolved = RESOLVED_BINS / settings.segment_s
    kept, dropped = [], {}
    for eff, option in candidates:
        label = eff.name + (f" {option}" if option else "")
        fs = man.fs_hz[man.quantity.isin(eff.quantities)].to_numpy(float)
        if eff.name == "transfer_path" and fs.size:
            top = TOP_SHARE * float(fs.min())
            p = next(p for p in eff.params if p.name == "fn_hz")
            if top <= p.low:
                dropped[label] = (f"its mode (fn_hz >= {p.low:g} Hz) lies above 0.45 fs = "
                                  f"{top:g} Hz of the records it acts on")
                continue
            if top < p.high:
                eff = dataclasses.replace(eff, params=tuple(
                    _clipped(q, top) if q is p else q for q in eff.params))
        if eff.name == "torque_ripple" and option["order"] * f1 < resolved:
            dropped[label] = (f"its line at {option['order'] * f1:.3g} Hz is not resolved in a "
                              f"segment of {settings.segment_s:g} s (needs >= {resolved:g} Hz)")
            continue
        if eff.name == "gear_runout" and f1 * z1 / z2 < resolved:
            dropped[label] = (f"its sidebands at +-{f1 * z1 / z2:.3g} Hz are not resolved in a "
                              f"segment of {settings.segment_s:g} s (needs >= {resolved:g} Hz)")
            continue
        kept.append((eff, option))
    if not kept:
        longer = any("not resolved" in why for why in dropped.values())
        raise ValueError(f"bundle {bundle.path}: none of the candidates "
                         f"{sorted({e.name for e, _ in candidates})} can show in these records "
                         f"({'; '.join(f'{k}: {v}' for k, v in dropped.items())}); widen "
                         "loop.candidates" + (" or lengthen loop.segment_s" if longer else ""))
    return kept, dropped


def check_stated_once(cfg: Any, data: Bundle | FeatureTable, base: Scenario,
                      given: set[str]) -> None:
    """Refuse a setting of the command line (``given``: the keys it sets; ``cfg``: the run's
    ``case`` and ``data``) the data overrides, which the run would ignore without a word: a
    ``gear.*`` (or ``operating.*``, or ``case=``) value that the ``gear.yaml`` (``operating.yaml``)
    beside the data states otherwise, and with a bundle an ``operating.n1_rpm``, or an
    ``operating.torque_Nm`` where every record states its torque (each record's own speed and torque
    are used: ``manifest.csv``)."""
    stated = dict(data.gear) if isinstance(data, Bundle) else dict(data.stated)
    for k, v in stated.items():
        group = "gear" if hasattr(base.gear, k) else "operating"
        current = getattr(getattr(base, group), k)
        keys = [f"{group}.{k}"] + (["case"] if group == "operating" and cfg.case is not None
                                   and k in ("n1_rpm", "torque_Nm") else [])
        setting = next((key for key in keys if key in given), None)
        if setting is not None and float(v) != float(current):
            sidecar = "gear.yaml" if group == "gear" else "operating.yaml"
            shown = f"case={cfg.case}" if setting == "case" else f"{setting}={current:g}"
            raise ValueError(f"{shown} on the command line and {k}: {v:g} in the {sidecar} of "
                             f"data={cfg.data} disagree (the file's would be used); state it "
                             "in one place")
    if isinstance(data, Bundle):
        man = data.manifest
        if "operating.n1_rpm" in given:
            raise ValueError(f"operating.n1_rpm={base.operating.n1_rpm:g}: a bundle's records "
                             f"state their own speed (manifest.csv n1_rpm of data={cfg.data}), "
                             "so this setting would not be used; leave it out")
        if "operating.torque_Nm" in given and man.torque_Nm.notna().all():
            raise ValueError(f"operating.torque_Nm={base.operating.torque_Nm:g}: every record "
                             f"of data={cfg.data} states its torque (manifest.csv torque_Nm), "
                             "so this setting would not be used (it is the start of the "
                             "calibration only where a record's torque is unknown); leave it "
                             "out")


def check_reference_folder(spec: str) -> None:
    """Refuse a ``reference=`` that is neither of the unit's own history's forms
    (:func:`~physics.loop.search.own_history.parse_history`) nor a folder, naming
    ``reference=`` and the forms it takes (read as a bundle, it would be blamed on ``data=``)."""
    path = Path(spec)
    if path.is_dir():
        return
    what = ("does not exist" if not path.exists() else
            "is a feature table, not a bundle" if path.suffix == ".csv" else "is not a folder")
    raise ValueError(f"reference={spec}: neither first:N, before:X nor a bundle folder "
                     f"({str(path)!r} {what}); "
                     "reference= takes first:N (this unit's first N records of each group), "
                     "before:X (its records before X load cycles or the ISO 8601 date X) or a "
                     "sister gearbox's bundle folder; e.g. reference=first:2")
