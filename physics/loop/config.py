"""The loop's settings (``loop.*``, :class:`LoopSettings`) and the schema of ``python -m
physics.loop`` (:class:`LoopConfig`), validated on construction."""

from __future__ import annotations

from dataclasses import dataclass, field

from omegaconf import MISSING

from physics.loop.effects import EFFECTS
from physics.params import PhysicsConfig, bounded, validate_fields


@dataclass(frozen=True)
class LoopSettings:
    """Settings of the loop (``loop.*`` in ``conf/loop/loop.yaml``), validated on construction."""

    segment_s: float = bounded(0.25, 0.0, 100.0, "analysis segment [s]; the model simulates one")
    transient_s: float = bounded(0.05, 0.0, 100.0, closed=True)
    # RK4 step of the model's records (``dynamics.step_factor`` for the loop's simulations
    # only; the wear and the datasets keep theirs): half the integration of 0.25, and its
    # change of the signature is far below what a record's start time moves
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
    # best explored points each candidate's least squares starts from, the lowest fit kept
    # (the calibration with ``model_form``: :data:`~physics.loop.search.fit.CALIBRATION_STARTS`)
    starts: int = bounded(1, 1, 100, "explored points each candidate's fit starts from",
                          whole=True)
    floor_db: float = bounded(0.3, 0.0, 100.0, "model error floor added to each entry's scatter",
                              closed=True)
    # the model discrepancy: weight of the pooled variance in each entry family's estimate, in
    # residuals (:func:`~physics.loop.model.discrepancy.discrepancy_sd`) ...
    discrepancy_prior: float = bounded(10.0, 0.0, 1e6, closed=True)
    # ... and the false-add rate per bundle the adoption rule is designed for
    false_add_rate: float = bounded(0.01, 0.0, 1.0, "share of bundles without an effect that "
                                    "may get one")
    candidates: tuple[str, ...] | None = None  # effects to try; None: the whole library
    # an adopted effect reads the wear unless it lowers the model-based wear estimate's
    # leave-one-out skill on the train records of known wear by more than this
    # (:func:`~physics.loop.search.wear_reading.wear_check`)
    max_wear_loss: float = bounded(0.1, 0.0, 100.0, "skill of the wear estimate an adopted "
                                   "effect may cost", closed=True)
    # calibrate the rest of the declared model's form uncertainty
    # (:data:`~physics.loop.model.declared.MODEL_FORM`: the run-out modulation is calibrated either
    # way) with the nuisance; off by default: better on the independent simulator's bundles, but on
    # the project's own it absorbs a friction, leaves a tooth defect's error above half and lets the
    # greedy second round stack a spurious effect (docs/loop.md)
    model_form: bool = False
    # seconds of work after which the loop stops at its next candidate and writes what it has
    # computed, marked partial: in the second round the first round's report, in the first the
    # calibration and the candidates fitted by then (verdict not_judged); 0: no limit
    time_limit_s: float = bounded(0.0, 0.0, 1e7, "seconds; 0 for no limit", closed=True)
    # where no effect is named: each candidate's detection limit, the smallest size the rule
    # would name on these records (physics.loop.search.detection; a few simulations per candidate)
    detection_limits: bool = True

    def __post_init__(self):
        validate_fields(self, "loop")
        for name in ("model_form", "detection_limits"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"loop.{name} = {getattr(self, name)!r} must be true or false")
        e = self.explore
        if isinstance(e, bool) or not isinstance(e, int) or e < 0 or e & (e - 1):
            raise ValueError(f"loop.explore = {e!r} must be 0 or a power of 2 (a Sobol "
                             "sample keeps its balance only then); use e.g. 16 or 32")
        if self.candidates is not None:
            given = self.candidates
            if isinstance(given, str):  # one name: not its letters
                given = (given,)
            if not isinstance(given, list | tuple) or not all(isinstance(n, str) for n in given):
                raise ValueError(f"loop.candidates = {given!r} must be a list of effect names "
                                 f"(or one name); choose from {sorted(EFFECTS)}")
            object.__setattr__(self, "candidates", tuple(given))
            unknown = sorted(set(self.candidates) - set(EFFECTS))
            if unknown or not self.candidates:
                raise ValueError(f"loop.candidates = {list(self.candidates)}: {unknown or 'none'}"
                                 f" not in the effect library; choose from {sorted(EFFECTS)}")


@dataclass
class LoopConfig(PhysicsConfig):
    """Schema of ``python -m physics.loop``."""

    data: str = MISSING  # a bundle folder (docs/own-data.md) or a feature table
    # a bundle of a sister gearbox without the effects sought, at the same operating points,
    # quantities and sampling rates: the declared model's mean form error is measured on it
    # and removed (physics.loop.search.form_error); or this bundle's own earliest records, first:N
    # or before:<cycles or ISO date> (physics.loop.search.own_history), left out of the analysis;
    # None: no reference
    reference: str | None = None
    case: int | None = None  # 1-5: operating point and lubricant of Table 11 (feature tables)
    progress: bool = True
    loop: LoopSettings = field(default_factory=LoopSettings)
