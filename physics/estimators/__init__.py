"""Wear estimators from vibration features (thesis 4.4): the analytic empirical inverse. Imports the
physics subpackages above it (``gear`` ... ``signals``)."""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.estimators.empirical_inverse": (
        "EmpiricalInverse", "Estimate", "wear_errors", "accuracy"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
