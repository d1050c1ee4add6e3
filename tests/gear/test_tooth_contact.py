"""Tooth contact of flanks of any shape (physics.gear.tooth_contact): conjugacy, exact
offsets, the tip corners off the path, the loaded contact against the on-path load sharing and
a hand calculation, and convergence in the flank's discretisation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.gear.load_sharing import pair_loads
from physics.gear.stiffness import MeshStiffness, mesh_stiffness
from physics.gear.tooth import generate_tooth
from physics.gear.tooth_contact import PairGaps, loaded_contact, worn_flank
from physics.params import GearPair, Scenario


@pytest.fixture(scope="module")
def ms():
    return MeshStiffness(Scenario().gear, Scenario().material)


def _path(ms, n=41, inset=0.05e-3):
    g = ms.geometry
    return np.linspace(g.s_start + inset, g.s_end - inset, n)


def test_unworn_involutes_meet_on_the_path_and_part_off_it(ms):
    g = ms.geometry
    gaps = PairGaps(g, ms.forms)
    assert np.max(np.abs(gaps(_path(ms)))) < 5e-9  # conjugate action, within the polyline
    before = gaps(g.s_start - np.linspace(0.05e-3, 1e-3, 20))
    after = gaps(g.s_end + np.linspace(0.05e-3, 1e-3, 20))
    for off in (before, after):  # the tip corners approach: a clearance growing with distance
        assert np.all(off > 0) and np.all(np.diff(off) > 0)
    # near an end the corner's clearance grows quadratically (a smooth approach)
    d = np.array([0.1e-3, 0.2e-3])
    ratio = gaps(g.s_end + 2 * d) / gaps(g.s_end + d)
    assert ratio == pytest.approx([4.0, 4.0], rel=0.35)


def test_uniform_wear_is_a_rotation(ms):
    """Material removed evenly along the normal of an involute is the same involute turned: the
    gap is the depth, whichever flank lost it."""
    g = ms.geometry
    grid = np.linspace(g.s_start - 0.5e-3, g.s_end + 0.5e-3, 401)
    mid = np.linspace(g.s_start + 1.5e-3, g.s_end - 1.5e-3, 15)
    h = np.full_like(grid, 10e-6)
    for w1, w2 in ((h, None), (None, h), (h / 2, h / 2)):
        gaps = PairGaps(g, ms.forms, grid, w1, w2)(mid)
        np.testing.assert_allclose(gaps, 10e-6, atol=5e-9)


@given(amp=st.floats(1e-6, 80e-6), centre=st.floats(-4e-3, 4e-3), width=st.floats(0.3e-3, 5e-3),
       gear_share=st.floats(0.0, 1.0))
@settings(max_examples=25, deadline=None)
def test_worn_flanks_never_part_by_more_than_their_conjugate_points(amp, centre, width,
                                                                    gear_share):
    """The conjugate points are one pair of candidates: the least gap is at most their summed
    wear, h1 + h2 (to first order it equals it; it is less where the flanks meet elsewhere)."""
    ms = mesh_stiffness(Scenario().gear, Scenario().material)  # built once (cached)
    g = ms.geometry
    grid = np.linspace(g.s_start, g.s_end, 301)
    wear = amp * np.exp(-0.5 * ((grid - centre) / width) ** 2)
    gaps = PairGaps(g, ms.forms, grid, (1 - gear_share) * wear, gear_share * wear)
    s = _path(ms, 31)
    first_order = np.interp(s, grid, wear)
    assert np.all(gaps(s) <= first_order + 5e-9)


def test_a_worn_band_relieves_the_approach_and_leaves_a_ridge(ms):
    """Pinion root worn 20 um from the start of the path up (tapering to 0 over 2 mm) and not
    below it, where conjugate action never reached. Before the start the gear's tip corner
    hovers over the band (it slides down the pinion flank as it approaches): the wear relieves
    the early contact by most of its depth. Just after the start the corner passes over the
    unworn flank below the band and finds that ridge, where the band alone would leave most of
    its 20 um."""
    g = ms.geometry
    grid = np.linspace(g.s_start, g.s_start + 2e-3, 101)
    wear = 20e-6 * (1 - (grid - g.s_start) / 2e-3)
    gaps = PairGaps(g, ms.forms, grid, wear, None)
    unworn = PairGaps(g, ms.forms)
    before = g.s_start - np.array([0.05e-3, 0.1e-3])
    assert np.all(gaps(before) - unworn(before) > 10e-6)
    after = g.s_start + np.array([0.02e-3, 0.05e-3, 0.1e-3])
    assert np.all(gaps(after) < 0.25 * np.interp(after, grid, wear))


def test_loaded_contact_balances_the_load_and_matches_the_on_path_sharing(ms):
    """Unworn: total load = force everywhere; inside the path (away from the ends, where the
    corners' early and late contact acts) the pairs share it as the on-path model does."""
    g = ms.geometry
    force = 300.0 / g.rb2
    gaps = PairGaps(g, ms.forms)
    lc = loaded_contact(g, gaps, ms.pair_function(), force, n=200)
    np.testing.assert_allclose(lc.loads.sum(axis=1), force, rtol=1e-9)
    pair_a = lc.loads[:, 1]
    reference = pair_loads(g, lc.roll, np.full_like(lc.roll, force), lambda s: 0 * s,
                           ms.pair_function())
    margin = 0.8e-3  # the corners' early and late contact reach about 0.5 mm here
    inside = (lc.roll > g.s_start + margin) & (lc.roll + g.base_pitch < g.s_end - margin) | (
        (lc.roll > g.s_end - g.base_pitch + margin) & (lc.roll < g.s_start + g.base_pitch
                                                       - margin))
    assert inside.sum() > 50
    np.testing.assert_allclose(pair_a[inside], reference[inside], rtol=0.01)
    cycle = ms.mesh_cycle(200)
    np.testing.assert_allclose(lc.stiffness[inside], cycle["k_total"][inside], rtol=0.01)
    # the corners: the approaching pair takes load before its theoretical entry
    assert lc.loads[:, 0].max() > 0.02 * force


def test_loaded_te_of_a_tip_relief_against_a_hand_calculation(ms):
    """A linear relief of the pinion tip, C = 15 um at the tip, from 1 mm before the end of
    the path. Its gap is at most the relief and less by the curvature's correction (the flanks
    meet beside the conjugate points where the relief slopes: about 1 um here); and in
    the double zone where the relieved pair still touches, the approach is the hand
    calculation ``(F + k_a g_a + k_r g_r) / (k_a + k_r)`` with ``g_r`` the relieved pair's
    gap."""
    g = ms.geometry
    grid = np.linspace(g.s_start, g.s_end, 401)
    start = g.s_end - 1e-3
    relief = np.where(grid > start, 15e-6 * (grid - start) / 1e-3, 0.0)
    gaps = PairGaps(g, ms.forms, grid, relief, None)
    k = ms.pair_function(grid, relief, None)
    force = 300.0 / g.rb2
    lc = loaded_contact(g, gaps, k, force, n=400)
    s_b = lc.roll + g.base_pitch
    two = (lc.loads[:, 2] > 0) & (lc.loads[:, 0] == 0) & (lc.loads[:, 3] == 0)
    pick = (s_b > start + 0.1e-3) & (s_b < g.s_end - 0.1e-3) & two
    assert pick.sum() > 5
    g_r = gaps(s_b[pick])
    first_order = np.interp(s_b[pick], grid, relief)
    assert np.all(g_r <= first_order + 5e-9) and np.all(g_r > first_order - 1.5e-6)
    k_a, k_r = k(lc.roll[pick]), k(s_b[pick])
    g_a = gaps(lc.roll[pick])  # 0 within the flanks' polyline (nanometres)
    hand = (force + k_a * g_a + k_r * g_r) / (k_a + k_r)
    np.testing.assert_allclose(lc.transmission_error[pick], hand, rtol=1e-9)


def test_gap_converges_as_the_flanks_are_refined():
    gear = GearPair()
    ms = MeshStiffness(gear, Scenario().material)
    g = ms.geometry
    grid = np.linspace(g.s_start, g.s_end, 301)
    wear = 12e-6 * ((grid - g.s_end) / (g.s_start - g.s_end)) ** 2
    s = np.concatenate([_path(ms, 21), g.s_start - np.array([0.1e-3, 0.2e-3])])
    values = [PairGaps(g, (generate_tooth(gear, 1, n // 2, n), generate_tooth(gear, 2, n // 2, n)),
                       grid, wear, wear / 3)(s) for n in (250, 500, 1000)]
    d1, d2 = np.max(np.abs(values[1] - values[0])), np.max(np.abs(values[2] - values[1]))
    assert d2 < 0.5 * d1 or d2 < 2e-9
    assert d2 < 0.02e-6


def test_bad_wear_is_refused(ms):
    g = ms.geometry
    grid = np.linspace(g.s_start, g.s_end, 11)
    with pytest.raises(ValueError, match="does not match the roll grid"):
        worn_flank(ms.forms[0], g, 1, grid, np.zeros(5))
    with pytest.raises(ValueError, match=">= 0"):
        worn_flank(ms.forms[0], g, 1, grid, -np.ones(11))
    with pytest.raises(ValueError, match="force = 0"):
        loaded_contact(g, PairGaps(g, ms.forms), ms.pair_function(), 0.0)
