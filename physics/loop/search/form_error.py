"""The declared model's form error measured on a reference gearbox: the discrepancy's mean.

Two reasonable gear models of one pair differ by far more than measurement noise (on the
independent simulator's records the calibrated declared model sits at 5 to 9 times the noise
in a clean bundle, docs/loop.md). In Kennedy and O'Hagan's terms the residual is
``r = delta + eps``: a model discrepancy ``delta`` and the noise (J. R. Stat. Soc. B 63 (2001)
425). :func:`physics.loop.model.discrepancy.discrepancy_sd` estimates the discrepancy's variance on
the bundle's own train records; its **mean** cannot be estimated there, since an undeclared
effect in the records is, on one gearbox, a mean residual as well. It can be estimated on a
gearbox known to carry none of the effects sought: a sister unit of the same type that passed
its acceptance test, or the same unit at commissioning, recorded at the same operating points
with the same sensors and sampling rates (the reference signature of condition monitoring,
whose change criterion II of ISO 20816-1:2016 judges; here it is the model's residual
that is referred to the reference, not the signature).

:func:`form_reference` calibrates the declared model on such a reference bundle exactly as the
loop calibrates it on the measured one and keeps, for each group (operating point, quantity,
sampling rate), the mean residual of each signature entry over all reference records
[dB] (:class:`FormReference`); ``run_loop(..., reference=...)``
removes it from the measured signatures of the bundle
under study, group by group, before the loop calibrates anything. What remains is the
residual the declared model does not share with the reference gearbox: an undeclared effect,
the two units' difference, the noise. It also keeps the reference records' discrepancy about
that mean (:attr:`FormReference.spread`): the declared model's scatter on clean records of the
gearbox type, by which the loop judges an unexplained residual. The bundle's own train records
cannot give it where an effect is present in all of them (it raises their scatter in its own
entries); the reference's scatter does not hold the two units' difference beyond what the
calibrated nuisance takes up, nor, for the unit's own earliest records, the declared model's
error in how the signature changes with the wear since them.

What it cannot do: remove a form error that depends on parameters in which the two units
differ strongly (another mounting, another load spectrum), or see an effect that the
reference gearbox carries too; both are the user's choice of reference.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from physics.loop.config import LoopSettings
from physics.loop.measured.bundle import Bundle
from physics.loop.measured.records import Records, group_keys, group_label, prepare
from physics.loop.model.comparison import residuals_db, rms
from physics.loop.model.declared import declared_modes, declared_nuisance
from physics.loop.model.discrepancy import discrepancy_sd
from physics.loop.model.simulation import model_signals
from physics.loop.search.fit import calibrate
from physics.loop.threads import one_blas_thread
from physics.params import Scenario


@dataclass(frozen=True)
class FormReference:
    """Mean signature residual [dB] of the calibrated declared model on a reference gearbox's
    records, per group key ``(n1_rpm, torque_Nm, quantity, fs_hz)``: the discrepancy's mean
    (:func:`form_reference` measures it)."""

    offsets: dict[tuple, np.ndarray]
    records: dict[tuple, int]  # reference records behind each group's mean
    gear: dict  # the reference bundle's gear overrides (the type both units must share)
    calibration: dict  # the reference's calibrated nuisance
    #: per group of two or more reference records, the discrepancy sd [dB] of each entry by
    #: which a record referred to the reference mean is judged (:func:`_spread`)
    spread: dict[tuple, np.ndarray]
    # what the reference is: a sister gearbox, or this unit's own earliest records
    # (:mod:`physics.loop.search.own_history`), with the records it holds
    source: str = "a sister gearbox"
    names: tuple[str, ...] = ()
    #: whether the reference is this unit's own earliest records (then its :attr:`calibration`
    #: is held for the later ones, :func:`physics.loop.search.fit.held`)
    same_unit: bool = False

    def check(self, bundle: Bundle) -> None:
        """Refuse a bundle this reference cannot serve (:func:`check_reference`)."""
        check_reference(bundle, self.gear, list(self.offsets))

    def subtracted(self, rec: Records) -> Records:
        """``rec`` with each record's measured signature less its group's reference mean."""
        measured = [m - self.offsets[rec.group(i).key] for i, m in enumerate(rec.measured)]
        return dataclasses.replace(rec, measured=measured)

    def judging(self, rec: Records) -> Records:
        """``rec`` with the discrepancy of the reference records (:attr:`spread`) in place of
        the one estimated on ``rec``'s train records, which an effect present in all of them
        inflates; in a group of one reference record (no scatter to measure) the train
        records' is kept."""
        return dataclasses.replace(rec, groups=[
            dataclasses.replace(g, discrepancy_sd=self.spread[g.key])
            if g.key in self.spread else g for g in rec.groups])

    def summary(self) -> dict:
        """For the report: each group's reference records and RMS mean residual [dB]."""
        return {"source": self.source, "reference_records": list(self.names),
                "calibration_held": self.same_unit,
                "records": {group_label(k): n for k, n in self.records.items()},
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


@one_blas_thread
def form_reference(reference: Bundle, base: Scenario, settings: LoopSettings,
                   source: str = "a sister gearbox", same_unit: bool = False) -> FormReference:
    """Calibrate the declared model on ``reference`` (its train records, as the loop does) and
    average each group's residual over all its records; ``source`` says what the reference
    is (for the report), ``same_unit`` whether it is the unit's own earliest records. Also the
    residuals' discrepancy about that mean (:attr:`FormReference.spread`)."""
    rec = prepare(reference, base, settings)
    start = declared_nuisance(base) | declared_modes(base)
    nuisance, _ = calibrate(rec, start)
    idx = np.arange(len(rec.models))
    res = residuals_db(rec, idx, model_signals(rec, idx, nuisance, None, {}))
    offsets = {g.key: np.mean([res[i] for i in g.records], axis=0) for g in rec.groups}
    return FormReference(
        offsets=offsets, spread=_spread(rec, res, offsets),
        records={g.key: len(g.records) for g in rec.groups},
        gear=dict(reference.gear), calibration=nuisance, source=source,
        names=tuple(reference.records), same_unit=same_unit)


def _spread(rec: Records, res: list[np.ndarray], offsets: dict[tuple, np.ndarray]
            ) -> dict[tuple, np.ndarray]:
    """Per group, the discrepancy sd [dB] by which a record referred to the group's mean
    ``offsets`` is judged: the reference records' discrepancy ``d`` about that mean
    (:func:`physics.loop.model.discrepancy.discrepancy_sd` of the residuals ``res`` centred, each
    scaled by ``sqrt(n / (n - 1))``, the variance the mean of ``n`` took), plus the error of
    the mean itself, which every record referred to it shares: ``(d^2 + entry_sd^2) / n``.
    A group of one record has no scatter to measure: it enters no estimate and gets none."""
    groups = [g for g in rec.groups if len(g.records) >= 2]
    centred = [np.array([res[i] - offsets[g.key] for i in g.records])
               * np.sqrt(len(g.records) / (len(g.records) - 1)) for g in groups]
    sds = discrepancy_sd(groups, centred, rec.settings.discrepancy_prior)
    return {g.key: np.sqrt(d**2 * (1 + 1 / len(g.records)) + g.entry_sd**2 / len(g.records))
            for g, d in zip(groups, sds, strict=True)}
