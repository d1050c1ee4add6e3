"""Bad input to the tooth-position API (physics.gear.accuracy.tooth_positions_um, the ISO 1328
tolerance functions, physics.dynamics.teeth.with_tooth_positions and per_tooth_model),
refused before any work in one line that names the argument, the value, the rule and the fix:

- a tooth count that is not a whole number in GearPair's range (18.5, NaN, 10**12), or no
  number at all (None, '18'); a whole numpy integer or float (np.int64(18), 18.0) is taken, as
  GearPair takes it;
- an accuracy grade that is not a whole ISO 1328-1 grade in [0, 12] (5.5, True, '5', None);
- a seed that is not an int >= 0 (True, None, 1.0);
- a module or diameter that is no finite number (None, '36', {});
- tooth models that are no sequence of PairModel (None, [1, 2]); positions that are None, a
  scalar, 2-D, text, NaN or infinite, or far beyond any pitch deviation (um or mm given as m).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.dynamics.model import build_model
from physics.dynamics.teeth import per_tooth_model, with_tooth_positions
from physics.gear.accuracy import (
    cumulative_pitch_tolerance_um,
    maximum_backlash_um,
    minimum_backlash_um,
    profile_form_tolerance_um,
    runout_tolerance_um,
    single_pitch_tolerance_um,
    tooth_positions_um,
    tooth_thickness_tolerance_um,
)
from physics.gear.stiffness import mesh_stiffness
from physics.params import GearPair, Scenario

TOLERANCES = (cumulative_pitch_tolerance_um, runout_tolerance_um, profile_form_tolerance_um,
              single_pitch_tolerance_um)


def one_line(e: pytest.ExceptionInfo) -> str:
    text = str(e.value)
    assert "\n" not in text
    return text


# --- tooth_positions_um: the tooth count -----------------------------------------------------


@pytest.mark.parametrize("z", [18.5, float("nan"), math.inf, 10**12, 4, 1001, -18])
def test_a_tooth_count_that_is_not_a_whole_number_in_range_is_refused(z):
    with pytest.raises(ValueError, match=r"^z = .* must be a whole number in \[5, 1000\]") as e:
        tooth_positions_um(z, 5, 2.0, 36.0, 0)
    one_line(e)


@pytest.mark.parametrize("z", [None, "18", [18], True])
def test_a_tooth_count_that_is_no_number_is_a_type_error(z):
    with pytest.raises(TypeError, match=r"^z = .* must be a whole number") as e:
        tooth_positions_um(z, 5, 2.0, 36.0, 0)
    assert repr(z) in one_line(e)


@pytest.mark.parametrize("z", [18, 18.0, np.int64(18), np.int16(18), np.float64(18)])
def test_a_whole_tooth_count_is_taken_as_gear_pair_takes_it(z):
    """GearPair accepts each of these for z1; the teeth are those of z = 18."""
    assert GearPair(z1=z).z1 == 18
    np.testing.assert_array_equal(tooth_positions_um(z, 5, 2.0, 36.0, 3),
                                  tooth_positions_um(18, 5, 2.0, 36.0, 3))


def test_the_tooth_count_limits_are_gear_pairs():
    for z in (4, 1001):
        with pytest.raises(ValueError, match=rf"^gear.z1 = {z} must be a whole number in "
                                             r"\[5, 1000\]"):
            GearPair(z1=z, z2=max(z, 27))
        with pytest.raises(ValueError, match=r"\[5, 1000\]"):
            tooth_positions_um(z, 5, 2.0, 36.0, 0)
    assert len(tooth_positions_um(5, 5, 2.0, 36.0, 0)) == 5
    assert len(tooth_positions_um(1000, 5, 2.0, 36.0, 0)) == 1000


# --- accuracy grades ---------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(grade=st.integers(0, 12), as_float=st.booleans())
def test_any_whole_grade_in_range_is_accepted(grade, as_float):
    q = float(grade) if as_float else grade
    x = tooth_positions_um(18, q, 2.0, 36.0, 0)
    np.testing.assert_array_equal(x, tooth_positions_um(18, grade, 2.0, 36.0, 0))
    for f in TOLERANCES:
        assert f(q, 2.0, 36.0) == f(grade, 2.0, 36.0) > 0


@settings(max_examples=60, deadline=None)
@given(grade=st.floats(-1e6, 1e6, allow_nan=False).filter(lambda g: not g.is_integer()))
def test_any_fractional_grade_is_refused(grade):
    with pytest.raises(ValueError, match=r"^grade = .* whole number in \[0, 12\]"):
        tooth_positions_um(18, grade, 2.0, 36.0, 0)
    for f in TOLERANCES:
        with pytest.raises(ValueError, match=r"accuracy grade"):
            f(grade, 2.0, 36.0)


@settings(max_examples=40, deadline=None)
@given(grade=st.integers(-10**6, 10**6).filter(lambda g: not 0 <= g <= 12))
def test_any_whole_grade_outside_the_standard_is_refused(grade):
    for f in TOLERANCES:
        with pytest.raises(ValueError, match=r"\[0, 12\].*ISO 1328-1:1995 accuracy grade"):
            f(grade, 2.0, 36.0)


@pytest.mark.parametrize("grade", [True, False, None, "5", [5], 5 + 0j])
def test_a_grade_that_is_no_number_is_a_type_error(grade):
    for f in (*TOLERANCES, lambda q, m, d: tooth_positions_um(18, q, m, d, 0)):
        with pytest.raises(TypeError, match=r"^grade = .* must be a whole number") as e:
            f(grade, 2.0, 36.0)
        assert repr(grade) in one_line(e)


def test_nan_and_infinite_grades_are_refused():
    for grade in (float("nan"), math.inf, -math.inf):
        with pytest.raises(ValueError, match=r"^grade = "):
            single_pitch_tolerance_um(grade, 2.0, 36.0)


# --- seed -------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [True, False, None, 1.0, "1", np.float64(2)])
def test_a_seed_that_is_not_an_int_is_a_type_error(seed):
    with pytest.raises(TypeError, match=r"^seed = .* must be an int >= 0") as e:
        tooth_positions_um(18, 5, 2.0, 36.0, seed)
    one_line(e)


@pytest.mark.parametrize("seed", [-1, np.int8(-1)])
def test_a_negative_seed_is_refused(seed):
    with pytest.raises(ValueError, match=r"^seed = .* must be an int >= 0"):
        tooth_positions_um(18, 5, 2.0, 36.0, seed)


def test_numpy_integer_seeds_are_the_same_gear():
    np.testing.assert_array_equal(tooth_positions_um(18, 5, 2.0, 36.0, np.int64(7)),
                                  tooth_positions_um(18, 5, 2.0, 36.0, 7))


# --- module and diameter ----------------------------------------------------------------------


@pytest.mark.parametrize(("module_mm", "d_mm", "name"), [
    (None, 36.0, "module_mm"), ({}, 36.0, "module_mm"), ("2", 36.0, "module_mm"),
    (True, 36.0, "module_mm"), (2.0, "36", "d_mm"), (2.0, None, "d_mm")])
def test_a_size_that_is_no_number_is_a_type_error(module_mm, d_mm, name):
    for f in TOLERANCES:
        with pytest.raises(TypeError, match=rf"^{name} = .* must be a finite number > 0") as e:
            f(5, module_mm, d_mm)
        one_line(e)
    with pytest.raises(TypeError, match=rf"^{name} = "):
        tooth_positions_um(18, 5, module_mm, d_mm, 0)


@pytest.mark.parametrize(("module_mm", "d_mm", "name"), [
    (float("nan"), 36.0, "module_mm"), (-2.0, 36.0, "module_mm"), (2.0, math.inf, "d_mm"),
    (2.0, 0.0, "d_mm")])
def test_a_size_that_is_not_finite_and_positive_is_refused(module_mm, d_mm, name):
    for f in TOLERANCES:
        with pytest.raises(ValueError, match=rf"^{name} = .* must be a finite number > 0"):
            f(5, module_mm, d_mm)


def test_sizes_outside_the_standards_bands_name_the_argument():
    with pytest.raises(ValueError, match=r"^d_mm \(reference diameter\) = 1e\+09 mm lies "
                                         r"outside the standard's size bands"):
        tooth_positions_um(18, 5, 2.0, 1e9, 0)


def test_the_backlash_and_thickness_functions_check_their_grades_and_sizes():
    with pytest.raises(ValueError, match=r"^grade = 3 must be a whole number in \[4, 9\]"):
        tooth_thickness_tolerance_um(3, 2.0, 36.0, 20.0)
    with pytest.raises(TypeError, match=r"^grade = True"):
        maximum_backlash_um(True, 2.0, 36.0, 54.0, 45.0, 20.0)
    with pytest.raises(TypeError, match=r"^pressure_angle_deg = None"):
        tooth_thickness_tolerance_um(6, 2.0, 36.0, None)
    with pytest.raises(ValueError, match=r"^pressure_angle_deg = 90 must lie in \(10, 35\)"):
        maximum_backlash_um(6, 2.0, 36.0, 54.0, 45.0, 90.0)
    with pytest.raises(TypeError, match=r"^centre_distance_mm = '45'"):
        minimum_backlash_um("45", 2.0)
    assert maximum_backlash_um(6.0, 2.0, 36.0, 54.0, 45.0, 20.0) == maximum_backlash_um(
        6, 2.0, 36.0, 54.0, 45.0, 20.0)


# --- with_tooth_positions and per_tooth_model --------------------------------------------------


@pytest.fixture(scope="module")
def one():
    scn = Scenario()
    return build_model(scn, mesh_stiffness(scn.gear, scn.material))


Z1 = Scenario().gear.z1


@pytest.mark.parametrize("teeth", [None, 3, "teeth", [1, 2], []])
def test_tooth_models_that_are_not_a_list_of_pair_models_are_refused(teeth):
    for call in (lambda: with_tooth_positions(teeth, [0.0] * 2),
                 lambda: per_tooth_model(teeth)):
        with pytest.raises((TypeError, ValueError), match=r"^teeth(\[0\])? = .*PairModel") as e:
            call()
        one_line(e)


def test_a_single_model_in_place_of_the_list_is_refused(one):
    with pytest.raises(TypeError, match=r"^teeth = PairModel.* must be a sequence of PairModel"):
        with_tooth_positions(one, [0.0] * Z1)
    with pytest.raises(TypeError, match=r"^teeth\[1\] = None \(NoneType\) is not a PairModel"):
        per_tooth_model([one, None] + [one] * (Z1 - 2))


@pytest.mark.parametrize(("positions", "kind"), [
    (None, TypeError), (0.0, TypeError), ("0" * Z1, TypeError), (["a"] * Z1, TypeError),
    ([None] * Z1, TypeError), ([True] * Z1, TypeError), (np.zeros((Z1, 2)), ValueError),
    ({i: 0.0 for i in range(Z1)}, TypeError)])
def test_positions_that_are_not_a_row_of_numbers_are_refused(one, positions, kind):
    with pytest.raises(kind, match=r"^positions_m = .*1-D sequence of finite numbers") as e:
        with_tooth_positions([one] * Z1, positions)
    one_line(e)


@pytest.mark.parametrize("bad", [float("nan"), math.inf, -math.inf])
def test_non_finite_positions_are_refused(one, bad):
    positions = [0.0] * Z1
    positions[5] = bad
    with pytest.raises(ValueError, match=rf"^positions_m\[5\] = {bad!r}: .*finite"):
        with_tooth_positions([one] * Z1, positions)


def test_non_finite_tables_are_refused_by_per_tooth_model(one):
    import dataclasses

    bad = dataclasses.replace(one, g_a=np.full_like(one.g_a, np.nan))
    with pytest.raises(ValueError, match=r"^teeth\[3\]\.g_a holds NaN or infinite values"):
        per_tooth_model([one] * 3 + [bad] + [one] * (Z1 - 4))


@pytest.mark.parametrize("scale", [1.0, 5.0, -5.0, 1e-3])
def test_positions_in_um_or_mm_given_as_metres_are_refused(one, scale):
    """1.0 and 5.0: um given as m; 1e-3: 1 mm, beyond twice grade 12's F_p of the pinion."""
    with pytest.raises(ValueError, match=r"^positions_m\[0\] = .* m lies beyond \+-0.000324 m, "
                                         r"2 x the cumulative pitch tolerance F_p"):
        with_tooth_positions([one] * Z1, [scale] * Z1)


@settings(max_examples=30, deadline=None)
@given(grade=st.integers(0, 12), seed=st.integers(0, 2**32))
def test_positions_of_any_grade_in_metres_are_taken(one, grade, seed):
    """The deviations ISO 1328-1 allows, of every grade, lie well within the bound."""
    g = Scenario().gear
    x = 1e-6 * tooth_positions_um(Z1, grade, g.module_mm, g.module_mm * Z1, seed)
    moved = with_tooth_positions([one] * Z1, x)
    assert len(moved) == Z1
    inside = one.g_a < 1.0
    np.testing.assert_allclose(moved[2].g_a[inside], one.g_a[inside] - x[2])


@settings(max_examples=30, deadline=None)
@given(d=st.floats(-3.2e-4, 3.2e-4))
def test_any_position_within_the_bound_is_taken_as_a_list_tuple_or_array(one, d):
    for positions in ([d] * Z1, (d,) * Z1, np.full(Z1, d), [np.float32(d)] * Z1):
        assert len(with_tooth_positions([one] * Z1, positions)) == Z1
