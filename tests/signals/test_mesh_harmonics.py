"""The DTE's mesh-harmonic levels and phases (dataset features ``dte_mesh<k>_db``,
``dte_mesh<k>_cos``, ``dte_mesh<k>_sin``): hand calculations on a sum of sinusoids, their
invariance to a record's gain, offset and start, and the sign convention's effect."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.signals.order_analysis import (
    MESH_ORDERS,
    mesh_harmonic_levels,
    mesh_harmonic_phases,
    mesh_harmonics,
)

FS, FM = 40960.0, 600.0
T = np.arange(4096) / FS  # 0.1 s, the dataset's records
LEVELS = [f"mesh{k}_db" for k in MESH_ORDERS]
PHASES = [f"mesh{k}_{f}" for k in MESH_ORDERS for f in ("cos", "sin")]


def _record(amps: np.ndarray, phases: np.ndarray) -> np.ndarray:
    return sum(a * np.sin(2 * np.pi * (k + 1) * FM * T + p)
               for k, (a, p) in enumerate(zip(amps, phases, strict=True)))


def test_levels_of_a_sum_of_sinusoids_are_its_amplitude_ratios():
    amps = np.array([10.0, 3.0, 1.0, 0.5, 0.2, 0.1]) * 1e-6
    x = _record(amps, np.linspace(0.3, 2.0, 6))
    got = mesh_harmonic_levels(x, FS, FM)
    assert list(got) == [f"mesh{k}_db" for k in MESH_ORDERS]
    for k in MESH_ORDERS:  # 20 log10(A_k / A_1), by hand
        assert got[f"mesh{k}_db"] == pytest.approx(20 * np.log10(amps[k - 1] / amps[0]),
                                                   abs=0.01)


@settings(max_examples=25, deadline=None)
@given(gain=st.floats(1e-3, 1e3), offset=st.floats(-1e-3, 1e-3),
       seed=st.integers(0, 2**16))
def test_levels_ignore_the_records_gain_and_offset(gain, offset, seed):
    """A sensor's scale and the DTE's unknown constant (an encoder pair) leave them alone."""
    rng = np.random.default_rng(seed)
    x = _record(rng.uniform(0.1, 10.0, 6) * 1e-6, rng.uniform(0, 2 * np.pi, 6))
    a, b = mesh_harmonic_levels(x, FS, FM), mesh_harmonic_levels(gain * x + offset, FS, FM)
    assert list(a) == list(b) == LEVELS
    for k in a:
        assert b[k] == pytest.approx(a[k], abs=1e-3)


def test_both_at_once_are_the_levels_and_the_phases():
    rng = np.random.default_rng(2)
    xs = np.stack([_record(rng.uniform(0.1, 10, 6), rng.uniform(0, 6, 6)) for _ in range(2)])
    both = mesh_harmonics(xs, FS, FM)
    apart = mesh_harmonic_levels(xs, FS, FM) | mesh_harmonic_phases(xs, FS, FM)
    assert list(both) == list(apart) and set(both) == {*LEVELS, *PHASES}
    assert all(np.array_equal(both[k], apart[k]) for k in both)


def test_a_batch_is_read_record_by_record():
    rng = np.random.default_rng(1)
    xs = np.stack([_record(rng.uniform(0.1, 10, 6), rng.uniform(0, 6, 6)) for _ in range(3)])
    batch = mesh_harmonic_levels(xs, FS, FM)
    assert list(batch) == LEVELS
    for i, x in enumerate(xs):
        one = mesh_harmonic_levels(x, FS, FM)
        assert all(batch[k][i] == pytest.approx(one[k], abs=1e-4) for k in one)


@pytest.mark.parametrize("f_mesh", [0.0, -600.0, FS / 10, float("nan")])
@pytest.mark.parametrize("read", [mesh_harmonic_levels, mesh_harmonic_phases])
def test_harmonics_beyond_nyquist_or_no_mesh_are_refused(f_mesh, read):
    with pytest.raises(ValueError, match=r"must lie in \(0, fs/2"):
        read(np.sin(T), FS, f_mesh)


def test_phases_of_a_sum_of_sinusoids_are_its_relative_phases():
    """``d_k = phi_k - k phi_1`` of ``sum a_k sin(k w t + p_k)``, by hand: the projection on
    ``exp(i w t)`` gives a sine of phase ``p`` the phase ``pi / 2 - p``, so ``d_k = -(p_k - k
    p_1 + (k - 1) pi / 2)``."""
    amps = np.array([10.0, 3.0, 1.0, 0.5, 0.2, 0.1]) * 1e-6
    rng = np.random.default_rng(3)
    for _ in range(4):
        p = rng.uniform(-np.pi, np.pi, 6)
        got = mesh_harmonic_phases(_record(amps, p), FS, FM)
        assert list(got) == [f"mesh{k}_{f}" for k in MESH_ORDERS for f in ("cos", "sin")]
        for k in MESH_ORDERS:
            d = -(p[k - 1] - k * p[0] + (k - 1) * np.pi / 2)
            z = got[f"mesh{k}_cos"] + 1j * got[f"mesh{k}_sin"]
            assert abs(z - np.exp(1j * d)) < 2e-3


@settings(max_examples=25, deadline=None)
@given(gain=st.floats(1e-3, 1e3), offset=st.floats(-1e-3, 1e-3),
       delay=st.integers(0, 2000), seed=st.integers(0, 2**16))
def test_phases_ignore_the_records_gain_offset_and_start(gain, offset, delay, seed):
    """A positive gain, the DTE's constant and where the record starts leave them alone: a
    later start of ``delay`` samples is the same waveform."""
    rng = np.random.default_rng(seed)
    amps, p = rng.uniform(0.1, 10.0, 6) * 1e-6, rng.uniform(0, 2 * np.pi, 6)
    long = np.arange(len(T) + delay) / FS
    x = sum(a * np.sin(2 * np.pi * (k + 1) * FM * long + q)
            for k, (a, q) in enumerate(zip(amps, p, strict=True)))
    a = mesh_harmonic_phases(x[:len(T)], FS, FM)
    b = mesh_harmonic_phases(gain * x[delay:] + offset, FS, FM)
    assert list(a) == list(b) == PHASES
    for k in a:
        assert b[k] == pytest.approx(a[k], abs=2e-3)


def test_a_record_of_the_other_sign_turns_the_even_orders_half_way():
    rng = np.random.default_rng(5)
    x = _record(rng.uniform(0.1, 10.0, 6) * 1e-6, rng.uniform(0, 2 * np.pi, 6))
    a, b = mesh_harmonic_phases(x, FS, FM), mesh_harmonic_phases(-x, FS, FM)
    for k in MESH_ORDERS:
        sign = 1 if k % 2 else -1
        for f in ("cos", "sin"):
            assert b[f"mesh{k}_{f}"] == pytest.approx(sign * a[f"mesh{k}_{f}"], abs=1e-4)
