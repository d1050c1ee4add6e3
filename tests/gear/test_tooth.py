"""Generated tooth form (involute + trochoid fillet) against closed-form geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from physics.gear.tooth import _rack, _to_tooth_frame, generate_tooth
from physics.params import GearPair


@pytest.fixture(scope="module", params=[1, 2], ids=["pinion", "gear"])
def form(request):
    return generate_tooth(GearPair(), request.param)


def test_involute_part_satisfies_the_involute_equation(form):
    i = form.involute_from
    R, x, y = form.radius[i:], form.x[i:], form.y[i:]
    a_r = np.arccos(form.rb / R)
    alpha = math.radians(20)
    theta = math.pi / (2 * form.z) + (math.tan(alpha) - alpha) - (np.tan(a_r) - a_r)
    assert np.allclose(np.arctan2(x, y), theta, atol=1e-12)
    assert R[-1] == pytest.approx(form.ra)


def test_tooth_thickness_at_the_pitch_circle_is_half_the_pitch(form):
    # arc tooth thickness at the pitch circle = pi m / 2 for unshifted teeth
    half_angle = np.interp(form.r, form.radius, np.arctan2(form.x, form.y))
    assert 2 * half_angle * form.r == pytest.approx(math.pi * form.module / 2, rel=1e-6)


def test_fillet_starts_on_the_root_circle_and_joins_the_involute_smoothly(form):
    assert form.radius[0] == pytest.approx(form.rf, rel=1e-12)
    i = form.involute_from
    jump = np.hypot(form.x[i] - form.x[i - 1], form.y[i] - form.y[i - 1])
    step = np.hypot(form.x[i + 1] - form.x[i], form.y[i + 1] - form.y[i])
    assert jump < 2 * step  # no gap at the joint
    assert form.nx[i] == pytest.approx(form.nx[i - 1], abs=5e-3)  # tangent continuity
    assert form.rb - 1e-5 < form.radius[i - 1]  # the fillet ends at or above the base circle


def test_normals_are_perpendicular_to_the_profile(form):
    dense = generate_tooth(GearPair(), 1 if form.z == 18 else 2, 3000, 3000)
    tx, ty = np.gradient(dense.x), np.gradient(dense.y)
    inner = np.ones(len(dense.x), bool)
    inner[[0, -1, dense.involute_from - 1, dense.involute_from]] = False  # one-sided differences
    assert np.allclose(dense.nx[inner], (ty / np.hypot(tx, ty))[inner], atol=1e-5)


def test_fillet_is_the_envelope_of_the_cutter_tip_round(form):
    """No cutter position cuts into the tooth, and each fillet point is touched by one."""
    gear = GearPair()
    x_c, y_c, rho = _rack(gear)
    phi = np.linspace(-0.6, 0.6, 6001)
    centres = _to_tooth_frame(np.broadcast_to([x_c, y_c], (phi.size, 2)), phi, form.r)
    i = form.involute_from
    pts = np.stack([form.x[:i], form.y[:i]], axis=1)
    dist = np.linalg.norm(pts[:, None, :] - centres[None, :, :], axis=2).min(axis=1)
    assert np.all(dist > rho - 1e-7)  # never inside the cutter
    assert np.allclose(dist, rho, atol=2e-7)  # and touched by it


def test_undercut_pinion_is_refused():
    with pytest.raises(ValueError, match="undercut"):
        generate_tooth(GearPair(z1=12, z2=27, bore_radius1_mm=5.0), 1)
