"""Load per tooth pair along the path of contact, with the wear gap (thesis 2.2).

In the double-tooth zones the two pairs in contact deflect together. A pair whose flanks have
lost ``g_i`` of material along the line of action (pinion plus gear wear at its contact point)
only touches once the common approach ``delta`` exceeds ``g_i``; it then carries
``k_i (delta - g_i)``. With ``F = sum_i k_i (delta - g_i)``:

    F_A = k_A (F + k_B (g_B - g_A)) / (k_A + k_B)

which is the thesis's ``W_1 = M_1 (F_n/B +- |Delta| M_2) / (M_1 + M_2)`` with the sign set by
which pair has worn more. If that gives a negative load the more-worn pair has lost contact and the
other carries all of ``F``. (Flodin & Andersson, Wear 207 (1997); Bajpai, Kahraman & Anderson,
ASME J. Mech. Des. 126 (2004).)

The single-pair stiffness comes from :func:`iso6336_single_pair_stiffness` (a constant along the
path) until the potential-energy mesh stiffness replaces it behind the same ``stiffness`` argument
of :func:`pair_loads`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from physics.geometry import MeshGeometry
from physics.params import GearPair

#: ``stiffness(s) -> k [N/m]``: stiffness of the tooth pair in contact at roll coordinate s.
PairStiffness = Callable[[np.ndarray], np.ndarray]


def iso6336_single_pair_stiffness(gear: GearPair) -> float:
    """Single-pair stiffness ``c' b`` [N/m] of ISO 6336-1:2019 method B (clause 9).

    ``q' = C1 + C2/z1 + C3/z2`` (unshifted spur teeth) with C1 = 0.04723, C2 = 0.15551,
    C3 = 0.25791 mm um/N; ``c'_th = 1/q'``; ``c' = c'_th C_M C_R C_B`` with C_M = 0.8 (solid
    discs), C_R = 1 and ``C_B = [1 + 0.5 (1.2 - h_fP/m)] [1 - 0.02 (20 deg - alpha)]``.
    """
    q = 0.04723 + 0.15551 / gear.z1 + 0.25791 / gear.z2  # mm um / N
    h_fp = gear.ha_star + gear.c_star
    c_b = (1 + 0.5 * (1.2 - h_fp)) * (1 - 0.02 * (20.0 - gear.pressure_angle_deg))
    c_prime = (1 / q) * 0.8 * 1.0 * c_b  # N/(mm um)
    return c_prime * 1e9 * gear.face_width  # N/(mm um) = 1e9 N/m^2, times face width [m]


def pair_loads(
    geom: MeshGeometry,
    s: np.ndarray,
    force: np.ndarray,
    gap: Callable[[np.ndarray], np.ndarray],
    stiffness: PairStiffness,
) -> np.ndarray:
    """Normal load [N] on the tooth pair in contact at each roll coordinate ``s``.

    Parameters
    ----------
    geom : geometry of the pair (zones and partner positions).
    s : roll coordinates [m].
    force : total normal mesh force [N] at each ``s`` (quasi-static ``T2/rb2``, or the dynamic
        mesh force per mesh position).
    gap : ``gap(s)`` = pinion wear + gear wear [m] at the contact point of the pair at ``s``.
    stiffness : ``stiffness(s)`` [N/m] of the pair at ``s``.
    """
    s = np.asarray(s, dtype=float)
    force = np.broadcast_to(np.asarray(force, dtype=float), s.shape)
    double = geom.is_double(s)
    s_b = np.where(double, geom.partner(s), s)
    k_a, k_b = stiffness(s), stiffness(s_b)
    g_a, g_b = gap(s), gap(s_b)
    shared = k_a * (force + k_b * (g_b - g_a)) / (k_a + k_b)
    return np.where(double, np.clip(shared, 0.0, force), force)
