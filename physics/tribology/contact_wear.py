"""Flank wear driven by the tooth contact of the flanks as they are, from new to worn out.

:mod:`physics.tribology.wear` follows the thesis (2.2, 2.6): each pair touches at its point of
the theoretical path, its load shared with the wear summed there as a gap, and the band's
pressure solved across it; it leaves its scope where the worn flanks no longer meet as one line
contact (tens to a few hundred micrometres). Here the wear step follows the contact that the
worn flanks actually make (:mod:`physics.gear.tooth_contact`): at every mesh position each
tooth pair that can touch, on or off the path, tip corners included, its rigid gap and where its
flanks come closest; the quasi-static loads of the pairs from those gaps and the pairs'
potential-energy stiffnesses (:func:`physics.gear.tooth_contact.share_load`); and the Archard
law on each contact.

Per pass, a contact of load ``w`` per face width that slides at ``v_s`` wears each flank by the
volume ``k_eff w v_s dt / H`` per unit width in the time ``dt`` of a mesh position, spread over
the arc its contact point crosses on that flank in ``dt``, or over the Hertz band ``2 b`` where
it crosses less (a tip corner stays on its own point, the flank it rides does not): for rolling
contact on the path this is the thesis's ``k p L_i / H`` with ``L_i = 2 b |1 - v_j / v_i|``
(thesis 2.6; Flodin & Andersson, Wear 207 (1997) 16-23), and a corner's wear spreads over its
band as it rounds off. The contact's curvature radii and rolling speeds are those of the
involute points that touch (``R_i`` from their roll coordinates, ``v_i = omega_i R_i``); ``k_eff``
is the scenario's (:func:`physics.tribology.wear.wear_coefficient`: dry, or the mixed law from
the contact state at that load).

What it leaves out, said where it matters: the pressure across the band of a worn contact (a
Hertz band of the involutes' radii; the wear per pass does not depend on its shape, its peak
does: no shakedown check here), the dynamic load (quasi-static mesh force), and wear of the
coast flanks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from physics.gear import contact, kinematics
from physics.gear.stiffness import MeshStiffness, mesh_stiffness
from physics.gear.tooth_contact import (
    PairGaps,
    clamped,
    flank_coordinate,
    pair_slots,
    share_load,
)
from physics.params import Scenario
from physics.scope import check_scope
from physics.tribology.contact_state import solve_contact_state
from physics.tribology.wear import film_deficiency, quasi_static_force, wear_coefficient

#: mesh positions per base pitch at which the contact is solved each block
POSITIONS = 256
#: grid spacing of the flanks' wear, as a share of the base pitch
SPACING = 1 / 400
#: a block wears the fastest point by ``solver.update_um`` or by this share of the deepest
#: wear so far, whichever is more (the shape of deep wear changes over a share of its depth)
RELATIVE_STEP = 0.02


@dataclass(frozen=True)
class ContactWear:
    """Wear of both flanks on the roll grid ``s`` (the whole involute of each flank)."""

    s: np.ndarray  # [m]
    pinion: np.ndarray  # wear depth [m]
    gear: np.ndarray
    cycles: float
    active: np.ndarray  # bool: the grid's points on the theoretical path (the active profiles)
    #: every block's end (and the start): cycles ``(k,)``, pinion and gear wear ``(k, n)`` [m]
    history: tuple[np.ndarray, np.ndarray, np.ndarray]

    def deepest(self) -> np.ndarray:
        """Deepest wear of either active profile at each block end [m]."""
        _, p, g = self.history
        return np.maximum(p[:, self.active].max(axis=1), g[:, self.active].max(axis=1))

    def at_depth(self, depth: float) -> tuple[np.ndarray, np.ndarray, float]:
        """Pinion and gear wear [m] and cycles when the deepest point of either active profile
        first reached ``depth`` [m] (linear between block ends: each block wears linearly)."""
        cycles, p, g = self.history
        deepest = self.deepest()
        if not 0 <= depth <= deepest[-1]:
            raise ValueError(f"depth = {depth:g} m lies outside the run's 0-{deepest[-1]:g} m")
        i = int(np.searchsorted(deepest, depth))
        if i == 0:
            return p[0], g[0], float(cycles[0])
        f = (depth - deepest[i - 1]) / (deepest[i] - deepest[i - 1])
        return (p[i - 1] + f * (p[i] - p[i - 1]), g[i - 1] + f * (g[i] - g[i - 1]),
                float(cycles[i - 1] + f * (cycles[i] - cycles[i - 1])))


def whole_flank_grid(ms: MeshStiffness) -> np.ndarray:
    """A uniform grid of the flank coordinate over both flanks, fillets included (pinion from
    the foot of its fillet to its tip, gear from its tip to the foot of its fillet;
    :func:`physics.gear.tooth_contact.flank_coordinate`) [m]."""
    geom = ms.geometry
    lo = min(flank_coordinate(ms.forms[0], geom, 1).min(), geom.s_start)
    hi = max(flank_coordinate(ms.forms[1], geom, 2).max(), geom.s_end)
    step = geom.base_pitch * SPACING
    return np.linspace(lo, hi, math.ceil((hi - lo) / step) + 1)


def _deposit(grid: np.ndarray, centre: np.ndarray, width: np.ndarray, depth: np.ndarray
             ) -> np.ndarray:
    """Depth on the grid's cells of deposits of ``depth`` spread evenly over ``centre +-
    width / 2`` (each conserves its volume, ``depth * width``, wherever it lands)."""
    step = grid[1] - grid[0]
    edges = np.concatenate([grid - 0.5 * step, [grid[-1] + 0.5 * step]])
    lo = centre - 0.5 * width
    covered = np.clip(edges[:, None] - lo[None, :], 0.0, width[None, :])  # (edges, deposits)
    volume = covered @ depth
    return np.maximum(np.diff(volume), 0.0) / step  # (rounding leaves -1e-26 where none)


def wear_per_cycle(scn: Scenario, ms: MeshStiffness, grid: np.ndarray, wear1: np.ndarray,
                   wear2: np.ndarray, force: float) -> tuple[np.ndarray, np.ndarray]:
    """Pinion and gear wear per pinion cycle [m] on ``grid`` for the flanks worn by ``wear1,
    wear2`` under the normal mesh force ``force`` [N] (module doc)."""
    geom, g, op = ms.geometry, scn.gear, scn.operating
    # every pair's pass through the mesh, in order of roll
    slots = pair_slots(geom, geom.mesh_period(POSITIONS)[0]).T.ravel()
    gap, u1, u2 = PairGaps(geom, ms.forms, grid, wear1, wear2).contacts(slots)
    k = ms.pair_function(grid, wear1, wear2)(clamped(geom, slots))
    cols = (4, POSITIONS)
    _, load = share_load(gap.reshape(cols).T, k.reshape(cols).T, force)
    load = load.T.ravel()
    on = load > 0
    tan_w = math.tan(geom.alpha_w)
    R1 = np.maximum(geom.rb1 * tan_w + u1, 1e-6)
    R2 = np.maximum(geom.rb2 * tan_w - u2, 1e-6)
    omega1, omega2 = op.omega1, op.omega1 * g.z1 / g.z2
    v1, v2 = omega1 * R1, omega2 * R2
    ds = geom.base_pitch / POSITIONS
    dt = ds / (geom.rb1 * omega1)
    R = contact.equivalent_radius(R1, R2)
    # the contact state of the loaded positions only: an unloaded one has no contact, and its
    # clamped radii lie outside the lubrication model's range
    state = solve_contact_state(scn, load[on], R[on], v1[on], v2[on])
    psi = (np.ones(on.sum()) if scn.tribology.regime == "dry"
           else film_deficiency(state.v_s, state.temperature, scn.lubricant))
    k_eff = np.zeros_like(load)
    k_eff[on] = wear_coefficient(scn.tribology, state.asperity_ratio, psi)
    w = load / g.face_width
    volume = (k_eff * w * kinematics.sliding_velocity(v1, v2) * dt
              / scn.material.hardness)  # per unit width
    e_star = contact.reduced_modulus(scn.material, scn.material)
    band = 2 * contact.hertz_half_width(np.where(on, w, 0.0), R, e_star)
    low1, low2 = (float(flank_coordinate(form, geom, wheel)[form.involute_from])
                  for form, wheel in zip(ms.forms, (1, 2), strict=True))
    out = []
    for u, R, rb, fillet in ((u1, R1, geom.rb1, u1 < low1), (u2, R2, geom.rb2, u2 > low2)):
        # arc per unit of the flank coordinate: R / r_b on the involute (dl = R du / r_b), 1 on
        # the fillet (its coordinate is its arc)
        scale = np.where(fillet, 1.0, R / rb)
        moved = np.abs(np.gradient(u)) * scale  # arc the contact crosses per position
        arc = np.maximum(moved, band)
        width = arc / scale
        out.append(_deposit(grid, u[on], width[on], volume[on] / arc[on]))
    # ripples shorter than the band are levelled (the elastic band bears on them as one, which
    # the rigid gap does not see): a Gaussian of the static band's half-width at the pitch
    R1_p, R2_p = geom.curvature_radii(np.array([0.0]))
    b_p = contact.hertz_half_width(force / g.face_width, contact.equivalent_radius(R1_p, R2_p),
                                   e_star)[0]
    sigma = b_p * geom.rb1 / R1_p[0] / (grid[1] - grid[0])
    return (ndimage.gaussian_filter1d(out[0], sigma, mode="nearest"),
            ndimage.gaussian_filter1d(out[1], sigma, mode="nearest") * g.z1 / g.z2)


def simulate_contact_wear(scn: Scenario, depth: float, cycles: float = math.inf,
                          stiffness: MeshStiffness | None = None) -> ContactWear:
    """Wear both flanks from new until the deepest point of either active profile reaches
    ``depth`` [m] (or ``cycles`` pinion cycles), in blocks that wear no point by more than
    ``solver.update_um`` or by ``RELATIVE_STEP`` of the deepest wear so far (module doc)."""
    if not (math.isfinite(depth) and depth > 0):
        raise ValueError(f"depth = {depth!r} must be a finite depth > 0 (m)")
    if not cycles > 0:
        raise ValueError(f"cycles = {cycles!r} must be > 0 (pinion cycles)")
    scn = check_scope(scn)
    ms = stiffness or mesh_stiffness(scn.gear, scn.material)
    grid = whole_flank_grid(ms)
    force = quasi_static_force(scn, ms.geometry)
    step = scn.solver.update_um * 1e-6
    active = (grid >= ms.geometry.s_start) & (grid <= ms.geometry.s_end)
    w1, w2 = np.zeros_like(grid), np.zeros_like(grid)
    done = 0.0
    ends, hist1, hist2 = [0.0], [w1], [w2]
    while done < cycles and max(w1[active].max(), w2[active].max()) < depth:
        r1, r2 = wear_per_cycle(scn, ms, grid, w1, w2, force)
        peak = max(r1.max(), r2.max())
        if peak <= 0:
            break
        allowed = max(step, RELATIVE_STEP * max(w1.max(), w2.max()))
        block = min(allowed / peak, cycles - done)
        w1, w2, done = w1 + r1 * block, w2 + r2 * block, done + block
        ends.append(done)
        hist1.append(w1)
        hist2.append(w2)
    return ContactWear(grid, w1, w2, done, active,
                       (np.array(ends), np.array(hist1), np.array(hist2)))
