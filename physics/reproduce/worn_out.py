"""New to worn out: the contact-driven wear of both pairs to a depth that ends a gear's life,
dry and lubricated, and what the worn teeth can still carry (``python -m
physics.reproduce.worn_out``).

Each run wears a pair from new by the contact its worn flanks make
(:func:`physics.tribology.contact_wear.simulate_contact_wear`, every tooth alike, the
quasi-static load) until the deepest point of either active profile reaches its depth: the
thesis pair at case 3 (2000 r/min, 300 N m) to 0.3 mm, the public rig's pair (module 3, 18/35,
15 rev/s; :func:`physics.reproduce.rig.rig_scenario`) to 1 mm at the ends of its loads. Dry is
the thesis's Archard law; lubricated the scenario's mixed law, its asperity share from the
mixed-EHL solver's table or from its regression (``tribology.asperity_model``). A run ends
where its pair leaves the model's scope, with the reason it names: a tooth whose root stress
passes its fatigue strength (:func:`physics.gear.tooth_bending.check_root_strength`), a tooth
worn to its centre line, or a contact outside the mixed-EHL table's range. Per run the table
holds the cycles, each wheel's deepest wear and the larger root stress of the two wheels' teeth
at the highest point of single contact, new and the largest over the life, beside the
strength (:data:`physics.scope.ROOT_STRENGTH`).
"""

# ruff: noqa: E402 (the imports after the handlers: see install_at_start)
from __future__ import annotations

from physics.interrupt import guard, install_at_start, note

install_at_start(__name__)  # Ctrl-C and SIGTERM handled from here on, during the slow imports

import argparse
import dataclasses
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from physics.files import check_fresh, check_writable, resolved, write_csv
from physics.gear.stiffness import mesh_stiffness
from physics.gear.tooth_bending import root_stress
from physics.params import OutOfScope, Scenario
from physics.reproduce.rig import rig_scenario
from physics.scope import ROOT_STRENGTH
from physics.tribology.contact_wear import simulate_contact_wear
from physics.tribology.wear import quasi_static_force

COLUMNS = ("pair", "torque_Nm", "regime", "asperity_model", "target_mm", "outcome", "cycles",
           "pinion_max_um", "gear_max_um", "root_stress_new_MPa", "root_stress_worn_MPa",
           "root_strength_MPa", "seconds")
OUTPUT_FILES = ("worn_out.csv",)
#: (pair, torque [N m], regime, asperity model, depth [mm]) of each run
RUNS = (
    ("thesis", 300.0, "dry", "solver", 0.3),
    ("thesis", 300.0, "mixed", "solver", 0.3),
    ("thesis", 300.0, "mixed", "regression", 0.3),
    ("rig", 20.0, "dry", "solver", 1.0),
    ("rig", 200.0, "dry", "solver", 1.0),
    ("rig", 100.0, "mixed", "solver", 1.0),
    ("rig", 100.0, "mixed", "regression", 1.0),
)


def scenario(pair: str, torque_Nm: float, regime: str, asperity_model: str) -> Scenario:
    """The run's scenario: the thesis pair at case 3 or the rig's at 15 rev/s, at the torque,
    wear law and asperity model given."""
    if pair not in ("thesis", "rig"):
        raise ValueError(f"pair = {pair!r} must be 'thesis' or 'rig'")
    base = Scenario() if pair == "thesis" else rig_scenario(torque_Nm)
    return dataclasses.replace(
        base, operating=dataclasses.replace(base.operating, torque_Nm=torque_Nm),
        tribology=dataclasses.replace(base.tribology, regime=regime,
                                      asperity_model=asperity_model))


def worn_out_run(pair: str, torque_Nm: float, regime: str, asperity_model: str,
                 target_mm: float) -> dict:
    """One row of the table (module text): the run to ``target_mm`` or to where it left the
    scope, and its teeth's root stress over the life."""
    scn = scenario(pair, torque_Nm, regime, asperity_model)
    ms = mesh_stiffness(scn.gear, scn.material)
    force = quasi_static_force(scn, ms.geometry)

    def stress(p: np.ndarray | None, g: np.ndarray | None, s: np.ndarray | None) -> float:
        return max(root_stress(ms, 1, force, s_grid=s, wear=p).stress,
                   root_stress(ms, 2, force, s_grid=s, wear=g).stress)

    row = {"pair": pair, "torque_Nm": torque_Nm, "regime": regime,
           "asperity_model": asperity_model, "target_mm": target_mm,
           "root_stress_new_MPa": stress(None, None, None) / 1e6,
           "root_strength_MPa": ROOT_STRENGTH / 1e6}
    start = time.perf_counter()
    try:
        run = simulate_contact_wear(scn, target_mm * 1e-3, stiffness=ms)
    except OutOfScope as err:
        return row | {"outcome": f"left the scope: {err}", "cycles": np.nan,
                      "pinion_max_um": np.nan, "gear_max_um": np.nan,
                      "root_stress_worn_MPa": np.nan, "seconds": time.perf_counter() - start}
    _, p, g = run.history
    worn = max(stress(pk[0], gk[0], run.s) for pk, gk in zip(p, g, strict=True))
    return row | {"outcome": "reached", "cycles": run.cycles,
                  "pinion_max_um": float(run.pinion[:, run.active].max()) * 1e6,
                  "gear_max_um": float(run.gear[:, run.active].max()) * 1e6,
                  "root_stress_worn_MPa": worn / 1e6, "seconds": time.perf_counter() - start}


def worn_out_table(runs: Sequence[tuple] = RUNS, scale: float = 1.0,
                   progress: bool = False) -> pd.DataFrame:
    """Every run's row (:func:`worn_out_run`), each depth times ``scale``."""
    rows = [worn_out_run(pair, torque, regime, model, depth * scale)
            for pair, torque, regime, model, depth in tqdm(runs, desc="runs", unit="run",
                                                           disable=not progress)]
    return pd.DataFrame(rows, columns=list(COLUMNS))


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m physics.reproduce.worn_out",
        description="The contact-driven wear of the thesis pair to 0.3 mm and of the public "
                    "rig's pair to 1 mm, dry and lubricated, with the worn teeth's root stress "
                    "against their fatigue strength, and where a run leaves the model's scope.",
        epilog="writes worn_out.csv (one row per run) into --out")
    ap.add_argument("--out", type=Path, default=Path("outputs") / "worn_out",
                    help="folder the file goes to (default: %(default)s)")
    ap.add_argument("--quick", action="store_true",
                    help="every depth a tenth (a check of the code path, seconds)")
    ap.add_argument("--overwrite", action="store_true",
                    help="replace the file an earlier run left in --out (else refused)")
    args = ap.parse_args(argv)
    try:
        check_writable(args.out, "--out")
        check_fresh(args.out, "--out", OUTPUT_FILES, args.overwrite, "--overwrite")
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    note(lambda: "nothing is written before every run is complete; run the command again")
    return guard(lambda: _run(0.1 if args.quick else 1.0, resolved(args.out)))


def _run(scale: float, out: Path) -> int:
    table = worn_out_table(scale=scale, progress=True)
    write_csv(table, out / "worn_out.csv")
    with pd.option_context("display.width", 200, "display.max_colwidth", 60):
        print(table.drop(columns=["root_strength_MPa"]).to_string(
            index=False, float_format=lambda v: f"{v:.3g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
