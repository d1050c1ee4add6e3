"""Meshing geometry of a spur pair along the line of action (thesis 2.1).

Coordinate: the *roll coordinate* ``s`` [m], the signed distance from the pitch point P along the
line of action, negative towards the start of contact (pinion root / gear tip, point B1) and
positive towards the end of contact (pinion tip / gear root, point B2), pinion driving. Every
mesh-position quantity in the package uses this coordinate.

A non-standard centre distance a changes the working pressure angle,
``cos(alpha_w) = a0 cos(alpha) / a`` (the base circles do not change; Litvin & Fuentes, Gear
Geometry and Applied Theory, 2nd ed., ch. 10; ISO 21771:2007), and with it the length of the
path of contact
``g_alpha = sqrt(ra1^2 - rb1^2) + sqrt(ra2^2 - rb2^2) - a sin(alpha_w)`` (thesis 2.1 with alpha
replaced by alpha_w, as ISO 21771 writes it). The contact ratio is ``g_alpha / p_b``. Only the
drive flanks are modelled: a centre distance below the standard one (thesis 2.7.6) presumes teeth
thinned enough to keep backlash; the model does not check the coast flanks.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from physics.params import GearPair


@dataclass(frozen=True)
class MeshGeometry:
    """Derived SI geometry of a gear pair: radii, path of contact and zones.

    Build it with :func:`mesh_geometry`, which also checks that the pair lies within the model's
    scope (contact ratio in (1, 2), no undercut, no tip interference).
    """

    gear: GearPair
    r1: float  # pitch (reference) radii [m]
    r2: float
    rb1: float  # base radii [m]
    rb2: float
    ra1: float  # tip radii [m]
    ra2: float
    rf1: float  # root radii [m]
    rf2: float
    center_distance: float  # [m]
    alpha_w: float  # working pressure angle [rad]
    base_pitch: float  # p_b [m]
    s_start: float  # roll coordinate of B1 (start of contact) [m], < 0
    s_end: float  # roll coordinate of B2 (end of contact) [m], > 0

    @property
    def path_length(self) -> float:
        """Length of the path of contact B1B2 [m]."""
        return self.s_end - self.s_start

    @property
    def tip_thickness(self) -> float:
        """The thinner tooth's thickness at its tip circle along its drive flank's normal [m]:
        ``2 r_a psi_a cos(alpha_a)``, ``psi_a`` the involute's angle from the tooth's centre
        line at the tip (:func:`physics.gear.tooth.involute_angle`) and ``alpha_a`` the pressure
        angle there (the normal of an involute is tangent to the base circle, at ``alpha_a`` to
        the tip circle's tangent). A drive flank worn that deep along its normal leaves no
        tip."""
        from physics.gear.tooth import involute_angle

        g, out = self.gear, []
        for z, rb, ra in ((g.z1, self.rb1, self.ra1), (g.z2, self.rb2, self.ra2)):
            psi, alpha_a = involute_angle(z, math.radians(g.pressure_angle_deg), rb, ra)
            out.append(2 * ra * float(psi) * math.cos(float(alpha_a)))
        return min(out)

    @property
    def contact_ratio(self) -> float:
        return self.path_length / self.base_pitch

    @property
    def single_zone(self) -> tuple[float, float]:
        """Roll coordinates bounding the single-tooth zone: ``(s_end - p_b, s_start + p_b)``."""
        return self.s_end - self.base_pitch, self.s_start + self.base_pitch

    def is_double(self, s: np.ndarray) -> np.ndarray:
        """True where two tooth pairs are in contact (outside the single-tooth zone)."""
        lo, hi = self.single_zone
        s = np.asarray(s, dtype=float)
        return (s < lo) | (s > hi)

    def partner(self, s: np.ndarray) -> np.ndarray:
        """Roll coordinate of the other pair in contact at ``s`` (``nan`` in the single zone).

        In the first double zone (approach) the preceding pair is one base pitch ahead
        (``s + p_b``); in the second (recess) the following pair is one base pitch behind.
        """
        lo, hi = self.single_zone
        s = np.asarray(s, dtype=float)
        return np.where(s < lo, s + self.base_pitch, np.where(s > hi, s - self.base_pitch, np.nan))

    def curvature_radii(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Involute radii of curvature of pinion and gear at ``s`` (thesis 2.1: R = r_b tan a_k).

        ``R1 = rb1 tan(alpha_w) + s`` and ``R2 = rb2 tan(alpha_w) - s``: distances from the two
        points of tangency with the base circles, N1 and N2.
        """
        s = np.asarray(s, dtype=float)
        return self.rb1 * math.tan(self.alpha_w) + s, self.rb2 * math.tan(self.alpha_w) - s

    def flank_radii(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Radius from each wheel's centre of the flank point in contact at ``s`` [m]."""
        R1, R2 = self.curvature_radii(s)
        return np.hypot(self.rb1, R1), np.hypot(self.rb2, R2)

    def mesh_period(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Roll coordinates over one mesh period at ``n`` phases: pair A from the start of
        contact, pair B one base pitch ahead (clipped to the end of contact), and B's contact
        mask (B is in contact in the double-tooth zone only)."""
        s_a = self.s_start + self.base_pitch * np.arange(n) / n
        ahead = s_a + self.base_pitch
        return s_a, np.minimum(ahead, self.s_end), ahead <= self.s_end

    def grid(self, n: int) -> np.ndarray:
        """``n`` points on the path of contact with the two zone boundaries among them.

        Points are spaced as evenly as possible, but the two zone transitions each get a
        node, so a step in the load lands on the grid instead of being smeared.
        """
        lo, hi = self.single_zone
        knots = np.array([self.s_start, lo, hi, self.s_end])
        lengths = np.diff(knots)
        counts = np.maximum(2, np.round(lengths / self.path_length * (n - 1)).astype(int))
        counts[-1] = max(2, n - 1 - counts[:-1].sum())
        parts = [np.linspace(knots[i], knots[i + 1], counts[i] + 1)[:-1] for i in range(3)]
        return np.concatenate([*parts, [self.s_end]])


def working_pressure_angle(gear: GearPair) -> float:
    """``alpha_w = arccos(a0 cos(alpha) / a)`` [rad] (no profile shift: base radii are fixed)."""
    a0 = gear.standard_center_distance_mm * 1e-3
    return math.acos(a0 * math.cos(gear.alpha) / gear.center_distance)


@functools.lru_cache(maxsize=64)
def mesh_geometry(gear: GearPair) -> MeshGeometry:
    """Geometry of the pair, validated against the scope of the wear model.

    Parameters
    ----------
    gear : GearPair
        The pair (frozen, so the result is cached per pair).

    Returns
    -------
    MeshGeometry
        Radii, working pressure angle, base pitch ``p_b = pi m cos(alpha)`` and the roll
        coordinates of the start (B1) and end (B2) of contact (thesis 2.1; ISO 21771:2007 with
        the working pressure angle, module docstring).

    Raises
    ------
    ValueError
        For an undercut pinion (z1 below the rack-generation limit ``2 ha* / sin^2 alpha``), a
        centre distance that leaves no contact or interference, or a contact ratio outside (1, 2).

    Examples
    --------
    The thesis pair (Table 0: m = 2 mm, z = 18/27, 20 deg, standard centre distance 45 mm):

    >>> from physics.params import GearPair
    >>> g = mesh_geometry(GearPair())
    >>> round(g.base_pitch * 1e3, 3)  # p_b [mm]
    5.904
    >>> round(math.pi * 2.0 * math.cos(math.radians(20.0)), 3)  # pi m cos(alpha), by hand
    5.904
    >>> round(g.contact_ratio, 3)
    1.58

    The contact ratio by hand, ``(sqrt(ra1^2 - rb1^2) + sqrt(ra2^2 - rb2^2) - a sin(alpha)) /
    p_b`` with tip radii ``r + ha* m`` = 20 and 29 mm and base radii ``r cos(alpha)``:

    >>> c = math.cos(math.radians(20.0))
    >>> g_alpha = (math.sqrt(20.0**2 - (18 * c) ** 2) + math.sqrt(29.0**2 - (27 * c) ** 2)
    ...            - 45.0 * math.sin(math.radians(20.0)))
    >>> round(g_alpha / (math.pi * 2.0 * c), 3)
    1.58

    Contact starts before the pitch point (pinion root) and ends after it (pinion tip):

    >>> round(g.s_start * 1e3, 3), round(g.s_end * 1e3, 3)  # [mm]
    (-4.811, 4.516)
    """
    m, z1, z2, alpha = gear.m, gear.z1, gear.z2, gear.alpha
    z_min = 2 * gear.ha_star / math.sin(alpha) ** 2
    if z1 < z_min - 1e-9:
        raise ValueError(
            f"gear.z1 = {z1} is undercut by the generating rack: with ha* = {gear.ha_star:g} and "
            f"alpha = {gear.pressure_angle_deg:g} deg, z1 must be >= 2 ha*/sin^2(alpha) = "
            f"{z_min:.2f} (unshifted teeth); use more pinion teeth or a larger pressure angle"
        )
    r1, r2 = m * z1 / 2, m * z2 / 2
    rb1, rb2 = r1 * math.cos(alpha), r2 * math.cos(alpha)
    ra1, ra2 = r1 + gear.ha_star * m, r2 + gear.ha_star * m
    rf1, rf2 = r1 - (gear.ha_star + gear.c_star) * m, r2 - (gear.ha_star + gear.c_star) * m
    a = gear.center_distance
    a_min = max(ra1 + rf2, ra2 + rf1)  # zero tip clearance
    a_max = ra1 + ra2 - 1e-9  # tip circles just touch: no path of contact
    if not a_min - 1e-12 <= a < a_max:
        raise ValueError(
            f"gear.center_distance_mm = {a * 1e3:g} must lie in [{a_min * 1e3:.3f}, "
            f"{a_max * 1e3:.3f}) mm: below, a tip digs into the mating root (negative clearance); "
            "above, the tip circles leave no path of contact"
        )
    alpha_w = working_pressure_angle(gear)
    pb = math.pi * m * math.cos(alpha)
    t1, t2 = rb1 * math.tan(alpha_w), rb2 * math.tan(alpha_w)  # N1P, N2P
    s_start = -(math.sqrt(ra2**2 - rb2**2) - t2)
    s_end = math.sqrt(ra1**2 - rb1**2) - t1
    if s_start <= -t1 or s_end >= t2:
        raise ValueError(
            f"gear.center_distance_mm = {a * 1e3:g}: a tip circle reaches past the other wheel's "
            "base-circle tangency point (involute interference); increase the centre distance"
        )
    geom = MeshGeometry(gear, r1, r2, rb1, rb2, ra1, ra2, rf1, rf2, a, alpha_w, pb, s_start, s_end)
    eps = geom.contact_ratio
    if not 1.0 < eps < 2.0:
        raise ValueError(
            f"contact ratio {eps:.3f} of this gear pair lies outside (1, 2), the scope of the "
            "wear model (one or two pairs in contact); change the teeth, ha* or centre distance"
        )
    return geom
