"""The model's operating scope (physics.scope): limits computed by hand, refusals that name the
value and the fix, property-based over the parameter ranges."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.params import Dynamics, Operating, Scenario
from physics.scope import (
    SAMPLES_PER_MESH,
    STATIC_CONTACT_LIMIT,
    check_record,
    check_scope,
    mesh_frequency_hz,
    pitch_point_pressure,
    shakedown_pressure,
)


def test_pitch_point_pressure_by_hand():
    """Hertz at the pitch point of the thesis pair, 300 N m on the gear (Johnson eq. 4.45)."""
    a = math.radians(20.0)
    rb1, rb2 = 0.018 * math.cos(a), 0.027 * math.cos(a)
    R = 1 / (1 / (rb1 * math.tan(a)) + 1 / (rb2 * math.tan(a)))
    w = 300.0 / rb2 / 0.030
    e_star = 206e9 / (2 * (1 - 0.3**2))
    p = math.sqrt(w * e_star / (math.pi * R))
    assert pitch_point_pressure(Scenario()) == pytest.approx(p, rel=1e-9)


def test_pressure_grows_with_the_root_of_torque():
    p1 = pitch_point_pressure(Scenario(operating=Operating(torque_Nm=100.0)))
    p4 = pitch_point_pressure(Scenario(operating=Operating(torque_Nm=400.0)))
    assert p4 / p1 == pytest.approx(2.0, rel=1e-12)


@settings(max_examples=25, deadline=None)
@given(torque=st.floats(460.0, 9e5), speed=st.floats(100.0, 11000.0))
def test_torque_beyond_the_contact_capacity_is_refused(torque, speed):
    scn = Scenario(operating=Operating(n1_rpm=speed, torque_Nm=torque))
    with pytest.raises(ValueError, match=rf"operating\.torque_Nm = {torque:g} .*use at most"):
        check_scope(scn)


@settings(max_examples=25, deadline=None)
@given(speed=st.floats(11400.0, 99999.0))
def test_speed_the_sampling_cannot_resolve_is_refused(speed):
    scn = Scenario(operating=Operating(n1_rpm=speed))
    with pytest.raises(ValueError, match=rf"n1_rpm = {speed:g} .*raise dynamics.sample_rate_hz"):
        check_scope(scn)


@settings(max_examples=25, deadline=None)
@given(torque=st.floats(1.0, 440.0), speed=st.floats(400.0, 11000.0))
def test_the_thesis_range_is_inside(torque, speed):
    scn = Scenario(operating=Operating(n1_rpm=speed, torque_Nm=torque))
    assert check_scope(scn) is scn
    assert pitch_point_pressure(scn) <= STATIC_CONTACT_LIMIT
    assert scn.dynamics.sample_rate_hz >= SAMPLES_PER_MESH * mesh_frequency_hz(scn)


def test_short_record_is_refused_with_the_length_it_needs():
    scn = Scenario(dynamics=Dynamics(duration_s=0.005))
    with pytest.raises(ValueError, match=r"duration_s = 0.005 .* set dynamics.duration_s to "
                                         r"0.02 or more"):
        check_record(scn)
    assert check_scope(scn) is scn  # the model itself runs at any length


def test_numpy_scalars_are_accepted():
    scn = Scenario(operating=Operating(n1_rpm=np.int64(2000), torque_Nm=np.float32(300.0)))
    assert check_scope(scn).operating.n1_rpm == 2000.0
    assert type(scn.operating.n1_rpm) is float


@given(st.floats(1e9, 2e10))
def test_shakedown_limit_is_four_shear_yields_by_hand(hardness):
    """p0 = 4 k with k = Y / sqrt(3) and Y = H / 3 (Johnson 1985, 9.2; Tabor 1951): 0.770 H,
    5.39 GPa for 7 GPa; always above the 2.4 GPa static capacity the scenario is held to."""
    y = hardness / 3.0
    assert shakedown_pressure(hardness) == pytest.approx(4.0 * y / math.sqrt(3.0), rel=1e-12)
    assert shakedown_pressure(7e9) == pytest.approx(5.389e9, rel=1e-3)
    assert shakedown_pressure(7e9) > STATIC_CONTACT_LIMIT
