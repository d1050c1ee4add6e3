"""The compiled kernels, compiled once into numba's cache before a parallel test run's workers
start (``pytest_sessionstart`` in ``tests/conftest.py``).

On a fresh clone the cache is empty: each pytest-xdist worker, and each app a test starts
before a worker has written the cache, would compile the same kernels (each process about
20 s: the groups below take 9.8 and 10.6 s alone). Here two processes compile them, one group
each, through the code paths the package calls them by (so the signatures are the ones the
tests and apps use); the workers and apps then load them. ``python -m tests.kernel_cache
GROUP`` compiles one group.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: the kernels the groups compile (each with the kernels it calls), by module
KERNELS = (("physics/dynamics/kernels.py", "integrate"),
           ("physics/dynamics/kernels.py", "decimate"),
           ("physics/testbeds/independent_simulator.py", "_newmark"),
           ("physics/gear/tooth_contact.py", "_least_gap"),
           ("physics/tribology/worn_contact.py", "_polonsky_keer"),
           ("physics/tribology/worn_contact.py", "_sweep"))


def _dynamics() -> None:
    """The torsional model's integrator and decimation; the independent simulator's."""
    import dataclasses

    from physics.dynamics.model import build_model, simulate
    from physics.params import Scenario
    from physics.testbeds.independent_simulator import simulate_record

    scn = Scenario()
    dyn = dataclasses.replace(scn.dynamics, duration_s=0.01, transient_s=0.005, phase_bins=16)
    assert simulate(build_model(scn), dyn).dte.size  # .dte: the decimation
    simulate_record(duration_s=0.05)


def _contact() -> None:
    """The worn flanks' least gap and the worn band's contact (Polonsky-Keer, the sweep)."""
    import numpy as np

    from physics.gear.contact import reduced_modulus
    from physics.gear.stiffness import MeshStiffness
    from physics.gear.tooth_contact import PairGaps
    from physics.params import Scenario
    from physics.tribology import worn_contact as wc

    scn = Scenario()
    ms = MeshStiffness(scn.gear, scn.material)
    geom = ms.geometry
    PairGaps(geom, ms.forms)(np.linspace(geom.s_start, geom.s_end, 5))
    s = geom.grid(41)
    r1, r2 = geom.curvature_radii(s)
    grid = np.linspace(s[0] - 0.5e-3, s[-1] + 0.5e-3, 61)
    depth = np.clip(-grid / abs(s[0]), 0.0, None) ** 2 * 30e-6
    band = wc.solve_worn_contact(s, np.full_like(s, 2e5), r1, r2, geom.rb1, geom.rb2,
                                 reduced_modulus(scn.material, scn.material), grid, depth,
                                 depth, 20e-6)
    band.sweep(s, grid, r1 / geom.rb1, np.ones_like(s))


#: the groups, each compiled in a process of its own
GROUPS = {"dynamics": _dynamics, "contact": _contact}


def stale() -> bool:
    """Whether numba's cache beside the sources (its default place; always where
    ``NUMBA_CACHE_DIR`` moves it) lacks one of :data:`KERNELS` or holds it older than its
    module."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return True
    for path, name in KERNELS:
        source = ROOT / path
        index = list((source.parent / "__pycache__").glob(f"{source.stem}.{name}-*.nbi"))
        if not index or index[0].stat().st_mtime < source.stat().st_mtime:
            return True
    return False


def compile_all() -> str:
    """Both groups at once, each in a process of its own (one numba thread each); what a
    group that failed printed (its kernels are then compiled where the tests call them)."""
    env = {**os.environ, "NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    procs = [subprocess.Popen([sys.executable, "-m", "tests.kernel_cache", g], cwd=ROOT, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
             for g in GROUPS]
    outputs = [p.communicate()[0] for p in procs]
    return "".join(out for out, p in zip(outputs, procs, strict=True) if p.returncode)


if __name__ == "__main__":
    GROUPS[sys.argv[1]]()
