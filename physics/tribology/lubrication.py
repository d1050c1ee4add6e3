"""Lubricant rheology and the Masjedi-Khonsari mixed-EHL regressions (thesis 2.4).

The full rough-surface EHL problem (modified Reynolds equation with flow factors, film thickness
with elastic deflection, load balance with a Greenwood-Williamson asperity model) is replaced, as
in the thesis, by the regression formulas that Masjedi & Khonsari fitted to its solutions
(M. Masjedi, M.M. Khonsari, "Film thickness and asperity load formulas for line-contact
elastohydrodynamic lubrication with provision for surface roughness", ASME J. Tribol. 134 (2012)
011503). Their dimensionless groups, in Hamrock's convention, are

    W = w / (E' R)          load, w per unit face width [N/m]
    U = eta0 u_e / (E' R)   speed, u_e the entraining velocity
    G = alpha E'            material
    V = H / E'              hardness of the softer surface
    sigma_bar = sigma / R   composite RMS roughness

with ``2/E' = (1-v1^2)/E1 + (1-v2^2)/E2``, i.e. ``E' = 2 E*``.
"""

from __future__ import annotations

import numpy as np

ROELANDS_ETA_INF = 6.31e-5  # Pa s: ln(eta_inf) = -9.67 (Roelands 1966; Hamrock 1994, ch. 4)
ROELANDS_P0 = 1.96e8  # Pa, = 1/5.1e-9 (same sources)
ROELANDS_T_INF = 138.0  # K


def roelands_exponents(eta0: float, alpha: float, beta0: float, t0: float) -> tuple[float, float]:
    """Roelands pressure index Z and temperature index S0 from alpha and beta0.

    ``Z = alpha / (5.1e-9 (ln eta0 + 9.67))`` and ``S0 = beta0 (T0 - 138) / (ln eta0 + 9.67)``
    (Hamrock, Fundamentals of Fluid Film Lubrication, 1994, eqs. 4.9 and 4.12), so that the
    Roelands law has the pressure-viscosity coefficient ``alpha`` at p = 0 and the viscosity-
    temperature coefficient ``beta0`` at T0.
    """
    ln_ratio = np.log(eta0 / ROELANDS_ETA_INF)
    return alpha * ROELANDS_P0 / ln_ratio, beta0 * (t0 - ROELANDS_T_INF) / ln_ratio


def viscosity(
    p: np.ndarray, T: np.ndarray, eta0: float, alpha: float, beta0: float, t0: float
) -> np.ndarray:
    """Roelands viscosity-pressure-temperature law [Pa s] (thesis 2.4).

    ``eta = eta0 exp{ (ln eta0 + 9.67) [ (1 + p/p0)^Z ((T - 138)/(T0 - 138))^(-S0) - 1 ] }``
    with ``p0 = 1.96e8 Pa``. The thesis writes the isothermal form with a fixed Z = 0.68 and
    ``ln(eta0/1e-9)``; we take Z and S0 from the lubricant's alpha and beta0 (see
    :func:`roelands_exponents` and ``docs/reproduction.md``).
    """
    z, s0 = roelands_exponents(eta0, alpha, beta0, t0)
    ln_ratio = np.log(eta0 / ROELANDS_ETA_INF)
    p, T = np.asarray(p, dtype=float), np.asarray(T, dtype=float)
    thermal = ((T - ROELANDS_T_INF) / (t0 - ROELANDS_T_INF)) ** (-s0)
    return eta0 * np.exp(ln_ratio * ((1 + p / ROELANDS_P0) ** z * thermal - 1))


def density(p: np.ndarray, T: np.ndarray, rho0: float, t0: float) -> np.ndarray:
    """Dowson-Higginson density with thermal expansion [kg/m^3], p in Pa, T in K.

    ``rho = rho0 (1 + 0.6e-9 p / (1 + 1.7e-9 p) - 6.5e-4 (T - T0))``: the pressure term of
    Dowson & Higginson (Elastohydrodynamic Lubrication, 1966; the thesis prints it with p in GPa)
    and the volumetric expansion of mineral oil used in thermal EHL (e.g. Yang & Wen, ASME J.
    Tribol. 112 (1990) 631-636).
    """
    p, T = np.asarray(p, dtype=float), np.asarray(T, dtype=float)
    return rho0 * (1 + 0.6e-9 * p / (1 + 1.7e-9 * p) - 6.5e-4 * (T - t0))


def dimensionless_groups(
    w: np.ndarray, R: np.ndarray, u_e: np.ndarray, eta0: np.ndarray, alpha: float,
    e_prime: float, hardness: float, sigma: float,
) -> dict[str, np.ndarray]:
    """The Masjedi-Khonsari groups W, U, G, V and sigma_bar (module docstring)."""
    R = np.asarray(R, dtype=float)
    return {
        "W": np.asarray(w) / (e_prime * R),
        "U": np.asarray(eta0) * np.asarray(u_e) / (e_prime * R),
        "G": np.full_like(R, alpha * e_prime),
        "V": np.full_like(R, hardness / e_prime),
        "sigma_bar": sigma / R,
    }


def min_film_thickness(W, U, G, sigma_bar) -> np.ndarray:
    """``H_min = h_min / R = 1.652 W^-0.077 U^0.716 G^0.695 (1 + 0.026 sigma_bar)^-0.312``.

    Thesis 2.4 (Masjedi & Khonsari 2012). The thesis prints the roughness term as
    ``(1 + 0.026 sigma_bar / R)``; sigma_bar is already ``sigma / R``, so we read it as
    ``(1 + 0.026 sigma_bar)``.
    """
    return 1.652 * W**-0.077 * U**0.716 * G**0.695 * (1 + 0.026 * sigma_bar) ** -0.312


def asperity_load_ratio_pct(W, U, G, V, sigma_bar) -> np.ndarray:
    """Share of the load carried by asperities, in percent (thesis 2.4, Masjedi & Khonsari 2012).

    ``L_a = 0.005 W^-0.408 U^-0.088 G^-0.103 V^0.485 ln(1 + 4470 sigma_bar)``, capped at 100 %.
    """
    la = 0.005 * W**-0.408 * U**-0.088 * G**-0.103 * V**0.485 * np.log1p(4470 * sigma_bar)
    return np.minimum(la, 100.0)
