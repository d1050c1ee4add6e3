"""Stage 4 of the loop, the search: the calibration and every candidate's fit (``fit``), a
reference gearbox's form error (``form_error``) or this unit's own earliest records as the
reference (``own_history``), the model-based wear reading (``wear_reading``), the candidates
ranked and judged (``attribution``) and the detection limits of those not named
(``detection``)."""

from __future__ import annotations

from physics.exports import lazy_exports

_SOURCES = {
    "physics.loop.search.fit": ("Candidate", "calibrate", "search"),
    "physics.loop.search.form_error": ("FormReference", "form_reference"),
    "physics.loop.search.own_history": ("History", "parse_history", "own_reference"),
    "physics.loop.search.wear_reading": ("Reader", "wear_estimates"),
    "physics.loop.search.attribution": ("Round", "attribute"),
    "physics.loop.search.detection": ("detection_limits",),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
