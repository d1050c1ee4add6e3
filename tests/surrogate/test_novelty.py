"""A warning where the network does not know: the novelty score against the training rows,
its flag, the normalised conformal interval that widens with it, and the one line a run or a
prediction says when its rows lie outside the network's training data."""

from __future__ import annotations

import json
import logging

import numpy as np
import pandas as pd
import pytest
import torch

from surrogate.conformal import exchangeable_quantile
from surrogate.inference import Surrogate, conformal_scale
from surrogate.novelty import Novelty, difficulty, envelope_report
from surrogate.schema import FeatureSchema


def draw(rng, n: int) -> np.ndarray:
    """Standardised rows of a training distribution whose inputs 0 and 1 move together."""
    x = rng.normal(size=(n, 3))
    x[:, 1] = x[:, 0] + 0.1 * x[:, 1]
    return x


def test_novelty_is_rare_on_the_training_distribution_and_certain_far_from_it():
    """Rows drawn like the training rows score above 1 at about ``1 - level``; rows shifted by
    ten deviations in one input, and rows that break the training rows' correlation of two
    inputs (each input alone typical), nearly all do."""
    rng = np.random.default_rng(0)
    nov = Novelty.fit(draw(rng, 2000), draw(rng, 500), rng.uniform(0, 1, 2000), level=0.95)
    same = draw(rng, 4000)
    assert np.mean(nov.score(same) > 1) == pytest.approx(0.05, abs=0.025)
    assert np.all(nov.score(same + np.array([10, 10, 0])) > 1)
    broken = same.copy()
    broken[:, 1] = -broken[:, 0]  # the same marginals, the correlation reversed
    assert np.mean(nov.score(broken) > 1) > 0.8
    assert np.median(nov.score(same)) < np.median(nov.score(broken)) / 3


def test_novelty_by_gearbox_flags_a_new_gearbox_at_most_at_the_level():
    """A gearbox's rows lie near or far together (a gearbox offset beside each row's own
    scatter): over many draws of 26 validation gearboxes of 7 rows, the radius taken by
    gearbox flags a row of a new gearbox at most at ``1 - level``; the rows' quantile flags
    more, as it counts 182 rows where 26 units vary."""
    rng = np.random.default_rng(5)

    def gearboxes(k, rows=7):
        return (rng.normal(0, 1, (k, 1, 3)) + 0.1 * rng.normal(0, 1, (k, rows, 3))).reshape(-1, 3)

    nov = Novelty.fit(gearboxes(300), gearboxes(26), np.zeros(2100))
    groups, level = np.repeat(np.arange(26), 7), 0.95
    flagged = {"gearbox": [], "rows": []}
    for _ in range(1500):
        d_val, d_new = nov.distance(gearboxes(26)), nov.distance(gearboxes(1))
        flagged["gearbox"].append(np.mean(d_new > exchangeable_quantile(d_val, level, groups)))
        flagged["rows"].append(np.mean(d_new > np.quantile(d_val, level)))
    assert np.mean(flagged["gearbox"]) <= 1 - level + 0.01  # MC error about 0.005
    assert np.mean(flagged["rows"]) > 1 - level + 0.01
    fitted = Novelty.fit(gearboxes(300), (val := gearboxes(26)), np.zeros(2100), groups=groups)
    assert fitted.radius == pytest.approx(exchangeable_quantile(
        fitted.distance(val), fitted.level, groups))


def test_exchangeable_quantile_refuses_what_it_cannot_take():
    with pytest.raises(ValueError, match="non-empty 1-D"):
        exchangeable_quantile(np.array([]), 0.9)
    with pytest.raises(ValueError, match="1 held-out scores are not finite"):
        exchangeable_quantile(np.array([1.0, np.nan]), 0.9)
    with pytest.raises(ValueError, match="must lie in"):
        exchangeable_quantile(np.ones(3), 1.0)
    with pytest.raises(ValueError, match="2 group labels for 3 scores"):
        exchangeable_quantile(np.ones(3), 0.5, np.array([0, 1]))


def test_novelty_travels_as_tensors_and_plain_numbers(tmp_path):
    rng = np.random.default_rng(1)
    nov = Novelty.fit(draw(rng, 300), draw(rng, 100), np.linspace(0, 0.02, 300))
    path = tmp_path / "n.pt"
    torch.save({"novelty": nov.payload()}, path)
    back = Novelty.from_payload(torch.load(path, weights_only=True)["novelty"])
    x = draw(rng, 50)
    np.testing.assert_allclose(back.score(x), nov.score(x), rtol=1e-5)
    assert (back.target_low, back.target_high) == (0.0, 0.02)
    bad = nov.payload() | {"radius": -1.0}
    with pytest.raises(ValueError, match="invalid"):
        Novelty.from_payload(bad)


def test_normalised_conformal_covers_the_level_and_widens_with_novelty():
    """Residuals that grow with the novelty: the interval calibrated on ``|y - mu| /
    difficulty`` covers the level on exchangeable calibration rows and on far rows alike,
    where the ensemble's spread alone (calibrated on the same rows) misses the far ones."""
    rng = np.random.default_rng(2)

    def rows(n, shift):
        score = rng.uniform(0, 1, n) + shift
        std = rng.uniform(0.5, 1.5, n)
        return std, score, rng.normal(0, 1, n) * std * (1 + score)

    std, score, res = rows(4000, 0.0)
    scale = conformal_scale(np.zeros_like(res), difficulty(std, score), res, 0.9)
    plain = conformal_scale(np.zeros_like(res), std, res, 0.9)
    s2, sc2, r2 = rows(4000, 0.0)
    assert np.mean(np.abs(r2) <= scale * difficulty(s2, sc2)) == pytest.approx(0.9, abs=0.02)
    s3, sc3, r3 = rows(4000, 3.0)  # far rows
    assert np.mean(np.abs(r3) <= scale * difficulty(s3, sc3)) == pytest.approx(0.9, abs=0.03)
    assert np.mean(np.abs(r3) <= plain * s3) < 0.6


def test_the_envelope_report_says_so_once_past_the_training_rate():
    rng = np.random.default_rng(3)
    nov = Novelty.fit(draw(rng, 300), draw(rng, 100), np.linspace(0, 0.015, 300))
    figures, line = envelope_report(np.arange(100) < 8, nov)
    assert figures == {"flagged_rows": 8, "flagged_share": 0.08} and line is None
    figures, line = envelope_report(np.ones(100, bool), nov, np.full(100, 0.6), "rows", "mm")
    assert figures["target_beyond_rows"] == 100 and "\n" not in line
    assert line.startswith("100 of 100 rows (100 %) lie outside the network's training data")
    assert "0-0.015 mm, up to 40 times its top" in line


@pytest.fixture(scope="module")
def network():
    """A small ensemble of three inputs with a novelty reference from drawn rows."""
    from surrogate.model import WearRegressor

    rng = np.random.default_rng(4)
    train = pd.DataFrame(draw(rng, 400) * [1, 1, 2] + [5, 5, 10], columns=["a", "b", "c"])
    train["wear_mm"] = rng.uniform(0, 0.02, len(train))
    schema = FeatureSchema.fit(train, ["a", "b", "c"], {"a": "1", "b": "1", "c": "1",
                                                        "wear_mm": "mm"}, "wear_mm")
    torch.manual_seed(0)
    model = WearRegressor(3, schema.to_dict(), width=8, depth=1, members=3)
    val = pd.DataFrame(draw(rng, 100) * [1, 1, 2] + [5, 5, 10], columns=["a", "b", "c"])
    nov = Novelty.fit(schema.scale(train[["a", "b", "c"]].to_numpy()),
                      schema.scale(val.to_numpy()), train.wear_mm.to_numpy())
    return Surrogate(model, 1.6, nov), train


def test_every_prediction_carries_its_novelty_and_far_rows_are_flagged_with_wider_intervals(
        network):
    s, train = network
    near = s.predict(train[["a", "b", "c"]].iloc[:50])
    far_rows = train[["a", "b", "c"]].iloc[:50].assign(b=lambda d: 10 - d.a)  # inside ranges
    far = s.predict(far_rows)
    assert {"novelty", "out_of_range"} <= set(near.columns)
    assert near.out_of_range.mean() <= 0.1 and far.out_of_range.mean() > 0.9
    assert np.median(far.novelty) > 3 * np.median(near.novelty)
    width = (far.wear_mm_upper - far.wear_mm_lower) / far.wear_mm_std
    assert width.median() > 2 * ((near.wear_mm_upper - near.wear_mm_lower)
                                 / near.wear_mm_std).median()
    # the envelope stays part of the flag: one input beyond its range, the rest typical
    edge = train[["a", "b", "c"]].iloc[:1].assign(c=train.c.max() + 0.5 * np.ptp(train.c))
    assert bool(s.predict(edge).out_of_range.iloc[0])


def test_predict_says_once_when_the_rows_lie_outside(network, tmp_path, caplog):
    from surrogate.predict import PredictJob, execute

    s, train = network
    rows = train[["a", "b", "c"]].assign(b=lambda d: 10 - d.a, wear_mm=0.5)
    with caplog.at_level(logging.WARNING, logger="surrogate.predict"):
        execute(PredictJob(s, rows, tmp_path / "w.csv"))
    lines = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    assert len(lines) == 1 and "outside the network's training data" in lines[0]
    assert "never saw such wear" in lines[0]
    out = pd.read_csv(tmp_path / "w.csv")
    assert out.out_of_range.mean() > 0.8 and out.novelty.notna().all()
    json.dumps(out.iloc[0].to_dict(), default=str)
