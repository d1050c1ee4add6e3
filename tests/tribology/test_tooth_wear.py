"""Each tooth its own flank (physics.tribology.contact_wear along the meshing sequence): the
uniform state as the special case, the cyclic symmetry of the sequence, the invariance to a
common offset of the teeth, a tooth ahead or worn ahead levelled by wear, and bad input."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import physics.tribology.contact_wear as cw
from physics.gear.stiffness import mesh_stiffness
from physics.params import Scenario
from physics.tribology.wear import quasi_static_force


@pytest.fixture(scope="module")
def pair():
    base = Scenario()
    scn = dataclasses.replace(base, tribology=dataclasses.replace(base.tribology, regime="dry"),
                              solver=dataclasses.replace(base.solver, update_um=3.0))
    ms = mesh_stiffness(scn.gear, scn.material)
    grid = cw.whole_flank_grid(ms)
    # a worn state: a pinion root band and a gear band, both off the pitch point
    w1 = 3e-6 * np.exp(-((grid + 2e-3) / 1e-3) ** 2)
    w2 = 1e-6 * np.exp(-((grid - 2e-3) / 1e-3) ** 2)
    return scn, ms, grid, w1, w2, quasi_static_force(scn, ms.geometry)


def _mean_depth(run: cw.ContactWear) -> np.ndarray:
    """Mean wear of each pinion tooth over its active profile at each block end ``(k, z1)``."""
    s = run.s[run.active]
    return np.trapezoid(run.history[1][:, :, run.active], s, axis=2) / (s[-1] - s[0])


def test_teeth_alike_along_the_hunting_period_wear_as_one_flank(pair):
    """Every tooth of both wheels carried, all alike: the 54 pairs of the thesis pair's hunting
    period each wear as the one-flank model does."""
    scn, ms, grid, w1, w2, force = pair
    z1, z2 = scn.gear.z1, scn.gear.z2
    one1, one2 = cw.wear_per_cycle(scn, ms, grid, w1, w2, force)
    r1, r2 = cw.tooth_wear_per_cycle(scn, ms, grid, np.tile(w1, (z1, 1)), np.tile(w2, (z2, 1)),
                                     force)
    assert r1.shape == (z1, grid.size) and r2.shape == (z2, grid.size)
    np.testing.assert_allclose(r1, np.broadcast_to(one1, r1.shape), rtol=0, atol=1e-12 * one1.max())
    np.testing.assert_allclose(r2, np.broadcast_to(one2, r2.shape), rtol=0, atol=1e-12 * one2.max())


def test_the_sequence_is_cyclic_and_a_common_offset_moves_no_load(pair):
    """Positions rolled by one tooth roll the rates by one tooth (the sequence has no first
    tooth); every tooth ahead by the same amount (a thicker tooth) closes every gap alike and
    changes no pair's load, so no rate."""
    scn, ms, grid, w1, w2, force = pair
    z1 = scn.gear.z1
    pos = np.random.default_rng(3).normal(0.0, 1e-6, z1)
    worn = np.tile(w1, (z1, 1))
    r1, r2 = cw.tooth_wear_per_cycle(scn, ms, grid, worn, w2[None], force,
                                     (pos, np.zeros(1)))
    s1, s2 = cw.tooth_wear_per_cycle(scn, ms, grid, worn, w2[None], force,
                                     (np.roll(pos, 1), np.zeros(1)))
    np.testing.assert_allclose(s1, np.roll(r1, 1, axis=0), rtol=0, atol=1e-9 * r1.max())
    np.testing.assert_allclose(s2, r2, rtol=0, atol=1e-9 * r2.max())
    assert np.ptp(r1.max(axis=1)) > 0.05 * r1.max()  # the teeth do differ
    one1, _ = cw.wear_per_cycle(scn, ms, grid, w1, w2, force)
    c1, _ = cw.tooth_wear_per_cycle(scn, ms, grid, worn, w2[None], force,
                                    (np.full(z1, 4e-6), np.zeros(1)))
    np.testing.assert_allclose(c1, np.broadcast_to(one1, c1.shape), rtol=0,
                               atol=1e-9 * one1.max())


def test_a_tooth_worn_at_its_root_hands_its_load_to_the_tooth_ahead_of_it(pair):
    """The order of the sequence: pinion tooth 1 worn at its root (the first double-contact
    zone, where it has just entered) sheds load to the pair then ahead of it in roll, tooth 0,
    at that tooth's tip (the second double-contact zone); tooth 2, which enters after tooth 1,
    meets it there tip to root unworn and wears as the rest."""
    scn, ms, grid, _, _, force = pair
    g = ms.geometry
    z1 = scn.gear.z1
    wear = np.zeros((z1, grid.size))
    root = (grid >= g.s_start) & (grid < g.single_zone[0])
    wear[1, root] = 3e-6
    r1, _ = cw.tooth_wear_per_cycle(scn, ms, grid, wear, np.zeros((1, grid.size)), force)
    tip = (grid > g.single_zone[1]) & (grid <= g.s_end)
    at_tip = r1[:, tip].sum(axis=1)
    assert at_tip[0] > 1.05 * at_tip[3]
    assert at_tip[2] == pytest.approx(at_tip[3], rel=1e-3)
    assert r1[1, root].sum() < 0.95 * r1[3, root].sum()  # the worn root itself is relieved


def test_a_tooth_ahead_wears_its_lead_away(pair):
    """A pinion tooth 2 um ahead of its place meets its mates early in the double-contact
    zones, carries more and wears faster than the rest: its lead over them, position less
    extra wear, falls at every block (Archard wear levels the teeth) and does not overshoot."""
    scn = pair[0]
    pos = np.zeros(scn.gear.z1)
    pos[0] = 2e-6
    run = cw.simulate_contact_wear(scn, 8e-6, positions=(pos, None))
    assert run.pinion.shape[0] == scn.gear.z1 and run.gear.shape[0] == 1
    depth = _mean_depth(run)
    lead = pos[0] - (depth[:, 0] - depth[:, 1:].mean(axis=1))
    assert np.all(np.diff(lead) < 0) and lead[-1] > 0
    assert depth[1, 0] > 1.03 * depth[1, 1:].mean()  # the first block's: it carries more
    # its two neighbours share the double-contact zones with it and carry less than the rest
    far = np.median(depth[-1, 2:-1])
    assert depth[-1, 1] < far and depth[-1, -1] < far


def test_a_tooth_worn_ahead_of_the_rest_is_caught_up(pair):
    """Damage induced on one tooth (2 um off its active profile, the start state): it stands
    back, carries less and wears slower; the rest catch up at every block."""
    scn, ms, grid = pair[:3]
    z1 = scn.gear.z1
    active = (grid >= ms.geometry.s_start) & (grid <= ms.geometry.s_end)
    start = np.zeros((z1, grid.size))
    start[0, active] = 2e-6
    run = cw.simulate_contact_wear(scn, 8e-6, start=(start, None))  # the gear new
    depth = _mean_depth(run)
    ahead = depth[:, 0] - depth[:, 1:].mean(axis=1)
    assert ahead[0] == pytest.approx(2e-6, rel=1e-3)
    assert np.all(np.diff(ahead) < 0) and ahead[-1] > 0


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"positions": (np.zeros(5), None)}, r"positions of the pinion of shape \(5,\): give 18"),
    ({"positions": (np.full(18, np.nan), None)}, "finite deviations"),
    ({"positions": (np.zeros(18),)}, "positions has 1 parts"),
    ({"start": (np.zeros(7), np.zeros(7))}, r"start wear of the pinion of shape \(7,\)"),
    ({"start": "grid"}, "start has a str; give a pair"),
    ({"positions": (["a"] * 18, None)}, "positions of the pinion are no numbers"),
    ({"positions": (np.full(18, 2e-6 * 1e6), None)}, "reach 2 m, beyond the 0.000324 m"),
    ({"start": (["a"], None)}, "start wear of the pinion is no array of depths"),
])
def test_bad_tooth_states_are_refused(pair, kwargs, message):
    with pytest.raises(ValueError, match=message):
        cw.simulate_contact_wear(pair[0], 1e-6, **kwargs)


def test_a_negative_start_is_refused(pair):
    scn, _, grid = pair[:3]
    start = np.zeros((scn.gear.z1, grid.size))
    start[3, 10] = -1e-6
    with pytest.raises(ValueError, match="negative or not finite"):
        cw.simulate_contact_wear(scn, 1e-6, start=(start, np.zeros(grid.size)))
