"""Wear followed from new to severe: ``python -m physics.reproduce.severe``.

Runs the wear model far beyond the thesis's 12 um of root wear, with the contact pressure of the
worn flanks solved from the wear gap (:mod:`physics.tribology.worn_contact`), and prints one row
per run: the deepest pinion and gear wear, the largest contact pressure and whether the run stayed
in the model's scope or left it at the shakedown limit (and where). The runs: the thesis's pair
and a module-3 pair under the dry law to several hundred micrometres, quasi-static and with the
dynamic load fed back (thesis 3.5), and the lubricated law at half the viscosity and at a
roughness of 0.8 um. ``--quick`` shortens every run tenfold.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
import warnings
from collections.abc import Callable, Sequence

from physics.dynamics.evolution import simulate_dynamic_wear
from physics.params import OutOfScope, Scenario
from physics.tribology.wear import WearResult, simulate_wear


def _with(scn: Scenario, part: str, **kw) -> Scenario:
    return dataclasses.replace(scn, **{part: dataclasses.replace(getattr(scn, part), **kw)})


def runs() -> list[tuple[str, Scenario, float, Callable[..., WearResult]]]:
    """(label, scenario, pinion cycles, wear integrator) of each run."""
    base = Scenario()
    dry = _with(base, "tribology", regime="dry")
    module3 = _with(dry, "gear", module_mm=3.0)
    return [
        ("thesis pair, dry, quasi-static", dry, 6e8, simulate_wear),
        ("module 3, dry, quasi-static", module3, 6e8, simulate_wear),
        ("thesis pair, dry, dynamic", dry, 3e8, simulate_dynamic_wear),
        ("thesis pair, half viscosity, dynamic", _with(base, "lubricant", eta0_Pa_s=0.175),
         1.5e7, simulate_dynamic_wear),
        ("thesis pair, sigma 0.8 um, dynamic", _with(base, "tribology", sigma_um=0.8), 1.5e7,
         simulate_dynamic_wear),
    ]


def run_one(scn: Scenario, cycles: float, integrate: Callable[..., WearResult]) -> dict:
    """One run's row: deepest wear, largest pressure, outcome."""
    start = time.perf_counter()
    try:
        res = integrate(scn, cycles)
    except OutOfScope as err:
        return {"cycles": cycles, "outcome": str(err), "seconds": time.perf_counter() - start}
    c = res.last_rate.contact
    return {"cycles": cycles, "pinion_max_um": res.pinion.max() * 1e6,
            "gear_max_um": res.gear.max() * 1e6, "p_max_GPa": c.p_max.max() / 1e9,
            "outcome": "in scope", "seconds": time.perf_counter() - start}


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m physics.reproduce.severe",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="every run ten times shorter")
    args = ap.parse_args(argv)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the gear-body range warning of the stiffness model
        for label, scn, cycles, integrate in runs():
            row = run_one(scn, cycles / 10 if args.quick else cycles, integrate)
            if "p_max_GPa" in row:
                print(f"{label:40s} {row['cycles']:8.2g} cycles: pinion {row['pinion_max_um']:7.1f}"
                      f" um, gear {row['gear_max_um']:7.1f} um, p_max {row['p_max_GPa']:.2f} GPa,"
                      f" in scope ({row['seconds']:.0f} s)", flush=True)
            else:
                print(f"{label:40s} {row['cycles']:8.2g} cycles: {row['outcome']} "
                      f"({row['seconds']:.0f} s)", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
