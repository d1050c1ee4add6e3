"""The mixed-EHL contact state along the path of contact (thesis 2.1-2.5, coupled).

For given pair loads and flank curvatures this module combines Hertz (``physics.contact``),
kinematics, the Masjedi-Khonsari film and asperity share (``physics.lubrication``) and the flash
temperature (``physics.thermal``), and iterates the contact temperature: the inlet viscosity that
sets the film is evaluated at ``T = T0 + Delta T`` (thesis 2.5, "both viscosity and density are
updated using this temperature"), the film sets the asperity share and the heat, the heat sets
``Delta T``. The fixed point is found by damped iteration, vectorised over positions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from physics import contact, kinematics, lubrication, thermal
from physics.params import Scenario


@dataclass(frozen=True)
class ContactState:
    """Contact quantities at each mesh position; arrays of the shape of the load array.

    Where a pair carries no load (it lost contact to the wear gap) pressures, film and
    temperature rise are zero and the film ratio is ``inf``.
    """

    load_per_width: np.ndarray  # w [N/m]
    R: np.ndarray  # equivalent radius [m]
    half_width: np.ndarray  # b [m]
    p_max: np.ndarray  # [Pa]
    p_mean: np.ndarray  # [Pa]
    v1: np.ndarray  # [m/s]
    v2: np.ndarray
    v_s: np.ndarray
    v_e: np.ndarray
    h_min: np.ndarray  # [m]
    film_ratio: np.ndarray  # Lambda = h_min / sigma
    asperity_ratio: np.ndarray  # L_a / 100 (fraction of the load on asperities)
    flash_temperature: np.ndarray  # Delta T [K]
    temperature: np.ndarray  # T0 + Delta T [K]
    density: np.ndarray  # lubricant density at p_mean, T [kg/m^3]
    iterations: int


def solve_contact_state(
    scn: Scenario, load: np.ndarray, R1: np.ndarray, R2: np.ndarray
) -> ContactState:
    """Consistent contact state for pair loads ``load`` [N] and flank radii ``R1, R2`` [m]."""
    g, mat, lub, tri, op = scn.gear, scn.material, scn.lubricant, scn.tribology, scn.operating
    load = np.asarray(load, dtype=float)
    loaded = load > 0
    w = np.where(loaded, load, 1.0) / g.face_width  # placeholder 1 N where unloaded, masked below
    e_star = contact.reduced_modulus(mat, mat)
    R = contact.equivalent_radius(R1, R2)
    b = contact.hertz_half_width(w, R, e_star)
    p_max = contact.hertz_max_pressure(w, b)
    p_mean = contact.hertz_mean_pressure(w, b)
    v1, v2 = kinematics.surface_velocities(R1, R2, op.omega1, g.z1, g.z2)
    v_s, v_e = kinematics.sliding_velocity(v1, v2), kinematics.entraining_velocity(v1, v2)
    t0 = op.bulk_temperature_K
    sigma = tri.sigma_um * 1e-6
    dry = tri.regime == "dry"
    visc = {"eta0": lub.eta0_Pa_s, "alpha": lub.alpha_m2_per_N,
            "beta0": lub.temp_visc_coeff_per_K, "t0": t0}

    delta_t = np.zeros_like(R)
    for iterations in range(1, scn.solver.max_iterations + 1):  # noqa: B007 - reported below
        T = t0 + delta_t
        if dry:
            h_min, la = np.zeros_like(R), np.ones_like(R)
            tau = np.zeros_like(R)
        else:
            eta_inlet = lubrication.viscosity(0.0, T, **visc)
            grp = lubrication.dimensionless_groups(
                w, R, v_e, eta_inlet, lub.alpha_m2_per_N, 2 * e_star, mat.hardness, sigma)
            h_min = R * lubrication.min_film_thickness(
                grp["W"], grp["U"], grp["G"], grp["sigma_bar"])
            la = lubrication.asperity_load_ratio_pct(
                grp["W"], grp["U"], grp["G"], grp["V"], grp["sigma_bar"]) / 100
            p_h = (1 - la) * p_mean
            tau = np.minimum(lubrication.viscosity(p_h, T, **visc) * v_s / h_min,
                             lub.limiting_shear_coeff * p_h)
        q = thermal.heat_flux(v_s, la * p_mean, tau, tri.dry_friction_coeff)
        new = thermal.flash_temperature(
            q, b, v1, v2, mat.thermal_conductivity_W_mK, mat.diffusivity)
        new = np.where(loaded, new, 0.0)
        change = np.max(np.abs(new - delta_t), initial=0.0)
        delta_t = 0.5 * (delta_t + new)
        if change < scn.solver.temperature_tol_K:
            delta_t = new
            break
    else:
        raise RuntimeError(
            f"contact temperature did not converge in {scn.solver.max_iterations} iterations "
            f"(last change {change:.3g} K); raise solver.max_iterations")

    zero = np.zeros_like(R)
    return ContactState(
        load_per_width=np.where(loaded, w, 0.0), R=R, half_width=np.where(loaded, b, 0.0),
        p_max=np.where(loaded, p_max, 0.0), p_mean=np.where(loaded, p_mean, 0.0),
        v1=v1, v2=v2, v_s=v_s, v_e=v_e,
        h_min=np.where(loaded, h_min, zero),
        film_ratio=np.where(loaded, h_min / sigma, np.inf),
        asperity_ratio=np.where(loaded, la, 0.0),
        flash_temperature=delta_t, temperature=t0 + delta_t,
        density=lubrication.density(
            np.where(loaded, p_mean, 0.0), t0 + delta_t, lub.rho0_kg_m3, t0),
        iterations=iterations,
    )
