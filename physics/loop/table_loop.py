"""The measured-data loop on a feature table (thesis Table 15, a rig's stage means): features
against wear only.

A feature table carries no signal, so the comparison is in the features themselves. Its rows
are wear states, not a time series: they are taken in order of wear (sorted stably, rows of one
depth in the file's order), so that the first is the least worn and the last the most worn
whatever the file's order. For each row (a wear depth) the declared model is run at the worn
state of that depth, its housing acceleration (or DTE) goes through the measurement chain with
white noise, and the Table 13 features of model and measurement are compared as log ratios.
The worn state of a depth is the pair worn from new by the contact its worn flanks make to that
depth of the deepest point of either active profile
(:func:`physics.loop.measured.worn_states.table_models`), which follows the flanks towards the
tooth's tip thickness: a depth at or beyond it is refused before any work
(:func:`~physics.loop.measured.worn_states.check_table_depths`), a depth whose flanks leave the
model's scope on the way (a tooth worn to its centre line) when the worn states are computed,
before the fits, naming its row. The dynamics take the
scenario's contact (``dynamics.flank_contact``): with ``exact`` the effects that act on the
path's pairs alone (:data:`PATH_ONLY`) are not searched.

1. **Calibration**: damping ratio, pinion run-out, profile error, ``m_h`` (acceleration) and the
   noise level, by bounded least squares on the least-worn row, each within the range its
   source gives (:func:`physics.loop.model.declared.physical_nuisance`): the declared model
   describes the healthy machine, and the change with wear is what the model must then explain.
2. **Attribution**: every effect of :mod:`physics.loop.effects` that can show in the quantity is
   added; effects marked ``grows_with_wear`` (a local defect, backlash growth) take their size
   in proportion to the row's wear depth (zero on the unworn row; a shape parameter such as a
   pit's length is kept), the others a constant size.
   Each is judged by ``K``-fold cross-validation over the rows (:func:`folds`; leave one row
   out up to ``TABLE_FOLDS`` rows): its parameters, ``m_h``, the noise and an unknown torque's
   factor refitted on the other rows with the structural nuisance kept, the left-out rows
   predicted; the calibrated model alone gets the same refit; and by BIC (Gaussian, unknown
   variance) on all rows; the null rule of :mod:`physics.loop` applies.
3. **Report**: the same keys as the bundle loop; the error is the RMS log ratio of the
   features (natural log, so 0.1 is about 10 %), overall and per feature, with the mean
   relative error in percent, the rise of each feature from the first to the last row,
   measured and modelled (the most worn row's over the least worn's, the rows in order of
   wear), and the nuisance values at a bound of their ranges.

Refused before any work (:func:`check_table`): what the columns or cells do not allow, fewer
than three distinct wear states, more than :data:`MAX_TABLE_ROWS` rows, a stated damping ratio
or housing mass outside the range the calibration searches (:func:`check_stated_nuisance`), a
depth the worn states cannot reach, and candidates none of which can show in the table's
quantity (:func:`table_candidates`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import re

import numpy as np
import pandas as pd
from scipy import optimize

from physics.arguments import argument
from physics.dynamics.model import PairModel, simulate
from physics.loop.config import LoopSettings
from physics.loop.effects import EFFECTS, Effect
from physics.loop.judge.adoption import holds, null_test
from physics.loop.measured.bundle import (
    MAX_ACCEL_RMS,
    MAX_DTE_MODULES,
    STANDARD_GRAVITY,
    FeatureTable,
    check_feature_frame,
)
from physics.loop.measured.worn_states import check_table_depths, table_models
from physics.loop.model.declared import (
    SCENARIO_DYNAMIC,
    SPEED,
    TORQUE,
    at_bounds,
    declared_nuisance,
    from_unit,
    physical_nuisance,
    to_unit,
    with_nuisance,
    with_speed,
    with_torque,
)
from physics.loop.model.simulation import CACHE_SIZE, SETTLE_DECAYS
from physics.loop.report import LoopReport
from physics.loop.search.attribution import candidates_for
from physics.loop.threads import one_blas_thread
from physics.params import Dynamics, Scenario
from physics.signals.features import DIMENSIONAL, FEATURES, features
from physics.signals.measurement import declared_chain, sensed

log = logging.getLogger(__name__)

_COLUMN = re.compile(r"^(?P<feat>[a-z_]+?)(?:_(?P<scale>1e-?\d+)?_?(?P<unit>m_per_s2|m|g))?$")
#: the quantity and the factor to SI of each unit suffix; ``g``: standard gravity (3rd CGPM,
#: 1901; ISO 80000-3), the unit accelerometers are read in
UNITS = {"m_per_s2": ("accel_m_s2", 1.0), "g": ("accel_m_s2", STANDARD_GRAVITY),
         "m": ("dte_m", 1.0)}
#: folds of the cross-validation over a table's rows: one row each (leave one out) up to this
#: many rows, this many interleaved folds beyond (each spans the table's wear): K = 5 or 10 has
#: less variance than leave-one-out at a K-th of the fits (Hastie, Tibshirani & Friedman, The
#: Elements of Statistical Learning, 2nd ed., 2009, 7.10.1)
TABLE_FOLDS = 5
#: the most rows a feature table may have. Each row is one dynamic simulation of the declared
#: model at every evaluation of every fit: the calibration, and for the null and each candidate
#: a fit on all rows and one per fold (:data:`TABLE_FOLDS`), ``loop.max_nfev`` evaluations each;
#: the time grows in proportion to the rows. The public rig's 36 stage means took 25 min on two
#: cores (docs/loop.md), so 100 rows take about 70 min and 5000 would take days. A table of
#: stage means (one row per wear state, the records of a state averaged) has a few to tens
MAX_TABLE_ROWS = 100
#: the nuisance parameters a table's calibration searches within their sources' ranges
#: (:func:`~physics.loop.model.declared.physical_nuisance`) from the value the scenario states
#: (``dynamics.*``): a stated value outside its range would be replaced by the range's bound
#: without a word (``housing_mass_kg``: acceleration tables only, the DTE has no housing)
STATED_NUISANCE = ("damping_ratio", "housing_mass_kg")
#: the loop's settings a feature table's run does not use (they steer the bundle loop's
#: records, its staged search, its model discrepancy, its wear reader and its time limit): one
#: given for a table is refused (:func:`check_table_settings`), not ignored without a word
BUNDLE_SETTINGS = ("test_fraction", "wear_grid", "refine", "explore", "starts", "floor_db",
                   "discrepancy_prior", "false_add_rate", "max_wear_loss", "model_form",
                   "time_limit_s", "detection_limits")


def check_table_settings(given: set[str]) -> None:
    """Refuse (ValueError, one line) ``loop.*`` settings of :data:`BUNDLE_SETTINGS` among the
    keys ``given`` on the command line for a feature table: its run would not use them."""
    unused = [k for k in given if k.startswith("loop.") and k[5:] in BUNDLE_SETTINGS]
    if unused:
        raise ValueError(f"{', '.join(sorted(unused))}: a feature table's run does not use "
                         f"{'this setting' if len(unused) == 1 else 'these settings'} (they "
                         "steer the loop on a bundle of records); leave "
                         f"{'it' if len(unused) == 1 else 'them'} out (docs/loop.md)")


#: effects that act on the contact of the path's pairs A and B alone
#: (:mod:`physics.loop.effects`), not searched with the exact contact
#: (``dynamics.flank_contact=exact``), whose tip corners touch off the path: what each would
#: leave out there
PATH_ONLY = {
    "gear_runout": "its moving start of contact is the path's; the exact contact's early "
                   "contact enters with the pair already",
    "friction": "its force factors act on the path's pairs, not on the tip corners that touch "
                "off the path, where sliding is fastest",
    "tip_relief": "it relieves the path's pairs, not the tip corners that touch off the path, "
                  "which a relief removes first",
}


def parse_columns(df: pd.DataFrame) -> tuple[str, dict[str, tuple[str, float]]]:
    """Quantity (``accel_m_s2`` or ``dte_m``) and column -> (feature, scale to SI) of a table.

    Columns are ``<feature>`` (dimensionless) or ``<feature>_[<scale>_]<unit>`` with unit
    ``m_per_s2``, ``g`` or ``m`` (e.g. ``rms_m_per_s2``, ``rms_g``, ``peak_to_peak_1e-5_m``):
    a dimensional feature (``rms``, ``peak_to_peak``) without its unit, or a dimensionless one
    with a unit, is refused (docs/own-data.md: the dimensional ones carry their unit; read as
    SI, a column in g beside one in m/s^2 would be compared in different units).
    """
    argument(df, "the feature table", pd.DataFrame, "a pandas DataFrame")
    cols, quantities = {}, set()
    for c in df.columns:
        if c in ("wear_mm", "cycles", "cycles_1e6"):
            continue
        m = _COLUMN.match(c)
        if not m or m["feat"] not in FEATURES:
            raise ValueError(f"feature table column {c!r} is not a Table 13 feature "
                             f"{FEATURES} with an optional unit suffix (_m_per_s2, _g, _m)")
        if m["feat"] in DIMENSIONAL and not m["unit"]:
            raise ValueError(f"feature table column {c!r}: {m['feat']} is dimensional and "
                             f"needs its unit as a suffix ({m['feat']}_m_per_s2, {m['feat']}_g "
                             f"or {m['feat']}_m; docs/own-data.md); rename the column")
        if m["feat"] not in DIMENSIONAL and (m["unit"] or m["scale"]):
            raise ValueError(f"feature table column {c!r}: {m['feat']} is dimensionless and "
                             f"takes no unit or scale; name the column {m['feat']!r}")
        quantity, si = UNITS[m["unit"]] if m["unit"] else (None, 1.0)
        cols[c] = (m["feat"], float(m["scale"] or 1.0) * si)
        if quantity:
            quantities.add(quantity)
    if len(quantities) != 1:
        raise ValueError(f"feature table: the dimensional features need units of one quantity, "
                         f"_m_per_s2 or _g (housing acceleration) or _m (DTE); found "
                         f"{sorted(quantities)}")
    return quantities.pop(), cols


@dataclasses.dataclass
class TableData:
    quantity: str
    wear: np.ndarray  # [mm]
    measured: np.ndarray  # (rows, features) in SI
    names: list[str]  # feature names
    models: list[PairModel]
    base: Scenario
    settings: LoopSettings
    #: the nuisance's search ranges (:func:`~physics.loop.model.declared.physical_nuisance`)
    bounds: dict
    #: the torque is unknown: ``torque_factor`` is refitted with ``m_h`` and the noise
    torque_unknown: bool = False
    #: the speed is unknown: ``speed_factor`` is refitted with them
    speed_unknown: bool = False
    #: simulated responses by the parameters the dynamics see (:func:`responses`)
    cache: dict = dataclasses.field(default_factory=dict)


def check_table(table: FeatureTable, base: Scenario, given: set[str] | None = None) -> None:
    """Refuse, before any work, a table the loop cannot judge or follow: its columns and
    cells (:func:`~physics.loop.measured.bundle.check_feature_frame`, :func:`parse_columns`,
    :func:`check_feature_values`), fewer than three distinct wear states, more than
    :data:`MAX_TABLE_ROWS` rows, a stated nuisance outside its range
    (:func:`check_stated_nuisance`; ``given``: the keys the command line sets), a depth the
    worn states cannot reach (:func:`~physics.loop.measured.worn_states.check_table_depths`)."""
    argument(table, "check_table(table)", FeatureTable, "a FeatureTable")
    argument(base, "check_table(base)", Scenario, "a physics.params.Scenario")
    where = f"feature table {table.path}" if table.path is not None else "feature table"
    frame = check_feature_frame(table.frame, where)
    quantity, cols = parse_columns(frame)
    check_feature_values(dataclasses.replace(table, frame=frame), quantity, cols,
                         base.gear.module_mm)
    wear = frame.wear_mm.to_numpy(float)
    states = np.unique(wear)
    if states.size < 3:
        shown = ", ".join(f"{w:g}" for w in states)
        raise ValueError(f"{where}: {len(frame)} row(s) of {states.size} distinct wear "
                         f"state(s) (wear_mm {shown}); the cross-validation over the rows "
                         "needs at least 3 distinct wear states: add rows of other depths")
    if len(frame) > MAX_TABLE_ROWS:
        raise ValueError(f"{where}: {len(frame):,} rows, above the {MAX_TABLE_ROWS} the loop "
                         "takes: each row is one dynamic simulation at every step of every "
                         "fit (the public rig's 36 rows took 25 min on two cores, so this table "
                         f"would take about {len(frame) * 25 / 36 / 60:.2g} h); average the rows "
                         "of each wear state (stage means) or give every n-th row")
    check_stated_nuisance(base, quantity, given)
    check_table_depths(base, wear)


def check_stated_nuisance(base: Scenario, quantity: str, given: set[str] | None = None
                          ) -> None:
    """Refuse a stated ``dynamics.damping_ratio`` or ``dynamics.housing_mass_kg``
    (:data:`STATED_NUISANCE`: set on the command line, ``given``, or other than the schema's
    default) outside the range the table's calibration searches for this pair
    (:func:`~physics.loop.model.declared.physical_nuisance`): the fit would start at the
    range's bound and report the value it found, not the stated one, without a word. The
    default housing mass (20 kg, a small housing) is a starting point, not a statement about
    this pair: it is not refused."""
    ranges = physical_nuisance(base)
    default = Dynamics()
    for name in STATED_NUISANCE:
        if name == "housing_mass_kg" and quantity != "accel_m_s2":
            continue
        value = getattr(base.dynamics, name)
        stated = value != getattr(default, name) or f"dynamics.{name}" in (given or ())
        lo, hi, _ = ranges[name]
        if stated and not lo <= value <= hi:
            unit, source = (("kg", "the datasets' 10-40 kg of small housings, times the cube "
                             "of this pair's centre distance over the thesis pair's")
                            if name == "housing_mass_kg" else
                            ("of critical", "what Kasuba & Evans (1981) report for spur "
                             "meshes"))
            raise ValueError(f"dynamics.{name} = {value:g} lies outside {lo:.3g}-{hi:.3g} "
                             f"{unit}, the range a feature table's calibration searches for "
                             f"this pair ({source}); it would be replaced by the range's bound "
                             "without a word: state a value inside, or leave it out (it is "
                             "calibrated)")


def table_candidates(quantity: str, base: Scenario, settings: LoopSettings
                     ) -> tuple[list[tuple[Effect, dict]], dict[str, str]]:
    """The (effect, option) candidates searched on a table of ``quantity`` and those left out
    with the reason (:data:`PATH_ONLY` with the exact contact); none searched is refused,
    naming each candidate and why it cannot show."""
    exact = base.dynamics.flank_contact == "exact"
    searched = [(e, o) for e, o in candidates_for({quantity}, settings)
                if not (exact and e.name in PATH_ONLY)]
    not_searched = ({n: f"with dynamics.flank_contact=exact {why}" for n, why in
                     PATH_ONLY.items() if quantity in EFFECTS[n].quantities}
                    if exact else {})
    if not searched:  # each left out by the exact contact (candidates_for: by the quantity)
        names = settings.candidates or tuple(EFFECTS)
        left = [n for n, e in EFFECTS.items() if n not in PATH_ONLY and quantity in e.quantities]
        raise ValueError(f"loop.candidates = {list(names)}: none is searched on this table ("
                         + "; ".join(f"{n}: {why}" for n, why in not_searched.items()
                                     if n in names)
                         + f"); add candidates the exact contact leaves in ({', '.join(left)}), "
                         "or set dynamics.flank_contact=path")
    return searched, not_searched


def check_feature_values(table: FeatureTable, quantity: str, cols: dict[str, tuple[str, float]],
                         module_mm: float) -> None:
    """Refuse a feature value its definition or its unit does not allow (one line naming the
    row, the column, the value and the rule): a dimensionless feature below 1 (Pearson's
    kurtosis, crest, margin, impulse and shape factors are 1 at least for any signal), an
    RMS or peak-to-peak that is not positive, or beyond what the quantity reaches: a housing
    acceleration's RMS above :data:`~physics.loop.measured.bundle.MAX_ACCEL_RMS`, a DTE's
    beyond :data:`~physics.loop.measured.bundle.MAX_DTE_MODULES` of the module (twice that
    peak to peak), the bounds and their physical basis of a bundle's records."""
    where = f"feature table {table.path}" if table.path is not None else "feature table"
    limit = (MAX_ACCEL_RMS if quantity == "accel_m_s2" else MAX_DTE_MODULES * module_mm * 1e-3)
    unit = "m/s^2" if quantity == "accel_m_s2" else "m"
    for col, (feat, scale) in cols.items():
        values = table.frame[col].to_numpy(float)
        if feat in DIMENSIONAL:
            si = values * scale
            top = limit * (2 if feat == "peak_to_peak" and quantity == "dte_m" else 1)
            top = math.inf if feat == "peak_to_peak" and quantity == "accel_m_s2" else top
            bad = (si <= 0) | (si > top)
            rule = (f"must be positive and at most {top:.3g} {unit}" + (
                " (500 g RMS, beyond any gearbox housing's vibration and any industrial "
                "accelerometer's range; not in m/s^2? raw ADC counts, mm/s^2)"
                if quantity == "accel_m_s2" else
                f" (a tenth of the module, {module_mm:g} mm: beyond any tooth deflection, "
                "profile error and backlash; not in m? um or mm given as m)"))
        else:
            bad = values < 1
            rule = ("must be 1 at least: the kurtosis, crest, margin, impulse and shape factors "
                    "of any signal are (a normal signal's kurtosis is 3, not 0: Pearson's, not "
                    "the excess)")
        if bad.any():
            row = int(np.argmax(bad))
            raise ValueError(f"{where}: row {row + 1}, column {col!r} = {values[row]:g} {rule}")
    for col in ("cycles", "cycles_1e6"):
        if col in table.frame and (table.frame[col].to_numpy(float) < 0).any():
            row = int(np.argmax(table.frame[col].to_numpy(float) < 0))
            raise ValueError(f"{where}: row {row + 1}, column {col!r} = "
                             f"{table.frame[col].iloc[row]:g} must be >= 0 (load cycles)")
    si = {feat: table.frame[col].to_numpy(float) * scale for col, (feat, scale) in cols.items()}
    if quantity == "accel_m_s2" and {"rms", "peak_to_peak"} <= set(si):
        # a signal of mean zero (a housing acceleration's is removed) spans at least twice its
        # RMS: its variance is at most (max - min)^2 / 4 (Popoviciu's inequality)
        bad = si["peak_to_peak"] < 2 * si["rms"] * (1 - 1e-3)
        if bad.any():
            row = int(np.argmax(bad))
            raise ValueError(f"{where}: row {row + 1}: peak_to_peak {si['peak_to_peak'][row]:g} "
                             f"m/s^2 is below twice the RMS {si['rms'][row]:g} m/s^2, which no "
                             "signal of mean zero gives (its variance is at most a quarter of "
                             "its range squared): check the columns' units and scales")


def prepare_table(table: FeatureTable, base: Scenario, settings: LoopSettings) -> TableData:
    """The table checked (:func:`check_table`), its rows in order of wear (sorted stably: the
    rows are wear states, and the rise is from the least to the most worn), its features in
    SI units and the declared model of each row's worn state."""
    check_table(table, base)
    df = check_feature_frame(table.frame)
    quantity, cols = parse_columns(df)
    order = np.argsort(df.wear_mm.to_numpy(float), kind="stable")
    if np.any(order != np.arange(len(order))):
        log.info("feature table: its rows are taken in order of wear_mm (the file's rows %s)",
                 ", ".join(str(i + 1) for i in order))
    df = df.iloc[order]
    wear = df.wear_mm.to_numpy(float)
    measured = np.column_stack([df[c].to_numpy(float) * s for c, (_, s) in cols.items()])
    return TableData(quantity, wear, measured, [f for f, _ in cols.values()],
                     table_models(base, wear, rows=order + 1), base, settings,
                     physical_nuisance(base), table.torque_unknown, table.speed_unknown)


def responses(td: TableData, rows: np.ndarray, nuisance: dict, eff: Effect | None,
              values: dict) -> np.ndarray:
    """Simulated mesh force (or DTE) of ``rows``, one analysis segment each, memoised on the
    parameters the dynamics see: a change of ``m_h``, the noise or a measurement-chain effect
    reuses the simulation."""
    dynamic = eff is not None and eff.model is not None
    key = (tuple(int(i) for i in rows),
           tuple(nuisance.get(n) for n in (*SCENARIO_DYNAMIC, *TORQUE, *SPEED)),
           (eff.name, tuple(sorted(values.items()))) if dynamic else None)
    if key in td.cache:
        return td.cache[key]
    dyn = td.base.dynamics
    ms = [with_speed(with_torque(with_nuisance(td.models[i], nuisance, dyn.damping_ratio),
                                 nuisance), nuisance)
          for i in rows]  # torque and speed before an effect: a ripple's share is of these
    if dynamic:
        top = max(float(td.wear.max()), 1e-12)
        ms = [eff.model(m, _sized(eff, values, td.wear[i] / top))
              for m, i in zip(ms, rows, strict=True)]
    run = dataclasses.replace(dyn, duration_s=td.settings.segment_s,
                              transient_s=td.settings.transient_s, phase_bins=16,
                              step_factor=td.settings.step_factor)
    x = sensed(simulate(ms, run, settle=SETTLE_DECAYS), td.quantity)
    if len(td.cache) >= CACHE_SIZE:
        td.cache.pop(next(iter(td.cache)))  # the oldest entry
    td.cache[key] = x
    return x


def model_features(td: TableData, rows: np.ndarray, nuisance: dict, eff: Effect | None,
                   values: dict) -> np.ndarray:
    """Features of the model at ``rows``, (rows, features), through chain and noise."""
    dyn = td.base.dynamics
    x = declared_chain(responses(td, rows, nuisance, eff, values), td.quantity,
                       nuisance["housing_mass_kg"], fs=dyn.sample_rate_hz,
                       support_hz=dyn.support_hz, support_damping=dyn.support_damping,
                       mount_hz=dyn.mount_hz, mount_damping=dyn.mount_damping)
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


def folds(wear: np.ndarray, k: int = TABLE_FOLDS) -> list[np.ndarray]:
    """The held-out rows of each fold of the cross-validation (:data:`TABLE_FOLDS`): one row
    each up to ``k`` rows, else ``k`` folds of every ``k``-th row in order of wear."""
    order = np.argsort(wear, kind="stable")
    return [order[j::k] for j in range(min(k, len(wear)))]


def _fit(td: TableData, rows: np.ndarray, free: list[tuple], fixed: dict, eff: Effect | None,
         option: dict) -> tuple[dict, dict, float]:
    """Fit the ``free`` (name, low, high, log) parameters on ``rows``; nuisance, values, rss."""
    nuisance_names = set(td.bounds) | set(TORQUE) | set(SPEED) | {"noise"}

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


def stopped_table(stop: BaseException, settings: LoopSettings, nuisance: dict | None,
                  null: dict | None, judged: list[dict], candidates: int, not_searched: dict
                  ) -> LoopReport:
    """The report of a feature table's run interrupted (Ctrl-C or SIGTERM) before every
    candidate was judged: the calibration if finished, the declared model's held-out error if
    judged, and the candidates judged by then (their fits and held-out errors); no effect is
    named from a part of the candidates (verdict ``not_judged``), nothing is simulated after
    the stop."""
    missing = ("the calibration was not finished: no candidate was judged" if nuisance is None
               else f"{len(judged)} of {candidates} candidates were judged: no effect is named "
               "from a part of them")
    ranking = [{"effect": c["effect"], "option": c["option"],
                "parameters": {k: v for k, v in c["parameters"].items() if k not in c["option"]},
                "nuisance": c["nuisance"], "refined": True, "train_rss": c["rss"],
                "heldout_error": c["heldout"]} for c in judged]
    return LoopReport.stopped(
        "feature_table", stop, settings.time_limit_s, missing, nuisance, "the least-worn row",
        null["heldout"] if null else None,
        "RMS natural-log ratio of the features, cross-validated over the rows",
        null["bic"] if null else None, ranking,
        {"min_gain": settings.min_gain, "min_delta_bic": settings.min_delta_bic},
        {"not_searched": not_searched})


@one_blas_thread
def run_feature_table(table: FeatureTable | pd.DataFrame, base: Scenario,
                      settings: LoopSettings | None = None) -> LoopReport:
    """The loop on a feature table (a data frame: no ``gear.yaml`` or ``operating.yaml`` beside
    it, the torque the configured one; checked as a file's, :func:`check_table`); returns its
    report. Its rows are taken in order of wear (module doc)."""
    argument(table, "run_feature_table(table)", (FeatureTable, pd.DataFrame),
             "a FeatureTable (physics.loop.read_measurements) or a pandas DataFrame of wear_mm "
             "and features")
    argument(base, "run_feature_table(base)", Scenario, "a physics.params.Scenario")
    settings = argument(settings, "run_feature_table(settings)", (LoopSettings, type(None)),
                        "a LoopSettings or None (the defaults)") or LoopSettings()
    if isinstance(table, pd.DataFrame):
        table = FeatureTable(None, check_feature_frame(table), {})
    # refused before any work: unknown names, none that can show in the table's quantity
    searched, not_searched = table_candidates(parse_columns(check_feature_frame(table.frame))[0],
                                              base, settings)
    td = prepare_table(table, base, settings)
    log.info("feature table: %d rows, %d candidates; each fit simulates every row", len(td.wear),
             len(searched))
    rows = np.arange(len(td.wear))
    start = declared_nuisance(base) | {"noise": _noise_bounds(td)[2] * 0.2}
    gain = ([("housing_mass_kg", *td.bounds["housing_mass_kg"])] if td.quantity != "dte_m"
            else [])
    names = [n for n in td.bounds if n != "housing_mass_kg"]
    cal_free = [(n, *td.bounds[n]) for n in names] + gain + [_noise_bounds(td)]
    ref = rows[[int(np.argmin(td.wear))]]  # the healthy (least worn) state
    try:
        nuisance, _, _ = _fit(td, ref, cal_free, start, None, {})
    except KeyboardInterrupt as stop:
        return stopped_table(stop, settings, None, None, [], len(searched), not_searched)
    # refitted with every candidate and every fold; an unknown torque's or speed's factor over
    # its whole prior (physics.loop.model.declared.TORQUE, SPEED)
    torque = ([("torque_factor", *TORQUE["torque_factor"])] if td.torque_unknown else []) + (
        [("speed_factor", *SPEED["speed_factor"])] if td.speed_unknown else [])
    refit = [*gain, _noise_bounds(td), *torque]
    ranges = {n: b for n, *b in cal_free + torque}

    def judge(eff: Effect | None, option: dict) -> dict:
        free = (eff.bounds() if eff else []) + refit
        nui, vals, rss = _fit(td, rows, free, nuisance, eff, option)
        held = np.empty_like(td.measured)
        for out in folds(td.wear):  # the same fit, blind to the fold's rows
            n_k, v_k, _ = _fit(td, np.setdiff1d(rows, out), free, nuisance, eff, option)
            held[out] = _log_ratio(td, out, model_features(td, out, n_k, eff, v_k)).reshape(
                len(out), -1)
        n = held.size
        return {"effect": eff.name if eff else None, "option": option, "nuisance": nui,
                "parameters": vals, "n_params": len(eff.params) if eff else 0, "rss": rss,
                "bic": n * math.log(rss / n) + len(free) * math.log(n),
                "heldout": float(np.sqrt(np.mean(held**2))),
                "heldout_by_feature": np.sqrt(np.mean(held**2, axis=0))}

    null, ranking = None, []
    try:
        null = judge(None, {})
        log.info("feature table: the declared model judged (held-out %.3f)", null["heldout"])
        for k, (e, o) in enumerate(searched):
            ranking.append(judge(e, o))
            log.info("feature table: candidate %d of %d, %s%s judged (held-out %.3f)", k + 1,
                     len(searched), e.name, f" {o}" if o else "", ranking[-1]["heldout"])
    except KeyboardInterrupt as stop:  # what was judged by then, kept
        return stopped_table(stop, settings, nuisance, null, ranking, len(searched),
                             not_searched)
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

    def table_of(m: np.ndarray) -> dict:
        return {n: m[:, j].tolist() for j, n in enumerate(td.names)}

    def rise(m: np.ndarray) -> dict:
        return {n: float(m[-1, j] / m[0, j]) for j, n in enumerate(td.names)}

    def mre(m: np.ndarray) -> float:
        return float(np.mean(np.abs(m / td.measured - 1)) * 100)

    def by_feature(c: dict) -> dict:
        return dict(zip(td.names, c["heldout_by_feature"].tolist(), strict=True))

    return LoopReport(
        mode="feature_table",
        chosen_effect=chosen["effect"],
        chosen_option=best["option"] if adopt else None,
        chosen_parameters=effect_values(chosen) if adopt else None,
        error_before=null["heldout"],
        error_after=chosen["heldout"],
        error_unit=f"RMS natural-log ratio of the features, {len(folds(td.wear))}-fold "
                   "cross-validation over the rows",
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
            "flank_contact": base.dynamics.flank_contact,
            "feature_errors": {"before": by_feature(null), "after": by_feature(chosen)},
            "features_measured": table_of(td.measured),
            "features_before": table_of(before),
            "features_after": table_of(after),
            "rise_measured": rise(td.measured),
            "rise_before": rise(before),
            "rise_after": rise(after),
            "nuisance_ranges": ranges,
            "at_bound": {"calibration": at_bounds(nuisance, ranges),
                         "before": at_bounds(null["nuisance"], ranges),
                         "after": at_bounds(chosen["nuisance"], ranges),
                         "chosen effect": at_bounds(chosen["parameters"], {
                             n: b for n, *b in eff.bounds()}) if eff else {}},
            "not_searched": not_searched,
            "stated_beside": table.stated,  # by the gear.yaml and operating.yaml beside it
            "assumed": _assumed(table, base, null["nuisance"], chosen["nuisance"]),
        },
    )


def _assumed(table: FeatureTable, base: Scenario, before: dict, after: dict) -> dict:
    """What the table's sidecars left unknown and what stood in: an unknown torque or speed
    (the configured one times the factor calibrated before and after the chosen effect, its
    prior), gear data stated unknown (the configured pair's values)."""
    out = {}
    for key, name, unknown in (("torque_Nm", "torque_factor", table.torque_unknown),
                               ("n1_rpm", "speed_factor", table.speed_unknown)):
        if unknown:
            lo, hi, _ = (TORQUE | SPEED)[name]
            v0 = getattr(base.operating, key)
            out[key] = {"records": "all rows", "configured": v0, "prior": [lo * v0, hi * v0],
                        "calibrated": v0 * before[name], "after": v0 * after[name],
                        "worn_teeth_at": v0}
    gear = [k for k in table.unknown if k not in ("torque_Nm", "n1_rpm")]
    if gear:
        out["gear"] = {k: getattr(base.gear, k) for k in gear}
    return out
