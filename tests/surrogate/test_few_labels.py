"""The few-label readers of surrogate.few_labels: each recovers the relation it is built on,
by hand, and the study's draws, scores and refusals."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from surrogate.few_labels import (
    PhysicsReader,
    exponential_read,
    few_label_study,
    line_read,
    monotone_envelopes,
    physics_curves,
    stage_error,
    summary,
)

WEAR = np.linspace(0.0, 0.9, 19)


def comparison() -> pd.DataFrame:
    """Two model curves of RMS over new: rising steeply at 50 N m, flatter with a dip at 20."""
    return pd.DataFrame({"wear_mm": WEAR, "rms_model_50Nm": np.exp(2.0 * WEAR),
                         "rms_model_20Nm": 1 + 0.5 * WEAR - 0.3 * np.sin(8 * WEAR),
                         "rms_path_50Nm": 1 + WEAR})


def test_the_physics_reader_finds_the_curve_and_level_of_data_made_by_it():
    """Ratios 1.3 times the 50 N m curve: that torque, a level of log 1.3, and every wear read
    back exactly; a ratio beyond the curve reads its last wear."""
    curves = physics_curves(comparison())
    assert set(curves) == {50.0, 20.0}
    lab = np.array([0.2, 0.5, 0.8])
    reader = PhysicsReader(*monotone_envelopes(WEAR, curves), lab, 1.3 * np.exp(2.0 * lab))
    assert reader.torque == 50.0 and reader.level == pytest.approx(np.log(1.3))
    w = np.array([0.05, 0.33, 0.61, 0.9])
    assert reader.read(1.3 * np.exp(2.0 * w)) == pytest.approx(w)
    assert reader.read(np.array([1e3]))[0] == pytest.approx(0.9)


def test_a_curve_that_dips_is_read_through_its_monotone_envelope():
    """The 20 N m curve falls after its first stages: its envelope is flat there, and a level
    on the flat part reads the first wear that reaches it (one wear per level)."""
    reader = PhysicsReader(*monotone_envelopes(WEAR, {20.0: comparison().rms_model_20Nm}),
                           np.array([0.9]), np.array([1.0 + 0.45 - 0.3 * np.sin(7.2)]))
    assert np.all(np.diff(reader.envelope) >= 0)
    read = reader.read(np.exp(reader.envelope + reader.level))
    _, first = np.unique(reader.envelope, return_index=True)
    assert np.all(np.min(np.abs(read[:, None] - WEAR[first][None, :]), axis=1) < 1e-9)
    assert len(first) < len(WEAR)  # the dip made some levels one


def test_the_exponential_and_the_line_recover_their_own_relations():
    lab = np.array([0.0, 0.3, 0.6, 0.9])
    w = np.array([0.1, 0.45, 0.8])
    assert exponential_read(lab, 1.2 * np.exp(1.7 * lab), 1.2 * np.exp(1.7 * w)) == (
        pytest.approx(w))
    assert line_read(lab, 1 + 2 * lab, 1 + 2 * w) == pytest.approx(w)
    assert exponential_read(lab, np.exp(-lab), np.ones(2)).tolist() == [0.0, 0.0]  # no rise


def test_the_stage_error_weighs_each_stage_once():
    """Stage a: 3 records off by 10 %; stage b: 1 record off by 30 %: (10 + 30) / 2."""
    true = np.array([1.0, 1.0, 1.0, 2.0])
    assert stage_error(np.array([1.1, 0.9, 1.1, 2.6]), true, np.array(list("aaab"))) == (
        pytest.approx(20.0))


def records(n: int = 8) -> pd.DataFrame:
    """A rig whose RMS over new is the 50 N m curve, two records a stage."""
    rows = [{"stage": "Healthy", "wear_mm": 0.0, "acc_rms_g": 0.2}] * 4
    for k, w in enumerate(np.linspace(0.1, 0.8, n)):
        rows += [{"stage": f"W{k + 1}", "wear_mm": w, "acc_rms_g": 0.2 * np.exp(2.0 * w)}] * 2
    return pd.DataFrame(rows)


def test_the_study_draws_labelled_stages_and_reads_the_others():
    """On a rig of the model's own curve the physics reader is exact and the others are not;
    the draws are the seed's; the summary names the best reader of every draw."""
    study = few_label_study(records(), comparison(), labelled=3, draws=20, seed=1)
    assert len(study) == 20 and (study.physics_exact_mre_pct < 1e-6).all()
    assert (study.physics_exact_torque_Nm == 50.0).all() and (study.line_mre_pct > 1).all()
    assert study.stages.str.split().map(len).eq(3).all()
    again = few_label_study(records(), comparison(), labelled=3, draws=20, seed=1)
    pd.testing.assert_frame_equal(study, again)
    table = summary(study)
    assert table.reader.tolist() == ["physics_exact", "physics_path", "exponential", "line"]
    assert table.best_share.sum() == pytest.approx(1.0)
    assert table.set_index("reader").loc["physics_exact", "best_share"] == 1.0


def test_the_study_refuses_what_it_cannot_do():
    with pytest.raises(ValueError, match="at least 2"):
        few_label_study(records(), comparison(), labelled=1)
    with pytest.raises(ValueError, match="label fewer"):
        few_label_study(records(4), comparison(), labelled=4)
    with pytest.raises(ValueError, match="rms_model_<torque>Nm"):
        few_label_study(records(), comparison().drop(columns=["rms_model_50Nm",
                                                              "rms_model_20Nm"]))
