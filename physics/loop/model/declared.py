"""The declared model's parameters: the nuisance the loop calibrates before it considers any
effect, their bounds and declared values, and the declared model built with them.

- :data:`NUISANCE`: the scenario's damping ratio, pinion run-out and profile error, and the
  housing's effective mass ``m_h`` of the acceleration chain;
- :data:`MODEL_FORM`: the model's own form uncertainty
  (:func:`physics.dynamics.model_form.with_model_form`) and the pinion run-out's mesh
  modulation (:func:`physics.dynamics.model_form.with_modulation`);
- :data:`SUPPORT`, :data:`MOUNT`: the acceleration chain's declared modes.

Each bounded parameter has unit coordinates (:func:`to_unit`, :func:`from_unit`: log-scaled
where its range spans decades), in which the loop's searches move.
"""

from __future__ import annotations

import dataclasses
import math

from physics.dataset.generation import NuisanceRanges
from physics.dynamics.model import PairModel
from physics.dynamics.model_form import with_model_form
from physics.gear.accuracy import profile_form_tolerance_um, runout_tolerance_um
from physics.gear.geometry import mesh_geometry
from physics.params import GearPair, Scenario

#: declared nuisance parameters of the scenario: name, bounds, log-scaled
NUISANCE = {"damping_ratio": (0.01, 0.3, True), "eccentricity1_um": (0.2, 60.0, True),
            "profile_error_um": (0.1, 30.0, True), "housing_mass_kg": (0.01, 1e5, True)}
#: the declared model's own form uncertainty
#: (:func:`~physics.dynamics.model_form.with_model_form`): name, bounds, log-scaled, the neutral
#: value (None: the scenario's). Calibrated with the nuisance above, before any effect is
#: considered; at the neutral values the model is the declared one.
MODEL_FORM = {"stiffness_factor": (0.5, 2.0, True, 1.0),
              "resonance_factor": (0.5, 2.0, True, 1.0),
              "double_contact_factor": (0.6, 1.6, True, 1.0),
              "half_backlash_um": (0.5, 200.0, True, None),
              "mesh_modulation": (0.0, 0.2, False, 0.0),
              "modulation_phase_rad": (0.0, 2 * math.pi, False, 0.0)}
#: the declared bearing-support mode of the acceleration chain
#: (:func:`physics.signals.measurement.support_path`): name, bounds, log-scaled. Calibrated with
#: ``m_h`` where the scenario declares one (``dynamics.support_hz`` > 0), around that value.
SUPPORT = {"support_hz": (200.0, 20000.0, True), "support_damping": (0.005, 0.3, True)}
#: the declared mode of the housing on its mounting
#: (:func:`physics.signals.measurement.housing_mount`) where the scenario states one
#: (``dynamics.mount_hz`` > 0): held at the stated values, not calibrated. Its own lines, the
#: shaft orders, carry little, and above it the mode tilts the lowest mesh harmonics: freed,
#: on records of a housing mounted at 55 Hz stated as 90 Hz, the fit takes it to 330 Hz
MOUNT = {"mount_hz": (5.0, 1000.0, True), "mount_damping": (0.02, 0.5, True)}
#: the acceleration chain's modes, each by the frequency that declares it
CHAIN_MODES = {"support_hz": SUPPORT, "mount_hz": MOUNT}
CHAIN = SUPPORT | MOUNT
#: the torque of records whose manifest leaves it unknown: the configured torque
#: (``operating.torque_Nm``) times ``torque_factor``, calibrated with the nuisance under a wide
#: prior (a factor of 5 either way, explored over the whole range); the worn teeth stay those of
#: the configured torque
TORQUE = {"torque_factor": (0.2, 5.0, True)}
#: the pinion speed of a feature table whose ``operating.yaml`` leaves it unknown: the
#: configured speed (``operating.n1_rpm``) times ``speed_factor``, two octaves either way (the
#: thesis's operating cases span 1000-3000 r/min, a factor 3; Table 11); the worn teeth stay
#: those of the configured speed
SPEED = {"speed_factor": (0.25, 4.0, True)}
#: bounds of every nuisance parameter of the declared model (the calibrated ones' search range;
#: the stated mounting's, the range its stated values must lie in)
BOUNDS = NUISANCE | CHAIN | {n: b[:3] for n, b in MODEL_FORM.items()} | TORQUE | SPEED
#: the nuisance parameters the dynamics see (``m_h`` acts on the measurement chain); the model
#: form's only with ``loop.model_form``
SCENARIO_DYNAMIC = ("damping_ratio", "eccentricity1_um", "profile_error_um")
DYNAMIC_NUISANCE = (*SCENARIO_DYNAMIC, *MODEL_FORM)
#: the once-per-revolution mesh modulation that the declared pinion run-out makes in every real
#: gearbox (:func:`~physics.dynamics.model_form.with_modulation`), calibrated with or without
#: ``loop.model_form``: the thesis's run-out on the line of action alone is dynamically inert, and
#: a mesh without it left every independent DTE bundle's pinion sidebands to ``torque_ripple``, the
#: clean ones too
RUNOUT_MODULATION = ("mesh_modulation", "modulation_phase_rad")
#: the parameters a Sobol sample explores before least squares (their residual surface has
#: several basins): the dynamic ones and the support mode's (a basin per mesh harmonic it can
#: sit on)
EXPLORED = (*DYNAMIC_NUISANCE, *SUPPORT, *TORQUE)


#: the ISO 1328 accuracy grades of industrial spur gearboxes, from ground to hobbed unground
#: teeth: the span the datasets draw the pinion's run-out and profile error from
#: (:class:`physics.dataset.generation.NuisanceRanges`)
ACCURACY_GRADES = (4, 9)


def physical_nuisance(scn: Scenario) -> dict[str, tuple[float, float, bool]]:
    """The nuisance's search ranges (name: low, high, log-scaled) for the scenario's pair,
    each from its source:

    - ``damping_ratio``: the datasets' range (:class:`~physics.dataset.generation.
      NuisanceRanges`: 0.03-0.17 of critical, the span Kasuba & Evans, ASME J. Mech. Des. 103
      (1981) 398, report for spur meshes);
    - ``eccentricity1_um``: half the pinion's radial run-out tolerance ``F_r`` (ISO 1328-2:1997,
      annex B) and ``profile_error_um``: half its profile form tolerance ``f_f_alpha`` (ISO
      1328-1:1995), each of grades :data:`ACCURACY_GRADES` for the pinion's module and
      reference diameter (:mod:`physics.gear.accuracy`), as the datasets draw them;
    - ``housing_mass_kg``: the datasets' 10-40 kg of small single-stage housings, for the
      thesis pair's centre distance, times the cube of the pair's centre distance over it:
      geometrically similar casings of one material weigh as their volume, the cube of their
      size.
    """
    ranges = NuisanceRanges()
    g, thesis = scn.gear, GearPair()
    d1 = g.module_mm * g.z1
    runout = [0.5 * runout_tolerance_um(q, g.module_mm, d1) for q in ACCURACY_GRADES]
    form = [0.5 * profile_form_tolerance_um(q, g.module_mm, d1) for q in ACCURACY_GRADES]
    size = (mesh_geometry(g).center_distance / mesh_geometry(thesis).center_distance) ** 3
    mass = [m * size for m in ranges.housing_mass_kg]
    return {"damping_ratio": (*ranges.damping_ratio, True), "eccentricity1_um": (*runout, True),
            "profile_error_um": (*form, True), "housing_mass_kg": (*mass, True)}


def at_bounds(values: dict, ranges: dict, share: float = 0.01) -> dict[str, tuple[str, float]]:
    """The parameters of ``values`` within ``share`` of their (log) range of a bound of
    ``ranges`` (name: low, high, log-scaled): which bound (``lower``, ``upper``) and its value.
    A fit that ends there wanted to go further: the range, not the data, set its value."""
    out = {}
    for n, (lo, hi, lg) in ranges.items():
        if n in values:
            u = to_unit(values[n], lo, hi, lg)
            if u <= share or u >= 1 - share:
                out[n] = ("lower", lo) if u <= share else ("upper", hi)
    return out


def with_torque(m: PairModel, nuisance: dict) -> PairModel:
    """``m`` with its static mesh force times an unknown torque's calibrated ``torque_factor``
    (:data:`TORQUE`; ``m`` itself where ``nuisance`` has none); its worn teeth stay those of the
    configured torque."""
    f = nuisance.get("torque_factor")
    return m if f is None else dataclasses.replace(m, static_force=m.static_force * f)


def with_speed(m: PairModel, nuisance: dict) -> PairModel:
    """``m`` run at its speed times an unknown speed's calibrated ``speed_factor``
    (:data:`SPEED`; ``m`` itself where ``nuisance`` has none): every rate of the kinematics
    (shafts, mesh, rolling, a torque ripple's order) scales with it, while the stiffness and
    gap tables, given per mesh phase, and the worn teeth stay those of the configured speed."""
    f = nuisance.get("speed_factor")
    if f is None:
        return m
    return dataclasses.replace(m, omega1=m.omega1 * f, omega_mesh=m.omega_mesh * f,
                               roll_speed=m.roll_speed * f, omega2=m.omega2 * f,
                               omega_ripple=m.omega_ripple * f)


def declared_nuisance(scn: Scenario) -> dict[str, float]:
    """The nuisance parameters' configured values (the calibration's starting point, with
    :func:`declared_model_form`)."""
    return {n: float(getattr(scn.dynamics, n)) for n in NUISANCE}


def declared_model_form(scn: Scenario) -> dict[str, float]:
    """The model-form parameters at their neutral values (the declared model itself)."""
    return {n: float(getattr(scn.dynamics, n) if b[3] is None else b[3])
            for n, b in MODEL_FORM.items()}


def declared_modes(scn: Scenario) -> dict[str, float]:
    """The acceleration chain's declared modes (:data:`CHAIN_MODES`: the bearing support's,
    none for a rigid support, ``dynamics.support_hz`` = 0; the mounting's, none for a free
    housing, ``dynamics.mount_hz`` = 0); a declared mode outside the loop's bounds is
    refused."""
    dyn = scn.dynamics
    out = {}
    for key, mode in CHAIN_MODES.items():
        if getattr(dyn, key) == 0:
            continue
        for n, (lo, hi, _) in mode.items():
            if not lo <= getattr(dyn, n) <= hi:
                raise ValueError(f"dynamics.{n} = {getattr(dyn, n)!r} must lie in [{lo:g}, "
                                 f"{hi:g}] for the loop to use it; state the mode inside that "
                                 f"range or set dynamics.{key}=0 (no such mode)")
        out |= {n: float(getattr(dyn, n)) for n in mode}
    return out


def modes_of(nuisance: dict) -> dict[str, float]:
    """The chain modes' entries of ``nuisance`` (none: a rigid support and a free housing), as
    :func:`physics.signals.measurement.declared_chain` takes them."""
    return {n: nuisance[n] for n in CHAIN if n in nuisance}


def completed(nuisance: dict, scn: Scenario) -> dict:
    """``nuisance`` with the model-form parameters it lacks at their neutral values."""
    return declared_model_form(scn) | nuisance


def to_unit(p: float, lo: float, hi: float, is_log: bool) -> float:
    return (math.log(p / lo) / math.log(hi / lo)) if is_log else (p - lo) / (hi - lo)


def from_unit(u: float, lo: float, hi: float, is_log: bool) -> float:
    return lo * (hi / lo) ** u if is_log else lo + u * (hi - lo)


def with_nuisance(m: PairModel, nuisance: dict, base_ratio: float) -> PairModel:
    """The declared model with calibrated damping and error amplitudes, and the model-form
    parameters of :func:`~physics.dynamics.model_form.with_model_form` (those ``nuisance`` lacks
    stay neutral). The mesh modulation (:func:`~physics.dynamics.model_form.with_modulation`) is
    not applied here: it goes after any effect."""
    m = dataclasses.replace(
        m, damping=m.damping * nuisance["damping_ratio"] / base_ratio,
        long_error=nuisance["eccentricity1_um"] * 1e-6 * math.sin(m.geometry.alpha_w),
        short_error=nuisance["profile_error_um"] * 1e-6)
    return with_model_form(m, nuisance)
