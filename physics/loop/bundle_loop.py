"""Close the loop with measured data: calibrate, find the residual, attribute it, extend, report.

``python -m physics.loop data=BUNDLE`` (Hydra app, ``conf/loop.yaml``) runs the steps below on a
measured bundle (:mod:`physics.bundle`) and writes ``report.json``, ``report.md`` and figures into
its run folder.

1. **Records**: each record becomes a scenario (its speed, torque, lubricant and gear overrides)
   with its worn teeth: the dynamically coupled wear evolution (:mod:`physics.evolution`) is run
   once per operating point to the records' cycle counts (or, where only the wear depth is known,
   to the cycle count of that depth). A bundle may mix operating points, quantities, sampling
   rates and record lengths: records of one (speed, torque, quantity, sampling rate) form a
   **group** (:class:`Group`) with its own signature definition and entry scatter. Records are
   split into train and test by record within each group (the manifest's ``split`` column
   where given, else seeded), never by windows of one record.
2. **Calibration** of the declared nuisance parameters on the train records of all groups at
   once, before any effect is considered: the physical ones (mesh damping ratio, pinion run-out
   and profile error amplitudes, the once-per-revolution mesh modulation that the run-out makes,
   with its phase, :data:`RUNOUT_MODULATION` and :func:`with_modulation`, and with
   ``loop.model_form`` the rest of the model's own form uncertainty, :data:`MODEL_FORM`:
   mesh-stiffness level, double/single stiffness ratio, effective mass and backlash,
   :func:`with_model_form`) are one value for the whole bundle; the measurement chain's (the
   housing's effective mass ``m_h`` and, where the scenario declares them, the bearing support's
   mode and the housing mounting's, each with its damping, :data:`CHAIN_MODES`) belong to the
   acceleration records only; the groups' standardised residuals are concatenated into one cost.
   With a **reference** (``reference=``, :mod:`physics.loop.form_reference`: a sister
   gearbox's clean records at the same operating points and sensors), the declared model is
   first calibrated on those, and its mean residual per group and entry there, the model's
   own form error, is removed from the measured signatures before this calibration.
   A parameter that does not move the residuals (the pinion run-out on the line of action: a
   shaft-rate error is dynamically inert in the torsional model; the modulation's phase, which
   no amplitude of the signature sees unless another once-per-revolution feature is in the
   model; the backlash in acceleration records whose flanks never part) is held at its declared
   value and reported as not identifiable. Every candidate effect is then fitted jointly with
   the free parameters, model form included. The search (:func:`search`): a scrambled Sobol
   sample around the declared values, ``m_h`` levelled at each point, the best refined by
   bounded least squares on the standardised signature residuals. Measurement noise is not
   fitted: its level is read off each record's spectral floor
   (:func:`physics.order_analysis.white_noise_std`) and white noise of that level (seeded per
   record) is added to the model's record.
3. **Residual and model discrepancy**: the signature of :mod:`physics.order_analysis` (mesh
   harmonics with pinion and gear sidebands up to 0.45 fs, half-octave bands, statistics,
   synchronous-average kurtosis, all in dB) of measurement minus calibrated model, per entry,
   divided by the entry's scatter between the measured records' segments (pooled over the
   group's train records, plus a floor ``floor_db``) and a model discrepancy in quadrature.
   The discrepancy (:func:`discrepancy_sd`) is estimated on the train residuals of the
   calibrated declared model, per entry family and group: with it the RMS standardised
   residual is about 1 where model and measurement agree up to noise and the model's known
   form error. It enters the judgement (held-out errors, the null test), not the fits: the
   calibration and every candidate's fit weigh the residuals by the noise alone, because a
   discrepancy estimated on records where an effect is missing is large exactly in that
   effect's entries and would down-weight them in its fit (a tip relief of 16 um in the
   project's own records was fitted at 11 um with it). The report's headline error stays in
   units of the noise alone.
4. **Attribution**: every effect of :mod:`physics.effects` that can show in the bundle's
   quantities is added in turn (a measurement-chain effect acts only on its own quantities).
   Screening: the effect at a grid of sizes, nuisance at the calibration, the best size
   polished by a short least squares. Every candidate (or the best ``refine`` by train
   chi-square) then gets the same search as the calibration, their parameters jointly with the
   identifiable nuisance (a missing effect biases the calibration, at worst to its bounds,
   so the nuisance must move with the effect). Candidates are ranked by held-out error (RMS
   standardised residual, with discrepancy, over the test records) with the Bayesian
   information criterion on the train records beside it (chi-square plus k ln n, the scatter
   being known, k the effect's parameters).
   The **null test** (:func:`physics.loop.report.null_test`), judged where each candidate's own
   signature lives (the entries its model moves by more than their noise,
   :func:`signature_gain`): the best by held-out error of those that pass it is adopted (a
   candidate that soaks up form error across the spectrum can rank first and fail it while the
   effect in the data passes); a candidate passes only if it lowers the held-out error there (in
   units of the noise) by at least ``min_gain`` (20 %), its BIC by at least ``min_delta_bic``
   (10, "very strong" on Kass & Raftery's scale), and, in every group where it shows (of the
   quantities it can act on), removes more standardised sum of squares per held-out record than
   the discrepancy lets a candidate of its size absorb by chance
   (:func:`discrepancy_allowance`). The records' wear takes no part in this decision: an adopted
   effect **reads the wear** (item 6) only if, where the train records' wear is known, it does
   not lower the model-based wear estimate's leave-one-out skill on them by more than
   ``max_wear_loss`` (0.1: its mean absolute error may grow by a tenth of the constant guess's;
   :func:`wear_check`); else the model before it keeps reading it. The held-out records' wear is
   only scored, before and after, never used to decide (a decision on it would leave the
   held-out score no longer held out). The rule is designed
   for a false-add rate of ``false_add_rate`` (1 %) per bundle when the declared model's form
   error is unstructured (no effect of the library resembles it); a form error that looks like
   an effect is not separable from it by any rule on these data. Each candidate's
   **separability** is reported beside it (:func:`separable_share`): the share of its change
   of the train residuals that no linear combination of the free nuisance's directions
   reproduces (near 0: the declared model's own freedom makes the same change; a DTE sensor
   gain against a free stiffness level, whose lengths scale out of the equation of motion, is
   the exact case).
   **Greedy second round** (:func:`attribute` again): once an effect is adopted, every other
   effect is tried on the model that carries it (:func:`stacked`, the first's parameters
   held at their fit, the nuisance refitted), judged by the same rule against that model.
5. **Report**: error before and after on the held-out records, overall and per group, as the
   standardised signature residual (noise alone: the figure the report leads with; noise and
   discrepancy) and in dB, as the mean relative error of the Table 13 features [%], and,
   where the wear is known, as the error of a model-based wear estimate (the wear state whose
   simulated signature is nearest, relative to the group's train records of known wear:
   :func:`wear_estimates`) [%] and as its skill against the train records' mean wear
   (:func:`wear_skill`; at or below 0 the estimate reads no wear on these records, and the
   choice of the model that reads it above then compares noise).
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import pandas as pd
from omegaconf import MISSING
from scipy import optimize
from scipy.stats import chi2, qmc
from tqdm import tqdm

from physics.dynamics.evolution import root_wear_evolution, simulate_dynamic_wear
from physics.dynamics.model import PairModel, build_model, simulate
from physics.dynamics.model_form import with_model_form
from physics.gear.stiffness import MeshStiffness
from physics.loop.bundle import Bundle, record_scenario
from physics.loop.effects import EFFECTS, Effect, revolution_tables
from physics.loop.report import LoopReport, first_passing, holds, null_test
from physics.params import PhysicsConfig, Scenario, bounded, validate_fields
from physics.signals.features import FEATURES, features
from physics.signals.measurement import declared_chain, sensed
from physics.signals.order_analysis import (
    mean_signatures,
    signature_names,
    signature_segments,
    white_noise_std,
)

log = logging.getLogger(__name__)

#: declared nuisance parameters of the scenario: name, bounds, log-scaled
NUISANCE = {"damping_ratio": (0.01, 0.3, True), "eccentricity1_um": (0.2, 60.0, True),
            "profile_error_um": (0.1, 30.0, True), "housing_mass_kg": (0.01, 1e5, True)}
#: the declared model's own form uncertainty (:func:`with_model_form`): name, bounds,
#: log-scaled, the neutral value (None: the scenario's). Calibrated with the nuisance above,
#: before any effect is considered; at the neutral values the model is the declared one.
MODEL_FORM = {"stiffness_factor": (0.5, 2.0, True, 1.0),
              "resonance_factor": (0.5, 2.0, True, 1.0),
              "double_contact_factor": (0.6, 1.6, True, 1.0),
              "half_backlash_um": (0.5, 200.0, True, None),
              "mesh_modulation": (0.0, 0.2, False, 0.0),
              "modulation_phase_rad": (0.0, 2 * math.pi, False, 0.0)}
#: the declared bearing-support mode of the acceleration chain
#: (:func:`physics.signals.measurement.support_path`): name, bounds, log-scaled. Calibrated with
#: ``m_h`` where the scenario declares one (``dynamics.support_hz`` > 0), around that value.
SUPPORT = {"support_hz": (200.0, 20000.0, True), "support_damping": (0.005, 0.3, True)}
#: the declared mode of the housing on its mounting
#: (:func:`physics.signals.measurement.housing_mount`) where the scenario states one
#: (``dynamics.mount_hz`` > 0): held at the stated values, not calibrated. Its own lines, the
#: shaft orders, carry little, and above it the mode tilts the lowest mesh harmonics: freed,
#: on records of a housing mounted at 55 Hz stated as 90 Hz, the fit took it to 330 Hz
MOUNT = {"mount_hz": (5.0, 1000.0, True), "mount_damping": (0.02, 0.5, True)}
#: the acceleration chain's modes, each by the frequency that declares it
CHAIN_MODES = {"support_hz": SUPPORT, "mount_hz": MOUNT}
CHAIN = SUPPORT | MOUNT
#: bounds of every nuisance parameter of the declared model (the calibrated ones' search range;
#: the stated mounting's, the range its stated values must lie in)
BOUNDS = NUISANCE | CHAIN | {n: b[:3] for n, b in MODEL_FORM.items()}
#: the nuisance parameters the dynamics see (``m_h`` acts on the measurement chain); the model
#: form's only with ``loop.model_form``
SCENARIO_DYNAMIC = ("damping_ratio", "eccentricity1_um", "profile_error_um")
DYNAMIC_NUISANCE = (*SCENARIO_DYNAMIC, *MODEL_FORM)
#: the once-per-revolution mesh modulation that the declared pinion run-out makes in every
#: real gearbox (:func:`with_modulation`), calibrated with or without ``loop.model_form``: the
#: thesis's run-out on the line of action alone is dynamically inert, and a mesh without it
#: left every independent DTE bundle's pinion sidebands to ``torque_ripple``, the clean ones too
RUNOUT_MODULATION = ("mesh_modulation", "modulation_phase_rad")
#: the parameters a Sobol sample explores before least squares (their residual surface has
#: several basins): the dynamic ones and the support mode's (a basin per mesh harmonic it can
#: sit on)
EXPLORED = (*DYNAMIC_NUISANCE, *SUPPORT)
#: signature entries that do not scale with the record's gain
SCALE_FREE = ("kurtosis", "crest", "tsa_kurtosis")
#: RMS change of the standardised train residuals below which a parameter is not identifiable
MIN_SENSITIVITY = 0.02
#: half-width of the nuisance's search around its declared values (unit coordinates: a factor
#: of 2.3 in damping ratio, of 4 in profile error)
EXPLORE_SPAN = 0.25
#: the calibration explores this many times ``loop.explore`` points (its model form over the
#: whole range: the resonance's residual surface has a basin per mesh harmonic it can sit on)
CALIBRATION_EXPLORE = 4
#: ... and refines this many of its best points by least squares, keeping the best fit: from
#: one start the fit ends in the basin of whichever point the exploration ranks first, which the
#: last digits of the signatures decide (one independent bundle, a rounding change: train
#: chi-square 43,394 -> 47,860, stiffness factor 0.83 -> 0.64)
CALIBRATION_STARTS = 3
#: least-squares evaluations that polish a screened candidate's best grid point
SCREEN_NFEV = 6
#: unit-coordinate step of the free parameters' directions that judge a candidate's
#: separability (:func:`free_directions`)
SEPARABILITY_STEP = 0.02
#: simulations kept by :func:`responses`
CACHE_SIZE = 256


def declared_nuisance(scn: Scenario) -> dict[str, float]:
    """The nuisance parameters' configured values (the calibration's starting point, with
    :func:`declared_model_form`)."""
    return {n: float(getattr(scn.dynamics, n)) for n in NUISANCE}


def declared_model_form(scn: Scenario) -> dict[str, float]:
    """The model-form parameters at their neutral values (the declared model itself)."""
    return {n: float(getattr(scn.dynamics, n) if b[3] is None else b[3])
            for n, b in MODEL_FORM.items()}


def declared_modes(scn: Scenario) -> dict[str, float]:
    """The acceleration chain's declared modes (:data:`CHAIN_MODES`: the bearing support's,
    none for a rigid support, ``dynamics.support_hz`` = 0; the mounting's, none for a free
    housing, ``dynamics.mount_hz`` = 0); a declared mode outside the loop's bounds is
    refused."""
    dyn = scn.dynamics
    out = {}
    for key, mode in CHAIN_MODES.items():
        if getattr(dyn, key) == 0:
            continue
        for n, (lo, hi, _) in mode.items():
            if not lo <= getattr(dyn, n) <= hi:
                raise ValueError(f"dynamics.{n} = {getattr(dyn, n)!r} must lie in [{lo:g}, "
                                 f"{hi:g}] for the loop to use it; state the mode inside that "
                                 f"range or set dynamics.{key}=0 (no such mode)")
        out |= {n: float(getattr(dyn, n)) for n in mode}
    return out


def modes_of(nuisance: dict) -> dict[str, float]:
    """The chain modes' entries of ``nuisance`` (none: a rigid support and a free housing), as
    :func:`physics.signals.measurement.declared_chain` takes them."""
    return {n: nuisance[n] for n in CHAIN if n in nuisance}


def completed(nuisance: dict, scn: Scenario) -> dict:
    """``nuisance`` with the model-form parameters it lacks at their neutral values."""
    return declared_model_form(scn) | nuisance


@dataclass(frozen=True)
class LoopSettings:
    """Settings of the loop (``loop.*`` in ``conf/loop/loop.yaml``), validated on construction."""

    segment_s: float = bounded(0.25, 0.0, 100.0, "analysis segment [s]; the model simulates one")
    transient_s: float = bounded(0.05, 0.0, 100.0, closed=True)
    # RK4 step of the model's records (``dynamics.step_factor`` for the loop's simulations
    # only; the wear and the datasets keep theirs): 0.5 moves the signature by 0.12-0.23
    # noise sd RMS against 0.25, a sixteenth of what starting the record 0.1 ms later moves
    # it (2.6-3.8), and halves the integration (docs/measured-data.md, the loop's time)
    step_factor: float = bounded(0.5, 0.0, 2.78, "omega_max dt of the model's records; above "
                                 "2.78 fourth-order Runge-Kutta is unstable")
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
    # screened candidates refined jointly with the nuisance (the library has at most nine per
    # bundle: by default every one; the screen alone, on a calibration that has absorbed part of
    # an effect, ranked an independent bundle's friction below three others)
    refine: int = bounded(100, 1, 100, "screened candidates refined jointly with the nuisance",
                          whole=True)
    explore: int = 32  # Sobol points searched before each refinement (0 or a power of 2)
    floor_db: float = bounded(0.3, 0.0, 100.0, "model error floor added to each entry's scatter",
                              closed=True)
    # the model discrepancy: weight of the pooled variance in each entry family's estimate, in
    # residuals (:func:`discrepancy_sd`) ...
    discrepancy_prior: float = bounded(10.0, 0.0, 1e6, closed=True)
    # ... and the false-add rate per bundle the adoption rule is designed for
    false_add_rate: float = bounded(0.01, 0.0, 1.0, "share of bundles without an effect that "
                                    "may get one")
    candidates: tuple[str, ...] | None = None  # effects to try; None: the whole library
    # an adopted effect reads the wear unless it lowers the model-based wear estimate's
    # leave-one-out skill on the train records of known wear by more than this
    # (:func:`wear_check`)
    max_wear_loss: float = bounded(0.1, 0.0, 100.0, "skill of the wear estimate an adopted "
                                   "effect may cost", closed=True)
    # calibrate the rest of the declared model's form uncertainty (:data:`MODEL_FORM`: the run-out
    # modulation is calibrated either way) with the nuisance;
    # off by default: better on the independent simulator's bundles, but on the project's own
    # it absorbs a friction, leaves a tooth defect's error above half and lets the greedy
    # second round stack a spurious effect (docs/measured-data.md, 2026-11-24)
    model_form: bool = False

    def __post_init__(self):
        validate_fields(self, "loop")
        if not isinstance(self.model_form, bool):
            raise ValueError(f"loop.model_form = {self.model_form!r} must be true or false")
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
    # a bundle of a sister gearbox without the effects sought, at the same operating points,
    # quantities and sampling rates: the declared model's mean form error is measured on it
    # and removed (physics.loop.form_reference); None: no reference
    reference: str | None = None
    case: int | None = None  # 1-5: operating point and lubricant of Table 11 (feature tables)
    progress: bool = True
    loop: LoopSettings = field(default_factory=LoopSettings)


@dataclass(frozen=True)
class Group:
    """Records of one operating point, quantity and sampling rate: one signature definition.

    ``entry_sd`` is each entry's scatter between the measured segments (noise), ``discrepancy_sd``
    the model-form discrepancy of :func:`discrepancy_sd` (zero until it is estimated); a
    residual is standardised by their quadrature sum, :attr:`sd`.
    """

    key: tuple[float, float, str, float]  # n1_rpm, torque_Nm, quantity, fs_hz
    records: np.ndarray  # indices into the bundle
    names: list[str]  # the signature's entries
    entry_sd: np.ndarray  # [dB]
    discrepancy_sd: np.ndarray  # [dB]

    @property
    def sd(self) -> np.ndarray:
        return np.hypot(self.entry_sd, self.discrepancy_sd)

    @property
    def label(self) -> str:
        return group_label(self.key)


def group_label(key: tuple[float, float, str, float]) -> str:
    """A group's name: ``<n1>rpm_<torque>Nm_<quantity>_<fs>Hz``."""
    n1, torque, quantity, fs = key
    return f"{n1:g}rpm_{torque:g}Nm_{quantity}_{fs:g}Hz"


@dataclass
class Records:
    """The bundle's records as model inputs, with their measured signatures."""

    bundle: Bundle
    scenarios: list[Scenario]
    models: list[PairModel]  # declared model with worn teeth, default nuisance
    measured: list[np.ndarray]  # segment-averaged signature of each record [dB]
    groups: list[Group]
    group_of: np.ndarray  # each record's index into ``groups``
    noise_std: np.ndarray
    train: np.ndarray  # indices
    test: np.ndarray
    settings: LoopSettings
    wear_states: list[list[tuple[float, PairModel]]] = field(default_factory=list)
    cache: dict = field(default_factory=dict)  # simulations by dynamic parameters

    def group(self, i: int) -> Group:
        """The group of record ``i``."""
        return self.groups[self.group_of[i]]


@dataclass(frozen=True)
class FormReference:
    """Mean signature residual [dB] of the calibrated declared model on a reference gearbox's
    records, per group key ``(n1_rpm, torque_Nm, quantity, fs_hz)``: the discrepancy's mean
    (:func:`physics.loop.form_reference.form_reference` measures it)."""

    offsets: dict[tuple, np.ndarray]
    records: dict[tuple, int]  # reference records behind each group's mean
    gear: dict  # the reference bundle's gear overrides (the type both units must share)
    calibration: dict  # the reference's calibrated nuisance

    def check(self, bundle: Bundle) -> None:
        """Refuse a bundle this reference cannot serve (:func:`check_reference`)."""
        check_reference(bundle, self.gear, list(self.offsets))

    def subtracted(self, rec: Records) -> Records:
        """``rec`` with each record's measured signature less its group's reference mean."""
        measured = [m - self.offsets[rec.group(i).key] for i, m in enumerate(rec.measured)]
        return dataclasses.replace(rec, measured=measured)

    def summary(self) -> dict:
        """For the report: each group's reference records and RMS mean residual [dB]."""
        return {"records": {group_label(k): n for k, n in self.records.items()},
                "rms_offset_db": {group_label(k): rms(v) for k, v in self.offsets.items()},
                "calibration": self.calibration}


def check_reference(bundle: Bundle, gear: dict, keys: list[tuple]) -> None:
    """Refuse, before any work, a reference of gear overrides ``gear`` and group ``keys`` for
    ``bundle``: another gear, or a group (operating point, quantity, sampling rate) of the
    bundle the reference has no records of."""
    if bundle.gear != gear:
        raise ValueError(f"reference: its gear.yaml overrides {gear} differ from the "
                         f"bundle's {bundle.gear}; the reference must be a gearbox of the "
                         "same type (same gear data); record it with the same gear.yaml")
    missing = [group_label(k) for k in group_keys(bundle.manifest)[0] if k not in keys]
    if missing:
        raise ValueError(f"reference: no records at {missing} (the reference has "
                         f"{[group_label(k) for k in keys]}); its mean residual is per "
                         "operating point, quantity and sampling rate: record the reference "
                         "gearbox at each of them, or leave out reference=")


def split_records(man: pd.DataFrame, test_fraction: float, seed: int,
                  strata: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Train/test record indices: the manifest's split where given, else seeded by record,
    within each stratum (group of :func:`group_keys`) so that every group with two free
    records holds some out."""
    given = man.split.astype("string").fillna("").to_numpy(str)
    idx = np.arange(len(man))
    strata = np.zeros(len(man), int) if strata is None else np.asarray(strata)
    rng = np.random.default_rng(seed)
    test = [idx[given == "test"]]
    for s in dict.fromkeys(strata.tolist()):  # in order of first appearance
        free = idx[(given == "") & (strata == s)]
        n_test = max(1, round(test_fraction * len(free))) if len(free) > 1 else 0
        if n_test:
            test.append(rng.choice(free, n_test, replace=False))
    test = np.sort(np.concatenate(test).astype(int))
    train = np.setdiff1d(idx, test)
    if len(train) == 0 or len(test) == 0:
        raise ValueError(f"the bundle needs at least one train and one test record (it has "
                         f"{len(man)} records); add records or set the split column")
    return train, test


def group_keys(man: pd.DataFrame) -> tuple[list[tuple], np.ndarray]:
    """The distinct (n1_rpm, torque_Nm, quantity, fs_hz) of a manifest, in order of first
    appearance, and each record's index into them."""
    keys = list(zip(man.n1_rpm.astype(float), man.torque_Nm.astype(float), man.quantity,
                    man.fs_hz.astype(float), strict=True))
    distinct = list(dict.fromkeys(keys))
    return distinct, np.array([distinct.index(k) for k in keys], int)


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
    """Scenarios, worn models, measured signatures, noise levels, groups and the split of a
    bundle. Records of one operating point, quantity and sampling rate form a group with its
    own signature definition and entry scatter; a bundle may hold any number of groups."""
    man = bundle.manifest
    scenarios = [record_scenario(base, row) for row in man.itertuples(index=False)]
    ms = MeshStiffness(base.gear, base.material)
    keys, group_of = group_keys(man)
    train, test = split_records(man, settings.test_fraction, settings.seed, group_of)
    keyed: dict[tuple, list[int]] = {}
    for i, row in enumerate(man.itertuples(index=False)):
        keyed.setdefault((row.n1_rpm, row.torque_Nm), []).append(i)
    models: list[PairModel | None] = [None] * len(man)
    wear_states: list[list[tuple[float, PairModel]]] = [[] for _ in range(len(man))]
    for idx in keyed.values():
        scn = scenarios[idx[0]]
        cycles = dict(zip(idx, records_cycles(scn, man.iloc[idx]), strict=True))
        grid = wear_grid_cycles(scn, max(cycles.values()), settings.wear_grid)
        by_cycles, root = worn_models(scn, ms, [*cycles.values(), *grid])
        for i in idx:
            models[i] = by_cycles[cycles[i]]
            wear_states[i] = [(root[float(g)], by_cycles[float(g)]) for g in grid]
    fs = man.fs_hz.to_numpy(float)
    dte = (man.quantity == "dte_m").to_numpy()
    segments = [signature_segments(bundle.signals[r], fs[i], *shaft_rates(scenarios[i]),
                                   scenarios[i].gear.z1, dte[i], settings.segment_s)
                for i, r in enumerate(man.record)]
    if min(s.shape[0] for s in segments) < 2:
        raise ValueError(f"every record needs at least two analysis segments of "
                         f"{settings.segment_s:g} s (their scatter is the noise of the "
                         "comparison); lengthen the records or shorten segment_s")
    groups = []
    for g, key in enumerate(keys):
        members = np.flatnonzero(group_of == g)
        scn = scenarios[members[0]]
        names = signature_names(*shaft_rates(scn), scn.gear.z1, key[3], key[2] == "dte_m")
        sd = entry_scatter([segments[i] for i in np.intersect1d(members, train)]
                           or [segments[i] for i in members], settings.floor_db)
        groups.append(Group(key, members, names, sd, np.zeros_like(sd)))
    noise = np.array([white_noise_std(bundle.signals[r], fs[i],
                                      0.5 * shaft_rates(scenarios[i])[0] * scenarios[i].gear.z1)
                      for i, r in enumerate(man.record)])
    return Records(bundle, scenarios, models, [s.mean(axis=0) for s in segments], groups,
                   group_of, noise, train, test, settings, wear_states)


def entry_scatter(segments: list[np.ndarray], floor_db: float) -> np.ndarray:
    """Scatter [dB] of each signature entry of a one-segment model against an n-segment mean:
    var = sd^2 (1 + 1/n), the median over the records given (a group's train records; its
    test records only where it has no train record: their segments are noise, not a fit),
    plus the model error floor ``floor_db`` in quadrature."""
    var = np.median([s.var(axis=0, ddof=1) * (1 + 1 / s.shape[0]) for s in segments], axis=0)
    return np.sqrt(var + floor_db**2)


def wear_curve(scn: Scenario, span: float, points: int, power: float,
               enough: Callable[[np.ndarray, np.ndarray], bool]
               ) -> tuple[np.ndarray, np.ndarray, bool]:
    """The model's pinion root wear [m] on the life grid ``span * u**power`` (``points`` values
    of u from 0 to 1), the span doubled up to four times until ``enough(life, root)``; returns
    the last grid, its wear and whether it was enough."""
    for _ in range(5):
        life = span * np.linspace(0.0, 1.0, points) ** power
        root = root_wear_evolution(scn, life)[0]
        if enough(life, root):
            return life, root, True
        span *= 2
    return life, root, False


def cycles_for_wear(scn: Scenario, wear_mm: np.ndarray, cycles_max: float = 1.5e7
                    ) -> np.ndarray:
    """Cycle counts at which the model's pinion root wear reaches ``wear_mm``."""
    life, root_m, ok = wear_curve(scn, cycles_max, 16, 1,
                                  lambda _, root: root[-1] * 1e3 >= np.max(wear_mm))
    root = root_m * 1e3
    if not ok:
        raise ValueError(f"the model's root wear reaches only {root[-1]:.4g} mm in "
                         f"{life[-1]:.3g} cycles, below {np.max(wear_mm):g} mm: check the "
                         "operating point and tribology.regime")
    return np.interp(wear_mm, root, life)


def wear_grid_cycles(scn: Scenario, cycles_max: float, n: int) -> list[float]:
    """Cycle counts of ``n`` wear states of one operating point whose pinion root wear is
    spread evenly from 0 to 1.2 times the model's at ``cycles_max`` (the most worn record);
    none if no record is worn. Even in wear, not in cycles: the lubricated law wears the root
    fastest while it runs in (case 3: 6.9 of 15.7 um in the first ninth of its cycles), so states
    even in cycles leave the records below that without a state to read them by."""
    if cycles_max <= 0:
        return []

    def top(life: np.ndarray, root: np.ndarray) -> float:
        return 1.2 * float(np.interp(cycles_max, life, root))

    # the life grid dense where the wear rises fastest
    life, root, ok = wear_curve(scn, 2.0 * cycles_max, 33, 2,
                                lambda life, root: root[-1] >= top(life, root))
    if not ok:
        raise ValueError(f"the model's root wear does not grow by a fifth beyond its value at "
                         f"{cycles_max:.3g} cycles within {life[-1]:.3g}: check the operating "
                         "point and tribology.regime")
    return [float(c) for c in np.interp(np.linspace(0.0, top(life, root), n), root, life)]


def records_cycles(scn: Scenario, rows: pd.DataFrame) -> np.ndarray:
    """Load cycles of records of one operating point: stated, else those at which the model
    reaches their wear (one wear simulation for them all), else 0."""
    cycles = rows.cycles.to_numpy(float).copy()
    wear = rows.wear_mm.to_numpy(float)
    find = np.isnan(cycles) & (np.nan_to_num(wear) > 0)
    if find.any():
        cycles[find] = cycles_for_wear(scn, wear[find])
    return np.nan_to_num(cycles)


def shaft_rates(scn: Scenario) -> tuple[float, float]:
    f1 = scn.operating.n1_rpm / 60
    return f1, f1 * scn.gear.z1 / scn.gear.z2


def with_nuisance(m: PairModel, nuisance: dict, base_ratio: float) -> PairModel:
    """The declared model with calibrated damping and error amplitudes, and the model-form
    parameters of :func:`with_model_form` (those ``nuisance`` lacks stay neutral). The mesh
    modulation (:func:`with_modulation`) is not applied here: it goes after any effect."""
    m = dataclasses.replace(
        m, damping=m.damping * nuisance["damping_ratio"] / base_ratio,
        long_error=nuisance["eccentricity1_um"] * 1e-6 * math.sin(m.geometry.alpha_w),
        short_error=nuisance["profile_error_um"] * 1e-6)
    return with_model_form(m, nuisance)


def with_modulation(m: PairModel, v: dict) -> PairModel:
    """A once-per-pinion-revolution modulation of the mesh stiffness, ``k_i(t) (1 + mu
    cos(w1 t + phi))`` (``mesh_modulation`` ``mu``, ``modulation_phase_rad`` ``phi``; ``mu`` = 0
    or missing: ``m`` itself).

    Radial run-out of the pinion (ISO 1328-2:2020, ``F_r``) and its wobble change the centre
    distance and the load distribution across the face once per revolution, and with them
    the length of the contact lines that carry the load, so the mesh stiffness; the declared
    model holds the run-out only as a line-of-action error (thesis 3.3), which is inert in
    the torsional model. Lumped models of such errors modulate the mesh once per revolution
    in amplitude (Inalpolat & Kahraman, J. Sound Vib. 329 (2010) 371; the sidebands ``k f_m
    +- f_1`` of Randall, J. Mech. Des. 104 (1982) 259). The depth is not predictable from a
    tolerance class (the face-load factor's variation is unknown), so it is calibrated. The
    tables are tiled over one pinion revolution (``periods`` = ``z1``; a model that already
    spans one, with a tooth defect, keeps its tables) and multiplied cell by cell, pairs A
    and B by the same instantaneous factor.

    A gear that runs out (the effect ``gear_runout``: ``m.centre_runout``, its eccentricity
    ``e2``) changes the centre distance in the same way once per gear revolution, so it
    modulates the mesh by the same mechanism: depth ``mu e2 / e1`` (the depth per unit
    eccentricity of the pinion's, ``e1`` = ``eccentricity1_um``) in the same phase relation to
    its own centre-distance change (``k (1 + mu2 cos(w2 t + phi))``, a time term of the
    kernel: the tables would have to span both revolutions). Without it a gear run-out would
    make its sidebands by the kinematic error and the moving path of contact alone, while the
    pinion's, declared, makes them by all three.
    """
    mu = float(v.get("mesh_modulation", 0.0))
    if mu == 0.0:
        return m
    phase = float(v.get("modulation_phase_rad", 0.0))
    rev = revolution_tables(m)
    n = len(rev.k_a)
    # table cell c is reached at the pinion angle 2 pi c / n (the tables start at t = 0)
    factor = 1.0 + mu * np.cos(2 * np.pi * np.arange(n) / n + phase)
    depth2 = mu * m.centre_runout / (v["eccentricity1_um"] * 1e-6) if m.centre_runout else 0.0
    return dataclasses.replace(rev, k_a=rev.k_a * factor, k_b=rev.k_b * factor,
                               gear_modulation=depth2, gear_modulation_phase=phase)


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
        key = (tuple(int(i) for i in idx), tuple(nuisance.get(n) for n in DYNAMIC_NUISANCE),
               (eff.name, tuple(sorted(values.items()))) if dynamic else None)
        if key in rec.cache:
            return rec.cache[key]
    man = rec.bundle.manifest
    base_ratio = rec.scenarios[0].dynamics.damping_ratio
    ms = [with_nuisance(m, nuisance, base_ratio)
          for m in (models if models is not None else [rec.models[i] for i in idx])]
    if dynamic:
        ms = [eff.model(m, values) for m in ms]
    ms = [with_modulation(m, nuisance) for m in ms]
    out: list[np.ndarray] = [np.empty(0)] * len(idx)
    fs_all = man.fs_hz.to_numpy(float)[idx]
    for fs in np.unique(fs_all):
        sel = np.flatnonzero(fs_all == fs)
        dyn = dataclasses.replace(rec.scenarios[0].dynamics, sample_rate_hz=float(fs),
                                  duration_s=rec.settings.segment_s,
                                  transient_s=rec.settings.transient_s, phase_bins=16,
                                  step_factor=rec.settings.step_factor)
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
    rigid-housing acceleration (or DTE), the effect's measurement stage on the quantities it
    acts on, the record's noise."""
    man = rec.bundle.manifest
    raw = responses(rec, idx, nuisance, eff, values, models)
    out = []
    for k, i in enumerate(idx):
        quantity = man.quantity.iloc[i]
        fs = float(man.fs_hz.iloc[i])
        x = declared_chain(raw[k], quantity, nuisance["housing_mass_kg"], fs=fs,
                           **modes_of(nuisance))
        if eff is not None and eff.record is not None and quantity in eff.quantities:
            x = eff.record(x, fs, values)
        rng = np.random.default_rng([rec.settings.seed, int(i)])  # common numbers per record
        out.append(x + rec.noise_std[i] * rng.standard_normal(x.size))
    return out


def residuals_db(rec: Records, idx: np.ndarray, signals: list[np.ndarray]
                 ) -> list[np.ndarray]:
    """Measured minus model signature of each of records ``idx`` (its group's entries) [dB];
    the records of one operating point, quantity and sampling rate analysed in one batch."""
    man = rec.bundle.manifest
    batches: dict[tuple, list[int]] = {}
    for k, i in enumerate(idx):
        scn = rec.scenarios[i]
        key = (float(man.fs_hz.iloc[i]), *shaft_rates(scn), scn.gear.z1,
               man.quantity.iloc[i] == "dte_m")
        batches.setdefault(key, []).append(k)
    res: list[np.ndarray] = [np.empty(0)] * len(idx)
    for key, ks in batches.items():
        sig = mean_signatures([signals[k] for k in ks], *key, rec.settings.segment_s)
        for k, s in zip(ks, sig, strict=True):
            res[k] = rec.measured[idx[k]] - s
    return res


def standardised(rec: Records, idx: np.ndarray, signals: list[np.ndarray],
                 discrepancy: bool = True) -> list[np.ndarray]:
    """Each record's dB residual over its group's noise and discrepancy (:attr:`Group.sd`), or
    over the noise alone (``Group.entry_sd``)."""
    return [r / (rec.group(i).sd if discrepancy else rec.group(i).entry_sd)
            for r, i in zip(residuals_db(rec, idx, signals), idx, strict=True)]


def residuals(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> np.ndarray:
    """Standardised residuals of records ``idx``, concatenated (groups of different lengths)."""
    return np.concatenate(standardised(rec, idx, signals))


def noise_only(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> float:
    """RMS residual of records ``idx`` in units of the noise alone (no discrepancy)."""
    return rms(np.concatenate(standardised(rec, idx, signals, discrepancy=False)))


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x**2)))


def to_unit(p: float, lo: float, hi: float, is_log: bool) -> float:
    return (math.log(p / lo) / math.log(hi / lo)) if is_log else (p - lo) / (hi - lo)


def from_unit(u: float, lo: float, hi: float, is_log: bool) -> float:
    return lo * (hi / lo) ** u if is_log else lo + u * (hi - lo)


def is_accel(rec: Records, idx: np.ndarray) -> np.ndarray:
    """Which of records ``idx`` are housing acceleration (the quantity ``m_h`` acts on)."""
    return rec.bundle.manifest.quantity.to_numpy()[idx] == "accel_m_s2"


def accel_in(rec: Records) -> bool:
    return bool(is_accel(rec, np.arange(len(rec.models))).any())


def with_level(rec: Records, nuisance: dict, eff: Effect | None, values: dict) -> dict:
    """``m_h`` moved so that the model's level matches the train acceleration records'.

    ``m_h`` divides every amplitude, so in dB it is an offset of the entries that scale with
    the record (all but kurtosis and crest factors): one step of their mean residual, weighted
    by the inverse variance of each entry (:attr:`Group.sd`). The noise does not scale with
    it, so this is a starting value, not the fit. DTE records do not see ``m_h``.
    """
    acc = is_accel(rec, rec.train)
    if not acc.any():
        return nuisance
    res = residuals_db(rec, rec.train, model_signals(rec, rec.train, nuisance, eff, values))
    num = den = 0.0
    for r, i, a in zip(res, rec.train, acc, strict=True):
        if a:
            g = rec.group(i)
            w = np.where([n not in SCALE_FREE for n in g.names], g.sd**-2.0, 0.0)
            num, den = num + float(np.sum(r * w)), den + float(np.sum(w))
    lo, hi, _ = NUISANCE["housing_mass_kg"]
    return nuisance | {"housing_mass_kg": float(np.clip(
        nuisance["housing_mass_kg"] * 10 ** (-num / den / 20), lo, hi))}


def train_cost(rec: Records, nuisance: dict, eff: Effect | None, values: dict) -> float:
    return float(np.sum(residuals(rec, rec.train, model_signals(rec, rec.train, nuisance, eff,
                                                                values)) ** 2))


def identifiable(rec: Records, nuisance: dict, names: tuple[str, ...]) -> list[str]:
    """Those of ``names`` that change the train residuals: each is moved by a tenth of its
    (log) range; one that moves the standardised residuals by less than ``MIN_SENSITIVITY``
    RMS is not identifiable from these records and stays at its declared value."""
    nuisance = completed(nuisance, rec.scenarios[0])
    r0 = residuals(rec, rec.train, model_signals(rec, rec.train, nuisance, None, {}))
    out = []
    for n in names:
        u = to_unit(nuisance[n], *BOUNDS[n])
        moved = nuisance | {n: from_unit(u + (0.1 if u < 0.5 else -0.1), *BOUNDS[n])}
        r1 = residuals(rec, rec.train, model_signals(rec, rec.train, moved, None, {}))
        if rms(r1 - r0) >= MIN_SENSITIVITY:
            out.append(n)
    return out


def split_fitted(fitted: dict) -> tuple[dict, dict]:
    """(effect values with option, nuisance) of a fitted parameter set."""
    return ({k: v for k, v in fitted.items() if k not in BOUNDS},
            {n: fitted[n] for n in BOUNDS if n in fitted})


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
    explained: dict = field(default_factory=dict)  # per group: see :func:`signature_gain`
    own_before: float = math.nan  # held-out error in its own entries, declared model ...
    own_after: float = math.nan  # ... and with the candidate
    separable: float = math.nan  # share of its change no free parameter mimics (separable_share)


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


def wide(rec: Records, eff: Effect | None) -> bool:
    """Whether a search is the calibration with the model form over its whole range."""
    return eff is None and rec.settings.model_form


def explore(rec: Records, eff: Effect | None, c: Candidate, free_nuisance: list[str]
            ) -> list[Candidate]:
    """``c`` and a scrambled Sobol sample (``settings.explore`` points) over the effect's whole
    range and the dynamic nuisance within ``EXPLORE_SPAN`` (unit coordinates) of its declared
    values (the model form: of ``c``'s; in the calibration with ``loop.model_form``,
    :func:`wide`, ``CALIBRATION_EXPLORE`` times as many points and the model form over its
    whole range; the default loop's run-out modulation around its declared value, none),
    ``m_h`` levelled at each; best first. A missing effect drags the calibration
    (to the bounds, at worst), and least squares from a single start stays in its basin; the
    declared values are the prior that does not depend on the fit."""
    params = eff.params if eff is not None else ()
    dyn = [n for n in free_nuisance if n in EXPLORED]
    # the scenario's nuisance (and support mode) around its declared values; the model form
    # over its whole range in the model-form calibration (its neutral value is no prior worth
    # holding to), around the calibration with an effect
    scn = rec.scenarios[0]
    prior = completed(c.nuisance, scn) | declared_nuisance(scn) | declared_modes(scn)
    span = {n: (0.5 if wide(rec, eff) and n in MODEL_FORM else EXPLORE_SPAN) for n in dyn}
    centres = {n: (0.5 if span[n] == 0.5 else to_unit(prior[n], *BOUNDS[n])) for n in dyn}
    dim = len(params) + len(dyn)
    n_points = rec.settings.explore * (CALIBRATION_EXPLORE if wide(rec, eff) else 1)
    pts = (qmc.Sobol(dim, seed=rec.settings.seed).random(n_points) if dim and n_points
           else np.empty((0, 0)))
    found = [c]
    for u in pts:
        vals = c.option | {p.name: from_unit(float(x), p.low, p.high, p.log)
                           for p, x in zip(params, u, strict=False)}
        nui = dict(c.nuisance)
        for n, x in zip(dyn, u[len(params):], strict=True):
            nui[n] = from_unit(float(np.clip(centres[n] + span[n] * (2 * x - 1), 0, 1)),
                               *BOUNDS[n])
        nui = with_level(rec, nui, eff, vals)
        found.append(dataclasses.replace(c, values=vals, nuisance=nui,
                                         train_rss=train_cost(rec, nui, eff, vals)))
    return sorted(found, key=lambda x: x.train_rss)  # stable: the first of equals leads


def search(rec: Records, eff: Effect | None, c: Candidate, free_nuisance: list[str]
           ) -> Candidate:
    """The model's (the declared one's, ``eff`` None, or with an effect) parameters fitted on
    the train records: the best explored start refined by least squares (the calibration with
    the model form: the best ``CALIBRATION_STARTS``, the lowest fit kept), the effect's
    parameters jointly with the identifiable nuisance. The declared model and every refined
    candidate get the same search."""
    starts = explore(rec, eff, c, free_nuisance)[:CALIBRATION_STARTS if wide(rec, eff) else 1]
    free = eff.bounds() if eff is not None else []
    free += [(n, *BOUNDS[n]) for n in free_nuisance]
    fits = [least_squares(rec, eff, s.option, s.values | s.nuisance, free,
                          rec.settings.max_nfev) for s in starts]
    k = min(range(len(fits)), key=lambda i: fits[i][1])
    vals, nui = split_fitted(fits[k][0])
    return dataclasses.replace(starts[k], values=vals, nuisance=nui, train_rss=fits[k][1],
                               refined=True)


def screened(settings: LoopSettings) -> tuple[str, ...]:
    """The dynamic parameters the calibration may free: the scenario's nuisance and the mesh
    modulation of the pinion's run-out (:data:`RUNOUT_MODULATION`); the rest of the model form
    with ``loop.model_form`` only."""
    return DYNAMIC_NUISANCE if settings.model_form else (*SCENARIO_DYNAMIC, *RUNOUT_MODULATION)


def calibrate(rec: Records, start: dict) -> tuple[dict, list[str]]:
    """Fit the declared nuisance parameters on the train records (from their declared
    values); returns the calibrated nuisance and the names of the free ones. ``m_h`` (and a
    declared support mode) scales and shapes every acceleration amplitude and is always free
    for acceleration records; a dynamic parameter that is not identifiable stays at its
    declared value."""
    start = with_level(rec, completed(start, rec.scenarios[0]), None, {})
    free = identifiable(rec, start, screened(rec.settings))
    if accel_in(rec):
        free += ["housing_mass_kg", *[n for n in SUPPORT if n in start]]
    c = Candidate("declared", {}, {}, start, train_cost(rec, start, None, {}), 0)
    return search(rec, None, c, free).nuisance, free


def bic(chi2: float, n: int, k: int) -> float:
    """Bayesian information criterion of standardised residuals (known scatter)."""
    return chi2 + k * math.log(n)


def entry_family(name: str) -> str:
    """The family of a signature entry: its name without its numbers (one kind of line at
    every mesh harmonic, e.g. ``line_mesh+p`` for all first and second upper pinion sidebands;
    all bands; each statistic alone)."""
    return re.sub(r"\d+", "", name)


def discrepancy_sd(groups: list[Group], res_db: list[np.ndarray], prior_count: float
                   ) -> list[np.ndarray]:
    """Model-discrepancy standard deviation [dB] of each entry of each group, from the train
    residuals of the calibrated declared model (``res_db[k]``: group k's records x entries,
    possibly none).

    The residual is read as ``r = delta + eps``: a model discrepancy ``delta`` (Kennedy &
    O'Hagan, J. R. Stat. Soc. B 63 (2001) 425), independent of the measurement noise ``eps``
    whose variance is the segment scatter ``entry_sd^2``, so ``E r^2 = entry_sd^2 + d^2``.
    Method of moments per entry family (:func:`entry_family`) of each group: ``v`` the mean of
    ``r^2 - entry_sd^2`` over its ``m`` residuals; shrunk towards the pooled value ``v0`` (the
    same mean over every train residual of the bundle) as the posterior scale of a normal
    variance under a scaled-inverse-chi^2 prior of ``prior_count`` degrees of freedom
    (Gelman et al., Bayesian Data Analysis, 3rd ed., 2013, 2.6): ``d^2 = max(0, (nu0 v0 +
    m v) / (nu0 + m))``, ``v0`` clipped at zero. A family of many entries is estimable from
    few records; a group without train records gets the pooled value.
    Without this term a calibration against data from a different model form is pulled by
    the discrepancy and any effect that soaks part of it looks significant (Brynjarsdottir &
    O'Hagan, Inverse Problems 30 (2014) 114007).
    """
    excess = [r**2 - g.entry_sd**2 for g, r in zip(groups, res_db, strict=True)]
    pooled = np.concatenate([e.ravel() for e in excess])
    v0 = max(float(pooled.mean()), 0.0) if pooled.size else 0.0
    out = []
    for g, e in zip(groups, excess, strict=True):
        fam = np.array([entry_family(n) for n in g.names])
        d2 = np.full(len(g.names), v0)
        for f in np.unique(fam) if e.size else ():
            cells = e[:, fam == f]
            d2[fam == f] = (prior_count * v0 + cells.sum()) / (prior_count + cells.size)
        out.append(np.sqrt(np.maximum(d2, 0.0)))
    return out


def with_discrepancy(rec: Records, nuisance: dict) -> Records:
    """``rec`` with the discrepancy of :func:`discrepancy_sd` estimated on its train records
    for the declared model at ``nuisance``."""
    res = residuals_db(rec, rec.train, model_signals(rec, rec.train, nuisance, None, {}))
    pos = by_group(rec, rec.train)
    per_group = [np.array([res[j] for j in pos.get(k, [])]).reshape(-1, len(g.names))
                 for k, g in enumerate(rec.groups)]
    sds = discrepancy_sd(rec.groups, per_group, rec.settings.discrepancy_prior)
    return dataclasses.replace(rec, groups=[dataclasses.replace(g, discrepancy_sd=d)
                                            for g, d in zip(rec.groups, sds, strict=True)])


def discrepancy_allowance(k: int, n_candidates: int, rate: float) -> float:
    """Standardised sum of squares per held-out record that the model discrepancy lets a
    candidate of ``k`` parameters explain by chance.

    Under the discrepancy model of :func:`discrepancy_sd` (Gaussian, independent between
    entries, shared by the records of a group, so that what a fit absorbs on the train records
    it also absorbs on the held-out ones), least squares of k parameters removes from a
    record's standardised sum of squares at most the projection of ``delta + eps`` on k
    directions: a chi-square of k degrees of freedom. Its upper ``rate / n_candidates``
    quantile, Bonferroni over the candidates, bounds the chance that any of them passes by
    ``rate``, the false-add rate per bundle (so each may be judged, the best passing one
    adopted).
    """
    return float(chi2.isf(rate / max(n_candidates, 1), max(k, 1)))


def signature_gain(rec: Records, idx: np.ndarray, before: list[np.ndarray],
                   after: list[np.ndarray], quantities: tuple[str, ...]
                   ) -> tuple[dict[str, float], float, float]:
    """Where a candidate's own signature lives and what it explains there, on records ``idx``.

    Its entries in a group: those where the model's signature moves with the candidate by
    more than the entry's noise scatter (mean over the group's records; measured data do not
    enter this choice). Only groups of the ``quantities`` the candidate can show in count: in
    the others (the DTE records of a bundle, for a transfer path to the accelerometer) only
    the nuisance refitted with it moves the signature, and a measurement-chain effect would
    otherwise be judged where it cannot act. Returns, per group where it has entries, the mean
    over the records of the drop of the standardised sum of squares (noise and discrepancy)
    over those entries, and the RMS residual there in units of the noise alone, before and
    after (its groups pooled; the effect-size guard of the null test, in the unit of the
    report's headline).
    """
    res_b, res_a = residuals_db(rec, idx, before), residuals_db(rec, idx, after)
    explained, e_b, e_a = {}, [], []
    for k, mine in by_group(rec, idx).items():
        g = rec.groups[k]
        if g.key[2] not in quantities:
            continue
        own = np.mean([np.abs(res_b[j] - res_a[j]) for j in mine], axis=0) > g.entry_sd
        if not own.any():
            continue
        rb = np.array([res_b[j][own] for j in mine])
        ra = np.array([res_a[j][own] for j in mine])
        explained[g.label] = float(np.mean(np.sum((rb**2 - ra**2) / g.sd[own] ** 2, axis=1)))
        e_b.append((rb / g.entry_sd[own]).ravel())
        e_a.append((ra / g.entry_sd[own]).ravel())
    if not explained:
        return {}, math.nan, math.nan
    return explained, rms(np.concatenate(e_b)), rms(np.concatenate(e_a))


def free_directions(rec: Records, nuisance: dict, eff: Effect | None, values: dict,
                    free_nuisance: list[str]) -> np.ndarray:
    """Columns: the change of the standardised train residuals per unit-coordinate step of
    each free nuisance parameter (forward differences of ``SEPARABILITY_STEP``, towards the
    inside of its range) at the model ``eff`` at ``values`` with ``nuisance``."""
    r0 = residuals(rec, rec.train, model_signals(rec, rec.train, nuisance, eff, values))
    cols = []
    for n in free_nuisance:
        u = to_unit(nuisance[n], *BOUNDS[n])
        step = SEPARABILITY_STEP if u < 0.5 else -SEPARABILITY_STEP
        moved = nuisance | {n: from_unit(u + step, *BOUNDS[n])}
        r1 = residuals(rec, rec.train, model_signals(rec, rec.train, moved, eff, values))
        cols.append((r1 - r0) / step)
    return np.column_stack(cols) if cols else np.empty((r0.size, 0))


def separable_share(directions: np.ndarray, change: np.ndarray) -> float:
    """Share of the sum of squares of ``change`` that no linear combination of the columns of
    ``directions`` reproduces: 1 for a change orthogonal to all of them, 0 for one in their
    span (the least-squares residual of ``change`` on ``directions``, relative)."""
    ss = float(change @ change)
    if ss == 0.0:
        return math.nan
    if directions.shape[1] == 0:
        return 1.0
    coef, *_ = np.linalg.lstsq(directions, change, rcond=None)
    rest = change - directions @ coef
    return float(rest @ rest) / ss


def feature_error(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> float:
    """Mean relative error of the Table 13 features, model against measurement [%]."""
    errs = []
    for k, i in enumerate(idx):
        meas = features(rec.bundle.signals[rec.bundle.records[i]])
        mod = features(signals[k])
        errs += [abs(float(mod[f]) / float(meas[f]) - 1) * 100 for f in FEATURES]
    return float(np.mean(errs))


def train_wear_residuals(rec: Records, nuisance: dict, eff: Effect | None, values: dict
                         ) -> dict[int, dict[int, np.ndarray]]:
    """The dB residual of each train record of known wear at its own worn model, keyed by
    group index, then by record (bundle index); groups without such records left out."""
    wear = rec.bundle.manifest.wear_mm.to_numpy(float)
    known = np.array([i for i in rec.train if not np.isnan(wear[i])], int)
    if not known.size:
        return {}
    res = residuals_db(rec, known, model_signals(rec, known, nuisance, eff, values))
    return {g: {int(known[j]): res[j] for j in pos} for g, pos in by_group(rec, known).items()}


def reference_moments(group: Group, rows: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Per entry, the mean of the residual ``rows`` [dB] and their spread beyond the group's
    noise [dB^2] (method of moments, ``var - entry_sd^2`` clipped at 0; zero with one row)."""
    r = np.array(rows)
    spread = (np.maximum(r.var(axis=0, ddof=1) - group.entry_sd**2, 0.0) if len(rows) > 1
              else np.zeros(r.shape[1]))
    return r.mean(axis=0), spread


def wear_reference(rec: Records, nuisance: dict, eff: Effect | None, values: dict
                   ) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """What the model misses of each group's records whatever their wear, read from the
    group's train records of known wear at their own worn models
    (:func:`train_wear_residuals`): per entry, their mean residual [dB] and its spread beyond
    the noise [dB^2] (:func:`reference_moments`). Keyed by group index; groups without such
    records left out.

    The residual of a record is read as ``r = mu + delta + eps``: ``mu`` what the model misses
    in every record of the group (its form error there, an undeclared effect), ``delta`` the
    part that changes from record to record, chiefly with wear (where the model's wear
    signature is not the gearbox's), ``eps`` the noise (Kennedy & O'Hagan's discrepancy with a
    mean, J. R. Stat. Soc. B 63 (2001) 425, estimated where the wear is known)."""
    return {g: reference_moments(rec.groups[g], list(rows.values()))
            for g, rows in train_wear_residuals(rec, nuisance, eff, values).items()}


def wear_estimates(rec: Records, idx: np.ndarray, nuisance: dict, eff: Effect | None,
                   values: dict, leave_one_out: bool = False) -> np.ndarray:
    """Model-based wear estimate of each record [mm]: the wear state whose simulated signature
    is nearest, the residuals taken relative to the group's train records of known wear
    (:func:`wear_reference`: their mean residual removed, each entry weighed by the noise and
    the residual's spread between them). A record is so read by how it differs from records
    of its own gearbox, operating point and sensor, with the entries where the model's wear
    signature tracks the gearbox's weighed most: what the model misses in all of them (its
    form error, an undeclared effect) does not move the estimate. ``leave_one_out``: each
    record read against the others (for train records of known wear). Measured on the
    independent simulator's bundles: docs/measured-data.md."""
    train = train_wear_residuals(rec, nuisance, eff, values)
    out = []
    for i in idx:
        states = rec.wear_states[i]
        if not states:
            out.append(np.nan)
            continue
        wear = np.array([w for w, _ in states])
        sig = model_signals(rec, np.array([i] * len(states)), nuisance, eff, values,
                            models=[m for _, m in states])
        group = rec.group(i)
        rows = [r for j, r in train.get(int(rec.group_of[i]), {}).items()
                if not (leave_one_out and j == i)]
        mean, spread = reference_moments(group, rows) if rows else (0.0, 0.0)
        sd = np.sqrt(group.sd**2 + spread)
        res = residuals_db(rec, np.array([i] * len(states)), sig)
        cost = np.array([rms((r - mean) / sd) for r in res])
        j = int(np.argmin(cost))
        if 0 < j < len(cost) - 1:  # parabolic refinement between grid states
            c0, c1, c2 = cost[j - 1:j + 2]
            d = c0 - 2 * c1 + c2
            shift = 0.5 * (c0 - c2) / d if d > 0 else 0.0
            out.append(float(np.interp(j + np.clip(shift, -1, 1), np.arange(len(wear)), wear)))
        else:
            out.append(float(wear[j]))
    return np.array(out)


class WearScore(NamedTuple):
    """How well the model-based wear estimate (:func:`wear_estimates`) reads the held-out
    records whose wear is known."""

    #: mean relative error over the worn ones [%] (mean absolute error [mm] if none is worn)
    error: float
    #: ``1 - MAE / MAE of the constant guess`` (the train records' mean known wear): <= 0 says
    #: the estimate carries no wear information on these records; None without such a guess
    skill: float | None
    #: the records scored (bundle indices), their known wear and its estimate [mm]
    records: tuple[int, ...] = ()
    true_mm: tuple[float, ...] = ()
    estimate_mm: tuple[float, ...] = ()


def wear_score(rec: Records, nuisance: dict, eff: Effect | None, values: dict,
               on_train: bool = False) -> WearScore | None:
    """Error and skill of the model-based wear estimate over the held-out records whose wear is
    known, or (``on_train``) over the train records whose wear is known, each read against the
    others of its group (leave one out); None if there is no such record."""
    wear = rec.bundle.manifest.wear_mm.to_numpy(float)

    def known(idx: np.ndarray) -> np.ndarray:
        return np.array([i for i in idx if not np.isnan(wear[i]) and rec.wear_states[i]], int)

    test, train = known(rec.test), known(rec.train)
    if on_train:
        test = train if train.size > 1 else np.empty(0, int)
    if not test.size:
        return None
    true = wear[test]
    est = wear_estimates(rec, test, nuisance, eff, values, leave_one_out=on_train)
    ok = true > 0
    error = (float(np.mean(np.abs(est[ok] - true[ok]) / true[ok]) * 100) if ok.any()
             else float(np.mean(np.abs(est - true))))
    return WearScore(error, wear_skill(est, true, wear[train]), tuple(int(i) for i in test),
                     tuple(map(float, true)), tuple(map(float, est)))


def wear_skill(est: np.ndarray, true: np.ndarray, train_wear: np.ndarray) -> float | None:
    """Skill of wear estimates ``est`` of records of wear ``true`` against the constant guess,
    the mean of ``train_wear`` (Murphy 1988's skill score on the mean absolute error): 1 exact,
    <= 0 no better than the guess; None without train wear or if the guess is exact."""
    guess = float(np.mean(np.abs(np.mean(train_wear) - true))) if train_wear.size else 0.0
    return 1 - float(np.mean(np.abs(est - true))) / guess if guess > 0 else None


def wear_check(before: WearScore | None, after: WearScore | None, max_loss: float
               ) -> dict | None:
    """Whether an adopted effect reads the wear (issue 16, item 6; ``before``, ``after``: the
    leave-one-out scores on the train records): it may lower the wear
    estimate's skill by at most ``max_loss``, i.e. raise its mean absolute error by at most
    that share of the constant guess's (the spread of the wear it reads), not of its own
    error, which on a good estimate is finer than the estimate's resolution (a torque ripple
    of our own records was refused at 3.9 -> 5.3 % of error, skill 0.85 -> 0.79). Where the
    skill is undefined (the guess exact: every such record of one wear) the mean relative
    error may grow by at most ``max_loss`` of its value. None without such scores: the
    adopted effect reads the wear. Both scores carry the same guess, so their skills are both
    defined or both not."""
    if before is None or after is None:
        return None
    if before.skill is not None and after.skill is not None:
        bound = before.skill - max_loss
        return {"measure": "skill", "before": before.skill, "value": after.skill,
                "bound": bound, "holds": after.skill >= bound}
    bound = (1 + max_loss) * before.error
    return {"measure": "error", "before": before.error, "value": after.error, "bound": bound,
            "holds": after.error <= bound}


def by_group(rec: Records, idx: np.ndarray) -> dict[int, list[int]]:
    """Positions in ``idx`` of each group's records, by group index in order (groups without a
    record in ``idx`` left out)."""
    out: dict[int, list[int]] = {}
    for j, i in enumerate(idx):
        out.setdefault(int(rec.group_of[i]), []).append(j)
    return dict(sorted(out.items()))


def residual_table(rec: Records, idx: np.ndarray, signals: list[np.ndarray]
                   ) -> dict[str, dict[str, float]]:
    """Mean dB residual of each signature entry over records ``idx``, per group label."""
    res = residuals_db(rec, idx, signals)
    return {rec.groups[k].label: dict(zip(rec.groups[k].names,
                                          np.mean([res[j] for j in pos], axis=0).tolist(),
                                          strict=True))
            for k, pos in by_group(rec, idx).items()}


def group_errors(rec: Records, idx: np.ndarray, signals: list[np.ndarray],
                 discrepancy: bool = True) -> dict[str, float]:
    """RMS standardised residual (:func:`standardised`) over records ``idx``, per group."""
    z = standardised(rec, idx, signals, discrepancy)
    return {rec.groups[k].label: rms(np.concatenate([z[j] for j in pos]))
            for k, pos in by_group(rec, idx).items()}


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


def group_summary(rec: Records, before: list[np.ndarray], after: list[np.ndarray]
                  ) -> dict[str, dict]:
    """Per group: its key, records, discrepancy per entry family [dB] and held-out errors before
    and after (``before``/``after``: model signals of the test records)."""
    err = {key: group_errors(rec, rec.test, sig, disc)
           for key, sig, disc in (("before", before, True), ("after", after, True),
                                  ("before_noise_only", before, False),
                                  ("after_noise_only", after, False))}
    out = {}
    for g in rec.groups:
        n1, torque, quantity, fs = g.key
        fam = {entry_family(n): float(d) for n, d in zip(g.names, g.discrepancy_sd,
                                                          strict=True)}
        out[g.label] = {"n1_rpm": n1, "torque_Nm": torque, "quantity": quantity, "fs_hz": fs,
                        "records": [rec.bundle.records[i] for i in g.records],
                        "entries": len(g.names), "discrepancy_db": fam,
                        **{f"error_{k}": v.get(g.label) for k, v in err.items()}}
    return out


@dataclass(frozen=True)
class Reader:
    """The model that reads the wear (:func:`wear_estimates`): its nuisance, effect, values."""

    name: str
    nuisance: dict
    effect: Effect | None = None
    values: dict = field(default_factory=dict)


def reads_wear(rec: Records, reader: Reader, adopted: Reader, max_loss: float
               ) -> tuple[Reader, dict | None]:
    """Which model reads the wear once ``adopted`` is adopted over the model ``reader`` that
    read it so far (issue 16, item 6): ``adopted`` unless :func:`wear_check` on the two models'
    leave-one-out scores on the train records of known wear refuses it; the check with
    ``reads_with`` (None without such records: ``adopted`` reads it)."""
    loo = [wear_score(rec, r.nuisance, r.effect, r.values, on_train=True)
           for r in (reader, adopted)]
    check = wear_check(*loo, max_loss)
    if check is None:
        return adopted, None
    chosen = adopted if check["holds"] else reader
    return chosen, check | {"reads_with": chosen.name, "before_model": reader.name,
                            "after_model": adopted.name}


@dataclass
class Round:
    """One round of attribution: the candidates ranked by held-out error and the verdict of
    the null test on the judged one (:attr:`best`)."""

    ranking: list[Candidate]
    effects: dict[str, Effect]  # each candidate's effect, by name
    null_bic: float
    allowed: float  # what the discrepancy allows the judged (:func:`discrepancy_allowance`)
    adopted: bool
    base_test: list[np.ndarray]  # the test signals of the model the candidates were added to
    # the null test's conditions on the judged (:func:`physics.loop.report.null_test`)
    checks: dict
    # the model that reads the wear after this round (:class:`Reader`)
    reader: Reader
    # where the judged was adopted: which model reads the wear, from the leave-one-out scores on
    # the train records (:func:`wear_check`, with ``reads_with``), None without them
    wear_reading: dict | None = None
    # held-out wear-estimate scores of the reader before and after this round (adopted only)
    wear: tuple[WearScore | None, WearScore | None] = (None, None)
    # the judged candidate's place in the ranking: the first that passes the null test, else
    # the first
    pick: int = 0
    # the other candidates that pass the null test too, in ranking order: where there are
    # any, the records do not single out the adopted effect
    also_passing: list[Candidate] = field(default_factory=list)

    @property
    def best(self) -> Candidate:
        """The judged candidate: the adopted one, or the first by held-out error if none
        passes."""
        return self.ranking[self.pick]

    def table(self) -> list[dict]:
        """The ranking as the report writes it."""
        return [{"effect": c.name, "option": c.option,
                 "parameters": {k: v for k, v in c.values.items() if k not in c.option},
                 "nuisance": c.nuisance, "refined": c.refined,
                 "heldout_error": c.heldout, "delta_bic": c.bic - self.null_bic,
                 "own_entries_error": [c.own_before, c.own_after],
                 "explained": c.explained, "n_params": c.n_params,
                 "separable": c.separable} for c in self.ranking]


def attribute(rec: Records, judged: Records, declared: Effect | None, declared_values: dict,
              nuisance: dict, free_nuisance: list[str], candidates: list[tuple[Effect, dict]],
              reader: Reader, progress: bool = False) -> Round:
    """Screen, refine and judge ``candidates`` against the model ``declared`` (None: the
    calibrated declared model; else it with an adopted effect at ``declared_values``) at
    ``nuisance``; the null test on each, the best that passes adopted (see the module text);
    if one is, which model
    reads the wear after it (:func:`reads_wear`; ``reader`` reads it before). Fits weigh the
    residuals of ``rec`` (noise alone); the held-out judgement uses ``judged`` (the same
    records with the model discrepancy, :func:`with_discrepancy`)."""
    settings = rec.settings
    base_train = model_signals(rec, rec.train, nuisance, declared, declared_values)
    base_test = model_signals(rec, rec.test, nuisance, declared, declared_values)
    null_res = residuals(rec, rec.train, base_train)
    n_train = null_res.size
    null_bic = bic(float(np.sum(null_res**2)), n_train, 0)
    before = rms(residuals(judged, rec.test, base_test))
    effects = {eff.name: eff for eff, _ in candidates}
    ranking = [screen_effect(rec, eff, option, nuisance)
               for eff, option in tqdm(candidates, desc="screening", disable=not progress)]
    ranking.sort(key=lambda c: c.train_rss)
    top = settings.refine
    ranking[:top] = [search(rec, effects[c.name], c, free_nuisance)
                     for c in tqdm(ranking[:top], desc="refining", disable=not progress)]
    directions = free_directions(rec, nuisance, declared, declared_values, free_nuisance)
    for c in ranking:
        without = residuals(rec, rec.train, model_signals(rec, rec.train, c.nuisance, declared,
                                                          declared_values))
        with_c = residuals(rec, rec.train, model_signals(rec, rec.train, c.nuisance,
                                                         effects[c.name], c.values))
        c.separable = separable_share(directions, with_c - without)
        test = model_signals(rec, rec.test, c.nuisance, effects[c.name], c.values)
        c.heldout = rms(residuals(judged, rec.test, test))
        c.explained, c.own_before, c.own_after = signature_gain(
            judged, rec.test, base_test, test, effects[c.name].judged_in())
        c.bic = bic(c.train_rss, n_train, c.n_params)
        log.info("%s %s: held-out %.2f (baseline %.2f), own entries %.2f -> %.2f, explained "
                 "%s, dBIC %.1f, separable %.2f%s", c.name, c.option, c.heldout, before,
                 c.own_before, c.own_after, {k: round(v, 1) for k, v in c.explained.items()},
                 c.bic - null_bic, c.separable, "" if c.refined else " (screened)")
    ranking.sort(key=lambda c: c.heldout)

    def verdict(c: Candidate) -> tuple[float, dict]:
        allowed = discrepancy_allowance(c.n_params, len(ranking), settings.false_add_rate)
        return allowed, null_test(c.own_after, c.own_before, c.bic - null_bic,
                                  settings.min_gain, settings.min_delta_bic,
                                  min(c.explained.values(), default=0.0), allowed)

    verdicts = [verdict(c) for c in ranking]
    pick = first_passing([checks for _, checks in verdicts])
    best = ranking[pick]
    allowed, checks = verdicts[pick]
    adopted = holds(checks)
    if not adopted:
        return Round(ranking, effects, null_bic, allowed, adopted, base_test, checks, reader)
    # last: it costs a simulation per wear state and record
    adopted_reader = Reader(f"the model with {best.name}", best.nuisance, effects[best.name],
                            best.values)
    after, reading = reads_wear(rec, reader, adopted_reader, settings.max_wear_loss)
    before = wear_score(rec, reader.nuisance, reader.effect, reader.values)
    wear = (before, before if after is reader else
            wear_score(rec, after.nuisance, after.effect, after.values))
    log.info("%s adopted; the wear read by %s (train leave-one-out %s), held-out %s -> %s",
             best.name, after.name, reading, *wear)
    also = [c for k, (c, (_, ch)) in enumerate(zip(ranking, verdicts, strict=True))
            if k != pick and holds(ch)]
    return Round(ranking, effects, null_bic, allowed, adopted, base_test, checks, after,
                 reading, wear, pick, also)


def stacked(first: Effect, values: dict, second: Effect) -> Effect:
    """``second`` added to a model that carries ``first`` at its fitted ``values``: a candidate
    of the greedy second round. Its parameters and options are the second's; the dynamics
    take both effects' model stages; each measurement stage acts on the quantities of both
    that have one (a pair whose measurement stages share no quantity is not stacked)."""
    staged = [e for e in (first, second) if e.record is not None]
    quantities = tuple(q for q in first.quantities + second.quantities
                       if all(q in e.quantities for e in staged))
    if staged and not quantities:
        raise ValueError(f"{first.name} and {second.name} act on the measurement chains of "
                         "different quantities; they are not stacked")

    def model(m: PairModel, v: dict) -> PairModel:
        stages = [(e, ev) for e, ev in ((first, values), (second, v)) if e.model is not None]
        built = [e.model(m, ev) for e, ev in stages]
        # an effect that tiles the tables over a pinion revolution (a tooth defect) needs
        # one-period tables and does not tile the others' per-pair factors: it goes first
        order = sorted(range(len(stages)), key=lambda i: built[i].periods == m.periods)
        m = built[order[0]]
        for i in order[1:]:
            e, ev = stages[i]
            m = e.model(m, ev)
        return m

    def record(x: np.ndarray, fs: float, v: dict) -> np.ndarray:
        for e, ev in ((first, values), (second, v)):
            x = e.record(x, fs, ev) if e.record is not None else x
        return x

    dynamic = first.model is not None or second.model is not None
    return dataclasses.replace(second, name=f"{first.name}+{second.name}",
                               quantities=tuple(dict.fromkeys(quantities)),
                               shows_in=second.quantities,
                               model=model if dynamic else None,
                               record=record if staged else None)


def second_candidates(first: Effect, values: dict, candidates: list[tuple[Effect, dict]]
                      ) -> list[tuple[Effect, dict]]:
    """The candidates of the greedy second round: every other effect stacked on ``first``."""
    return [(stacked(first, values, e), o) for e, o in candidates if e.name != first.name
            and not (first.record is not None and e.record is not None
                     and not set(first.quantities) & set(e.quantities))]


def run_loop(bundle: Bundle, base: Scenario, settings: LoopSettings | None = None,
             progress: bool = False, reference: FormReference | None = None) -> LoopReport:
    """The whole loop on one bundle; returns its report (see the module text). With a
    ``reference`` (:func:`physics.loop.form_reference.form_reference`, a sister gearbox's
    records) the declared model's mean form error measured there is removed from the
    measured signatures first."""
    settings = settings or LoopSettings()
    candidates = candidates_for(set(bundle.manifest.quantity), settings)
    start = declared_nuisance(base) | declared_modes(base)  # a bad chain mode: before work
    if reference is not None:
        reference.check(bundle)
    rec = prepare(bundle, base, settings)
    if reference is not None:
        rec = reference.subtracted(rec)
    nuisance, free_nuisance = calibrate(rec, start)
    judged = with_discrepancy(rec, nuisance)
    declared = Reader("the declared model", nuisance)
    first = attribute(rec, judged, None, {}, nuisance, free_nuisance, candidates, declared,
                      progress)
    base_test = first.base_test  # the calibrated declared model's
    rounds = [first]
    eff = first.effects[first.best.name]
    more = second_candidates(eff, first.best.values, candidates) if first.adopted else []
    if more:  # greedy: a second effect on the residual of the first, the same rule
        rounds.append(attribute(rec, judged, eff, first.best.values, first.best.nuisance,
                                free_nuisance, more, first.reader, progress))
    last = next((r for r in reversed(rounds) if r.adopted), None)
    best = last.best if last else None
    chosen = last.effects[best.name] if last else None
    after_nui = best.nuisance if last else nuisance
    after_vals = best.values if last else {}
    after_test = (model_signals(rec, rec.test, after_nui, chosen, after_vals) if last
                  else base_test)
    adopted = [r.best for r in rounds if r.adopted]
    # each adopted round has scored its reader before and after on the held-out records
    wear_before = first.wear[0] if first.adopted else wear_score(rec, nuisance, None, {})
    wear_after = last.wear[1] if last else wear_before
    rec.cache.clear()  # the report keeps the records, not the simulations
    return LoopReport(
        mode="bundle",
        chosen_effect=chosen.name if chosen else None,
        chosen_option=({k: v for c in adopted for k, v in c.option.items()} if last
                       else None),
        chosen_parameters=({k: v for c in adopted for k, v in c.values.items()
                            if k not in c.option} if last else None),
        error_before=noise_only(rec, rec.test, base_test),
        error_after=noise_only(rec, rec.test, after_test),
        error_unit="RMS of the held-out records' signature residuals, each in units of its "
                   "own scatter between segments (1: at the noise); with the model "
                   "discrepancy in quadrature: error_before_with_discrepancy",
        feature_error_before_pct=feature_error(rec, rec.test, base_test),
        feature_error_after_pct=feature_error(rec, rec.test, after_test),
        wear_error_before_pct=wear_before.error if wear_before else None,
        wear_error_after_pct=wear_after.error if wear_after else None,
        calibration=nuisance,
        calibrated_on="the train records",
        nuisance_after=after_nui,
        null_bic=first.null_bic,
        ranking=first.table(),
        decision_rule={"min_gain": settings.min_gain, "min_delta_bic": settings.min_delta_bic,
                       "false_add_rate": settings.false_add_rate, "allowed": first.allowed,
                       "max_wear_loss": settings.max_wear_loss},
        details={
            "error_before_db": rms(np.concatenate(residuals_db(rec, rec.test, base_test))),
            "error_after_db": rms(np.concatenate(residuals_db(rec, rec.test, after_test))),
            "error_before_with_discrepancy": rms(residuals(judged, rec.test, base_test)),
            "error_after_with_discrepancy": rms(residuals(judged, rec.test, after_test)),
            "not_identifiable": [n for n in screened(settings) if n not in free_nuisance],
            "form_reference": reference.summary() if reference is not None else None,
            "train_records": [bundle.records[i] for i in rec.train],
            "test_records": [bundle.records[i] for i in rec.test],
            "groups": group_summary(judged, base_test, after_test),
            "residual_before": residual_table(rec, rec.test, base_test),
            "residual_after": residual_table(rec, rec.test, after_test),
            "wear_skill_before": wear_before.skill if wear_before else None,
            "wear_skill_after": wear_after.skill if wear_after else None,
            "wear_estimates": ({"records": [bundle.records[i] for i in wear_before.records],
                                "true_mm": list(wear_before.true_mm),
                                "before_mm": list(wear_before.estimate_mm),
                                "after_mm": list(wear_after.estimate_mm)}
                               if wear_before and wear_after else None),
            "verdicts": [{"effect": r.best.name, "rank": r.pick, "adopted": r.adopted,
                          "checks": r.checks, "wear_reading": r.wear_reading,
                          "also_passing": [{"effect": c.name, "option": c.option,
                                            "heldout_error": c.heldout}
                                           for c in r.also_passing]}
                         for r in rounds],
            "wear_read_by": (last.reader if last else declared).name,
            "second_round": ({"on": first.best.name, "rank": rounds[1].pick,
                              "adopted": rounds[1].adopted,
                              "allowed": rounds[1].allowed, "ranking": rounds[1].table()}
                             if len(rounds) > 1 else None),
        },
        signals={"test": rec.test, "before": base_test, "after": after_test, "rec": rec},
    )
