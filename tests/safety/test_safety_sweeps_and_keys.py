"""A sweep's jobs are checked together before any starts, and one job's failure never stops
another; a key an app does not have (``+foo=1``) and a ``task_name`` outside ``logs/`` are
refused before any work, in one line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from hydra import compose, initialize_config_module
from hydra.core.global_hydra import GlobalHydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import open_dict

from physics import command
from tests.safety.test_safety_early_refusals import imports_of_a_refusal

ROOT = Path(__file__).resolve().parents[2]
APP = Path(__file__).parent / "apps" / "sweep_app.py"


def _run(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(APP), *args, "hydra.sweep.dir=sweep",
                           "hydra.run.dir=run"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)


def test_a_bad_job_refuses_the_whole_sweep_before_any_starts(tmp_path):
    run = _run(tmp_path, "-m", "x=1,-2,3")
    assert run.returncode == 2, run.stderr
    errors = [ln for ln in run.stderr.splitlines() if ln.startswith("error:")]
    assert errors == ["error: job 1 of the sweep (x=-2): x = -2 must be >= 0; no job was "
                      "started: fix or drop that value and run the sweep again"]
    assert "Traceback" not in run.stderr and not list(tmp_path.iterdir())


@pytest.mark.parametrize("launcher", ["basic", "joblib"])
def test_a_failing_job_does_not_stop_the_others(tmp_path, launcher):
    run = _run(tmp_path, "-m", "x=1,13,3", f"hydra/launcher={launcher}")
    assert run.returncode == 1, run.stderr
    errors = [ln for ln in run.stderr.splitlines() if ln.startswith("error:")]
    assert len(errors) == 1 and "1 of 3 jobs of the sweep failed: job 1 (x=13) failed: " \
        "RuntimeError: thirteen" in errors[0], run.stderr
    sweep = tmp_path / "sweep"
    assert (sweep / "0" / "done.txt").read_text() == "1"
    assert (sweep / "2" / "done.txt").read_text() == "3"
    assert "thirteen" in (sweep / "1" / command.FAILED).read_text()
    again = _run(tmp_path, "-m", "x=1,2,3", f"hydra/launcher={launcher}")  # same folder
    assert again.returncode == 2 and "hydra.sweep.dir = 'sweep' already holds 0 and 3 more" \
        in again.stderr, again.stderr  # the earlier sweep's records are not written over
    assert (sweep / "0" / "done.txt").read_text() == "1"
    assert "thirteen" in (sweep / "1" / command.FAILED).read_text()


def test_train_sweep_with_a_bad_case_is_refused_before_the_good_one_starts(tmp_path):
    """Every job's settings that need no data are judged before the first job's full check,
    which imports Lightning and torch (-X importtime lists every module imported)."""
    imported = imports_of_a_refusal(
        [str(ROOT / "train.py"), "-m", "case=3,9"], tmp_path,
        "job 1 of the sweep (case=9): case = '9' is not an operating case")
    assert not {"lightning", "torch"} & imported
    assert not list(tmp_path.iterdir())


APPS = {"dataset": ("gearwear_conf.dataset", "dataset"),
        "reproduce": ("gearwear_conf.reproduce", "reproduce"),
        "loop": ("gearwear_conf.loop", "loop"),
        "predict": ("gearwear_conf.predict", "predict"),
        "train": ("gearwear_conf.train", "train")}


def _composed(app: str, overrides: list[str]):
    """The app's config as Hydra composes it for a run, with Hydra's runtime config set."""
    from physics.command import register_schema
    from physics.dataset.generation import DatasetConfig
    from physics.loop.config import LoopConfig
    from physics.reproduce.thesis import ReproduceConfig
    from surrogate import settings

    for name, schema in (("dataset_schema", DatasetConfig), ("loop_schema", LoopConfig),
                         ("reproduce_schema", ReproduceConfig)):
        register_schema(name, schema)  # as the apps do

    if app == "train":
        settings.register()
    module, name = APPS[app]
    GlobalHydra.instance().clear()
    with initialize_config_module(module, version_base="1.3"):
        cfg = compose(name, overrides=overrides, return_hydra_config=True)
        with open_dict(cfg):
            cfg.hydra.runtime.output_dir = "/tmp/unused"
            cfg.hydra.job.name = name
        HydraConfig.instance().set_config(cfg)
        task = cfg.copy()
        with open_dict(task):
            del task["hydra"]
        yield task
    GlobalHydra.instance().clear()


@pytest.mark.parametrize("app", sorted(APPS))
def test_an_unknown_key_is_refused_naming_it_and_the_allowed_keys(app, config_store):
    ok = ["ckpt=a", "input=b"] if app == "predict" else []
    for cfg in _composed(app, [*ok]):
        command.check_keys(cfg)  # the app's own config passes
    for cfg in _composed(app, [*ok, "+foo=1"]):
        with pytest.raises(ValueError, match=r"^foo = 1: this command has no key foo; the "
                                             r"top-level keys are .*") as err:
            command.check_keys(cfg)
        listed = str(err.value).split("top-level keys are ")[1].split(" (")[0].split(", ")
        assert {k for k in cfg if k != "foo"} <= set(listed) and "foo" not in listed
    nested = {"train": "+model.foo=1", "predict": None}.get(app, "+gear.foo=1")
    if nested:
        for cfg in _composed(app, [*ok, nested]):
            with pytest.raises(ValueError, match=r"has no key (model|gear)\.foo; the keys of "):
                command.check_keys(cfg)


def test_open_groups_take_added_keys(config_store):
    for cfg in _composed("train", ["+data.generate.replicates=4", "+data.columns.p2p=x"]):
        command.check_keys(cfg)


@pytest.mark.parametrize("name", ["../../x", "/abs/x", "a/../../y"])
def test_a_task_name_outside_logs_is_refused(name, tmp_path, config_store, monkeypatch):
    from surrogate.training import prepare

    monkeypatch.chdir(tmp_path)
    for cfg in _composed("train", [f"task_name={name}"]):
        with open_dict(cfg):
            cfg.paths.root_dir = str(tmp_path)
            cfg.paths.output_dir = str(tmp_path / "out")
        with pytest.raises(ValueError, match=rf"^task_name = '{name}' puts .* outside "
                                             rf"{tmp_path / 'logs'}; use a plain name"):
            prepare(cfg)


def test_a_refused_run_folder_spelled_with_dots_is_undone(tmp_path):
    """``logs/../../x/runs/r``: Hydra makes ``logs`` on the way; both go on refusal."""
    work = tmp_path / "a" / "work"
    work.mkdir(parents=True)
    (tmp_path / "a" / "mine.txt").write_text("mine")
    command._BEFORE.clear()
    spelled = work / "logs" / ".." / ".." / "x" / "runs" / "r"
    command._record_before(spelled)
    spelled.mkdir(parents=True)
    (spelled / "train.log").write_text("")
    with pytest.raises(SystemExit):
        command.refuse(ValueError("bad"), Path(str(tmp_path / "a" / "x" / "runs" / "r")))
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["mine.txt", "work"]
    assert not list(work.iterdir())


@pytest.mark.parametrize(("override", "key"), [("speeds_rpm=[1000,-100]", "speeds_rpm"),
                                               ("torques_Nm=[-5]", "torques_Nm")])
def test_a_bad_list_entry_is_blamed_on_its_list(override, key, tmp_path, config_store):
    from physics.reproduce.thesis import prepare

    for cfg in _composed("reproduce", [override, f"out_dir={tmp_path / 'out'}"]):
        with pytest.raises(ValueError, match=rf"^{key}: the entry -[\d.]+ is refused: "
                                             rf"operating\.\w+ = .*; change or drop that entry "
                                             rf"of {key}$"):
            prepare(cfg)
    assert not list(tmp_path.iterdir())


def test_an_interrupted_sweep_says_truly_what_it_keeps(tmp_path, monkeypatch):
    """Before any job's folder is made the line says nothing was computed (it said finished
    jobs were kept); after, how many of the jobs had started and where their folders are."""
    sweep = tmp_path / "sweep"
    jobs = [command.SweepJob(n, (f"x={n}",), sweep / str(n)) for n in range(3)]
    monkeypatch.setattr(command, "_JOBS", jobs)
    assert command.sweep_kept(sweep) == "no job of the sweep had started; nothing was computed"
    (sweep / "0").mkdir(parents=True)
    (sweep / "1").mkdir()
    assert command.sweep_kept(sweep).startswith(
        f"2 of 3 of the sweep's jobs had started; their folders are kept in {sweep}")
    monkeypatch.setattr(command, "_JOBS", [])  # another sweeper: its folders as they are
    assert command.sweep_kept(sweep).startswith("2 of the sweep's jobs had started")
    assert command.sweep_kept(tmp_path / "none").startswith("no job of the sweep had started")
