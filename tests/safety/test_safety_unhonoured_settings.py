"""Every setting a training run cannot honour is refused before any work, in one line naming it
and the fix: ``init_from=m.pt data.sensors=[dte]`` (a network that reads acceleration
features). Also refused: the default inputs' choice beside
``data.inputs``, another shape for a fine-tune, the physics dataset's build settings beside a
table of one's own, and ``data.inputs=[]``."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from surrogate.training import prepare

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(Path(__file__).parent))
from test_safety_user_tables import table, train_cfg  # noqa: E402


@pytest.fixture(scope="module")
def network(small_model) -> Path:
    """A small network trained for one epoch on a user table (every default input: both
    sensors' features and the operating point)."""
    return small_model("network")


def refused(network: Path, tmp_path: Path, *overrides: str) -> str:
    table().to_csv(tmp_path / "in.csv", index=False)
    with pytest.raises(ValueError) as err:
        prepare(train_cfg(tmp_path, *overrides, table="in.csv"))
    text = str(err.value)
    assert "\n" not in text
    assert not (tmp_path / "run").exists()
    return text


@pytest.mark.parametrize(("setting", "named"), [
    ("data.sensors=[dte]", "data.sensors = ['dte']"),
    ("data.operating_point=false", "data.operating_point = False"),
])
def test_a_fine_tune_refuses_a_choice_of_other_inputs(network, tmp_path, setting, named):
    text = refused(network, tmp_path, f"init_from={network}", setting)
    assert text.startswith(f"init_from = {network}: a fine-tune reads that network's inputs "
                           "['dte_peak_to_peak', "), text
    assert "'acc_kurtosis', 'acc_crest'" in text and f"and {named} asks for others" in text
    assert text.endswith(f"drop {named.split(' = ')[0]}, or train from scratch on them "
                         "(without init_from)"), text


def test_a_fine_tune_takes_a_choice_that_gives_its_network_s_inputs(network, tmp_path):
    """The same inputs chosen again are honoured: nothing to refuse."""
    table().to_csv(tmp_path / "in.csv", index=False)
    job = prepare(train_cfg(tmp_path, f"init_from={network}", "data.sensors=[dte,acc]",
                            "data.operating_point=true", table="in.csv"))
    assert job.data.inputs[-2:] == ["n1_rpm", "torque_Nm"]


def test_a_fine_tune_refuses_another_shape(network, tmp_path):
    text = refused(network, tmp_path, f"init_from={network}", "model.width=64")
    assert text == (f"model.width = 64: a fine-tune keeps the shape of its network (init_from "
                    f"= {network}: width 16); drop model.width, or train from scratch (without "
                    "init_from)")


def test_sensors_beside_named_inputs_are_refused(network, tmp_path):
    text = refused(network, tmp_path, "data.sensors=[dte]",
                   "data.inputs=[dte_kurtosis,acc_crest]")
    assert text == ("data.sensors = ['dte'] choose the default inputs, but data.inputs names "
                    "the inputs (['dte_kurtosis', 'acc_crest']): drop data.sensors, or "
                    "data.inputs")


def test_the_physics_dataset_s_build_settings_beside_a_table_are_refused(network, tmp_path):
    text = refused(network, tmp_path, "data.gearboxes=64")
    assert text.startswith("data.gearboxes = 64 set how the physics dataset is built, and "
                           "this run reads your table"), text
    assert text.endswith("drop data.gearboxes")


def test_an_empty_list_of_inputs_is_refused_as_such(network, tmp_path):
    text = refused(network, tmp_path, "data.inputs=[]")
    assert text == ("data: data.inputs = [] names no input; give the feature columns "
                    "(data.inputs=[fme15,acc_rms]) or leave data.inputs unset (null) for the "
                    "default inputs of data.sensors")
    assert "acc_kurtosis" not in text


def test_the_command_refuses_the_issue_s_fine_tune_in_one_line(network, tmp_path):
    """As a user types it: exit 2, one ``error:`` line, nothing trained, no run folder left;
    refused before Lightning's import (``-X importtime`` lists every module imported)."""
    table().to_csv(tmp_path / "in.csv", index=False)
    env = {k: v for k, v in os.environ.items() if not k.startswith("HYDRA_")}
    run = subprocess.run([sys.executable, "-X", "importtime", str(ROOT / "train.py"),
                          f"data.table={tmp_path}/in.csv", "data.group=rig",
                          f"init_from={network}", "data.sensors=[dte]"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=300, env=env)
    assert run.returncode == 2, run.stderr[-2000:]
    lines = [ln for ln in run.stderr.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1 and "data.sensors = ['dte'] asks for others" in lines[0], run.stderr
    assert "Traceback" not in run.stderr
    imported = {ln.split("|")[-1].strip() for ln in run.stderr.splitlines()
                if ln.startswith("import time:")}
    assert "torch" in imported and "lightning" not in imported
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.csv"]
