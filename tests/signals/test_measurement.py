"""The declared measurement chain: the bearing-support and mounting modes against hand
calculations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.signals.measurement import (
    declared_chain,
    housing_mount,
    support_path,
    transfer_path,
    transmissibility,
)

FS = 40960.0
N = 8192  # 0.2 s: bins of 5 Hz


def tone(f_hz: float) -> np.ndarray:
    return np.sin(2 * np.pi * f_hz * np.arange(N) / FS)


def amplitude(x: np.ndarray, f_hz: float) -> float:
    """Amplitude of the tone ``f_hz``, centred on a bin of ``x``'s length, in ``x``."""
    return 2 * abs(np.fft.rfft(x)[round(f_hz * len(x) / FS)]) / len(x)


@settings(max_examples=30, deadline=None)
@given(fn=st.floats(300.0, 15000.0), zeta=st.floats(0.005, 0.5), ratio=st.floats(0.2, 3.0))
def test_support_gain_is_the_single_degree_of_freedom_transmissibility(fn, zeta, ratio):
    # by hand: |T|^2 = (1 + (2 zeta r)^2) / ((1 - r^2)^2 + (2 zeta r)^2)
    f = round(min(ratio * fn, 0.45 * FS) * N / FS) * FS / N
    r = f / fn
    by_hand = math.sqrt((1 + (2 * zeta * r) ** 2) / ((1 - r * r) ** 2 + (2 * zeta * r) ** 2))
    assert amplitude(support_path(tone(f), FS, fn, zeta), f) == pytest.approx(by_hand, rel=1e-9)
    assert abs(transmissibility(np.array([f]), fn, zeta)[0]) == pytest.approx(by_hand, rel=1e-12)


@pytest.mark.parametrize("fn, zeta", [(1000.0, 0.05), (2500.0, 0.03), (6000.0, 0.2)])
def test_support_agrees_with_the_time_domain_transfer_path_at_the_mode(fn, zeta):
    # the bilinear transfer path is pre-warped at fn: both discretisations are exact there
    f = round(fn * N / FS) * FS / N
    steady = slice(N // 2, N)  # after the time-domain filter's start transient
    a_time = np.max(np.abs(transfer_path(tone(f), FS, f, zeta)[steady]))
    a_freq = np.max(np.abs(support_path(tone(f), FS, f, zeta)[steady]))
    assert a_freq == pytest.approx(a_time, rel=0.01)


@settings(max_examples=30, deadline=None)
@given(fn=st.floats(500.0, 8000.0), zeta=st.floats(0.01, 0.1), g=st.floats(-1.0, 1.0))
def test_transfer_path_gain_at_its_mode_follows_the_residue(fn, zeta, g):
    # by hand: at s = i wn, s^2 / (s^2 + 2 zeta wn s + wn^2) = i / (2 zeta), so
    # |1 - g s^2 / (...)| = sqrt(1 + g^2 / (4 zeta^2)); the pre-warped bilinear form is exact there
    f = round(fn * N / FS) * FS / N
    # the last N samples, after the start transient has decayed to e^-10 of itself (10 time
    # constants 1 / (zeta wn)); f lies on their bins. The tone's amplitude, not the largest
    # sample: at 5.3 samples a period the samples miss the crest by up to 2 %
    settle = math.ceil(10 / (zeta * 2 * math.pi * f) * FS)
    x = np.sin(2 * np.pi * f * np.arange(settle + N) / FS)
    peak = amplitude(transfer_path(x, FS, f, zeta, g)[settle:], f)
    assert peak == pytest.approx(math.sqrt(1 + g * g / (4 * zeta * zeta)), rel=1e-3)


@pytest.mark.parametrize("g", [1.0, 0.0, -0.5])
def test_transfer_path_passes_the_band_below_its_mode_and_scales_the_band_above_by_one_minus_g(g):
    fn, zeta = 3000.0, 0.03
    steady = slice(N // 2, N)
    low = round(fn / 30 * N / FS) * FS / N
    assert np.max(np.abs(transfer_path(tone(low), FS, fn, zeta, g)[steady])) == pytest.approx(
        1.0, abs=0.01)
    # above the mode, by hand: |1 - g r^2 / (r^2 - 1 - 2 i zeta r)|, r the bilinear transform's
    # frequency ratio tan(pi f / fs) / tan(pi fn / fs); -> |1 - g| far above
    high = round(4 * fn * N / FS) * FS / N
    r = math.tan(math.pi * high / FS) / math.tan(math.pi * fn / FS)
    by_hand = abs(1 - g * r * r / (r * r - 1 - 2j * zeta * r))
    out = np.max(np.abs(transfer_path(tone(high), FS, fn, zeta, g)[steady]))
    assert out == pytest.approx(by_hand, rel=1e-3)
    assert out == pytest.approx(abs(1 - g), abs=0.06)


def test_a_support_far_above_the_band_is_rigid_and_zero_declares_none():
    rng = np.random.default_rng(0)
    x = rng.standard_normal((3, N))
    # r <= 0.02 up to fs/2: |T| - 1 ~ r^2 = 4e-4
    assert np.max(np.abs(support_path(x, FS, 1e6, 0.05) - x)) < 2e-3 * np.max(np.abs(x))
    rigid = declared_chain(x, "accel_m_s2", 20.0)
    assert np.array_equal(declared_chain(x, "accel_m_s2", 20.0, fs=FS, support_hz=0.0), rigid)
    assert np.array_equal(declared_chain(x, "dte_m", 20.0, fs=FS, support_hz=2000.0), x)


def test_a_support_mode_needs_its_sampling_rate_and_a_valid_damping():
    with pytest.raises(ValueError, match="sampling rate"):
        declared_chain(tone(100.0), "accel_m_s2", 20.0, support_hz=2000.0)
    with pytest.raises(ValueError, match="zeta"):
        support_path(tone(100.0), FS, 2000.0, 1.5)


@settings(max_examples=30, deadline=None)
@given(fn=st.floats(5.0, 1000.0), zeta=st.floats(0.02, 0.5), ratio=st.floats(0.05, 20.0))
def test_mount_gain_is_that_of_a_force_driven_mass_on_a_spring(fn, zeta, ratio):
    # by hand: |a / a_free| = r^2 / sqrt((1 - r^2)^2 + (2 zeta r)^2)
    f = max(round(ratio * fn * N / FS), 1) * FS / N
    r = f / fn
    by_hand = r * r / math.sqrt((1 - r * r) ** 2 + (2 * zeta * r) ** 2)
    assert amplitude(housing_mount(tone(f), FS, fn, zeta), f) == pytest.approx(by_hand,
                                                                                rel=1e-9)


def test_a_mount_lowers_the_shaft_orders_and_leaves_the_mesh_band():
    x = tone(15.0) + tone(2000.0)  # a half shaft order and a mesh harmonic, 1 N each
    free = declared_chain(x, "accel_m_s2", 20.0)
    mounted = declared_chain(x, "accel_m_s2", 20.0, fs=FS, mount_hz=150.0, mount_damping=0.2)
    assert amplitude(mounted, 15.0) < 0.011 * amplitude(free, 15.0)  # (15 / 150)^2 = 0.01
    assert amplitude(mounted, 2000.0) == pytest.approx(amplitude(free, 2000.0), rel=0.01)
    with pytest.raises(ValueError, match="sampling rate"):
        declared_chain(x, "accel_m_s2", 20.0, mount_hz=150.0)
