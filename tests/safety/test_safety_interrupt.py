"""Ctrl-C (SIGINT to the process group, as a terminal sends it) and SIGTERM (to the app's
process) at random moments of each app on a small config: exit code 130 / 143, exactly one
``interrupted:`` line on stderr, no traceback, no temporary or lock file left, and a run
interrupted before its work leaves nothing at all. A signal that comes after the work ended
may find the run finished (exit 0, no line); the first try comes within the app's first
second, so at least one try per app is interrupted.

The default run tries each app twice (once with each signal); the slow variant 10 times
in a row."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

ROOT = Path(__file__).resolve().parents[2]
SMALL_DATASET = ["data.cases=[3]", "data.replicates=2", "data.wear_states=2", "data.chunks=2",
                 "progress=false"]
FAST_REPRO = ["solver.n_points=101", "stiffness.fem_refine=1", "stiffness.fem_refines=[1]",
              "stiffness.positions=40", "evolution.cases=[3]", "evolution.points=9",
              "evolution.table14_cycles=[0,1.5e7]", "table15_operating_points=false"]
SMALL_LOOP = ["loop.max_nfev=4", "loop.explore=4", "loop.candidates=[friction,tip_relief]",
              "progress=false"]
TINY_TRAIN = ["+data.generate.replicates=4", "+data.generate.wear_states=3",
              "+data.generate.cycles_max=3e6", "+data.generate.chunks=2",
              "data.val_replicates=1", "data.test_replicates=1", "trainer.max_epochs=3000",
              "trainer.min_epochs=3000", "model.members=2", "trainer.enable_progress_bar=false"]


@pytest.fixture(scope="module")
def inputs(tmp_path_factory, small_model) -> dict[str, Path]:
    """A bundle for the loop; a model, the user table it was trained on and a feature table
    for predict (``small_model``)."""
    from physics.params import Scenario
    from physics.testbeds import make_bundle

    bundle = tmp_path_factory.mktemp("inputs") / "bundle"
    make_bundle(bundle, Scenario(), "friction", seed=1, records=6, duration_s=0.5)
    ckpt = small_model("auto")
    return {"bundle": bundle, "ckpt": ckpt, "table": ckpt.parents[1] / "in.csv",
            "features": ckpt.parents[1] / "features.csv"}


def argv(app: str, inputs: dict[str, Path]) -> tuple[list[str], float]:
    """The command of ``app`` and the latest moment (s) a signal is sent."""
    py = sys.executable
    if app == "dataset":
        return [py, "-m", "physics.dataset", *SMALL_DATASET], 10.0
    if app == "reproduce":
        return [py, "-m", "physics.reproduce", *FAST_REPRO, "out_dir=results"], 8.0
    if app == "loop":
        return [py, "-m", "physics.loop", f"data={inputs['bundle']}", *SMALL_LOOP], 10.0
    if app == "train":
        return [py, str(ROOT / "train.py"), *TINY_TRAIN], 8.0  # the fit starts at about 6 s
    return [py, "-m", "surrogate.predict", f"ckpt={inputs['ckpt']}",
            f"input={inputs['features']}", "output=wear.csv"], 6.0


def interrupt(cmd: list[str], cwd: Path, signum: int, delay: float,
              env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    proc = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, start_new_session=True, env=env)
    try:  # a run that ends before the moment has nothing left to interrupt: not waited for
        proc.wait(timeout=delay)
    except subprocess.TimeoutExpired:
        try:
            if signum == signal.SIGINT:
                os.killpg(proc.pid, signum)  # as a terminal sends Ctrl-C: to the whole group
            else:
                os.kill(proc.pid, signum)  # as kill(1) or a process manager sends it
        except ProcessLookupError:
            pass
    _, err = proc.communicate(timeout=300)
    return subprocess.CompletedProcess(cmd, proc.returncode, "", err)


def left(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*")
                  if p.name.endswith((".tmp", ".lock")) or ".staged" in p.name)


def check_tries(app: str, inputs: dict[str, Path], tmp_path: Path, tries: int) -> None:
    rng = random.Random()
    cmd, latest = argv(app, inputs)
    # the loop's candidates on two threads, as outside a test worker (one numba thread there)
    env = {**os.environ, "NUMBA_NUM_THREADS": "2"} if app == "loop" else None
    interrupted = 0
    for i in range(tries):
        signum = (signal.SIGINT, signal.SIGTERM)[i % 2]
        # the first try within the app's first second (its imports: always still running),
        # the others anywhere up to the latest moment
        delay = rng.uniform(0.2, 1.0 if i == 0 else latest)
        work = tmp_path / f"try{i}"
        work.mkdir()
        run = interrupt(cmd, work, signum, delay, env)
        what = f"{app}, {signal.Signals(signum).name} after {delay:.2f} s:\n{run.stderr[-3000:]}"
        lines = [ln for ln in run.stderr.splitlines() if ln.startswith("interrupted:")]
        assert "Traceback" not in run.stderr, what
        assert not left(work), f"{left(work)} left; {what}"
        if run.returncode in (0, -signum):  # the work had ended: nothing to report
            assert not lines, what
            continue
        assert run.returncode == {signal.SIGINT: 130, signal.SIGTERM: 143}[signum], what
        assert len(lines) == 1, what
        interrupted += 1
        if "nothing was written" in lines[0]:
            assert not any(work.iterdir()), f"{sorted(work.rglob('*'))} left; {what}"
    assert interrupted, f"{app}: no try was interrupted before the run ended"


APPS = ["dataset", "reproduce", "loop", "train", "predict"]


@pytest.mark.parametrize("app", APPS)
def test_ctrl_c_and_sigterm_at_random_moments(app, inputs, tmp_path):
    check_tries(app, inputs, tmp_path, 2)


@pytest.mark.slow
@pytest.mark.parametrize("app", APPS)
def test_ctrl_c_and_sigterm_ten_times_in_a_row(app, inputs, tmp_path):
    check_tries(app, inputs, tmp_path, 10)


def test_ctrl_c_during_training_names_the_checkpoints_and_exits_130(inputs, tmp_path):
    """Lightning catches KeyboardInterrupt in its fit loop ("graceful shutdown", exit 1): the
    app still ends with its one line and 130 (on a user table: no dataset to build first)."""
    cmd = [sys.executable, str(ROOT / "train.py"), f"data.table={inputs['table']}",
           "data.group=rig", *TINY_TRAIN[4:], "hydra.run.dir=run"]
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    for line in proc.stdout:  # Hydra logs to stdout: wait for the fit loop to run
        if "surrogate.training][INFO] - split:" in line:
            break
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob("run/checkpoints/*.ckpt")):
        assert time.monotonic() < deadline, "no checkpoint written"
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    lines = [ln for ln in err.splitlines() if ln.startswith("interrupted:")]
    assert proc.returncode == 130 and "Traceback" not in err, err[-3000:]
    assert len(lines) == 1 and "the checkpoints so far are in" in lines[0], err[-3000:]
    assert not (tmp_path / "run" / "wear_surrogate.pt").exists()


def test_a_signal_during_a_deferred_stretch_is_raised_at_the_next_check(monkeypatch):
    """Inside ``deferred()`` (the training's fit, a slow import) a signal is noted, not raised
    where the program is; ``check()`` (between batches) or the stretch's end raises it, SIGTERM
    as Terminated; one noted before is raised on entering."""
    from physics import interrupt

    monkeypatch.setattr(interrupt, "_PHASE", "run")
    monkeypatch.setattr(interrupt, "_SIGNAL", None)
    reached = []
    with pytest.raises(interrupt.Terminated):
        with interrupt.deferred():
            interrupt._on_signal(signal.SIGTERM, None)  # as the handler is called: no raise
            reached.append("after the signal")
    assert reached == ["after the signal"]
    with pytest.raises(interrupt.Terminated):
        interrupt.check()
    with pytest.raises(interrupt.Terminated):
        with interrupt.deferred():
            reached.append("entered")
    assert reached == ["after the signal"]


def test_an_interruption_raised_during_garbage_collection_prints_no_traceback(monkeypatch,
                                                                            capsys):
    """A signal that lands in a weakref callback (matplotlib's transforms, collected as the
    loop's figures close) cannot be passed on: Python would print "Exception ignored" and a
    traceback; the handlers let it be (the guard reports the interruption once), and other
    errors there are printed as Python prints them."""
    import weakref

    from physics import interrupt

    monkeypatch.setattr(sys, "unraisablehook", sys.unraisablehook)
    monkeypatch.setattr(interrupt, "_SIGNAL", signal.SIGTERM)
    monkeypatch.setattr(signal, "signal", lambda *args: None)  # the test runner's handlers stay
    interrupt.install_signal_handlers()

    class Node:
        pass

    def collected(error: BaseException) -> str:
        node = Node()
        ref = weakref.ref(node, lambda _: (_ for _ in ()).throw(error))
        del node  # the callback runs here and raises
        assert ref() is None
        return capsys.readouterr().err

    assert "Traceback" not in collected(interrupt.Terminated())
    assert "ValueError: another error" in collected(ValueError("another error"))


DURING_COMPOSITION = """
import os, signal, sys
from hydra._internal import config_loader_impl as loader
from physics import interrupt
interrupt.install_at_start("__main__")
compose = loader.ConfigLoaderImpl._load_configuration_impl
def interrupted(self, *args, **kwargs):
    try:
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C while Hydra composes the config
        return compose(self, *args, **kwargs)
    except KeyboardInterrupt:
        print("raised inside the composition", file=sys.stderr)
        raise
loader.ConfigLoaderImpl._load_configuration_impl = interrupted
sys.argv = ["surrogate.predict", *sys.argv[1:]]
from surrogate.predict import main
main()
"""


def test_ctrl_c_while_hydra_composes_the_config_ends_in_one_line(tmp_path):
    """A signal raised inside OmegaConf's composition once left its config half-set, and Hydra
    printed the error that followed with its traceback: until the config is composed a signal
    is not raised there, the run ends at once with its line."""
    run = subprocess.run([sys.executable, "-c", DURING_COMPOSITION, "ckpt=m.pt", "input=x.csv"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert run.returncode == 130 and "Traceback" not in run.stderr, run.stderr[-3000:]
    assert run.stderr.splitlines() == ["interrupted: nothing was written; run the command again"]
    assert not any(tmp_path.iterdir())
