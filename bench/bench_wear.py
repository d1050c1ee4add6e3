"""Wear-model benchmark: ``python bench/bench_wear.py``.

Prints wall times (best of several runs) for
- the baseline quasi-static 1e6-cycle wear run (target: <= 190 ms on a 2-core machine) and the
  1.5e7-cycle run of Table 8, with their profile-update blocks;
- all of tables 02-06 as ``python -m physics.reproduce`` computes them;
- the worn contact of the 1.5e7-cycle flanks solved for every mesh position at once (batched
  conjugate gradient), against the reference: the same solve one position per call, in a
  Python loop, measured in the same run; their ratio and their largest difference;
- the contact's deflection of 400 rows of cell pressures (64 and 512 cells) by its influence
  matrix, against the reference: the same deflection by FFT convolution (scipy.signal), in the
  same run; their ratio and largest difference.
"""

from __future__ import annotations

import tempfile
import timeit

import numpy as np
from omegaconf import OmegaConf
from scipy.signal import fftconvolve

from physics.gear import contact
from physics.params import Scenario
from physics.reproduce.thesis import ReproduceConfig, reproduce
from physics.tribology.wear import flank_grid, simulate_wear
from physics.tribology.worn_contact import influence_matrix, solve_worn_contact


def best_of(fn, repeat: int) -> float:
    """Least wall time of ``repeat`` single calls [s] (timeit's recommended statistic)."""
    return min(timeit.repeat(fn, number=1, repeat=repeat))


def worn_contact_inputs(scn: Scenario) -> dict:
    """The solve's inputs on the flanks worn by 1.5e7 quasi-static cycles (Table 8)."""
    res = simulate_wear(scn, 1.5e7)
    geom, s = res.geometry, res.s
    flank = flank_grid(scn, geom, s)
    f1, f2 = np.zeros_like(flank.grid), np.zeros_like(flank.grid)
    f1[flank.path], f2[flank.path] = res.pinion, res.gear
    R1, R2 = geom.curvature_radii(s)
    return {"s": s, "load_per_width": res.last_rate.load / scn.gear.face_width, "R1": R1,
            "R2": R2, "rb1": geom.rb1, "rb2": geom.rb2,
            "e_star": contact.reduced_modulus(scn.material, scn.material), "flank": flank.grid,
            "wear1": f1, "wear2": f2, "level": flank.level}


def one_by_one(args: dict) -> np.ndarray:
    """Reference: each mesh position's contact from its own call."""
    per = ("s", "load_per_width", "R1", "R2")
    return np.concatenate([
        solve_worn_contact(**{**args, **{k: args[k][i:i + 1] for k in per}}).p_max
        for i in range(args["s"].size)])


def deflections(cells: int) -> tuple[float, float, float]:
    """Wall times [s] of the deflection of 400 rows of random cell pressures on ``cells``
    cells of a 6-half-width window by the influence matrix and, as the reference, by FFT
    convolution with the matrix's first row; and their largest relative difference."""
    dX = 6.0 / cells
    K = influence_matrix(cells, dX)
    kernel = np.concatenate([K[0, :0:-1], K[0]])  # k(|i - j|) for i - j = -(n-1) .. n-1
    P = np.random.default_rng(0).random((400, cells))

    def convolved() -> np.ndarray:
        return fftconvolve(P, kernel[None, :], axes=1)[:, cells - 1: 2 * cells - 1]

    t_matrix = best_of(lambda: P @ K, 20)
    t_fft = best_of(convolved, 20)
    diff = float(np.max(np.abs(P @ K - convolved())) / np.max(np.abs(convolved())))
    return t_matrix, t_fft, diff


def main() -> None:
    scn = Scenario()
    t_run = best_of(lambda: simulate_wear(scn, 1e6), 5)
    t_long = best_of(lambda: simulate_wear(scn, 1.5e7), 2)
    blocks = simulate_wear(scn, 1e6).blocks, simulate_wear(scn, 1.5e7).blocks
    with tempfile.TemporaryDirectory() as tmp:
        full = OmegaConf.structured(ReproduceConfig(out_dir=tmp))  # the default config
        t_tables = best_of(lambda: reproduce(full), 1)
    args = worn_contact_inputs(scn)
    batched = solve_worn_contact(**args)
    t_batch = best_of(lambda: solve_worn_contact(**args), 5)
    t_ref = best_of(lambda: one_by_one(args), 1)
    # the batch keeps a Hertz band for its lightly loaded pairs (a share of the batch's largest
    # load, worn_contact.LIGHT), which a call of one position never has: compare the others
    heavy = batched.solved
    diff = np.max(np.abs(one_by_one(args) - batched.p_max)[heavy] / batched.p_max.max())
    print(f"grid points                          : {scn.solver.n_points}")
    print(f"baseline 1e6-cycle wear run          : {t_run * 1e3:8.1f} ms   ({blocks[0]} blocks; "
          "target <= 190 ms)")
    print(f"baseline 1.5e7-cycle run (Table 8)   : {t_long:8.2f} s    ({blocks[1]} blocks)")
    print(f"tables 02-06 + wear profile          : {t_tables:8.2f} s")
    print(f"worn contact, all positions at once  : {t_batch * 1e3:8.1f} ms   "
          f"({int(batched.solved.sum())} of {batched.solved.size} solved numerically)")
    print(f"worn contact, one position per call  : {t_ref * 1e3:8.1f} ms   (reference)")
    print(f"speed-up of the batched solve        : {t_ref / t_batch:8.1f} x")
    print(f"largest difference of the peaks      : {diff:.1e} of the largest peak "
          "(numerically solved positions)")
    for cells in (64, 512):
        t_matrix, t_fft, diff = deflections(cells)
        print(f"deflection, 400 rows x {cells:3d} cells     : {t_matrix * 1e3:8.3f} ms   "
              f"(FFT convolution {t_fft * 1e3:.3f} ms: {t_fft / t_matrix:.1f} x; largest "
              f"difference {diff:.1e})")


if __name__ == "__main__":
    main()
