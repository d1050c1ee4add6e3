"""What makes the loop fast without changing what it finds: the dynamics integrated from a few
decay times before each record (the record the same to round-off), one BLAS thread."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from physics.dynamics.model import build_model, settle_time, simulate
from physics.loop.effects import EFFECTS
from physics.loop.simulation import SETTLE_DECAYS
from physics.loop.threads import one_blas_thread
from physics.params import scenario_from_config


def _blas_threads() -> list[int]:
    return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]


def test_loop_work_runs_on_one_blas_thread_and_restores_it():
    before = _blas_threads()
    inside = one_blas_thread(_blas_threads)()
    assert inside and all(n == 1 for n in inside)
    assert _blas_threads() == before


@pytest.fixture(scope="module")
def models():
    scn = scenario_from_config({"case": 3})
    m = build_model(scn)
    low = dataclasses.replace(m, damping=m.damping * 0.01 / scn.dynamics.damping_ratio)
    return scn, [m, low, EFFECTS["gear_runout"].model(m, {"runout_um": 40.0}),
                 EFFECTS["torque_ripple"].model(m, {"ripple_pct": 10.0, "order": 0.5})]


def _difference(a, b, k: int = 0) -> float:
    """Largest RMS difference of record ``k``'s DTE and force, relative to its spread."""
    return max(float(np.sqrt(np.mean((x[k] - y[k]) ** 2)) / np.std(y[k]))
               for x, y in ((a.dte, b.dte), (a.force, b.force)))


def test_settled_records_agree_with_those_integrated_from_rest(models):
    """The loop's records (from SETTLE_DECAYS decay times before the record) against the
    integration from t = 0: the same to 1e-9 of their spread, at the declared damping and at
    the calibration's lowest (1 %), with the gear run-out's and a half-order ripple's phases;
    too short a settling (3 decay times at 1 % damping) is seen."""
    scn, ms = models
    dyn = dataclasses.replace(scn.dynamics, sample_rate_hz=40960.0, duration_s=0.05,
                              transient_s=0.05, phase_bins=16, step_factor=0.5)
    full = simulate(ms, dyn)
    settled = simulate(ms, dyn, settle=SETTLE_DECAYS)
    for k in range(len(ms)):
        assert _difference(settled, full, k) < 1e-9, k
    assert np.allclose(settled.time, full.time)
    assert settle_time(ms[:1], SETTLE_DECAYS) < 0.5 * dyn.transient_s  # steps are saved
    short = simulate(ms[1:2], dyn, settle=3.0)
    assert _difference(short, simulate(ms[1:2], dyn)) > 1e-6
