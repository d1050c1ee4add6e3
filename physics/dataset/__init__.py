"""Wear and vibration datasets across the operating cases of thesis Table 11: spec, chunks, resume,
merge (``physics.dataset.generation``) and the app ``python -m physics.dataset``. Imports the
physics subpackages above it; nothing imports the app."""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.dataset.generation": (
        "DatasetConfig", "DatasetSpec", "DatasetJob", "NuisanceRanges", "NUISANCE_COLUMNS",
        "spec_from_config", "plan_dataset", "build_dataset", "dataset_digest", "units",
        "unit_draw", "unit_scenario", "run_unit", "chunk_folder", "chunk_path"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
