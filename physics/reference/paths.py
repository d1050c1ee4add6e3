"""Where the reference data shipped with the package lie (``README.md`` beside this module:
sources and what they do not state)."""

from __future__ import annotations

from pathlib import Path

#: the thesis's numeric tables, one CSV each (``table15_measured_acceleration_features.csv``:
#: its measurement)
THESIS_TABLES = Path(__file__).resolve().parent / "thesis_tables"
#: the public run-to-failure rig (module 3, 18/35 teeth, 36 wear stages to 0.93 mm)
INSTITUTE_RIG = Path(__file__).resolve().parent / "institute_rig"
#: its records at 15 rev/s: stage, wear label, acceleration RMS, FM energy
RIG_RECORDS = INSTITUTE_RIG / "rig_15rps_records.csv"
