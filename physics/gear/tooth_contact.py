"""Tooth contact of flanks of any shape, on and off the theoretical path of contact.

Worn flanks are no longer conjugate: where they meet, and whether they meet at all, follows from
their shapes, not from the line of action. Here each tooth pair is given its *rigid gap* at
every mesh position: the extra transmission error, on the line of action, that closes the
clearance between the two teeth as they are. With the pinion rotated by ``phi1`` and the gear
by ``phi2`` as conjugate involutes would be when their contact lies at roll coordinate ``s``
(``phi1 = phi1(0) + s / r_b1``, ``phi2 = phi2(0) - s / r_b2``, also where ``s`` lies beyond the
ends of the path), the gap is

    g(s) = min( min_j r_b1 [theta_j - theta_f1(rho_j)],  min_i r_b2 [theta_i - theta_f2(rho_i)] )

over every point ``j`` of the gear's drive flank, its tip corner included, seen in the pinion's
tooth frame at radius ``rho_j`` and angle ``theta_j`` from the tooth's centre line, against the
pinion flank's angle ``theta_f1`` at that radius; and the same for every pinion point ``i``
against the gear's flank. A rotation of the pinion by ``d phi`` moves its involute by
``r_b1 d phi`` along its normal, everywhere (the involute's defining property; Litvin & Fuentes,
*Gear Geometry and Applied Theory*, 2nd ed., ch. 10), so ``r_b1 [theta - theta_f]`` is the
transmission error that brings the point onto the flank, exactly, at any distance from the path.
This is the separation function of tooth-contact analysis for spur pairs (Litvin & Fuentes,
ch. 9; the same rigid separation drives Eritenel & Parker, J. Sound Vib. 331 (2012) 2261, and
the loaded contact of Conry & Seireg, ASME J. Eng. Ind. 93 (1971) 1115, once each pair is
lumped into one compliance).

What it holds that a wear gap summed on the line of action cannot:

- on the path of unworn involutes, ``g = 0`` (conjugate action); worn, ``g`` is the least
  clearance of the worn shapes, ``h1 + h2`` to first order in the wear slope;
- before the path's start, the gear's tip corner approaching the pinion's flank below the start
  of active profile, a flank that conjugate action never touched and so never wore: the ridge at
  the end of a worn band (Brauer & Andersson, Wear 254 (2003) 1216); after the path's end, the
  pinion's tip corner on the gear's root. A loaded pair deflects into these early and late
  contacts (extended contact: Lin, Houser & Oswald, NASA CR-4214, 1989; Ma, Zeng et al., Mech.
  Mach. Theory 2015).

The flanks are the generated teeth of :mod:`physics.gear.tooth` (involute and trochoid fillet),
each worn along its outward normal by the wear depth of the flank point, the depth given on the
roll grid of the path (the point that conjugate action brings to roll coordinate ``s``) and 0
where that grid does not reach.

:func:`loaded_contact` solves the quasi-static loaded contact of the pairs with these gaps and
each pair's lumped compliance (the potential-energy stiffness of :mod:`physics.gear.stiffness`):
the loaded transmission error, each pair's load and the mesh stiffness per position.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from physics.gear.geometry import MeshGeometry
from physics.gear.tooth import ToothForm, checked_wear, involute_angle

#: a point of one tooth is compared with the other's flank only within the flank's radii
#: (fillet foot to tip); farther points cannot touch it: their gap is this [m]
NO_CONTACT = 1.0


@dataclass(frozen=True)
class WornFlank:
    """A drive flank in its tooth frame: radius and angle from the centre line of each point,
    root to tip (the last point is the tip corner); ``involute_from`` the first point of the
    involute (below it the fillet, which can only be touched, by the other's tip corner)."""

    radius: np.ndarray  # [m], increasing
    angle: np.ndarray  # [rad]
    involute_from: int
    roll: np.ndarray  # each point's flank coordinate (:func:`flank_coordinate`) [m]


def flank_coordinate(form: ToothForm, geom: MeshGeometry, wheel: int) -> np.ndarray:
    """Where each profile point of ``form`` lies in the roll coordinate: on the involute, the
    roll ``s`` at which conjugate action brings it onto the line of action; on the fillet,
    continued below the involute's lowest point by the arc length along the fillet (away from
    the path: down for the pinion, up for the gear), so that wear given on one grid reaches
    the root where a tip corner touches it [m]."""
    R = np.sqrt(np.maximum(form.radius**2 - form.rb**2, 0.0))  # involute's curvature radius
    tan_w = math.tan(geom.alpha_w)
    sign = 1.0 if wheel == 1 else -1.0
    u = sign * (R - form.rb * tan_w)
    i = form.involute_from
    arc = np.concatenate([np.cumsum(np.hypot(np.diff(form.x[: i + 1]),
                                             np.diff(form.y[: i + 1]))[::-1])[::-1], [0.0]])
    u[:i] = u[i] - sign * arc[:i]
    return u


def worn_flank(form: ToothForm, geom: MeshGeometry, wheel: int, s_grid: np.ndarray | None,
               wear: np.ndarray | None) -> WornFlank:
    """The drive flank of ``form`` worn by ``wear`` [m] given on the roll grid ``s_grid``: each
    profile point moved inward along its outward normal by the depth at its flank coordinate
    (:func:`flank_coordinate`; 0 beyond the grid)."""
    x, y = form.x.copy(), form.y.copy()
    s_pt = flank_coordinate(form, geom, wheel)
    if wear is not None:
        s_grid, wear = checked_wear(s_grid, wear)
        order = np.argsort(s_grid)
        depth = np.interp(s_pt, s_grid[order], wear[order], left=0.0, right=0.0)
        # the outward normal of the +x flank, root to tip: (dy, -dx) / |(dx, dy)|
        dx, dy = np.gradient(x), np.gradient(y)
        norm = np.hypot(dx, dy)
        x, y = x - depth * dy / norm, y + depth * dx / norm
    radius = np.hypot(x, y)
    angle = np.arctan2(x, y)
    keep = np.concatenate([[True], np.diff(radius) > 0])  # a flank worn steeper than radial
    return WornFlank(radius[keep], angle[keep], int(keep[:form.involute_from].sum()),
                     s_pt[keep])


class PairGaps:
    """Rigid gap of one tooth pair at any roll coordinate (module doc).

    Both drive flanks are mirrored into the frames that put the pinion turning counter-clockwise
    and the gear clockwise about centres ``(0, 0)`` and ``(a, 0)``, the line of action through
    the pitch point rising at ``alpha_w`` (``s`` grows from the pinion's root to its tip).
    """

    def __init__(self, geom: MeshGeometry, forms: tuple[ToothForm, ToothForm],
                 s_grid: np.ndarray | None = None, wear1: np.ndarray | None = None,
                 wear2: np.ndarray | None = None):
        self.geometry = geom
        self.flanks = (worn_flank(forms[0], geom, 1, s_grid, wear1),
                       worn_flank(forms[1], geom, 2, s_grid, wear2))
        alpha = geom.gear.alpha
        rw1 = geom.rb1 / math.cos(geom.alpha_w)
        rw2 = geom.rb2 / math.cos(geom.alpha_w)
        # rotations that put each involute through the pitch point (s = 0)
        self._phi0 = (
            -0.5 * math.pi - float(involute_angle(forms[0].z, alpha, forms[0].rb, rw1)[0]),
            0.5 * math.pi - float(involute_angle(forms[1].z, alpha, forms[1].rb, rw2)[0]))

    def rotations(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Conjugate rotations of pinion and gear for a contact at roll ``s`` [rad]."""
        g = self.geometry
        return self._phi0[0] + s / g.rb1, self._phi0[1] - s / g.rb2

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """Gap [m] of the pair whose conjugate contact would lie at roll ``s`` (any shape)."""
        return self.contacts(s)[0]

    def contacts(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Gap [m] of the pair at roll ``s`` and where its flanks come closest: the roll
        coordinates of the pinion's and the gear's flank points there (of their unworn
        involute points; at a tip corner, the corner's). Shapes of ``s``."""
        s = np.asarray(s, dtype=float)
        g = self.geometry
        phi1, phi2 = self.rotations(s.ravel())
        f1, f2 = self.flanks
        a = g.center_distance
        # gear points in the pinion's tooth frame, and pinion points in the gear's (the centre
        # of the other wheel at +a or -a along x)
        i1, i2 = f1.involute_from, f2.involute_from
        gap1, j1, k1 = _least_gap(f2.radius[i2:], f2.angle[i2:], phi2, phi1, a, f1.radius,
                                  f1.angle, g.rb1)
        gap2, j2, k2 = _least_gap(f1.radius[i1:], f1.angle[i1:], phi1, phi2, -a, f2.radius,
                                  f2.angle, g.rb2)
        cells1, cells2 = np.arange(f1.roll.size), np.arange(f2.roll.size)
        first = gap1 <= gap2  # a gear point on the pinion's flank
        u1 = np.where(first, np.interp(k1, cells1, f1.roll), f1.roll[i1:][j2])
        u2 = np.where(first, f2.roll[i2:][j1], np.interp(k2, cells2, f2.roll))
        return tuple(x.reshape(s.shape) for x in (np.minimum(gap1, gap2), u1, u2))


@numba.njit(cache=True, parallel=True, fastmath=False)
def _least_gap(r_pt, a_pt, phi_pt, phi_fl, offset, r_fl, a_fl, rb):
    """Least gap over the points (``r_pt``, ``a_pt``: radius and angle in their tooth frame,
    turned by ``phi_pt``, wheel centre at ``offset`` along x from the flank's) to the flank
    (``r_fl``, ``a_fl``, radii increasing, turned by ``phi_fl``), in the flank wheel's rotation
    times ``rb``, for each position, with the point's index and the flank's fractional index
    where it comes closest; ``NO_CONTACT`` where no point lies within the flank's radii. Both
    tooth frames are mirrored (angle from the centre line = polar angle - pi/2 - phi).

    Each point is turned by the position's rotation matrix (one cosine and sine per position
    and per point, not per pair: within 1e-16 m of turning each by its own angle), and the
    flank cell holding its radius is walked from the previous point's (the points follow the
    profile, so it moves by a cell or two), the cell ``np.searchsorted`` would give."""
    n, m, nf = phi_pt.size, r_pt.size, r_fl.size
    out = np.full(n, NO_CONTACT)
    where_pt = np.zeros(n, dtype=np.int64)
    where_fl = np.zeros(n)
    lo2, hi2 = r_fl[0] ** 2, r_fl[-1] ** 2
    x0, y0 = np.empty(m), np.empty(m)  # the points in their frame, unturned
    for j in range(m):
        x0[j] = r_pt[j] * math.cos(0.5 * math.pi + a_pt[j])
        y0[j] = r_pt[j] * math.sin(0.5 * math.pi + a_pt[j])
    for i in numba.prange(n):
        best = NO_CONTACT
        c, sn = math.cos(phi_pt[i]), math.sin(phi_pt[i])
        k = 0
        for j in range(m):
            x = offset + x0[j] * c - y0[j] * sn
            y = x0[j] * sn + y0[j] * c
            rho2 = x * x + y * y
            if rho2 < lo2 or rho2 > hi2:
                continue
            rho = math.sqrt(rho2)
            while k > 0 and r_fl[k] >= rho:  # the last cell starting below rho, or the first
                k -= 1
            while k + 1 < nf and r_fl[k + 1] < rho:
                k += 1
            t = (rho - r_fl[k]) / (r_fl[k + 1] - r_fl[k])
            flank = a_fl[k] + t * (a_fl[k + 1] - a_fl[k])
            d = math.atan2(y, x) - 0.5 * math.pi - phi_fl[i] - flank
            d = (d + math.pi) % (2.0 * math.pi) - math.pi
            if rb * d < best:
                best = rb * d
                where_pt[i] = j
                where_fl[i] = k + t
        out[i] = best
    return out, where_pt, where_fl


@dataclass(frozen=True)
class LoadedContact:
    """Quasi-static loaded contact of the pairs over one mesh period (:func:`loaded_contact`).

    ``roll`` is the roll of the pair that entered last on the theoretical path; the pairs are
    ``roll + (j - 1) p_b``, ``j = 0 .. 3`` (the one before its theoretical entry first)."""

    roll: np.ndarray  # [m]
    transmission_error: np.ndarray  # loaded TE on the line of action [m]
    loads: np.ndarray  # (positions, 4) load of each pair [N]
    stiffness: np.ndarray  # mesh stiffness: summed stiffness of the loaded pairs [N/m]


def pair_slots(geom: MeshGeometry, roll: np.ndarray) -> np.ndarray:
    """Roll coordinates ``(positions, 4)`` of the pairs that can touch at each ``roll`` of the
    pair last entered: one before its theoretical entry, it, the one ahead, and the one after
    that (past the end of a path shorter than two base pitches)."""
    return np.asarray(roll, dtype=float)[:, None] + geom.base_pitch * np.arange(-1, 3)


def clamped(geom: MeshGeometry, s: np.ndarray) -> np.ndarray:
    """``s`` clamped to the theoretical path: where an off-path pair's compliance is taken (a
    tip corner loads its tooth at the tip, the mating flank just beyond the active profile)."""
    return np.clip(s, geom.s_start, geom.s_end)


def share_load(g: np.ndarray, k: np.ndarray, force: np.ndarray | float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Approach and pair loads of pairs with gaps ``g`` and stiffnesses ``k`` (rows: positions,
    columns: pairs) under ``force`` [N]: ``sum_j k_j max(delta - g_j, 0) = force`` solved
    exactly (piecewise linear; the engaged pairs are those with the smallest gaps)."""
    n = g.shape[0]
    order = np.argsort(g, axis=1)
    gs, ks = np.take_along_axis(g, order, 1), np.take_along_axis(k, order, 1)
    ksum, kg = np.cumsum(ks, axis=1), np.cumsum(ks * gs, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = (np.reshape(force, (-1, 1)) + kg) / ksum  # with the first m pairs engaged
    upper = np.concatenate([gs[:, 1:], np.full((n, 1), np.inf)], axis=1)
    m = np.argmax((ksum > 0) & (delta <= upper), axis=1)  # the first consistent engaged set
    te = delta[np.arange(n), m]
    return te, k * np.maximum(te[:, None] - g, 0.0)


def loaded_contact(geom: MeshGeometry, gaps: PairGaps, stiffness, force: float,
                   n: int = 256) -> LoadedContact:
    """Loaded TE, pair loads and mesh stiffness over one mesh period at normal force ``force``
    [N] (:func:`share_load`), with ``k_j`` the pair stiffness ``stiffness(s)`` at the pair's
    roll clamped to the path (:func:`clamped`)."""
    if not force > 0:
        raise ValueError(f"force = {force!r} must be > 0 (N)")
    roll = geom.mesh_period(n)[0]
    s = pair_slots(geom, roll)
    g = gaps(s)
    k = stiffness(clamped(geom, s).ravel()).reshape(s.shape)
    te, loads = share_load(g, k, force)
    return LoadedContact(roll, te, loads, (k * (te[:, None] > g)).sum(axis=1))
