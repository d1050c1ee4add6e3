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

The pair stiffness along the path comes from the potential-energy model of the worn teeth
(:class:`physics.stiffness.MeshStiffness`), passed in as the ``stiffness`` function.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from physics.gear.geometry import MeshGeometry

#: ``stiffness(s) -> k [N/m]``: stiffness of the tooth pair in contact at roll coordinate s.
PairStiffness = Callable[[np.ndarray], np.ndarray]


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
    force : total normal mesh force [N] at the instant the pair under consideration is at ``s``
        (quasi-static ``T2/rb2``, or the dynamic mesh force per mesh position). The pair at ``s``
        and its partner share that instant's force; a force that is periodic in the base pitch
        (steady mesh-rate dynamics) gives the same instant from either pair's side.
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
