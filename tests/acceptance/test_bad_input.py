"""Bad input on every entry point: refused before any work, with one message naming the value
(and the record or column), no traceback, no file left behind.

The table is checked in-process, each row through its app's first phase as the app runs it
(``physics.command.run_command``): Hydra composes the app's config with the row's overrides
(a wrong type is refused there) and the app's ``prepare`` checks the rest (a ValueError). Then
one subprocess per app, typed as a user would, checks the exit path itself: exit code 2, the
one-line message, no traceback and nothing left in the folder.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from physics.loop.measured.bundle import write_bundle
from tests.acceptance.refusal import APPS, ROOT, chain, refusal, tree

FS = 40960.0


def bundle(folder: Path, change: Callable[[pd.DataFrame, dict], None] | None = None) -> Path:
    """A valid three-record bundle (white records), then ``change(manifest, signals)``."""
    rng = np.random.default_rng(0)
    names = ["r00", "r01", "r02"]
    man = pd.DataFrame({"record": names, "quantity": "dte_m", "fs_hz": FS, "n1_rpm": 2000.0,
                        "torque_Nm": 300.0, "wear_mm": [0.0, 0.005, 0.01], "cycles": "",
                        "split": ""})
    sig = {n: rng.normal(size=int(0.6 * FS)) * 1e-6 for n in names}
    if change is not None:
        change(man, sig)
    return write_bundle(folder / "b", man, sig)


def _set(col: str, row, value) -> Callable:
    def change(man: pd.DataFrame, sig: dict) -> None:
        man[col] = man[col].astype(object)
        man.loc[row, col] = value
    return change


def _garbage_npy(folder: Path) -> Path:
    path = bundle(folder)
    (path / "signals" / "r01.npy").write_bytes(b"not a numpy file at all")
    return path


def _empty_manifest(folder: Path) -> Path:
    path = bundle(folder)
    (path / "manifest.csv").write_text("")
    return path


def _repeated_column(folder: Path) -> Path:
    """The manifest with a second ``fs_hz`` column (pandas reads it as fs_hz.1)."""
    path = bundle(folder)
    lines = (path / "manifest.csv").read_text().splitlines()
    (path / "manifest.csv").write_text("\n".join(
        [lines[0] + ",fs_hz", *(line + ",99" for line in lines[1:])]) + "\n")
    return path


def _bad_gear(folder: Path) -> Path:
    path = bundle(folder)
    (path / "gear.yaml").write_text("z1: abc\n")
    return path


def _empty_csv(folder: Path) -> Path:
    path = folder / "features.csv"
    path.write_text("")
    return path


def _reference_elsewhere(folder: Path) -> Path:
    """A bundle at 2000 r/min and, beside it (``<folder>/ref/b``), a reference of the same
    gearbox type recorded at 1800 r/min only."""
    bundle(folder / "ref", _set("n1_rpm", slice(None), 1800.0))
    return bundle(folder)


def _torque(value) -> Callable[[Path], Path]:
    return lambda f: bundle(f, _set("torque_Nm", 2, value))


#: (app, overrides, input to make first or None, text the message must hold)
CASES = [
    ("reproduce", ["cycles=abc"], None, "'abc'"),
    ("reproduce", ["cycles=-1"], None, "cycles = -1"),
    ("reproduce", ["gear.z1=abc"], None, "'abc'"),
    ("reproduce", ["gear.z1=3"], None, "gear.z1 = 3"),
    ("reproduce", ["case=9"], None, "case = 9"),
    ("reproduce", ["operating.torque_Nm=900000"], None, "operating.torque_Nm = 900000"),
    ("reproduce", ["operating.n1_rpm=99999"], None, "operating.n1_rpm = 99999"),
    ("reproduce", ["lubricants=[foo]"], None, "'foo'"),
    ("reproduce", ["thesis_tables=/nonexistent"], None, "/nonexistent"),
    ("reproduce", ["gear.center_distance_mm=60"], None, "center_distance_mm = 60"),
    ("reproduce", ["dynamics.duration_s=0.001"], None, "dynamics.duration_s = 0.001"),
    ("dataset", ["jobs=abc"], None, "'abc'"),
    ("dataset", ["jobs=0"], None, "jobs = 0"),
    ("dataset", ["data.nuisance.snr_db=[.inf,30]"], None, "'.inf'"),
    ("dataset", ["data.nuisance.snr_db=[nan,30]"], None, "snr_db = [nan, 30.0]"),
    ("dataset", ["data.nuisance.damping_ratio=[0.2,0.1]"], None, "damping_ratio = [0.2, 0.1]"),
    ("dataset", ["name=../../escape"], None, "'../../escape'"),
    ("dataset", ["chunk=7"], None, "chunk = 7"),
    ("dataset", ["data.cases=[9]"], None, "case = 9"),
    ("dataset", ["data.cycles_max=inf"], None, "cycles_max = inf"),
    ("dataset", ["data.replicates=0"], None, "replicates = 0"),
    ("train", ["case=9"], None, "case = '9'"),
    ("train", ["model.lr=abc"], None, "'abc'"),
    ("train", ["model.lr=-1"], None, "model.lr = -1"),
    ("train", ["model.width=0"], None, "model.width = 0"),
    ("train", ["data.batch_size=0"], None, "batch_size = 0"),
    ("train", ["trainer.max_epochs=abc"], None, "abc"),
    ("train", ["+data.generate.replicates=0"], None, "replicates = 0"),
    ("train", ["data.gearboxes=0"], None, "data.gearboxes = 0"),
    ("train", ["data.val_replicates=0"], None, "data.val_replicates = 0"),
    ("train", ["data.inputs=[dte_rms,mean_wear_mm]"], None,
     "data.target = 'mean_wear_mm' is also among data.inputs"),
    ("train", ["data.inputs=[dte_rms,dte_rms]"], None, "names ['dte_rms'] more than once"),
    ("predict", ["ckpt=missing.pt", "input=x.csv"], None, "missing.pt"),
    ("loop", ["data=missing"], None, "'missing'"),
    ("loop", ["data=missing", "dynamics.flank_contact=exact"], None,
     "dynamics.flank_contact = 'exact': the loop's effects"),
    ("loop", ["data={input}"], _empty_manifest, "manifest.csv"),
    ("loop", ["data={input}"], _repeated_column, "column(s) ['fs_hz'] more than once"),
    ("loop", ["data={input}"], _garbage_npy, "record 'r01': signals/r01.npy"),
    ("loop", ["data={input}"], _bad_gear, "gear.z1 = 'abc'"),
    ("loop", ["data={input}"], _torque("abc"), "record 'r02': torque_Nm = 'abc'"),
    ("loop", ["data={input}"], _torque(9e5), "record 'r02': operating.torque_Nm = 900000"),
    ("loop", ["data={input}"], lambda f: bundle(f, _set("n1_rpm", 1, 20000.0)),
     "record 'r01': fs_hz"),
    ("loop", ["data={input}"], _empty_csv, "features.csv"),
    ("loop", ["data={input}", "loop.test_fraction=1.5"], bundle, "loop.test_fraction = 1.5"),
    ("loop", ["data={input}", "loop.segment_s=0"], bundle, "loop.segment_s = 0"),
    ("loop", ["data={input}", "loop.candidates=[rust]"], bundle, "rust"),
    ("loop", ["data={input}", "loop.explore=3"], bundle, "loop.explore = 3"),
    ("loop", ["data={input}", "reference=missing"], bundle, "'missing'"),
    ("loop", ["data={input}", "reference={input}/../ref/b"], _reference_elsewhere,
     "reference: no records at ['2000rpm_300Nm_dte_m_40960Hz']"),
]
#: one row per app whose whole exit path runs as a subprocess: the first of its ValueErrors
#: (exit code 2), and a wrong type refused by Hydra itself while it composes
EXIT_PATH = [("reproduce", ["cycles=abc"], None, "'abc'"),
             ("reproduce", ["gear.z1=3"], None, "gear.z1 = 3"),
             ("dataset", ["jobs=0"], None, "jobs = 0"),
             ("train", ["model.lr=-1"], None, "model.lr = -1"),
             ("predict", ["ckpt=missing.pt", "input=x.csv"], None, "missing.pt"),
             ("loop", ["data={input}"], _torque(9e5),
              "record 'r02': operating.torque_Nm = 900000")]


def _folders(tmp_path: Path, make) -> tuple[str | None, Path]:
    """The row's input, made in ``tmp_path/in``, and an empty working folder."""
    inputs, work = tmp_path / "in", tmp_path / "work"
    inputs.mkdir()
    work.mkdir()
    made = make(inputs) if make is not None else None
    return (str(made) if made is not None else None), work


def _id(row) -> str:
    return f"{row[0]} " + " ".join(row[1])[:50]


@pytest.mark.parametrize(("app", "overrides", "make", "message"), CASES,
                         ids=[_id(c) for c in CASES])
def test_bad_input_is_refused_before_work(tmp_path, config_store, app, overrides, make,
                                          message):
    made, work = _folders(tmp_path, make)
    err = refusal(app, [o.replace("{input}", made or "") for o in overrides], work)
    text = chain(err)
    assert message in text, text
    if not isinstance(err, ValueError):  # then Hydra refused it while composing
        assert "compos" in type(err).__name__.lower() or "Validation" in type(
            err).__name__, repr(err)
    assert not tree(work), f"left behind: {sorted(map(str, tree(work)))}"


@pytest.mark.parametrize(("app", "overrides", "make", "message"), EXIT_PATH,
                         ids=[_id(c) for c in EXIT_PATH])
def test_a_refused_command_ends_with_one_line_and_leaves_nothing(tmp_path, app, overrides, make,
                                                                 message):
    made, work = _folders(tmp_path, make)
    argv = [*APPS[app].argv, *(o.replace("{input}", made or "") for o in overrides)]
    env = {k: v for k, v in os.environ.items() if not k.startswith("HYDRA_")}
    proc = subprocess.run([sys.executable, *argv], cwd=work, capture_output=True, text=True,
                          timeout=300, env=env)
    out = proc.stdout + proc.stderr
    assert proc.returncode == (1 if "abc" in message else 2), out  # Hydra's own refusal: 1
    assert message in out, out
    assert "Traceback" not in out, out
    if proc.returncode == 2:  # the app's refusal: one line
        lines = [line for line in proc.stderr.splitlines() if line.startswith("error: ")]
        assert len(lines) == 1 and message in lines[0], out
    assert not tree(work), f"left behind: {sorted(map(str, tree(work)))}"


def test_the_benchmark_refuses_a_bad_count(tmp_path, monkeypatch, capsys):
    from surrogate.benchmark import main

    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as refused:
        main(["--seeds", "0"])
    assert refused.value.code == 2
    assert "--seeds 0: give at least 1" in capsys.readouterr().err
    assert not tree(tmp_path)


@pytest.mark.parametrize("override, named", [
    ("model.interval=2", "must lie in (0, 1)"),
    ("foo.bar=1", "Could not override 'foo.bar'"),
    ("data.inputs=[dte_peak_to_peak,cycles]", "data.inputs is set by each of the benchmark's"),
    ("+seed=3", "seed is set by each")])
def test_the_benchmark_refuses_a_bad_override_before_work(tmp_path, monkeypatch, capsys,
                                                          override, named):
    """A train.py override the benchmark passes to every network is checked by composing and
    preparing the case-3 run in a temporary folder: refused in one line naming it, exit 2, no
    dataset built and nothing left behind."""
    from surrogate.benchmark import main

    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as refused:
        main(["--override", override])
    assert refused.value.code == 2
    err = capsys.readouterr().err
    assert f"--override {override}: " in err and named in err
    assert not tree(tmp_path)


@pytest.mark.parametrize("args, named", [(["--starts", "0"], "loop.starts = 0"),
                                         (["--own-history", "2", "--reference"],
                                          "--own-history takes no --reference")])
def test_the_loop_bench_refuses_bad_settings_before_work(tmp_path, args, named):
    """The loop bench checks its settings (the loop's own validation) before any bundle is
    made: one line naming the flag, exit 2, no output folder."""
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "bench_loop.py"), *args,
                           "--out", str(tmp_path / "out")], capture_output=True, text=True,
                          cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 2
    assert named in proc.stderr.splitlines()[-1]
    assert not (tmp_path / "out").exists()
