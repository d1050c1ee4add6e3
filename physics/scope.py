"""The operating scope of the model: a scenario outside it is refused before any work.

Each parameter class of :mod:`physics.params` checks its own fields; the limits here combine
several of them and so need the geometry (:mod:`physics.gear`). The model is elastic, so the
contact must stay below the static capacity of the flank; its sampled dynamics must resolve the
mesh harmonics that its features and order analysis read; and a record must hold enough mesh
periods to give features at all.

- Static contact capacity: ``Z_NT = 1.6`` (static life factor of case-carburised steel, ISO
  6336-2:2019, Table 2) times ``sigma_Hlim = 1500 MPa`` (case-carburised steel of quality MQ,
  ISO 6336-5:2016, Fig. 9) gives 2.4 GPa for the largest Hertz pressure of the single-tooth
  zone at the pitch point. Above it the case yields and neither Hertz nor Archard applies.
- Sampling: the sample rate must be at least 4 times the third mesh harmonic (the measured-data
  rule of ``docs/own-data.md``), i.e. ``f_s >= 12 f_mesh``.
- Record length (:func:`check_record`, for the apps that take features of the records): at
  least 10 mesh periods.
- Tooth-root strength (:data:`ROOT_STRENGTH`, checked at every block of the contact-driven
  wear, :func:`physics.gear.tooth_bending.check_root_strength`): ``Y_ST sigma_Flim``, the
  stress correction of the standard reference test gear ``Y_ST = 2.0`` (ISO 6336-3:2006, 6.4)
  times the nominal bending endurance of case-carburised steel of quality MQ ``sigma_Flim =
  500 MPa`` (core hardness >= 30 HRC; ISO 6336-5:2016, 5.3), 1000 MPa; life, size and
  roughness factors 1 (a long life of a small, ground tooth). A tooth thinned by wear until
  its root stress passes it breaks by fatigue, and the run leaves the scope.
- Worn flanks (:func:`shakedown_pressure`, checked at every profile update of the wear
  integration): a worn profile that concentrates the load until the largest Hertz pressure on
  the flank passes the elastic shakedown limit of rolling line contact deforms the surface
  plastically at every cycle; neither Hertz nor mild Archard wear applies, and the run leaves
  the scope (:class:`physics.params.OutOfScope`), as a tooth worn through does.
"""

from __future__ import annotations

import math

from physics.gear.contact import (
    equivalent_radius,
    hertz_half_width,
    hertz_max_pressure,
    reduced_modulus,
)
from physics.gear.geometry import mesh_geometry
from physics.params import Scenario

#: largest Hertz pressure of the model's scope [Pa] (see the module text)
STATIC_CONTACT_LIMIT = 1.6 * 1500e6
#: tooth-root fatigue strength ``Y_ST sigma_Flim`` [Pa] (see the module text)
ROOT_STRENGTH = 2.0 * 500e6
#: least sample rate per mesh frequency
SAMPLES_PER_MESH = 12.0
#: least mesh periods in a simulated record
MESH_PERIODS = 10


def shakedown_pressure(hardness: float) -> float:
    """Largest Hertz pressure [Pa] at which rolling line contact still shakes down elastically,
    for an indentation hardness ``hardness`` [Pa]: ``p0 = 4 k`` (Johnson, Contact Mechanics,
    1985, section 9.2: free rolling, kinematic hardening), with the shear yield stress
    ``k = Y / sqrt(3)`` (von Mises) and the yield stress ``Y = H / 3`` (Tabor, The Hardness of
    Metals, 1951), so ``4 H / (3 sqrt(3)) = 0.77 H``: 5.4 GPa for the 7 GPa case of
    :class:`physics.params.Material`."""
    return 4.0 * hardness / (3.0 * math.sqrt(3.0))


def pitch_point_pressure(scn: Scenario) -> float:
    """Hertz pressure of one pair carrying the whole nominal load at the pitch point [Pa]."""
    g = scn.gear
    geom = mesh_geometry(g)
    R1, R2 = geom.curvature_radii(0.0)
    force = scn.operating.torque_Nm / geom.rb2
    w = force / g.face_width
    R = equivalent_radius(R1, R2)
    e_star = reduced_modulus(scn.material, scn.material)
    return float(hertz_max_pressure(w, hertz_half_width(w, R, e_star)))


def mesh_frequency_hz(scn: Scenario) -> float:
    return scn.operating.n1_rpm / 60 * scn.gear.z1


def check_scope(scn: Scenario) -> Scenario:
    """Return ``scn`` if it lies in the model's scope; raise ``ValueError`` naming the value,
    the rule and the fix otherwise."""
    op, dyn = scn.operating, scn.dynamics
    p = pitch_point_pressure(scn)
    if p > STATIC_CONTACT_LIMIT:
        t_max = op.torque_Nm * (STATIC_CONTACT_LIMIT / p) ** 2
        raise ValueError(
            f"operating.torque_Nm = {op.torque_Nm:g} gives a Hertz pressure of {p / 1e9:.2f} GPa "
            f"at the pitch point, above the {STATIC_CONTACT_LIMIT / 1e9:.1f} GPa static capacity "
            f"of case-carburised steel (the model is elastic); use at most {t_max:.0f} N m or a "
            "wider face (gear.face_width_mm)")
    f_mesh = mesh_frequency_hz(scn)
    if dyn.sample_rate_hz < SAMPLES_PER_MESH * f_mesh:
        n_max = dyn.sample_rate_hz / SAMPLES_PER_MESH * 60 / scn.gear.z1
        raise ValueError(
            f"operating.n1_rpm = {op.n1_rpm:g} puts the mesh frequency at {f_mesh:.0f} Hz; the "
            f"sample rate {dyn.sample_rate_hz:g} Hz must be at least {SAMPLES_PER_MESH:g} times "
            f"that to resolve three mesh harmonics; use at most {n_max:.0f} r/min or raise "
            "dynamics.sample_rate_hz")
    return scn


def check_record(scn: Scenario) -> Scenario:
    """:func:`check_scope`, and a simulated record long enough for features (10 mesh periods);
    for the apps that take features of the records."""
    check_scope(scn)
    f_mesh, dyn = mesh_frequency_hz(scn), scn.dynamics
    periods = dyn.duration_s * f_mesh
    if periods < MESH_PERIODS:
        need = MESH_PERIODS / f_mesh
        raise ValueError(
            f"dynamics.duration_s = {dyn.duration_s:g} holds {periods:.1f} mesh periods at "
            f"n1_rpm = {scn.operating.n1_rpm:g}; the features need at least {MESH_PERIODS}: set "
            f"dynamics.duration_s to {math.ceil(need * 100) / 100:g} or more")
    return scn
