"""Mixed-EHL solver benchmark: ``python bench/bench_mixed_ehl.py``.

Prints:
- wall time of one solve at the thesis pitch point (w = 394 kN/m, R = 3.694 mm, u_e = 1.289
  m/s, sigma = 0.5 um; target < 1 s, typically 0.1 s) for n = 256, 512 and 1024, with the
  Newton iterations, films, film ratio and asperity share, beside the Masjedi-Khonsari
  regression's share;
- the time of 10 000 look-ups in the shipped solver table that the wear model reads
  (:mod:`physics.tribology.asperity_table`), and its share at the pitch point.
"""

from __future__ import annotations

import math
import time

import numpy as np

from physics.tribology import asperity_table, lubrication
from physics.tribology.mixed_ehl import solve_line_contact

E_PRIME = 206e9 / (1 - 0.3**2)
LUB = {"eta0": 0.35, "alpha": 2.5e-8, "beta0": 0.03, "rho0": 870.0, "t0": 315.0}


def pitch_point() -> tuple[float, float, float]:
    a = math.radians(20.0)
    rho1, rho2 = 0.018 * math.sin(a), 0.027 * math.sin(a)
    w = 300.0 / (0.027 * math.cos(a)) / 0.030
    return w, rho1 * rho2 / (rho1 + rho2), 2000.0 * math.pi / 30 * rho1


def best_of(fn, repeat: int = 3) -> tuple[float, object]:
    best, out = math.inf, None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def main() -> None:
    w, R, u_e = pitch_point()
    g = lubrication.dimensionless_groups(w, R, u_e, LUB["eta0"], LUB["alpha"], E_PRIME, 7e9,
                                         0.5e-6)
    mk = float(lubrication.asperity_load_ratio_pct(g["W"], g["U"], g["G"], g["V"],
                                                   g["sigma_bar"]))
    print(f"thesis pitch point: w = {w / 1e3:.1f} kN/m, R = {R * 1e3:.3f} mm, "
          f"u_e = {u_e:.3f} m/s, W = {float(g['W']):.3e}, U = {float(g['U']):.3e}, "
          f"G = {float(g['G']):.0f}")
    for n in (256, 512, 1024):
        dt, sol = best_of(lambda n=n: solve_line_contact(w, R, u_e, E_PRIME, *LUB.values(),
                                                         0.5e-6, n=n))
        print(f"  n = {n:4d}: {dt * 1e3:7.1f} ms, {sol.iterations} Newton steps (finest grid), "
              f"converged {sol.converged}, p_H = {sol.hertz_pressure / 1e9:.3f} GPa, "
              f"h_min = {sol.h_min * 1e6:.4f} um, h_c = {sol.h_central * 1e6:.4f} um, "
              f"lambda = {sol.film_ratio_min:.3f}, asperity share = "
              f"{100 * sol.asperity_load_share:.5f} % (Masjedi-Khonsari {mk:.4f} %)")
    dt, sol = best_of(lambda: solve_line_contact(w, R, u_e, E_PRIME, *LUB.values(), 0.0))
    print(f"  smooth, n = 512: {dt * 1e3:.1f} ms, h_min = {sol.h_min * 1e6:.4f} um, "
          f"h_c = {sol.h_central * 1e6:.4f} um")

    table = asperity_table.shipped_table()
    rng = np.random.default_rng(0)
    W = rng.uniform(1e-4, 6e-4, 10_000)
    U = np.exp(rng.uniform(math.log(1e-11), math.log(1e-9), 10_000))
    sb = np.full_like(W, g["sigma_bar"])
    dt, _ = best_of(lambda: asperity_table.lookup(W, U, sb, LUB["alpha"], LUB["eta0"], E_PRIME))
    at = asperity_table.lookup(np.array([g["W"]]), np.array([g["U"]]),
                               np.array([g["sigma_bar"]]), LUB["alpha"], LUB["eta0"], E_PRIME)
    print(f"10 000 look-ups in the shipped table ({table.share.size} nodes): {dt * 1e3:.2f} ms; "
          f"at the pitch point it gives {100 * float(at.share[0]):.5f} %")


if __name__ == "__main__":
    main()
