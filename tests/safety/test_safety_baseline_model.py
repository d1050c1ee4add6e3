"""Item 4: a baseline model (data.baseline=true) refuses what it cannot read, naming the
gearbox: a gearbox of a single row, rows out of time order where cycles are given, a gearbox
whose first row is not its baseline record (where its true wear is given)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from surrogate.inference import Surrogate, check_gearboxes
from surrogate.inputs import CONDITIONS, DEFAULT_INPUTS
from surrogate.training import train
from tests.acceptance.refusal import refusal

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(Path(__file__).parent))
from test_safety_user_tables import table, train_cfg  # noqa: E402


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("baseline")
    df = table(groups=8).rename(columns={"root_wear_mm": "mean_wear_mm"})
    df.to_csv(tmp / "mine.csv", index=False)
    # the table's features (the default inputs), read as changes since each baseline record
    inputs = ",".join([*DEFAULT_INPUTS, *CONDITIONS])
    assert np.isfinite(train(train_cfg(tmp, "data.baseline=true", f"data.inputs=[{inputs}]",
                                       val_replicates=2)))
    return tmp / "run" / "wear_surrogate.pt"


def rows() -> pd.DataFrame:
    return table(groups=3).rename(columns={"root_wear_mm": "mean_wear_mm"})


def test_a_readable_table_is_read(model):
    s = Surrogate.load(model)
    assert s.schema.baseline
    out = s.predict(rows().drop(columns="mean_wear_mm"), ["rig"])
    assert len(out) == 15


@pytest.mark.parametrize(("change", "message"), [
    (lambda d: d[(d.rig != "rig1") | (d.cycles == 0)],
     r"gearbox \{'rig': 'rig1'\} has a single row"),
    (lambda d: d.iloc[[0, 2, 1, 3, 4, *range(5, 15)]],
     r"gearbox \{'rig': 'rig0'\}: rows 1 and 2 are out of time order \(cycles 2e\+06 then "
     r"1e\+06\).*sort each gearbox's rows by cycles"),
    (lambda d: d.drop(columns="cycles").iloc[[*range(5), 9, 5, 6, 7, 8, *range(10, 15)]],
     r"gearbox \{'rig': 'rig1'\} has no baseline record: its first row \(row 5\)"),
])
def test_what_a_baseline_model_cannot_read_is_refused(model, change, message):
    s = Surrogate.load(model)
    with pytest.raises(ValueError, match=message) as err:
        s.predict(change(rows()).reset_index(drop=True), ["rig"])
    assert "\n" not in str(err.value)


def test_check_gearboxes_with_two_key_columns():
    df = pd.DataFrame({"a": [1, 1, 2], "b": ["x", "x", "y"], "cycles": [0.0, 1.0, 0.0]})
    with pytest.raises(ValueError, match=r"gearbox \{'a': 2, 'b': 'y'\} has a single row"):
        check_gearboxes(df, ["a", "b"])


def test_acceptance_predict_refuses_a_single_row_gearbox(model, tmp_path):
    """The command refuses it before it writes, in one line naming the gearbox (a refusal's
    exit path: tests/acceptance/test_bad_input.py)."""
    d = rows()
    d = d[(d.rig != "rig2") | (d.cycles == 0)].drop(columns="mean_wear_mm")
    d.to_csv(tmp_path / "in.csv", index=False)
    err = refusal("predict", [f"ckpt={model}", f"input={tmp_path / 'in.csv'}", "gearbox=rig",
                              f"output={tmp_path / 'w.csv'}"], tmp_path)
    assert isinstance(err, ValueError) and "\n" not in str(err)
    assert "gearbox {'rig': 'rig2'} has a single row" in str(err)
    assert not (tmp_path / "w.csv").exists()
