"""The DTE's complex mesh lines against a once-per-revolution mark (dataset features
``dte_line<k>_re``, ``dte_line<k>_im``): a hand calculation, their independence of where a
record starts once its start phase is given, their linearity (the change between two records
is the change of the signal) and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.signals.order_analysis import LINE_ORDERS, mesh_harmonics, mesh_lines

FS, FM = 40960.0, 600.0
N = 4096  # 0.1 s, the dataset's records


def _record(amps, phases, t0: float = 0.0) -> np.ndarray:
    """sum_k a_k cos(2 pi k FM t + p_k) sampled from t0: the complex line a_k e^(i p_k) at
    mesh phase zero (t = 0)."""
    t = t0 + np.arange(N) / FS
    return sum(a * np.cos(2 * np.pi * k * FM * t + p)
               for k, a, p in zip(LINE_ORDERS, amps, phases, strict=True))


def _complex(lines: dict, k: int) -> np.ndarray:
    return lines[f"line{k}_re"] + 1j * lines[f"line{k}_im"]


def test_lines_of_a_sum_of_cosines_are_its_amplitudes_and_phases():
    amps = np.array([10.0, 3.0, 1.0, 0.5, 0.2, 0.1]) * 1e-6
    phases = np.linspace(-2.5, 2.9, 6)
    got = mesh_lines(_record(amps, phases), FS, FM, 0.0)
    assert list(got) == [f"line{k}_{p}" for k in LINE_ORDERS for p in ("re", "im")]
    for k, a, p in zip(LINE_ORDERS, amps, phases, strict=True):  # a e^(i p), by hand
        assert abs(_complex(got, k) - a * np.exp(1j * p)) < 2e-3 * amps[0]


@settings(max_examples=25, deadline=None)
@given(t0=st.floats(0.0, 0.5), offset=st.floats(-1e-3, 1e-3), seed=st.integers(0, 2**16))
def test_a_record_started_elsewhere_reads_the_same_lines_given_its_start_phase(t0, offset,
                                                                               seed):
    """A record of the same signal taken from another instant, with an offset (the DTE's
    constant), gives the same lines once the mesh phase at its first sample is stated."""
    rng = np.random.default_rng(seed)
    amps, phases = rng.uniform(0.1, 10.0, 6) * 1e-6, rng.uniform(-np.pi, np.pi, 6)
    a = mesh_lines(_record(amps, phases), FS, FM, 0.0)
    b = mesh_lines(_record(amps, phases, t0) + offset, FS, FM, 2 * np.pi * FM * t0)
    for k in LINE_ORDERS:
        assert abs(_complex(b, k) - _complex(a, k)) < 1e-4 * amps.max()


def test_the_change_of_the_lines_is_the_lines_of_the_change():
    """Linear in the record: what a flank form adds to two records drops out of their
    difference (the wear feature's premise)."""
    rng = np.random.default_rng(3)
    form = _record(rng.uniform(1, 8, 6) * 1e-6, rng.uniform(-3, 3, 6))
    wear = _record(rng.uniform(0.1, 2, 6) * 1e-6, rng.uniform(-3, 3, 6))
    new, worn = (mesh_lines(x, FS, FM, 0.0) for x in (form, form + wear))
    alone = mesh_lines(wear, FS, FM, 0.0)
    for k in LINE_ORDERS:
        assert abs(_complex(worn, k) - _complex(new, k) - _complex(alone, k)) < 1e-5 * 8e-6


def test_a_batch_with_its_own_start_phases_is_read_record_by_record():
    rng = np.random.default_rng(1)
    xs = np.stack([_record(rng.uniform(0.1, 10, 6), rng.uniform(0, 6, 6)) for _ in range(3)])
    starts = np.array([0.0, 1.0, -2.0])
    batch = mesh_lines(xs, FS, FM, starts)
    assert list(batch) == [f"line{k}_{p}" for k in LINE_ORDERS for p in ("re", "im")]
    for i in range(3):
        one = mesh_lines(xs[i], FS, FM, starts[i])
        for name in batch:
            assert batch[name][i] == pytest.approx(one[name], rel=1e-5, abs=1e-15)


def test_the_harmonics_levels_phases_and_lines_come_from_one_projection():
    rng = np.random.default_rng(4)
    x = _record(rng.uniform(0.1, 10, 6) * 1e-6, rng.uniform(-3, 3, 6), t0=0.01)
    both = mesh_harmonics(x, FS, FM, start_phase_rad=2 * np.pi * FM * 0.01)
    apart = mesh_harmonics(x, FS, FM) | mesh_lines(x, FS, FM, 2 * np.pi * FM * 0.01)
    assert list(both) == list(apart)
    assert {f"line{k}_{p}" for k in LINE_ORDERS for p in ("re", "im")} <= set(both)
    assert all(np.array_equal(both[k], apart[k]) for k in both)


def test_lines_beyond_nyquist_or_orders_without_the_first_are_refused():
    x = _record(np.ones(6), np.zeros(6))
    with pytest.raises(ValueError, match="fs/2"):
        mesh_lines(x, FS, FS / 8, 0.0)
    with pytest.raises(ValueError, match="start with the mesh frequency"):
        mesh_lines(x, FS, FM, 0.0, orders=(2, 3))
