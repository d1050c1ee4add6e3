"""Vibration features (thesis Table 13) on signals with known statistics."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.signals.features import FEATURES, feature_units, features


def test_sine():
    t = np.arange(100_000) / 100_000
    f = features(3.0 * np.sin(2 * np.pi * 50 * t))
    assert f["rms"] == pytest.approx(3 / math.sqrt(2), rel=1e-9)
    assert f["peak_to_peak"] == pytest.approx(6.0, rel=1e-6)
    assert f["crest"] == pytest.approx(math.sqrt(2), rel=1e-6)
    assert f["kurtosis"] == pytest.approx(1.5, rel=1e-6)
    assert f["impulse"] == pytest.approx(math.pi / 2, rel=1e-6)  # peak / (2 A / pi)
    assert f["shape"] == pytest.approx(math.pi / (2 * math.sqrt(2)), rel=1e-6)
    # mean sqrt|A sin| = sqrt(A) (2/pi) int_0^{pi/2} sqrt(sin) = sqrt(A) G(3/4) / (sqrt(pi) G(5/4))
    m = math.sqrt(3) * math.gamma(0.75) / (math.sqrt(math.pi) * math.gamma(1.25))
    assert f["margin"] == pytest.approx(3 / m**2, rel=1e-4)


def test_gaussian_noise_has_pearson_kurtosis_three():
    x = np.random.default_rng(0).normal(size=(4, 400_000))
    assert np.allclose(features(x)["kurtosis"], 3.0, atol=0.03)


def test_square_wave_and_impulses():
    sq = np.sign(np.sin(np.linspace(0, 40 * np.pi, 40_001)[:-1] + 0.1))
    f = features(sq)
    assert f["kurtosis"] == pytest.approx(1.0, abs=1e-3) and f["crest"] == pytest.approx(1.0)
    spikes = np.zeros(10_000)
    spikes[::1000] = 1.0
    assert features(spikes)["kurtosis"] > 100  # impulsive: far above Gaussian


def test_dte_keeps_its_mean():
    x = 50e-6 + 10e-6 * np.sin(np.linspace(0, 20 * np.pi, 10_000))
    f = features(x)
    assert f["rms"] > f["peak_to_peak"]  # as in thesis Table 14
    assert f["peak_to_peak"] == pytest.approx(20e-6, rel=1e-4)


@settings(max_examples=30, deadline=None)
@given(scale=st.floats(1e-9, 1e6), offset_rows=st.integers(1, 4))
def test_batch_equals_single_and_scaling(scale, offset_rows):
    rng = np.random.default_rng(offset_rows)
    x = rng.standard_t(5, size=(offset_rows, 3, 2000))
    batch = features(x)
    single = features(x[0, 1])
    for k in FEATURES:
        assert batch[k].shape == (offset_rows, 3)
        assert batch[k][0, 1] == pytest.approx(single[k], rel=1e-12)
    scaled = features(scale * x)
    for k in FEATURES:
        ratio = scale if k in ("rms", "peak_to_peak") else 1.0
        assert np.allclose(scaled[k], ratio * batch[k], rtol=1e-9)


def test_units():
    u = feature_units("m/s^2")
    assert u["rms"] == "m/s^2" and u["kurtosis"] == "1" and set(u) == set(FEATURES)


@pytest.mark.parametrize(
    ("signal", "message"),
    [
        (np.array([]), "at least 2 samples"),
        (np.array([1.0]), "at least 2 samples"),
        (np.ones(100), "the signal is constant"),
        (np.array([1.0, np.nan, 2.0]), "the signal holds NaN or infinite"),
        (np.array([[1.0, 2.0, 3.0], [1.0, np.inf, 2.0]]), r"signal \(1,\) holds NaN"),
        (np.array([[1.0, 2.0, 3.0], [4.0, 4.0, 4.0]]), r"signal \(1,\) is constant"),
    ],
)
def test_bad_signals(signal, message):
    with pytest.raises(ValueError, match=message):
        features(signal)
