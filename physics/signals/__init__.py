"""Vibration signals (thesis 4.2): the Table 13 features, the gear condition indicators of the
time-synchronous average (FM0, FM4, NA4, M6A, M8A, energy ratio, sideband level; the function
``physics.signals.indicators.indicators``), order analysis, the pinion speed of a record
without a tachometer (``physics.signals.shaft_speed``) and the declared measurement chain
(DTE, housing acceleration, noise). Imports ``physics.params`` and ``physics.dynamics``."""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.signals.features": ("FEATURES", "DIMENSIONAL", "feature_units"),
    "physics.signals.indicators": (
        "INDICATORS", "indicator_units", "time_synchronous_average", "tsa_components", "na4",
        "shaft_rate_from_spectrum"),
    "physics.signals.measurement": (
        "housing_acceleration", "sensed", "declared_chain", "transmissibility", "support_path",
        "housing_mount", "transfer_path", "add_noise"),
    "physics.signals.shaft_speed": ("pinion_speed", "SpeedEstimate"),
    "physics.signals.order_analysis": (
        "line_amplitudes", "power_spectrum", "white_noise_std", "synchronous_average",
        "line_frequencies", "band_edges", "signature_names", "signatures", "signature_segments",
        "mean_signatures", "mesh_harmonic_levels", "mesh_harmonic_phases", "mesh_harmonics",
        "mesh_lines", "MESH_ORDERS", "LINE_ORDERS", "PHASE_PARTS", "VECTOR_PARTS"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
