"""The model's housing vibration against wear beside a real rig's (``python -m
physics.reproduce.rig``).

The rig: the public run-to-failure spur-gear rig described in ``docs/reproduction.md`` (module
3 mm, 18 / 35 teeth, 15 rev/s, 36 wear stages from new to 0.93 mm; its table has one row per
record with ``stage``, ``wear_mm`` and ``acc_rms_g``). What its source does not state is set
here, each choice named:

- speed: 15 rev/s of the pinion (900 r/min); face width, bores and materials: the project's
  defaults (:mod:`physics.params`);
- load: not stated. The model runs at each torque of ``TORQUES_NM`` (a plausible range for a
  module-3 pair of this size, 20-200 N m); ``rms_model`` is the 100 N m one and every torque
  has a column of its own. Nothing of this sweep is calibrated to the rig. Beside it the load
  of the contact on the path is calibrated once, on one stage (:func:`calibrations`): the
  torque of ``CALIBRATION_TORQUES_NM`` whose rise at the stage nearest ``CALIBRATE_AT_MM``
  is nearest the rig's (``rms_calibrated``), judged on the other stages; every stage of
  ``CALIBRATION_RANGE_MM`` taken in turn as that one stage shows what the choice does;
- wear state of a stage: the pair worn from new under the dry Archard law by the contact its
  worn flanks make (:func:`physics.tribology.contact_wear.simulate_contact_wear`, at the
  stage's torque) until the deepest point of either active profile reaches the stage's depth
  (which depth the rig's labels give is not stated; the deepest is the one a profile
  measurement reads);
- contact in the dynamics: the flanks as they are (``dynamics.flank_contact = "exact"``); the
  thesis's contact on the path (``"path"``) on the same worn states beside it, in the columns
  ``rms_path_*``;
- sensor: the rigid-housing acceleration (:func:`physics.signals.measurement.housing_acceleration`),
  so its RMS over its new-gear value is the mesh force's standard deviation over the new
  gear's, whatever the housing mass.

Each column is divided by its new-gear value (the rig's healthy stage mean). The summary gives,
per contact and torque, Spearman's rank correlation over the stages and the rises at the stages
nearest 0.4 and 0.9 mm, model beside rig. The calibrated curve is worn again under
perturbations that change nothing physical (:data:`PRECISION_OFFSETS_M`): how far its figures
move is their numerical precision (:func:`precision`).

The stage means also go out as the measured-data loop's feature table (:func:`loop_table`,
folder ``rig_loop_table``): ``wear_mm`` and ``rms_g`` per stage, with the ``gear.yaml`` and
``operating.yaml`` of what the rig's source states (the torque ``unknown``).
"""

# ruff: noqa: E402 (the imports after the handlers: see install_at_start)
from __future__ import annotations

from physics.interrupt import guard, install_at_start, note

install_at_start(__name__)  # Ctrl-C and SIGTERM handled from here on, during the slow imports

import argparse
import dataclasses
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from physics.dynamics.model import EXACT_PHASES, PairModel, build_model, simulate
from physics.files import (
    check_fresh,
    check_not_input,
    check_writable,
    pyplot,
    read_csv_table,
    resolved,
    save_figure,
    write_csv,
    write_text,
)
from physics.gear.stiffness import mesh_stiffness
from physics.params import Scenario
from physics.reference import RIG_RECORDS
from physics.tribology.contact_wear import simulate_contact_wear

#: the rig's stated geometry and speed
RIG_GEAR = {"module_mm": 3.0, "z1": 18, "z2": 35}
RIG_SPEED_RPM = 900.0
#: torques the unknown load is swept over [N m]; the 100 N m one is ``rms_model``
TORQUES_NM = (20.0, 50.0, 100.0, 200.0)
#: record length of each stage's simulation [s] (7.5 pinion revolutions)
DURATION_S = 0.5
#: stages whose rises the summary compares [mm]
RISE_AT_MM = (0.4, 0.9)
#: the grid the path contact's load is calibrated on [N m] (ratios of at most 1.25: a torque
#: within about 12 % of the best), the sweep's 20, 50 and 100 N m among them
CALIBRATION_TORQUES_NM = (20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 60.0, 70.0, 85.0, 100.0)
#: the one stage the load is calibrated on [mm]: below both compared depths, above the first
#: stages' relief (40-120 um), where neither contact follows the rig
CALIBRATE_AT_MM = 0.2
#: the stages each taken in turn as that one stage, to show what the choice does [mm]
CALIBRATION_RANGE_MM = (0.15, 0.35)
COLUMNS = ("stage", "wear_mm", "acc_rms_g", "stage_order")
#: the calibrated curve worn again with every pinion tooth this far ahead of its place [m]: a
#: common offset closes every gap alike and shares the load as before (no physical change),
#: so what it moves is the wear evolution's sensitivity to round-off (``rig_precision.csv``)
PRECISION_OFFSETS_M = (1e-15, 2e-15, 3e-15)


#: a rise of the summary is read at a stage this close to its depth of ``RISE_AT_MM`` [mm]
#: (the rig's stages lie 0.01-0.05 mm apart), else it is left empty
RISE_TOLERANCE_MM = 0.025
#: what the command writes into ``--out``
OUTPUT_FILES = ("rig_comparison.csv", "rig_summary.csv", "rig_calibration.csv",
                "rig_precision.csv", "rig_comparison.png",
                "rig_loop_table/rig_stage_means.csv", "rig_loop_table/gear.yaml",
                "rig_loop_table/operating.yaml")


def read_rig_table(path: Path, key: str = "rig table") -> pd.DataFrame:
    """The rig's records: one row per record with ``stage``, ``stage_order``, ``wear_mm`` and
    ``acc_rms_g``, checked before any work; a ``ValueError`` naming ``key`` (the command's
    ``--table``), the file and what is wrong: not a UTF-8 CSV
    (:func:`physics.files.read_csv_table`), a column missing, a value not a finite number, a
    negative depth, no new-gear stage (``wear_mm`` 0), or a depth the rig pair's teeth do not
    have (at or beyond their tip thickness,
    :attr:`~physics.gear.geometry.MeshGeometry.tip_thickness`: a table in um read as
    mm)."""
    fix = f"give the rig's records table ({', '.join(COLUMNS)}; one row per record)"
    table = read_csv_table(path, key, fix, columns=COLUMNS,
                           numeric=("wear_mm", "acc_rms_g", "stage_order"))
    wear = table["wear_mm"].to_numpy(dtype=float)
    if (wear < 0).any():
        raise ValueError(f"{key} {path}: wear_mm = {wear.min():g} is negative; give each "
                         "stage's wear depth in mm, 0 for the new gear")
    if not (wear == 0).any():
        raise ValueError(f"{key} {path}: no stage of wear_mm = 0 (the new gear every "
                         "column is divided by)")
    scn = rig_scenario(TORQUES_NM[0])
    tip = mesh_stiffness(scn.gear, scn.material).geometry.tip_thickness * 1e3
    if wear.max() >= tip:
        raise ValueError(f"{key} {path}: wear_mm = {wear.max():g} mm reaches the {tip:.3g} mm "
                         "the rig pair's thinner tooth is thick at its tip (along its flank's "
                         "normal): a flank worn that deep has no tip left to mesh; leave out "
                         "the deeper stages, or check that wear_mm is in mm (not um)")
    return table


def _stage_rms(table: pd.DataFrame) -> pd.DataFrame:
    """One row per stage in stage order: ``stage_order``, ``stage``, ``wear_mm`` and the mean
    ``rms_g`` of its records."""
    return (table.groupby(["stage_order", "stage"], sort=True)
            .agg(wear_mm=("wear_mm", "first"), rms_g=("acc_rms_g", "mean")).reset_index())


def stage_means(table: pd.DataFrame) -> pd.DataFrame:
    """Stage means of the rig's RMS, in stage order, over the healthy stage's."""
    means = _stage_rms(table)
    healthy = float(means.loc[means["wear_mm"] == 0, "rms_g"].mean())
    return means.assign(rms_measured=means["rms_g"] / healthy).drop(columns="rms_g")


def loop_table(table: pd.DataFrame, folder: Path) -> None:
    """The rig's stage means as a feature table of the measured-data loop (``python -m
    physics.loop data=FOLDER/rig_stage_means.csv``): ``wear_mm`` and the stage's mean
    ``rms_g`` in stage order, beside a ``gear.yaml`` of the rig's stated geometry and an
    ``operating.yaml`` of its stated speed, the torque ``unknown``."""
    write_csv(_stage_rms(table)[["wear_mm", "rms_g"]], folder / "rig_stage_means.csv")
    gear = "".join(f"{k}: {v:g}\n" for k, v in RIG_GEAR.items())
    write_text(folder / "gear.yaml", gear)
    write_text(folder / "operating.yaml", f"n1_rpm: {RIG_SPEED_RPM:g}\ntorque_Nm: unknown\n")


def rig_scenario(torque_Nm: float) -> Scenario:
    """The rig's pair at 15 rev/s and ``torque_Nm`` under the dry wear law."""
    base = Scenario()
    return dataclasses.replace(
        base, gear=dataclasses.replace(base.gear, **RIG_GEAR),
        operating=dataclasses.replace(base.operating, n1_rpm=RIG_SPEED_RPM, torque_Nm=torque_Nm),
        tribology=dataclasses.replace(base.tribology, regime="dry"),
        dynamics=dataclasses.replace(base.dynamics, duration_s=DURATION_S))


def worn_states(scn: Scenario, depths_mm: np.ndarray, offset_m: float = 0.0
                ) -> tuple[np.ndarray | None, list[tuple[np.ndarray, np.ndarray]]]:
    """The pair of ``scn`` worn from new by the contact its worn flanks make
    (:func:`physics.tribology.contact_wear.simulate_contact_wear`) to each depth [mm] of the
    deepest point of either active profile: the roll grid and the pinion and gear wear [m] of
    each state (unworn flanks where no depth is above 0); ``offset_m``: every pinion tooth
    that far ahead of its place (:data:`PRECISION_OFFSETS_M`)."""
    top = float(np.max(depths_mm))
    if top <= 0:
        return None, [(None, None)] * len(depths_mm)
    # every tooth alike (one row a wheel; teeth set off alike stay alike, and are solved once)
    ahead = None if offset_m == 0 else (np.full(scn.gear.z1, offset_m), None)
    run = simulate_contact_wear(scn, top * 1e-3, positions=ahead)
    return run.s, [(p[0], g[0]) for p, g, _ in (run.at_depth(d * 1e-3) for d in depths_mm)]


def worn_models(scn: Scenario, contact: str, s: np.ndarray | None,
                states: list[tuple[np.ndarray, np.ndarray]]) -> list[PairModel]:
    """The dynamic models of the worn states of :func:`worn_states` with the contact
    ``contact`` (``dynamics.flank_contact``: ``exact`` or ``path``), at ``EXACT_PHASES``."""
    sc = dataclasses.replace(scn, dynamics=dataclasses.replace(scn.dynamics,
                                                               flank_contact=contact))
    return [build_model(sc, s_grid=s, wear1=w1, wear2=w2, n_phase=EXACT_PHASES)
            for w1, w2 in states]


def model_rms(torque_Nm: float, depths_mm: np.ndarray,
              contacts: Sequence[str] = ("exact", "path"), offset_m: float = 0.0
              ) -> dict[str, np.ndarray]:
    """Housing-acceleration RMS of the rig's pair worn to each depth, over the new pair's, with
    each of ``contacts`` (``exact``, ``path``: the keys); ``offset_m`` as in
    :func:`worn_states`."""
    scn = rig_scenario(torque_Nm)
    s, states = worn_states(scn, depths_mm, offset_m)
    out = {}
    for contact in contacts:
        spread = simulate(worn_models(scn, contact, s, states), scn.dynamics,
                          every_phase=False).force.std(axis=1)
        out[contact] = spread / spread[np.flatnonzero(depths_mm == 0)[0]]
    return out


def rise_stage(depths: np.ndarray, at: float) -> int | None:
    """The stage (position in ``depths`` [mm]) nearest ``at`` [mm], if it lies within
    :data:`RISE_TOLERANCE_MM` of it; else None (no stage of the table stands for that depth)."""
    i = int(np.argmin(np.abs(depths - at)))
    return i if abs(depths[i] - at) <= RISE_TOLERANCE_MM else None


def unread_rises(depths: np.ndarray) -> str | None:
    """A line naming the depths of :data:`RISE_AT_MM` no stage of ``depths`` stands for (their
    rises are left empty in the summary), None if each has one."""
    missing = [at for at in RISE_AT_MM if rise_stage(depths, at) is None]
    if not missing:
        return None
    shown = " and ".join(f"{at:g} mm" for at in missing)
    return (f"no stage of the table lies within {RISE_TOLERANCE_MM:g} mm of {shown} (its "
            f"stages reach {depths.min():g}-{depths.max():g} mm): the summary's rises there "
            "are left empty")


def _judged(measured: pd.Series, model: pd.Series, depths: np.ndarray,
            left_out: int | None = None) -> dict[str, float]:
    """Spearman's rank correlation of ``model`` with ``measured`` over the stages (but the
    stage ``left_out``), and the rises at ``RISE_AT_MM``, model beside rig."""
    from scipy import stats  # imported on first use: a refusal need not wait for it
    keep = np.arange(len(depths)) != (-1 if left_out is None else left_out)
    row = {"rank_correlation": stats.spearmanr(measured[keep], model[keep]).statistic}
    for at in RISE_AT_MM:
        i = rise_stage(depths, at)
        row[f"rise_measured_{at:g}mm"] = np.nan if i is None else measured.iloc[i]
        row[f"rise_model_{at:g}mm"] = np.nan if i is None else model.iloc[i]
        row[f"model_over_measured_{at:g}mm"] = (row[f"rise_model_{at:g}mm"]
                                                / row[f"rise_measured_{at:g}mm"])
    return row


def calibrations(measured: pd.Series, depths: np.ndarray, curves: dict[float, np.ndarray],
                 stages: Sequence[int]) -> pd.DataFrame:
    """The path contact's load calibrated on one stage, each of ``stages`` in turn: the torque
    of ``curves`` (RMS over new by torque) whose rise there is nearest the rig's (in ratio),
    whether it is an end of the grid, and the curve judged on the other stages
    (:func:`_judged`)."""
    torques = np.array(sorted(curves))
    rows = []
    for i in stages:
        misfit = [abs(np.log(curves[t][i] / measured.iloc[i])) for t in torques]
        best = int(np.argmin(misfit))
        rows.append({"calibration_wear_mm": depths[i], "torque_Nm": torques[best],
                     "at_grid_end": best in (0, len(torques) - 1),
                     "calibration_rise_measured": measured.iloc[i],
                     "calibration_rise_model": curves[torques[best]][i],
                     **_judged(measured, pd.Series(curves[torques[best]]), depths, i)})
    return pd.DataFrame(rows)


def precision(measured: pd.Series, depths: np.ndarray, torque_Nm: float, curve: np.ndarray,
              left_out: int, progress: bool = False) -> pd.DataFrame:
    """The calibrated curve ``curve`` (the path contact at ``torque_Nm``) judged as
    :func:`calibrations` judges it (the stage ``left_out`` left out), beside the same pair worn
    again with each common offset of :data:`PRECISION_OFFSETS_M`: one row per offset (0 first),
    ``offset_m`` and the judged figures. Physically the same curve each time, so their spread
    is the figures' numerical precision."""
    rows = [{"offset_m": 0.0, **_judged(measured, pd.Series(curve), depths, left_out)}]
    for off in tqdm(PRECISION_OFFSETS_M, desc="precision", unit="run", disable=not progress):
        again = model_rms(torque_Nm, depths, ("path",), off)["path"]
        rows.append({"offset_m": off, **_judged(measured, pd.Series(again), depths, left_out)})
    return pd.DataFrame(rows)


def rig_comparison(table: pd.DataFrame, progress: bool = False
                   ) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame, pd.DataFrame | None]:
    """One row per stage (``wear_mm``, ``rms_measured``, ``rms_model``, ``rms_calibrated`` and
    one column per torque and contact of the sweep), the sweep's summary per contact and torque
    (rank correlation, rises at ``RISE_AT_MM``), the one-stage calibrations of the path
    contact's load (:func:`calibrations`; the first row is the one at ``CALIBRATE_AT_MM``, the
    others each stage of ``CALIBRATION_RANGE_MM``) and the first's :func:`precision` (None
    where no stage lies at ``CALIBRATE_AT_MM``); ``progress``: bars over the torques and the
    precision's runs."""
    means = stage_means(table)
    depths = means["wear_mm"].to_numpy(dtype=float)
    path = {}
    for torque in tqdm(sorted({*TORQUES_NM, *CALIBRATION_TORQUES_NM}), desc="torques",
                       unit="torque", disable=not progress):
        swept = torque in TORQUES_NM
        rms = model_rms(torque, depths, ("exact", "path") if swept else ("path",))
        path[torque] = rms["path"]
        if swept:
            means[f"rms_model_{torque:g}Nm"] = rms["exact"]
            means[f"rms_path_{torque:g}Nm"] = rms["path"]
    means["rms_model"] = means["rms_model_100Nm"]
    rows = []
    for contact, prefix in (("exact", "rms_model"), ("path", "rms_path")):
        for torque in TORQUES_NM:
            rows.append({"contact": contact, "torque_Nm": torque,
                         **_judged(means["rms_measured"], means[f"{prefix}_{torque:g}Nm"],
                                   depths)})
    grid = {t: path[t] for t in CALIBRATION_TORQUES_NM}
    low, high = CALIBRATION_RANGE_MM
    chosen = rise_stage(depths, CALIBRATE_AT_MM)
    others = [i for i in np.flatnonzero((depths >= low) & (depths <= high)) if i != chosen]
    calibrated = calibrations(means["rms_measured"], depths, grid,
                              ([] if chosen is None else [chosen]) + others)
    spread = None
    if chosen is not None:
        torque = calibrated["torque_Nm"].iloc[0]
        means["rms_calibrated"] = grid[torque]
        spread = precision(means["rms_measured"], depths, torque, grid[torque], chosen, progress)
    return means, pd.DataFrame(rows), calibrated, spread


def plot_rig_comparison(means: pd.DataFrame, path: Path,
                        torque_calibrated: float | None = None) -> None:
    """Measured and modelled RMS rise against wear, one line per torque; the exact contact on
    the left, the path contact on the right, with its load calibrated at one stage
    (``torque_calibrated``, ``rms_calibrated``) where there is one."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 5.0), sharey=True, layout="constrained")
    for ax, (prefix, title) in zip(axes, (("rms_model", "flanks as they meet (exact)"),
                                          ("rms_path", "contact on the path (thesis 2.2)")),
                                   strict=True):
        ax.plot(means["wear_mm"], means["rms_measured"], "ko-", label="rig (stage means)")
        for torque in TORQUES_NM:
            ax.plot(means["wear_mm"], means[f"{prefix}_{torque:g}Nm"], ".-",
                    label=f"model, {torque:g} N m")
        if prefix == "rms_path" and torque_calibrated is not None:
            ax.plot(means["wear_mm"], means["rms_calibrated"], "-", color="tab:purple", lw=2.5,
                    label=f"model, {torque_calibrated:g} N m (calibrated at one stage)")
            ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
        ax.set_title(title)
        ax.set_xlabel("wear depth of the stage [mm]")
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("housing acceleration RMS / new")
    axes[0].legend(fontsize=8)
    save_figure(fig, path)
    plt.close(fig)


def default_table() -> Path:
    """The rig's table shipped with the package (:data:`physics.reference.RIG_RECORDS`)."""
    return RIG_RECORDS


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m physics.reproduce.rig",
        description="The model's housing vibration against wear beside a real rig's stage "
                    "means, the rig's unknown load swept over 20-200 N m.",
        epilog="writes rig_comparison.csv (one row per stage), rig_summary.csv (one row per "
               "torque), rig_calibration.csv (the path contact's load calibrated on one stage, "
               "then on each stage of 0.15-0.35 mm in turn), rig_precision.csv (that calibrated "
               "curve worn again under round-off perturbations), rig_comparison.png and the loop's "
               "feature table rig_loop_table/ "
               "(rig_stage_means.csv, gear.yaml, operating.yaml) into --out")
    ap.add_argument("--table", type=Path, default=default_table(),
                    help="the rig's records (stage, stage_order, wear_mm, acc_rms_g); default: "
                         "%(default)s")
    ap.add_argument("--out", type=Path, default=Path("outputs") / "rig",
                    help="folder the files go to (default: %(default)s)")
    ap.add_argument("--overwrite", action="store_true",
                    help="replace the rig files an earlier run left in --out (else refused)")
    args = ap.parse_args(argv)
    if not args.table.is_file():
        print(f"error: --table {args.table} is not a file; give the rig's records table "
              "(stage, stage_order, wear_mm, acc_rms_g)", file=sys.stderr)
        return 2
    try:
        table = read_rig_table(args.table, "--table")
        check_writable(args.out, "--out")
        check_not_input([resolved(args.out) / name for name in OUTPUT_FILES], "--out",
                        args.table, "--table")
        check_fresh(args.out, "--out", ("rig_*.csv", "rig_*.png", "rig_loop_table/*"),
                    args.overwrite, "--overwrite")
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    note(lambda: "nothing is written before the comparison is complete; run the command again")
    return guard(lambda: _run(table, resolved(args.out)))


def _run(table: pd.DataFrame, out: Path) -> int:
    unread = unread_rises(stage_means(table)["wear_mm"].to_numpy(dtype=float))
    if unread is not None:
        print(f"note: {unread}", file=sys.stderr)
    stages, summary, calibrated, spread = rig_comparison(table, progress=True)
    write_csv(stages, out / "rig_comparison.csv")
    write_csv(summary, out / "rig_summary.csv")
    write_csv(calibrated, out / "rig_calibration.csv")
    if spread is not None:
        write_csv(spread, out / "rig_precision.csv")
    torque = calibrated["torque_Nm"].iloc[0] if "rms_calibrated" in stages else None
    plot_rig_comparison(stages, out / "rig_comparison.png", torque)
    loop_table(table, out / "rig_loop_table")
    print(summary.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
