"""Calibrate the lubricated wear coefficient once: ``python -m physics.tribology.calibration``.

The lubricated (mixed) Archard law ``dh = k psi L_a p_mean L / H`` of thesis 2.6, with the
asperity share ``L_a`` of the numerical mixed-EHL solver and the oil-film deficiency
coefficient ``psi``, gives a wear three orders of magnitude below the thesis's figures when k
takes the thesis's value 5e-4 (Table 1). Its single wear coefficient is calibrated here to one
headline figure, and to nothing else:

    the baseline average pinion wear depth after 1e6 pinion cycles, 0.245 um
    (thesis Table 2, row n1 = 2000 r/min; the baseline of Table 1: 300 N m on the gear,
    sigma 0.5 um, eta0 0.35 Pa s),

which is the default of ``--target-um`` and ``--cycles``; the script reads no thesis file. The
result is the default of :attr:`physics.params.Tribology.wear_coeff` and of
``conf/physics/tribology/thesis.yaml``; ``tests/tribology/test_calibration.py`` checks that
this computation reproduces the stored default.

Method: the average wear ``h(k)`` of :func:`physics.tribology.wear.simulate_wear` is
proportional to k while the run stays within one profile update and slightly sub-linear beyond
(the worn profile redistributes the load), so ``ln h(ln k)`` is nearly a straight line of unit
slope; the secant method on it converges in two or three runs. "Average wear" is
:meth:`physics.tribology.wear.WearResult.mean_depth` of the pinion (the definition used for
the reproduced tables, ``docs/reproduction.md``).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import warnings
from collections.abc import Sequence

from physics.params import Scenario
from physics.tribology.wear import simulate_wear

#: thesis Table 2, n1 = 2000 r/min (the Table 1 baseline): average pinion wear [um]
DEFAULT_TARGET_UM = 0.245
#: pinion cycles of that figure (thesis 2.7)
DEFAULT_CYCLES = 1e6
#: the thesis's stated wear coefficient (Table 1), for comparison
THESIS_WEAR_COEFF = 5e-4


def mean_wear(scn: Scenario, k: float, cycles: float) -> float:
    """Average pinion wear depth [m] after ``cycles`` with ``tribology.wear_coeff = k``."""
    tri = dataclasses.replace(scn.tribology, wear_coeff=k)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the gear-body range warning of the stiffness model
        return simulate_wear(dataclasses.replace(scn, tribology=tri), cycles).mean_depth()


def calibrate_wear_coeff(target_um: float = DEFAULT_TARGET_UM, cycles: float = DEFAULT_CYCLES,
                         scn: Scenario | None = None, rtol: float = 1e-6,
                         max_iter: int = 30) -> float:
    """The wear coefficient k that gives ``target_um`` average pinion wear after ``cycles``
    for ``scn`` (default: the baseline, ``Scenario()``, lubricated regime). Secant iteration
    on ``ln h`` against ``ln k`` until ``h`` is within ``rtol`` of the target."""
    scn = Scenario() if scn is None else scn
    if scn.tribology.regime != "mixed":
        raise ValueError("the calibration is of the lubricated law: tribology.regime must be "
                         "'mixed'")
    if not (math.isfinite(target_um) and target_um > 0 and math.isfinite(cycles) and cycles > 0):
        raise ValueError(f"target_um = {target_um!r} and cycles = {cycles!r} must be positive "
                         "and finite")
    goal = math.log(target_um * 1e-6)
    x0 = math.log(scn.tribology.wear_coeff)
    f0 = math.log(mean_wear(scn, math.exp(x0), cycles)) - goal
    x1 = x0 - f0  # unit slope: the proportional guess
    for _ in range(max_iter):
        f1 = math.log(mean_wear(scn, math.exp(x1), cycles)) - goal
        if abs(f1) < rtol:
            return math.exp(x1)
        slope = (f1 - f0) / (x1 - x0) if x1 != x0 else 1.0
        slope = slope if 0.2 < slope < 5.0 else 1.0  # keep the step sane
        x0, f0, x1 = x1, f1, x1 - f1 / slope
    raise RuntimeError(f"the calibration did not converge in {max_iter} wear runs")


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m physics.tribology.calibration",
        description="Calibrate the lubricated wear coefficient (tribology.wear_coeff) of the "
                    "baseline scenario to one average pinion wear figure. Default target: "
                    "0.245 um after 1e6 cycles, the baseline row (n1 = 2000 r/min) of thesis "
                    "Table 2.")
    ap.add_argument("--target-um", type=float, default=DEFAULT_TARGET_UM,
                    help="average pinion wear depth to reach [um] (default 0.245: thesis "
                         "Table 2, 2000 r/min)")
    ap.add_argument("--cycles", type=float, default=DEFAULT_CYCLES,
                    help="pinion cycles (default 1e6, thesis 2.7)")
    args = ap.parse_args(argv)
    try:
        k = calibrate_wear_coeff(args.target_um, args.cycles)
    except ValueError as err:
        ap.error(str(err))
    base = Scenario()
    thesis = mean_wear(base, THESIS_WEAR_COEFF, args.cycles)
    print(f"calibrated wear_coeff k = {k:.4g}  (3 significant digits: {float(f'{k:.3g}'):g})")
    print(f"  average pinion wear after {args.cycles:g} cycles: {args.target_um:g} um")
    print(f"  the thesis's k = {THESIS_WEAR_COEFF:g} gives {thesis * 1e6:.4g} um "
          f"(k ratio {k / THESIS_WEAR_COEFF:.3g})")
    print(f"  stored default (physics.params.Tribology.wear_coeff): {base.tribology.wear_coeff:g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
