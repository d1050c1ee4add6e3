"""Rolling, sliding and entraining velocities and sliding distances (thesis 2.3).

All functions take the two involute radii of curvature at the contact, ``R1`` and ``R2`` [m]
(:meth:`physics.geometry.MeshGeometry.curvature_radii`), and broadcast over positions.
"""

from __future__ import annotations

import numpy as np


def surface_velocities(
    R1: np.ndarray, R2: np.ndarray, omega1: float, z1: int, z2: int
) -> tuple[np.ndarray, np.ndarray]:
    """Tangential (rolling) velocities of the two flanks at the contact [m/s].

    ``v1 = omega1 R1`` and ``v2 = omega2 R2`` with ``omega2 = omega1 z1 / z2`` (thesis 2.3).
    """
    omega2 = omega1 * z1 / z2
    return omega1 * np.asarray(R1), omega2 * np.asarray(R2)


def sliding_velocity(v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """``v_s = |v1 - v2|`` [m/s]; zero at the pitch point (thesis 2.3).

    With ``v_i = omega_i R_i`` (:func:`surface_velocities`), ``R1 = rb1 tan(alpha_w) + s``,
    ``R2 = rb2 tan(alpha_w) - s`` and ``omega1 rb1 = omega2 rb2``, the sliding velocity is
    ``v_s = (omega1 + omega2) |s|``: proportional to the distance from the pitch point along the
    line of action (follows from thesis 2.3 and the involute radii of thesis 2.1,
    :meth:`physics.gear.geometry.MeshGeometry.curvature_radii`).

    Parameters
    ----------
    v1, v2 : array_like
        Tangential (rolling) velocities of the pinion and gear flanks at the contact [m/s].

    Returns
    -------
    numpy.ndarray
        Sliding velocity ``|v1 - v2|`` [m/s], broadcast over ``v1`` and ``v2``.

    Examples
    --------
    The thesis pair at 2000 r/min, at the start of contact, the pitch point and the end of
    contact:

    >>> import math
    >>> from physics.gear.geometry import mesh_geometry
    >>> from physics.params import GearPair
    >>> g = mesh_geometry(GearPair())
    >>> omega1 = 2000 * 2 * math.pi / 60  # [rad/s]
    >>> s = np.array([g.s_start, 0.0, g.s_end])
    >>> v1, v2 = surface_velocities(*g.curvature_radii(s), omega1, 18, 27)
    >>> [round(float(v), 3) for v in sliding_velocity(v1, v2)]  # [m/s]
    [1.679, 0.0, 1.576]
    >>> [round(omega1 * (1 + 18 / 27) * abs(float(x)), 3) for x in s]  # (omega1 + omega2) |s|
    [1.679, 0.0, 1.576]
    """
    return np.abs(np.asarray(v1) - np.asarray(v2))


def entraining_velocity(v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """``v_e = (v1 + v2) / 2`` [m/s] (thesis 2.3)."""
    return 0.5 * (np.asarray(v1) + np.asarray(v2))


def sliding_distances(
    half_width: np.ndarray, v1: np.ndarray, v2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Sliding distance a flank point covers in one pass through the contact [m].

    A point of flank i crosses the contact band ``2 b`` in ``2 b / v_i`` while sliding at
    ``|v1 - v2|``: ``L1 = 2 b |1 - v2/v1|``, ``L2 = 2 b |1 - v1/v2|`` (thesis 2.3; Flodin &
    Andersson, Wear 207 (1997) 16-23).
    """
    v1, v2 = np.asarray(v1), np.asarray(v2)
    slide = np.abs(v1 - v2)
    return 2 * half_width * slide / v1, 2 * half_width * slide / v2
