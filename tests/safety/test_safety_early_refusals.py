"""Item 6: an output folder that cannot be written is refused in prepare, in one line, before
any work (it gave a PermissionError traceback after the work)."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from omegaconf.errors import MissingMandatoryValue

from physics.dataset.generation import plan_dataset, spec_from_config
from physics.files import check_writable
from physics.params import Scenario
from tests.acceptance.refusal import refusal

ROOT = Path(__file__).resolve().parents[2]
SMALL = {"cases": [3], "wear_states": 3, "replicates": 2, "chunks": 1}


def test_unwritable_and_file_outputs_are_refused(tmp_path):
    with pytest.raises(ValueError, match=r"out_dir = '/proc/gearwear/data': cannot write in "
                                         r"/proc"):
        check_writable("/proc/gearwear/data", "out_dir")
    (tmp_path / "f").write_text("mine")
    with pytest.raises(ValueError, match=r"is a file, not a folder"):
        check_writable(tmp_path / "f" / "sub", "out_dir")
    check_writable(tmp_path / "new" / "deeper", "out_dir")
    assert not (tmp_path / "new").exists() and (tmp_path / "f").read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f"]


@contextlib.contextmanager
def read_only(folder: Path):
    """``folder`` takes no new file within the block: its write bits off and, for root, whom
    they do not stop, the immutable attribute (``chattr +i``; skipped where there is none)."""
    folder.chmod(0o555)
    root = os.geteuid() == 0
    if root and (shutil.which("chattr") is None or subprocess.run(
            ["chattr", "+i", str(folder)], capture_output=True).returncode != 0):
        folder.chmod(0o755)
        pytest.skip("root writes into a read-only folder, and chattr +i does not work here")
    try:
        yield
    finally:
        if root:
            subprocess.run(["chattr", "-i", str(folder)], check=True)
        folder.chmod(0o755)


def test_a_read_only_folder_is_refused(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    with read_only(ro):
        with pytest.raises(ValueError, match="cannot write in"):
            plan_dataset(Scenario(), spec_from_config(SMALL), ro / "data")
    assert not any(ro.iterdir())


def test_dataset_plan_refuses_an_unwritable_out_dir():
    with pytest.raises(ValueError, match=r"out_dir = '/proc/x': cannot write"):
        plan_dataset(Scenario(), spec_from_config(SMALL), "/proc/x")


@pytest.mark.parametrize("argv", [
    ["-m", "physics.dataset", "out_dir=/proc/gearwear", "data.cases=[3]", "data.replicates=2",
     "data.chunks=1"],
    ["-m", "surrogate.predict", "ckpt=ANY", "input=ANY", "output=/proc/gearwear/w.csv"],
])
def test_acceptance_apps_refuse_an_unwritable_output_in_one_line(tmp_path, small_model, argv):
    if "surrogate.predict" in argv:
        pytest.importorskip("onnxruntime")
        ckpt = small_model("auto")  # a model and a table reach the output check
        argv = [a.replace("ckpt=ANY", f"ckpt={ckpt}")
                .replace("input=ANY", f"input={ckpt.parents[1] / 'features.csv'}")
                for a in argv]
    run = subprocess.run([sys.executable, *argv, f"hydra.run.dir={tmp_path / 'h'}"],
                         capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert run.returncode == 2, run.stderr[-2000:]
    lines = [ln for ln in run.stderr.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1 and "cannot write in /proc" in lines[0]
    assert "Traceback" not in run.stderr


def test_check_inside_refuses_a_folder_that_escapes_its_root(tmp_path):
    from physics.files import check_inside

    check_inside(tmp_path / "logs" / "train" / "runs", tmp_path / "logs", "task_name")
    with pytest.raises(ValueError, match=r"task_name puts .* outside .*logs; use a plain name"):
        check_inside(tmp_path / "logs" / ".." / ".." / "x", tmp_path / "logs", "task_name")


def test_an_existing_file_as_out_dir_is_refused_at_once(tmp_path):
    (tmp_path / "out").write_text("mine")
    with pytest.raises(ValueError, match=r"is a file, not a folder"):
        check_writable(tmp_path / "out", "out_dir")


def test_a_setting_without_default_left_out_is_one_line_naming_it(tmp_path):
    """The command typed without its one required setting: one line naming the setting and
    how to give it (not omegaconf's MissingMandatoryValue traceback), exit 2, no run folder
    left; the loop's ``data`` is refused as predict's ``ckpt`` is, by the runner all the apps
    share (:func:`physics.command.run_command`)."""
    run = subprocess.run([sys.executable, "-m", "surrogate.predict"], capture_output=True,
                         text=True, timeout=300, cwd=tmp_path)
    assert run.returncode == 2, run.stderr[-2000:]
    assert "Traceback" not in run.stderr, run.stderr[-2000:]
    (line,) = [ln for ln in run.stderr.splitlines() if ln.startswith("error:")]
    assert line.startswith("error: ckpt is not given and has no default: give ckpt=")
    assert not list(tmp_path.iterdir()), sorted(tmp_path.rglob("*"))


def test_the_loops_data_left_out_is_its_missing_setting(tmp_path, config_store):
    err = refusal("loop", [], tmp_path)
    assert isinstance(err, MissingMandatoryValue) and err.full_key == "data"
    assert not list(tmp_path.iterdir())


def test_help_whose_reader_left_ends_without_a_traceback():
    """``python train.py --help | head -1``: the reader leaves before the help is printed
    (here: before the command starts, so the write always fails); the command ends quietly,
    exit 1 (it was a BrokenPipeError traceback)."""
    proc = subprocess.Popen([sys.executable, "train.py", "--help"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=ROOT)
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait(timeout=300) == 1, err
    assert "Traceback" not in err and "BrokenPipe" not in err, err


def imports_of_a_refusal(args: list[str], cwd: Path, says: str) -> set[str]:
    """The modules ``python -X importtime <args>`` imported (``-X importtime`` lists every one)
    before its refusal: one line saying ``says``, exit 2, no traceback."""
    proc = subprocess.run([sys.executable, "-X", "importtime", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=120)
    imported = {line.split("|")[-1].strip() for line in proc.stderr.splitlines()
                if line.startswith("import time:")}
    errors = [line for line in proc.stderr.splitlines() if line.startswith("error:")]
    assert proc.returncode == 2 and len(errors) == 1 and says in errors[0], proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr and "surrogate.settings" in imported  # listing read
    return imported


@pytest.mark.parametrize("bad, says", [
    ("case=9", "case = '9' is not an operating case"),
    ("model.lr=-1", "model.lr = -1.0 must lie in (0, 1)"),
    ("trainer.max_epochs=0", "trainer.max_epochs = 0 must be >= 1"),
    ("seed=-1", "seed = -1 must be a whole number >= 0"),
    ("data.table=missing.csv", "data.table = 'missing.csv' does not exist"),
    ("data.table=.", "data.table = '.' is a folder, not a file"),
])
def test_train_refuses_what_needs_no_data_before_importing_lightning(tmp_path, bad, says):
    """The settings judged without data or a model (surrogate.settings.check_run) are refused
    before train.py imports Lightning and torch (-X importtime lists every module imported):
    one line, exit 2, nothing left."""
    imported = imports_of_a_refusal([str(ROOT / "train.py"), bad, "hydra.run.dir=run"],
                                    tmp_path, says)
    assert not {"lightning", "torch"} & imported, sorted({"lightning", "torch"} & imported)
    assert not any(tmp_path.iterdir())


def test_train_refuses_a_tables_settings_before_importing_torch(tmp_path):
    """A user table's settings are judged by the run's data (surrogate.wear_data) before
    train.py imports torch (a run that fine-tunes none needs no network to check them): a
    group column it lacks, an input it lacks (named as absent, not asked for a unit), each in
    one line, exit 2, the table alone left."""
    (tmp_path / "t.csv").write_text("a,wear_mm,rig\n1,0,1\n2,0.1,1\n")
    for bad, says in ((["data.group=nope"], "data.group = 'nope' is not a column of t.csv"),
                      (["data.group=rig", "data.inputs=[b]", "data.target=wear_mm"],
                       "t.csv lacks column(s) ['b']")):
        imported = imports_of_a_refusal([str(ROOT / "train.py"), "data.table=t.csv", *bad,
                                         "hydra.run.dir=run"], tmp_path, says)
        assert "torch" not in imported and "lightning" not in imported
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]


@pytest.mark.parametrize("args, says", [
    (["ckpt=missing.pt", "input=in.csv"], "ckpt = 'missing.pt' does not exist"),
    (["ckpt=model.pt", "input=missing.csv"], "input = 'missing.csv' does not exist"),
    (["ckpt=model.pt", "input=in.csv", "output=in.csv"], "is the input file itself"),
])
def test_predict_refuses_its_files_before_importing_torch(tmp_path, args, says):
    """The files predict reads and writes are judged before the model's reader (torch) is
    imported (-X importtime lists every module imported): one line, exit 2, the files as
    they were."""
    (tmp_path / "model.pt").write_bytes(b"not read")
    (tmp_path / "in.csv").write_text("a\n1\n")
    imported = imports_of_a_refusal(["-m", "surrogate.predict", *args, "hydra.run.dir=run"],
                                    tmp_path, says)
    assert "torch" not in imported
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.csv", "model.pt"]
    assert (tmp_path / "in.csv").read_text() == "a\n1\n"
