"""Wear-model benchmark: ``python bench/bench_wear.py``.

Prints wall times (best of several runs) for
- the baseline quasi-static 1e6-cycle wear run with the default lubricated model (asperity share
  and film from the mixed-EHL solver's precomputed table, issue 15), and the same run with the
  Masjedi-Khonsari regression and the thesis's k = 5e-4 (``tribology.asperity_model=regression
  tribology.wear_coeff=5e-4``, the model before issue 15), measured in the same process, with
  their ratio (issue 15: within 10 times), and the one-off load of the shipped table;
- all of tables 02-06 as ``python -m physics.reproduce`` computes them (target: <= 10 s),
- the reference: the same contact-state and wear-rate evaluation done point by point in a Python
  loop (one mesh position per call), measured in the same run, and the speed-up ratio.
"""

from __future__ import annotations

import dataclasses
import tempfile
import timeit

import numpy as np
from omegaconf import OmegaConf

from physics.params import Scenario, Tribology
from physics.reproduce.thesis import ReproduceConfig, reproduce
from physics.tribology import asperity_table
from physics.tribology.wear import simulate_wear, wear_rate


def best_of(fn, repeat: int) -> float:
    """Least wall time of ``repeat`` single calls [s] (timeit's recommended statistic)."""
    return min(timeit.repeat(fn, number=1, repeat=repeat))


def point_by_point(scn: Scenario) -> np.ndarray:
    """Reference: the wear rate at each mesh position from its own call (no vectorisation)."""
    res = simulate_wear(scn, 0.0)
    geom, s = res.geometry, res.s
    zero = np.zeros(1)
    force = np.full(1, scn.operating.torque_Nm / geom.rb2)
    k = np.full(1, 4.0e8)

    def stiffness(x):
        return np.broadcast_to(k, np.shape(x))

    return np.array([wear_rate(scn, geom, s[i:i + 1], zero, zero, force, stiffness).pinion[0]
                     for i in range(len(s))])


def main() -> None:
    scn = Scenario()
    t_load = best_of(lambda: (asperity_table.shipped_table.cache_clear(),
                              asperity_table.shipped_table()), 3)
    t_run = best_of(lambda: simulate_wear(scn, 1e6), 7)
    # the model before issue 15: the regression with the thesis's k (one profile block)
    regression = dataclasses.replace(
        scn, tribology=Tribology(asperity_model="regression", wear_coeff=5e-4))
    t_reg = best_of(lambda: simulate_wear(regression, 1e6), 7)
    blocks = simulate_wear(scn, 1e6).blocks, simulate_wear(regression, 1e6).blocks
    vec = simulate_wear(scn, 0.0)
    t_vec = best_of(lambda: simulate_wear(scn, 0.0), 5)
    t_ref = best_of(lambda: point_by_point(scn), 2)
    with tempfile.TemporaryDirectory() as tmp:
        full = OmegaConf.structured(ReproduceConfig(out_dir=tmp))  # the default config
        t_tables = best_of(lambda: reproduce(full), 2)
    print(f"grid points                         : {scn.solver.n_points}")
    print(f"baseline 1e6-cycle wear run, solver : {t_run * 1e3:8.1f} ms   ({blocks[0]} profile "
          "update blocks)")
    print(f"  regression, k = 5e-4 (before)     : {t_reg * 1e3:8.1f} ms   ({blocks[1]} blocks)")
    print(f"  ratio solver / regression         : {t_run / t_reg:8.2f}      (target <= 10)")
    print(f"load of the shipped solver table    : {t_load * 1e3:8.1f} ms   (once per process)")
    print(f"tables 02-06 + wear profile         : {t_tables:8.2f} s    (target <= 10 s)")
    print(f"one wear-rate pass, vectorised      : {t_vec * 1e3:8.2f} ms")
    print(f"one wear-rate pass, point by point  : {t_ref * 1e3:8.1f} ms   (reference)")
    print(f"speed-up of the vectorised pass     : {t_ref / t_vec:8.0f} x")
    same = np.allclose(point_by_point(dataclasses.replace(scn)), vec.last_rate.pinion, rtol=1e-6)
    print(f"reference agrees with vectorised    : {same}")


if __name__ == "__main__":
    main()
