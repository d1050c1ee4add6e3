"""A refused run removes only what it made: the record taken before Hydra made the run folder;
a run that leaves the model's scope ends in one line."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from omegaconf import OmegaConf

from physics import command
from physics.loop.measured.bundle import write_bundle
from physics.params import OutOfScope


def _refuse_in(folder: Path) -> None:
    """What a refused app does: Hydra makes its folder and files, then the refusal undoes them."""
    command._BEFORE.clear()
    command._record_before(folder)
    (folder / ".hydra").mkdir(parents=True, exist_ok=True)
    (folder / ".hydra" / "config.yaml").write_text("x: 1\n")
    (folder / "__main__.log").write_text("")
    with pytest.raises(SystemExit) as exit_:
        command.refuse(ValueError("bad"), folder)
    assert exit_.value.code == 2


def test_user_files_in_the_run_folder_stay(tmp_path):
    (tmp_path / "notebook.log").write_text("notes")
    (tmp_path / "results").mkdir()
    _refuse_in(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notebook.log", "results"]


def test_a_new_chain_of_folders_goes_but_not_the_parent(tmp_path):
    (tmp_path / "mine.log").write_text("mine")
    _refuse_in(tmp_path / "logs" / "deep" / "run")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.log"]


def test_a_user_folder_that_held_only_logs_stays(tmp_path):
    logs = tmp_path / "mylogs"
    logs.mkdir()
    (logs / "a.log").write_text("a")
    (logs / "b.log").write_text("b")
    _refuse_in(logs)
    assert sorted(p.name for p in logs.iterdir()) == ["a.log", "b.log"]


def test_a_job_folder_of_a_recorded_sweep_counts_as_made(tmp_path):
    command._BEFORE.clear()
    sweep = tmp_path / "sweep"
    command._record_before(sweep)
    job = sweep / "0"
    (job / ".hydra").mkdir(parents=True)
    with pytest.raises(SystemExit):
        command.refuse(ValueError("bad"), job)
    assert list(tmp_path.iterdir()) == []


def test_without_a_record_nothing_is_removed(tmp_path):
    command._BEFORE.clear()
    (tmp_path / ".hydra").mkdir()
    with pytest.raises(SystemExit):
        command.refuse(ValueError("bad"), tmp_path)
    assert (tmp_path / ".hydra").is_dir()


def test_refused_loop_run_in_the_working_folder_keeps_the_users_files(tmp_path):
    """The app as typed: ``hydra.run.dir=.`` in a folder holding the user's notebook is refused
    before Hydra writes there; in an empty one, a refused run leaves it empty."""
    man = pd.DataFrame({"record": ["r0", "r1", "r2"], "quantity": "dte_m", "fs_hz": 40960.0,
                        "n1_rpm": 2000.0, "torque_Nm": 300.0, "wear_mm": [0.0, 0.005, 0.01],
                        "cycles": "", "split": ""})
    sig = {r: np.random.default_rng(0).normal(size=16384) * 1e-6 for r in man.record}
    sig["r1"][5] = np.nan
    data = write_bundle(tmp_path / "bundle", man, sig)
    work = tmp_path / "work"
    work.mkdir()
    (work / "notebook.log").write_text("notes")
    run = subprocess.run([sys.executable, "-m", "physics.loop", f"data={data}",
                          "hydra.run.dir=."], cwd=work, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 2, run.stderr
    assert "hydra.run.dir = '.' already holds notebook.log" in run.stderr, run.stderr
    assert [p.name for p in work.iterdir()] == ["notebook.log"]
    assert (work / "notebook.log").read_text() == "notes"
    (work / "notebook.log").unlink()  # an empty folder is taken; the refused run leaves it so
    run = subprocess.run([sys.executable, "-m", "physics.loop", f"data={data}",
                          "hydra.run.dir=."], cwd=work, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 2, run.stderr
    assert "non-finite sample" in run.stderr and "Traceback" not in run.stderr
    assert not list(work.iterdir())


@dataclasses.dataclass
class _Config:
    x: int = 1


def test_a_run_that_leaves_the_models_scope_ends_in_one_line(capsys):
    """The physics stopped, not the code: one line and exit code 1 (the run folder kept); any
    other error in the work keeps its traceback."""
    cfg = OmegaConf.structured(_Config)

    def out_of_scope(_plan):
        raise OutOfScope("the worn flanks no longer meet as one line contact")

    with pytest.raises(SystemExit) as exit_:
        command.run_command(cfg, lambda c: c.x, out_of_scope)
    assert exit_.value.code == 1 and exit_.value.__cause__ is None
    assert capsys.readouterr().err == ("error: out of the model's scope: the worn flanks no "
                                       "longer meet as one line contact\n")

    def bug(_plan):
        raise RuntimeError("a bug")

    with pytest.raises(RuntimeError, match="a bug"):
        command.run_command(cfg, lambda c: c.x, bug)
