"""The mixed-EHL contact state along the path of contact (thesis 2.1-2.5, coupled).

For given pair loads, flank curvatures and velocities this module combines Hertz
(``physics.contact``), the film and asperity load share, and the flash temperature
(``physics.thermal``). The film and share come from the numerical mixed-EHL line-contact solver
(``tribology.asperity_model = "solver"``, the default: :mod:`physics.tribology.mixed_ehl`, read
from its precomputed table :mod:`physics.tribology.asperity_table`) or from the
Masjedi-Khonsari regressions the thesis prints (``"regression"``: :mod:`physics.tribology.
lubrication`). The film forms in the inlet, at the bulk temperature: both are isothermal
(the regressions are fits to isothermal solutions, the solver runs at the inlet temperature),
and the flash temperature exists only inside the band. Inside
the band the viscosity and density follow the contact temperature ``T = T0 + Delta T`` (thesis
2.5): the film's shear stress, and with it the heat and ``Delta T``, depend on ``eta(p, T)``. That
fixed point is found by damped iteration, vectorised over positions. (The thesis evaluates the
inlet viscosity at the flash temperature too; see ``docs/reproduction.md``.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from physics.gear import contact, kinematics
from physics.params import Scenario
from physics.tribology import asperity_table, lubrication, thermal


@dataclass(frozen=True)
class ContactState:
    """Contact quantities at each mesh position; arrays of the shape of the load array.

    Where a pair carries no load (it lost contact to the wear gap) pressures, film and
    temperature rise are zero and the film ratio is ``inf``. ``h_central`` and ``p_peak`` (the
    largest fluid plus asperity pressure, the outlet pressure spike included) come from the
    solver; they are NaN with the regression (which gives neither) and zero in the dry regime.
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
    h_central: np.ndarray  # film at the Hertz centre [m]
    p_peak: np.ndarray  # peak of fluid + asperity pressure [Pa]
    film_ratio: np.ndarray  # Lambda = h_min / sigma
    asperity_ratio: np.ndarray  # L_a / 100 (fraction of the load on asperities)
    flash_temperature: np.ndarray  # Delta T [K]
    temperature: np.ndarray  # T0 + Delta T [K]
    density: np.ndarray  # lubricant density at p_mean, T [kg/m^3]
    iterations: int


def solve_contact_state(
    scn: Scenario, load: np.ndarray, R: np.ndarray, v1: np.ndarray, v2: np.ndarray,
) -> ContactState:
    """Consistent contact state for pair loads ``load`` [N].

    ``R`` is the equivalent radius [m] of the Hertz contact the film sees (of the unworn
    involutes, or of the worn band's peak pressure: :mod:`physics.tribology.wear`), ``v1, v2``
    the rolling velocities of the flanks [m/s] (set by the unworn kinematics).
    """
    g, mat, lub, tri, op = scn.gear, scn.material, scn.lubricant, scn.tribology, scn.operating
    load = np.asarray(load, dtype=float)
    loaded = load > 0
    w = np.where(loaded, load, 1.0) / g.face_width  # placeholder 1 N where unloaded, masked below
    e_star = contact.reduced_modulus(mat, mat)
    R = np.asarray(R, dtype=float)
    b = contact.hertz_half_width(w, R, e_star)
    p_max = contact.hertz_max_pressure(w, b)
    p_mean = contact.hertz_mean_pressure(w, b)
    v_s, v_e = kinematics.sliding_velocity(v1, v2), kinematics.entraining_velocity(v1, v2)
    t0 = op.bulk_temperature_K
    sigma = tri.sigma_um * 1e-6
    dry = tri.regime == "dry"
    visc = {"eta0": lub.eta0_Pa_s, "alpha": lub.alpha_m2_per_N,
            "beta0": lub.temp_visc_coeff_per_K, "t0": t0}

    if dry:
        h_min, la = np.zeros_like(R), np.ones_like(R)
        h_c, p_peak = np.zeros_like(R), np.zeros_like(R)
    else:  # isothermal inlet at the bulk temperature
        grp = lubrication.dimensionless_groups(
            w, R, v_e, lub.eta0_Pa_s, lub.alpha_m2_per_N, 2 * e_star, mat.hardness, sigma)
        if tri.asperity_model == "regression":
            h_min = R * lubrication.min_film_thickness(grp["W"], grp["U"], grp["G"],
                                                       grp["sigma_bar"])
            la = lubrication.asperity_load_ratio_pct(
                grp["W"], grp["U"], grp["G"], grp["V"], grp["sigma_bar"]) / 100
            h_c, p_peak = np.full_like(R, np.nan), np.full_like(R, np.nan)
        else:
            ehl = asperity_table.lookup(grp["W"], grp["U"], grp["sigma_bar"],
                                        lub.alpha_m2_per_N, lub.eta0_Pa_s, 2 * e_star)
            la, h_min, h_c = ehl.share, ehl.film_ratio_min * sigma, ehl.film_ratio_central * sigma
            p_peak = ehl.peak_ratio * p_max
    p_h = (1 - la) * p_mean

    def rise(delta_t: np.ndarray) -> np.ndarray:
        """Flash temperature produced by the heat of the contact at temperature T0 + delta_t."""
        if dry:
            tau = np.zeros_like(R)
        else:
            eta = lubrication.viscosity(p_h, t0 + delta_t, **visc)
            # a nominal film <= 0 (mean planes through each other): the shear is limiting
            newtonian = np.where(h_min > 0, eta * v_s / np.where(h_min > 0, h_min, 1.0), np.inf)
            tau = np.minimum(newtonian, lub.limiting_shear_coeff * p_h)
        q = thermal.heat_flux(v_s, la * p_mean, tau, tri.dry_friction_coeff)
        dt = thermal.flash_temperature(q, b, v1, v2, mat.thermal_conductivity_W_mK,
                                       mat.diffusivity)
        return np.where(loaded, dt, 0.0)

    delta_t, iterations = _fixed_point(rise, np.zeros_like(R), scn.solver.temperature_tol_K,
                                       scn.solver.max_iterations)
    zero = np.zeros_like(R)
    return ContactState(
        load_per_width=np.where(loaded, w, 0.0), R=R, half_width=np.where(loaded, b, 0.0),
        p_max=np.where(loaded, p_max, 0.0), p_mean=np.where(loaded, p_mean, 0.0),
        v1=v1, v2=v2, v_s=v_s, v_e=v_e,
        h_min=np.where(loaded, h_min, zero),
        h_central=np.where(loaded, h_c, zero), p_peak=np.where(loaded, p_peak, zero),
        film_ratio=np.where(loaded, h_min / sigma, np.inf),
        asperity_ratio=np.where(loaded, la, 0.0),
        flash_temperature=delta_t, temperature=t0 + delta_t,
        density=lubrication.density(
            np.where(loaded, p_mean, 0.0), t0 + delta_t, lub.rho0_kg_m3, t0),
        iterations=iterations,
    )


def _fixed_point(f, lo: np.ndarray, tol: float, max_iter: int) -> tuple[np.ndarray, int]:
    """Solve ``x = f(x)`` elementwise for a non-increasing ``f`` with ``f(lo) >= lo``.

    More temperature thins the film's shear stress and so the heat: ``f`` falls with ``x`` and
    ``g(x) = f(x) - x`` changes sign in ``[lo, f(lo)]``. Regula falsi with the Illinois
    modification keeps that bracket (bisection's safety) and converges superlinearly; it runs
    vectorised over positions until every residual is below ``tol``.
    """
    a = lo
    ga = f(a) - a  # >= 0
    b = a + ga
    gb = f(b) - b  # <= 0
    last = np.zeros(a.shape, dtype=np.int8)  # +1: b was replaced last step, -1: a was
    for iterations in range(1, max_iter + 1):  # noqa: B007 - returned
        done = (np.abs(ga) < tol) | (np.abs(gb) < tol) | (b - a < tol)
        if np.all(done):
            break
        span = gb - ga
        c = np.where(span < 0, b - gb * (b - a) / np.where(span < 0, span, -1.0), a)
        gc = f(c) - c
        to_b = gc <= 0  # the root lies in [a, c]
        ga, gb = (np.where(to_b, np.where(last == 1, 0.5 * ga, ga), gc),
                  np.where(to_b, gc, np.where(last == -1, 0.5 * gb, gb)))
        a, b = np.where(to_b, a, c), np.where(to_b, c, b)
        last = np.where(to_b, 1, -1).astype(np.int8)
    else:
        raise RuntimeError(
            f"contact temperature did not converge in {max_iter} iterations (largest bracket "
            f"{np.max(b - a):.3g} K); raise solver.max_iterations")
    return np.where(np.abs(ga) <= np.abs(gb), a, b), iterations
