"""A user's own table: his feature columns as inputs with their units (data.inputs, data.units
or a sidecar), splits he chooses (data.group_by with test and validation groups by value,
leave-one-group-out cross-validation), outputs in his terms (run folder, ids, pass-through
columns), and the median, linear and estimator baselines beside the network in every run.

The table: one rig at two shaft speeds (15 and 45 rev/s) over 12 wear stages, two records a
stage, with an acceleration RMS and a frequency-modulation energy feature (``fme15``, a name
the project does not know)."""

from __future__ import annotations

import json
import logging
import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hydra import compose, initialize_config_module

from physics.estimators.empirical_inverse import wear_errors
from surrogate import settings
from surrogate.baselines import not_better_line
from surrogate.candidates import Candidate
from surrogate.inference import Surrogate
from surrogate.predict import predict_file
from surrogate.training import prepare, train
from tests.acceptance.refusal import refusal

ROOT = Path(__file__).resolve().parents[2]
INPUTS = "data.inputs=[fme15,acc_rms]"


def rig_table(stages: int = 12, records: int = 2, seed: int = 0) -> pd.DataFrame:
    """One rig, two speeds, ``stages`` wear stages from new to 0.6 mm, ``records`` a stage."""
    rng = np.random.default_rng(seed)
    rows = []
    for speed in (15, 45):
        for stage in range(stages):
            wear = 0.6 * (stage / (stages - 1)) ** 1.3
            for r in range(records):
                rows.append({
                    "rig": "A", "speed": speed, "stage": stage, "record": f"s{speed}_{stage}_{r}",
                    "acc_rms": (0.2 + 0.01 * speed) * (1 + 1.5 * wear) * rng.normal(1, 0.02),
                    "fme15": (0.5 + 3 * wear**1.2) * (1 + 0.002 * speed) * rng.normal(1, 0.03),
                    "wear_mm": wear})
    return pd.DataFrame(rows)


def write(tmp: Path, df: pd.DataFrame | None = None, sidecar: str | None = "fme15: m/s^2\n"
          ) -> Path:
    path = tmp / "rig.csv"
    (rig_table() if df is None else df).to_csv(path, index=False)
    if sidecar is not None:
        (tmp / "rig.units.yaml").write_text(sidecar)
    return path


def cfg(tmp: Path, *overrides: str, epochs: int = 3, units: str = "wear_mm: mm"):
    """A small run on ``tmp / rig.csv``: wear_mm (by ``units``, data.units) from the user's
    columns."""
    settings.register()
    with initialize_config_module("gearwear_conf.train", version_base="1.3"):
        return compose("train", overrides=[
            f"paths.root_dir={tmp}", f"paths.output_dir={tmp / 'run'}",
            f"data.dataset={tmp / 'unused.parquet'}", f"data.table={tmp / 'rig.csv'}",
            INPUTS, "data.target=wear_mm", f"data.units={{{units}}}",
            "trainer.enable_progress_bar=false", f"trainer.max_epochs={epochs}",
            "trainer.min_epochs=1", "model.members=2", "logger=csv", *overrides])


BY_SPEED = ("data.group=stage", "data.group_by=speed", "data.test_groups=[45]",
            "data.val_replicates=3")


@pytest.fixture(scope="module")
def by_speed(tmp_path_factory) -> Path:
    """Trained at 15 rev/s (three stages of it validate), tested at 45."""
    tmp = tmp_path_factory.mktemp("by_speed")
    write(tmp)
    assert np.isfinite(train(cfg(tmp, *BY_SPEED)))
    return tmp / "run"


# -- 1. any column as input ---------------------------------------------------------------------

def test_acceptance_a_users_own_columns_are_inputs_and_the_checkpoint_records_them(by_speed):
    s = Surrogate.load(by_speed / "wear_surrogate.pt")
    assert s.schema.inputs == ("fme15", "acc_rms")
    assert s.schema.units == ("m/s^2", "m/s^2")  # fme15's from the sidecar, acc_rms ours
    assert (s.schema.target, s.schema.target_unit) == ("wear_mm", "mm")  # by data.units
    train_rows = pd.read_csv(by_speed.parent / "rig.csv").query("speed == 15")
    # standardised with the training rows (15 rev/s less the three validating stages)
    assert s.schema.mean[0] == pytest.approx(train_rows.fme15.mean(), rel=0.2)
    assert s.schema.high[0] <= train_rows.fme15.max() and s.schema.std[0] > 0


def test_acceptance_predict_requires_the_users_columns_and_passes_the_rest_through(by_speed,
                                                                                     tmp_path):
    """The command refuses a table without a column the model reads, in one line naming it and
    its unit, before it writes (a refusal's exit path: tests/acceptance/test_bad_input.py)."""
    rows = rig_table(seed=5).assign(note="bench B")
    rows.drop(columns="fme15").to_csv(tmp_path / "no_fme.csv", index=False)
    err = refusal("predict", [f"ckpt={by_speed / 'wear_surrogate.pt'}",
                              f"input={tmp_path / 'no_fme.csv'}", f"output={tmp_path / 'w.csv'}"],
                  tmp_path)
    assert isinstance(err, ValueError) and "\n" not in str(err)
    assert "lacks column(s) ['fme15']" in str(err) and "'fme15': 'm/s^2'" in str(err)
    assert not (tmp_path / "w.csv").exists()
    rows.to_csv(tmp_path / "in.csv", index=False)
    out = predict_file(by_speed / "wear_surrogate.pt", tmp_path / "in.csv", tmp_path / "w.csv")
    assert list(out.columns[:6]) == ["rig", "speed", "stage", "record", "wear_mm", "note"]
    assert (out.note == "bench B").all() and out.wear_mm_pred.notna().all()


@pytest.mark.parametrize(("units", "sidecar", "change", "message"), [
    ("wear_mm: mm", None, None, r"column\(s\) \['fme15'\] have no unit; give them with "
                                r"data.units=\{fme15: UNIT\} or in rig.units.yaml"),
    ("wear_mm: mm, fme15: m/s2", None, lambda d: d.assign(fme15=d.fme15 * 1e6),
     r"row 1, column 'fme15' = 512959 lies outside \[0, 100000\], what its unit m/s\^2 allows"),
    ("wear_mm: mm", "fme15: '1'\n",
     lambda d: d.assign(fme15=np.where(d.index == 4, np.inf, d.fme15)),
     r"row 5, column 'fme15' = inf is not a finite number"),
    ("wear_mm: mm", "fme15: V\n",
     lambda d: d.assign(fme15=np.where(d.stage == 3, d.fme15 * 1e3, d.fme15)),
     r"column 'fme15' has a median of .* in group 3 but .* mixed units; give every group in V"),
    ("wear_mm: mm", "fme15: [m]\n", None, r"rig.units.yaml must map column names to units"),
])
def test_a_users_columns_are_checked_by_the_units_he_gives(tmp_path, units, sidecar,
                                                           change, message):
    df = rig_table()
    write(tmp_path, change(df) if change else df, sidecar)
    with pytest.raises(ValueError, match=message) as err:
        prepare(cfg(tmp_path, "data.group=stage", "data.val_replicates=2",
                    "data.test_replicates=2", units=units))
    assert "\n" not in str(err.value)


# -- 2. splits a user chooses -------------------------------------------------------------------

def test_acceptance_train_at_one_speed_test_at_the_other_outputs_keep_the_users_ids(by_speed):
    pred = pd.read_csv(by_speed / "test_predictions.csv")
    assert set(pred.speed) == {45} and len(pred) == 24  # every row at 45, none at 15
    assert {"rig", "stage", "record", "wear_mm", "wear_mm_pred"} <= set(pred.columns)
    assert "replicate" not in pred.columns and "case" not in pred.columns
    assert pred.record.str.startswith("s45_").all()
    log = (by_speed / "train.log").read_text() if (by_speed / "train.log").exists() else ""
    assert "case 0" not in log


def test_splits_name_groups_by_value_and_refuse_in_the_users_terms(tmp_path):
    write(tmp_path)
    job = prepare(cfg(tmp_path, "data.group=stage", "data.test_groups=[10,11]",
                      "data.val_groups=[0.0,5]"))
    job.data.setup()
    stages = {k: set(job.data.labels.stage.iloc[f.row]) for k, f in job.data.frames.items()}
    assert stages == {"test": {10, 11}, "val": {0, 5}, "train": set(range(1, 10)) - {5},
                      "cal": {0, 5}}  # two validation groups: they also calibrate
    with pytest.raises(ValueError, match=r"data.test_groups = \[46\]: column 'speed' of .*rig.csv "
                                         r"has no value 46; its values: \[15, 45\]"):
        prepare(cfg(tmp_path, "data.group=stage", "data.group_by=speed", "data.test_groups=[46]"))
    with pytest.raises(ValueError, match=r"both name speed = \[45\]"):
        prepare(cfg(tmp_path, *BY_SPEED, "data.val_groups=[45]"))
    with pytest.raises(ValueError) as err:  # the defaults: 8 test, 8 validating groups
        prepare(cfg(tmp_path, "data.group=speed"))
    text = str(err.value)
    assert "has 2 groups of 'speed'" in text and "data.test_groups" in text
    assert "case 0" not in text and "data.generate" not in text and "\n" not in text
    with pytest.raises(ValueError, match="apply to a table of your own"):
        prepare(cfg(tmp_path, "data.table=null", "data.group_by=speed"))


def test_leave_one_group_out_logs_each_fold_and_the_mean(tmp_path, caplog):
    """One fold per speed, each fold's model kept, cv.csv and metrics.json with each fold's and
    the mean figures (in-process: a refusal's and a run's command-line path are the
    acceptance tests' own)."""
    write(tmp_path, sidecar="fme15: m/s^2\nwear_mm: mm\n")
    with caplog.at_level(logging.INFO, logger="surrogate"):
        train(cfg(tmp_path, "data.group=stage", "data.group_by=speed", "data.cv=logo",
                  "data.val_replicates=3", "model.folds=2"))
    out = "\n".join(r.getMessage() for r in caplog.records)
    folder = tmp_path / "run"
    assert "fold speed = 15 (24 test rows): model kept" in out
    assert "fold speed = 45 (24 test rows): model kept" in out
    assert "leave-one-group-out over speed (2 folds)" in out
    cv = pd.read_csv(folder / "cv.csv")
    assert list(cv.speed) == [15, 45] and (cv.test_rows == 24).all()
    metrics = json.loads((folder / "metrics.json").read_text())
    assert metrics["folds"] == 2 and metrics["group_by"] == "speed"
    for key in ("test_mean_relative_error_pct", "test_linear_mean_relative_error_pct",
                "test_median_mean_relative_error_pct"):
        assert metrics[key] == pytest.approx(cv[key].mean())
    for k in (15, 45):
        assert (folder / f"fold_{k}" / "wear_surrogate.pt").is_file()
    pred = pd.read_csv(folder / "test_predictions.csv")
    assert len(pred) == 48 and set(pred.speed) == {15, 45}
    assert (folder / "parity.png").is_file()


def test_a_run_on_a_users_table_is_named_after_the_table():
    """The run folder Hydra makes for ``data.table=.../rig.csv``: logs/train/runs/rig_<time>
    (and case3_<time> for the physics dataset)."""
    settings.register()
    for table, name in (("/anywhere/rig.csv", "rig"), ("null", "case3")):
        with initialize_config_module("gearwear_conf.train", version_base="1.3"):
            run = compose("train", overrides=[f"data.table={table}"],
                          return_hydra_config=True).hydra.run.dir
        assert re.fullmatch(rf"logs/train/runs/{name}_\d{{4}}-\d\d-\d\d_\d\d-\d\d-\d\d", run), run


# -- 3. baselines beside the network ------------------------------------------------------------

def test_acceptance_every_run_scores_the_baselines_on_the_same_rows(by_speed):
    metrics = json.loads((by_speed / "metrics.json").read_text())
    pred = pd.read_csv(by_speed / "test_predictions.csv")
    for name in ("", "linear_", "median_"):
        column = f"wear_mm_{name[:-1]}" if name else "wear_mm_pred"
        mine = wear_errors(pred[column], pred.wear_mm)["mean_relative_error_pct"]
        assert metrics[f"test_{name}mean_relative_error_pct"] == pytest.approx(mine)
    assert pred.wear_mm_median.nunique() == 1  # the training rows' median, whatever the rows
    assert "test_estimator_rmse" not in metrics  # no DTE features in this table
    assert isinstance(metrics["test_network_better_than_linear"], bool)


def test_a_network_no_better_than_a_line_says_so_in_one_line(tmp_path, caplog):
    """Wear a straight line of one input's level (its logarithm, as the linear model reads a
    positive feature): the linear model reads it exactly, and a network of two epochs does
    not; the run says so, once."""
    df = rig_table().assign(wear_mm=lambda d: np.log(d.acc_rms / d.acc_rms.min()) * 0.4)
    write(tmp_path, df)
    with caplog.at_level(logging.WARNING, logger="surrogate.training"):
        train(cfg(tmp_path, "data.group=stage", "data.val_replicates=2", "data.test_replicates=3",
                  epochs=2))
    lines = [r.getMessage() for r in caplog.records if "not better" in r.getMessage()]
    assert len(lines) == 1, lines
    assert lines[0].startswith("the network (") and ("is not better than a linear model of "
                                                     "the same inputs (") in lines[0]
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["test_linear_mean_relative_error_pct"] < 1e-6
    assert metrics["test_network_better_than_linear"] is False


def test_the_estimator_stands_beside_where_its_inputs_exist(tmp_path):
    sys.path.insert(0, str(ROOT / "tests" / "safety"))
    from test_safety_user_tables import table, train_cfg

    table(groups=8).to_csv(tmp_path / "mine.csv", index=False)
    train(train_cfg(tmp_path, val_replicates=2))
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert np.isfinite(metrics["test_estimator_mean_relative_error_pct"])
    pred = pd.read_csv(tmp_path / "run" / "test_predictions.csv")
    assert {"rig", "root_wear_mm_estimator", "root_wear_mm_linear"} <= set(pred.columns)


def test_the_linear_model_and_the_verdict():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(50, 2))
    model = Candidate.fit("linear", x, 3 + x @ [1.0, -0.5], np.arange(50))
    assert model.params["intercept"] == pytest.approx(3)
    assert model.params["coef"] == pytest.approx([1, -0.5])
    assert model.predict(np.array([[-10.0, 0.0]]))[0] == 0.0  # no negative wear
    net, lin = {"mean_relative_error_pct": 13.5}, {"mean_relative_error_pct": 13.1}
    assert not_better_line(net, lin) == ("the network (13.5 %) is not better than a linear "
                                         "model of the same inputs (13.1 %) on these test rows")
    assert not_better_line(lin, net) is None


def test_calibration_split_halves_the_validation_trajectories_apart_from_the_stopping_ones():
    """Of 16 or more validation trajectories, half (drawn with the seed) calibrate the interval
    and the others choose the epoch: disjoint, together the validation set; fewer stay one."""
    from surrogate.splits import MIN_APART, calibration_split

    def frames(n: int, cases: tuple[int, ...] = (3,)) -> dict:
        val = pd.concat([pd.DataFrame({"case": c, "replicate": np.repeat(np.arange(n), 3),
                                       "x": 0.0}) for c in cases], ignore_index=True)
        return {"train": val.iloc[:0], "val": val, "test": val.iloc[:0]}

    def trajectories(f: pd.DataFrame) -> set:
        return set(map(tuple, f[["case", "replicate"]].to_numpy()))

    for n, cases in ((MIN_APART, (3,)), (27, (3,)), (7, (1, 2, 5))):
        parts = calibration_split(frames(n, cases), seed=4)
        stop, cal = trajectories(parts["val"]), trajectories(parts["cal"])
        assert not stop & cal and stop | cal == trajectories(frames(n, cases)["val"])
        for c in cases:  # half of each case's, rounded down
            assert sum(1 for k in cal if k[0] == c) == n // 2
        assert (parts["cal"].groupby(["case", "replicate"]).size() == 3).all()  # whole ones
        again = calibration_split(frames(n, cases), seed=4)
        assert again["cal"].equals(parts["cal"])
    small = calibration_split(frames(MIN_APART - 1), seed=4)
    assert small["cal"] is small["val"]


def test_the_interval_is_calibrated_on_trajectories_that_chose_no_epoch(tmp_path):
    """A table with 16 validation stages: the conformal scale in the model is the one of the
    calibration half, which the checkpoint's choice of epoch never saw (metrics say so)."""
    from surrogate.inference import conformal_scale

    write(tmp_path, rig_table(stages=30, records=2))
    c = cfg(tmp_path, "model.kind=network", "data.group=stage", "data.val_replicates=16",
            "data.test_replicates=2",
            epochs=5)
    job = prepare(c)
    train(c)
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["interval_calibrated_apart"] is True
    dm = job.data
    dm.setup()
    assert dm.calibration_apart and "cal " in dm.split_summary()
    s = Surrogate.load(tmp_path / "run" / "wear_surrogate.pt")
    scale = {}
    for part in ("val", "cal"):
        rows = dm.network_rows(part)
        x = rows[list(s.schema.inputs)].to_numpy(float)
        mean, std = s.predict_array(x)
        gearbox = rows.groupby(["case", "replicate"], sort=False).ngroup().to_numpy()
        scale[part] = conformal_scale(mean, s.difficulty(std, s.novelty_score(x)),
                                      rows.wear_mm.to_numpy(), 0.9, groups=gearbox)
    assert s.interval_scale == pytest.approx(scale["cal"], rel=1e-5)
    assert scale["cal"] != pytest.approx(scale["val"], rel=1e-3)
