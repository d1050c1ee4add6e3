"""The operating point a model was trained at, kept with it and checked at every reading
(surrogate.inputs.operating_columns, FeatureSchema.operating_outside): which columns state it,
the range and its margin by hand, the file round trip, and the public rig's table trained at
its 15 rev/s and read as if measured at 45, where no feature tells the model so."""

from __future__ import annotations

import logging

import numpy as np
import pandas as pd
import pytest
from hydra import compose, initialize_config_module

from physics.reference import RIG_RECORDS
from surrogate import settings
from surrogate.inference import Surrogate
from surrogate.inputs import operating_columns
from surrogate.schema import FeatureSchema
from surrogate.training import train


def test_the_columns_that_state_the_operating_point():
    """By name (the dataset's n1_rpm, a word of speed, rpm, rps, torque, load) or by a unit of
    speed or torque; never an input, the target, or a column that is not a finite number."""
    frame = pd.DataFrame({"n1_rpm": [900.0], "Speed_rps": [15.0], "shaft": [15.0],
                          "load": ["L10"], "torque_Nm": [100.0], "acc_rms": [0.1],
                          "wear_mm": [0.0], "stage": [1]})
    units = {"shaft": "rev/s", "acc_rms": "g", "wear_mm": "mm"}
    assert operating_columns(frame, units, ["acc_rms", "torque_Nm"], ["wear_mm"]) == [
        "n1_rpm", "Speed_rps", "shaft"]
    assert operating_columns(frame, {}, [], ["n1_rpm"]) == ["Speed_rps", "torque_Nm"]


def schema(low: tuple, high: tuple, names=("speed", "torque_Nm")) -> FeatureSchema:
    return FeatureSchema(("x",), ("1",), "wear_mm", "mm", (0.0,), (1.0,), (0.0,), (1.0,), 1.0,
                         operating=names, operating_low=low, operating_high=high)


def test_a_row_outside_the_training_operating_point_is_flagged_by_hand():
    """Speed trained at 15 alone: +-5 % of 15 (0.75) is the same; torque over 100-200: 5 %
    of 200 (10, more than 5 % of the range, 5). A value that is not a number is outside."""
    s = schema((15.0, 100.0), (15.0, 200.0))
    rows = pd.DataFrame({"x": 0.5, "speed": [15.0, 15.74, 15.76, 14.2, 15.0, 15.0, np.nan],
                         "torque_Nm": [150.0, 150.0, 150.0, 150.0, 90.5, 209.0, 150.0]})
    outside, named, missing = s.operating_outside(rows)
    assert outside.tolist() == [False, False, True, True, False, False, True]
    assert named == ["speed"] and missing == []
    rows.loc[4, "torque_Nm"] = 89.0
    assert s.operating_outside(rows)[0][4] and s.operating_outside(rows)[1] == ["speed",
                                                                                "torque_Nm"]
    line = s.operating_line(rows)
    assert "3 of 7 rows were measured" in line and "speed 15, torque_Nm 100-200 in training" in line
    assert "1 of 7 rows give no number for speed, torque_Nm" in line
    outside, _, missing = s.operating_outside(rows.drop(columns="speed"))
    assert missing == ["speed"] and outside.sum() == 1
    assert "no column speed" in s.operating_line(rows.drop(columns="speed"))
    assert schema((), (), ()).operating_line(rows) is None


def test_the_operating_range_survives_the_file_and_is_checked_on_load():
    """The range round-trips; a file without it (an older model) checks nothing; a range of
    another length, reversed, not finite or not numbers is refused."""
    s = schema((15.0, 100.0), (15.0, 200.0))
    assert FeatureSchema.from_dict(s.to_dict()) == s
    older = {k: v for k, v in s.to_dict().items() if not k.startswith("operating")}
    assert FeatureSchema.from_dict(older).operating == ()
    for low, high in (((15.0,), (15.0, 200.0)), ((16.0, 100.0), (15.0, 200.0)),
                      ((np.nan, 100.0), (15.0, 200.0)), (("a", 100.0), (15.0, 200.0))):
        with pytest.raises(ValueError, match="operating range"):
            FeatureSchema.from_dict({**s.to_dict(), "operating_low": list(low),
                                     "operating_high": list(high)})


def rig_cfg(tmp, *overrides: str):
    """A run on the public rig's records written to ``tmp / rig.csv``: wear from the RMS and
    the FM energy, every stage but eight training."""
    settings.register()
    with initialize_config_module("gearwear_conf.train", version_base="1.3"):
        return compose("train", overrides=[
            f"paths.root_dir={tmp}", f"paths.output_dir={tmp / 'run'}",
            f"data.dataset={tmp / 'unused.parquet'}", f"data.table={tmp / 'rig.csv'}",
            "data.inputs=[acc_rms_g,fm_energy]", "data.target=wear_mm",
            "data.units={acc_rms_g: g, fm_energy: '1', wear_mm: mm}", "data.group=stage",
            "data.val_replicates=4", "data.test_replicates=4", "logger=csv", *overrides])


@pytest.fixture(scope="module")
def rig_model(tmp_path_factory):
    """A linear model of the public rig's records (its RMS and FM energy; every stage but
    four validating), the table stating its 15 rev/s in a column."""
    tmp = tmp_path_factory.mktemp("rig_speed")
    rig = pd.read_csv(RIG_RECORDS).assign(speed_rps=15.0)
    rig.to_csv(tmp / "rig.csv", index=False)
    train(rig_cfg(tmp, "model.kind=linear", "trainer.enable_progress_bar=false",
                  "trainer.max_epochs=2", "trainer.min_epochs=1", "model.members=2"))
    return Surrogate.load(tmp / "run" / "wear_surrogate.pt"), rig


def test_the_real_rig_read_at_another_speed_is_flagged_in_every_row(rig_model, caplog):
    """Its features alone do not tell 45 rev/s from a worn gear at 15; the stated speed does:
    every row flagged, said in one line; at 15 rev/s the flags are the novelty's alone."""
    model, rig = rig_model
    assert model.schema.operating == ("speed_rps",)
    at15 = model.predict(rig)
    with caplog.at_level(logging.WARNING, logger="surrogate.inference"):
        at45 = model.predict(rig.assign(speed_rps=45.0))
    assert at45.out_of_range.all() and at15.out_of_range.mean() < 0.5
    assert np.array_equal(at45.wear_mm_pred, at15.wear_mm_pred)  # the reading itself: the same
    said = [r.getMessage() for r in caplog.records if "operating point" in r.getMessage()]
    assert len(said) == 1 and "530 of 530 rows" in said[0] and "speed_rps 15" in said[0]
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="surrogate.inference"):
        unstated = model.predict(rig.drop(columns="speed_rps"))
    assert np.array_equal(unstated.out_of_range, at15.out_of_range)
    assert any("no column speed_rps" in r.getMessage() for r in caplog.records)


def test_an_operating_column_that_is_not_a_number_is_said_unchecked(tmp_path, caplog):
    """A speed written as text ("15 rps") or with a gap cannot be checked: not kept, and the
    run says so before training."""
    from surrogate.training import prepare

    frame = pd.DataFrame({"speed": ["15 rps", "15 rps"], "torque_Nm": [100.0, np.nan],
                          "n1_rpm": [900.0, 900.0]})
    assert operating_columns(frame, {}, []) == ["n1_rpm"]
    rig = pd.read_csv(RIG_RECORDS).assign(speed="15 rps")
    rig.to_csv(tmp_path / "rig.csv", index=False)
    with caplog.at_level(logging.WARNING, logger="surrogate.wear_data"):
        job = prepare(rig_cfg(tmp_path))
    assert job.data.operating == []
    assert any("['speed']" in r.getMessage() and "not a number in every row" in r.getMessage()
               for r in caplog.records)
