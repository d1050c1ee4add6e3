"""Tooth-contact benchmark: ``python bench/bench_contact.py``.

Prints wall times (best of several runs) for
- the rigid gaps of every pair that can touch at 1024 mesh positions (four pairs each), worn
  flanks, compiled and parallel over positions, against the reference: the same gaps by numpy
  broadcasting over positions and points, measured in the same run; their ratio and their
  largest difference;
- one contact-driven wear rate of the public rig's pair (module 3, 18/35, 100 N m), and a
  whole life from new to 1 mm of wear (target: at most 5 minutes on two cores), with its
  blocks;
- the same rate, worn, with each pinion tooth its own flank (18 distinct pairs a pinion
  revolution) and with every tooth of both wheels its own (the hunting period, 630 pairs:
  scaled from the 35 of the gear's teeth each its own), each against the one worn flank's
  rate of the same run;
- the dynamics of that pair worn 0.4 mm with the exact contact (off-path pairs in the kernel)
  beside the path contact, 36 states of 0.5 s at once, and their ratio.
"""

from __future__ import annotations

import dataclasses
import math
import time
import timeit

import numpy as np

from physics.dynamics.model import EXACT_PHASES, build_model, simulate
from physics.gear.stiffness import mesh_stiffness
from physics.gear.tooth_contact import NO_CONTACT, PairGaps, pair_slots
from physics.reproduce.rig import rig_scenario
from physics.tribology.contact_wear import (
    simulate_contact_wear,
    tooth_wear_per_cycle,
    wear_per_cycle,
    whole_flank_grid,
)
from physics.tribology.wear import quasi_static_force


def best_of(fn, repeat: int) -> float:
    """Least wall time of ``repeat`` single calls [s] (timeit's recommended statistic)."""
    return min(timeit.repeat(fn, number=1, repeat=repeat))


def broadcast_gaps(gaps: PairGaps, s: np.ndarray) -> np.ndarray:
    """Reference: the gaps by numpy over (positions, points), both bodies' points."""
    g = gaps.geometry
    phi1, phi2 = gaps.rotations(s)
    out = []
    for (fp, fl), ph_pt, ph_fl, off, rb in (
            (gaps.flanks[::-1], phi2, phi1, g.center_distance, g.rb1),
            (gaps.flanks, phi1, phi2, -g.center_distance, g.rb2)):
        r, a = fp.radius[fp.involute_from:], fp.angle[fp.involute_from:]
        psi = 0.5 * math.pi + a[None, :] + ph_pt[:, None]
        x, y = off + r * np.cos(psi), r * np.sin(psi)
        rho = np.hypot(x, y)
        flank = np.interp(rho, fl.radius, fl.angle, left=np.nan, right=np.nan)
        d = np.mod(np.arctan2(y, x) - 0.5 * math.pi - ph_fl[:, None] - flank + math.pi,
                   2 * math.pi) - math.pi
        out.append(np.where(np.isnan(d), NO_CONTACT, rb * d).min(axis=1))
    return np.minimum(*out)


def main() -> None:
    scn = rig_scenario(100.0)
    ms = mesh_stiffness(scn.gear, scn.material)
    geom = ms.geometry
    grid = whole_flank_grid(ms)
    wear = 50e-6 * np.exp(-0.5 * ((grid - geom.s_start) / 2e-3) ** 2)
    gaps = PairGaps(geom, ms.forms, grid, wear, 0.3 * wear)
    s = pair_slots(geom, geom.s_start + geom.base_pitch * np.arange(1024) / 1024).ravel()
    gaps(s)  # compile
    t_fast = best_of(lambda: gaps(s), 5)
    t_ref = best_of(lambda: broadcast_gaps(gaps, s), 3)
    diff = np.max(np.abs(gaps(s) - broadcast_gaps(gaps, s)))
    print(f"rigid gaps, {s.size} pair positions: compiled {t_fast * 1e3:.1f} ms, numpy "
          f"broadcasting {t_ref * 1e3:.1f} ms: {t_ref / t_fast:.1f} times faster; largest "
          f"difference {diff * 1e9:.2g} nm")

    force = quasi_static_force(scn, geom)
    zero = np.zeros_like(grid)
    t_rate = best_of(lambda: wear_per_cycle(scn, ms, grid, zero, zero, force), 3)
    z1, z2 = scn.gear.z1, scn.gear.z2
    # teeth that differ (each its own depth of the worn profile above: teeth alike would be
    # solved once, MeshSequence.distinct_pairs), against the one flank worn so
    t_worn = best_of(lambda: wear_per_cycle(scn, ms, grid, wear, 0.3 * wear, force), 3)
    pinion = wear[None] * np.linspace(0.5, 1.5, z1)[:, None]
    t_pinion = best_of(lambda: tooth_wear_per_cycle(scn, ms, grid, pinion, 0.3 * wear[None],
                                                    force), 1)
    # a rate's cost grows with its distinct pairs: the hunting period's 630 from the 35 pairs
    # of the pinion's teeth alike and the gear's each its own
    gear = 0.3 * wear[None] * np.linspace(0.5, 1.5, z2)[:, None]
    t_gear = best_of(lambda: tooth_wear_per_cycle(scn, ms, grid, wear[None], gear, force), 1)
    t_hunting = t_gear * math.lcm(z1, z2) / z2
    print(f"tooth by tooth, worn teeth that differ: {t_pinion:.2f} s a rate with each pinion "
          f"tooth its own ({t_pinion / t_worn:.0f} times the one worn flank's "
          f"{t_worn * 1e3:.0f} ms); every tooth of both wheels ({math.lcm(z1, z2)} pairs) "
          f"about {t_hunting:.0f} s ({t_hunting / t_worn:.0f} times)")
    start = time.perf_counter()
    run = simulate_contact_wear(scn, 1e-3)
    t_life = time.perf_counter() - start
    print(f"contact-driven wear rate of the rig's pair: {t_rate * 1e3:.0f} ms; new to 1 mm: "
          f"{t_life:.0f} s in {run.history[0].size - 1} blocks, {run.cycles:.3g} cycles "
          f"(target: 300 s)")

    depths = np.linspace(0.0, 0.4e-3, 36)
    states = [(p[0], g[0]) for p, g, _ in (run.at_depth(d) for d in depths)]  # teeth alike
    times = {}
    for contact in ("path", "exact"):
        sc = dataclasses.replace(scn, dynamics=dataclasses.replace(scn.dynamics,
                                                                   flank_contact=contact))
        models = [build_model(sc, s_grid=grid, wear1=w1, wear2=w2, n_phase=EXACT_PHASES)
                  for w1, w2 in states]
        simulate(models[:1], sc.dynamics, every_phase=False)  # compile
        times[contact] = best_of(lambda sc=sc, models=models: simulate(
            models, sc.dynamics, every_phase=False), 2)
    print(f"dynamics, 36 worn states of 0.5 s: exact contact {times['exact']:.2f} s, path "
          f"contact {times['path']:.2f} s: {times['exact'] / times['path']:.2f} times the "
          f"path's cost")


if __name__ == "__main__":
    main()
