"""Bad input on every entry point, typed as a user would: refused before any work, with one
message naming the value (and the record or column), no traceback, no file left behind."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from physics.loop.bundle import write_bundle

FS = 40960.0


def bundle(folder: Path, change: Callable[[pd.DataFrame, dict], None] | None = None) -> Path:
    """A valid three-record bundle (white records), then ``change(manifest, signals)``."""
    rng = np.random.default_rng(0)
    names = ["r00", "r01", "r02"]
    man = pd.DataFrame({"record": names, "quantity": "dte_m", "fs_hz": FS, "n1_rpm": 2000.0,
                        "torque_Nm": 300.0, "wear_mm": [0.0, 0.005, 0.01], "cycles": "",
                        "split": ""})
    sig = {n: rng.normal(size=int(0.4 * FS)) * 1e-6 for n in names}
    if change is not None:
        change(man, sig)
    return write_bundle(folder / "b", man, sig)


def _set(col: str, row: int, value) -> Callable:
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


REPRODUCE = ["-m", "physics.reproduce"]
DATASET = ["-m", "physics.dataset"]
LOOP = ["-m", "physics.loop"]
TRAIN = ["train.py"]
#: (arguments, input to make first or None, text the message must hold)
CASES = [
    ([*REPRODUCE, "cycles=abc"], None, "'abc'"),
    ([*REPRODUCE, "cycles=-1"], None, "cycles = -1"),
    ([*REPRODUCE, "gear.z1=abc"], None, "'abc'"),
    ([*REPRODUCE, "gear.z1=3"], None, "gear.z1 = 3"),
    ([*REPRODUCE, "case=9"], None, "case = 9"),
    ([*REPRODUCE, "operating.torque_Nm=900000"], None, "operating.torque_Nm = 900000"),
    ([*REPRODUCE, "operating.n1_rpm=99999"], None, "operating.n1_rpm = 99999"),
    ([*REPRODUCE, "lubricants=[foo]"], None, "'foo'"),
    ([*REPRODUCE, "thesis_tables=/nonexistent"], None, "/nonexistent"),
    ([*REPRODUCE, "gear.center_distance_mm=60"], None, "center_distance_mm = 60"),
    ([*REPRODUCE, "dynamics.duration_s=0.001"], None, "dynamics.duration_s = 0.001"),
    ([*DATASET, "jobs=abc"], None, "'abc'"),
    ([*DATASET, "jobs=0"], None, "jobs = 0"),
    ([*DATASET, "data.nuisance.snr_db=[.inf,30]"], None, "'.inf'"),
    ([*DATASET, "data.nuisance.snr_db=[nan,30]"], None, "snr_db = [nan, 30.0]"),
    ([*DATASET, "data.nuisance.damping_ratio=[0.2,0.1]"], None, "damping_ratio = [0.2, 0.1]"),
    ([*DATASET, "name=../../escape"], None, "'../../escape'"),
    ([*DATASET, "chunk=7"], None, "chunk = 7"),
    ([*DATASET, "data.cases=[9]"], None, "case = 9"),
    ([*DATASET, "data.cycles_max=inf"], None, "cycles_max = inf"),
    ([*DATASET, "data.replicates=0"], None, "replicates = 0"),
    ([*TRAIN, "case=9"], None, "case = '9'"),
    ([*TRAIN, "model.lr=abc"], None, "'abc'"),
    ([*TRAIN, "model.lr=-1"], None, "model.lr = -1"),
    ([*TRAIN, "model.width=0"], None, "model.width = 0"),
    ([*TRAIN, "data.batch_size=0"], None, "batch_size = 0"),
    ([*TRAIN, "trainer.max_epochs=abc"], None, "abc"),
    ([*TRAIN, "+data.generate.replicates=0"], None, "replicates = 0"),
    ([*TRAIN, "data.gearboxes=0"], None, "data.gearboxes = 0"),
    ([*TRAIN, "data.val_replicates=0"], None, "data.val_replicates = 0"),
    (["-m", "surrogate.predict", "ckpt=missing.pt", "input=x.csv"], None, "missing.pt"),
    (["-m", "surrogate.benchmark", "--seeds", "0"], None, "--seeds 0: give at least 1"),
    ([*LOOP, "data=missing"], None, "'missing'"),
    ([*LOOP, "data={input}"], _empty_manifest, "manifest.csv"),
    ([*LOOP, "data={input}"], _garbage_npy, "record 'r01': signals/r01.npy"),
    ([*LOOP, "data={input}"], _bad_gear, "gear.z1 = 'abc'"),
    ([*LOOP, "data={input}"], lambda f: bundle(f, _set("torque_Nm", 2, "abc")),
     "record 'r02': torque_Nm = 'abc'"),
    ([*LOOP, "data={input}"], lambda f: bundle(f, _set("torque_Nm", 2, 9e5)),
     "record 'r02': operating.torque_Nm = 900000"),
    ([*LOOP, "data={input}"], lambda f: bundle(f, _set("n1_rpm", 1, 20000.0)),
     "record 'r01': fs_hz"),
    ([*LOOP, "data={input}"], _empty_csv, "features.csv"),
    ([*LOOP, "data={input}", "loop.test_fraction=1.5"], bundle, "loop.test_fraction = 1.5"),
    ([*LOOP, "data={input}", "loop.segment_s=0"], bundle, "loop.segment_s = 0"),
    ([*LOOP, "data={input}", "loop.candidates=[rust]"], bundle, "rust"),
    ([*LOOP, "data={input}", "loop.explore=3"], bundle, "loop.explore = 3"),
    ([*LOOP, "data={input}", "reference=missing"], bundle, "'missing'"),
    ([*LOOP, "data={input}", "reference={input}/../ref/b"], _reference_elsewhere,
     "reference: no records at ['2000rpm_300Nm_dte_m_40960Hz']"),
]


def _tree(folder: Path) -> set[Path]:
    return {p.relative_to(folder) for p in folder.rglob("*")}


@pytest.mark.parametrize(("args", "make", "message"), CASES,
                         ids=[" ".join(a[1:])[:50] for a, _, _ in CASES])
def test_bad_input_is_refused_before_work(tmp_path, args, make, message):
    inputs = tmp_path / "in"
    inputs.mkdir()
    made = make(inputs) if make is not None else None
    work = tmp_path / "work"
    work.mkdir()
    argv = [a.replace("{input}", str(made)) for a in args]
    if argv[0] == "train.py":
        argv[0] = str(Path(__file__).resolve().parents[2] / "train.py")
    env = {k: v for k, v in os.environ.items() if not k.startswith("HYDRA_")}
    proc = subprocess.run([sys.executable, *argv], cwd=work, capture_output=True, text=True,
                          timeout=300, env=env)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0, out
    assert message in out, out
    assert "Traceback" not in out, out
    assert not _tree(work), f"left behind: {sorted(map(str, _tree(work)))}"
