"""Reproduction of the thesis tables 2-14 (``python -m physics.reproduce``): tables
(``physics.reproduce.thesis``) and figures (``physics.reproduce.plots``). Imports every physics
subpackage above it; nothing imports the app."""

from __future__ import annotations

import importlib

#: the public names, by the module that defines each; a name is imported on first use, so that
#: importing the package (or one of its modules) stays light and free of import cycles
_SOURCES = {
    "physics.reproduce.thesis": ("ReproduceConfig", "reproduce"),
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
