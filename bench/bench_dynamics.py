"""Dynamics benchmark: ``python bench/bench_dynamics.py``.

Prints:
- the compiled RK4 integrator's simulated seconds per wall second on one core (target:
  >= 10), and on all cores for a batch, beside a ``scipy.integrate.solve_ivp`` (DOP853)
  integration of the same equations in their two-inertia form, measured in the same run;
- one case's dynamically coupled wear evolution to 1.5e7 cycles (target: <= 20 s) and all five
  cases of Table 11 (target: <= 60 s);
- the first simulation of a fresh process with an empty numba cache (what every fresh install,
  test worker and dataset worker pays once: the kernels' compilation) beside the same in a
  second process that loads the cache the first wrote;
- the thesis pair with every tooth of both wheels its own (the 54 meshes of its hunting period,
  each with its own exact-contact tables; :func:`physics.dynamics.teeth.sequence_model`) over
  three hunting periods (9 pinion revolutions: whole revolutions of both shafts), its building
  and its simulation, beside the one-period exact model over the same record.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import tempfile
import time
import warnings

import numba
import numpy as np

from physics.dynamics.evolution import root_wear_evolution
from physics.dynamics.model import (
    anti_aliased,
    anti_aliasing_filter,
    build_model,
    simulate,
    simulate_two_dof,
    time_step,
)
from physics.dynamics.teeth import sequence_model
from physics.gear.stiffness import SainsotRangeWarning, mesh_stiffness
from physics.params import Scenario, scenario_from_config
from physics.tribology.contact_wear import whole_flank_grid

warnings.simplefilter("ignore", SainsotRangeWarning)


#: a fresh process's first simulation, timed inside it (the imports before the clock starts)
FIRST_RUN = """
import time
from physics.dynamics.model import build_model, simulate
from physics.params import Scenario
scn = Scenario()
model = build_model(scn)
t = time.perf_counter()
simulate(model, scn.dynamics)
print(time.perf_counter() - t)
"""


def first_simulation_s(cache: str) -> float:
    """Seconds of a fresh process's first simulation with the numba cache folder ``cache``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    run = subprocess.run([sys.executable, "-c", FIRST_RUN], env=env, check=True,
                         capture_output=True, text=True)
    return float(run.stdout.split()[-1])


def main() -> None:
    with tempfile.TemporaryDirectory() as cache:
        cold = first_simulation_s(cache)
        warm = first_simulation_s(cache)

    scn = Scenario()
    model = build_model(scn)
    long_run = dataclasses.replace(scn.dynamics, duration_s=10.0, transient_s=0.0)
    simulate(model, dataclasses.replace(long_run, duration_s=0.01))  # compile / load the cache
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    t = time.perf_counter()
    resp = simulate(model, long_run)
    one_core = 10.0 / (time.perf_counter() - t)
    numba.set_num_threads(threads)
    t = time.perf_counter()
    simulate([model] * threads, long_run)
    batch = 10.0 * threads / (time.perf_counter() - t)

    short = dataclasses.replace(scn.dynamics, duration_s=0.005, transient_s=0.0)
    ref_resp = simulate(model, short)
    # the reference at every integration step, through the records' anti-aliasing filter (the
    # record is filtered, not point-sampled: tests/dynamics/test_dynamics.py)
    dt, n_sub = time_step([model], short)
    half = (len(anti_aliasing_filter(n_sub)) - 1) // (2 * n_sub)
    n_out = ref_resp.dte.shape[1]
    steps = np.arange(n_sub - half * n_sub, (n_out + half) * n_sub + 1)
    t = time.perf_counter()
    x_ref, _ = simulate_two_dof(model, ref_resp.time[0] + (steps - n_sub) * dt)
    ref_rate = ref_resp.time[-1] / (time.perf_counter() - t)
    x_ref = anti_aliased(x_ref, n_sub, n_out)
    diff = np.max(np.abs(x_ref - ref_resp.dte[0])) / np.ptp(ref_resp.dte[0])

    cycles = np.linspace(0, 1.5e7, 31)
    t = time.perf_counter()
    root_wear_evolution(scenario_from_config({"case": 3}), cycles)
    one_case = time.perf_counter() - t
    t = time.perf_counter()
    for case in range(1, 6):
        root_wear_evolution(scenario_from_config({"case": case}), cycles)
    five = time.perf_counter() - t

    exact = dataclasses.replace(scn, dynamics=dataclasses.replace(
        scn.dynamics, flank_contact="exact", duration_s=9 * 60.0 / scn.operating.n1_rpm))
    ms = mesh_stiffness(scn.gear, scn.material)
    grid = whole_flank_grid(ms)
    rng = np.random.default_rng(0)  # teeth worn 0-2 um near the pinion root and the gear tip
    shape = np.exp(-0.5 * ((grid - ms.geometry.s_start) / 1e-3) ** 2)
    w1 = rng.uniform(0, 2e-6, (scn.gear.z1, 1)) * shape
    w2 = rng.uniform(0, 2e-6, (scn.gear.z2, 1)) * shape[::-1]
    t = time.perf_counter()
    hunting = sequence_model(exact, ms, grid, w1, w2)
    built = time.perf_counter() - t
    one = sequence_model(exact, ms, grid, w1[:1], w2[:1])  # one flank each, tiled
    simulate([one], exact.dynamics, every_phase=False)  # compile
    t = time.perf_counter()
    simulate([hunting], exact.dynamics, every_phase=False)
    t_hunting = time.perf_counter() - t
    t = time.perf_counter()
    simulate([one], exact.dynamics, every_phase=False)
    t_one = time.perf_counter() - t

    print(f"RK4 step {resp.time_step * 1e6:.3f} us (omega_max dt = "
          f"{resp.time_step * model.omega_max:.3f})")
    print(f"compiled RK4, one core          : {one_core:9.1f} simulated s / wall s (target >= 10)")
    print(f"compiled RK4, batch of {threads}, {threads} cores: {batch:9.1f} simulated s / wall s")
    print(f"solve_ivp DOP853, two-inertia   : {ref_rate:9.4f} simulated s / wall s (reference)")
    print(f"ratio compiled / solve_ivp      : {one_core / ref_rate:9.0f} x")
    print(f"largest DTE difference           : {diff * 100:9.3f} % of its peak-to-peak")
    print(f"case 3 coupled evolution to 1.5e7: {one_case:9.2f} s (target <= 20 s)")
    print(f"all five cases                   : {five:9.2f} s (target <= 60 s)")
    print(f"first simulation, empty cache    : {cold:9.2f} s (the kernels' compilation)")
    print(f"first simulation, cache loaded   : {warm:9.2f} s (reference; {cold / warm:.0f} x)")
    print(f"hunting period, 54 meshes' tables: {built:9.2f} s to build; 9 revolutions "
          f"({exact.dynamics.duration_s:.2f} s) in {t_hunting:.2f} s, against {t_one:.2f} s with "
          f"one flank each ({t_hunting / t_one:.2f} x)")


if __name__ == "__main__":
    main()
