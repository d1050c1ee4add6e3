"""Stage 1 of the loop, the measured records: the bundle format (``bundle``: read, validate,
write), the records as model inputs with their groups and split (``records``), the declared
model's worn states at the records' operating points (``worn_states``) and what a bundle lets
the loop do, decided before any work (``usable``). Imports nothing of the later stages."""

from __future__ import annotations

from physics.exports import lazy_exports

_SOURCES = {
    "physics.loop.measured.bundle": (
        "Bundle", "FeatureTable", "read_bundle", "write_bundle", "read_feature_table",
        "read_measurements", "record_scenario"),
    "physics.loop.measured.records": ("Group", "Records", "prepare", "split_records"),
    "physics.loop.measured.worn_states": ("WearHistory", "wear_history", "worn_models",
                                          "table_models", "check_table_depths"),
    "physics.loop.measured.usable": ("check_usable", "shown_candidates"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
