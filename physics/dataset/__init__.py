"""Wear and vibration datasets across the operating cases of thesis Table 11: spec, chunks, resume,
merge (``physics.dataset.generation``) and the app ``python -m physics.dataset``. Imports the
physics subpackages above it; nothing imports the app."""

from __future__ import annotations

import importlib

#: the public names, by the module that defines each; a name is imported on first use, so that
#: importing the package (or one of its modules) stays light and free of import cycles
_SOURCES = {
    "physics.dataset.generation": (
        "DatasetConfig", "DatasetSpec", "DatasetJob", "NuisanceRanges", "NUISANCE_COLUMNS",
        "spec_from_config", "plan_dataset", "build_dataset", "dataset_digest", "units",
        "unit_draw", "unit_scenario", "run_unit", "chunk_folder", "chunk_path"),
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
