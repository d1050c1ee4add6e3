"""Validated, frozen parameter sets of the spur-gear wear model.

Field names carry their unit where it is not SI (``module_mm``, ``torque_Nm``); each class offers
the SI values the physics uses as properties. Defaults are the thesis's values (Tables 0, 1 and 11
of ``physics/reference/thesis_tables``); constants the thesis does not state are chosen once here,
from standard gear-steel and lubricant data, with their source beside them. The Hydra YAML groups
under ``conf/`` hold the same values (``tests/test_params.py`` keeps the two in step).

Every class validates itself on construction: a bad value raises ``ValueError`` naming the field,
the value, the allowed range and how to fix it, before any computation starts.
"""

from __future__ import annotations

import functools
import math
import numbers
from dataclasses import dataclass, field, fields
from importlib.resources import files
from importlib.resources.abc import Traversable
from typing import Any

R_GAS = 8.314462618  # J/(mol K), CODATA 2018 molar gas constant


class OutOfScope(ValueError):
    """A run left the model's scope on its own (a tooth worn through, the mixed-EHL table's
    range exceeded by the worn profile, a worn flank past the shakedown limit): the physics has
    stopped, not the code. Scenarios that are out of scope from the start are refused before
    any work (:mod:`physics.scope`)."""


def bounded(default: Any, lo: float, hi: float, hint: str = "", *, closed: bool = False,
            whole: bool = False) -> Any:
    """A numeric field with its allowed range (``lo < v < hi``; ``closed``: ``lo <= v < hi``;
    ``whole``: a whole number in ``[lo, hi]``) and a hint for the fix, checked by
    :func:`validate_fields`."""
    return field(default=default, metadata={"lo": lo, "hi": hi, "hint": hint, "closed": closed,
                                            "whole": whole})


def choice(default: str, *allowed: str) -> Any:
    """A text field restricted to ``allowed``."""
    return field(default=default, metadata={"choices": allowed})


def _fail(owner: str, name: str, value: Any, rule: str, hint: str = "") -> ValueError:
    return ValueError(f"{owner}.{name} = {value!r} {rule}" + (f"; {hint}" if hint else ""))


def validate_fields(obj: Any, owner: str) -> None:
    """Check and normalise every field of dataclass ``obj`` declared with :func:`bounded` or
    :func:`choice`: numpy scalars and integral floats become plain ``int``/``float``; a value
    of the wrong type or outside its range raises ``ValueError`` naming the field, the value,
    the rule and the fix. ``None`` passes where the default is ``None``."""
    for f in fields(obj):
        meta, v = f.metadata, getattr(obj, f.name)
        if v is None and f.default is None:
            continue
        if "choices" in meta:
            if v not in meta["choices"]:
                raise _fail(owner, f.name, v, f"must be one of {list(meta['choices'])}")
            continue
        if "lo" not in meta:
            continue
        lo, hi, hint = meta["lo"], meta["hi"], meta["hint"]
        if meta["whole"]:
            ok = isinstance(v, numbers.Integral) or (isinstance(v, float) and v.is_integer())
            if isinstance(v, bool) or not ok or not lo <= v <= hi:
                raise _fail(owner, f.name, v, f"must be a whole number in [{lo:g}, {hi:g}]", hint)
            object.__setattr__(obj, f.name, int(v))
            continue
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
            raise _fail(owner, f.name, v, "must be a finite number", hint)
        inside = lo <= v < hi if meta["closed"] else lo < v < hi
        if not inside:
            left = "[" if meta["closed"] else "("
            raise _fail(owner, f.name, v, f"must lie in {left}{lo:g}, {hi:g})", hint)
        object.__setattr__(obj, f.name, float(v))


@dataclass(frozen=True)
class GearPair:
    """Spur gear pair geometry (thesis 2.1), standard full-depth involute teeth, no profile shift.

    ``center_distance_mm = None`` means the standard centre distance ``m (z1 + z2) / 2``. The bore
    radii and the cutter tip-radius coefficient are not stated by the thesis: a pinion on a 20 mm
    shaft and a gear on a 30 mm shaft, and the ISO 53 profile A cutter tip radius 0.38 m.
    """

    module_mm: float = bounded(2.0, 0.0, 100.0, "give the module in mm")
    z1: int = bounded(18, 5, 1000, "teeth of the pinion", whole=True)
    z2: int = bounded(27, 5, 1000, "teeth of the gear", whole=True)
    pressure_angle_deg: float = bounded(20.0, 10.0, 35.0)
    face_width_mm: float = bounded(30.0, 0.0, 2000.0)
    ha_star: float = bounded(1.0, 0.0, 2.0)
    c_star: float = bounded(0.25, 0.0, 1.0)
    center_distance_mm: float | None = bounded(None, 0.0, 1e5, "null: the standard distance")
    bore_radius1_mm: float = bounded(10.0, 0.0, 1e5)
    bore_radius2_mm: float = bounded(15.0, 0.0, 1e5)
    # ISO 53:1998 basic rack profile A, rho_fP / m
    cutter_tip_radius_coeff: float = bounded(0.38, 0.0, 0.6, closed=True)

    def __post_init__(self) -> None:
        o = "gear"
        validate_fields(self, o)
        if self.z1 > self.z2:
            raise ValueError(
                f"{o}.z1 = {self.z1} exceeds z2 = {self.z2}: z1 is the pinion, the smaller wheel; "
                "swap them"
            )
        a0 = self.standard_center_distance_mm
        a = self.center_distance_mm
        if a is not None and not 0.9 * a0 < a < 1.1 * a0:
            raise _fail(o, "center_distance_mm", a, f"must lie in ({0.9 * a0:g}, {1.1 * a0:g})",
                        f"the standard centre distance is {a0:g} mm; null selects it")
        for name, z in (("bore_radius1_mm", self.z1), ("bore_radius2_mm", self.z2)):
            rf = self.module_mm * (z / 2 - self.ha_star - self.c_star)
            if not getattr(self, name) < rf:
                raise _fail(o, name, getattr(self, name), f"must be below the root radius "
                            f"{rf:g} mm", "the bore must lie inside the root circle")

    @property
    def standard_center_distance_mm(self) -> float:
        return self.module_mm * (self.z1 + self.z2) / 2

    @property
    def m(self) -> float:
        """Module [m]."""
        return self.module_mm * 1e-3

    @property
    def alpha(self) -> float:
        """Standard (cutting) pressure angle [rad]."""
        return math.radians(self.pressure_angle_deg)

    @property
    def face_width(self) -> float:
        """Face width B [m]."""
        return self.face_width_mm * 1e-3

    @property
    def center_distance(self) -> float:
        """Operating centre distance [m]."""
        a = self.center_distance_mm
        return (self.standard_center_distance_mm if a is None else a) * 1e-3


@dataclass(frozen=True)
class Material:
    """Gear steel, identical for pinion and gear (the thesis names none).

    Case-carburised gear steel (20CrMnTi / 18CrNiMo7-6 class):
    - E = 206 GPa, nu = 0.3: ISO 6336-1:2019, 6.5 (steel/steel reference values).
    - Surface hardness 7.0 GPa: case-carburised flanks of 58-62 HRC are HV 650-750 (ASTM E140
      conversion); HV 700 x 9.807 MPa.
    - k = 46 W/(m K), rho = 7830 kg/m^3, c = 465 J/(kg K): low-alloy gear steel, as tabulated in
      the FEUP gear group's material library (GEARpie) and within the AISI 4130-4340 range of
      Incropera et al., Fundamentals of Heat and Mass Transfer, Table A.1; diffusivity 1.26e-5
      m^2/s.
    """

    youngs_modulus_GPa: float = bounded(206.0, 0.0, 1000.0)
    poisson: float = bounded(0.3, 0.0, 0.5)
    hardness_GPa: float = bounded(7.0, 0.0, 50.0,
                                  "give the indentation hardness in GPa (HV x 0.009807)")
    thermal_conductivity_W_mK: float = bounded(46.0, 0.0, 500.0)
    density_kg_m3: float = bounded(7830.0, 0.0, 30000.0)
    specific_heat_J_kgK: float = bounded(465.0, 0.0, 5000.0)

    def __post_init__(self) -> None:
        validate_fields(self, "material")

    @property
    def E(self) -> float:
        return self.youngs_modulus_GPa * 1e9

    @property
    def hardness(self) -> float:
        return self.hardness_GPa * 1e9

    @property
    def diffusivity(self) -> float:
        """Thermal diffusivity k / (rho c) [m^2/s]."""
        return self.thermal_conductivity_W_mK / (self.density_kg_m3 * self.specific_heat_J_kgK)


@dataclass(frozen=True)
class Lubricant:
    """Lubricant at the bulk temperature (thesis Table 1, 2.4-2.6).

    Defaults are the thesis baseline (eta0 0.35 Pa s, alpha 2.5e-8 m^2/N, Lambda_lim 0.091, and
    X, t0, Ea of 2.6). ``temp_visc_coeff_per_K`` is the viscosity-temperature coefficient beta0 =
    -d ln(eta)/dT at the bulk temperature, which sets the Roelands temperature index S0. The
    thesis states neither it nor the density: we take 0.03 /K, the low end of mineral and PAO gear
    oils near 40 C (0.03-0.06 /K; the Walther fits in ``conf/lubricant`` give 0.044-0.052), and
    870 kg/m^3, a mineral oil at ambient pressure.
    """

    name: str = "thesis baseline"
    eta0_Pa_s: float = bounded(0.35, 0.0, 100.0, "dynamic viscosity in Pa s")
    alpha_m2_per_N: float = bounded(
        2.5e-8, 0.0, 1e-7, "pressure-viscosity coefficient in m^2/N (1/Pa), e.g. 2.2e-8")
    rho0_kg_m3: float = bounded(870.0, 0.0, 3000.0)
    temp_visc_coeff_per_K: float = bounded(0.03, 0.0, 0.2)
    limiting_shear_coeff: float = bounded(0.091, 0.0, 1.0)
    molecular_diameter_m: float = bounded(3e-10, 0.0, 1e-8)
    vibration_time_s: float = bounded(3e-12, 0.0, 1e-9)
    adsorption_heat_J_mol: float = bounded(4.9e4, 0.0, 1e6)

    def __post_init__(self) -> None:
        validate_fields(self, "lubricant")


@dataclass(frozen=True)
class Tribology:
    """Surface and wear constants (thesis Table 1 and 2.5-2.7).

    ``sigma_um`` is the composite RMS roughness; ``dry_friction_coeff`` the boundary (asperity)
    friction coefficient f_c of 2.5, not stated by the thesis: 0.1, the middle of the 0.05-0.15
    of boundary-lubricated steel on steel (Stachowiak & Batchelor, Engineering Tribology, 4th
    ed., ch. 8). ``regime = "dry"`` selects the classical Archard law on the whole Hertz
    pressure with ``dry_wear_coeff`` (2.7.5, Table 5). ``boundary_share`` b blends the two in
    the lubricated regime, ``(1 - b)`` lubricated law ``+ b`` dry law: the share of running time
    under boundary lubrication (starts and stops, starved supply, oil-temperature peaks), in
    which the film carries nothing. The thesis uses one law or the other; a real gearbox lies
    between, by an amount nobody measures; the dataset can draw b per trajectory
    (``data.nuisance.boundary_share``, off by default).

    ``asperity_model`` chooses where the lubricated (mixed) law takes the film and the share of
    the load carried by asperities: ``"solver"`` (default), the numerical mixed-EHL line-contact
    solver of :mod:`physics.tribology.mixed_ehl` through its precomputed table
    (:mod:`physics.tribology.asperity_table`); ``"regression"``, the Masjedi-Khonsari formulas
    the thesis prints (2.4), kept for comparison.

    ``wear_coeff`` is ``k_a``, the Archard coefficient of the asperity contacts the oil film
    leaves unprotected, in the lubricated law ``k_eff = min(k_a L_a psi, k_dry)`` on the total
    load (thesis 2.6, bounded by the dry law: :mod:`physics.tribology.wear`). The thesis's
    ``k = 5e-4`` (Table 1) belongs to an asperity share of 6.5 % (Table 2) that its formulas do
    not give; the default is calibrated once, to the quasi-static pinion root wear of Table 8
    (2.7 um after 1.5e7 cycles), by ``python -m physics.tribology.calibration``: ``k_a = 0.274``
    (with ``asperity_model = "solver"`` and the other defaults). On the baseline path the
    Archard coefficient on the total load it implies is 6.8e-10 (load- and sliding-weighted
    mean; at most 5.5e-9; ``k/H`` = 1.1e-19 m^2/N), below the thesis's dry 2e-8 and three
    orders below the mild boundary-lubricated wear of slow gears (of the order of 1e-16 m^2/N:
    Flodin & Andersson, Wear 207 (1997) 16-23), as a mostly separating film should be. ``k_a``
    itself is the coefficient of clean metal contacts, a severe adhesive value. Every other
    table follows from it uncalibrated (``docs/reproduction.md``).
    """

    sigma_um: float = bounded(0.5, 0.0, 10.0, "composite RMS roughness in um")
    wear_coeff: float = bounded(
        0.274, 0.0, 1.0, "the Archard coefficient of unprotected asperity contacts, k_a "
        "(calibrated 0.274 with the solver)")
    dry_wear_coeff: float = bounded(2e-8, 0.0, 1.0)
    dry_friction_coeff: float = bounded(0.1, 0.0, 1.0)
    regime: str = choice("mixed", "mixed", "dry")
    boundary_share: float = bounded(
        0.0, 0.0, 1.0, "share of running time under boundary lubrication, 0 <= b < 1 (b = 1: "
        "tribology.regime=dry)", closed=True)
    asperity_model: str = choice("solver", "solver", "regression")

    def __post_init__(self) -> None:
        validate_fields(self, "tribology")


@dataclass(frozen=True)
class Operating:
    """Operating point (thesis Table 1 / Table 11): pinion speed, torque on the gear, bulk temp."""

    n1_rpm: float = bounded(2000.0, 0.0, 1e5, "pinion speed in r/min, positive")
    torque_Nm: float = bounded(300.0, 0.0, 1e6, "gear torque in N m, positive")
    bulk_temperature_K: float = bounded(315.0, 200.0, 500.0, "bulk temperature in kelvin")

    def __post_init__(self) -> None:
        validate_fields(self, "operating")

    @property
    def omega1(self) -> float:
        """Pinion angular speed [rad/s]."""
        return self.n1_rpm * 2 * math.pi / 60


@dataclass(frozen=True)
class WearSolver:
    """Numerics of the wear integration (thesis 2.6).

    ``n_points``: grid points along the path of contact; ``update_um``: the largest wear change
    (anywhere on either flank) allowed before the profile and all contact quantities are updated.
    """

    n_points: int = bounded(401, 21, 100_001, whole=True)
    update_um: float = bounded(1.0, 0.0, 100.0)
    temperature_tol_K: float = bounded(1e-3, 0.0, 10.0)
    max_iterations: int = bounded(100, 1, 100_000, whole=True)

    def __post_init__(self) -> None:
        validate_fields(self, "solver")


@dataclass(frozen=True)
class Dynamics:
    """Torsional gear-pair model of thesis 3.3: damping, backlash, errors, inertias, sampling.

    None of these are stated by the thesis; each is chosen from standard data:

    - ``damping_ratio`` 0.07 of critical mesh damping ``c = 2 zeta sqrt(k_mean m_e)``: inside the
      0.03-0.17 that Kasuba & Evans (ASME J. Mech. Des. 103 (1981) 398-409) report for spur gear
      meshes, and the value used by Kahraman & Singh (J. Sound Vib. 142 (1990) 49-75).
    - ``half_backlash_um`` 47.5: half the minimum normal backlash ``(2/3)(0.06 + 0.0005 a +
      0.03 m)`` mm of ISO/TR 10064-2 for a = 45 mm, m = 2 mm.
    - ``eccentricity1_um`` 7.5: half the radial runout 15 um of an ISO 1328-2 grade 6 pinion
      (d = 36 mm, m = 2); it acts on the line of action as ``e sin(alpha_w)`` at shaft rate.
    - ``profile_error_um`` 3.0: half the profile form tolerance of ISO 1328-1 grade 6 (6 um), the
      amplitude of the mesh-rate (short-period) error.
    - ``form_deviation_um`` 0, ``form_waves`` 1, ``form_phase_rad`` 0: the pinion flank's own
      profile form deviation, a wave along the active profile in the mesh's gap
      (:func:`physics.gear.accuracy.form_deviation`); 0 is the thesis's involute flank, whose
      manufacturing error is the mesh-rate sinusoid above alone. The dataset draws it
      (:class:`physics.dataset.generation.NuisanceRanges`).
    - ``inertia*_kg_m2``: null computes solid steel discs of the face width between the bore and
      the pitch circle.
    - ``sample_rate_hz`` 40960: the thesis's test rig (4.3).
    - ``feedback_revolutions`` 1: at every profile update the wear feedback (thesis 3.5) runs
      the model for ``transient_s`` and then at least this many whole pinion revolutions (more
      where one revolution's steps miss a mesh-phase bin), over which it averages the mesh
      force by mesh phase (whole revolutions: the shaft-rate run-out averages out). Not
      stated by the thesis; one whole revolution averages the shaft-rate run-out out and costs
      less than ``duration_s`` (0.1 s, 3.3 revolutions at 2000 r/min), for a change of the
      wear far below the step error of docs/reproduction.md, Limits.
    - ``housing_mass_kg`` 20: effective mass ``m_h`` of the declared measurement chain, a rigid
      housing whose acceleration along the line of action is ``(F_d - mean F_d) / m_h``; the
      order of a small single-stage housing. It is a nuisance parameter, calibrated against
      measurements (:mod:`physics.loop`): with 20 kg the healthy thesis pair gives an RMS of
      about 70 m/s^2 where the rig of thesis Table 15 measured 1.1 m/s^2 through its real
      transfer path.
    - ``support_hz`` 0 and ``support_damping`` 0.05: a declared bearing-support mode between the
      mesh and the housing (:func:`physics.signals.measurement.support_path`): the pinion body
      on its shaft and bearings. 0 declares a rigid support; a user who knows the mode (an
      impact test, or ``sqrt(k_b / m)`` of the bearing stiffness and the body's mass) states
      it, and the measured-data loop calibrates it around that value. 0.05: a lightly damped
      mode (rolling bearings add little damping: SKF Evolution, "Damping in a rolling bearing
      arrangement"; the loop fits it within 0.005-0.3).
    - ``mount_hz`` 0 and ``mount_damping`` 0.1: a declared mode of the housing on its mounting
      (:func:`physics.signals.measurement.housing_mount`): below it the housing's acceleration
      is stiffness-controlled, so shaft-order and drive-line-order lines are far weaker than
      the free mass ``m_h`` makes them; the mesh harmonics lie well above it. 0 declares a free
      housing; a user states ``sqrt(k_m / m)`` of the mounts' stiffness and the housing's mass
      (resilient mounts 5-30 Hz, a housing bolted to a frame 50-300 Hz). 0.1: elastomer
      mounts' loss factor of 0.1-0.3 (Harris & Piersol, Shock and Vibration Handbook, 5th ed.,
      ch. 32: natural rubber and neoprene) is a damping ratio of 0.05-0.15; the loop fits it
      within 0.02-0.5.
    - ``flank_contact`` "path": each pair's gap is its two flanks' wear (and form deviation)
      summed at its point of the theoretical path, and a pair touches on that path only
      (thesis 2.2). "exact": the rigid gap of the flanks as they are, on and off the path, tip
      corners included, and the pairs before their entry and after their exit that can touch
      (:mod:`physics.gear.tooth_contact`). "path" is the default while the datasets, tables and
      the loop are made with it; ``rig_comparison.csv`` shows both.
    - ``stiffness_factor``, ``double_contact_factor``, ``resonance_factor`` 1: the model's form
      uncertainty (:mod:`physics.dynamics.model_form`): the mesh stiffness level, the
      double/single stiffness ratio and the mesh resonance relative to the declared model (the
      potential-energy stiffness, the blanks' inertias). 1 is the thesis model; a dataset
      draws them per trajectory where its ``data.nuisance`` ranges say so, the measured-data
      loop calibrates them (``loop.model_form``).
    """

    damping_ratio: float = bounded(0.07, 0.0, 1.0, "fraction of critical damping; 0.03-0.17 "
                                   "for gear meshes", closed=True)
    half_backlash_um: float = bounded(47.5, 0.0, 1e4, "half the normal backlash, um",
                                      closed=True)
    eccentricity1_um: float = bounded(7.5, 0.0, 1000.0, closed=True)
    profile_error_um: float = bounded(3.0, 0.0, 1000.0, closed=True)
    form_deviation_um: float = bounded(0.0, 0.0, 1000.0, "half the peak-to-valley of the "
                                       "pinion flank's form deviation; 0: the involute",
                                       closed=True)
    form_waves: float = bounded(1.0, 0.0, 100.0, "half-waves of the form deviation over the "
                                "active profile")
    form_phase_rad: float = bounded(0.0, -100.0, 100.0, "phase of the form deviation's wave")
    inertia1_kg_m2: float | None = bounded(None, 0.0, 1e3, "null: a solid steel disc")
    inertia2_kg_m2: float | None = bounded(None, 0.0, 1e3, "null: a solid steel disc")
    sample_rate_hz: float = bounded(40960.0, 100.0, 1e7)
    duration_s: float = bounded(0.1, 0.0, 100.0)
    transient_s: float = bounded(0.02, 0.0, 100.0, closed=True)
    step_factor: float = bounded(
        0.25, 0.0, 2.78, "omega_max dt above 2.78 makes fourth-order Runge-Kutta unstable; 0.25 "
        "keeps it accurate")
    phase_bins: int = bounded(512, 16, 1 << 20, whole=True)
    feedback_revolutions: int = bounded(
        1, 1, 10_000, "pinion revolutions the wear feedback averages the mesh force over",
        whole=True)
    housing_mass_kg: float = bounded(20.0, 0.0, 1e5)
    support_hz: float = bounded(0.0, 0.0, 1e6, "0: a rigid support; else the bearing-support "
                                "mode [Hz]", closed=True)
    support_damping: float = bounded(0.05, 0.0, 1.0, "fraction of critical damping")
    mount_hz: float = bounded(0.0, 0.0, 1e6, "0: a free housing; else the housing's mode on its "
                              "mounting [Hz]", closed=True)
    mount_damping: float = bounded(0.1, 0.0, 1.0, "fraction of critical damping")
    stiffness_factor: float = bounded(1.0, 0.0, 100.0, "mesh stiffness over the declared one")
    double_contact_factor: float = bounded(1.0, 0.0, 100.0, "double-contact stiffness over the "
                                           "declared one")
    resonance_factor: float = bounded(1.0, 0.0, 100.0, "mesh resonance over the declared one")
    flank_contact: str = choice("path", "path", "exact")

    def __post_init__(self) -> None:
        validate_fields(self, "dynamics")


@dataclass(frozen=True)
class Scenario:
    """Everything one wear simulation needs.

    The defaults are the thesis's: the gear pair of Table 0 and the baseline of Table 1, which
    is operating case 3 of Table 11, with the constants the thesis does not state chosen in each
    group (module docstring).

    Parameters
    ----------
    gear : GearPair
        Geometry of the pair (thesis 2.1).
    material : Material
        Steel of both wheels.
    lubricant : Lubricant
        Lubricant at the bulk temperature (thesis Table 1, 2.4-2.6).
    tribology : Tribology
        Surface and wear constants (thesis Table 1, 2.5-2.7).
    operating : Operating
        Pinion speed, gear torque and bulk temperature (thesis Tables 1 and 11).
    solver : WearSolver
        Numerics of the wear integration (thesis 2.6).
    dynamics : Dynamics
        The torsional gear-pair model and the measurement chain (thesis 3.3).

    Examples
    --------
    >>> scn = Scenario()
    >>> g = scn.gear  # the thesis pair, Table 0
    >>> g.module_mm, g.z1, g.z2, g.pressure_angle_deg, g.face_width_mm
    (2.0, 18, 27, 20.0, 30.0)
    >>> g.standard_center_distance_mm  # m (z1 + z2) / 2
    45.0
    >>> op = scn.operating  # the baseline, Table 1
    >>> op.n1_rpm, op.torque_Nm, op.bulk_temperature_K
    (2000.0, 300.0, 315.0)
    >>> scn.lubricant.eta0_Pa_s, scn.lubricant.alpha_m2_per_N, scn.tribology.sigma_um
    (0.35, 2.5e-08, 0.5)
    >>> scn == scenario_from_config({"case": 3})  # the baseline is case 3 of Table 11
    True
    >>> scenario_from_config({"case": 5}).operating.n1_rpm
    2200.0
    """

    gear: GearPair = GearPair()
    material: Material = Material()
    lubricant: Lubricant = Lubricant()
    tribology: Tribology = Tribology()
    operating: Operating = Operating()
    solver: WearSolver = WearSolver()
    dynamics: Dynamics = Dynamics()


@dataclass
class PhysicsConfig:
    """The physics groups of an app's config (``conf/physics/``): the schema every physics app's
    config extends (structured configs; each group validates itself when built)."""

    gear: GearPair = field(default_factory=GearPair)
    material: Material = field(default_factory=Material)
    lubricant: Lubricant = field(default_factory=Lubricant)
    tribology: Tribology = field(default_factory=Tribology)
    operating: Operating = field(default_factory=Operating)
    solver: WearSolver = field(default_factory=WearSolver)
    dynamics: Dynamics = field(default_factory=Dynamics)


_PARTS = {
    "gear": GearPair, "material": Material, "lubricant": Lubricant,
    "tribology": Tribology, "operating": Operating, "solver": WearSolver, "dynamics": Dynamics,
}


def _build(cls: type, values: dict[str, Any], where: str) -> Any:
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(values) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown}; allowed: {sorted(known)}")
    return cls(**values)


def config_file(*parts: str) -> Traversable:
    """A file of the physics configs (``conf/physics/`` in the checkout), found through the
    installed package ``gearwear_conf``, so it works from any folder and from a wheel."""
    return files("gearwear_conf").joinpath("physics", *parts)


def config_choices(group: str) -> list[str]:
    """The choices of a physics config group (``lubricant`` -> ``['pao', 'sae30', 'thesis']``)."""
    return sorted(p.name[:-5] for p in config_file(group).iterdir() if p.name.endswith(".yaml"))


_CASE_FIELDS = {
    "operating": ("n1_rpm", "torque_Nm"),
    "lubricant": ("eta0_Pa_s", "alpha_m2_per_N", "limiting_shear_coeff"),
}


def operating_cases() -> dict[int, dict[str, float]]:
    """The five operating cases of thesis Table 11, from ``conf/physics/cases.yaml`` (a fresh
    copy each call: the caller may change it)."""
    return {k: dict(v) for k, v in _read_cases()}


@functools.cache
def _read_cases() -> tuple[tuple[int, tuple[tuple[str, float], ...]], ...]:
    """``cases.yaml`` parsed once per process (a dataset's plan reads a case for each of its
    gearboxes)."""
    import yaml

    text = config_file("cases.yaml").read_text()
    return tuple((int(k), tuple(dict(v).items())) for k, v in yaml.safe_load(text).items())


def case_values(case: Any) -> dict[str, float]:
    """Values of operating case ``case`` (1-5, thesis Table 11); a clear error otherwise."""
    cases = operating_cases()
    try:
        key = int(case)
    except (TypeError, ValueError):
        key = None
    if key not in cases or isinstance(case, bool) or str(case).strip() != str(key):
        raise ValueError(f"case = {case!r} is not an operating case; valid cases: "
                         f"{sorted(cases)} (thesis Table 11)")
    return cases[key]


def check_case(cfg: Any, given: Any = ()) -> None:
    """Refuse (ValueError, one line) a ``case`` (1-5, thesis Table 11) beside a value of the
    fields it sets (:data:`_CASE_FIELDS`: ``operating.n1_rpm``, ``operating.torque_Nm`` and the
    lubricant's ``eta0_Pa_s``, ``alpha_m2_per_N``, ``limiting_shear_coeff``) that differs from
    the case's: the case's would be used without a word. A value counts as given where its key
    (``operating.torque_Nm``) or its group (``lubricant=pao``) is in ``given`` (the keys of the
    command line: :func:`physics.command.run_command`), or where it differs from the field's
    default (what a YAML choice, another group or a caller's mapping set). A config without
    ``case``, or without these groups (``train.py``'s ``case``), passes."""
    case = cfg.get("case") if hasattr(cfg, "get") else None
    groups = [g for g in _CASE_FIELDS if hasattr(cfg, "get") and cfg.get(g) is not None]
    if case is None or not groups:
        return
    values = case_values(case)
    given = {str(k).split("=", 1)[0].lstrip("+~") for k in given}
    for group in groups:
        default = _PARTS[group]()
        for name in _CASE_FIELDS[group]:
            value = cfg[group].get(name) if hasattr(cfg[group], "get") else None
            if value is None or name not in values:
                continue
            try:
                same = float(value) == float(values[name])
                changed = float(value) != float(getattr(default, name))
            except (TypeError, ValueError):
                continue  # not a number: the group's own check names it
            key = f"{group}.{name}"
            if not same and (changed or key in given or group in given):
                own = (f"{key}" if group == "operating" else
                       f"a lubricant of your own (lubricant=<choice> or {key})")
                raise ValueError(
                    f"case = {case} sets {key} = {values[name]:g} (thesis Table 11), and "
                    f"{key} = {value:g} is given too: the case's value would be used without a "
                    f"word; give either case={case} or {own}, not both")


def scenario_from_config(cfg: Any) -> Scenario:
    """Build a :class:`Scenario` from a mapping (a Hydra/OmegaConf config or a plain dict).

    Only the groups present are read (``gear``, ``material``, ``lubricant``, ``tribology``,
    ``operating``, ``solver``); a ``case`` key (1-5), if set, gives the operating point and
    the lubricant values that Table 11 lists, and a value of these that differs from the case's
    is refused (:func:`check_case`).
    """
    try:
        from omegaconf import OmegaConf

        if OmegaConf.is_config(cfg):
            cfg = OmegaConf.to_container(cfg, resolve=True)
    except ImportError:  # pragma: no cover - omegaconf is a dependency
        pass
    cfg = dict(cfg)
    check_case(cfg)
    case = case_values(cfg["case"]) if cfg.get("case") is not None else {}
    parts: dict[str, Any] = {}
    for key, cls in _PARTS.items():
        values = dict(cfg.get(key) or {})
        values.update({k: case[k] for k in _CASE_FIELDS.get(key, ()) if k in case})
        parts[key] = _build(cls, values, key)
    return Scenario(**parts)


def scenario_for_case(cfg: Any, case: Any) -> Scenario:
    """The scenario of ``cfg`` (a mapping, as :func:`scenario_from_config` reads) at operating
    case ``case`` of Table 11: the values the case sets (:func:`check_case`) are the case's,
    in place of the config's own; the rest is the config's (a study over the cases)."""
    try:
        from omegaconf import OmegaConf

        is_config = OmegaConf.is_config(cfg)
    except ImportError:  # pragma: no cover - omegaconf is a dependency
        is_config = False
    parts: dict[str, Any] = {}
    for group in _PARTS:
        if cfg.get(group) is None:
            continue
        values = (OmegaConf.to_container(cfg[group], resolve=True) if is_config
                  else dict(cfg[group]))
        parts[group] = {k: v for k, v in values.items() if k not in _CASE_FIELDS.get(group, ())}
    return scenario_from_config({**parts, "case": case})
