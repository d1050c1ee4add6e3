"""Acceptance on a one-rig table of the independent simulator (another model form than ours),
as a user with one test rig has it: one gearbox, 32 wear stages, two shaft speeds, the
acceleration RMS and the DTE peak-to-peak value as the network's inputs (the estimator's DTE
kurtosis and a cycle count beside). Trained at 15 rev/s and tested at 45, with stages left
out at both speeds, and leaving each stage out in turn; each beside the linear model and the
thesis's estimator (``python -m surrogate.benchmark``'s ``one_rig.csv``; docs/benchmark.md,
One rig)."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from surrogate import benchmark
from surrogate.training import train

ROOT = Path(__file__).resolve().parents[2]
FAST = ["trainer.max_epochs=40", "trainer.min_epochs=10", "model.members=2", "model.folds=2",
        "trainer.enable_progress_bar=false", "logger=csv"]


@pytest.fixture(scope="module")
def rig(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("one_rig")
    benchmark.one_rig_table().to_csv(tmp / "one_rig.csv", index=False)
    return tmp


def run(rig: Path, split: str, caplog, training: list[str] = FAST
        ) -> tuple[dict, pd.DataFrame, list[str]]:
    folder = rig / split
    with caplog.at_level(logging.WARNING, logger="surrogate.training"):
        train(benchmark.train_config(ROOT, folder, f"data.table={rig / 'one_rig.csv'}",
                                     *benchmark.ONE_RIG_INPUTS,
                                     *benchmark.ONE_RIG_SPLITS[split], *training))
    lines = [r.getMessage() for r in caplog.records if "training data" in r.getMessage()]
    return (json.loads((folder / "metrics.json").read_text()),
            pd.read_csv(folder / "test_predictions.csv"), lines)


def test_the_table_is_one_gearbox_over_32_stages_at_two_speeds(rig):
    df = pd.read_csv(rig / "one_rig.csv")
    assert len(df) == 64 and set(df.speed) == {15, 45} and df.stage.nunique() == 32
    # the wear moves the acceleration at each speed, and the speed moves its level
    for _, one in df.groupby("speed"):
        assert one.acc_rms.iloc[-1] != pytest.approx(one.acc_rms.iloc[0], rel=0.1)
    assert df[df.speed == 45].acc_rms.median() > 1.3 * df[df.speed == 15].acc_rms.median()


def test_acceptance_train_at_one_speed_test_at_the_other_says_it_does_not_know(rig, caplog):
    """Every row at the other speed lies outside the training data: flagged, said once, and
    none of them both missed by the interval and unflagged; the baselines stand beside."""
    metrics, pred, lines = run(rig, "by_speed", caplog)
    assert set(pred.speed) == {45} and len(pred) == 32
    # the speed column is the operating point: every row at 45 rev/s flagged, whatever its
    # features (the model was trained at 15 alone)
    assert metrics["test_flagged_share"] == 1.0 and pred.out_of_range.all()
    assert metrics["test_missed_not_flagged_share"] == 0.0
    assert len(lines) == 1
    for who in ("", "linear_", "estimator_", "median_"):
        assert np.isfinite(metrics[f"test_{who}mean_relative_error_pct"]), who


def test_acceptance_stages_left_out_are_read_inside_the_training_data(rig, caplog):
    """Held-out stages between trained ones at both speeds: few rows flagged, the interval
    covering most, the network, the linear model and the estimator all scored."""
    metrics, pred, lines = run(rig, "stages_out", caplog)
    assert pred.stage.nunique() == 6 and set(pred.speed) == {15, 45}
    assert metrics["test_flagged_share"] <= 0.25 and not lines
    assert metrics["test_interval_coverage"] >= 0.6
    for who in ("", "linear_", "estimator_"):
        assert np.isfinite(metrics[f"test_{who}mean_relative_error_pct"]), who


@pytest.mark.slow
def test_acceptance_every_stage_left_out_in_turn_beats_the_line_and_covers(rig, caplog):
    """Leave-one-stage-out cross-validation with the default training, as a user of one rig
    would judge the network: 32 folds, every stage (both speeds) read by a network that never
    saw it; over the folds its mean relative error at most the linear model's of the same
    inputs (the network's figure, whichever model each fold keeps), the kept models' 95 %
    intervals covering at least 0.85 of the held-out rows."""
    metrics, _, _ = run(rig, "stage_cv", caplog, training=[])
    folds = pd.read_csv(rig / "stage_cv" / "cv.csv")
    assert metrics["folds"] == 32 and sorted(folds.stage) == list(range(32))
    assert (folds.test_rows == 2).all()
    assert (metrics["test_network_mean_relative_error_pct"]
            <= metrics["test_linear_mean_relative_error_pct"])
    assert metrics["test_interval_coverage"] >= 0.85
