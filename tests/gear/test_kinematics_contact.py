"""Kinematics (thesis 2.3) and Hertz line contact against limits and hand calculations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.gear import contact, kinematics
from physics.params import Material


def _velocities(geom, s, n1=2000.0):
    R1, R2 = geom.curvature_radii(s)
    return kinematics.surface_velocities(R1, R2, n1 * math.pi / 30, 18, 27)


def test_zero_sliding_at_the_pitch_point(geom):
    v1, v2 = _velocities(geom, np.array([0.0]))
    assert kinematics.sliding_velocity(v1, v2)[0] == pytest.approx(0.0, abs=1e-12)
    L1, L2 = kinematics.sliding_distances(1e-4, v1, v2)
    assert L1[0] == pytest.approx(0.0, abs=1e-15) and L2[0] == pytest.approx(0.0, abs=1e-15)


def test_sliding_reverses_at_the_pitch_point_and_grows_linearly(geom):
    s = np.linspace(geom.s_start, geom.s_end, 101)
    v1, v2 = _velocities(geom, s)
    signed = v1 - v2
    assert np.all(signed[s < -1e-9] < 0) and np.all(signed[s > 1e-9] > 0)
    # v1 - v2 = (omega1 + omega2) s exactly on the line of action
    omega1 = 2000 * math.pi / 30
    assert np.allclose(signed, omega1 * (1 + 18 / 27) * s)


def test_sliding_largest_at_the_path_ends(geom):
    s = geom.grid(201)
    v1, v2 = _velocities(geom, s)
    L1, L2 = kinematics.sliding_distances(1e-4, v1, v2)
    # specific sliding is largest at each wheel's root: pinion root at B1, gear root at B2
    assert np.argmax(L1) == 0
    assert np.argmax(L2) == len(s) - 1
    assert np.argmin(np.abs(s)) == np.argmin(L1)


def test_sliding_distances_cover_the_same_slip_time():
    # both points slide |v1 - v2| for their own dwell times 2b/v_i: L1 v1 = L2 v2
    v1, v2 = np.array([1.2, 0.4]), np.array([0.8, 1.9])
    L1, L2 = kinematics.sliding_distances(2e-4, v1, v2)
    assert np.allclose(L1 * v1, L2 * v2)


def test_entraining_velocity_is_the_mean():
    assert kinematics.entraining_velocity(1.0, 3.0) == 2.0


def test_hertz_hand_calculation():
    steel = Material()
    e_star = contact.reduced_modulus(steel, steel)
    assert e_star == pytest.approx(206e9 / (2 * (1 - 0.09)))
    w, R = 3.94e5, 3.694e-3  # thesis pitch point, 300 N m, single pair
    b = contact.hertz_half_width(w, R, e_star)
    assert b == pytest.approx(math.sqrt(4 * w * R / (math.pi * e_star)))
    pmax = contact.hertz_max_pressure(w, b)
    assert pmax == pytest.approx(math.sqrt(w * e_star / (math.pi * R)))  # Johnson eq. 4.45
    assert 1.9e9 < pmax < 2.1e9
    assert contact.hertz_mean_pressure(w, b) == pytest.approx(math.pi * pmax / 4)


@settings(max_examples=50)
@given(w=st.floats(1e3, 1e7), R=st.floats(1e-4, 1e-1))
def test_hertz_pressure_integrates_to_the_load(w, R):
    e_star = 1.13e11
    b = contact.hertz_half_width(w, R, e_star)
    pmax = contact.hertz_max_pressure(w, b)
    x = np.linspace(-b, b, 20001)
    load = np.trapezoid(pmax * np.sqrt(np.clip(1 - (x / b) ** 2, 0, None)), x)
    assert load == pytest.approx(w, rel=1e-4)


def test_equivalent_radius():
    assert contact.equivalent_radius(2.0, 2.0) == pytest.approx(1.0)
