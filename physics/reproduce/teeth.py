"""Wear tooth by tooth: how much the teeth's differences shorten the life to a depth, and what
they do to the housing vibration (``python -m physics.reproduce.teeth``).

The thesis pair at the reproduction's operating point (case 3) under the scenario's wear law
(mixed lubrication), its pinion teeth off their places by the single pitch deviations of an
ISO 1328-1 grade (:func:`physics.gear.accuracy.tooth_positions_um`, seeded: the same gearbox
always gets the same teeth), worn by the contact-driven law with each tooth its own flank
(:func:`physics.tribology.contact_wear.simulate_contact_wear`) until the deepest point of any
tooth reaches Table 15's 15 um; beside it, the same pair's teeth worn alike (one flank, today's
model), read at the same depths. For each depth:

- ``cycles_ratio``: the pinion cycles the tooth-by-tooth pair takes to reach the depth (at its
  worst tooth) over those of the pair worn alike: the life to a depth limit that the teeth's
  differences leave;
- ``least_tooth_um``: the deepest point of the least worn pinion tooth then, beside
  ``position_range_um``, the range of the pinion's tooth positions (the lead the teeth ahead
  have to wear away);
- ``rise_own`` and ``rise_alike``: each feature of the rigid-housing acceleration
  (:func:`physics.signals.measurement.housing_acceleration`; RMS, peak-to-peak, kurtosis) and of
  the synchronous average of each shaft (FM4, the sideband level:
  :mod:`physics.signals.indicators`; the gear's with ``_gear``, over the record's six gear
  revolutions) over the new pair's, the teeth at the same places
  (:func:`physics.dynamics.teeth.sequence_model`, exact flank contact, whole hunting periods:
  9 pinion revolutions), beside Table 15's measured rise where it has one.

The gear's teeth are carried alike (their mean: every gear tooth meets 2 of the 18 pinion
teeth here, gcd 9, so an approximation), except in the one run per grade list marked
``wheels = both``, which carries every tooth of both wheels over the hunting period (54
meshes; the gear's positions from the seed's second draw).
"""

# ruff: noqa: E402 (the imports after the handlers: see install_at_start)
from __future__ import annotations

from physics.interrupt import guard, install_at_start, note

install_at_start(__name__)  # Ctrl-C and SIGTERM handled from here on, during the slow imports

import argparse
import dataclasses
import math
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from physics.dynamics.model import simulate
from physics.dynamics.teeth import sequence_model
from physics.files import check_fresh, check_writable, pyplot, resolved, save_figure, write_csv
from physics.gear.accuracy import tooth_positions_um
from physics.gear.mesh_sequence import hunting_period
from physics.gear.stiffness import mesh_stiffness
from physics.params import Dynamics, Scenario
from physics.reference import THESIS_TABLES
from physics.reproduce.localised import DEPTHS_UM, REVOLUTIONS, measured_rises
from physics.signals.features import features
from physics.signals.indicators import indicators
from physics.signals.measurement import housing_acceleration
from physics.tribology.contact_wear import ContactWear, simulate_contact_wear

#: ISO 1328-1 grades of the pinion drawn (the datasets' span is 4-9) and seeds per grade
GRADES = (5, 7, 9)
SEEDS = (0, 1)
#: the grade whose first seed is also run with every tooth of both wheels its own
BOTH_WHEELS_GRADE = 7
#: the features compared (Table 15's three, then two indicators of each shaft's synchronous
#: average: the pinion's, and the gear's with ``_gear``)
FEATURES = ("rms", "peak_to_peak", "kurtosis", "fm4", "sideband_level", "fm4_gear",
            "sideband_level_gear")
COLUMNS = ("grade", "seed", "wheels", "wear_um", "cycles_ratio", "least_tooth_um",
           "position_range_um", "feature", "rise_own", "rise_alike", "rise_measured")
OUTPUT_FILES = ("tooth_wear.csv", "tooth_wear.png")


def scenario() -> Scenario:
    """The thesis pair at case 3, exact flank contact, records of whole hunting periods (the
    sequence of both wheels' teeth repeats in them), as many pinion revolutions as come
    nearest Table 15's :data:`physics.reproduce.localised.REVOLUTIONS`."""
    scn = Scenario()
    g = scn.gear
    period = hunting_period(g.z1, g.z2) // g.z1  # pinion revolutions
    revolutions = max(1, round(REVOLUTIONS / period)) * period
    return dataclasses.replace(scn, dynamics=whole_record(scn.dynamics, revolutions,
                                                          scn.operating.n1_rpm))


def whole_record(dyn: Dynamics, revolutions: int, n1_rpm: float) -> Dynamics:
    """``dyn`` with exact flank contact and a record of at least ``revolutions`` whole pinion
    revolutions at ``n1_rpm`` in whole samples (a fraction of a sample short, the synchronous
    average would drop the last revolution)."""
    fs = dyn.sample_rate_hz
    samples = math.ceil(revolutions * 60.0 / n1_rpm * fs - 1e-9)
    return dataclasses.replace(dyn, flank_contact="exact", duration_s=samples / fs)


def positions(scn: Scenario, grade: int, seed: int, both: bool) -> tuple[np.ndarray, ...]:
    """The pinion's (and with ``both`` the gear's) tooth positions [m] of gearbox ``seed``:
    draws ``2 seed`` and ``2 seed + 1`` of :func:`tooth_positions_um`; None for teeth alike."""
    g = scn.gear
    pinion = tooth_positions_um(g.z1, grade, g.module_mm, g.module_mm * g.z1, 2 * seed) * 1e-6
    gear = (tooth_positions_um(g.z2, grade, g.module_mm, g.module_mm * g.z2, 2 * seed + 1)
            * 1e-6 if both else None)
    return pinion, gear


def _least_tooth(run: ContactWear, wear1: np.ndarray) -> float:
    return float(wear1[:, run.active].max(axis=1).min())


def tooth_study(scn: Scenario, runs: list[tuple[int, int, bool]], measured: pd.DataFrame | None,
                progress: bool = False) -> pd.DataFrame:
    """The table of the module doc for each ``(grade, seed, both wheels)`` of ``runs``."""
    ms = mesh_stiffness(scn.gear, scn.material)
    top = max(DEPTHS_UM) * 1e-6
    alike = simulate_contact_wear(scn, top, stiffness=ms)
    rows = []
    for grade, seed, both in tqdm(runs, desc="gearboxes", unit="gearbox", disable=not progress):
        pinion, gear = positions(scn, grade, seed, both)
        own = simulate_contact_wear(scn, top, stiffness=ms, positions=(pinion, gear))
        at = (pinion, np.zeros(1) if gear is None else gear)
        models = [sequence_model(scn, ms, own.s, own.history[1][0], own.history[2][0], at)]
        states = []
        for depth in DEPTHS_UM:
            w1, w2, cycles = own.at_depth(depth * 1e-6)
            a1, a2, cycles_alike = alike.at_depth(depth * 1e-6)
            models += [sequence_model(scn, ms, own.s, w1, w2, at),
                       sequence_model(scn, ms, alike.s, np.repeat(a1, len(w1), axis=0),
                                      np.repeat(a2, len(w2), axis=0), at)]
            states.append((cycles / cycles_alike, _least_tooth(own, w1)))
        force = simulate(models, scn.dynamics, every_phase=False).force
        accel = housing_acceleration(force, scn.dynamics.housing_mass_kg)
        fs, f1, g = scn.dynamics.sample_rate_hz, scn.operating.n1_rpm / 60.0, scn.gear
        values = features(accel) | indicators(accel, fs, f1, g.z1)
        values |= {f"{name}_gear": v
                   for name, v in indicators(accel, fs, f1 * g.z1 / g.z2, g.z2).items()}
        for k, depth in enumerate(DEPTHS_UM):
            for name in FEATURES:
                v = np.asarray(values[name])
                hit = (None if measured is None or name not in measured else
                       measured.loc[np.isclose(measured["wear_mm"], depth * 1e-3), name])
                rows.append({"grade": grade, "seed": seed, "wheels": "both" if both else "pinion",
                             "wear_um": depth, "cycles_ratio": states[k][0],
                             "least_tooth_um": states[k][1] * 1e6,
                             "position_range_um": np.ptp(pinion) * 1e6, "feature": name,
                             "rise_own": v[1 + 2 * k] / v[0], "rise_alike": v[2 + 2 * k] / v[0],
                             "rise_measured": np.nan if hit is None or hit.empty
                             else hit.iloc[0]})
    return pd.DataFrame(rows, columns=list(COLUMNS))


def plot_tooth_study(table: pd.DataFrame, path: Path) -> None:
    """Left: the life to each depth, tooth by tooth over teeth alike, per grade. Right: the
    housing RMS over new against depth, tooth by tooth and alike, beside Table 15's."""
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(10.0, 4.5), layout="constrained")
    rms = table[(table["feature"] == "rms") & (table["wheels"] == "pinion")]
    for grade, part in rms.groupby("grade"):
        mean = part.groupby("wear_um")
        left.plot(mean["cycles_ratio"].mean().index, mean["cycles_ratio"].mean(), "o-",
                  label=f"grade {grade}")
        right.plot(mean["rise_own"].mean().index, mean["rise_own"].mean(), "o-",
                   label=f"tooth by tooth, grade {grade}")
    alike = rms.groupby("wear_um")["rise_alike"].mean()
    right.plot(alike.index, alike, "k--", label="teeth worn alike")
    measured = rms.groupby("wear_um")["rise_measured"].first().dropna()
    if not measured.empty:
        right.plot(measured.index, measured, "ks", label="Table 15, measured")
    left.set_xlabel("deepest wear of any pinion tooth [um]")
    left.set_ylabel("cycles to the depth: tooth by tooth / alike")
    left.set_ylim(0.0, 1.05)
    right.set_xlabel("deepest wear of any pinion tooth [um]")
    right.set_ylabel("housing acceleration RMS / new")
    for ax in (left, right):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    left.set_title("life to a depth (mean of the seeds)")
    right.set_title("housing vibration (mean of the seeds)")
    save_figure(fig, path)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m physics.reproduce.teeth",
        description="Wear tooth by tooth on the thesis pair at case 3: the life to Table 15's "
                    "depths and the housing vibration, the pinion's teeth off their places by "
                    "an ISO 1328 grade, against the same pair worn alike.",
        epilog="writes tooth_wear.csv (one row per gearbox, depth and feature) and "
               "tooth_wear.png into --out")
    ap.add_argument("--out", type=Path, default=Path("outputs") / "teeth",
                    help="folder the files go to (default: %(default)s)")
    ap.add_argument("--grades", type=int, nargs="+", default=list(GRADES),
                    help="ISO 1328-1 grades of the pinion, 4-9 (default: %(default)s)")
    ap.add_argument("--seeds", type=int, default=len(SEEDS),
                    help="gearboxes per grade, seeds 0, 1, ... (default: %(default)s)")
    ap.add_argument("--overwrite", action="store_true",
                    help="replace the files an earlier run left in --out (else refused)")
    args = ap.parse_args(argv)
    try:
        bad = [g for g in args.grades if not 4 <= g <= 9]
        if bad:
            raise ValueError(f"--grades {bad[0]}: the datasets' ISO 1328 grades are 4-9; give "
                             "grades in that span")
        if args.seeds < 1:
            raise ValueError(f"--seeds {args.seeds}: give at least one gearbox per grade")
        check_writable(args.out, "--out")
        check_fresh(args.out, "--out", OUTPUT_FILES, args.overwrite, "--overwrite")
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    runs = [(g, s, False) for g in args.grades for s in range(args.seeds)]
    if BOTH_WHEELS_GRADE in args.grades:
        runs.append((BOTH_WHEELS_GRADE, 0, True))
    note(lambda: "nothing is written before the study is complete; run the command again")
    return guard(lambda: _run(runs, resolved(args.out)))


def _run(runs: list[tuple[int, int, bool]], out: Path) -> int:
    table = tooth_study(scenario(), runs, measured_rises(THESIS_TABLES), progress=True)
    write_csv(table, out / "tooth_wear.csv")
    plot_tooth_study(table, out / "tooth_wear.png")
    rms = table[table["feature"] == "rms"]
    print(rms.groupby(["wheels", "grade", "wear_um"])[["cycles_ratio", "least_tooth_um",
                                                         "rise_own", "rise_alike"]]
          .mean().to_string(float_format=lambda v: f"{v:.3g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
