"""Table 15 by the model alone: pinion-root wear on one tooth and on every tooth.

The thesis's only measurement (4.3, Table 15) is the housing acceleration of its rig with wear
"induced" at the pinion root, 5, 10 and 15 um; it does not say on how many teeth. Here the
thesis pair at the reproduction's operating point (case 3 by default) carries that root wear on
pinion tooth 0 alone and, beside it, on every pinion tooth (the gear unworn), with the contact of
the flanks as they are (``dynamics.flank_contact = "exact"``) and each pinion tooth its own
flank over whole revolutions (:func:`physics.dynamics.teeth.per_tooth_model`). The induced wear's
shape along the flank is the model's own pinion wear (the reproduction's base run) scaled to
its root depth. Each feature of the rigid-housing acceleration
(:func:`physics.signals.measurement.housing_acceleration`; RMS, peak-to-peak, Pearson's
kurtosis) is divided by the new pair's, beside the measured rises when the thesis's tables are
given; and so are the condition indicators of its synchronous average that the thesis did not
read (:mod:`physics.signals.indicators`: FM0, FM4, NA4, energy ratio, sideband level). The thesis
does not state its housing's resonances either: each one-tooth rise of Table 15's features is
also taken through one housing mode (:func:`physics.signals.measurement.transfer_path`) at every
point of :data:`HOUSING_MODES`, the dataset's range of them, and the least and the largest rise
over the range are kept beside the rigid housing's. Nor does it state the rig's operating point:
:func:`table15_operating_points` repeats the comparison at every speed and torque of the
reproduction's Tables 2 and 3.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd

from physics.dataset.generation import NuisanceRanges
from physics.dynamics.model import EXACT_PHASES, build_model, simulate
from physics.dynamics.teeth import per_tooth_model
from physics.files import read_csv_table
from physics.gear.stiffness import mesh_stiffness
from physics.params import Scenario
from physics.reference import THESIS_TABLES
from physics.signals.features import features
from physics.signals.indicators import indicators
from physics.signals.measurement import housing_acceleration, transfer_path
from physics.tribology.wear import WearResult

#: the root depths the thesis's rig was given (4.3) [um]
DEPTHS_UM = (5.0, 10.0, 15.0)
#: the features compared, and their columns in the thesis's Table 15 CSV
FEATURES = {"rms": "rms_m_per_s2", "peak_to_peak": "peak_to_peak_m_per_s2",
            "kurtosis": "kurtosis"}
#: the indicators of the synchronous average beside them (no measured values)
INDICATOR_ROWS = ("fm0", "fm4", "na4", "energy_ratio", "sideband_level")
#: whole pinion revolutions in each record
REVOLUTIONS = 10
#: one housing mode between mesh and accelerometer, (natural frequency [Hz], damping ratio,
#: residue): over the range the datasets draw (:class:`physics.dataset.generation.NuisanceRanges`,
#: 2-8 kHz and 2-10 %; five frequencies on a geometric grid by three damping ratios), the
#: sensor on the mode (residue 1, the datasets' path) or the mode beside the rigid path
#: (residue -1: twice the rigid level above the mode; :func:`transfer_path`)
HOUSING_MODES = tuple((float(fn), float(zeta), residue)
                      for fn in np.geomspace(*NuisanceRanges().transfer_fn_hz, 5)
                      for zeta in np.geomspace(*NuisanceRanges().transfer_zeta, 3)
                      for residue in (1.0, -1.0))
MEASURED_TABLE = "table15_measured_acceleration_features.csv"


def thesis_tables_fix(key: str = "thesis_tables") -> str:
    """What to give instead of a thesis tables folder that lacks a table the run reads."""
    return (f"give {key} the folder of the thesis's tables (those shipped: {THESIS_TABLES}), "
            f"or {key}=null to leave out the measured rises and the check of the thesis's "
            "estimator")


def measured_table(folder: Path, key: str = "thesis_tables") -> pd.DataFrame:
    """The thesis's Table 15 (:data:`MEASURED_TABLE` in ``folder``), checked: a UTF-8 CSV with
    ``wear_mm`` and the columns of :data:`FEATURES`, finite numbers, and a new-gear row
    (``wear_mm`` 0) whose features are not 0 (each rise is over it); else a ValueError naming
    ``key``, the file and the fix."""
    fix = thesis_tables_fix(key)
    path = Path(folder) / MEASURED_TABLE
    table = read_csv_table(path, f"{key}: Table 15", fix, numeric=["wear_mm", *FEATURES.values()])
    new = table.loc[table["wear_mm"] == 0]
    if new.empty:
        raise ValueError(f"{key}: Table 15 {path} has no new-gear row (wear_mm = 0), which "
                         f"each measured rise is over; {fix}")
    zero = [c for c in FEATURES.values() if new[c].iloc[0] == 0]
    if zero:
        raise ValueError(f"{key}: Table 15 {path}: the new-gear row's {zero[0]} is 0, which no "
                         f"rise can be taken over; {fix}")
    return table


def measured_rises(folder: Path | None) -> pd.DataFrame | None:
    """Table 15's features over its new-gear row, from the thesis's tables folder (None: not
    given; the table checked by :func:`measured_table`)."""
    if folder is None:
        return None
    table = measured_table(folder)
    new = table.loc[table["wear_mm"] == 0].iloc[0]
    return pd.DataFrame({"wear_mm": table["wear_mm"],
                         **{f: table[c] / new[c] for f, c in FEATURES.items()}})


def table15_model(scn: Scenario, base: WearResult, thesis_tables: Path | None,
                  contact: str = "exact") -> pd.DataFrame:
    """One row per depth and feature (Table 15's, then the indicators): ``wear_mm``,
    ``feature``, ``rise_measured`` (NaN without the thesis's tables, and for the indicators),
    ``rise_one_tooth``, ``rise_all_teeth``, and for Table 15's features
    ``rise_one_tooth_mode_least`` and ``rise_one_tooth_mode_largest``: the one-tooth rise
    through each of :data:`HOUSING_MODES` (NaN for the indicators; module doc); ``contact``:
    the dynamics' ``flank_contact``."""
    dyn = dataclasses.replace(scn.dynamics, flank_contact=contact,
                              duration_s=REVOLUTIONS * 60.0 / scn.operating.n1_rpm)
    scn = dataclasses.replace(scn, dynamics=dyn)
    ms = mesh_stiffness(scn.gear, scn.material)
    shape = base.pinion / base.pinion.max()
    z1 = scn.gear.z1
    new = build_model(scn, ms, n_phase=EXACT_PHASES)
    models = [per_tooth_model([new] * z1)]
    for depth in DEPTHS_UM:
        worn = build_model(scn, ms, base.s, shape * depth * 1e-6, np.zeros_like(shape),
                           n_phase=EXACT_PHASES)
        models += [per_tooth_model([worn] + [new] * (z1 - 1)), per_tooth_model([worn] * z1)]
    force = simulate(models, dyn, every_phase=False).force
    accel = housing_acceleration(force, dyn.housing_mass_kg)
    values = features(accel)
    values |= indicators(accel, dyn.sample_rate_hz, scn.operating.n1_rpm / 60.0, z1)
    one_tooth = [0, *range(1, 1 + 2 * len(DEPTHS_UM), 2)]  # new, then each depth on one tooth
    through = [features(transfer_path(accel[one_tooth], dyn.sample_rate_hz, fn, zeta, g))
               for fn, zeta, g in HOUSING_MODES]
    mode_rises = {name: np.array([f[name][1:] / f[name][0] for f in through])
                  for name in FEATURES}  # (mode, depth)
    measured = measured_rises(thesis_tables)
    rows = []
    for i, depth in enumerate(DEPTHS_UM):
        wear_mm = depth * 1e-3
        for name in (*FEATURES, *INDICATOR_ROWS):
            v = values[name]
            hit = (None if measured is None or name not in FEATURES else
                   measured.loc[np.isclose(measured["wear_mm"], wear_mm), name])
            modes = mode_rises[name][:, i] if name in FEATURES else np.full(1, np.nan)
            rows.append({"wear_mm": wear_mm, "feature": name,
                         "rise_measured": np.nan if hit is None or hit.empty else hit.iloc[0],
                         "rise_one_tooth": v[1 + 2 * i] / v[0],
                         "rise_all_teeth": v[2 + 2 * i] / v[0],
                         "rise_one_tooth_mode_least": modes.min(),
                         "rise_one_tooth_mode_largest": modes.max()})
    return pd.DataFrame(rows)


def table15_operating_points(scn: Scenario, base: WearResult, speeds_rpm: list[float],
                             torques_Nm: list[float], contact: str = "exact") -> pd.DataFrame:
    """Table 15's features by the model at every speed and torque given (the reproduction's:
    those of the thesis's Tables 2 and 3): the thesis does not state its rig's operating point
    (4.3), and the rises move with it. One row per point, depth and feature: ``n1_rpm``,
    ``torque_Nm``, ``wear_mm``, ``feature``, ``rise_one_tooth``, ``rise_all_teeth``
    (:func:`table15_model` at that point, the same induced wear)."""
    parts = []
    for n1 in speeds_rpm:
        for torque in torques_Nm:
            at = dataclasses.replace(scn, operating=dataclasses.replace(
                scn.operating, n1_rpm=float(n1), torque_Nm=float(torque)))
            table = table15_model(at, base, None, contact)
            table = table[table["feature"].isin(list(FEATURES))]
            parts.append(table[["wear_mm", "feature", "rise_one_tooth", "rise_all_teeth"]]
                         .assign(n1_rpm=float(n1), torque_Nm=float(torque)))
    out = pd.concat(parts, ignore_index=True)
    return out[["n1_rpm", "torque_Nm", "wear_mm", "feature", "rise_one_tooth", "rise_all_teeth"]]
