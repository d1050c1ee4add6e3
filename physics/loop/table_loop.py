"""The measured-data loop on a feature table (thesis Table 15): features against wear only.

A feature table carries no signal, so the comparison is in the features themselves: for each
row (a wear depth) the declared model is run at the worn state of that depth (the dynamically
coupled wear evolution of the configured operating point, :mod:`physics.dynamics.evolution`),
its housing acceleration (or DTE) goes through the measurement chain with white noise, and the
Table 13 features of model and measurement are compared as log ratios. Rows deeper than the
model follows (its wear run leaves the model's scope first: a worn flank past the shakedown
limit, worn flanks that no longer meet as one line contact) are left out and listed
(``beyond_reach`` of the report); three rows must remain.

1. **Calibration**: damping ratio, pinion run-out, profile error, ``m_h`` (acceleration) and the
   noise level, by bounded least squares on the least-worn row: the declared model describes
   the healthy machine, and the change with wear is what the model must then explain.
2. **Attribution**: every effect of :mod:`physics.loop.effects` that can show in the quantity is
   added; effects marked ``grows_with_wear`` (a local defect, backlash growth) take their size
   in proportion to the row's wear depth (zero on the unworn row; a shape parameter such as a
   pit's length is kept), the others a constant size.
   Each is judged by leave-one-row-out error (its parameters, ``m_h`` and noise refitted on the
   other rows with the structural nuisance kept, the left-out row predicted; the calibrated
   model alone gets the same refit) and by BIC (Gaussian, unknown variance) on all rows;
   the null rule of :mod:`physics.loop` applies.
3. **Report**: the same keys as the bundle loop; the error is the RMS log ratio of the
   features (natural log, so 0.1 is about 10 %), with the mean relative error in percent and
   the rise of each feature from the first to the last row, measured and modelled.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import re

import numpy as np
import pandas as pd
from scipy import optimize

from physics.dynamics.model import PairModel, simulate
from physics.gear.stiffness import mesh_stiffness
from physics.loop.config import LoopSettings
from physics.loop.effects import EFFECTS, Effect
from physics.loop.judge.adoption import holds, null_test
from physics.loop.measured.worn_states import cycles_for_wear, wear_reach, worn_models
from physics.loop.model.declared import (
    NUISANCE,
    declared_nuisance,
    from_unit,
    to_unit,
    with_nuisance,
)
from physics.loop.model.simulation import SETTLE_DECAYS
from physics.loop.report import LoopReport
from physics.loop.search.attribution import candidates_for
from physics.loop.threads import one_blas_thread
from physics.params import OutOfScope, Scenario
from physics.signals.features import FEATURES, features
from physics.signals.measurement import declared_chain, sensed

log = logging.getLogger(__name__)

_COLUMN = re.compile(r"^(?P<feat>[a-z_]+?)(?:_(?P<scale>1e-?\d+)?_?(?P<unit>m_per_s2|m))?$")


def parse_columns(df: pd.DataFrame) -> tuple[str, dict[str, tuple[str, float]]]:
    """Quantity (``accel_m_s2`` or ``dte_m``) and column -> (feature, scale to SI) of a table.

    Columns are ``<feature>`` (dimensionless) or ``<feature>_[<scale>_]<unit>`` with unit
    ``m_per_s2`` or ``m`` (e.g. ``rms_m_per_s2``, ``peak_to_peak_1e-5_m``).
    """
    cols, units = {}, set()
    for c in df.columns:
        if c in ("wear_mm", "cycles", "cycles_1e6"):
            continue
        m = _COLUMN.match(c)
        if not m or m["feat"] not in FEATURES:
            raise ValueError(f"feature table column {c!r} is not a Table 13 feature "
                             f"{FEATURES} with an optional unit suffix (_m_per_s2, _m)")
        cols[c] = (m["feat"], float(m["scale"] or 1.0))
        if m["unit"]:
            units.add(m["unit"])
    if len(units) != 1:
        raise ValueError(f"feature table: the dimensional features need one unit suffix, "
                         f"_m_per_s2 (housing acceleration) or _m (DTE); found {sorted(units)}")
    return ("accel_m_s2" if units == {"m_per_s2"} else "dte_m"), cols


@dataclasses.dataclass
class TableData:
    quantity: str
    wear: np.ndarray  # [mm]
    measured: np.ndarray  # (rows, features) in SI
    names: list[str]  # feature names
    models: list[PairModel]
    base: Scenario
    settings: LoopSettings
    #: rows deeper than the model follows (:func:`beyond_reach`), left out; None: none
    beyond: dict | None = None


def beyond_reach(wear: np.ndarray, reach_mm: float, why: str | None) -> dict | None:
    """The rows of a table deeper than the root wear ``reach_mm`` the declared model follows
    (it leaves its scope there, ``why``): their wear, the reach and the reason; None if all
    lie within it. Three rows at least must remain, else :class:`OutOfScope`."""
    inside = wear <= reach_mm
    if inside.all():
        return None
    if inside.sum() < 3:
        raise OutOfScope(f"feature table: {int(inside.sum())} of {len(wear)} rows lie within "
                         f"the {reach_mm:.4g} mm of root wear the declared model follows at this "
                         f"operating point, and the leave-one-out judgement needs 3; {why}")
    return {"reach_mm": reach_mm, "reason": why, "rows": np.flatnonzero(~inside).tolist(),
            "wear_mm": wear[~inside].tolist()}


def prepare_table(df: pd.DataFrame, base: Scenario, settings: LoopSettings) -> TableData:
    quantity, cols = parse_columns(df)
    wear = df.wear_mm.to_numpy(float)
    if np.any(wear < 0):
        raise ValueError("feature table: wear_mm must be >= 0")
    if len(df) < 3:
        raise ValueError(f"feature table: {len(df)} rows; the leave-one-out judgement needs "
                         "at least 3 wear states")
    beyond = beyond_reach(wear, *wear_reach(base, wear))
    if beyond is not None:
        log.warning("feature table: %d rows deeper than %.4g mm of root wear are left out: "
                    "the declared model leaves its scope there (%s)", len(beyond["rows"]),
                    beyond["reach_mm"], beyond["reason"])
        df = df.drop(index=df.index[beyond["rows"]])
        wear = df.wear_mm.to_numpy(float)
    cycles = cycles_for_wear(base, wear)
    ms = mesh_stiffness(base.gear, base.material)
    by_cycles, _ = worn_models(base, ms, list(cycles))
    measured = np.column_stack([df[c].to_numpy(float) * s for c, (_, s) in cols.items()])
    return TableData(quantity, wear, measured, [f for f, _ in cols.values()],
                     [by_cycles[float(c)] for c in cycles], base, settings, beyond)


def model_features(td: TableData, rows: np.ndarray, nuisance: dict, eff: Effect | None,
                   values: dict) -> np.ndarray:
    """Features of the model at ``rows``, (rows, features), through chain and noise."""
    dyn = td.base.dynamics
    ms = [with_nuisance(td.models[i], nuisance, dyn.damping_ratio) for i in rows]
    if eff is not None and eff.model is not None:
        top = max(float(td.wear.max()), 1e-12)
        ms = [eff.model(m, _sized(eff, values, td.wear[i] / top)) for m, i in zip(ms, rows,
                                                                                 strict=True)]
    run = dataclasses.replace(dyn, duration_s=td.settings.segment_s,
                              transient_s=td.settings.transient_s, phase_bins=16,
                              step_factor=td.settings.step_factor)
    resp = simulate(ms, run, settle=SETTLE_DECAYS)
    x = declared_chain(sensed(resp, td.quantity), td.quantity, nuisance["housing_mass_kg"],
                       fs=dyn.sample_rate_hz, support_hz=dyn.support_hz,
                       support_damping=dyn.support_damping, mount_hz=dyn.mount_hz,
                       mount_damping=dyn.mount_damping)
    if eff is not None and eff.record is not None:
        x = eff.record(x, dyn.sample_rate_hz, values)
    rng = np.random.default_rng(td.settings.seed)
    x = x + nuisance["noise"] * rng.standard_normal(x.shape)
    f = features(x)
    return np.column_stack([np.asarray(f[n], float) for n in td.names])


def _sized(eff: Effect, values: dict, share: float) -> dict:
    return eff.scaled(values, share) if eff.grows_with_wear else values


def _log_ratio(td: TableData, rows: np.ndarray, model: np.ndarray) -> np.ndarray:
    return np.log(np.abs(model) / np.abs(td.measured[rows])).ravel()


def _fit(td: TableData, rows: np.ndarray, free: list[tuple], fixed: dict, eff: Effect | None,
         option: dict) -> tuple[dict, dict, float]:
    """Fit the ``free`` (name, low, high, log) parameters on ``rows``; nuisance, values, rss."""
    nuisance_names = set(NUISANCE) | {"noise"}

    def split(u):
        v = {n: from_unit(float(x), lo, hi, lg) for (n, lo, hi, lg), x in zip(free, u,
                                                                               strict=True)}
        nui = fixed | {k: v[k] for k in v if k in nuisance_names}
        return nui, option | {k: v[k] for k in v if k not in nuisance_names}

    def fun(u):
        nui, vals = split(u)
        return _log_ratio(td, rows, model_features(td, rows, nui, eff, vals))

    starts = [np.array([to_unit(fixed[n], lo, hi, lg) if n in fixed else s
                        for n, lo, hi, lg in free]).clip(0.01, 0.99) for s in (0.2, 0.5, 0.8)]
    u0 = min(starts, key=lambda u: float(np.sum(fun(u) ** 2)))
    sol = optimize.least_squares(fun, u0, bounds=(0, 1), diff_step=0.02,
                                 max_nfev=td.settings.max_nfev)
    nui, vals = split(sol.x)
    return nui, vals, float(np.sum(sol.fun**2))


def _noise_bounds(td: TableData) -> tuple[str, float, float, bool]:
    """Noise between 0.1 % and half the least-worn row's RMS: a sensor on a running gearbox
    sees the machine, not its own noise (SNR >= 6 dB)."""
    scale = float(td.measured[0, td.names.index("rms")]) if "rms" in td.names else 1.0
    return ("noise", 1e-3 * scale, 0.5 * scale, True)


@one_blas_thread
def run_feature_table(df: pd.DataFrame, base: Scenario,
                      settings: LoopSettings | None = None) -> LoopReport:
    """The loop on a feature table; returns its report."""
    settings = settings or LoopSettings()
    candidates_for(set(), settings)  # refuses unknown names before any work
    td = prepare_table(df, base, settings)
    rows = np.arange(len(td.wear))
    start = declared_nuisance(base) | {"noise": _noise_bounds(td)[2] * 0.2}
    gain = [("housing_mass_kg", *NUISANCE["housing_mass_kg"])] if td.quantity != "dte_m" else []
    names = [n for n in NUISANCE if n != "housing_mass_kg"]
    cal_free = [(n, *NUISANCE[n]) for n in names] + gain + [_noise_bounds(td)]
    ref = rows[[int(np.argmin(td.wear))]]  # the healthy (least worn) state
    nuisance, _, _ = _fit(td, ref, cal_free, start, None, {})
    refit = [*gain, _noise_bounds(td)]  # refitted with every candidate and every fold

    def judge(eff: Effect | None, option: dict) -> dict:
        free = (eff.bounds() if eff else []) + refit
        nui, vals, rss = _fit(td, rows, free, nuisance, eff, option)
        held = []
        for r in rows:  # leave one row out: the same fit, blind to the row
            keep = rows[rows != r]
            n_k, v_k, _ = _fit(td, keep, free, nuisance, eff, option)
            held.append(_log_ratio(td, np.array([r]), model_features(td, np.array([r]), n_k,
                                                                     eff, v_k)))
        held = np.concatenate(held)
        n = len(rows) * len(td.names)
        return {"effect": eff.name if eff else None, "option": option, "nuisance": nui,
                "parameters": vals, "n_params": len(eff.params) if eff else 0, "rss": rss,
                "bic": n * math.log(rss / n) + len(free) * math.log(n),
                "heldout": float(np.sqrt(np.mean(held**2)))}

    null = judge(None, {})
    ranking = [judge(e, o) for e, o in candidates_for({td.quantity}, settings)]
    ranking.sort(key=lambda c: c["heldout"])
    best = ranking[0]
    checks = null_test(best["heldout"], null["heldout"], best["bic"] - null["bic"],
                       settings.min_gain, settings.min_delta_bic)
    adopt = holds(checks)
    chosen = best if adopt else null
    eff = EFFECTS[chosen["effect"]] if adopt else None
    before = model_features(td, rows, null["nuisance"], None, {})
    after = model_features(td, rows, chosen["nuisance"], eff, chosen["parameters"])

    def effect_values(c: dict) -> dict:  # the fitted parameters, without the option
        return {k: v for k, v in c["parameters"].items() if k not in c["option"]}

    def table(m: np.ndarray) -> dict:
        return {n: m[:, j].tolist() for j, n in enumerate(td.names)}

    def rise(m: np.ndarray) -> dict:
        return {n: float(m[-1, j] / m[0, j]) for j, n in enumerate(td.names)}

    def mre(m: np.ndarray) -> float:
        return float(np.mean(np.abs(m / td.measured - 1)) * 100)

    return LoopReport(
        mode="feature_table",
        chosen_effect=chosen["effect"],
        chosen_option=best["option"] if adopt else None,
        chosen_parameters=effect_values(chosen) if adopt else None,
        error_before=null["heldout"],
        error_after=chosen["heldout"],
        error_unit="RMS natural-log ratio of the features, leave-one-row-out",
        feature_error_before_pct=mre(before),
        feature_error_after_pct=mre(after),
        wear_error_before_pct=None,
        wear_error_after_pct=None,
        calibration=nuisance,
        calibrated_on="the least-worn row",
        nuisance_after=chosen["nuisance"],
        null_bic=null["bic"],
        ranking=[{"effect": c["effect"], "option": c["option"],
                  "parameters": effect_values(c), "nuisance": c["nuisance"],
                  "heldout_error": c["heldout"], "delta_bic": c["bic"] - null["bic"],
                  "n_params": c["n_params"]} for c in ranking],
        decision_rule={"min_gain": settings.min_gain, "min_delta_bic": settings.min_delta_bic},
        details={
            "verdicts": [{"effect": best["effect"], "adopted": adopt, "checks": checks}],
            "wear_mm": td.wear.tolist(),
            "quantity": td.quantity,
            "features_measured": table(td.measured),
            "features_before": table(before),
            "features_after": table(after),
            "rise_measured": rise(td.measured),
            "rise_before": rise(before),
            "rise_after": rise(after),
            "beyond_reach": td.beyond,
        },
    )
