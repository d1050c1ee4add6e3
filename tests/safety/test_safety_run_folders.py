"""A run folder the user chose is never filled over what it holds: ``hydra.run.dir`` (or
``hydra.sweep.dir`` with ``-m``) naming a folder that already holds anything (a user's
``metrics.json`` or ``report.md``, an earlier run's files) is refused before Hydra writes there,
one line, exit 2, the files as they were (``physics.command.check_run_folder``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from omegaconf import OmegaConf

from physics.command import RunRecord

ROOT = Path(__file__).resolve().parents[2]


def start_refused(key: str, node: dict) -> int:
    """The exit code with which RunRecord ends a run (``key`` ``hydra.run.dir``) or a sweep
    (``hydra.sweep.dir``) of the Hydra config ``{"hydra": node}`` before it starts."""
    config = OmegaConf.create({"hydra": node})
    with pytest.raises(SystemExit) as end:
        if key == "hydra.run.dir":
            RunRecord().on_run_start(config)
        else:
            RunRecord().on_multirun_start(config)
    return end.value.code


@pytest.mark.parametrize("key", ["hydra.run.dir", "hydra.sweep.dir"])
def test_a_run_folder_holding_files_is_refused_before_hydra_writes(tmp_path, capsys, key):
    (tmp_path / "metrics.json").write_text("my own figures")
    (tmp_path / "report.md").write_text("my own report")
    node = {"run": {"dir": str(tmp_path)}} if key == "hydra.run.dir" else {
        "sweep": {"dir": str(tmp_path)}, "launcher": {"_target_": "x"}}
    assert start_refused(key, node) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {key} = '{tmp_path}' already holds "
                                               "metrics.json and 1 more") and (
        f"give {key} a new or empty folder" in err[0]), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["metrics.json", "report.md"]
    assert (tmp_path / "metrics.json").read_text() == "my own figures"


def test_a_new_or_empty_run_folder_is_taken(tmp_path):
    (tmp_path / "empty").mkdir()
    for folder in (tmp_path / "empty", tmp_path / "new" / "run"):
        RunRecord().on_run_start(OmegaConf.create({"hydra": {"run": {"dir": str(folder)}}}))


def test_train_into_a_users_folder_leaves_it_as_it_was(tmp_path):
    """Through the main job's command: the user's metrics.json stays, nothing is added."""
    (tmp_path / "metrics.json").write_text("mine")
    run = subprocess.run([sys.executable, str(ROOT / "train.py"), f"hydra.run.dir={tmp_path}"],
                         capture_output=True, text=True, timeout=300, cwd=tmp_path.parent)
    assert run.returncode == 2, run.stderr
    assert run.stderr.strip().splitlines() == [run.stderr.strip()]
    assert "already holds metrics.json" in run.stderr
    assert [p.name for p in tmp_path.iterdir()] == ["metrics.json"]
    assert (tmp_path / "metrics.json").read_text() == "mine"


@pytest.mark.parametrize("override", ["hydra/launcher=cluster", "hydra/launcher=joblib",
                                      "hydra.sweeper.params.x=1,2", "+hydra.launcher.n_jobs=4"])
def test_a_sweep_setting_in_a_single_run_is_refused(tmp_path, capsys, override):
    """A launcher or sweeper chosen for a run without -m was ignored without a word (the run
    went on here, not on the cluster): refused before Hydra makes the run folder."""
    config = OmegaConf.create({"hydra": {"run": {"dir": str(tmp_path / "run")},
                                         "overrides": {"hydra": [override]}}})
    with pytest.raises(SystemExit) as end:
        RunRecord().on_run_start(config)
    assert end.value.code == 2
    assert capsys.readouterr().err.startswith(
        f"error: {override} sets how a sweep's jobs run (-m), and this is a single run")
    assert not (tmp_path / "run").exists()
    RunRecord().on_run_start(OmegaConf.create({"hydra": {
        "run": {"dir": str(tmp_path / "run")}, "overrides": {"hydra": ["hydra.job.chdir=false"]}}}))


def test_a_run_folder_on_a_full_disk_is_refused_before_hydra_writes(tmp_path, capsys,
                                                                     monkeypatch):
    """Hydra's own writes (.hydra/config.yaml) on a full disk ended in its traceback, before
    the app ran: a disk with less than ROOM_BYTES free is refused first, in one line."""
    import shutil

    from physics import command

    monkeypatch.setattr(shutil, "disk_usage", lambda _p: shutil._ntuple_diskusage(1, 1, 1000))
    with pytest.raises(SystemExit) as end:
        RunRecord().on_run_start(OmegaConf.create({"hydra": {"run": {
            "dir": str(tmp_path / "run")}}}))
    assert end.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: hydra.run.dir = '{tmp_path / 'run'}': the disk holding "
                          f"{tmp_path} has 1 KiB free, less than the "
                          f"{command.ROOM_BYTES // 1024**2} MiB") and "make room" in err, err
    assert not (tmp_path / "run").exists()
