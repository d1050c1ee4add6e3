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
    """Half-width ``b = sqrt(4 w R / (pi E*))`` [m] for load per unit length ``w`` [N/m].

    Johnson, Contact Mechanics (1985), eq. 4.43 (the thesis's 2.1 form is ``sqrt(2)`` wider:
    module docstring).

    Parameters
    ----------
    w : array_like
        Normal load per unit face width [N/m].
    R : array_like
        Equivalent radius of curvature ``1/R = 1/R1 + 1/R2`` [m] (:func:`equivalent_radius`).
    e_star : float
        Contact modulus ``E*`` [Pa] (:func:`reduced_modulus`).

    Returns
    -------
    numpy.ndarray
        Hertz half-width ``b`` [m], broadcast over ``w`` and ``R``.

    Examples
    --------
    The thesis pair at the pitch point, one pair carrying the whole static load of case 3
    (``F = T2 / rb2`` = 11.8 kN over 30 mm; ``R1 = r1 sin(alpha)``, ``R2 = r2 sin(alpha)``):

    >>> import math
    >>> from physics.params import Material
    >>> e_star = reduced_modulus(Material(), Material())
    >>> round(e_star / 1e9, 1)  # 206 GPa / (2 (1 - 0.3^2)) [GPa]
    113.2
    >>> sin = math.sin(math.radians(20.0))
    >>> R = float(equivalent_radius(0.018 * sin, 0.027 * sin))  # [m]
    >>> w = 300.0 / (0.027 * math.cos(math.radians(20.0))) / 0.030  # [N/m]
    >>> b = float(hertz_half_width(w, R, e_star))
    >>> round(b * 1e6, 1)  # [um]
    128.0
    >>> round(math.sqrt(4 * w * R / (math.pi * e_star)) * 1e6, 1)  # by hand
    128.0
    """
    return np.sqrt(4 * np.asarray(w) * np.asarray(R) / (np.pi * e_star))


def hertz_max_pressure(w: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Peak Hertz pressure ``p_max = 2 w / (pi b)`` [Pa] (thesis 2.1; Johnson eq. 4.44).

    Parameters
    ----------
    w : array_like
        Normal load per unit face width [N/m].
    b : array_like
        Hertz half-width [m] (:func:`hertz_half_width`).

    Returns
    -------
    numpy.ndarray
        Peak pressure at the centre of the band [Pa], broadcast over ``w`` and ``b``.

    Examples
    --------
    With :func:`hertz_half_width`, ``p_max = sqrt(w E* / (pi R))`` (``b`` eliminated between
    Johnson eqs. 4.43 and 4.44); at the thesis pair's pitch point under the whole static load
    of case 3:

    >>> import math
    >>> from physics.params import Material
    >>> e_star = reduced_modulus(Material(), Material())
    >>> sin = math.sin(math.radians(20.0))
    >>> R = float(equivalent_radius(0.018 * sin, 0.027 * sin))
    >>> w = 300.0 / (0.027 * math.cos(math.radians(20.0))) / 0.030
    >>> p = float(hertz_max_pressure(w, hertz_half_width(w, R, e_star)))
    >>> round(p / 1e9, 3)  # [GPa]
    1.961
    >>> round(math.sqrt(w * e_star / (math.pi * R)) / 1e9, 3)  # by hand
    1.961
    >>> round(float(hertz_mean_pressure(w, hertz_half_width(w, R, e_star))) / p, 4)  # pi / 4
    0.7854
    """
    return 2 * np.asarray(w) / (np.pi * np.asarray(b))


def hertz_mean_pressure(w: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Mean pressure over the band, ``w / (2 b) = pi p_max / 4`` [Pa]."""
    return np.asarray(w) / (2 * np.asarray(b))
