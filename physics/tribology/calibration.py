"""Calibrate the asperity wear coefficient once: ``python -m physics.tribology.calibration``.

The lubricated (mixed) Archard law of thesis 2.6, ``k_eff = min(k_a L_a psi, k_dry)``
(:mod:`physics.tribology.wear`), has one coefficient the thesis gives no usable value for: the
Archard coefficient ``k_a`` of the asperity contacts that the oil film leaves unprotected. The
thesis's ``k = 5e-4`` (Table 1) belongs to its printed asperity share of 6.5 % (Table 2), which
nothing in its own formulas yields (``docs/reproduction.md``). ``k_a`` is calibrated here to one
figure, and to nothing else:

    the quasi-static pinion root wear after 1.5e7 pinion cycles, 2.7 um
    (thesis Table 8, the record that drives the mesh stiffness, the dynamics and the datasets;
    baseline of Table 1: 2000 r/min, 300 N m on the gear, sigma 0.5 um, eta0 0.35 Pa s),

which is the default of ``--target-um`` and ``--cycles``; the script reads no thesis file. The
result is the default of :attr:`physics.params.Tribology.wear_coeff` and of
``conf/physics/tribology/thesis.yaml``; ``tests/tribology/test_calibration.py`` checks that this
computation reproduces the stored default. "Root wear" is the wear at the first point of the
pinion's active flank, as everywhere in the package. The thesis's Chapter 2 (Table 2: 0.245 um
average after 1e6 cycles) wears 14 times faster per cycle than its Chapter 3 (Table 10: 0.257 um
average after 1.5e7); we follow Chapter 3, whose record feeds everything downstream.

Method: the root wear ``h(k_a)`` of :func:`physics.tribology.wear.simulate_wear` is nearly
proportional to ``k_a`` (sub-linear once the worn root sheds load to the partner pair), so
``ln h(ln k_a)`` is nearly a straight line of unit slope; the secant method converges in a few
runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import warnings
from collections.abc import Sequence

import numpy as np

from physics.params import Scenario
from physics.tribology.wear import WearResult, simulate_wear

#: thesis Table 8, 1.5e7 cycles: quasi-static pinion root wear [um]
DEFAULT_TARGET_UM = 2.7
#: pinion cycles of that figure (thesis 3.2)
DEFAULT_CYCLES = 1.5e7
#: the thesis's stated wear coefficient (Table 1), for comparison
THESIS_WEAR_COEFF = 5e-4


def wear_run(scn: Scenario, k: float, cycles: float) -> WearResult:
    """Quasi-static wear after ``cycles`` with ``tribology.wear_coeff = k``."""
    tri = dataclasses.replace(scn.tribology, wear_coeff=k)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the gear-body range warning of the stiffness model
        return simulate_wear(dataclasses.replace(scn, tribology=tri), cycles)


def root_wear(scn: Scenario, k: float, cycles: float) -> float:
    """Pinion root wear depth [m] after ``cycles`` with ``tribology.wear_coeff = k``."""
    return float(wear_run(scn, k, cycles).pinion[0])


def total_load_coefficient(res: WearResult) -> tuple[float, float]:
    """The Archard coefficient on the total load that a run implies: the load- and
    sliding-weighted mean of ``k_eff`` over the unworn path, and its largest value."""
    rate = res.first_rate
    slide = np.abs(rate.state.v1 - rate.state.v2) * rate.load
    return (float(np.sum(rate.coefficient * slide) / np.sum(slide)),
            float(rate.coefficient.max()))


def calibrate_wear_coeff(target_um: float = DEFAULT_TARGET_UM, cycles: float = DEFAULT_CYCLES,
                         scn: Scenario | None = None, rtol: float = 1e-6,
                         max_iter: int = 30) -> float:
    """The asperity wear coefficient ``k_a`` that gives ``target_um`` pinion root wear after
    ``cycles`` for ``scn`` (default: the baseline, ``Scenario()``, lubricated regime). Secant
    iteration on ``ln h`` against ``ln k_a`` until ``h`` is within ``rtol`` of the target."""
    scn = Scenario() if scn is None else scn
    if scn.tribology.regime != "mixed":
        raise ValueError("the calibration is of the lubricated law: tribology.regime must be "
                         "'mixed'")
    if not (math.isfinite(target_um) and target_um > 0 and math.isfinite(cycles) and cycles > 0):
        raise ValueError(f"target_um = {target_um!r} and cycles = {cycles!r} must be positive "
                         "and finite")
    goal = math.log(target_um * 1e-6)
    x0 = math.log(scn.tribology.wear_coeff)
    f0 = math.log(root_wear(scn, math.exp(x0), cycles)) - goal
    x1 = x0 - f0  # unit slope: the proportional guess
    for _ in range(max_iter):
        f1 = math.log(root_wear(scn, math.exp(x1), cycles)) - goal
        if abs(f1) < rtol:
            return math.exp(x1)
        slope = (f1 - f0) / (x1 - x0) if x1 != x0 else 1.0
        slope = slope if 0.2 < slope < 5.0 else 1.0  # keep the step sane
        x0, f0, x1 = x1, f1, x1 - f1 / slope
    raise RuntimeError(f"the calibration did not converge in {max_iter} wear runs")


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m physics.tribology.calibration",
        description="Calibrate the asperity wear coefficient (tribology.wear_coeff) of the "
                    "baseline scenario to one pinion root wear figure. Default target: 2.7 um "
                    "after 1.5e7 cycles under the quasi-static load, thesis Table 8.")
    ap.add_argument("--target-um", type=float, default=DEFAULT_TARGET_UM,
                    help="pinion root wear depth to reach [um] (default 2.7: thesis Table 8)")
    ap.add_argument("--cycles", type=float, default=DEFAULT_CYCLES,
                    help="pinion cycles (default 1.5e7, thesis 3.2)")
    args = ap.parse_args(argv)
    try:
        k = calibrate_wear_coeff(args.target_um, args.cycles)
    except ValueError as err:
        ap.error(str(err))
    base = Scenario()
    mean_k, top_k = total_load_coefficient(wear_run(base, k, args.cycles))
    print(f"calibrated wear_coeff k_a = {k:.4g}  (3 significant digits: {float(f'{k:.3g}'):g})")
    print(f"  pinion root wear after {args.cycles:g} cycles: {args.target_um:g} um")
    print(f"  Archard coefficient on the total load: {mean_k:.3g} (load- and sliding-weighted "
          f"mean), at most {top_k:.3g}; dry: {base.tribology.dry_wear_coeff:g}")
    print(f"  stored default (physics.params.Tribology.wear_coeff): {base.tribology.wear_coeff:g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
