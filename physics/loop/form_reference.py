"""The declared model's form error measured on a reference gearbox: the discrepancy's mean.

Two reasonable gear models of one pair differ by far more than measurement noise (on the
independent simulator's records the calibrated declared model sits at 6 to 10 times the noise
in a clean bundle, docs/measured-data.md). In Kennedy and O'Hagan's terms the residual is
``r = delta + eps``: a model discrepancy ``delta`` and the noise (J. R. Stat. Soc. B 63 (2001)
425). :func:`physics.loop.bundle_loop.discrepancy_sd` estimates the discrepancy's variance on
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
[dB] (:class:`physics.loop.bundle_loop.FormReference`); ``run_loop(..., reference=...)``
removes it from the measured signatures of the bundle
under study, group by group, before the loop calibrates anything. What remains is the
residual the declared model does not share with the reference gearbox: an undeclared effect,
the two units' difference, the noise.

What it cannot do: remove a form error that depends on parameters in which the two units
differ strongly (another mounting, another load spectrum), or see an effect that the
reference gearbox carries too; both are the user's choice of reference.
"""

from __future__ import annotations

import numpy as np

from physics.loop.bundle import Bundle
from physics.loop.bundle_loop import (
    FormReference,
    LoopSettings,
    calibrate,
    declared_modes,
    declared_nuisance,
    model_signals,
    prepare,
    residuals_db,
)
from physics.params import Scenario


def form_reference(reference: Bundle, base: Scenario, settings: LoopSettings) -> FormReference:
    """Calibrate the declared model on ``reference`` (its train records, as the loop does) and
    average each group's residual over all its records."""
    rec = prepare(reference, base, settings)
    start = declared_nuisance(base) | declared_modes(base)
    nuisance, _ = calibrate(rec, start)
    idx = np.arange(len(rec.models))
    res = residuals_db(rec, idx, model_signals(rec, idx, nuisance, None, {}))
    return FormReference(
        offsets={g.key: np.mean([res[i] for i in g.records], axis=0) for g in rec.groups},
        records={g.key: len(g.records) for g in rec.groups},
        gear=dict(reference.gear), calibration=nuisance)
