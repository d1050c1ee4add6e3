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
    """``v_s = |v1 - v2|`` [m/s]; zero at the pitch point (thesis 2.3)."""
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
