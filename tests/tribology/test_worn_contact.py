"""The worn flanks' line contact with the wear as a gap: Hertz recovered, load balance, exact
cases of a tilted and a re-curved band, convergence under refinement, severe wear, and the
sweep that keeps the Archard wear volume."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.gear.geometry import mesh_geometry
from physics.params import GearPair
from physics.tribology import worn_contact as wc

E_STAR = 206e9 / (2 * (1 - 0.3**2))


def _cells(window: float = 3.0, n: int = 128) -> tuple[np.ndarray, float]:
    dX = 2 * window / n
    return -window + (np.arange(n) + 0.5) * dX, dX


def test_hertz_is_recovered_from_the_parabolic_gap():
    """An unworn band: the numerical pressure is Hertz's ellipse within 0.1 % at its peak and
    1 % of p_max everywhere outside the edge cells, and carries the Hertz load."""
    X, dX = _cells()
    P, _ = wc.solve_gap_contact(X**2 / 2, dX)
    assert P.max() == pytest.approx(1.0, rel=1e-3)
    assert P.sum() * dX == pytest.approx(math.pi / 2, rel=1e-12)
    inner = np.abs(X) < 0.95
    assert np.abs(P[0, inner] - np.sqrt(1 - X[inner]**2)).max() < 0.01


@pytest.mark.parametrize("tilt", [-0.8, 0.3])
def test_a_uniformly_sloping_wear_shifts_hertz(tilt):
    """Wear that grows linearly across the band adds ``tilt X`` to the gap: the exact solution
    is Hertz's ellipse moved to ``X = -tilt`` (the gap's least point), same peak."""
    X, dX = _cells()
    P, _ = wc.solve_gap_contact(X**2 / 2 + tilt * X, dX)
    assert P.max() == pytest.approx(1.0, rel=2e-3)
    assert np.sum(X * P) / np.sum(P) == pytest.approx(-tilt, abs=1e-3)


@pytest.mark.parametrize("kappa", [-0.4, 0.5])
def test_a_wear_curvature_changes_the_effective_radius(kappa):
    """Wear curved across the band, ``kappa X^2 / 2``, is a radius ``R / (1 + kappa)``: Hertz
    then gives ``p_max sqrt(1 + kappa)`` and a half-width ``b / sqrt(1 + kappa)`` (Johnson 4.45)."""
    X, dX = _cells()
    P, _ = wc.solve_gap_contact((1 + kappa) * X**2 / 2, dX)
    assert P.max() == pytest.approx(math.sqrt(1 + kappa), rel=3e-3)
    width = dX * np.count_nonzero(P > 0) / 2
    assert width == pytest.approx(1 / math.sqrt(1 + kappa), abs=2 * dX)


def test_the_influence_matrix_deflects_a_hertz_ellipse_into_its_parabola():
    """Johnson, Contact Mechanics 4.2: the Hertz pressure sqrt(1 - X^2) on a line contact
    deflects the surfaces by a constant minus X^2/2 across the band (Hertz units), and a
    uniform load's deflection is even about the band's centre."""
    X, dX = _cells(n=256)
    P = np.sqrt(np.clip(1 - X**2, 0, None))
    u = P @ wc.influence_matrix(X.size, dX)
    inside = np.abs(X) < 0.95
    flat = u[inside] + X[inside] ** 2 / 2
    assert np.ptp(flat) < 2e-3 * np.ptp(X[inside] ** 2 / 2)
    v = np.ones_like(X) @ wc.influence_matrix(X.size, dX)
    np.testing.assert_allclose(v, v[::-1], rtol=1e-12)


@settings(max_examples=15, deadline=None)
@given(depth=st.floats(-0.5, 2.0), width=st.floats(0.1, 1.5), at=st.floats(-1.0, 1.0))
def test_contact_conditions_hold_for_any_local_wear(depth, width, at):
    """A wear pocket (depth > 0) or an unworn ridge (depth < 0) of any width under the band:
    the pressure is non-negative, carries the load, and the flanks touch (gap plus deflection
    at its least) wherever it presses and stand apart elsewhere."""
    X, dX = _cells()
    gap = X**2 / 2 + depth * np.exp(-((X - at) / width) ** 2)
    P, _ = wc.solve_gap_contact(gap, dX)
    assert np.all(P >= 0) and P.sum() * dX == pytest.approx(math.pi / 2, rel=1e-9)
    total = (P @ wc.influence_matrix(X.size, dX) + gap)[0]
    on = P[0] > 0
    touch = total[on].mean()
    assert np.abs(total[on] - touch).max() < 2e-3 * (gap.max() - gap.min())
    assert np.all(total[~on] >= touch - 2e-3 * (gap.max() - gap.min()))


def test_pressure_converges_under_refinement():
    """A pocket narrower than the band: the peak pressure converges as the cells shrink."""
    peaks = []
    for n in (64, 128, 256, 512):
        X, dX = _cells(n=n)
        P, _ = wc.solve_gap_contact(X**2 / 2 + 0.3 * np.exp(-(X / 0.3) ** 2), dX)
        peaks.append(P.max())
    d = np.abs(np.diff(peaks))
    assert d[2] < d[0] and peaks[-1] == pytest.approx(peaks[-2], rel=2e-3)


def _band(wear_scale: float, n: int = 201):
    geom = mesh_geometry(GearPair())
    s = geom.grid(n)
    R1, R2 = geom.curvature_radii(s)
    grid = np.linspace(s[0] - 0.5e-3, s[-1] + 0.5e-3, n + 2 * int(0.5e-3 / (s[1] - s[0])))
    # a worn pinion root and gear tip, falling smoothly to nothing at the pitch point
    depth = np.clip(-grid / abs(s[0]), 0.0, None) ** 2 * wear_scale
    w = np.full_like(s, 11824.0 / 0.030 / 2)
    return geom, s, R1, R2, grid, depth, w


def test_an_unworn_path_keeps_the_closed_form_hertz():
    geom, s, R1, R2, grid, depth, w = _band(0.0)
    c = wc.solve_worn_contact(s, w, R1, R2, geom.rb1, geom.rb2, E_STAR, grid, depth, depth, 20e-6)
    assert not c.solved.any()
    assert np.allclose(c.p_max, np.sqrt(w * E_STAR / (math.pi * R1 * R2 / (R1 + R2))))


def test_a_flank_worn_300um_has_a_finite_converged_pressure():
    """Severe wear: 300 um at the pinion root and gear tip. Every position is solved to a
    finite pressure carrying its load, and doubling the cells moves the peaks by < 2 %."""
    geom, s, R1, R2, grid, depth, w = _band(300e-6)
    c = wc.solve_worn_contact(s, w, R1, R2, geom.rb1, geom.rb2, E_STAR, grid, depth, 0 * depth,
                              20e-6)
    assert c.solved[s < -1e-3].all()
    assert np.all(np.isfinite(c.p_max)) and c.p_max.max() < 10e9
    assert np.allclose(c.P.sum(axis=1) * c.dX, math.pi / 2)
    fine = wc.solve_worn_contact(s, w, R1, R2, geom.rb1, geom.rb2, E_STAR, grid, depth,
                                 0 * depth, 20e-6, cells=2 * wc.CELLS)
    np.testing.assert_allclose(fine.p_max, c.p_max, rtol=0.02)


@settings(max_examples=10, deadline=None)
@given(scale=st.floats(0.0, 20e-6))
def test_sweep_keeps_the_worn_volume(scale):
    """Integrated along the flank, the swept per-pass wear is the point model's: the band moves
    wear between flank points but neither makes nor loses any (Hertz or worn bands)."""
    geom, s, R1, R2, grid, depth, w = _band(scale)
    c = wc.solve_worn_contact(s, w, R1, R2, geom.rb1, geom.rb2, E_STAR, grid, depth, depth, 20e-6)
    weight = 1e-3 + np.abs(s)
    swept = c.sweep(s, grid, R1 / geom.rb1, weight)
    edges = np.concatenate([[s[0]], 0.5 * (s[1:] + s[:-1]), [s[-1]]])
    assert swept.sum() * (grid[1] - grid[0]) == pytest.approx(
        np.sum(weight * w * np.diff(edges)), rel=1e-3)


def test_unloaded_positions_press_nothing_and_keep_the_sweep_small():
    """A pair that loses contact (no load at some positions, as under a large dynamic
    overshoot) has no band there: the sweep keeps the loaded positions' wear volume and its
    work stays that of the loaded bands' reach (no matrix spanning the whole flank)."""
    import tracemalloc

    geom, s, R1, R2, grid, depth, w = _band(20e-6)
    w = np.where((s > -2e-3) & (s < 1e-3), 0.0, w)
    c = wc.solve_worn_contact(s, w, R1, R2, geom.rb1, geom.rb2, E_STAR, grid, depth, depth, 20e-6)
    weight = 1e-3 + np.abs(s)
    tracemalloc.start()
    swept = c.sweep(s, grid, R1 / geom.rb1, weight)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    edges = np.concatenate([[s[0]], 0.5 * (s[1:] + s[:-1]), [s[-1]]])
    assert swept.sum() * (grid[1] - grid[0]) == pytest.approx(
        np.sum(weight * w * np.diff(edges)), rel=1e-3)
    assert peak < 50e6


def test_a_contact_that_does_not_settle_is_a_stated_scope_end(monkeypatch):
    """The pressure iteration's failure on deeply worn flanks ends the wear run as a scope end
    (OutOfScope, with the history a caller keeps), never as a raw RuntimeError."""
    import physics.tribology.worn_contact as wc
    from physics.params import OutOfScope, Scenario
    from physics.tribology.wear import simulate_wear

    original = wc.solve_gap_contact
    monkeypatch.setattr(wc, "solve_gap_contact",
                        lambda gap, dX: original(gap, dX, max_iter=1))
    with pytest.raises(OutOfScope, match="no longer meet as one line contact") as err:
        simulate_wear(Scenario(), 5e7)
    s, cycles, pinion, gear = err.value.history
    assert cycles.size == pinion.shape[0] == gear.shape[0] >= 1 and pinion.shape[1] == s.size


def test_the_compiled_contact_kernels_keep_ieee_arithmetic():
    """Fast-math lets the compiler reorder sums, and it did: the solver's pressures differed
    between a fresh compilation and numba's cache, so a dataset rebuilt in a fresh clone was
    not byte-identical (tests/dataset). Its kernels keep IEEE arithmetic."""
    for kernel in (wc._polonsky_keer, wc._start, wc._direction, wc._step, wc._sweep,
                   wc._passed_at, wc._hertz_passed):
        assert not kernel.targetoptions.get("fastmath"), kernel.py_func.__name__
