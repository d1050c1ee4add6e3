"""Potential-energy mesh stiffness of healthy and worn teeth (thesis 3.1-3.2)."""

from __future__ import annotations

import dataclasses
import logging
import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.gear.load_sharing import pair_loads
from physics.gear.stiffness import (
    MeshStiffness,
    SainsotRangeWarning,
    iso6336_single_pair_stiffness,
    sainsot_coefficients,
)
from physics.gear.tooth_fem import fe_pair_stiffness
from physics.params import GearPair, Material

warnings.simplefilter("ignore", SainsotRangeWarning)


@pytest.fixture(scope="module")
def ms():
    return MeshStiffness(GearPair(), Material())


def test_single_pair_stiffness_against_iso6336(ms):
    k = ms.pair(np.array([0.0]))[0] / 0.030 / 1e9  # N/(mm um)
    c_prime = iso6336_single_pair_stiffness(GearPair()) / 0.030 / 1e9
    assert c_prime == pytest.approx(11.9, abs=0.1)
    # ISO's theoretical c'_th = c' / 0.8 for solid discs is the model's counterpart
    assert 0.85 * c_prime / 0.8 < k < 1.25 * c_prime / 0.8


def test_mean_mesh_stiffness_against_iso6336(ms):
    cyc = ms.mesh_cycle(400)
    c_gamma = np.mean(cyc["k_total"]) / 0.030 / 1e9
    eps = ms.geometry.contact_ratio
    iso = iso6336_single_pair_stiffness(GearPair()) / 0.8 / 0.030 / 1e9 * (0.75 * eps + 0.25)
    assert 0.85 * iso < c_gamma < 1.25 * iso  # ISO: about 20 N/(mm um) for steel spur pairs


def test_double_to_single_ratio_and_zone_fractions(ms):
    cyc = ms.mesh_cycle(1000)
    double = cyc["k_pair2"] > 0
    eps = ms.geometry.contact_ratio
    assert double.mean() == pytest.approx(eps - 1, abs=2e-3)
    ratio = cyc["k_total"][double].mean() / cyc["k_total"][~double].mean()
    assert 1.5 < ratio < 1.9
    assert np.all(cyc["k_pair2"][~double] == 0)


def test_pair_stiffness_is_largest_mid_path(ms):
    g = ms.geometry
    s = np.linspace(g.s_start, g.s_end, 301)
    k = ms.pair(s)
    assert k[0] < k.max() and k[-1] < k.max()
    assert g.s_start + 0.2 * g.path_length < s[np.argmax(k)] < g.s_end - 0.2 * g.path_length


def test_hertz_term(ms):
    assert ms.k_hertz == pytest.approx(math.pi * 206e9 * 0.030 / (4 * 0.91))


def _synthetic_wear(g, s, depth):
    """Archard-like wear: deepest at both ends of the path, none at the pitch point."""
    return depth * (np.abs(s) / max(-g.s_start, g.s_end)) ** 2


def test_stiffness_falls_with_wear_and_more_in_the_double_zone(ms):
    g = ms.geometry
    s = g.grid(401)
    healthy = ms.mesh_cycle(400)
    drops = []
    for depth in (10e-6, 30e-6, 60e-6):
        w = _synthetic_wear(g, s, depth)
        worn = ms.mesh_cycle(400, s, w, 0.5 * w)
        assert np.all(worn["k_total"] <= healthy["k_total"] + 1e-6)
        drops.append(healthy["k_total"] - worn["k_total"])
    assert np.all(drops[0] <= drops[1] + 1e-6) and np.all(drops[1] <= drops[2] + 1e-6)
    double = healthy["k_pair2"] > 0
    assert drops[2][double].mean() > drops[2][~double].mean()


def test_energy_integrals_converge(ms):
    fine = MeshStiffness(GearPair(), Material(), n_fillet=1200, n_involute=2000)
    s = np.linspace(ms.geometry.s_start, ms.geometry.s_end, 50)
    assert np.allclose(ms.pair(s), fine.pair(s), rtol=1e-4)


@settings(max_examples=20, deadline=None)
@given(scale=st.floats(0.5, 4.0), width=st.floats(0.5, 3.0))
def test_stiffness_independent_of_module_and_linear_in_face_width(scale, width):
    """Plane elasticity of geometrically similar teeth: k depends on E and B only."""
    base = GearPair()
    scaled = dataclasses.replace(
        base, module_mm=2 * scale, face_width_mm=30 * width, bore_radius1_mm=10 * scale,
        bore_radius2_mm=15 * scale)
    a = MeshStiffness(base, Material(), plane="strain")
    b = MeshStiffness(scaled, Material(), plane="strain")
    fraction = np.linspace(0.02, 0.98, 9)
    s_a = a.geometry.s_start + fraction * a.geometry.path_length
    s_b = b.geometry.s_start + fraction * b.geometry.path_length
    assert np.allclose(b.pair(s_b), width * a.pair(s_a), rtol=1e-6)


def test_sainsot_coefficients_at_a_tabulated_point():
    # hand evaluation of L* at h_f = 2, theta_f = 0.1
    c = sainsot_coefficients(2.0, 0.1)
    expected_l = (-5.574e-5 / 0.01 - 1.9986e-3 * 4 - 2.3015e-4 * 20 + 4.7702e-3 / 0.1
                  + 0.0271 * 2 + 6.8045)
    assert c["L"] == pytest.approx(expected_l)


def test_bad_wear_inputs(ms):
    s = ms.geometry.grid(101)
    with pytest.raises(ValueError, match="does not match the roll grid"):
        ms.pair(np.array([0.0]), s, np.zeros(50), np.zeros(101))
    with pytest.raises(ValueError, match="negative wear"):
        ms.pair(np.array([0.0]), s, -np.ones(101) * 1e-6, np.zeros(101))
    with pytest.raises(ValueError, match="worn through"):
        ms.pair(np.array([0.0]), s, np.full(101, 2e-3), np.zeros(101))


def test_out_of_range_gear_body_warns():
    with pytest.warns(SainsotRangeWarning, match="extrapolated"):
        MeshStiffness(GearPair(bore_radius1_mm=2.0), Material())


def test_fe_agrees_with_energy_method_at_table7_positions(ms, caplog):
    """2-D plane-strain FE of both whole wheels against the energy method (coarse mesh); the
    solves log nothing at INFO where an app logs at INFO (scikit-fem's line per assembly)."""
    g = ms.geometry
    s = np.array([g.s_start + 0.25 * (g.contact_ratio - 1) * g.base_pitch, 0.0,
                  g.s_end - 0.1e-3])
    load = pair_loads(g, s, 11824.0, np.zeros_like, ms.pair_function())
    with caplog.at_level(logging.INFO):
        fe = fe_pair_stiffness(GearPair(), Material(), g, s, load, refine=1.0)
    assert np.allclose(fe.pair_stiffness, ms.pair(s), rtol=0.05)
    assert not [r for r in caplog.records if r.name.startswith("skfem")]


@pytest.mark.slow
def test_fe_converges_under_refinement(ms):
    g = ms.geometry
    s = np.array([0.0])
    ks = [fe_pair_stiffness(GearPair(), Material(), g, s, np.array([11824.0]),
                            refine=r).pair_stiffness[0] for r in (1, 2, 4, 8)]
    d = np.abs(np.diff(ks))
    assert d[2] < d[1] < d[0] and d[2] / ks[-1] < 1e-3
    assert ks[-1] == pytest.approx(ms.pair(s)[0], rel=0.02)
