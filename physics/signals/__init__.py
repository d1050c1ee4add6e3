"""Vibration signals (thesis 4.2): the Table 13 features, order analysis and the declared
measurement chain (DTE, housing acceleration, noise). Imports ``physics.params`` and
``physics.dynamics``."""

from __future__ import annotations

import importlib

#: the public names, by the module that defines each; a name is imported on first use, so that
#: importing the package (or one of its modules) stays light and free of import cycles
_SOURCES = {
    "physics.signals.features": ("FEATURES", "DIMENSIONAL", "feature_units"),
    "physics.signals.measurement": (
        "housing_acceleration", "sensed", "declared_chain", "transmissibility", "support_path",
        "housing_mount", "transfer_path", "add_noise"),
    "physics.signals.order_analysis": (
        "line_amplitudes", "power_spectrum", "white_noise_std", "synchronous_average",
        "line_frequencies", "band_edges", "signature_names", "signatures", "signature_segments",
        "mean_signatures"),
}
_SOURCE = {name: module for module, names in _SOURCES.items() for name in names}
__all__ = sorted(_SOURCE)


def __getattr__(name: str):
    if name in _SOURCE:
        value = getattr(importlib.import_module(_SOURCE[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
