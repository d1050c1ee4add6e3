"""Item 2: one writer per dataset. A second build into the same dataset refuses before any work,
naming the first's pid and the lock; a stale lock is taken over with a warning; the lock is
released at the end, also after a failure; the chunk jobs of one multirun share the dataset."""

from __future__ import annotations

import json
import logging
import os
import socket
import subprocess
import sys
from pathlib import Path

import pytest

import physics.dataset.generation as gen
from physics.dataset.generation import acquire_output, lock_path, plan_dataset, spec_from_config
from physics.params import Dynamics, Scenario, WearSolver

BASE = Scenario(solver=WearSolver(n_points=51),
                dynamics=Dynamics(duration_s=0.02, transient_s=0.005, phase_bins=64))
SMALL = {"cases": [3], "wear_states": 3, "replicates": 2, "cycles_max": 1e6, "chunks": 2}


def job(out: Path, chunk: int | None = None, **spec):
    return plan_dataset(BASE, spec_from_config({**SMALL, **spec}), out, chunk=chunk, jobs=1,
                        progress=False)


@pytest.fixture
def other_process():
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
    yield proc.pid
    proc.kill()
    proc.wait()


def _hold(path: Path, pid: int, **extra) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"pid": pid, "host": socket.gethostname(),
                                "command": "python -m physics.dataset", **extra}))


def test_a_second_build_is_refused_naming_the_first(tmp_path, other_process):
    j = job(tmp_path)
    _hold(lock_path(j), other_process, digest=j.digest)
    with pytest.raises(ValueError) as err:
        acquire_output(j)
    text = str(err.value)
    assert f"pid {other_process}" in text and str(lock_path(j)) in text and "\n" not in text
    # another config's whole build, and a chunk job, are refused the same way
    with pytest.raises(ValueError, match=f"pid {other_process}"):
        acquire_output(job(tmp_path, chunk=1, seed=7))
    assert not list(tmp_path.glob("*.chunk_*.lock"))  # the refused one leaves no lock


def test_chunk_jobs_of_one_config_share_the_dataset_but_not_of_two(tmp_path, other_process):
    first = job(tmp_path, chunk=0)
    _hold(lock_path(first), other_process, digest=first.digest)
    same = job(tmp_path, chunk=1)
    acquire_output(same)  # the next job of the same multirun
    gen.release_lock(lock_path(same))
    with pytest.raises(ValueError, match=f"pid {other_process}"):
        acquire_output(job(tmp_path, chunk=1, seed=7))  # another config's chunk job
    with pytest.raises(ValueError, match=f"pid {other_process}"):
        acquire_output(job(tmp_path))  # a whole build


def test_a_stale_lock_is_taken_over_with_a_warning(tmp_path, caplog):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    j = job(tmp_path)
    _hold(lock_path(j), dead.pid)
    with caplog.at_level(logging.WARNING):
        path = acquire_output(j)
    assert json.loads(path.read_text())["pid"] == os.getpid()
    assert any("stale lock" in r.getMessage() and str(dead.pid) in r.getMessage()
               for r in caplog.records)
    gen.release_lock(path)
    assert not path.exists()


def test_the_lock_is_released_when_the_build_fails(tmp_path, monkeypatch):
    j = job(tmp_path)

    def boom(job):
        assert lock_path(job).is_file()
        raise RuntimeError("a bug")

    monkeypatch.setattr(gen, "_build", boom)
    with pytest.raises(RuntimeError):
        gen.build_dataset(j)
    assert not lock_path(j).exists()


def test_acceptance_second_app_run_refused_in_one_line(tmp_path, other_process):
    """Through the app: exit 2, one line naming the first run's pid and the lock, nothing
    computed."""
    out = tmp_path / "data"
    _hold(out / "dataset.lock", other_process, digest="another config")
    run = subprocess.run([sys.executable, "-m", "physics.dataset", f"out_dir={out}",
                          "data.cases=[3]", "data.replicates=2", "data.chunks=2",
                          f"hydra.run.dir={tmp_path / 'hydra'}"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 2, run.stderr[-2000:]
    lines = [ln for ln in run.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and f"pid {other_process}" in lines[0]
    assert str(out / "dataset.lock") in lines[0]
    assert not (out / "dataset_chunks").exists()


def test_a_lock_that_cannot_be_written_is_removed_and_named(tmp_path, monkeypatch):
    """A full disk as the lock's line is written: the lock is removed (no empty lock that the
    next run takes for another run's) and the failure is a WriteFailed naming it, which the
    apps end in one line."""
    from physics.files import WriteFailed, take_lock

    class Full:
        def __init__(self, fd, mode):
            os.close(fd)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def write(self, text):
            raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fdopen", Full)
    lock = tmp_path / "d" / "dataset_case3.lock"
    with pytest.raises(WriteFailed) as err:
        take_lock(lock, "the dataset")
    assert f"the lock {lock} of the dataset could not be written (No space left" in str(err.value)
    assert not lock.exists()
    monkeypatch.undo()
    assert take_lock(lock, "the dataset") == lock and json.loads(lock.read_text())["pid"]
