"""Manufacturing tolerances by accuracy grade (physics.gear.accuracy): the ISO formulas' hand
values, their step per grade, the backlash between its minimum and its maximum, and a flank's
form deviation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.gear.accuracy import (
    cumulative_pitch_tolerance_um,
    form_deviation,
    iso_round,
    it_tolerance_um,
    maximum_backlash_um,
    minimum_backlash_um,
    profile_form_tolerance_um,
    runout_tolerance_um,
    single_pitch_tolerance_um,
    tooth_positions_um,
    tooth_thickness_tolerance_um,
)


def test_grade_5_by_hand_for_the_thesis_pinion():
    """m 2 mm lies in the band 0.5-2 mm (mean 1), d 36 mm in 20-50 mm (mean sqrt(1000))."""
    d = math.sqrt(20 * 50)
    assert cumulative_pitch_tolerance_um(5, 2.0, 36.0, rounded=False) == pytest.approx(
        0.3 * 1 + 1.25 * math.sqrt(d) + 7)
    assert profile_form_tolerance_um(5, 2.0, 36.0, rounded=False) == pytest.approx(
        2.5 * 1 + 0.17 * math.sqrt(d) + 0.5)
    assert single_pitch_tolerance_um(5, 2.0, 36.0, rounded=False) == pytest.approx(
        0.3 * (1 + 0.4 * math.sqrt(d)) + 4)


@pytest.mark.parametrize("grade", range(1, 12))
def test_each_grade_is_sqrt2_the_one_before_and_runout_is_four_fifths_of_pitch(grade):
    for f in (runout_tolerance_um, profile_form_tolerance_um, cumulative_pitch_tolerance_um,
              single_pitch_tolerance_um):
        assert f(grade + 1, 2.0, 36.0, rounded=False) == pytest.approx(
            math.sqrt(2) * f(grade, 2.0, 36.0, rounded=False))
    assert runout_tolerance_um(grade, 3.0, 120.0, rounded=False) == pytest.approx(
        0.8 * cumulative_pitch_tolerance_um(grade, 3.0, 120.0, rounded=False))


def test_rounding_steps_of_the_standard():
    assert (iso_round(4.26), iso_round(7.74), iso_round(7.76), iso_round(45.5)) == (
        4.3, 7.5, 8.0, 46.0)


def test_standard_tolerances_match_iso_286_for_30_to_50_mm():
    """The published IT values of the band 30-50 mm follow from IT = k i."""
    assert [round(it_tolerance_um(k, 36.0)) for k in (6, 7, 8, 9, 10)] == [16, 25, 39, 62, 100]


def test_minimum_backlash_by_hand():
    assert minimum_backlash_um(45.0, 2.0) == pytest.approx(2 / 3 * 0.1425 * 1000)


def test_maximum_backlash_grows_with_the_grade_from_the_minimum():
    top = [maximum_backlash_um(g, 2.0, 36.0, 54.0, 45.0, 20.0) for g in range(4, 10)]
    assert all(np.diff(top) > 0)
    assert top[0] > minimum_backlash_um(45.0, 2.0)
    # the thinner teeth open it by their tolerances times cos(alpha); a wider grade's
    # thickness tolerance is larger and at least its run-out's 2 tan(alpha) share
    t = tooth_thickness_tolerance_um(9, 2.0, 36.0, 20.0)
    assert t > 2 * math.tan(math.radians(20)) * runout_tolerance_um(9, 2.0, 36.0, rounded=False)


def test_outside_the_bands_is_refused():
    with pytest.raises(ValueError, match="module"):
        profile_form_tolerance_um(6, 0.3, 36.0)
    with pytest.raises(ValueError, match="accuracy grade"):
        runout_tolerance_um(13, 2.0, 36.0)


def test_form_deviation_by_hand():
    """Two half-waves from a quarter turn: +A at the start of contact, -A midway, +A at the
    end; metres from micrometres."""
    s = np.array([-1.0, 0.5, 2.0]) * 1e-3  # start, middle and end of a 3 mm path
    got = form_deviation(s, -1e-3, 3e-3, 4.0, 2.0, math.pi / 2)
    assert got == pytest.approx([4e-6, -4e-6, 4e-6], abs=1e-18)


@settings(max_examples=50, deadline=None)
@given(amp=st.floats(0.0, 20.0, allow_subnormal=False), waves=st.floats(0.5, 8.0),
       phase=st.floats(0, 2 * math.pi))
def test_form_deviation_stays_within_its_tolerance_band(amp, waves, phase):
    """Its peak-to-valley over the active profile is at most twice its amplitude (the
    tolerance ``f_f_alpha`` bounds it), and it repeats with the amplitude's sign."""
    s = np.linspace(0.0, 1.0, 501)
    d = form_deviation(s, 0.0, 1.0, amp, waves, phase)
    assert np.ptp(d) <= 2 * amp * 1e-6 * (1 + 1e-12)
    assert np.allclose(form_deviation(s, 0.0, 1.0, -amp, waves, phase), -d)


@given(z=st.integers(10, 120), grade=st.integers(3, 10), seed=st.integers(0, 2**31))
@settings(max_examples=40, deadline=None)
def test_tooth_positions_are_the_gears_own_and_within_its_tolerances(z, grade, seed):
    """The same seed gives the same teeth; the positions sum to zero about their mean, as the
    single pitch deviations (neighbours' differences, around the gear) do; the total spread
    stays within the cumulative pitch tolerance F_p."""
    x = tooth_positions_um(z, grade, 2.0, 36.0, seed)
    np.testing.assert_array_equal(x, tooth_positions_um(z, grade, 2.0, 36.0, seed))
    assert len(x) == z and abs(x.sum()) < 1e-9
    pitch = np.diff(np.append(x, x[0]))
    assert abs(pitch.sum()) < 1e-9
    assert np.ptp(x) < cumulative_pitch_tolerance_um(grade, 2.0, 36.0, rounded=False)


def test_single_pitch_deviations_reach_their_tolerance_at_three_sigma():
    """Over many gears, the share of single pitch deviations beyond f_pt is that of a normal
    beyond three standard deviations (0.27 %)."""
    x = np.concatenate([tooth_positions_um(50, 6, 2.0, 36.0, seed) for seed in range(400)])
    pitch = np.diff(x.reshape(400, 50), axis=1)
    outside = np.mean(np.abs(pitch) > single_pitch_tolerance_um(6, 2.0, 36.0, rounded=False))
    assert outside == pytest.approx(0.0027, abs=0.0015)

