"""Close the loop with measured data: calibrate, find the residual, attribute it, extend, report.

``python -m physics.loop data=BUNDLE`` (Hydra app, ``conf/loop.yaml``) runs the steps below on a
measured bundle (:mod:`physics.bundle`) and writes ``report.json``, ``report.md`` and figures into
its run folder.

1. **Records**: each record becomes a scenario (its speed, torque, lubricant and gear overrides)
   with its worn teeth: the dynamically coupled wear evolution (:mod:`physics.evolution`) is run
   once per operating point to the records' cycle counts (or, where only the wear depth is known,
   to the cycle count of that depth). Records are split into train and test by record (the
   manifest's ``split`` column where given, else seeded), never by windows of one record.
2. **Calibration** of the declared nuisance parameters on the train records: mesh damping ratio,
   pinion run-out and profile error amplitudes, and the housing's effective mass ``m_h`` (for
   acceleration records). A parameter that does not move the residuals (the pinion run-out on
   the line of action: a shaft-rate error is dynamically inert in the torsional model) is held
   at its declared value and reported as not identifiable. The search (:func:`search`): a
   scrambled Sobol sample around the declared values, ``m_h`` levelled at each point, the best
   refined by bounded least squares on the standardised signature residuals.
   Measurement noise is not fitted: its level is read off each record's spectral floor
   (:func:`physics.order_analysis.white_noise_std`) and white noise of that level (seeded per
   record) is added to the model's record.
3. **Residual**: the signature of :mod:`physics.order_analysis` (mesh harmonics with pinion and
   gear sidebands up to 0.45 fs, half-octave bands, statistics, synchronous-average kurtosis,
   all in dB) of measurement minus calibrated model, per entry, divided by the entry's scatter
   between the measured records' segments (pooled over the train records, plus a floor
   ``floor_db``): a standardised residual whose RMS is about 1 where model and measurement
   agree up to noise.
4. **Attribution**: every effect of :mod:`physics.effects` that can show in the bundle's
   quantities is added in turn. Screening: the effect at a grid of sizes, nuisance at the
   calibration, the best size polished by a short least squares. The best ``refine``
   candidates by train chi-square then get the same search as the calibration, their
   parameters jointly with the identifiable nuisance (a missing effect biases the
   calibration, at worst to its bounds, so the nuisance must move with the effect).
   Candidates are ranked by held-out error (RMS standardised residual over the test records)
   with the Bayesian information criterion on the train records beside it (chi-square plus
   k ln n, the scatter being known, k the effect's parameters).
   The **null test**: the best candidate is adopted only if it lowers the held-out error by at
   least ``min_gain`` (20 %) and its BIC by at least ``min_delta_bic`` (10, "very strong" on
   Kass & Raftery's scale); otherwise the report says no candidate explains the residual.
5. **Report**: error before and after on the held-out records, as the standardised signature
   residual (the figure the report leads with) and in dB, as the
   mean relative error of the Table 13 features [%], and, where the wear is known, as the error of
   a model-based wear estimate (the wear state whose simulated signature is nearest) [%].
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from omegaconf import MISSING
from scipy import optimize
from scipy.stats import qmc
from tqdm import tqdm

from physics.dynamics.evolution import root_wear_evolution, simulate_dynamic_wear
from physics.dynamics.model import PairModel, build_model, simulate
from physics.gear.stiffness import MeshStiffness
from physics.loop.bundle import Bundle, record_scenario
from physics.loop.effects import EFFECTS, Effect
from physics.loop.report import LoopReport, adopts
from physics.params import PhysicsConfig, Scenario, bounded, validate_fields
from physics.signals.features import FEATURES, features
from physics.signals.measurement import declared_chain, sensed
from physics.signals.order_analysis import (
    signature,
    signature_names,
    signature_segments,
    white_noise_std,
)

log = logging.getLogger(__name__)

#: declared nuisance parameters: name, bounds, log-scaled
NUISANCE = {"damping_ratio": (0.01, 0.3, True), "eccentricity1_um": (0.2, 60.0, True),
            "profile_error_um": (0.1, 30.0, True), "housing_mass_kg": (0.01, 1e5, True)}
#: the nuisance parameters the dynamics see (``m_h`` acts on the measurement chain)
DYNAMIC_NUISANCE = ("damping_ratio", "eccentricity1_um", "profile_error_um")
#: signature entries that do not scale with the record's gain
SCALE_FREE = ("kurtosis", "crest", "tsa_kurtosis")
#: RMS change of the standardised train residuals below which a parameter is not identifiable
MIN_SENSITIVITY = 0.02
#: half-width of the nuisance's search around its declared values (unit coordinates: a factor
#: of 2.3 in damping ratio, of 4 in profile error)
EXPLORE_SPAN = 0.25
#: least-squares evaluations that polish a screened candidate's best grid point
SCREEN_NFEV = 6
#: simulations kept by :func:`responses`
CACHE_SIZE = 256


def declared_nuisance(scn: Scenario) -> dict[str, float]:
    """The nuisance parameters' configured values (the calibration's starting point)."""
    return {n: float(getattr(scn.dynamics, n)) for n in NUISANCE}


@dataclass(frozen=True)
class LoopSettings:
    """Settings of the loop (``loop.*`` in ``conf/loop/loop.yaml``), validated on construction."""

    segment_s: float = bounded(0.25, 0.0, 100.0, "analysis segment [s]; the model simulates one")
    transient_s: float = bounded(0.05, 0.0, 100.0, closed=True)
    test_fraction: float = bounded(0.3, 0.0, 1.0, "share of the records held out")
    seed: int = bounded(0, 0, 2**32 - 1, whole=True)
    # adopt an effect only if it cuts the held-out error by this share ...
    min_gain: float = bounded(0.2, 0.0, 1.0, closed=True)
    # ... and the BIC by this much ("very strong", Kass & Raftery 1995)
    min_delta_bic: float = bounded(10.0, 0.0, 1e6, closed=True)
    wear_grid: int = bounded(10, 2, 1000, "wear states of the model-based wear estimate",
                             whole=True)
    # least-squares evaluations per fit (finite-difference Jacobians not counted)
    max_nfev: int = bounded(20, 1, 100_000, whole=True)
    refine: int = bounded(3, 1, 100, "screened candidates refined jointly with the nuisance",
                          whole=True)
    explore: int = 32  # Sobol points searched before each refinement (0 or a power of 2)
    floor_db: float = bounded(0.3, 0.0, 100.0, "model error floor added to each entry's scatter",
                              closed=True)
    candidates: tuple[str, ...] | None = None  # effects to try; None: the whole library

    def __post_init__(self):
        validate_fields(self, "loop")
        e = self.explore
        if isinstance(e, bool) or not isinstance(e, int) or e < 0 or e & (e - 1):
            raise ValueError(f"loop.explore = {e!r} must be 0 or a power of 2 (a Sobol "
                             "sample keeps its balance only then); use e.g. 16 or 32")
        if self.candidates is not None:
            object.__setattr__(self, "candidates", tuple(self.candidates))
            unknown = sorted(set(self.candidates) - set(EFFECTS))
            if unknown or not self.candidates:
                raise ValueError(f"loop.candidates = {list(self.candidates)}: {unknown or 'none'}"
                                 f" not in the effect library; choose from {sorted(EFFECTS)}")


@dataclass
class LoopConfig(PhysicsConfig):
    """Schema of ``python -m physics.loop``."""

    data: str = MISSING  # a bundle folder (shared/specs/measured-bundle.md) or a feature table
    case: int | None = None  # 1-5: operating point and lubricant of Table 11 (feature tables)
    progress: bool = True
    loop: LoopSettings = field(default_factory=LoopSettings)


@dataclass
class Records:
    """The bundle's records as model inputs, with their measured signatures."""

    bundle: Bundle
    scenarios: list[Scenario]
    models: list[PairModel]  # declared model with worn teeth, default nuisance
    measured: list[np.ndarray]  # segment-averaged signature of each record [dB]
    entry_sd: np.ndarray  # scatter of each signature entry between segments [dB]
    names: list[str]  # the signature's entries
    noise_std: np.ndarray
    train: np.ndarray  # indices
    test: np.ndarray
    settings: LoopSettings
    wear_states: list[list[tuple[float, PairModel]]] = field(default_factory=list)
    cache: dict = field(default_factory=dict)  # simulations by dynamic parameters


def split_records(man: pd.DataFrame, test_fraction: float, seed: int) -> tuple[np.ndarray,
                                                                                np.ndarray]:
    """Train/test record indices: the manifest's split where given, else seeded by record."""
    given = man.split.fillna("").to_numpy()
    idx = np.arange(len(man))
    free = idx[given == ""]
    rng = np.random.default_rng(seed)
    n_test = max(1, round(test_fraction * len(free))) if len(free) > 1 else 0
    test_free = rng.choice(free, n_test, replace=False) if n_test else np.array([], int)
    test = np.sort(np.concatenate([idx[given == "test"], test_free]).astype(int))
    train = np.setdiff1d(idx, test)
    if len(train) == 0 or len(test) == 0:
        raise ValueError(f"the bundle needs at least one train and one test record (it has "
                         f"{len(man)} records); add records or set the split column")
    return train, test


def worn_models(scn: Scenario, ms: MeshStiffness, cycles: list[float]
                ) -> tuple[dict[float, PairModel], dict[float, float]]:
    """Declared models and pinion root wear [mm] at each cycle count of one operating point."""
    grid = sorted({0.0, *[float(c) for c in cycles]})
    models, root = {0.0: build_model(scn, ms)}, {0.0: 0.0}
    if grid[-1] > 0:
        res = simulate_dynamic_wear(scn, grid[-1], snapshots=grid[1:])
        for c in grid[1:]:
            w1, w2 = res.snapshots[c]
            models[c] = build_model(scn, ms, res.s, w1, w2)
            root[c] = float(w1[0]) * 1e3
    return models, root


def prepare(bundle: Bundle, base: Scenario, settings: LoopSettings) -> Records:
    """Scenarios, worn models, measured signatures, noise levels and the split of a bundle."""
    man = bundle.manifest
    scenarios = [record_scenario(base, row) for row in man.itertuples(index=False)]
    ms = MeshStiffness(base.gear, base.material)
    train, test = split_records(man, settings.test_fraction, settings.seed)
    keyed: dict[tuple, list[int]] = {}
    for i, row in enumerate(man.itertuples(index=False)):
        keyed.setdefault((row.n1_rpm, row.torque_Nm), []).append(i)
    models: list[PairModel | None] = [None] * len(man)
    wear_states: list[list[tuple[float, PairModel]]] = [[] for _ in range(len(man))]
    for idx in keyed.values():
        scn = scenarios[idx[0]]
        cycles = {i: record_cycles(scn, man.iloc[i]) for i in idx}
        known = [c for c in cycles.values() if c > 0]
        grid = list(np.linspace(0, 1.2 * max(known), settings.wear_grid)) if known else []
        by_cycles, root = worn_models(scn, ms, [*cycles.values(), *grid])
        for i in idx:
            models[i] = by_cycles[cycles[i]]
            wear_states[i] = [(root[float(g)], by_cycles[float(g)]) for g in grid]
    fs = man.fs_hz.to_numpy(float)
    segments = [signature_segments(bundle.signals[r], fs[i], *shaft_rates(scenarios[i]),
                                   scenarios[i].gear.z1, man.quantity.iloc[i] == "dte_m",
                                   settings.segment_s) for i, r in enumerate(man.record)]
    if len({s.shape[1] for s in segments}) != 1:
        raise ValueError("the records' signatures differ in length (mixed quantities, speeds "
                         "or sampling rates); split the bundle into bundles of one kind")
    if min(s.shape[0] for s in segments) < 2:
        raise ValueError(f"every record needs at least two analysis segments of "
                         f"{settings.segment_s:g} s (their scatter is the noise of the "
                         "comparison); lengthen the records or shorten segment_s")
    # one-segment model against an n-segment mean: var = sd^2 (1 + 1/n); pooled over the train
    # records (the test records' data enter only their own residuals)
    var = np.median([segments[i].var(axis=0, ddof=1) * (1 + 1 / segments[i].shape[0])
                     for i in train], axis=0)
    entry_sd = np.sqrt(var + settings.floor_db**2)
    f1, f2 = shaft_rates(scenarios[0])
    names = signature_names(f1, f2, base.gear.z1, fs[0], man.quantity.iloc[0] == "dte_m")
    noise = np.array([white_noise_std(bundle.signals[r], fs[i], 0.5 * f1 * base.gear.z1)
                      for i, r in enumerate(man.record)])
    return Records(bundle, scenarios, models, [s.mean(axis=0) for s in segments], entry_sd,
                   names, noise, train, test, settings, wear_states)


def cycles_for_wear(scn: Scenario, wear_mm: np.ndarray, cycles_max: float = 1.5e7
                    ) -> np.ndarray:
    """Cycle counts at which the model's pinion root wear reaches ``wear_mm``."""
    for _ in range(5):
        grid = np.linspace(0.0, cycles_max, 16)
        root = root_wear_evolution(scn, grid)[0] * 1e3
        if root[-1] >= np.max(wear_mm):
            return np.interp(wear_mm, root, grid)
        cycles_max *= 2
    raise ValueError(f"the model's root wear reaches only {root[-1]:.4g} mm in {cycles_max:.3g} "
                     f"cycles, below {np.max(wear_mm):g} mm: check the operating point and "
                     "tribology.regime")


def record_cycles(scn: Scenario, row: pd.Series) -> float:
    """A record's load cycles: stated, else those at which the model reaches its wear, else 0."""
    if not pd.isna(row.cycles):
        return float(row.cycles)
    if not pd.isna(row.wear_mm) and row.wear_mm > 0:
        return float(cycles_for_wear(scn, np.array([float(row.wear_mm)]))[0])
    return 0.0


def shaft_rates(scn: Scenario) -> tuple[float, float]:
    f1 = scn.operating.n1_rpm / 60
    return f1, f1 * scn.gear.z1 / scn.gear.z2


def with_nuisance(m: PairModel, nuisance: dict, base_ratio: float) -> PairModel:
    """The declared model with calibrated damping and error amplitudes."""
    return dataclasses.replace(
        m, damping=m.damping * nuisance["damping_ratio"] / base_ratio,
        long_error=nuisance["eccentricity1_um"] * 1e-6 * math.sin(m.geometry.alpha_w),
        short_error=nuisance["profile_error_um"] * 1e-6)


def responses(rec: Records, idx: np.ndarray, nuisance: dict, eff: Effect | None,
              values: dict, models: list[PairModel] | None = None) -> list[np.ndarray]:
    """Simulated DTE or mesh force (by each record's quantity) of records ``idx``, one analysis
    segment each.

    Memoised on the parameters the dynamics see (``rec.cache``): a change of the measurement
    chain's parameters (``m_h``, a transfer path, a sensor) reuses the simulation.
    """
    dynamic = eff is not None and eff.model is not None
    key = None
    if models is None:
        key = (tuple(int(i) for i in idx), tuple(nuisance[n] for n in DYNAMIC_NUISANCE),
               (eff.name, tuple(sorted(values.items()))) if dynamic else None)
        if key in rec.cache:
            return rec.cache[key]
    man = rec.bundle.manifest
    base_ratio = rec.scenarios[0].dynamics.damping_ratio
    ms = [with_nuisance(m, nuisance, base_ratio)
          for m in (models if models is not None else [rec.models[i] for i in idx])]
    if dynamic:
        ms = [eff.model(m, values) for m in ms]
    out: list[np.ndarray] = [np.empty(0)] * len(idx)
    fs_all = man.fs_hz.to_numpy(float)[idx]
    for fs in np.unique(fs_all):
        sel = np.flatnonzero(fs_all == fs)
        dyn = dataclasses.replace(rec.scenarios[0].dynamics, sample_rate_hz=float(fs),
                                  duration_s=rec.settings.segment_s,
                                  transient_s=rec.settings.transient_s, phase_bins=16)
        resp = simulate([ms[k] for k in sel], dyn)
        for j, k in enumerate(sel):
            out[k] = sensed(resp, man.quantity.iloc[idx[k]])[j]
    if key is not None:
        for x in out:
            x.flags.writeable = False  # shared by every later call with this key
        if len(rec.cache) >= CACHE_SIZE:
            rec.cache.pop(next(iter(rec.cache)))  # the oldest entry
        rec.cache[key] = out
    return out


def model_signals(rec: Records, idx: np.ndarray, nuisance: dict, eff: Effect | None,
                  values: dict, models: list[PairModel] | None = None) -> list[np.ndarray]:
    """Simulated records (one analysis segment each) of records ``idx`` through the chain:
    rigid-housing acceleration (or DTE), the effect's measurement stage, the record's noise."""
    man = rec.bundle.manifest
    raw = responses(rec, idx, nuisance, eff, values, models)
    out = []
    for k, i in enumerate(idx):
        x = declared_chain(raw[k], man.quantity.iloc[i], nuisance["housing_mass_kg"])
        if eff is not None and eff.record is not None:
            x = eff.record(x, float(man.fs_hz.iloc[i]), values)
        rng = np.random.default_rng([rec.settings.seed, int(i)])  # common numbers per record
        out.append(x + rec.noise_std[i] * rng.standard_normal(x.size))
    return out


def residuals_db(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> np.ndarray:
    """Measured minus model signature, (records ``idx``, entries) [dB]."""
    man = rec.bundle.manifest
    res = []
    for k, i in enumerate(idx):
        scn = rec.scenarios[i]
        sig = signature(signals[k], float(man.fs_hz.iloc[i]), *shaft_rates(scn), scn.gear.z1,
                        man.quantity.iloc[i] == "dte_m", rec.settings.segment_s)
        res.append(rec.measured[i] - sig)
    return np.array(res)


def residuals(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> np.ndarray:
    """Standardised residuals (dB residual over the entry's scatter), all records stacked."""
    return (residuals_db(rec, idx, signals) / rec.entry_sd).ravel()


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x**2)))


def to_unit(p: float, lo: float, hi: float, is_log: bool) -> float:
    return (math.log(p / lo) / math.log(hi / lo)) if is_log else (p - lo) / (hi - lo)


def from_unit(u: float, lo: float, hi: float, is_log: bool) -> float:
    return lo * (hi / lo) ** u if is_log else lo + u * (hi - lo)


def accel_in(rec: Records) -> bool:
    return bool((rec.bundle.manifest.quantity == "accel_m_s2").any())


def with_level(rec: Records, nuisance: dict, eff: Effect | None, values: dict) -> dict:
    """``m_h`` moved so that the model's level matches the train records' (acceleration only).

    ``m_h`` divides every amplitude, so in dB it is an offset of the entries that scale with
    the record (all but kurtosis and crest factors): one step of its weighted mean residual.
    The noise does not scale with it, so this is a starting value, not the fit.
    """
    if not accel_in(rec):
        return nuisance
    res = residuals_db(rec, rec.train, model_signals(rec, rec.train, nuisance, eff, values))
    w = np.where([n not in SCALE_FREE for n in rec.names], rec.entry_sd**-2.0, 0.0)
    offset = float(np.sum(res * w) / (res.shape[0] * np.sum(w)))
    lo, hi, _ = NUISANCE["housing_mass_kg"]
    return nuisance | {"housing_mass_kg": float(np.clip(
        nuisance["housing_mass_kg"] * 10 ** (-offset / 20), lo, hi))}


def train_cost(rec: Records, nuisance: dict, eff: Effect | None, values: dict) -> float:
    return float(np.sum(residuals(rec, rec.train, model_signals(rec, rec.train, nuisance, eff,
                                                                values)) ** 2))


def identifiable(rec: Records, nuisance: dict, names: tuple[str, ...]) -> list[str]:
    """Those of ``names`` that change the train residuals: each is moved by a tenth of its
    (log) range; one that moves the standardised residuals by less than ``MIN_SENSITIVITY``
    RMS is not identifiable from these records and stays at its declared value."""
    r0 = residuals(rec, rec.train, model_signals(rec, rec.train, nuisance, None, {}))
    out = []
    for n in names:
        u = to_unit(nuisance[n], *NUISANCE[n])
        moved = nuisance | {n: from_unit(u + (0.1 if u < 0.5 else -0.1), *NUISANCE[n])}
        r1 = residuals(rec, rec.train, model_signals(rec, rec.train, moved, None, {}))
        if rms(r1 - r0) >= MIN_SENSITIVITY:
            out.append(n)
    return out


def split_fitted(fitted: dict) -> tuple[dict, dict]:
    """(effect values with option, nuisance) of a fitted parameter set."""
    return ({k: v for k, v in fitted.items() if k not in NUISANCE},
            {n: fitted[n] for n in NUISANCE})


def least_squares(rec: Records, eff: Effect | None, fixed: dict, start: dict,
                  free: list[tuple[str, float, float, bool]], max_nfev: int) -> tuple[dict,
                                                                                      float]:
    """Bounded least squares of the train residuals over ``free`` parameters (name, bounds,
    log), in unit-scaled coordinates; ``fixed | start`` holds all values, the nuisance's and
    the effect's. Returns the fitted values and the train chi-square."""
    def values(u):
        return fixed | start | {n: from_unit(float(x), lo, hi, lg)
                                for (n, lo, hi, lg), x in zip(free, u, strict=True)}

    def fun(u):
        vals, nui = split_fitted(values(u))
        return residuals(rec, rec.train, model_signals(rec, rec.train, nui, eff, vals))

    if not free:
        return fixed | start, float(np.sum(fun(np.empty(0)) ** 2))
    u0 = np.array([np.clip(to_unit(start[n], lo, hi, lg), 0.001, 0.999)
                   for n, lo, hi, lg in free])
    sol = optimize.least_squares(fun, u0, bounds=(0, 1), diff_step=0.01, max_nfev=max_nfev)
    return values(sol.x), float(np.sum(sol.fun**2))


@dataclass
class Candidate:
    name: str
    option: dict
    values: dict  # the effect's parameters (with its option)
    nuisance: dict  # refitted with the effect
    train_rss: float
    n_params: int
    refined: bool = False
    heldout: float = math.nan
    bic: float = 0.0


def screen_effect(rec: Records, eff: Effect, option: dict, nuisance: dict) -> Candidate:
    """The effect at a grid of sizes over its parameters' ranges (nuisance at the calibration,
    ``m_h`` levelled at each), the best grid point polished by a short least squares of the
    effect's parameters and ``m_h`` (a grid step is a seventh of the range, a factor of 1.4
    even for a sensor gain, too coarse for a signature as sharp as a gain on the DTE mean)."""
    per = 7 if len(eff.params) == 1 else 5
    best = None
    for u in itertools.product(*[np.linspace(0.05, 0.95, per)] * len(eff.params)):
        vals = option | {p.name: from_unit(x, p.low, p.high, p.log)
                         for p, x in zip(eff.params, u, strict=True)}
        nui = with_level(rec, nuisance, eff, vals)
        cost = train_cost(rec, nui, eff, vals)
        if best is None or cost < best.train_rss:
            best = Candidate(eff.name, option, vals, nui, cost, len(eff.params))
    free = eff.bounds()
    free += [("housing_mass_kg", *NUISANCE["housing_mass_kg"])] if accel_in(rec) else []
    fitted, rss = least_squares(rec, eff, option, best.values | best.nuisance, free, SCREEN_NFEV)
    vals, nui = split_fitted(fitted)
    return dataclasses.replace(best, values=vals, nuisance=nui, train_rss=rss)


def explore(rec: Records, eff: Effect | None, c: Candidate, free_nuisance: list[str]
            ) -> Candidate:
    """The best of ``c`` and a scrambled Sobol sample (``settings.explore`` points) over the
    effect's whole range and the dynamic nuisance within ``EXPLORE_SPAN`` (unit coordinates)
    of its declared values, ``m_h`` levelled at each. A missing effect drags the calibration
    (to the bounds, at worst), and least squares from a single start stays in its basin; the
    declared values are the prior that does not depend on the fit."""
    params = eff.params if eff is not None else ()
    dyn = [n for n in free_nuisance if n in DYNAMIC_NUISANCE]
    prior = declared_nuisance(rec.scenarios[0])
    dim = len(params) + len(dyn)
    pts = (qmc.Sobol(dim, seed=rec.settings.seed).random(rec.settings.explore) if dim
           else np.empty((0, 0)))
    best = c
    for u in pts:
        vals = c.option | {p.name: from_unit(float(x), p.low, p.high, p.log)
                           for p, x in zip(params, u, strict=False)}
        nui = dict(c.nuisance)
        for n, x in zip(dyn, u[len(params):], strict=True):
            centre = to_unit(prior[n], *NUISANCE[n])
            nui[n] = from_unit(float(np.clip(centre + EXPLORE_SPAN * (2 * x - 1), 0, 1)),
                               *NUISANCE[n])
        nui = with_level(rec, nui, eff, vals)
        cost = train_cost(rec, nui, eff, vals)
        if cost < best.train_rss:
            best = dataclasses.replace(c, values=vals, nuisance=nui, train_rss=cost)
    return best


def search(rec: Records, eff: Effect | None, c: Candidate, free_nuisance: list[str]
           ) -> Candidate:
    """The model's (the declared one's, ``eff`` None, or with an effect) parameters fitted on
    the train records: the best explored start refined by least squares, the effect's
    parameters jointly with the identifiable nuisance. The declared model and every refined
    candidate get the same search."""
    c = explore(rec, eff, c, free_nuisance)
    free = eff.bounds() if eff is not None else []
    free += [(n, *NUISANCE[n]) for n in free_nuisance]
    fitted, rss = least_squares(rec, eff, c.option, c.values | c.nuisance, free,
                                rec.settings.max_nfev)
    vals, nui = split_fitted(fitted)
    return dataclasses.replace(c, values=vals, nuisance=nui, train_rss=rss, refined=True)


def calibrate(rec: Records, start: dict) -> tuple[dict, list[str]]:
    """Fit the declared nuisance parameters on the train records (from their declared
    values); returns the calibrated nuisance and the names of the free ones. ``m_h`` scales
    every acceleration amplitude and is always free for acceleration records; a dynamic
    parameter that is not identifiable stays at its declared value."""
    start = with_level(rec, start, None, {})
    free = identifiable(rec, start, DYNAMIC_NUISANCE)
    free += ["housing_mass_kg"] if accel_in(rec) else []
    c = Candidate("declared", {}, {}, start, train_cost(rec, start, None, {}), 0)
    return search(rec, None, c, free).nuisance, free


def bic(chi2: float, n: int, k: int) -> float:
    """Bayesian information criterion of standardised residuals (known scatter)."""
    return chi2 + k * math.log(n)


def feature_error(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> float:
    """Mean relative error of the Table 13 features, model against measurement [%]."""
    errs = []
    for k, i in enumerate(idx):
        meas = features(rec.bundle.signals[rec.bundle.records[i]])
        mod = features(signals[k])
        errs += [abs(float(mod[f]) / float(meas[f]) - 1) * 100 for f in FEATURES]
    return float(np.mean(errs))


def wear_estimates(rec: Records, idx: np.ndarray, nuisance: dict, eff: Effect | None,
                   values: dict) -> np.ndarray:
    """Model-based wear estimate of each record: the wear state of nearest signature [mm]."""
    out = []
    for i in idx:
        states = rec.wear_states[i]
        if not states:
            out.append(np.nan)
            continue
        wear = np.array([w for w, _ in states])
        sig = model_signals(rec, np.array([i] * len(states)), nuisance, eff, values,
                            models=[m for _, m in states])
        cost = np.array([rms(residuals(rec, np.array([i]), [s])) for s in sig])
        j = int(np.argmin(cost))
        if 0 < j < len(cost) - 1:  # parabolic refinement between grid states
            c0, c1, c2 = cost[j - 1:j + 2]
            d = c0 - 2 * c1 + c2
            shift = 0.5 * (c0 - c2) / d if d > 0 else 0.0
            out.append(float(np.interp(j + np.clip(shift, -1, 1), np.arange(len(wear)), wear)))
        else:
            out.append(float(wear[j]))
    return np.array(out)


def residual_table(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> pd.Series:
    """Mean dB residual of each signature entry over records ``idx``."""
    return pd.Series(residuals_db(rec, idx, signals).mean(axis=0), index=rec.names)


def candidates_for(quantities: set[str], settings: LoopSettings) -> list[tuple[Effect, dict]]:
    """(effect, option) pairs to try: the library's (or ``settings.candidates``) effects that can
    show in the records' quantities."""
    names = settings.candidates if settings.candidates is not None else tuple(EFFECTS)
    unknown = sorted(set(names) - set(EFFECTS))
    if unknown:
        raise ValueError(f"loop.candidates: {unknown} not in the effect library; choose from "
                         f"{sorted(EFFECTS)}")
    return [(EFFECTS[n], o) for n in names if quantities & set(EFFECTS[n].quantities)
            for o in EFFECTS[n].options]


def run_loop(bundle: Bundle, base: Scenario, settings: LoopSettings | None = None,
             progress: bool = False) -> LoopReport:
    """The whole loop on one bundle; returns its report (see the module text)."""
    settings = settings or LoopSettings()
    candidates = candidates_for(set(bundle.manifest.quantity), settings)
    rec = prepare(bundle, base, settings)
    nuisance, free_nuisance = calibrate(rec, declared_nuisance(base))
    base_train = model_signals(rec, rec.train, nuisance, None, {})
    base_test = model_signals(rec, rec.test, nuisance, None, {})
    null_res = residuals(rec, rec.train, base_train)
    n_train = null_res.size
    null_bic = bic(float(np.sum(null_res**2)), n_train, 0)
    before = rms(residuals(rec, rec.test, base_test))
    ranking = [screen_effect(rec, eff, option, nuisance)
               for eff, option in tqdm(candidates, desc="screening", disable=not progress)]
    ranking.sort(key=lambda c: c.train_rss)
    top = settings.refine
    ranking[:top] = [search(rec, EFFECTS[c.name], c, free_nuisance)
                     for c in tqdm(ranking[:top], desc="refining", disable=not progress)]
    for c in ranking:
        c.heldout = rms(residuals(rec, rec.test, model_signals(rec, rec.test, c.nuisance,
                                                                  EFFECTS[c.name], c.values)))
        c.bic = bic(c.train_rss, n_train, c.n_params)
        log.info("%s %s: held-out %.2f (baseline %.2f), dBIC %.1f%s", c.name, c.option,
                 c.heldout, before, c.bic - null_bic, "" if c.refined else " (screened)")
    ranking.sort(key=lambda c: c.heldout)
    best = ranking[0]
    adopt = adopts(best.heldout, before, best.bic - null_bic, settings.min_gain,
                   settings.min_delta_bic)
    chosen = EFFECTS[best.name] if adopt else None
    after_nui = best.nuisance if adopt else nuisance
    after_vals = best.values if adopt else {}
    after_test = (model_signals(rec, rec.test, after_nui, chosen, after_vals) if adopt
                  else base_test)
    man = bundle.manifest
    known = np.array([i for i in rec.test if not pd.isna(man.wear_mm.iloc[i])
                      and rec.wear_states[i]], int)
    wear_err = {}
    if known.size:
        true = man.wear_mm.to_numpy(float)[known]
        for key, (nui, eff, vals) in {"before": (nuisance, None, {}),
                                      "after": (after_nui, chosen, after_vals)}.items():
            est = wear_estimates(rec, known, nui, eff, vals)
            ok = true > 0
            wear_err[key] = (float(np.mean(np.abs(est[ok] - true[ok]) / true[ok]) * 100)
                             if ok.any() else float(np.mean(np.abs(est - true))))
    rec.cache.clear()  # the report keeps the records, not the simulations
    return LoopReport(
        mode="bundle",
        chosen_effect=chosen.name if chosen else None,
        chosen_option=best.option if adopt else None,
        chosen_parameters=({k: v for k, v in best.values.items() if k not in best.option}
                           if adopt else None),
        error_before=before,
        error_after=rms(residuals(rec, rec.test, after_test)),
        error_unit="RMS of the held-out records' signature residuals, each in units of its "
                   "own scatter between segments (1: at the noise)",
        feature_error_before_pct=feature_error(rec, rec.test, base_test),
        feature_error_after_pct=feature_error(rec, rec.test, after_test),
        wear_error_before_pct=wear_err.get("before"),
        wear_error_after_pct=wear_err.get("after"),
        calibration=nuisance,
        calibrated_on="the train records",
        nuisance_after=after_nui,
        null_bic=null_bic,
        ranking=[{"effect": c.name, "option": c.option,
                  "parameters": {k: v for k, v in c.values.items() if k not in c.option},
                  "nuisance": c.nuisance, "refined": c.refined,
                  "heldout_error": c.heldout, "delta_bic": c.bic - null_bic,
                  "n_params": c.n_params} for c in ranking],
        decision_rule={"min_gain": settings.min_gain, "min_delta_bic": settings.min_delta_bic},
        details={
            "error_before_db": rms(residuals_db(rec, rec.test, base_test)),
            "error_after_db": rms(residuals_db(rec, rec.test, after_test)),
            "not_identifiable": [n for n in DYNAMIC_NUISANCE if n not in free_nuisance],
            "train_records": [bundle.records[i] for i in rec.train],
            "test_records": [bundle.records[i] for i in rec.test],
            "residual_before": residual_table(rec, rec.test, base_test).to_dict(),
            "residual_after": residual_table(rec, rec.test, after_test).to_dict(),
        },
        signals={"test": rec.test, "before": base_test, "after": after_test, "rec": rec},
    )
