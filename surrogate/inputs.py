"""The network's default inputs: which columns it reads of the sensors a user has, read
absolutely or against each gearbox's baseline record, with or without the operating point
(``data.sensors``, ``data.baseline``, ``data.operating_point``; docs/surrogate.md, Method).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from physics.signals.order_analysis import LINE_ORDERS, MESH_ORDERS

#: the sensors a user may have: DTE (``dte_*`` features) and housing acceleration (``acc_*``)
SENSORS = ("dte", "acc")
#: the features of each sensor that a gearbox's unknown offsets and scales leave alone. A DTE
#: record's mean is the half backlash plus the static deflection (tens of um, set by tolerances
#: the user does not know; an encoder pair measures the DTE only up to a constant), so of the
#: DTE the mean-free peak-to-peak value, the kurtosis and the levels of mesh harmonics 2-6
#: relative to the first (ratios of the record's own lines, which wear moves by several dB:
#: :func:`physics.signals.order_analysis.mesh_harmonic_levels`) are used; the housing
#: acceleration's level scales with the housing's effective mass and the transfer path, so of it
#: only the dimensionless shape features are used (Table 13 definitions in
#: :mod:`physics.signals.features`; docs/surrogate.md measures the gain on gearboxes away from
#: the training ones, and the harmonics' phases, dataset columns too, as an alternative)
INVARIANT = {"dte": ("peak_to_peak", "kurtosis", *(f"mesh{k}_db" for k in MESH_ORDERS)),
             "acc": ("kurtosis", "crest", "margin", "impulse", "shape")}
#: the absolute reading's default inputs (``data.baseline=false``): the invariant features of
#: both sensors
DEFAULT_INPUTS = [f"{q}_{f}" for q in SENSORS for f in INVARIANT[q]]
#: the operating point's columns, inputs beside the features with ``data.operating_point``
#: (as measured, never read against the baseline record)
CONDITIONS = ["n1_rpm", "torque_Nm"]
#: units of a column that states the operating point a row was measured at (a shaft speed, a
#: torque), as :mod:`surrogate.tables` normalises them
OPERATING_UNITS = ("r/min", "rev/s", "N m")
#: words of a column's name (split at ``_``, any case) that state the operating point where its
#: unit is not given (``speed``, ``speed_rps``, ``rpm``, ``load_Nm``)
OPERATING_WORDS = ("speed", "rpm", "rps", "torque", "load")


def operating_columns(frame, units: dict[str, str], inputs: list[str], skip=()) -> list[str]:
    """The columns of a training table ``frame`` that state the operating point its rows were
    measured at without being inputs: :data:`CONDITIONS`, a column in one of
    :data:`OPERATING_UNITS` (``units``) or named with one of :data:`OPERATING_WORDS`, numeric
    and finite in every row; not an input and not in ``skip`` (the target). A split by speed
    (``data.group_by=speed``) keeps it too: its test groups are what the range must flag. A
    model records their training range and flags a row read outside it
    (:meth:`surrogate.schema.FeatureSchema.operating_outside`): with the operating point not
    among its inputs, it cannot tell a reading at another speed from one at another wear."""

    return [c for c in stating_operating(frame, units, inputs, skip)
            if np.isfinite(pd.to_numeric(frame[c], errors="coerce").to_numpy(float)).all()]


def stating_operating(frame, units: dict[str, str], inputs: list[str], skip=()) -> list[str]:
    """The columns of ``frame`` that by name or unit state the operating point (module
    :func:`operating_columns`), whatever their values; those not a finite number in every row
    cannot be checked, and a run says so."""
    out = []
    for col in frame.columns:
        name = str(col)
        words = {w.lower() for w in name.split("_")}
        stated = (name in CONDITIONS or units.get(name) in OPERATING_UNITS
                  or bool(words & set(OPERATING_WORDS)))
        if stated and name not in inputs and name not in skip:
            out.append(name)
    return out


#: the baseline reading's default inputs: the DTE's mesh lines 1-6, each a complex amplitude
#: against a once-per-revolution mark (dataset columns ``dte_line<k>_re``, ``_im``), read as
#: their vector change since the baseline record (docs/surrogate.md, Method, Baseline mode)
BASELINE_INPUTS = [f"dte_line{k}" for k in LINE_ORDERS]


def input_columns(sensors: list[str], operating_point: bool, baseline: bool = False
                  ) -> list[str]:
    """The network's default inputs, with or without the operating point: read against the
    baseline record, the DTE's mesh lines (:data:`BASELINE_INPUTS`); read absolutely, the
    :data:`INVARIANT` features of the sensors a user has."""
    unknown = sorted(set(sensors) - set(SENSORS))
    if unknown or not sensors or len(set(sensors)) != len(sensors):
        raise ValueError(f"data.sensors = {list(sensors)} must name one or both of {SENSORS}")
    if baseline and "dte" not in sensors:
        raise ValueError(f"data.sensors = {list(sensors)}: the reading against the baseline "
                         "record takes the DTE's mesh lines; without a DTE read absolutely "
                         "(data.baseline=false) or name the inputs (data.inputs=[...])")
    cols = (BASELINE_INPUTS if baseline else
            [f"{q}_{f}" for q in SENSORS if q in sensors for f in INVARIANT[q]])
    return cols + (CONDITIONS if operating_point else [])
