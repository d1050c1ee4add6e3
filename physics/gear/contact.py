"""Hertz line contact of the two flanks (thesis 2.1, in the standard convention).

The thesis writes ``b_H = sqrt(8 W R / (pi E_z))`` with ``1/E_z = (1-v1^2)/E1 + (1-v2^2)/E2``
and a mean pressure ``4 p_max / pi``. Both are off: with that ``E_z`` (Johnson's ``E*``) the
half-width is ``sqrt(4 W R / (pi E*))`` (Johnson, Contact Mechanics, 1985, eq. 4.43), the thesis
form being ``sqrt(2)`` wider, and the mean pressure of the elliptic Hertz distribution is
``pi p_max / 4``. We use Johnson's forms; ``docs/reproduction.md`` records the difference.
"""

from __future__ import annotations

import numpy as np

from physics.params import Material


def reduced_modulus(m1: Material, m2: Material) -> float:
    """Contact modulus ``E*`` with ``1/E* = (1-v1^2)/E1 + (1-v2^2)/E2`` [Pa] (Johnson eq. 4.22).

    Hamrock's ``E'`` (used in the Masjedi-Khonsari groups) is ``2 E*``.
    """
    return 1.0 / ((1 - m1.poisson**2) / m1.E + (1 - m2.poisson**2) / m2.E)


def equivalent_radius(R1: np.ndarray, R2: np.ndarray) -> np.ndarray:
    """``1/R = 1/R1 + 1/R2`` [m] (thesis 2.1)."""
    R1, R2 = np.asarray(R1), np.asarray(R2)
    return R1 * R2 / (R1 + R2)


def hertz_half_width(w: np.ndarray, R: np.ndarray, e_star: float) -> np.ndarray:
    """Half-width ``b = sqrt(4 w R / (pi E*))`` [m] for load per unit length ``w`` [N/m]."""
    return np.sqrt(4 * np.asarray(w) * np.asarray(R) / (np.pi * e_star))


def hertz_max_pressure(w: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Peak Hertz pressure ``p_max = 2 w / (pi b)`` [Pa] (thesis 2.1; Johnson eq. 4.44)."""
    return 2 * np.asarray(w) / (np.pi * np.asarray(b))


def hertz_mean_pressure(w: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Mean pressure over the band, ``w / (2 b) = pi p_max / 4`` [Pa]."""
    return np.asarray(w) / (2 * np.asarray(b))
