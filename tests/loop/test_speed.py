"""What makes the loop fast without changing what it finds: the dynamics integrated from a few
decay times before each record (the record the same to round-off), one BLAS thread, candidates
and Jacobian columns on parallel threads (the results those of the serial order)."""

from __future__ import annotations

import dataclasses
import math
import threading
import time

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from physics.dynamics.model import build_model, settle_time, simulate
from physics.loop import threads
from physics.loop.config import LoopSettings
from physics.loop.effects import EFFECTS
from physics.loop.measured.bundle import read_bundle
from physics.loop.measured.records import prepare
from physics.loop.model.declared import completed
from physics.loop.model.simulation import SETTLE_DECAYS
from physics.loop.search.fit import Candidate, explore, screen_effect, search, train_cost
from physics.loop.threads import TimeLimit, each, one_blas_thread
from physics.params import scenario_from_config
from physics.testbeds.synthetic import make_bundle


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


def test_each_keeps_the_items_order_and_runs_them_on_parallel_threads(monkeypatch):
    monkeypatch.setattr(threads, "THREADS", 2)  # a test worker has one numba thread
    names, lock = set(), threading.Lock()

    def slow_square(x: int) -> int:
        with lock:
            names.add(threading.current_thread().name)
        time.sleep(0.02 * (5 - x))  # the first items end last
        return x * x

    assert each(slow_square, list(range(6)), "test") == [x * x for x in range(6)]
    assert len(names) == 2 and threading.current_thread().name not in names


def test_each_runs_in_turn_where_kernels_cannot_run_from_several_threads(monkeypatch):
    # numba's workqueue layer (no OpenMP or TBB) stops a process whose kernels two threads call
    monkeypatch.setattr(threads.numba, "threading_layer", lambda: "workqueue")
    assert threads.parallel_threads() == 1
    names = set()
    each(lambda x: names.add(threading.current_thread().name), [1, 2, 3], "test")
    assert names == {threading.current_thread().name}
    monkeypatch.setattr(threads.numba, "threading_layer", lambda: "omp")
    monkeypatch.setattr(threads.numba, "get_num_threads", lambda: 2)
    assert threads.parallel_threads() == 2


def test_each_stops_at_the_deadline_and_passes_an_error_on(monkeypatch):
    monkeypatch.setattr(threads, "THREADS", 2)
    with pytest.raises(TimeLimit):
        each(lambda x: x, [1, 2], "test", deadline=time.monotonic() - 1.0)
    started = []

    def fails_first(x: int) -> int:
        started.append(x)
        if x == 0:
            raise ValueError("item 0")
        time.sleep(0.05)
        return x

    with pytest.raises(ValueError, match="item 0"):
        each(fails_first, list(range(40)), "test")
    assert len(started) < 40  # the items not started were cancelled


def test_a_stop_keeps_what_the_items_running_then_computed(monkeypatch):
    """An interrupt raised by one item while another still runs: the running one ends and its
    result is among the stop's ``finished``, beside those done before."""
    monkeypatch.setattr(threads, "THREADS", 2)

    def item(x: int) -> int:
        if x == 1:
            time.sleep(0.1)  # item 0 ends, item 2 starts and stops the run: item 1 still runs
            return 1
        if x == 2:
            raise KeyboardInterrupt
        return x

    with pytest.raises(KeyboardInterrupt) as stop:
        each(item, [0, 1, 2], "test")
    assert stop.value.finished == [(0, 0), (1, 1)]


@pytest.fixture(scope="module")
def small_records(tmp_path_factory):
    scn = scenario_from_config({"case": 3})
    path, truth = make_bundle(tmp_path_factory.mktemp("threads") / "b", scn, "friction",
                              seed=2, records=4, duration_s=0.5)
    rec = prepare(read_bundle(path), scn, LoopSettings(seed=2, explore=2, max_nfev=2))
    return rec, completed(truth["nuisance"], scn)


def test_candidates_on_parallel_threads_find_what_they_find_in_turn(small_records,
                                                                   monkeypatch):
    """The screening of two candidates on two threads, and a search whose exploration and
    Jacobian columns run on two threads, against the same on one thread: the same fits to
    the last digit."""
    rec, nui = small_records
    cands = [(EFFECTS[n], {}) for n in ("gear_runout", "friction")]

    def fitted() -> list:
        rec.cache.clear()
        screened = each(lambda c: screen_effect(rec, *c, nui), cands, "screening")
        # from the calling thread: the exploration's points and the Jacobian's columns on
        # parallel threads
        best = search(rec, EFFECTS["friction"], screened[1], ["damping_ratio",
                                                               "housing_mass_kg"])
        return [(c.values, c.nuisance, c.train_rss) for c in (*screened, best)]

    monkeypatch.setattr(threads, "THREADS", 2)
    parallel = fitted()
    monkeypatch.setattr(threads, "THREADS", 1)
    assert fitted() == parallel


def test_a_measurement_stage_explores_its_parameters_on_shared_dynamics(small_records):
    """The transfer path's exploration (three parameters: four times the points of a
    one-parameter effect): its points span as many distinct dynamic nuisance draws as a
    one-parameter effect's, each shared by four draws of the path's parameters; each point's
    cost is its own (the same as computed afresh with nothing kept)."""
    rec, nui = small_records
    eff = EFFECTS["transfer_path"]
    c = Candidate(eff.name, {}, eff.defaults(), nui, math.inf, len(eff.params))
    rec.cache.clear()
    found = [p for p in explore(rec, eff, c, ["damping_ratio", "housing_mass_kg"]) if p is not c]
    assert len(found) == 4 * rec.settings.explore
    assert len({p.nuisance["damping_ratio"] for p in found}) == rec.settings.explore
    assert len({p.values["fn_hz"] for p in found}) == len(found)
    rec.cache.clear()
    for p in found:
        assert train_cost(rec, p.nuisance, eff, p.values) == p.train_rss
