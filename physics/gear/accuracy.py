"""Manufacturing tolerances of a spur pair from its accuracy grade: radial run-out, profile form,
and the normal backlash between its minimum and its maximum. They set the spread of real
gearboxes of one design (:class:`physics.dataset.generation.NuisanceRanges`). And a flank's
profile form deviation along its active profile (:func:`form_deviation`), the shape a profile
form tolerance bounds.

Sources (the formulas; no tabulated values are copied):

- ISO 1328-1:1995, clause 6 and 5.2: tolerances of accuracy grade 5 by formula, in um, with ``m``
  and ``d`` in mm taken as the geometric means of the standard's size bands the gear falls in;
  each grade multiplies the grade-5 value by ``sqrt(2)`` (grade ``Q``: ``2^((Q - 5)/2)``); values
  rounded to 1 um above 10 um, to 0.5 um from 5 to 10 um and to 0.1 um below 5 um.
  Profile form ``f_f_alpha = 2.5 sqrt(m) + 0.17 sqrt(d) + 0.5``; total cumulative pitch
  ``F_p = 0.3 m + 1.25 sqrt(d) + 7``; single pitch ``f_pt = 0.3 (m + 0.4 sqrt(d)) + 4``.
- ISO 1328-2:1997, annex B: radial run-out ``F_r = 0.8 F_p``.
- ISO/TR 10064-2:1996: minimum normal backlash ``j_bn,min = (2/3)(0.06 + 0.0005 a + 0.03 m)``
  mm (ferrous gears in a ferrous housing, pitch-line speed below 15 m/s); the tooth thickness
  tolerance ``T_sn = 2 tan(alpha_n) sqrt(F_r^2 + b_r^2)``, ``b_r`` the cutting-feed tolerance of
  the grade (grade 4: 1.26 IT7, 5: IT8, 6: 1.26 IT8, 7: IT9, 8: 1.26 IT9, 9: IT10, of the
  reference diameter).
- Centre-distance allowance ``+-f_a`` of the grade: half of IT6 (grades 3-4), IT7 (5-6), IT8
  (7-8), IT9 (9-10) of the centre distance (the allowances tabulated beside the ISO 1328 grades
  in DIN 3964 and GB/T 10095-1988).
- ISO 286-1:2010: the standard tolerance ``IT = k i``, ``i = 0.45 D^(1/3) + 0.001 D`` um
  (``D`` the geometric mean of the size band in mm; ``k`` 10, 16, 25, 40, 64 for IT6-IT10).

The largest backlash of a pair is the minimum one with both teeth at their thinnest and the
centre distance at its largest: ``j_bn,max = j_bn,min + (T_sn1 + T_sn2) cos(alpha) + 2 (2 f_a)
sin(alpha)`` (a thinner tooth opens the backlash by its thickness reduction times ``cos alpha``
along the line of action, a centre distance ``da`` larger by ``2 da sin alpha``).

>>> runout_tolerance_um(6, 2.0, 36.0), profile_form_tolerance_um(6, 2.0, 36.0)
(16.0, 5.5)
>>> round(minimum_backlash_um(45.0, 2.0), 1)
95.0
"""

from __future__ import annotations

import itertools
import math
import numbers
from dataclasses import fields
from typing import Any

import numpy as np

from physics.params import GearPair

#: ISO 1328-1:1995 size bands [mm]: reference diameter and normal module
DIAMETER_BANDS = (5.0, 20.0, 50.0, 125.0, 280.0, 560.0, 1000.0, 1600.0, 2500.0, 4000.0,
                  6000.0, 8000.0, 10000.0)
MODULE_BANDS = (0.5, 2.0, 3.5, 6.0, 10.0, 16.0, 25.0, 40.0, 70.0)
#: ISO 286-1 nominal size bands [mm] up to 500 mm, and the factor k of each IT grade
IT_BANDS = (0.0, 3.0, 6.0, 10.0, 18.0, 30.0, 50.0, 80.0, 120.0, 180.0, 250.0, 315.0, 400.0,
            500.0)
IT_FACTOR = {6: 10, 7: 16, 8: 25, 9: 40, 10: 64}
#: ISO/TR 10064-2 cutting-feed tolerance b_r per accuracy grade: (IT grade, factor)
FEED_TOLERANCE = {4: (7, 1.26), 5: (8, 1.0), 6: (8, 1.26), 7: (9, 1.0), 8: (9, 1.26),
                  9: (10, 1.0)}
#: centre-distance allowance f_a per accuracy grade: the IT grade of which it is half
CENTRE_ALLOWANCE_IT = {3: 6, 4: 6, 5: 7, 6: 7, 7: 8, 8: 8, 9: 9, 10: 9}
#: the accuracy grades of ISO 1328-1:1995 (0 the finest, 12 the coarsest)
GRADES = (0, 12)


def _gear_limits(name: str) -> tuple[float, float]:
    """The allowed range of a :class:`physics.params.GearPair` field, so that the checks here
    follow the pair's own."""
    meta = {f.name: f.metadata for f in fields(GearPair)}[name]
    return meta["lo"], meta["hi"]


def _shown(value: Any) -> str:
    """``repr(value)`` on one line and at most 60 characters (an array's repr wraps)."""
    text = " ".join(repr(value).split())
    return text if len(text) <= 60 else text[:57] + "..."


def _whole(name: str, value: Any, lo: int, hi: int, fix: str) -> int:
    """``value`` as an ``int`` when it is a whole number in ``[lo, hi]`` by the rule of
    :class:`physics.params.GearPair`'s whole fields (an int, a numpy integer or a float without
    a fraction such as ``18.0``; never a bool). ``TypeError`` for a value that is no number,
    ``ValueError`` for a number that breaks the rule; both name the argument, the value, the
    rule and ``fix``."""
    rule = (f"must be a whole number in [{lo}, {hi}] (an int, a numpy integer or a float such "
            f"as {lo}.0)")
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} = {_shown(value)} ({type(value).__name__}) {rule}; {fix}")
    whole = isinstance(value, numbers.Integral) or (isinstance(value, float)
                                                    and value.is_integer())
    if not whole or not lo <= value <= hi:
        raise ValueError(f"{name} = {_shown(value)} {rule}; {fix}")
    return int(value)


def _real(name: str, value: Any, fix: str, *, positive: bool = False) -> float:
    """``value`` as a ``float`` when it is a finite real number (not a bool; ``positive``:
    also > 0); otherwise ``TypeError`` (no number) or ``ValueError``, naming the argument, the
    value, the rule and ``fix``."""
    rule = "must be a finite number" + (" > 0" if positive else "")
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} = {_shown(value)} ({type(value).__name__}) {rule}; {fix}")
    if not math.isfinite(value) or (positive and not value > 0):
        raise ValueError(f"{name} = {_shown(value)} {rule}; {fix}")
    return float(value)


def _grade(grade: Any, lo: int = GRADES[0], hi: int = GRADES[1]) -> int:
    return _whole("grade", grade, lo, hi,
                  f"give an ISO 1328-1:1995 accuracy grade, {lo} the finest to {hi}")


def _sizes(module_mm: Any, d_mm: Any) -> tuple[float, float]:
    """The geometric means of the ISO 1328-1 size bands of the module and the reference
    diameter [mm], both checked first."""
    m = _real("module_mm", module_mm, "give the normal module in mm", positive=True)
    d = _real("d_mm", d_mm, "give the reference diameter m z in mm", positive=True)
    return (band_mean(m, MODULE_BANDS, "module_mm (normal module)"),
            band_mean(d, DIAMETER_BANDS, "d_mm (reference diameter)"))


def band_mean(x: float, edges: tuple[float, ...], what: str) -> float:
    """The geometric mean of the band ``(lo, hi]`` of ``edges`` that holds ``x`` (the first
    band closed below); ``ValueError`` outside the bands."""
    for lo, hi in itertools.pairwise(edges):
        if lo < x <= hi or x == lo == edges[0]:
            return math.sqrt(lo * hi) if lo > 0 else math.sqrt(1.0 * hi)
    raise ValueError(f"{what} = {x:g} mm lies outside the standard's size bands "
                     f"[{edges[0]:g}, {edges[-1]:g}] mm; the formulas hold only inside them")


def iso_round(value_um: float) -> float:
    """ISO 1328-1:1995 rounding: to 1 um above 10 um, 0.5 um from 5 to 10, 0.1 um below 5."""
    if value_um > 10.0:
        return float(math.floor(value_um + 0.5))
    if value_um >= 5.0:
        return math.floor(value_um * 2 + 0.5) / 2
    return math.floor(value_um * 10 + 0.5) / 10


def _pressure_angle(pressure_angle_deg: Any) -> float:
    lo, hi = _gear_limits("pressure_angle_deg")
    alpha = _real("pressure_angle_deg", pressure_angle_deg, "give it in degrees, e.g. 20")
    if not lo < alpha < hi:
        raise ValueError(f"pressure_angle_deg = {alpha:g} must lie in ({lo:g}, {hi:g}) degrees "
                         "as physics.params.GearPair's; give it in degrees, e.g. 20")
    return alpha


def _grade_factor(grade: int) -> float:
    """The factor of ``grade`` on the grade-5 value, ``2^((Q - 5)/2)``, the grade checked: a
    whole accuracy grade in [0, 12] (ISO 1328-1:1995)."""
    return 2.0 ** ((_grade(grade) - 5) / 2)


def cumulative_pitch_tolerance_um(grade: int, module_mm: float, d_mm: float,
                                  rounded: bool = True) -> float:
    """Total cumulative pitch tolerance ``F_p`` [um] (ISO 1328-1:1995)."""
    factor = _grade_factor(grade)
    m, d = _sizes(module_mm, d_mm)
    v = (0.3 * m + 1.25 * math.sqrt(d) + 7.0) * factor
    return iso_round(v) if rounded else v


def runout_tolerance_um(grade: int, module_mm: float, d_mm: float, rounded: bool = True) -> float:
    """Radial run-out tolerance ``F_r = 0.8 F_p`` [um] (ISO 1328-2:1997, annex B)."""
    v = 0.8 * cumulative_pitch_tolerance_um(grade, module_mm, d_mm, rounded=False)
    return iso_round(v) if rounded else v


def profile_form_tolerance_um(grade: int, module_mm: float, d_mm: float,
                              rounded: bool = True) -> float:
    """Profile form tolerance ``f_f_alpha`` [um] (ISO 1328-1:1995)."""
    factor = _grade_factor(grade)
    m, d = _sizes(module_mm, d_mm)
    v = (2.5 * math.sqrt(m) + 0.17 * math.sqrt(d) + 0.5) * factor
    return iso_round(v) if rounded else v


def single_pitch_tolerance_um(grade: int, module_mm: float, d_mm: float,
                              rounded: bool = True) -> float:
    """Single pitch tolerance ``f_pt`` [um] (ISO 1328-1:1995): the largest difference between
    a pitch of the gear and its theoretical pitch."""
    factor = _grade_factor(grade)
    m, d = _sizes(module_mm, d_mm)
    v = (0.3 * (m + 0.4 * math.sqrt(d)) + 4.0) * factor
    return iso_round(v) if rounded else v


def tooth_positions_um(z: int, grade: int, module_mm: float, d_mm: float,
                       seed: int) -> np.ndarray:
    """Each tooth's position deviation along the line of action [um] (``z`` values, positive:
    the drive flank stands ahead of its theoretical place, towards the mating flank), drawn for
    a gear of accuracy ``grade`` with ``seed``: the same gear always gets the same teeth.

    ISO 1328-1 states limits, not a distribution: here the positions are independent normal
    deviations whose single pitch deviations (the differences of neighbours, ``z`` of them
    around the gear, summing to zero) reach the tolerance ``f_pt`` at three standard deviations
    (``sigma = f_pt / (3 sqrt 2)``); the positions are taken about their mean (a common offset
    is a tooth thickness, the backlash's). Their total spread stays below the cumulative pitch
    tolerance ``F_p`` of the grade for the usual tooth counts.

    ``z`` is a whole number of teeth in :class:`physics.params.GearPair`'s range (5 to 1000;
    ``18``, ``np.int64(18)`` and ``18.0`` alike, as the pair takes them), ``grade`` a whole
    accuracy grade in [0, 12] and ``seed`` an int or numpy integer >= 0 (not a bool, not
    ``None``: it names the gear, so that its teeth come out the same each time); anything else
    is refused before any work, ``TypeError`` for what is no number at all."""
    lo, hi = _gear_limits("z1")
    z = _whole("z", z, int(lo), int(hi), "give the gear's number of teeth, as physics.params."
               "GearPair takes it")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise TypeError(f"seed = {_shown(seed)} ({type(seed).__name__}) must be an int >= 0; "
                        "give a whole number: it names the gear, the same seed the same teeth")
    if seed < 0:
        raise ValueError(f"seed = {seed!r} must be an int >= 0; give a whole number: it names "
                         "the gear, the same seed the same teeth")
    sigma = single_pitch_tolerance_um(grade, module_mm, d_mm, rounded=False) / (3 * math.sqrt(2))
    x = np.random.default_rng(seed).normal(0.0, sigma, z)
    return x - x.mean()


#: how far a tooth may stand off its place, in cumulative pitch tolerances ``F_p`` of the
#: coarsest ISO 1328-1:1995 grade (12): a tooth's position deviation from its theoretical place
#: is a cumulative pitch deviation, which that grade bounds by ``F_p`` (spread of the teeth),
#: and a common offset of all teeth (a tooth thickness) is of the same size at the most. For the
#: thesis pinion (m 2 mm, d 36 mm) the bound is 2 x 162 um = 0.32 mm; a value in um or mm given
#: as metres lies far beyond it.
POSITION_BOUND_FP = 2.0


def position_bound_m(module_mm: float, d_mm: float) -> float:
    """The largest position deviation a tooth of a wheel of ``module_mm`` and reference diameter
    ``d_mm`` may have, :data:`POSITION_BOUND_FP` times ISO 1328-1's ``F_p`` of grade 12, the
    module and diameter brought into the standard's size bands (the formula's own range) [m]."""
    m = min(max(module_mm, MODULE_BANDS[0]), MODULE_BANDS[-1])
    d = min(max(d_mm, DIAMETER_BANDS[0]), DIAMETER_BANDS[-1])
    return POSITION_BOUND_FP * cumulative_pitch_tolerance_um(12, m, d, rounded=False) * 1e-6


def it_tolerance_um(it_grade: int, size_mm: float) -> float:
    """The standard tolerance IT6-IT10 of a nominal size up to 500 mm [um] (ISO 286-1)."""
    it_grade = _whole("it_grade", it_grade, min(IT_FACTOR), max(IT_FACTOR),
                      "give the IT grade as a number, e.g. 7 for IT7")
    size = _real("size_mm", size_mm, "give the nominal size in mm", positive=True)
    big_d = band_mean(size, IT_BANDS, "size_mm (nominal size)")
    return IT_FACTOR[it_grade] * (0.45 * big_d ** (1 / 3) + 0.001 * big_d)


def minimum_backlash_um(centre_distance_mm: float, module_mm: float) -> float:
    """Minimum normal backlash ``j_bn,min`` [um] (ISO/TR 10064-2:1996)."""
    centre_distance_mm = _real("centre_distance_mm", centre_distance_mm,
                               "give the centre distance in mm", positive=True)
    module_mm = _real("module_mm", module_mm, "give the normal module in mm", positive=True)
    return 2.0 / 3.0 * (0.06 + 0.0005 * centre_distance_mm + 0.03 * module_mm) * 1000.0


def tooth_thickness_tolerance_um(grade: int, module_mm: float, d_mm: float,
                                 pressure_angle_deg: float) -> float:
    """Tooth thickness tolerance ``T_sn = 2 tan(alpha) sqrt(F_r^2 + b_r^2)`` [um]
    (ISO/TR 10064-2:1996), for the grades 4 to 9 whose cutting-feed tolerance it states."""
    grade = _grade(grade, min(FEED_TOLERANCE), max(FEED_TOLERANCE))
    _sizes(module_mm, d_mm)
    _pressure_angle(pressure_angle_deg)
    it, factor = FEED_TOLERANCE[grade]
    b_r = factor * it_tolerance_um(it, d_mm)
    f_r = runout_tolerance_um(grade, module_mm, d_mm, rounded=False)
    return 2 * math.tan(math.radians(pressure_angle_deg)) * math.hypot(f_r, b_r)


def maximum_backlash_um(grade: int, module_mm: float, d1_mm: float, d2_mm: float,
                        centre_distance_mm: float, pressure_angle_deg: float) -> float:
    """Largest normal backlash [um] of a pair of accuracy ``grade`` built for the minimum
    backlash: both teeth at their thinnest and the centre distance at its largest (module
    text), for the grades 4 to 9 (those of :func:`tooth_thickness_tolerance_um`)."""
    grade = _grade(grade, min(FEED_TOLERANCE), max(FEED_TOLERANCE))
    for name, d in (("d1_mm", d1_mm), ("d2_mm", d2_mm)):
        _real(name, d, "give the reference diameter m z in mm", positive=True)
    _real("centre_distance_mm", centre_distance_mm, "give the centre distance in mm",
          positive=True)
    alpha = math.radians(_pressure_angle(pressure_angle_deg))
    thinner = sum(tooth_thickness_tolerance_um(grade, module_mm, d, pressure_angle_deg)
                  for d in (d1_mm, d2_mm))
    f_a = it_tolerance_um(CENTRE_ALLOWANCE_IT[grade], centre_distance_mm) / 2
    return (minimum_backlash_um(centre_distance_mm, module_mm) + thinner * math.cos(alpha)
            + 2 * (2 * f_a) * math.sin(alpha))


def form_deviation(s: np.ndarray, s_start: float, path_length: float, amplitude_um: float,
                   waves: float, phase_rad: float) -> np.ndarray:
    """The pinion flank's profile form deviation [m] at roll coordinates ``s`` (m, on the path
    of contact from ``s_start``, ``path_length`` long), as the gap it opens at the contact (the
    sign of wear: material missing from the involute): ``A sin(pi n u + phase)``, ``u`` the
    position along the active profile (0 at the start of contact, 1 at its end).

    ISO 1328-1:1995 bounds the form deviation ``f_f_alpha`` as the distance between
    two copies of the mean profile line that enclose the measured profile over the evaluation
    range; the measured profiles of ground and hobbed teeth are waves of a few periods over
    it (grinding and feed marks) on a bulge or hollow. Here one such wave: ``A`` half its
    peak-to-valley (half of ``f_f_alpha`` at the most), ``n`` the half-waves over the active
    profile (1: a bulge or hollow), ``phase`` where they lie. The same on every tooth: it
    repeats at the mesh frequency and adds harmonics of it to the transmission error, as real
    flank deviations do (:mod:`physics.dynamics.model`)."""
    u = (np.asarray(s, float) - s_start) / path_length
    return amplitude_um * 1e-6 * np.sin(np.pi * waves * u + phase_rad)
