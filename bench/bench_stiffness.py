"""Mesh-stiffness benchmark: ``python bench/bench_stiffness.py``.

Prints, best of several runs:
- the 200-position mesh stiffness of a worn pair (target: <= 5 ms), healthy and worn;
- the reference: the same energy integrals by ``scipy.integrate.quad`` point by point (the way
  ROSS's gear element does it), measured in the same run, its agreement and the speed-up;
- the FE verification of Table 7 at the converged mesh (target: <= 60 s).
"""

from __future__ import annotations

import math
import time
import timeit
import warnings

import numpy as np
from scipy.integrate import IntegrationWarning, quad

from physics.gear.load_sharing import pair_loads
from physics.gear.stiffness import MeshStiffness, SainsotRangeWarning
from physics.gear.tooth_fem import fe_pair_stiffness
from physics.params import GearPair, Material, Scenario
from physics.tribology.wear import quasi_static_force

warnings.simplefilter("ignore", SainsotRangeWarning)
warnings.simplefilter("ignore", IntegrationWarning)  # the reference quad on a polyline


def best_of(fn, repeat: int) -> float:
    """Least wall time of ``repeat`` single calls [s] (timeit's recommended statistic)."""
    return min(timeit.repeat(fn, number=1, repeat=repeat))


def quad_tooth_compliance(ms: MeshStiffness, wheel: int, radius: float) -> float:
    """Reference: bending + shear + axial of one healthy tooth by adaptive quadrature."""
    form = ms.forms[wheel - 1]
    a_r = math.acos(form.rb / radius)
    theta = math.pi / (2 * form.z) + (math.tan(ms.gear.alpha) - ms.gear.alpha) - (
        math.tan(a_r) - a_r)
    a1 = a_r - theta
    y_l, x_l = radius * math.cos(theta), radius * math.sin(theta)
    B = ms.gear.face_width

    def half(y):
        return float(np.interp(y, form.y, form.x))

    def bend(y):
        w = 2 * half(y)
        return (math.cos(a1) * (y_l - y) - math.sin(a1) * x_l) ** 2 / (ms.E * w**3 * B / 12)

    def area(y):
        return 1.0 / (2 * half(y) * B)

    y0 = form.y[0]
    cb = quad(bend, y0, y_l, limit=200)[0]
    ca = quad(area, y0, y_l, limit=200)[0]
    return cb + (1.2 * math.cos(a1) ** 2 / ms.G + math.sin(a1) ** 2 / ms.E) * ca


def main() -> None:
    gear, mat = GearPair(), Material()
    ms = MeshStiffness(gear, mat)
    g = ms.geometry
    s = g.grid(401)
    wear1 = 2e-6 * (np.abs(s) / -g.s_start) ** 2
    t_healthy = best_of(lambda: ms.mesh_cycle(200), 20)
    t_worn = best_of(lambda: ms.mesh_cycle(200, s, wear1, 0.4 * wear1), 20)

    roll = g.s_start + g.base_pitch * np.arange(200) / 200
    r1, _ = g.flank_radii(roll)
    fast = ms.tooth(1, r1)
    fast_tooth = fast.bending + fast.shear + fast.axial
    t_quad = best_of(lambda: [quad_tooth_compliance(ms, 1, r) for r in r1], 1)
    ref = np.array([quad_tooth_compliance(ms, 1, r) for r in r1])
    worst = np.max(np.abs(fast_tooth / ref - 1))
    t_cum = best_of(lambda: ms.tooth(1, r1), 20)

    d = (g.contact_ratio - 1) * g.base_pitch
    pos = np.array([g.s_start + 0.25 * d, g.s_start + 0.25 * d + g.base_pitch,
                    0.5 * sum(g.single_zone), g.s_start + 0.75 * d,
                    g.s_start + 0.75 * d + g.base_pitch])
    load = pair_loads(g, pos, quasi_static_force(Scenario(), g), np.zeros_like,
                      ms.pair_function())
    t0 = time.perf_counter()
    fe = fe_pair_stiffness(gear, mat, g, pos, load, refine=4.0)
    t_fe = time.perf_counter() - t0

    print(f"mesh stiffness, 200 positions, healthy : {t_healthy * 1e3:7.2f} ms  (target <= 5 ms)")
    print(f"mesh stiffness, 200 positions, worn    : {t_worn * 1e3:7.2f} ms  (target <= 5 ms)")
    print(f"one tooth, 200 loads, cumulative       : {t_cum * 1e3:7.2f} ms")
    print(f"one tooth, 200 loads, quad per point   : {t_quad * 1e3:7.1f} ms  (reference)")
    print(f"speed-up over the reference            : {t_quad / t_cum:7.0f} x")
    print(f"largest difference from the reference  : {worst * 100:7.3f} %")
    print(f"FE, Table 7 positions, refine 4        : {t_fe:7.2f} s   (target <= 60 s; "
          f"{fe.elements[0]} + {fe.elements[1]} P2 triangles)")


if __name__ == "__main__":
    main()
