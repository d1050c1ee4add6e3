"""An independent spur-pair vibration simulator: measured-like bundles from a second model form.

The measured-data loop is otherwise judged on bundles that the project's own model made
(:mod:`physics.testbeds.synthetic`), which hides any mismatch of model *form*. This module is a
second simulator, written without the project's dynamics, stiffness, effect or measurement code
(it uses numpy, scipy, pandas, numba and the bundle writer only), whose records the loop has to
explain with a model that is not the one that made them. Each choice below is deliberately
unlike :mod:`physics.dynamics.model`; its source or the reason for it is given beside it.

Mesh stiffness (lumped, ISO 6336-1, not the potential-energy method)
    Single-pair stiffness ``c'`` = 14 N/(mm um) per mm of face and mean mesh stiffness
    ``c_gamma = c' (0.75 eps_alpha + 0.25)`` (ISO 6336-1:2006, clause 9; 14 N/(mm um) is the
    standard's value for solid steel spur gears on the standard basic rack). The mesh stiffness
    is a square wave over the mesh period: ``k_s = c' b`` in the single-contact zone (a share
    ``2 - eps_alpha`` of the base pitch) and ``k_d`` in the double-contact zone, with ``k_d``
    chosen so that the period mean is ``c_gamma b`` (which gives ``k_d = 1.75 k_s`` for any
    contact ratio). Zone changes are raised-cosine ramps over ``transition_roll_fraction``
    (0.08) of the base pitch: under load the entering tooth touches early (extended contact),
    over about ``sqrt(2 delta rho)`` = 0.45 mm of roll for a deflection ``delta`` of 20 um and a
    relative curvature radius ``rho`` of 5 mm, 8 % of the base pitch. In the double zone each
    pair carries half of ``k_d``.

Dynamics (two translational DOF, implicit fixed step)
    ``p`` is the relative torsional displacement on the line of action, on the equivalent mass
    ``m_e = J1 J2 / (J1 rb2^2 + J2 rb1^2)``; the inertias are solid discs to the pitch circle
    *plus the shafts* (``shaft_length_mm`` of steel shaft each), which the project's model does
    not carry. ``y`` is the pinion body's translation along the line of action on a bearing
    spring ``k_b``: the shaft in bending between its bearings, ``48 E I / L^3`` (simply supported
    beam under a central load, Roark's Formulas for Stress and Strain), in series with the two
    rolling bearings in parallel. The mesh deflection is ``delta = p + y - e_m(t) - g(t)`` and

        m_e p'' = W(t) - F,      m_b y'' + c_b y' + k_b y = -F,
        F = k(t) [f(delta) + beta delta_v'],

    with ``f`` the piecewise-linear backlash (contact at ``delta = 0``, free flight over the
    normal backlash ``2 Delta``, coast-flank contact beyond it) and stiffness-proportional
    (Rayleigh) mesh damping ``beta = 2 zeta_m / omega_m`` at the mesh mode ``omega_m`` of the
    two-DOF chain; ``delta_v' = p' + y' - e_m'`` (the geometric gap ``g`` does not damp). The
    equations are integrated with the Newmark average-acceleration (trapezoidal) rule, an
    implicit, unconditionally stable fixed-step scheme, with the contact state iterated each
    step, at ``internal_rate_hz`` (400 kHz), and resampled (polyphase, anti-aliased) to the
    output rate.

Errors
    Manufacturing: mesh harmonics 1-3 with random phases (amplitudes a grade-6-like share of the
    ISO 1328-1 profile tolerance, about 6 um at m = 2 mm, d = 36 mm); radial run-out ``F_r`` of
    pinion and gear: the eccentricity ``F_r / 2`` projects on the line of action with its full
    amplitude at the shaft rate, and amplitude-modulates the mesh excitation (the stiffness
    fluctuation and the mesh harmonics) by ``am_per_um F_r`` once per revolution of that shaft
    (the amplitude-modulation model of gear signals of Randall, J. Mech. Des. 104 (1982) 259,
    and McFadden, J. Vib. Acoust. 108 (1986) 165; the depth per um is a choice).
    Wear: the pinion's root wear depth ``h`` (mm, the bundle's ``wear_mm``) scales a wear
    profile along the path that is zero at the pitch point and largest at the root: Archard's
    depth ~ load x sliding distance, with the sliding proportional to the roll distance ``|s|``
    from the pitch point and the tooth's load doubling from the double- to the single-contact
    zone (the profile shape of Flodin & Andersson, Wear 207 (1997) 16), ``h`` at the start of
    the path, ``wear_tip_share`` (0.5) of that law on the addendum. The profile is added to the
    static transmission error tooth pass by tooth pass, as the wear-induced error of the newest
    pair in contact (the lumped "combined error" of thesis 3.3), not pair by pair inside the
    contact as :mod:`physics.dynamics.model` does. At the bundles' loads the static STE step of
    the stiffness (about 12 um) exceeds the wear, so root wear partly fills the double-contact
    dip (as relief would) and raises the step at the lowest point of single contact: DTE
    peak-to-peak grows by a few per cent over 0-15 um after a slight dip, the AC RMS of DTE
    and of the acceleration fall, the mean DTE rises.

Undeclared effects (names as :mod:`physics.loop.effects`, implementations of this module)
    =================  ===================================================================
    gear_runout        gear radial run-out (typical 25 um): kinematic error at ``f_2`` and
                       amplitude modulation at the gear's shaft order, sidebands
                       ``k f_m +- f_2``
    friction           Coulomb friction ``mu`` (typical 0.07) reversing at the pitch point,
                       acting through constant friction arms (those at the pitch point): a
                       mesh-rate square-wave moment, an external forcing on ``p`` (Velex &
                       Cahouet, J. Mech. Des. 122 (2000) 515 for the mechanism)
    tip_relief         linear long tip relief (typical 15 um) of both gears over the
                       double-contact zone; quasi-static load sharing at the static load
                       decides which pairs carry, lowering the stiffness jump's STE step
    tooth_defect       a pit on one pinion tooth (alias ``defect``): a steep-edged local
                       stiffness loss over ``face_share`` (typical 0.3) of the face, 0.8 mm of
                       roll in the single-contact zone (Chaari et al., Eur. J. Mech. A/Solids
                       27 (2008) 691, for spalls as stiffness loss), once per pinion revolution
    transfer_path      a housing mode between mesh and accelerometer: the acceleration plus
                       ``gain`` (typical 4) times a 2nd-order band-pass at 3.6 kHz, Q 20;
                       acceleration records only
    torque_ripple      load torque ripple (typical 5 %) at half the pinion order (a drive-line
                       order): a line at ``f_1 / 2`` and sidebands ``k f_m +- f_1 / 2``
    sensor             sensor gain error (typical 1.2) and a quadratic amplitude
                       nonlinearity (typical 5 % of full scale)
    =================  ===================================================================

    ``backlash_growth`` is not provided: at the bundles' loads the flanks never separate, so it
    would leave the records unchanged.

Measurement
    ``dte_m``: ``x = p + y - e_m(t)`` (the relative displacement on the line of action less the
    manufacturing error, thesis 3.3), zero at unloaded flank contact, mean included: its mean
    is the static deflection ``W / k`` plus the wear error (the project's DTE carries the half
    backlash in its mean as well; this one does not). ``accel_m_s2``: the housing, a mass
    ``housing_mass_kg`` (30 kg) on its mounting (a mode at 150 Hz, damping ratio 0.2, so that
    shaft-rate forces do not shake it as a free mass), driven by the bearing force
    ``k_b y + c_b y'`` (not the mesh force), mean removed. Both are resampled from the internal
    rate by a polyphase anti-aliasing filter. White Gaussian noise at ``snr_db`` relative to the
    record's AC power.

Determinism: every random draw comes from a seeded ``numpy.random.Generator``; the same
arguments give byte-identical arrays.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from pathlib import Path

import numba
import numpy as np
import pandas as pd
from scipy import signal

from physics.loop.measured.bundle import check_bundle_target, write_bundle

QUANTITIES = ("dte_m", "accel_m_s2")
STEEL_E = 206e9  # Pa, ISO 6336-1 steel reference modulus
#: the first wear state's time in a dated bundle: the Unix epoch (any start would do)
EPOCH = pd.Timestamp(0)

# effect -> (typical values at effect_size 1, how each value scales with effect_size, quantities)
_EFFECTS: dict[str, tuple[dict, dict, tuple[str, ...]]] = {
    "gear_runout": ({"runout_um": 25.0}, {"runout_um": True}, QUANTITIES),
    "friction": ({"mu": 0.07}, {"mu": True}, QUANTITIES),
    "tip_relief": ({"relief_um": 15.0, "length_share": 1.0},
                   {"relief_um": True, "length_share": False}, QUANTITIES),
    "tooth_defect": ({"face_share": 0.3, "centre_mm": -0.6, "length_mm": 0.8},
                     {"face_share": True, "centre_mm": False, "length_mm": False}, QUANTITIES),
    "transfer_path": ({"fn_hz": 3600.0, "q": 20.0, "gain": 4.0},
                      {"fn_hz": False, "q": False, "gain": True}, ("accel_m_s2",)),
    "torque_ripple": ({"ripple_pct": 5.0, "order": 0.5},
                      {"ripple_pct": True, "order": False}, QUANTITIES),
    "sensor": ({"gain": 1.2, "nonlinearity": 0.05}, {"gain": True, "nonlinearity": True},
               QUANTITIES),
}
_ALIASES = {"defect": "tooth_defect"}
EFFECT_NAMES = tuple(_EFFECTS)

#: another unit of the default pair's series (``IndependentPair(**SISTER_UNIT)``), the sister
#: of the loop's form reference (:mod:`physics.loop.search.form_error`): other manufacturing
#: errors (run-out and profile within one ISO 1328 grade), mesh damping, bearing and housing
#: data of another installation (10-30 % off the defaults; a choice, no standard)
SISTER_UNIT = {"mesh_damping_ratio": 0.065, "runout1_um": 9.0,
               "profile_harmonics_um": (1.9, 0.5, 0.35), "housing_mass_kg": 33.0,
               "bearing_stiffness_N_um": 180.0}


def _bad(name: str, value, rule: str) -> ValueError:
    return ValueError(f"{name} = {value!r} {rule}")


def _check(name: str, value, lo: float, hi: float, closed_lo: bool = False) -> None:
    """Raise unless ``value`` is a finite real number in (lo, hi) ([lo, hi) if closed_lo)."""
    ok = isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)
    if ok:
        v = float(value)
        ok = math.isfinite(v) and (lo <= v if closed_lo else lo < v) and v < hi
    if not ok:
        left = "[" if closed_lo else "("
        raise _bad(name, value, f"must be a finite number in {left}{lo:g}, {hi:g})")


@dataclass(frozen=True)
class IndependentPair:
    """Parameters of the independent simulator (defaults: the thesis pair, 3.3-3.4).

    Geometry: standard full-depth involute spur pair without profile shift. Every field is
    validated on construction: a bad value raises ``ValueError`` naming the field, the value and
    the allowed range.
    """

    module_mm: float = 2.0
    z1: int = 18
    z2: int = 27
    pressure_angle_deg: float = 20.0
    face_width_mm: float = 30.0
    # ISO 6336-1 single stiffness c' [N/(mm um)] and the roll share of each zone ramp
    single_stiffness_N_mm_um: float = 14.0
    transition_roll_fraction: float = 0.08
    density_kg_m3: float = 7850.0
    # shafts: radius, the length whose inertia rotates with each gear, the bearing span
    shaft_radius1_mm: float = 10.0
    shaft_radius2_mm: float = 15.0
    shaft_length_mm: float = 150.0
    bearing_span_mm: float = 80.0
    # radial stiffness of one rolling bearing [N/um]: the order of small deep-groove ball
    # bearings under kN loads (a choice, 2e8 N/m)
    bearing_stiffness_N_um: float = 200.0
    mesh_damping_ratio: float = 0.05  # inside the 0.03-0.17 of Kasuba & Evans (1981)
    bearing_damping_ratio: float = 0.03  # lightly damped rolling-bearing support (a choice)
    half_backlash_um: float = 40.0
    housing_mass_kg: float = 30.0
    # the housing on its mounting (bedplate): a mass-spring mode well below the mesh frequency
    mount_frequency_hz: float = 150.0
    mount_damping_ratio: float = 0.2
    profile_harmonics_um: tuple[float, ...] = (1.6, 0.6, 0.3)  # mesh harmonics 1, 2, 3
    runout1_um: float = 12.0  # pinion radial run-out (near ISO 1328-2 grade 6 at d = 36 mm)
    runout2_um: float = 0.0  # gear radial run-out in the base model
    am_per_um: float = 0.004  # AM depth of the mesh excitation per um of radial run-out
    wear_tip_share: float = 0.5  # wear law on the addendum relative to the dedendum's
    internal_rate_hz: float = 400_000.0
    transient_s: float = 0.05
    dte_full_scale_um: float = 100.0  # sensor full scales (for the sensor nonlinearity)
    accel_full_scale_m_s2: float = 1000.0

    def __post_init__(self) -> None:
        _check("module_mm", self.module_mm, 0.3, 30.0)
        for name, lo, hi in (("z1", 8, 200), ("z2", 8, 1000)):
            z = getattr(self, name)
            if not isinstance(z, int | np.integer) or isinstance(z, bool) or not lo <= z <= hi:
                raise _bad(name, z, f"must be a whole number of teeth in [{lo}, {hi}]")
        if self.z1 > self.z2:
            raise _bad("z1", self.z1, f"must not exceed z2 = {self.z2} (z1 is the pinion)")
        _check("pressure_angle_deg", self.pressure_angle_deg, 14.0, 30.0)
        _check("face_width_mm", self.face_width_mm, 1.0, 1000.0)
        _check("single_stiffness_N_mm_um", self.single_stiffness_N_mm_um, 5.0, 30.0)
        _check("transition_roll_fraction", self.transition_roll_fraction, 0.001, 0.2)
        _check("density_kg_m3", self.density_kg_m3, 1000.0, 20000.0)
        rf1 = self.module_mm * (self.z1 / 2 - 1.25)
        rf2 = self.module_mm * (self.z2 / 2 - 1.25)
        _check("shaft_radius1_mm", self.shaft_radius1_mm, 0.0, rf1)
        _check("shaft_radius2_mm", self.shaft_radius2_mm, 0.0, rf2)
        _check("shaft_length_mm", self.shaft_length_mm, 0.0, 5000.0, closed_lo=True)
        _check("bearing_span_mm", self.bearing_span_mm, 5.0, 5000.0)
        _check("bearing_stiffness_N_um", self.bearing_stiffness_N_um, 1.0, 1e5)
        _check("mesh_damping_ratio", self.mesh_damping_ratio, 0.005, 0.3)
        _check("bearing_damping_ratio", self.bearing_damping_ratio, 0.005, 0.5)
        _check("half_backlash_um", self.half_backlash_um, 0.0, 1000.0, closed_lo=True)
        _check("housing_mass_kg", self.housing_mass_kg, 0.1, 1e5)
        _check("mount_frequency_hz", self.mount_frequency_hz, 0.0, 5000.0, closed_lo=True)
        _check("mount_damping_ratio", self.mount_damping_ratio, 0.01, 2.0)
        h = self.profile_harmonics_um
        if not isinstance(h, tuple | list) or not 1 <= len(h) <= 10:
            raise _bad("profile_harmonics_um", h, "must be a tuple of 1-10 amplitudes in um")
        for i, a in enumerate(h):
            _check(f"profile_harmonics_um[{i}]", a, 0.0, 100.0, closed_lo=True)
        _check("runout1_um", self.runout1_um, 0.0, 500.0, closed_lo=True)
        _check("runout2_um", self.runout2_um, 0.0, 500.0, closed_lo=True)
        _check("am_per_um", self.am_per_um, 0.0, 0.02, closed_lo=True)
        _check("wear_tip_share", self.wear_tip_share, 0.0, 5.0, closed_lo=True)
        _check("internal_rate_hz", self.internal_rate_hz, 5e4, 1e7)
        _check("transient_s", self.transient_s, 0.0, 10.0, closed_lo=True)
        _check("dte_full_scale_um", self.dte_full_scale_um, 1.0, 1e5)
        _check("accel_full_scale_m_s2", self.accel_full_scale_m_s2, 1.0, 1e7)
        eps = self.contact_ratio
        if not 1.05 < eps < 1.95:
            raise _bad("contact_ratio", round(eps, 4), "must lie in (1.05, 1.95) for the "
                       "single/double-zone stiffness of this model; change z1, z2 or the "
                       "pressure angle")
        zone = min(eps - 1.0, 2.0 - eps)
        if self.transition_roll_fraction >= zone:
            raise _bad("transition_roll_fraction", self.transition_roll_fraction,
                       f"must be below the shorter contact zone, {zone:.3f} of the base pitch")
        wdt = self.omega_max * self.dt
        if wdt > 0.5:
            raise _bad("internal_rate_hz", self.internal_rate_hz,
                       f"is too low: omega_max dt = {wdt:.2f} must be <= 0.5 (raise it to "
                       f">= {self.omega_max / 0.5:.0f} Hz)")

    # ----- geometry [m] -----
    @property
    def alpha(self) -> float:
        return math.radians(self.pressure_angle_deg)

    @property
    def radii(self) -> tuple[float, float, float, float, float, float]:
        """Pitch, base and tip radii (r1, r2, rb1, rb2, ra1, ra2) [m]."""
        m = self.module_mm * 1e-3
        r1, r2 = m * self.z1 / 2, m * self.z2 / 2
        c = math.cos(self.alpha)
        return r1, r2, r1 * c, r2 * c, r1 + m, r2 + m

    @property
    def base_pitch(self) -> float:
        return math.pi * self.module_mm * 1e-3 * math.cos(self.alpha)

    @property
    def path(self) -> tuple[float, float]:
        """Start and end of the path of contact, roll distance from the pitch point [m]."""
        r1, r2, rb1, rb2, ra1, ra2 = self.radii
        pitch = rb1 * math.tan(self.alpha)
        start = (r1 + r2) * math.sin(self.alpha) - math.sqrt(ra2**2 - rb2**2)
        return start - pitch, math.sqrt(ra1**2 - rb1**2) - pitch

    @property
    def contact_ratio(self) -> float:
        s0, s1 = self.path
        return (s1 - s0) / self.base_pitch

    # ----- stiffness [N/m] -----
    @property
    def k_single(self) -> float:
        return self.single_stiffness_N_mm_um * self.face_width_mm * 1e6

    @property
    def k_mean(self) -> float:
        """ISO 6336-1 mean mesh stiffness c_gamma b."""
        return self.k_single * (0.75 * self.contact_ratio + 0.25)

    @property
    def k_double(self) -> float:
        eps = self.contact_ratio
        return (self.k_mean - (2.0 - eps) * self.k_single) / (eps - 1.0)

    # ----- masses, supports, damping -----
    @property
    def inertias(self) -> tuple[float, float]:
        """Polar moments [kg m^2]: solid discs to the pitch circle plus the shafts."""
        r1, r2 = self.radii[:2]
        rho, b, ls = self.density_kg_m3, self.face_width_mm * 1e-3, self.shaft_length_mm * 1e-3
        disc = 0.5 * math.pi * rho
        return (disc * (b * r1**4 + ls * (self.shaft_radius1_mm * 1e-3) ** 4),
                disc * (b * r2**4 + ls * (self.shaft_radius2_mm * 1e-3) ** 4))

    @property
    def equivalent_mass(self) -> float:
        j1, j2 = self.inertias
        rb1, rb2 = self.radii[2:4]
        return j1 * j2 / (j1 * rb2**2 + j2 * rb1**2)

    @property
    def body_mass(self) -> float:
        """Translating mass of the pinion body: its disc and the shaft between the bearings."""
        r1 = self.radii[0]
        rs = self.shaft_radius1_mm * 1e-3
        return math.pi * self.density_kg_m3 * (self.face_width_mm * 1e-3 * r1**2
                                                + self.bearing_span_mm * 1e-3 * rs**2)

    @property
    def bearing_stiffness(self) -> float:
        """Support stiffness along the line of action [N/m]: shaft bending in series with the
        two bearings in parallel."""
        rs, span = self.shaft_radius1_mm * 1e-3, self.bearing_span_mm * 1e-3
        shaft = 48 * STEEL_E * (math.pi * rs**4 / 4) / span**3
        bearings = 2 * self.bearing_stiffness_N_um * 1e6
        return 1.0 / (1.0 / shaft + 1.0 / bearings)

    @property
    def bearing_damping(self) -> float:
        return 2 * self.bearing_damping_ratio * math.sqrt(self.bearing_stiffness * self.body_mass)

    @property
    def omega_mesh_mode(self) -> float:
        """The mesh mode of the two-DOF chain at the mean stiffness [rad/s]."""
        return self._modes(self.k_mean)[1]

    @property
    def omega_max(self) -> float:
        return self._modes(self.k_double)[1]

    @property
    def rayleigh_beta(self) -> float:
        return 2 * self.mesh_damping_ratio / self.omega_mesh_mode

    @property
    def dt(self) -> float:
        return 1.0 / self.internal_rate_hz

    def _modes(self, k: float) -> tuple[float, float]:
        """Undamped natural frequencies [rad/s] of m_e -k- m_b -k_b- ground."""
        me, mb, kb = self.equivalent_mass, self.body_mass, self.bearing_stiffness
        a = me * mb
        b = -(k * (me + mb) + kb * me)
        c = k * kb
        disc = math.sqrt(max(b * b - 4 * a * c, 0.0))
        return math.sqrt((-b - disc) / (2 * a)), math.sqrt((-b + disc) / (2 * a))

    def mesh_frequency_hz(self, n1_rpm: float) -> float:
        return n1_rpm / 60.0 * self.z1


# ---------------------------------------------------------------------------------------------
# effects


def effect_values(effect: str | None, effect_size: float = 1.0) -> tuple[str | None, dict]:
    """Canonical name and parameter values of ``effect`` at ``effect_size`` (1 = typical)."""
    _check("effect_size", effect_size, 0.0, 10.0)
    if effect is None:
        return None, {}
    name = _ALIASES.get(effect, effect) if isinstance(effect, str) else effect
    if name not in _EFFECTS:
        raise _bad("effect", effect, f"is not an effect of this simulator; choose from "
                   f"{sorted(_EFFECTS)} (or None)")
    typical, scales, _ = _EFFECTS[name]
    values = {k: (v * effect_size if scales[k] else v) for k, v in typical.items()}
    if name == "tooth_defect":
        values["face_share"] = min(values["face_share"], 0.9)
    return name, values


# ---------------------------------------------------------------------------------------------
# the mesh over one pinion revolution


def _ramp(z: np.ndarray) -> np.ndarray:
    """Raised-cosine step: 0 for z <= 0, 1 for z >= 1."""
    z = np.clip(z, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * z)


def _wear_profile(pair: IndependentPair, s: np.ndarray, h: float) -> np.ndarray:
    """Wear depth [m] of a pinion tooth at roll s (from the pitch point), root wear ``h``.

    Archard: depth ~ load x sliding distance, with the sliding proportional to ``|s|`` and the
    tooth's load doubling from the double- to the single-contact zone; normalised to ``h`` at
    the start of the path (the root), ``wear_tip_share`` of that law beyond the pitch point.
    """
    s0, s1 = pair.path
    ld = (pair.contact_ratio - 1.0) * pair.base_pitch
    w = pair.transition_roll_fraction * pair.base_pitch
    double = np.maximum(_ramp((s0 + ld + 0.5 * w - s) / w), _ramp((s - (s1 - ld - 0.5 * w)) / w))
    law = np.abs(s) * (1.0 - 0.5 * double)
    scale = h / (abs(s0) * 0.5)
    return np.where(s < 0, scale * law, scale * pair.wear_tip_share * law)


def wear_depths(pair: IndependentPair, root_wear_mm: float, points: int = 4001
                ) -> dict[str, float]:
    """The wear profile of root wear ``root_wear_mm`` summarised as the physics dataset
    summarises its own (:mod:`physics.dataset.generation`): depth at the root, largest depth
    and mean depth over the path of contact (worn area per unit face width over the path's
    length), all in mm, keyed by the dataset's column names. (Its own three lines, not the
    dataset's: this module imports nothing of the project's model.)"""
    s0, s1 = pair.path
    s = np.linspace(s0, s1, points)
    w = _wear_profile(pair, s, root_wear_mm)
    return {"root_wear_mm": float(w[0]), "max_wear_mm": float(w.max()),
            "mean_wear_mm": float(np.trapezoid(w, s) / (s1 - s0))}


@dataclass(frozen=True)
class _Mesh:
    """Tables over one pinion revolution (``z1 * n_per`` cells, periodic)."""

    k: np.ndarray  # lumped mesh stiffness [N/m]
    gap: np.ndarray  # composite gap: relief composite plus the wear error per tooth pass [m]
    slide: np.ndarray  # load-share-weighted sliding sign (-1 approach ... +1 recess)
    n_per: int


def _mesh_tables(pair: IndependentPair, w0: float, wear_m: float, name: str | None,
                 values: dict, n_per: int = 512) -> _Mesh:
    pb, z1 = pair.base_pitch, pair.z1
    s0, s1 = pair.path
    nu = np.arange(z1 * n_per) / n_per
    j = np.floor(nu).astype(int)
    tau = (nu - j) * pb
    w = pair.transition_roll_fraction * pb
    wrap = tau + 0.5 * w >= pb
    u = np.where(wrap, tau - pb, tau)  # in [-w/2, pb - w/2)
    tooth_a = np.where(wrap, j + 1, j) % z1  # the newest pair (entering at u = 0)
    tooth_b = (tooth_a - 1) % z1  # the pair ahead of it
    ld = (pair.contact_ratio - 1.0) * pb
    a_a = _ramp((u + 0.5 * w) / w)  # presence of pair A (enters)
    a_b = _ramp((ld + 0.5 * w - u) / w)  # presence of pair B (leaves)
    k = pair.k_single + (pair.k_double - pair.k_single) * a_a * a_b
    k_a, k_b = k * a_a / (a_a + a_b), k * a_b / (a_a + a_b)
    s_a, s_b = s0 + u, s0 + pb + u

    if name == "tooth_defect":
        c, half = values["centre_mm"] * 1e-3, 0.5 * values["length_mm"] * 1e-3
        if not (s0 < c - half and c + half < s1):
            raise _bad("tooth_defect centre_mm", values["centre_mm"],
                       f"puts the pit off the path of contact ({s0 * 1e3:.2f}, "
                       f"{s1 * 1e3:.2f}) mm")
        edge = 0.15 * 2 * half

        def pit(s):  # flat-bottomed pit, edges over 15 % of its length
            return _ramp((s - (c - half)) / edge) * _ramp(((c + half) - s) / edge)

        k_a = k_a * np.where(tooth_a == 0, 1 - values["face_share"] * pit(s_a), 1.0)
        k_b = k_b * np.where(tooth_b == 0, 1 - values["face_share"] * pit(s_b), 1.0)

    # sliding reverses at the pitch point; EHL traction saturates at a slide-roll ratio of a
    # few per cent, here about 0.15 mm of roll from the pitch point
    sw = 1.5e-4
    slide = (k_a * np.tanh(s_a / sw) + k_b * np.tanh(s_b / sw)) / (k_a + k_b)

    gap = np.zeros_like(k)
    k_eff = k_a + k_b
    if name == "tip_relief":
        ca, length = values["relief_um"] * 1e-6, values["length_share"] * ld
        length = max(length, 1e-9)

        def relief(s):  # gear tip at the start of the path, pinion tip at its end
            return ca * (np.clip((s0 + length - s) / length, 0, 1)
                         + np.clip((s - (s1 - length)) / length, 0, 1))

        r_a, r_b = relief(s_a), relief(s_b)
        # which pairs carry at the static load (quasi-static load sharing, then lumped)
        both = (w0 + k_a * r_a + k_b * r_b) / (k_a + k_b)
        on_a = (both > r_a) | (k_b <= 0)
        on_b = (both > r_b) & (k_b > 0)
        only_a = on_a & ~on_b
        only_b = on_b & ~on_a
        k_eff = np.where(only_a, k_a, np.where(only_b, k_b, k_a + k_b))
        gap = np.where(only_a, r_a, np.where(only_b, r_b,
                                             (k_a * r_a + k_b * r_b) / (k_a + k_b)))

    # wear: the error of the newest pair in contact, tooth pass by tooth pass
    e_w = a_a * _wear_profile(pair, s_a, wear_m) + (1 - a_a) * _wear_profile(pair, s_b, wear_m)
    return _Mesh(k=k_eff, gap=gap + e_w, slide=slide, n_per=n_per)


# ---------------------------------------------------------------------------------------------
# integration


@numba.njit(cache=True)
def _newmark(k, gap, em, emd, w, dt, m_e, m_b, k_b, c_b, beta, backlash):  # pragma: no cover
    """Newmark average-acceleration steps of the two-DOF chain; returns DTE and bearing force.

    The contact state (drive flank, free, coast flank) is iterated until the step's solution
    agrees with the state it was solved in.
    """
    n = k.size
    x_out = np.empty(n)
    fb_out = np.empty(n)
    h2 = 0.25 * dt * dt
    h1 = 0.5 * dt
    y = -w[0] / k_b
    p = w[0] / k[0] + em[0] + gap[0] - y
    vp, vy = emd[0], 0.0
    ap = 0.0
    ay = 0.0
    state = 1
    x_out[0] = p + y - em[0]
    fb_out[0] = k_b * y
    for i in range(1, n):
        qp = p + dt * vp + h2 * ap
        qy = y + dt * vy + h2 * ay
        up = vp + h1 * ap
        uy = vy + h1 * ay
        d_hat = qp + qy - em[i] - gap[i]
        v_hat = up + uy - emd[i]
        ki = k[i]
        a22 = m_b + k_b * h2 + c_b * h1
        r2b = -k_b * qy - c_b * uy
        new_ap, new_ay = 0.0, 0.0
        for _ in range(6):
            if state == 0:
                chi, off = 0.0, 0.0
            elif state == 1:
                chi, off = 1.0, 0.0
            else:
                chi, off = 1.0, backlash
            kap = chi * ki * (h2 + beta * h1)
            f_hat = chi * ki * (d_hat + off + beta * v_hat)
            m11 = m_e + kap
            m22 = a22 + kap
            r1 = w[i] - f_hat
            r2 = r2b - f_hat
            det = m11 * m22 - kap * kap
            new_ap = (r1 * m22 - kap * r2) / det
            new_ay = (m11 * r2 - kap * r1) / det
            d_new = d_hat + h2 * (new_ap + new_ay)
            if d_new > 0.0:
                new_state = 1
            elif d_new < -backlash:
                new_state = -1
            else:
                new_state = 0
            if new_state == state:
                break
            state = new_state
        p = qp + h2 * new_ap
        y = qy + h2 * new_ay
        vp = up + h1 * new_ap
        vy = uy + h1 * new_ay
        ap, ay = new_ap, new_ay
        x_out[i] = p + y - em[i]
        fb_out[i] = k_b * y + c_b * vy
    return x_out, fb_out


@dataclass(frozen=True)
class _Phases:
    """The pair's random phases [rad] (fixed per gear set) and a record's start angle."""

    harmonics: tuple[float, ...]
    runout1: float
    runout2: float
    ripple: float

    @staticmethod
    def draw(pair: IndependentPair, rng: np.random.Generator) -> _Phases:
        ph = rng.uniform(0.0, 2 * np.pi, len(pair.profile_harmonics_um) + 3)
        return _Phases(tuple(float(v) for v in ph[:-3]), float(ph[-3]), float(ph[-2]),
                       float(ph[-1]))


def _lead_samples(pair: IndependentPair, fs_hz: float) -> int:
    """Samples between t = 0 and a record's first sample (the settling time, rounded)."""
    return round(pair.transient_s * fs_hz)


def _rates(fs_hz: float, target: float) -> tuple[int, int, float]:
    """(up, down, internal rate) with internal = fs * down / up near ``target``."""
    ratio = Fraction(fs_hz / target).limit_denominator(1000)
    up, down = ratio.numerator, ratio.denominator
    return up, down, fs_hz * down / up


def _respond(pair: IndependentPair, n1_rpm: float, torque_Nm: float, wear_mm: float,
             fs_hz: float, duration_s: float, name: str | None, values: dict,
             phases: _Phases, theta0: float) -> tuple[np.ndarray, np.ndarray]:
    """Clean DTE [m] and housing acceleration [m/s^2] (mean removed) at ``fs_hz``."""
    if name == "gear_runout":
        pair = dataclasses.replace(pair, runout2_um=pair.runout2_um + values["runout_um"])
    up, down, f_int = _rates(fs_hz, pair.internal_rate_hz)
    dt = 1.0 / f_int
    if pair.omega_max * dt > 0.5:
        raise _bad("fs_hz", fs_hz, "gives an internal rate too low for the mesh mode; use a "
                   "standard rate (e.g. 40960)")
    rb1, rb2 = pair.radii[2:4]
    w0 = torque_Nm / rb2
    mesh = _mesh_tables(pair, w0, wear_mm * 1e-3, name, values)
    n_out = round(duration_s * fs_hz)
    n_lead = _lead_samples(pair, fs_hz)
    n_tail = round(0.01 * fs_hz)
    n_int = math.ceil((n_lead + n_out + n_tail) * down / up) + 1
    t = np.arange(n_int) * dt

    om1 = 2 * np.pi * n1_rpm / 60.0
    om2 = om1 * pair.z1 / pair.z2
    theta1 = theta0 + om1 * t
    theta2 = theta1 * pair.z1 / pair.z2
    n_tab = mesh.k.size
    cell = np.mod(theta1 * (pair.z1 / (2 * np.pi)) * mesh.n_per, n_tab)
    grid = np.arange(n_tab)
    k_t = np.interp(cell, grid, mesh.k, period=n_tab)
    gap_t = np.interp(cell, grid, mesh.gap, period=n_tab)

    # run-out: eccentricity F_r / 2 on the line of action, and amplitude modulation
    e1, e2 = 0.5e-6 * pair.runout1_um, 0.5e-6 * pair.runout2_um
    c1, s1 = np.cos(theta1 + phases.runout1), np.sin(theta1 + phases.runout1)
    c2, s2 = np.cos(theta2 + phases.runout2), np.sin(theta2 + phases.runout2)
    am = pair.am_per_um * (pair.runout1_um * c1 + pair.runout2_um * c2)
    am_d = -pair.am_per_um * (pair.runout1_um * om1 * s1 + pair.runout2_um * om2 * s2)
    k_bar = float(np.mean(mesh.k))
    k_t = k_bar + (k_t - k_bar) * (1.0 + am)
    mesh_angle = theta1 * pair.z1
    om_m = om1 * pair.z1
    harm = np.zeros_like(t)
    harm_d = np.zeros_like(t)
    for h, (amp, ph) in enumerate(zip(pair.profile_harmonics_um, phases.harmonics,
                                      strict=True), start=1):
        harm += amp * 1e-6 * np.sin(h * mesh_angle + ph)
        harm_d += amp * 1e-6 * h * om_m * np.cos(h * mesh_angle + ph)
    em = (1.0 + am) * harm + e1 * s1 + e2 * s2
    emd = am_d * harm + (1.0 + am) * harm_d + e1 * om1 * c1 + e2 * om2 * c2

    # the load: torque ripple and the friction moment as an external forcing on p
    w_t = np.full_like(t, w0)
    if name == "torque_ripple":
        w_t *= 1.0 + values["ripple_pct"] / 100 * np.sin(values["order"] * theta1
                                                         + phases.ripple)
    if name == "friction":
        j1, j2 = pair.inertias
        tan_a = math.tan(pair.alpha)
        arm = pair.equivalent_mass * (rb1 * rb1 * tan_a / j1 + rb2 * rb2 * tan_a / j2)
        slide_t = np.interp(cell, grid, mesh.slide, period=n_tab)
        w_t *= 1.0 - values["mu"] * arm * slide_t

    x, fb = _newmark(k_t, gap_t, em, emd, w_t, dt, pair.equivalent_mass, pair.body_mass,
                     pair.bearing_stiffness, pair.bearing_damping, pair.rayleigh_beta,
                     2e-6 * pair.half_backlash_um)
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(fb))):
        raise RuntimeError("the independent simulator diverged; check the parameters")
    x_fs = signal.resample_poly(x, up, down)
    fb_fs = signal.resample_poly(fb - fb.mean(), up, down)
    acc = _mounted_housing(fb_fs, fs_hz, pair)
    if name == "transfer_path":
        acc = acc + values["gain"] * _bandpass(acc, fs_hz, values["fn_hz"], values["q"])
    sl = slice(n_lead, n_lead + n_out)
    acc = acc[sl]
    return x_fs[sl].copy(), acc - acc.mean()


def _mounted_housing(force: np.ndarray, fs: float, pair: IndependentPair) -> np.ndarray:
    """Acceleration of the housing (mass m_h on its mounting, mode f_h, zeta_h) under the
    bearing force: (F / m_h) s^2 / (s^2 + 2 zeta_h w_h s + w_h^2), bilinear transform."""
    acc = force / pair.housing_mass_kg
    if pair.mount_frequency_hz == 0:
        return acc
    wh = 2 * math.pi * pair.mount_frequency_hz
    b, a = signal.bilinear([1.0, 0.0, 0.0], [1.0, 2 * pair.mount_damping_ratio * wh, wh * wh],
                           fs)
    return signal.lfilter(b, a, acc)


def _bandpass(x: np.ndarray, fs: float, f0: float, q: float) -> np.ndarray:
    """Unit-peak 2nd-order band-pass (analog (w0/Q) s / (s^2 + (w0/Q) s + w0^2), bilinear
    transform pre-warped at f0)."""
    if not 0 < f0 < 0.45 * fs:
        raise _bad("transfer_path fn_hz", f0, f"must lie below 0.45 fs = {0.45 * fs:g} Hz")
    kk = math.tan(math.pi * f0 / fs)
    norm = 1.0 / (1.0 + kk / q + kk * kk)
    b = np.array([kk / q, 0.0, -kk / q]) * norm
    a = np.array([1.0, 2.0 * (kk * kk - 1.0) * norm, (1.0 - kk / q + kk * kk) * norm])
    return signal.lfilter(b, a, x)


def _sensor(x: np.ndarray, quantity: str, pair: IndependentPair, values: dict) -> np.ndarray:
    """Gain error and quadratic amplitude nonlinearity (a share of full scale)."""
    fs = (pair.dte_full_scale_um * 1e-6 if quantity == "dte_m" else pair.accel_full_scale_m_s2)
    y = values["gain"] * (x + values["nonlinearity"] * x * np.abs(x) / fs)
    return y if quantity == "dte_m" else y - y.mean()


def _noise(x: np.ndarray, snr_db: float, rng: np.random.Generator) -> np.ndarray:
    if math.isinf(snr_db):
        return x
    ac = x - x.mean()
    sigma = math.sqrt(float(np.mean(ac * ac)) / 10 ** (snr_db / 10))
    return x + sigma * rng.standard_normal(x.size)


def _check_record(pair, n1_rpm, torque_Nm, wear_mm, quantity, fs_hz, duration_s, snr_db):
    _check("n1_rpm", n1_rpm, 0.0, 10000.0)
    if n1_rpm < 100:
        raise _bad("n1_rpm", n1_rpm, "must be >= 100 r/min (at least a few revolutions)")
    _check("torque_Nm", torque_Nm, 0.0, 5000.0)
    _check("wear_mm", wear_mm, 0.0, 0.1, closed_lo=True)
    if quantity not in QUANTITIES:
        raise _bad("quantity", quantity, f"must be one of {QUANTITIES}")
    _check("fs_hz", fs_hz, 0.0, 0.25 * pair.internal_rate_hz)
    need = 12 * pair.mesh_frequency_hz(n1_rpm)
    if fs_hz < need:
        raise _bad("fs_hz", fs_hz, f"is below 4 x the third mesh harmonic ({need:g} Hz) at "
                   f"n1_rpm = {n1_rpm:g}")
    _check("duration_s", duration_s, 0.0, 60.0)
    if round(duration_s * fs_hz) < 64:
        raise _bad("duration_s", duration_s, "gives fewer than 64 samples")
    if not (isinstance(snr_db, int | float) and not isinstance(snr_db, bool)
            and (snr_db == math.inf or -20.0 <= snr_db < 200.0)):
        raise _bad("snr_db", snr_db, "must lie in [-20, 200) dB or be inf (no noise)")


def _finish(clean_dte, clean_acc, quantity, pair, name, values, snr_db, rng):
    x = clean_dte if quantity == "dte_m" else clean_acc
    if name == "sensor":
        x = _sensor(x, quantity, pair, values)
    y = _noise(x, snr_db, rng)
    return (y - y.mean() if quantity == "accel_m_s2" else y), x


def simulate_record(pair: IndependentPair | None = None, n1_rpm: float = 2000.0,
                    torque_Nm: float = 300.0, wear_mm: float = 0.0, quantity: str = "dte_m",
                    fs_hz: float = 40960.0, duration_s: float = 0.5, effect: str | None = None,
                    effect_size: float = 1.0, snr_db: float = 30.0,
                    rng: np.random.Generator | None = None, gear_set_seed: int | None = None,
                    start_angle_rad: float | None = None) -> np.ndarray:
    """One record (1-D float64): DTE [m, mean included] or housing acceleration [m/s^2, mean
    removed] of the independent model at one operating point and wear depth.

    ``rng`` (default ``numpy.random.default_rng(0)``) draws the gear set's error phases, the
    record's start angle and the noise, in that order. ``gear_set_seed``: the error phases
    drawn from this seed instead (one gear set for every record that names it);
    ``start_angle_rad``: the pinion's angle at the record's first sample (what a
    once-per-revolution mark tells; the mesh phase there is ``z1`` times it) instead of a
    drawn one.
    """
    pair = IndependentPair() if pair is None else pair
    if not isinstance(pair, IndependentPair):
        raise _bad("pair", type(pair).__name__, "must be an IndependentPair")
    _check_record(pair, n1_rpm, torque_Nm, wear_mm, quantity, fs_hz, duration_s, snr_db)
    if start_angle_rad is not None:
        _check("start_angle_rad", start_angle_rad, -1e6, 1e6)
    if gear_set_seed is not None and (not isinstance(gear_set_seed, int | np.integer)
                                      or isinstance(gear_set_seed, bool) or gear_set_seed < 0):
        raise _bad("gear_set_seed", gear_set_seed, "must be a whole number >= 0 or None")
    name, values = effect_values(effect, effect_size)
    if name is not None and quantity not in _EFFECTS[name][2]:
        raise _bad("effect", effect, f"does not show in {quantity} records; it acts on "
                   f"{_EFFECTS[name][2]}")
    rng = np.random.default_rng(0) if rng is None else rng
    phases = _Phases.draw(pair, rng if gear_set_seed is None
                          else np.random.default_rng(gear_set_seed))
    if start_angle_rad is None:
        theta0 = float(rng.uniform(0.0, 12 * np.pi))
    else:  # the pinion's angle at t = 0, the record's first sample lying its lead after it
        theta0 = float(start_angle_rad) - 2 * np.pi * n1_rpm / 60.0 * _lead_samples(
            pair, fs_hz) / fs_hz
    dte, acc = _clean_record(pair, float(n1_rpm), float(torque_Nm), float(wear_mm),
                             float(fs_hz), float(duration_s), name,
                             tuple(sorted(values.items())), phases, theta0)
    return np.array(_finish(dte, acc, quantity, pair, name, values, snr_db, rng)[0])


@lru_cache(maxsize=2)
def _clean_record(pair: IndependentPair, n1_rpm: float, torque_Nm: float, wear_mm: float,
                  fs_hz: float, duration_s: float, name: str | None,
                  values: tuple[tuple[str, float], ...], phases: _Phases, theta0: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_respond` for :func:`simulate_record`, read-only and kept for the same record's
    other quantity: a caller that asks for a record's DTE and then its acceleration (one gear
    set, one start angle) simulates it once."""
    dte, acc = _respond(pair, n1_rpm, torque_Nm, wear_mm, fs_hz, duration_s, name,
                        dict(values), phases, theta0)
    dte.setflags(write=False)
    acc.setflags(write=False)
    return dte, acc


def make_independent_bundle(
        path: str | Path, effect: str | None = None,
        operating_points: Sequence[tuple[float, float]] = ((2000.0, 300.0), (1800.0, 290.0)),
        wear_mm: Sequence[float] = (0.0, 0.003, 0.006, 0.009, 0.012, 0.015),
        quantities: Sequence[str] = ("dte_m",), fs_hz: float = 40960.0,
        duration_s: float = 0.5, snr_db: float = 30.0, seed: int = 0,
        effect_size: float = 1.0, pair: IndependentPair | None = None,
        values: dict | None = None, onset: float | None = None,
        dated: bool = False) -> tuple[Path, dict]:
    """Write a bundle (``docs/own-data.md``) of the independent model: one record
    per operating point x wear depth x quantity, all from one gear set (its error phases drawn
    once from ``seed``), each record at its own random start angle and with its own noise.

    ``values`` set some of the effect's values beyond its typical ones: ``{"order": 2.6}``
    puts a torque ripple at a non-integer order of the pinion shaft (default: 1/2).
    ``onset`` (a share of the life, 0-1): the effect appears during the bundle's life, in the
    records of at least ``onset`` times the largest wear depth only (the earlier ones are
    clean). ``dated``: the manifest gets a ``time`` column (ISO 8601), the wear states a week
    apart in order of wear, so that the earliest records can be a reference
    (``reference=first:N``); the cycles stay unknown, so the loop reads its model at each
    record's stated wear (at cycle counts its own wear law would put there, the model's other
    wear rate would be a residual of its own).

    Returns the bundle's path and the truth: the effect (canonical name), its values, the
    pair's parameters, the seed, and ``effect_to_noise_db``, the power the effect adds to the
    records against the noise's (``None`` without an effect).

    A ``path`` that holds anything but an earlier bundle is refused before any work
    (:func:`~physics.loop.measured.bundle.check_bundle_target`); an earlier bundle there is
    replaced.
    """
    path = check_bundle_target(path)
    pair = IndependentPair() if pair is None else pair
    if not isinstance(pair, IndependentPair):
        raise _bad("pair", type(pair).__name__, "must be an IndependentPair")
    if not isinstance(seed, int | np.integer) or isinstance(seed, bool) or seed < 0:
        raise _bad("seed", seed, "must be a whole number >= 0")
    ops = [tuple(op) for op in operating_points]
    if not ops or any(len(op) != 2 for op in ops):
        raise _bad("operating_points", operating_points, "must be a non-empty sequence of "
                   "(n1_rpm, torque_Nm) pairs")
    wears = list(wear_mm)
    if not wears:
        raise _bad("wear_mm", wear_mm, "must hold at least one wear depth")
    if onset is not None and not 0.0 < onset <= 1.0:
        raise _bad("onset", onset, "must be a share of the life in (0, 1]; e.g. 0.3 leaves "
                   "the wear states below 30 % of the largest clean")
    qs = list(quantities)
    if not qs or any(q not in QUANTITIES for q in qs) or len(set(qs)) != len(qs):
        raise _bad("quantities", quantities, f"must be distinct names from {QUANTITIES}")
    given = dict(values or {})
    name, values = effect_values(effect, effect_size)
    extra = sorted(set(given) - set(values))
    if extra:
        raise _bad("values", given, f"set values {extra} that {name} does not have; it has "
                   f"{sorted(values)}")
    values |= given
    if name is not None and not set(qs) & set(_EFFECTS[name][2]):
        raise _bad("effect", effect, f"does not show in {qs} records; it acts on "
                   f"{_EFFECTS[name][2]}")
    for n1, torque in ops:
        for wear in wears:
            for q in qs:
                _check_record(pair, n1, torque, wear, q, fs_hz, duration_s, snr_db)
        revs = duration_s * n1 / 60.0
        if revs < 10:
            raise _bad("duration_s", duration_s, f"holds {revs:.1f} pinion revolutions at "
                       f"{n1:g} r/min; a bundle record needs at least 10")

    phases = _Phases.draw(pair, np.random.default_rng([seed, 0]))
    rows, signals = [], {}
    added, noise = 0.0, 0.0
    k = 0
    for i_op, (n1, torque) in enumerate(ops):
        for i_w, wear in enumerate(wears):
            rng = np.random.default_rng([seed, 1, i_op, i_w])
            theta0 = float(rng.uniform(0.0, 12 * np.pi))
            args = (pair, float(n1), float(torque), float(wear), float(fs_hz),
                    float(duration_s))
            here = name if onset is None or wear >= onset * max(wears) else None
            dte, acc = _respond(*args, here, values, phases, theta0)
            plain = None
            if here == "sensor":  # acts after the response only
                plain = (dte, acc)
            elif here is not None:
                plain = _respond(*args, None, {}, phases, theta0)
            for q in qs:
                rec_rng = np.random.default_rng([seed, 2, i_op, i_w, QUANTITIES.index(q)])
                y, clean = _finish(dte, acc, q, pair, here, values, snr_db, rec_rng)
                if plain is not None and q in _EFFECTS[name][2]:
                    base = plain[0] if q == "dte_m" else plain[1]
                    scale = np.mean((clean - clean.mean()) ** 2)
                    added += float(np.mean((clean - base) ** 2) / scale)
                    noise += float(np.mean((y - clean - (y - clean).mean()) ** 2) / scale)
                rec = f"ind{k:03d}"
                k += 1
                signals[rec] = np.ascontiguousarray(y, dtype=np.float64)
                rows.append({"record": rec, "quantity": q, "fs_hz": float(fs_hz),
                             "n1_rpm": float(n1), "torque_Nm": float(torque),
                             "wear_mm": float(wear), "cycles": np.nan, "split": ""}
                            | ({"time": (EPOCH + pd.Timedelta(weeks=i_w)).isoformat()}
                               if dated else {}))
    manifest = pd.DataFrame(rows, columns=["record", "quantity", "fs_hz", "n1_rpm",
                                           "torque_Nm", "wear_mm", "cycles", "split",
                                           *(["time"] if dated else [])])
    gear = {}
    thesis = IndependentPair()
    for key in ("module_mm", "z1", "z2", "pressure_angle_deg", "face_width_mm"):
        if getattr(pair, key) != getattr(thesis, key):
            gear[key] = getattr(pair, key)
    out = write_bundle(path, manifest, signals, gear or None)
    e2n = None
    if name is not None:
        e2n = (float(10 * np.log10(added / noise)) if added > 0 and noise > 0
               else (-math.inf if added == 0 else math.inf))
    truth = {
        "simulator": "independent", "effect": name, "values": values,
        "effect_size": float(effect_size) if name else None, "seed": int(seed),
        "pair": dataclasses.asdict(pair),
        "phases": dataclasses.asdict(phases), "snr_db": snr_db,
        "k_mean_N_m": pair.k_mean, "equivalent_mass_kg": pair.equivalent_mass,
        "effect_to_noise_db": e2n, "onset": onset,
    }
    return out, truth
