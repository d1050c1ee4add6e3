"""Validated, frozen parameter sets of the spur-gear wear model.

Field names carry their unit where it is not SI (``module_mm``, ``torque_Nm``); each class offers
the SI values the physics uses as properties. Defaults are the thesis's values (Tables 0, 1 and 11
of ``shared/reference/thesis_tables``); constants the thesis does not state are chosen once here,
from standard gear-steel and lubricant data, with their source beside them. The Hydra YAML groups
under ``conf/`` hold the same values (``tests/test_params.py`` keeps the two in step).

Every class validates itself on construction: a bad value raises ``ValueError`` naming the field,
the value, the allowed range and how to fix it, before any computation starts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

R_GAS = 8.314462618  # J/(mol K), CODATA 2018 molar gas constant


def _check_range(owner: str, name: str, value: float, lo: float, hi: float, hint: str = "") -> None:
    """Raise ``ValueError`` unless ``lo < value < hi`` (open interval, finite)."""
    ok = isinstance(value, int | float) and not isinstance(value, bool)
    if not (ok and math.isfinite(value) and lo < value < hi):
        rule = f"must lie in ({lo:g}, {hi:g})"
        raise ValueError(f"{owner}.{name} = {value!r} {rule}" + (f"; {hint}" if hint else ""))


@dataclass(frozen=True)
class GearPair:
    """Spur gear pair geometry (thesis 2.1), standard full-depth involute teeth, no profile shift.

    ``center_distance_mm = None`` means the standard centre distance ``m (z1 + z2) / 2``. The bore
    radii and the cutter tip-radius coefficient are not stated by the thesis: a pinion on a 20 mm
    shaft and a gear on a 30 mm shaft, and the ISO 53 profile A cutter tip radius 0.38 m.
    """

    module_mm: float = 2.0
    z1: int = 18
    z2: int = 27
    pressure_angle_deg: float = 20.0
    face_width_mm: float = 30.0
    ha_star: float = 1.0
    c_star: float = 0.25
    center_distance_mm: float | None = None
    bore_radius1_mm: float = 10.0
    bore_radius2_mm: float = 15.0
    cutter_tip_radius_coeff: float = 0.38  # ISO 53:1998 basic rack profile A, rho_fP / m

    def __post_init__(self) -> None:
        o = "gear"
        _check_range(o, "module_mm", self.module_mm, 0.0, 100.0, "give the module in mm")
        for name in ("z1", "z2"):
            z = getattr(self, name)
            if not isinstance(z, int) or isinstance(z, bool) or not 5 <= z <= 1000:
                raise ValueError(f"{o}.{name} = {z!r} must be a whole number of teeth in [5, 1000]")
        if self.z1 > self.z2:
            raise ValueError(
                f"{o}.z1 = {self.z1} exceeds z2 = {self.z2}: z1 is the pinion, the smaller wheel; "
                "swap them"
            )
        _check_range(o, "pressure_angle_deg", self.pressure_angle_deg, 10.0, 35.0)
        _check_range(o, "face_width_mm", self.face_width_mm, 0.0, 2000.0)
        _check_range(o, "ha_star", self.ha_star, 0.0, 2.0)
        _check_range(o, "c_star", self.c_star, 0.0, 1.0)
        _check_range(o, "cutter_tip_radius_coeff", self.cutter_tip_radius_coeff, -1e-12, 0.6)
        a0 = self.standard_center_distance_mm
        if self.center_distance_mm is not None:
            _check_range(
                o, "center_distance_mm", self.center_distance_mm, 0.9 * a0, 1.1 * a0,
                f"the standard centre distance is {a0:g} mm; null selects it",
            )
        rf1 = self.module_mm * (self.z1 / 2 - self.ha_star - self.c_star)
        rf2 = self.module_mm * (self.z2 / 2 - self.ha_star - self.c_star)
        _check_range(o, "bore_radius1_mm", self.bore_radius1_mm, 0.0, rf1,
                     f"the pinion root radius is {rf1:g} mm; the bore must lie inside it")
        _check_range(o, "bore_radius2_mm", self.bore_radius2_mm, 0.0, rf2,
                     f"the gear root radius is {rf2:g} mm; the bore must lie inside it")

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

    youngs_modulus_GPa: float = 206.0
    poisson: float = 0.3
    hardness_GPa: float = 7.0
    thermal_conductivity_W_mK: float = 46.0
    density_kg_m3: float = 7830.0
    specific_heat_J_kgK: float = 465.0

    def __post_init__(self) -> None:
        o = "material"
        _check_range(o, "youngs_modulus_GPa", self.youngs_modulus_GPa, 0.0, 1000.0)
        _check_range(o, "poisson", self.poisson, 0.0, 0.5)
        _check_range(o, "hardness_GPa", self.hardness_GPa, 0.0, 50.0,
                     "give the indentation hardness in GPa (HV x 0.009807)")
        _check_range(o, "thermal_conductivity_W_mK", self.thermal_conductivity_W_mK, 0.0, 500.0)
        _check_range(o, "density_kg_m3", self.density_kg_m3, 0.0, 30000.0)
        _check_range(o, "specific_heat_J_kgK", self.specific_heat_J_kgK, 0.0, 5000.0)

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
    eta0_Pa_s: float = 0.35
    alpha_m2_per_N: float = 2.5e-8
    rho0_kg_m3: float = 870.0
    temp_visc_coeff_per_K: float = 0.03
    limiting_shear_coeff: float = 0.091
    molecular_diameter_m: float = 3e-10
    vibration_time_s: float = 3e-12
    adsorption_heat_J_mol: float = 4.9e4

    def __post_init__(self) -> None:
        o = "lubricant"
        _check_range(o, "eta0_Pa_s", self.eta0_Pa_s, 0.0, 100.0, "dynamic viscosity in Pa s")
        _check_range(o, "alpha_m2_per_N", self.alpha_m2_per_N, 0.0, 1e-7,
                     "pressure-viscosity coefficient in m^2/N (1/Pa), e.g. 2.2e-8")
        _check_range(o, "rho0_kg_m3", self.rho0_kg_m3, 0.0, 3000.0)
        _check_range(o, "temp_visc_coeff_per_K", self.temp_visc_coeff_per_K, 0.0, 0.2)
        _check_range(o, "limiting_shear_coeff", self.limiting_shear_coeff, 0.0, 1.0)
        _check_range(o, "molecular_diameter_m", self.molecular_diameter_m, 0.0, 1e-8)
        _check_range(o, "vibration_time_s", self.vibration_time_s, 0.0, 1e-9)
        _check_range(o, "adsorption_heat_J_mol", self.adsorption_heat_J_mol, 0.0, 1e6)


@dataclass(frozen=True)
class Tribology:
    """Surface and wear constants (thesis Table 1 and 2.5-2.7).

    ``sigma_um`` is the composite RMS roughness; ``dry_friction_coeff`` the boundary (asperity)
    friction coefficient f_c of 2.5, not stated by the thesis: 0.1, the middle of the 0.05-0.15
    of boundary-lubricated steel on steel (Stachowiak & Batchelor, Engineering Tribology, 4th
    ed., ch. 8). ``regime = "dry"``
    selects the classical Archard law on the whole Hertz pressure with ``dry_wear_coeff``
    (2.7.5, Table 5).
    """

    sigma_um: float = 0.5
    wear_coeff: float = 5e-4
    dry_wear_coeff: float = 2e-8
    dry_friction_coeff: float = 0.1
    regime: str = "mixed"

    def __post_init__(self) -> None:
        o = "tribology"
        _check_range(o, "sigma_um", self.sigma_um, 0.0, 10.0, "composite RMS roughness in um")
        _check_range(o, "wear_coeff", self.wear_coeff, 0.0, 1.0)
        _check_range(o, "dry_wear_coeff", self.dry_wear_coeff, 0.0, 1.0)
        _check_range(o, "dry_friction_coeff", self.dry_friction_coeff, 0.0, 1.0)
        if self.regime not in ("mixed", "dry"):
            raise ValueError(f"tribology.regime = {self.regime!r} must be 'mixed' or 'dry'")


@dataclass(frozen=True)
class Operating:
    """Operating point (thesis Table 1 / Table 11): pinion speed, torque on the gear, bulk temp."""

    n1_rpm: float = 2000.0
    torque_Nm: float = 300.0
    bulk_temperature_K: float = 315.0

    def __post_init__(self) -> None:
        o = "operating"
        _check_range(o, "n1_rpm", self.n1_rpm, 0.0, 1e5, "pinion speed in r/min, positive")
        _check_range(o, "torque_Nm", self.torque_Nm, 0.0, 1e6, "gear torque in N m, positive")
        _check_range(o, "bulk_temperature_K", self.bulk_temperature_K, 200.0, 500.0,
                     "bulk temperature in kelvin")

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

    n_points: int = 401
    update_um: float = 1.0
    temperature_tol_K: float = 1e-3
    max_iterations: int = 100

    def __post_init__(self) -> None:
        o = "solver"
        if not isinstance(self.n_points, int) or not 21 <= self.n_points <= 100_001:
            raise ValueError(f"{o}.n_points = {self.n_points!r} must be a whole number in "
                             "[21, 100001]")
        _check_range(o, "update_um", self.update_um, 0.0, 100.0)
        _check_range(o, "temperature_tol_K", self.temperature_tol_K, 0.0, 10.0)
        if not isinstance(self.max_iterations, int) or self.max_iterations < 1:
            raise ValueError(f"{o}.max_iterations = {self.max_iterations!r} must be >= 1")


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
    - ``inertia*_kg_m2``: null computes solid steel discs of the face width between the bore and
      the pitch circle.
    - ``sample_rate_hz`` 40960: the thesis's test rig (4.3).
    - ``housing_mass_kg`` 20: effective mass ``m_h`` of the declared measurement chain, a rigid
      housing whose acceleration along the line of action is ``(F_d - mean F_d) / m_h``; the
      order of a small single-stage housing. It is a nuisance parameter, calibrated against
      measurements (:mod:`physics.loop`): with 20 kg the healthy thesis pair gives an RMS of
      about 70 m/s^2 where the rig of thesis Table 15 measured 1.1 m/s^2 through its real
      transfer path.
    """

    damping_ratio: float = 0.07
    half_backlash_um: float = 47.5
    eccentricity1_um: float = 7.5
    profile_error_um: float = 3.0
    inertia1_kg_m2: float | None = None
    inertia2_kg_m2: float | None = None
    sample_rate_hz: float = 40960.0
    duration_s: float = 0.1
    transient_s: float = 0.02
    step_factor: float = 0.25
    phase_bins: int = 512
    housing_mass_kg: float = 20.0

    def __post_init__(self) -> None:
        o = "dynamics"
        if not (isinstance(self.damping_ratio, int | float) and 0 <= self.damping_ratio < 1):
            raise ValueError(f"{o}.damping_ratio = {self.damping_ratio!r} must lie in [0, 1) "
                             "(fraction of critical damping; 0.03-0.17 for gear meshes)")
        if not (isinstance(self.half_backlash_um, int | float) and self.half_backlash_um >= 0
                and math.isfinite(self.half_backlash_um)):
            raise ValueError(f"{o}.half_backlash_um = {self.half_backlash_um!r} must be >= 0 "
                             "(half the normal backlash, um)")
        for name in ("eccentricity1_um", "profile_error_um"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and 0 <= v < 1000):
                raise ValueError(f"{o}.{name} = {v!r} must lie in [0, 1000) um")
        for name in ("inertia1_kg_m2", "inertia2_kg_m2"):
            if getattr(self, name) is not None:
                _check_range(o, name, getattr(self, name), 0.0, 1e3)
        _check_range(o, "sample_rate_hz", self.sample_rate_hz, 100.0, 1e7)
        _check_range(o, "housing_mass_kg", self.housing_mass_kg, 0.0, 1e5)
        _check_range(o, "duration_s", self.duration_s, 0.0, 100.0)
        if not (isinstance(self.transient_s, int | float) and 0 <= self.transient_s < 100):
            raise ValueError(f"{o}.transient_s = {self.transient_s!r} must lie in [0, 100) s")
        if not (isinstance(self.step_factor, int | float) and 0 < self.step_factor < 2.78):
            raise ValueError(
                f"{o}.step_factor = {self.step_factor!r} must lie in (0, 2.78): omega_max dt above "
                "2.78 makes fourth-order Runge-Kutta unstable; 0.25 keeps it accurate")
        if not isinstance(self.phase_bins, int) or self.phase_bins < 16:
            raise ValueError(f"{o}.phase_bins = {self.phase_bins!r} must be a whole number >= 16")


@dataclass(frozen=True)
class Scenario:
    """Everything one wear simulation needs."""

    gear: GearPair = GearPair()
    material: Material = Material()
    lubricant: Lubricant = Lubricant()
    tribology: Tribology = Tribology()
    operating: Operating = Operating()
    solver: WearSolver = WearSolver()
    dynamics: Dynamics = Dynamics()


_PARTS = {
    "gear": GearPair, "material": Material, "lubricant": Lubricant,
    "tribology": Tribology, "operating": Operating, "solver": WearSolver, "dynamics": Dynamics,
}


def _build(cls: type, values: dict[str, Any], where: str) -> Any:
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(values) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown}; allowed: {sorted(known)}")
    coerced = {}
    for f in fields(cls):
        if f.name in values:
            v = values[f.name]
            # YAML gives 2 for 2.0; keep ints for integer fields, floats elsewhere.
            if f.type in ("float", "float | None") and isinstance(v, int) and not isinstance(
                v, bool
            ):
                v = float(v)
            coerced[f.name] = v
    return cls(**coerced)


CASES_FILE = Path(__file__).resolve().parent.parent / "conf" / "cases.yaml"
_CASE_FIELDS = {
    "operating": ("n1_rpm", "torque_Nm"),
    "lubricant": ("eta0_Pa_s", "alpha_m2_per_N", "limiting_shear_coeff"),
}


def operating_cases() -> dict[int, dict[str, float]]:
    """The five operating cases of thesis Table 11, from ``conf/cases.yaml``."""
    import yaml

    with open(CASES_FILE) as fh:
        return {int(k): dict(v) for k, v in yaml.safe_load(fh).items()}


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


def scenario_from_config(cfg: Any) -> Scenario:
    """Build a :class:`Scenario` from a mapping (a Hydra/OmegaConf config or a plain dict).

    Only the groups present are read (``gear``, ``material``, ``lubricant``, ``tribology``,
    ``operating``, ``solver``); a ``case`` key (1-5), if set, overrides the operating point and
    the lubricant values that Table 11 lists.
    """
    try:
        from omegaconf import OmegaConf

        if OmegaConf.is_config(cfg):
            cfg = OmegaConf.to_container(cfg, resolve=True)
    except ImportError:  # pragma: no cover - omegaconf is a dependency
        pass
    cfg = dict(cfg)
    case = case_values(cfg["case"]) if cfg.get("case") is not None else {}
    parts: dict[str, Any] = {}
    for key, cls in _PARTS.items():
        values = dict(cfg.get(key) or {})
        values.update({k: case[k] for k in _CASE_FIELDS.get(key, ()) if k in case})
        parts[key] = _build(cls, values, key)
    return Scenario(**parts)
