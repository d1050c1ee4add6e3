"""Wear driven by the tooth contact of the flanks as they are (physics.tribology.contact_wear):
the new flanks' rate against the thesis's on-path model, conservation of the worn volume,
convergence in the mesh positions, and the run's bookkeeping."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import physics.tribology.contact_wear as cw
from physics.gear.stiffness import mesh_stiffness
from physics.params import Scenario
from physics.tribology.wear import quasi_static_force, simulate_wear


def _dry(**solver) -> Scenario:
    base = Scenario()
    return dataclasses.replace(
        base, tribology=dataclasses.replace(base.tribology, regime="dry"),
        solver=dataclasses.replace(base.solver, **solver))


def test_new_flanks_wear_as_the_on_path_model_inside_the_path():
    """Away from the ends of the path (where the corners' early and late contact acts) new
    flanks lose the volume per cycle of the thesis's on-path Archard model, and locally the
    same rate within the levelling, which smooths the steps at the zone transitions."""
    scn = _dry()
    ms = mesh_stiffness(scn.gear, scn.material)
    g = ms.geometry
    grid = cw.whole_flank_grid(ms)
    r1, r2 = cw.wear_per_cycle(scn, ms, grid, 0 * grid, 0 * grid, quasi_static_force(scn, g))
    ref = simulate_wear(scn, 1.0)
    inner = np.linspace(g.s_start + 1.5e-3, g.s_end - 1.5e-3, 401)
    for rate, reference in ((r1, ref.first_rate.pinion), (r2, ref.first_rate.gear)):
        ours, theirs = np.interp(inner, grid, rate), np.interp(inner, ref.s, reference)
        assert ours.mean() == pytest.approx(theirs.mean(), rel=0.05)
        assert np.max(np.abs(ours - theirs)) < 0.35 * theirs.max()


@given(centre=st.lists(st.floats(-3e-3, 3e-3), min_size=1, max_size=6),
       width=st.floats(1e-6, 1e-3), depth=st.floats(1e-9, 1e-5))
@settings(max_examples=40, deadline=None)
def test_deposits_keep_their_volume(centre, width, depth):
    grid = np.linspace(-5e-3, 5e-3, 401)
    c = np.asarray(centre)
    out = cw._deposit(grid, c, np.full_like(c, width), np.full_like(c, depth))
    assert out.sum() * (grid[1] - grid[0]) == pytest.approx(c.size * width * depth, rel=1e-9)


@given(centre=st.lists(st.floats(-6e-3, 6e-3), min_size=1, max_size=8),
       width=st.lists(st.floats(1e-7, 4e-3), min_size=8, max_size=8),
       depth=st.lists(st.floats(0.0, 1e-5), min_size=8, max_size=8))
@settings(max_examples=60, deadline=None)
def test_a_deposit_fills_each_cell_by_its_overlap_with_it(centre, width, depth):
    """Each cell holds the deposits' depths weighted by the share of the cell each covers
    (a deposit partly or wholly beyond the grid's ends loses what lies beyond): against the
    overlap of every deposit with every cell, by broadcasting."""
    grid = np.linspace(-5e-3, 5e-3, 201)
    c = np.asarray(centre)
    w, d = np.asarray(width)[:c.size], np.asarray(depth)[:c.size]
    step = grid[1] - grid[0]
    left, right = grid - 0.5 * step, grid + 0.5 * step
    overlap = np.clip(np.minimum(right[:, None], (c + 0.5 * w)[None])
                      - np.maximum(left[:, None], (c - 0.5 * w)[None]), 0.0, None)
    expected = overlap @ d / step
    out = cw._deposit(grid, c, w, d)
    np.testing.assert_allclose(out, expected, rtol=1e-9, atol=1e-12 * max(d.max(), 1e-30))


def test_wear_converges_in_the_mesh_positions(monkeypatch):
    scn = _dry(update_um=3.0)
    runs = []
    for n in (256, 512):
        monkeypatch.setattr(cw, "POSITIONS", n)
        runs.append(cw.simulate_contact_wear(scn, 30e-6))
    (a1, a2, ca), (b1, b2, cb) = (r.at_depth(30e-6) for r in runs)
    assert cb == pytest.approx(ca, rel=0.05)
    active = runs[0].active
    for x, y in ((a1, b1), (a2, b2)):
        assert np.max(np.abs(x - y)[:, active]) < 0.1 * np.max(y[:, active])


def test_a_run_stops_at_its_depth_and_reads_back_any_depth_before():
    run = cw.simulate_contact_wear(_dry(update_um=3.0), 20e-6)
    deepest = run.deepest()
    assert np.all(np.diff(deepest) > 0) and np.all(np.diff(run.history[0]) > 0)
    assert deepest[-2] < 20e-6 <= deepest[-1]
    w1, w2, cycles = run.at_depth(deepest[-1])
    np.testing.assert_array_equal(w1, run.pinion)
    assert cycles == run.cycles
    w1, w2, cycles = run.at_depth(10e-6)
    # each point is linear within a block; the deepest point may move: within 1 %
    assert max(w1[:, run.active].max(), w2[:, run.active].max()) == pytest.approx(10e-6,
                                                                                 rel=0.01)
    assert 0 < cycles < run.cycles
    with pytest.raises(ValueError, match="outside the run's"):
        run.at_depth(1e-3)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"depth": 0.0}, "depth = 0.0 must be a finite depth > 0"),
    ({"depth": float("nan")}, "must be a finite depth"),
    ({"depth": 1e-6, "cycles": -1.0}, "cycles = -1.0 must be > 0"),
])
def test_bad_run_input(kwargs, message):
    with pytest.raises(ValueError, match=message):
        cw.simulate_contact_wear(_dry(), **kwargs)
