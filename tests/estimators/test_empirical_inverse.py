"""The analytic empirical-inverse estimator of thesis 4.4."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from physics.estimators.empirical_inverse import EmpiricalInverse, accuracy
from physics.reference import THESIS_TABLES

REF = THESIS_TABLES


def _forward(est, cycles):
    n = cycles / 1e6
    return np.polyval(est.p2p_cubic, n), np.polyval(est.kurtosis_cubic, n), est.wear_at(cycles)


def test_inverts_its_own_forward_model_exactly():
    est = EmpiricalInverse.from_config("thesis")
    cycles = np.linspace(0.5e6, 1.5e7, 200)
    p2p, kurt, wear = _forward(est, cycles)
    out = est.predict(p2p, kurt)
    assert np.all(out.valid)
    assert np.allclose(out.cycles, cycles, rtol=1e-4, atol=2e3)
    assert np.allclose(out.wear, wear, rtol=1e-3, atol=1e-7)


def test_fit_mode_recovers_a_known_forward_model():
    truth = EmpiricalInverse.from_config("thesis")
    cycles = np.linspace(0, 1.5e7, 40)
    p2p, kurt, wear = _forward(truth, cycles)
    est = EmpiricalInverse.fit(cycles, p2p, kurt, wear)
    assert np.allclose(est.p2p_cubic, truth.p2p_cubic, rtol=1e-6)
    assert np.allclose(est.wear_law, truth.wear_law, rtol=1e-5)
    m = accuracy(est.predict(p2p[1:], kurt[1:]), wear[1:])
    assert m["mean_relative_error_pct"] < 0.1 and m["inconsistent_rows"] == 0


def test_kurtosis_alone_is_ambiguous_and_peak_to_peak_resolves_it():
    est = EmpiricalInverse.from_config("thesis")
    n = np.linspace(0, 15, 3001)
    k = np.polyval(est.kurtosis_cubic, n)
    target = 2.7
    crossings = np.sum(np.diff(np.sign(k - target)) != 0)
    assert crossings >= 2  # two cycle counts share this kurtosis
    for cycles in (1.5e6, 10.3e6):
        p2p, _, _ = _forward(est, np.array([cycles]))
        k_here = np.polyval(est.kurtosis_cubic, cycles / 1e6)
        out = est.predict(p2p, np.array([k_here]))
        assert out.cycles[0] == pytest.approx(cycles, rel=1e-3)


def test_inconsistent_and_out_of_range_pairs_are_flagged():
    est = EmpiricalInverse.from_config("thesis")
    p_mid, k_mid, _ = _forward(est, np.array([8e6]))
    # a kurtosis no cycle count pairs with this peak-to-peak
    out = est.predict(p_mid, k_mid + 2.0)
    assert not out.consistent[0]
    far = est.predict(np.array([1e-3]), np.array([50.0]))
    assert not far.in_range[0] and not far.valid[0]


def test_bad_input():
    est = EmpiricalInverse.from_config("thesis")
    with pytest.raises(ValueError, match="must be finite"):
        est.predict(np.array([np.nan]), np.array([3.0]))
    with pytest.raises(ValueError, match="not in conf/physics/estimator"):
        EmpiricalInverse.from_config("nope")
    with pytest.raises(ValueError, match="same length, at least 6"):
        EmpiricalInverse.fit(np.arange(3), np.arange(3), np.arange(3), np.arange(3))


def test_config_matches_the_published_coefficients():
    conf = yaml.safe_load((Path(__file__).resolve().parents[2] / "conf" / "physics" / "estimator"
                           / "thesis.yaml").read_text())
    table = pd.read_csv(REF / "table13_empirical_models_case3.csv")
    text = " ".join(table.expression)
    values = (*conf["p2p_cubic"], *conf["kurtosis_cubic"], *conf["wear_law_mm"])
    assert len(values) == 12  # two cubics' four coefficients, the wear law's four
    for value in values:
        assert f"{abs(value):g}".replace("e-07", "e-7") in text


def test_thesis_accuracy_is_computed_from_its_data():
    d = pd.read_csv(REF / "table14_dte_features_case3.csv")
    est = EmpiricalInverse.from_config("thesis")
    m = accuracy(est.predict(d["peak_to_peak_1e-5_m"] * 1e-5, d["kurtosis"]), d["wear_mm"])
    assert 90 < m["accuracy_pct"] < 99  # the thesis states 94.82 %
