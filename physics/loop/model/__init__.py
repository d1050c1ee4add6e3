"""Stage 2 of the loop, the model beside the records: the declared model's nuisance and form
parameters (``declared``), its records simulated (``simulation``), the residuals against the
measured ones (``comparison``) and the model discrepancy beyond the noise (``discrepancy``)."""

from __future__ import annotations

from physics.exports import lazy_exports

_SOURCES = {
    "physics.loop.model.declared": ("NUISANCE", "MODEL_FORM", "declared_nuisance", "with_nuisance"),
    "physics.loop.model.simulation": ("model_signals",),
    "physics.loop.model.comparison": ("residuals", "standardised", "feature_error"),
    "physics.loop.model.discrepancy": ("discrepancy_sd", "discrepancy_allowance"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
