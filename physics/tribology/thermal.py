"""Flash temperature of the sliding contact (thesis 2.5).

Heat generated in the band ``2b``: asperity friction on the asperity pressure plus shear of the
film on the fluid pressure (thesis 2.5),

    q = f_c v_s p_a + tau_film v_s,   tau_film = min(eta(p_h, T) v_s / h, Lambda_lim p_h)

The thesis takes the film at its limiting shear stress ``Lambda_lim p_h`` throughout; we keep the
Newtonian stress where it is lower (near the pitch point), which changes nothing where the film is
at its limit (Bair & Winer, ASME J. Lubr. Technol. 101 (1979) 251-257).

Each surface is a half-space passing under a uniform band heat source of half-width b at speed v.
Jaeger's steady solution (Proc. R. Soc. N.S.W. 76 (1942) 203-224) for the surface temperature at
``xi = x / b`` is

    T(xi) = (2 kappa q / (pi K v)) [F(Pe (xi + 1)) - F(Pe (xi - 1))],
    F(U) = int_0^U exp(-u) K0(|u|) du,     Pe = v b / (2 kappa)

We evaluate it exactly for every Peclet number (F by quadrature once, then interpolation) and take
its maximum over the band; for ``Pe > 5`` it tends to ``2 q b / (K sqrt(pi Pe))``, the form of
Tian & Kennedy (ASME J. Tribol. 116 (1994) 167-174). The heat is divided between the surfaces so
that both reach the same maximum temperature (Blok's postulate): ``1/dT = 1/dT_1 + 1/dT_2`` with
``dT_i`` the rise body i would take with all the heat. The thesis's printed formula,
``2 b q / (sqrt(pi) (K1/sqrt(k1 v1) + K2/sqrt(k2 v2)))``, is not dimensionally a temperature; its
intended high-Peclet form is this one with ``K_i sqrt(Pe_i)`` in the denominator.
"""

from __future__ import annotations

from functools import lru_cache
from itertools import pairwise

import numpy as np
from scipy.integrate import quad
from scipy.special import k0e

_XI = -np.cos(np.linspace(0.0, np.pi, 201))  # across the band, dense at the edges


@lru_cache(maxsize=1)
def _f_table() -> tuple[np.ndarray, np.ndarray]:
    """Knots and values of ``F(U) = int_0^U exp(-u) K0(|u|) du`` for |U| <= 2e4."""
    pos = np.concatenate([[0.0], np.geomspace(1e-8, 2e4, 1200)])

    def integrand(u: float, sign: float) -> float:
        # exp(-u) K0(|u|) = k0e(|u|) exp(-u - |u|): decays for u > 0, ~ 1/sqrt(|u|) for u < 0
        return k0e(u) * (np.exp(-2 * u) if sign > 0 else 1.0)

    values = {}
    for sign in (1.0, -1.0):
        pieces = [quad(integrand, a, b, args=(sign,), limit=200)[0]
                  for a, b in pairwise(pos)]
        values[sign] = np.concatenate([[0.0], np.cumsum(pieces)])
    knots = np.concatenate([-pos[:0:-1], pos])
    table = np.concatenate([-values[-1.0][:0:-1], values[1.0]])
    return knots, table


def _exact_max_rise(pe: np.ndarray) -> np.ndarray:
    """Jaeger's band-source rise maximised over the band (module docstring), for ``Pe > 0``."""
    knots, table = _f_table()
    p = pe[..., None]
    rise = np.interp(p * (_XI + 1), knots, table) - np.interp(p * (_XI - 1), knots, table)
    return rise.max(axis=-1) / (np.pi * pe)  # 2 kappa / (v b) = 1 / Pe


#: Peclet numbers of the tabulated maximum rise (log-spaced; 150 per decade)
_PE_TABLE = np.geomspace(1e-6, 1e4, 1501)


@lru_cache(maxsize=1)
def _max_rise_table() -> np.ndarray:
    """ln theta_max at ``ln _PE_TABLE``: the maximum is a smooth function of Pe alone, so the
    wear loop interpolates it instead of scanning the band at every grid point."""
    return np.log(_exact_max_rise(_PE_TABLE))


def band_source_max_rise(pe: np.ndarray) -> np.ndarray:
    """Dimensionless maximum surface rise ``theta = dT_max K / (q b)`` of a moving band source.

    Jaeger's exact solution (module docstring), maximised over the band, for ``0 < Pe <= 1e4``:
    interpolated in log-log between 150 knots per decade (within 2e-5 of the direct evaluation;
    tests/tribology/test_lubrication_thermal.py), evaluated directly below ``Pe = 1e-6``.
    """
    pe = np.asarray(pe, dtype=float)
    if np.any(pe <= 0) or np.any(pe > 1e4):
        raise ValueError("Peclet numbers must lie in (0, 1e4] for the band-source solution")
    out = np.exp(np.interp(np.log(pe), np.log(_PE_TABLE), _max_rise_table()))
    low = pe < _PE_TABLE[0]
    if np.any(low):
        out[low] = _exact_max_rise(pe[low])
    return out


def peclet(v: np.ndarray, b: np.ndarray, diffusivity: float) -> np.ndarray:
    """``Pe = v b / (2 kappa)`` with b the contact half-width."""
    return np.asarray(v) * np.asarray(b) / (2 * diffusivity)


def heat_flux(v_s: np.ndarray, p_a: np.ndarray, tau_film: np.ndarray, f_c: float) -> np.ndarray:
    """Frictional heat flux into the band [W/m^2]: ``f_c v_s p_a + tau_film v_s``."""
    return np.asarray(v_s) * (f_c * np.asarray(p_a) + np.asarray(tau_film))


def flash_temperature(
    q: np.ndarray, b: np.ndarray, v1: np.ndarray, v2: np.ndarray,
    conductivity: float, diffusivity: float,
) -> np.ndarray:
    """Maximum flash temperature rise [K] of two steel surfaces sharing the heat ``q``."""
    q, b = np.asarray(q, dtype=float), np.asarray(b, dtype=float)
    theta1 = band_source_max_rise(peclet(v1, b, diffusivity))
    theta2 = band_source_max_rise(peclet(v2, b, diffusivity))
    # body i alone: dT_i = q b theta_i / K; equal maxima: 1/dT = 1/dT_1 + 1/dT_2
    return q * b / conductivity * theta1 * theta2 / (theta1 + theta2)
