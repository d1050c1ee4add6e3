"""Reference data shipped with the package (``README.md`` here: sources and what they do not
state): the thesis's tables and a public wear rig's records, as paths to their CSV files.
Imports nothing of the project."""

from __future__ import annotations

from physics.exports import lazy_exports

_SOURCES = {"physics.reference.paths": ("THESIS_TABLES", "INSTITUTE_RIG", "RIG_RECORDS")}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
