"""Archard wear of both flanks (thesis 2.6-2.7): shape, trends, conservation, convergence."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.gear.geometry import mesh_geometry
from physics.gear.load_sharing import pair_loads
from physics.gear.stiffness import iso6336_single_pair_stiffness
from physics.params import (
    GearPair,
    Lubricant,
    Operating,
    OutOfScope,
    Scenario,
    Tribology,
    WearSolver,
)
from physics.tribology.wear import (
    check_shakedown,
    film_deficiency,
    quasi_static_force,
    simulate_wear,
)

CYCLES = 1e6


def _with(scn, part, **kw):
    return dataclasses.replace(scn, **{part: dataclasses.replace(getattr(scn, part), **kw)})


@pytest.fixture(scope="module")
def worn(baseline):
    return simulate_wear(baseline, CYCLES)


def _reach(res, at: float) -> float:
    """Roll distance the band's sweep spreads wear over at roll coordinate ``at`` [m]."""
    i = int(np.argmin(np.abs(res.s - at)))
    c, geom = res.first_rate.contact, res.geometry
    R1, R2 = geom.curvature_radii(res.s[i])
    return float(c.half_width[i] * max(geom.rb1 / R1, geom.rb2 / R2))


def test_wear_shape_of_thesis_2_7(worn):
    """Least wear at the pitch point, most at the pinion root and the gear tip, falling from the
    root to the pitch point and rising towards the tip (thesis 2.7, Figure 1), each feature
    spread over the band's sweep."""
    s, h1, h2 = worn.s, worn.pinion, worn.gear
    pitch = np.argmin(np.abs(s))
    assert abs(s[np.argmin(h1)]) <= _reach(worn, 0.0)
    assert h1[pitch] < 0.05 * h1.max()  # no sliding, little wear there
    assert np.argmax(h1) < len(s) // 10 and np.argmax(h2) < len(s) // 10  # pinion root, gear tip
    assert worn.mean_depth("pinion") > worn.mean_depth("gear")
    assert h1.max() > h2.max()
    lo, hi = worn.geometry.single_zone
    at = [s[0] + 2 * _reach(worn, s[0]), lo - _reach(worn, lo), lo + _reach(worn, lo), 0.0,
          hi - _reach(worn, hi), hi + _reach(worn, hi), s[-1]]
    h = np.interp(at, s, h1)
    assert h[0] > h[1] and h[2] > h[3] < h[4] and h[5] < h[6]


def test_step_at_both_zone_transitions(baseline):
    """The load halves where a second pair comes into contact: beside each zone transition the
    dry wear per unit of sliding (the load the flank point met) is about twice as large on the
    single-tooth side as on the double-tooth side, the change spread over the band's sweep
    (Bajpai et al. 2004) rather than the thesis's step at a point."""
    worn = simulate_wear(_with(baseline, "tribology", regime="dry"), 0.0)
    s, rate = worn.s, worn.first_rate
    met = rate.pinion / (2e-8 / 7e9 * np.abs(1 - rate.state.v2 / rate.state.v1) / 0.030)
    lo, hi = worn.geometry.single_zone
    for edge, inside in ((lo, +1), (hi, -1)):
        reach = _reach(worn, edge)
        single, double, far = np.interp(
            [edge + inside * 1.5 * reach, edge - inside * 1.5 * reach,
             edge - inside * 3 * reach], s, met)
        assert 1.6 < single / double < 2.4
        assert abs(double - far) < 0.1 * double  # the change sits at the transition


def test_swept_wear_keeps_archard_wear_volume(baseline):
    """Dry Archard: the band's sweep moves wear along the flank but keeps its volume: the worn
    area of each flank is the thesis's per-pass wear ``k w |1 - v_j/v_i| / H`` integrated along
    the path, and the gear's is z1/z2 times its own (it meshes that often per pinion cycle)."""
    dry = _with(baseline, "tribology", regime="dry")
    res = simulate_wear(dry, 0.0)
    rate, s = res.first_rate, res.s
    grid = res.s[0] + (np.arange(rate.flank1.size) - rate.path.start) * (s[1] - s[0])
    w = rate.load / 0.030
    slide = np.abs(rate.state.v1 - rate.state.v2)
    for flank, v, ratio in ((rate.flank1, rate.state.v1, 1.0), (rate.flank2, rate.state.v2,
                                                                 18 / 27)):
        point = ratio * 2e-8 * w * slide / v / 7e9
        inner = (grid > s[0] + 0.1 * (s[-1] - s[0])) & (grid < s[-1] - 0.1 * (s[-1] - s[0]))
        band = (s > s[0] + 0.1 * (s[-1] - s[0])) & (s < s[-1] - 0.1 * (s[-1] - s[0]))
        assert np.trapezoid(flank, grid) == pytest.approx(np.trapezoid(point, s), rel=0.02)
        assert np.trapezoid(flank[inner], grid[inner]) == pytest.approx(
            np.trapezoid(point[band], s[band]), rel=0.02)


def test_dry_archard_hand_calculation_in_the_single_tooth_zone(baseline):
    """dh1 = k F |1 - v2/v1| / (B H) per cycle for the pair carrying F (Archard over one pass),
    away from the zone transitions, where the conditions change little over the band."""
    dry = _with(baseline, "tribology", regime="dry")
    res = simulate_wear(dry, 0.0)
    rate, s = res.first_rate, res.s
    lo, _ = res.geometry.single_zone
    i = int(np.argmin(np.abs(s - (lo + 0.6e-3))))
    st_ = rate.state
    expected = 2e-8 * rate.load[i] / 0.030 * abs(1 - st_.v2[i] / st_.v1[i]) / 7e9
    assert rate.pinion[i] == pytest.approx(expected, rel=0.01)


def test_load_shared_by_stiffness_and_conserved(geom):
    s = geom.grid(201)
    k = iso6336_single_pair_stiffness(GearPair())
    F = 11824.0

    def stiff(x):
        return np.full_like(np.asarray(x, float), k)

    def no_gap(x):
        return np.zeros_like(np.asarray(x, float))

    load = pair_loads(geom, s, F, no_gap, stiff)
    d = geom.is_double(s)
    assert np.allclose(load[~d], F) and np.allclose(load[d], F / 2)
    # with a wear gap on the approach side, the partner pair takes the difference; loads add to F
    gap_len = 1e-6

    def gap(x):
        return np.where(np.asarray(x) < geom.single_zone[0], gap_len, 0.0)

    worn_load = pair_loads(geom, s, F, gap, stiff)
    inner = d & (s > geom.s_start) & (s < geom.s_end)  # partners of the ends sit on a boundary
    partner = pair_loads(geom, geom.partner(s[inner]), F, gap, stiff)
    assert np.allclose(worn_load[inner] + partner, F)
    first = s < geom.single_zone[0]
    assert np.allclose(worn_load[first], F / 2 - k * gap_len / 2)

    def deep(x):
        return np.where(np.asarray(x) < geom.single_zone[0], 1e-3, 0.0)

    assert np.allclose(pair_loads(geom, s, F, deep, stiff)[first], 0.0)  # contact lost


def test_wear_rises_with_torque_and_roughness(baseline):
    def mean(s):
        return simulate_wear(s, CYCLES).mean_depth()

    torques = [mean(_with(baseline, "operating", torque_Nm=t)) for t in (250, 300, 350)]
    assert torques[0] < torques[1] < torques[2]
    rough = [mean(_with(baseline, "tribology", sigma_um=s)) for s in (0.3, 0.5, 1.0)]
    assert rough[0] < rough[1] < rough[2]


def test_wear_falls_with_viscosity_and_pressure_viscosity(baseline):
    def mean(**kw):
        return simulate_wear(_with(baseline, "lubricant", **kw), CYCLES).mean_depth()

    assert mean(eta0_Pa_s=0.2) > mean(eta0_Pa_s=0.35) > mean(eta0_Pa_s=0.6)
    assert mean(alpha_m2_per_N=1.5e-8) > mean(alpha_m2_per_N=3.5e-8)


def test_speed_thickens_the_film_and_lowers_the_asperity_share(baseline):
    """Thesis 2.7.2's mechanism (with the solver's share the wear falls with speed too:
    ``test_calibration.py::test_wear_per_cycle_falls_with_speed``)."""
    states = [simulate_wear(_with(baseline, "operating", n1_rpm=n), 0.0) for n in (1000, 3000)]
    at = [np.interp(0.0, r.s, r.last_rate.state.h_min) for r in states]
    la = [np.interp(0.0, r.s, r.last_rate.state.asperity_ratio) for r in states]
    assert at[1] > at[0] and la[1] < la[0]


def test_dry_wear_above_mixed(baseline):
    """Thesis 2.7.5: dry friction wears more. With the calibrated lubricated coefficient the
    average is 2.3 times below the dry law's (thesis Table 5: 3.0); with the thesis's k = 5e-4
    it is four orders of magnitude below (docs/reproduction.md)."""
    mixed = simulate_wear(baseline, CYCLES)
    dry = simulate_wear(_with(baseline, "tribology", regime="dry"), CYCLES)
    assert dry.mean_depth() > 1.5 * mixed.mean_depth()
    thesis_k = simulate_wear(_with(baseline, "tribology", wear_coeff=5e-4), CYCLES)
    assert dry.mean_depth() > 1000 * thesis_k.mean_depth()


@settings(max_examples=8, deadline=None)
@given(b=st.floats(0.05, 0.95))
def test_boundary_share_blends_the_two_laws(baseline, b):
    """The unworn profile's wear rate under boundary share b is (1 - b) times the lubricated
    law's plus b times the dry law's at every point (the contact state of the lubricated
    regime; the dry law needs only the Hertz pressure and sliding distance, the same in both)."""
    first = {k: simulate_wear(_with(baseline, "tribology", **kw), 1.0).first_rate.pinion
             for k, kw in (("mixed", {}), ("dry", {"regime": "dry"}),
                           ("blend", {"boundary_share": b}))}
    np.testing.assert_allclose(first["blend"], (1 - b) * first["mixed"] + b * first["dry"],
                               rtol=1e-9, atol=1e-30)


def test_boundary_share_spreads_wear_over_the_dedendum(baseline):
    """More running time under boundary lubrication moves the worn profile from the lubricated
    law's root peak towards the dry law's wear over the whole dedendum."""
    ratio = []
    for b in (0.0, 0.5, 0.9):
        w = simulate_wear(_with(baseline, "tribology", boundary_share=b), CYCLES)
        ratio.append(w.pinion.max() / w.mean_depth())
    assert ratio[0] > ratio[1] > ratio[2]


def test_larger_centre_distance_less_wear(baseline):
    res = [simulate_wear(_with(baseline, "gear", center_distance_mm=a), CYCLES)
           for a in (44.955, 45.0, 45.045)]
    peaks = [r.pinion.max() for r in res]
    areas = [r.worn_area("pinion") + r.worn_area("gear") for r in res]
    assert peaks[0] > peaks[1] > peaks[2] and areas[0] > areas[1] > areas[2]


def test_wear_grows_with_cycles_everywhere(baseline):
    res = simulate_wear(baseline, 1.5e7, snapshots=[5e6, 1e7])
    a, b = res.snapshots[5e6], res.snapshots[1e7]
    assert np.all(b[0] >= a[0]) and np.all(res.pinion >= b[0])
    assert res.pinion[0] > b[0][0] > a[0][0] > 0


def test_profile_converges_under_grid_refinement(baseline):
    means = [simulate_wear(_with(baseline, "solver", n_points=n), CYCLES).mean_depth()
             for n in (101, 401, 1601)]
    assert abs(means[1] - means[2]) < 0.25 * abs(means[0] - means[2])  # converging
    assert means[1] == pytest.approx(means[2], rel=2e-3)


def test_profile_converges_under_update_refinement(baseline):
    """The explicit update converges at first order: halving the update step halves the change
    of the peak wear; the default 1 um step lies within 1 % of the limit."""
    dry = _with(baseline, "tribology", regime="dry")
    peaks = [simulate_wear(_with(dry, "solver", update_um=u), 1.5e7).pinion.max()
             for u in (1.0, 0.5, 0.25)]
    d = np.abs(np.diff(peaks))
    assert np.all((d[1:] / d[:-1] > 0.35) & (d[1:] / d[:-1] < 0.65))
    limit = peaks[-1] - (peaks[-2] - peaks[-1])  # Richardson, first order
    assert peaks[0] == pytest.approx(limit, rel=0.01)


def test_the_history_is_the_runs_own_wear_and_does_not_depend_on_where_it_ends(baseline):
    """Every block end is kept (the last is the result); a run told to stop once the root has
    worn 1 um stops at the first block past it, and its history is the start of a longer run's
    (without snapshots the blocks do not depend on the end): one run serves every shorter need."""
    long = simulate_wear(baseline, 1.5e7)
    cycles, pinion, gear = long.history
    assert cycles[0] == 0.0 and cycles[-1] == long.cycles == 1.5e7
    assert len(cycles) == long.blocks + 1 and np.all(np.diff(cycles) > 0)
    np.testing.assert_array_equal(pinion[-1], long.pinion)
    np.testing.assert_array_equal(gear[-1], long.gear)
    short = simulate_wear(baseline, 1.5e7, until=lambda c, w1: w1[-1, 0] >= 1e-6)
    c_short, p_short, g_short = short.history
    assert p_short[-1, 0] >= 1e-6 > p_short[-2, 0] and short.cycles == c_short[-1] < 1.5e7
    np.testing.assert_array_equal(c_short, cycles[:len(c_short)])
    np.testing.assert_array_equal(p_short, pinion[:len(c_short)])
    np.testing.assert_array_equal(g_short, gear[:len(c_short)])



def test_a_run_that_leaves_the_scope_carries_the_wear_the_model_followed(baseline):
    """A mesh force that grows with the wear (by half at 1 um) drives the flanks past the
    shakedown limit after a few blocks: the error carries every accepted block, the same
    blocks a run to the last of them makes."""
    dry = _with(baseline, "tribology", regime="dry")
    f0 = quasi_static_force(dry, mesh_geometry(dry.gear))

    def force(s, w1, w2):
        return np.full_like(s, f0 * (1 + 5e5 * max(w1.max(), w2.max())))

    with pytest.raises(OutOfScope, match="shakedown limit") as err:
        simulate_wear(dry, 1e9, force=force)
    s, cycles, pinion, gear = err.value.history
    assert len(cycles) >= 4 and cycles[0] == 0.0 and np.all(np.diff(cycles) > 0)
    assert pinion.shape == gear.shape == (len(cycles), len(s))
    followed = simulate_wear(dry, float(cycles[-1]), force=force)
    np.testing.assert_allclose(followed.history[0], cycles, rtol=1e-12)
    np.testing.assert_allclose(followed.pinion, pinion[-1], rtol=1e-9)

def test_updates_whenever_wear_changes_by_the_threshold(baseline):
    dry = _with(baseline, "tribology", regime="dry")
    res = simulate_wear(dry, 1.5e7)
    peak = max(res.pinion.max(), res.gear.max())
    # each block adds at most 1 um at the fastest point; step control shortens some
    assert math.ceil(peak / 1e-6) <= res.blocks <= 4 * math.ceil(peak / 1e-6)


def test_film_deficiency_limits():
    lub = Lubricant()
    assert film_deficiency(np.array([0.0]), 315.0, lub)[0] == 1.0
    psi = film_deficiency(np.array([0.5, 1.0, 2.0]), 315.0, lub)
    assert np.all(np.diff(psi) < 0)  # more sliding speed, less time to desorb
    assert film_deficiency(1.0, 400.0, lub) > film_deficiency(1.0, 330.0, lub)
    x = 3e-10 / (1.0 * 3e-12) * math.exp(-4.9e4 / (8.314462618 * 350.0))
    assert film_deficiency(1.0, 350.0, lub) == pytest.approx(1 - math.exp(-x), rel=1e-12)


def test_mesh_force_is_shared_per_instant(baseline):
    """A force per mesh position: each pair carries its share of the force at its own instant."""
    res = simulate_wear(baseline, 0.0)
    s, f0 = res.s, 11824.19747195
    shares = res.first_rate.load / f0

    def force(x, w1, w2):
        return f0 * (1.0 + 0.3 * np.sin(2 * np.pi * x / res.geometry.base_pitch))

    dyn = simulate_wear(baseline, 1e5, force=force)
    assert np.allclose(dyn.first_rate.load, shares * force(s, None, None), rtol=1e-9)
    assert not np.allclose(dyn.pinion, simulate_wear(baseline, 1e5).pinion, rtol=1e-3, atol=0)


def test_bad_mesh_force_shape(baseline):
    with pytest.raises(ValueError, match=r"mesh force has shape \(3,\).*one force per grid point"):
        simulate_wear(baseline, 1e5, force=lambda s, w1, w2: np.ones(3))


@settings(max_examples=25, deadline=None)
@given(n1=st.floats(500, 5000), torque=st.floats(100, 440), sigma=st.floats(0.1, 1.5))
def test_wear_physical_over_operating_range(n1, torque, sigma):
    """Over the model's scope (physics.scope: up to ~449 N m on this pair)."""
    scn = Scenario(operating=Operating(n1_rpm=n1, torque_Nm=torque),
                   tribology=Tribology(sigma_um=sigma), solver=WearSolver(n_points=101))
    res = simulate_wear(scn, 1e6)
    for h in (res.pinion, res.gear):
        assert np.all(np.isfinite(h)) and np.all(h >= 0)
    assert np.argmax(res.pinion) < len(res.s) // 8  # near the root
    pitch = np.argmin(np.abs(res.s))
    assert res.pinion[pitch] < 0.2 * res.pinion.max()  # the root wears far more than the pitch


def test_bad_cycles_refused(baseline):
    for bad in (-1, float("nan"), float("inf"), "1e6"):
        with pytest.raises(ValueError, match=r"cycles = .* must be a finite number"):
            simulate_wear(baseline, bad)
    with pytest.raises(ValueError, match="snapshots"):
        simulate_wear(baseline, 10.0, snapshots=[20.0])


def test_a_flank_past_the_shakedown_limit_leaves_the_scope():
    """The check itself: silent at the limit, out of scope above it, naming the pressure, where
    it acts, the limit and the deepest wear."""
    w = np.array([0.0, 40e-6, 0.0])
    s = np.array([-1e-3, 0.0, 1e-3])
    check_shakedown(np.array([np.nan, 2e9, 5e9]), s, 5e9, w, w, 1e6)
    with pytest.raises(OutOfScope, match=r"40 um\) carry a contact pressure of 5.10 GPa at roll "
                                         r"coordinate \+1.00 mm from the pitch point, above "
                                         r"the 5.00 GPa shakedown limit"):
        check_shakedown(np.array([2e9, 1e9, 5.1e9]), s, 5e9, w, w, 1e6)


def test_the_harshest_dataset_gearbox_stays_below_the_shakedown_limit():
    """Replicate 136 of the 256 case-3 gearboxes (high torque and wear coefficient, low
    damping): with the worn band's pressure from the gap, its pinion root wears to the end of
    the record with every flank pressure below the shakedown limit."""
    from physics.dataset.generation import DatasetSpec, run_unit

    rows, _ = run_unit(Scenario(), DatasetSpec(cases=(3,), replicates=256), 3, 136)
    wear = rows["root_wear_mm"].to_numpy()
    assert np.all(np.diff(wear) >= 0) and wear[-1] > 0
