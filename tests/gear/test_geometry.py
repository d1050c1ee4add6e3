"""Meshing geometry (thesis 2.1) against hand calculations and geometric identities."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, reject, settings
from hypothesis import strategies as st

from physics.gear.geometry import mesh_geometry
from physics.params import GearPair


def contact_ratio_by_tip_pressure_angles(g: GearPair) -> float:
    """Independent form: eps = [z1 (tan a_a1 - tan a_w) + z2 (tan a_a2 - tan a_w)] / (2 pi)."""
    m, a = g.module_mm, math.radians(g.pressure_angle_deg)
    r1, r2 = m * g.z1 / 2, m * g.z2 / 2
    aa1 = math.acos(r1 * math.cos(a) / (r1 + g.ha_star * m))
    aa2 = math.acos(r2 * math.cos(a) / (r2 + g.ha_star * m))
    a0 = r1 + r2
    aw = math.acos(a0 * math.cos(a) / (g.center_distance_mm or a0))
    return (g.z1 * (math.tan(aa1) - math.tan(aw)) + g.z2 * (math.tan(aa2) - math.tan(aw))) / (
        2 * math.pi)


def test_thesis_pair_contact_ratio_hand_calculation(geom):
    # rb1 = 16.914, ra1 = 20, rb2 = 25.372, ra2 = 29 mm; path = 10.672 + 14.046 - 15.391 mm
    path = math.sqrt(20**2 - 16.9145**2) + math.sqrt(29**2 - 25.3717**2) - 45 * math.sin(
        math.radians(20))
    assert geom.path_length * 1e3 == pytest.approx(path, rel=1e-4)
    assert geom.contact_ratio == pytest.approx(path / (math.pi * 2 * math.cos(math.radians(20))),
                                               rel=1e-4)
    assert geom.contact_ratio == pytest.approx(1.5797, abs=1e-4)
    assert geom.contact_ratio == pytest.approx(contact_ratio_by_tip_pressure_angles(GearPair()))


@pytest.mark.parametrize("a_mm", [44.955, 45.045, 45.4])
def test_non_standard_centre_distance_matches_independent_form(a_mm):
    g = GearPair(center_distance_mm=a_mm)
    assert mesh_geometry(g).contact_ratio == pytest.approx(contact_ratio_by_tip_pressure_angles(g))


def test_larger_centre_distance_smaller_contact_ratio():
    eps = [mesh_geometry(GearPair(center_distance_mm=a)).contact_ratio
           for a in (44.955, 45.0, 45.045)]
    assert eps[0] > eps[1] > eps[2]


def test_zones_have_thesis_proportions(geom):
    lo, hi = geom.single_zone
    pb, eps = geom.base_pitch, geom.contact_ratio
    assert lo - geom.s_start == pytest.approx((eps - 1) * pb)
    assert geom.s_end - hi == pytest.approx((eps - 1) * pb)
    assert hi - lo == pytest.approx((2 - eps) * pb)
    assert lo < 0 < hi  # pitch point in the single-tooth zone for this pair


def test_partner_is_one_base_pitch_away_and_also_on_the_path(geom):
    s = geom.grid(401)
    d = geom.is_double(s)
    other = geom.partner(s[d])
    assert np.allclose(np.abs(other - s[d]), geom.base_pitch)
    assert np.all((other >= geom.s_start - 1e-12) & (other <= geom.s_end + 1e-12))
    assert np.all(np.isnan(geom.partner(s[~d])))


def test_grid_holds_the_zone_boundaries(geom):
    s = geom.grid(201)
    assert len(s) == 201 and np.all(np.diff(s) > 0)
    for b in (*geom.single_zone, geom.s_start, geom.s_end):
        assert np.min(np.abs(s - b)) < 1e-15


def test_radii_of_curvature_add_up_to_the_tangent_length(geom):
    s = geom.grid(51)
    R1, R2 = geom.curvature_radii(s)
    assert np.allclose(R1 + R2, geom.center_distance * math.sin(geom.alpha_w))
    assert np.all(R1 > 0) and np.all(R2 > 0)
    r1, r2 = geom.flank_radii(np.array([geom.s_start, 0.0, geom.s_end]))
    assert r2[0] == pytest.approx(geom.ra2) and r1[-1] == pytest.approx(geom.ra1)
    assert r1[1] == pytest.approx(geom.r1) and r2[1] == pytest.approx(geom.r2)


@settings(max_examples=60, deadline=None)
@given(z1=st.integers(18, 40), dz=st.integers(0, 80), alpha=st.floats(18, 25),
       m=st.floats(1, 8), rel_a=st.floats(-0.003, 0.01))
def test_geometry_identities_over_the_design_space(z1, dz, alpha, m, rel_a):
    z2 = z1 + dz
    g0 = GearPair(module_mm=m, z1=z1, z2=z2, pressure_angle_deg=alpha, bore_radius1_mm=0.1,
                  bore_radius2_mm=0.1)
    a = g0.standard_center_distance_mm * (1 + rel_a)
    g = GearPair(module_mm=m, z1=z1, z2=z2, pressure_angle_deg=alpha, bore_radius1_mm=0.1,
                 bore_radius2_mm=0.1, center_distance_mm=a)
    try:
        geom = mesh_geometry(g)
    except ValueError:
        reject()  # outside the model's scope: refused, tested below
    assert 1 < geom.contact_ratio < 2
    assert geom.contact_ratio == pytest.approx(contact_ratio_by_tip_pressure_angles(g), rel=1e-9)
    assert geom.s_start < 0 < geom.s_end  # the pitch point lies on the path of contact
    R1, R2 = geom.curvature_radii(np.linspace(geom.s_start, geom.s_end, 7))
    assert np.all(R1 > 0) and np.all(R2 > 0)


def test_undercut_pinion_refused():
    with pytest.raises(ValueError, match=r"z1 = 15 is undercut.*17\.10"):
        mesh_geometry(GearPair(z1=15))


def test_contact_ratio_above_two_refused():
    with pytest.raises(ValueError, match=r"contact ratio 2\.\d+ .* outside \(1, 2\)"):
        mesh_geometry(GearPair(z1=40, z2=200, ha_star=1.25, pressure_angle_deg=16.0))


def test_centre_distance_without_clearance_refused():
    with pytest.raises(ValueError, match=r"center_distance_mm = 44\.4 must lie in"):
        mesh_geometry(GearPair(center_distance_mm=44.4))


def test_tip_interference_refused():
    with pytest.raises(ValueError, match="involute interference"):
        mesh_geometry(GearPair(center_distance_mm=44.55))
