"""Flash temperature of the sliding contact (thesis 2.5).

Heat generated in the band ``2b``: asperity friction on the asperity pressure plus shear of the
film on the fluid pressure (thesis 2.5),

    q = f_c v_s p_a + tau_film v_s,   tau_film = min(eta(p_h, T) v_s / h, Lambda_lim p_h)

The thesis takes the film at its limiting shear stress ``Lambda_lim p_h`` throughout; we keep the
Newtonian stress where it is lower (near the pitch point), which changes nothing where the film is
at its limit (Bair & Winer, ASME J. Lubr. Technol. 101 (1979) 251-257).

Each surface is a half-space passing under a uniform band source of half-width b at speed v. For
Peclet numbers ``Pe = v b / (2 kappa)`` above about 5, the maximum surface temperature rise if the
body took all the heat is ``2 q b / (K sqrt(pi Pe))`` (Jaeger 1942; Tian & Kennedy, ASME J.
Tribol. 116 (1994) 167-174). Dividing the heat so that both surfaces reach the same temperature
(Blok's postulate) gives

    Delta T = 2 b q / ( sqrt(pi) (K1 sqrt(Pe1) + K2 sqrt(Pe2)) )

which is the thesis's formula with its ``K_i / sqrt(k_i v_i)`` read as ``K_i sqrt(Pe_i)`` (the
printed group is not a temperature). At lower Pe (pinion root at low speed) the band-source
formula overestimates the rise: the heat also spreads sideways.
"""

from __future__ import annotations

import numpy as np


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
    root = np.sqrt(peclet(v1, b, diffusivity)) + np.sqrt(peclet(v2, b, diffusivity))
    return 2 * np.asarray(b) * np.asarray(q) / (np.sqrt(np.pi) * conductivity * root)
