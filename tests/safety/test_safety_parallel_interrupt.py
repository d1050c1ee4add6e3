"""Ctrl-C while a dataset is built in parallel worker processes (``physics.dataset``, and
``train.py`` building a missing dataset): one ``interrupted:`` line saying truly which chunks
were kept, exit code 130, no worker's traceback, no hang, no worker left running.

Two moments need care. A Ctrl-C between a worker's start and joblib's record of it leaves that
worker unknown to joblib, free to print a traceback after the app's line. And a second Ctrl-C
(it reaches the whole process group) would end the ``pgrep`` through which loky stops its
workers: loky's thread would die with a traceback and the workers run on, writing chunks after
the line had said none was kept, with the app waiting for them."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from joblib import delayed

from physics import interrupt

#: a dataset of two chunks, one unit each, built by two worker processes
SMALL = ["data.cases=[3]", "data.replicates=2", "data.wear_states=2", "data.chunks=2", "jobs=2"]


def live_in_session(sid: int) -> list[str]:
    """The processes of session ``sid`` that still run (not zombies), by command line."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
            line = (stat.parent / "cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        state, _, _, session = text[text.rindex(")") + 2:].split()[:4]
        if int(session) == sid and state != "Z":
            out.append(line)
    return out


def workers(sid: int) -> list[str]:
    """The loky worker processes of session ``sid`` still running."""
    return [line for line in live_in_session(sid) if "popen_loky_posix" in line]


def kept_on_disk(work: Path) -> list[str]:
    """The chunk files the manifest vouches for."""
    folder = work / "data" / "dataset_chunks"
    manifest = folder / "manifest.json"
    if not manifest.is_file():
        return []
    return sorted(n for n in json.loads(manifest.read_text())["chunks"] if (folder / n).is_file())


def said_kept(line: str) -> list[str]:
    """The chunk files an ``interrupted:`` line names as kept (``(chunk 0-2, 5)``)."""
    if "no chunk of the" in line:
        return []
    named = re.search(r"are kept in \S+ \(chunk ([^)]*)\)", line)
    assert named, line
    numbers = []
    for part in named.group(1).split(", "):
        a, _, b = part.partition("-")
        numbers += range(int(a), int(b or a) + 1)
    return [f"chunk_{c:03d}.parquet" for c in numbers]


def ended(proc: subprocess.Popen, what: str) -> str:
    """``proc``'s stderr once it ended (a hang fails), after its workers are gone."""
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        _, err = proc.communicate()
        pytest.fail(f"{what}: the app did not end within 60 s (killed):\n{err[-3000:]}")
    assert not workers(proc.pid), f"{what}: workers left running: {workers(proc.pid)}"
    deadline = time.monotonic() + 5  # loky's resource trackers end once the app's pipe closed
    while live_in_session(proc.pid):
        assert time.monotonic() < deadline, f"{what}: left running: {live_in_session(proc.pid)}"
        time.sleep(0.05)
    return err


def check_one_true_line(proc: subprocess.Popen, err: str, work: Path, what: str) -> None:
    lines = [ln for ln in err.splitlines() if "interrupted:" in ln]
    assert proc.returncode == 130, f"{what}: exit {proc.returncode}\n{err[-3000:]}"
    assert "Traceback" not in err and "Exception in thread" not in err, f"{what}:\n{err[-3000:]}"
    assert len(lines) == 1, f"{what}:\n{err[-3000:]}"
    assert said_kept(lines[0]) == kept_on_disk(work), f"{what}: {lines[0]}"
    assert not [p for p in work.rglob("*") if p.name.endswith((".tmp", ".lock"))]


#: the dataset app, SIGINT sent to itself right after loky started its first worker process
#: (before joblib has recorded it)
AT_WORKER_START = """
import os, signal, sys
from joblib.externals.loky.backend.process import LokyProcess
start = LokyProcess.start
def started(self):
    start(self)
    os.kill(os.getpid(), signal.SIGINT)
LokyProcess.start = started
sys.argv = ["physics.dataset", *sys.argv[1:]]
from physics.dataset.__main__ import main
main()
"""


def test_ctrl_c_as_a_worker_starts_ends_in_one_line_and_leaves_no_worker(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", AT_WORKER_START, *SMALL], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    err = ended(proc, "Ctrl-C as the first worker starts")
    check_one_true_line(proc, err, tmp_path, "Ctrl-C as the first worker starts")
    assert "no chunk of the 2 was finished" in err


def test_ctrl_c_twice_while_the_workers_compute_says_truly_what_was_kept(tmp_path):
    """Ctrl-C, and again 20 ms later, as a terminal sends it (to the whole process group),
    while both workers compute their chunk."""
    proc = subprocess.Popen([sys.executable, "-m", "physics.dataset", *SMALL], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 60
    while len(workers(proc.pid)) < 2:
        assert time.monotonic() < deadline and proc.poll() is None, "no worker started"
        time.sleep(0.05)
    time.sleep(1.0)  # the workers import and begin their chunks
    os.killpg(proc.pid, signal.SIGINT)
    time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGINT)
    err = ended(proc, "Ctrl-C twice")
    check_one_true_line(proc, err, tmp_path, "Ctrl-C twice")


def _slow(x: int) -> int:
    time.sleep(5)
    return x


def test_a_parallel_block_left_early_stops_and_reaps_its_workers():
    """In-process: the block left by an exception (a Ctrl-C in the caller's own loop) stops
    the workers at once and reaps them, a further signal meanwhile noted, not raised
    (:func:`physics.interrupt.shielded`)."""
    import multiprocessing

    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        with interrupt.worker_results((delayed(_slow)(i) for i in range(4)), 2) as runs:
            raise KeyboardInterrupt  # before a single result came
    assert time.monotonic() - start < 5  # not waited for
    assert not [c for c in multiprocessing.active_children() if c.is_alive()]
    assert runs is not None


def test_shielded_notes_a_signal_and_raises_it_nowhere(monkeypatch):
    monkeypatch.setattr(interrupt, "_PHASE", "run")
    monkeypatch.setattr(interrupt, "_SIGNAL", None)
    with interrupt.shielded():
        interrupt._on_signal(signal.SIGINT, None)  # as the handler is called: no raise
    assert interrupt._SIGNAL == signal.SIGINT and not interrupt._DEFERRED


def test_the_stop_quiets_the_executor_managers_own_exception_and_no_other(monkeypatch):
    """After the workers are killed on purpose, loky's manager thread may die on the task the
    kill dropped (a KeyError from its own thread): not printed; another thread's error is."""
    import threading

    seen = []
    monkeypatch.setattr(threading, "excepthook", lambda args: seen.append(args.thread.name))
    interrupt.quiet_executor_manager()
    interrupt.quiet_executor_manager()  # once is enough: not stacked

    def fail():
        raise KeyError(1)

    for name in (interrupt.EXECUTOR_MANAGER, "candidate_0"):
        t = threading.Thread(target=fail, name=name)
        t.start()
        t.join()
    assert seen == ["candidate_0"]
