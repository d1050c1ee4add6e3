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

Each tooth its own flank: a state carries one flank per tooth of a wheel, in mesh order, or
one flank for teeth alike (the uniform state, the special case, to the last digit). The pairs
pass the mesh in the meshing sequence (:mod:`physics.gear.mesh_sequence`; the hunting period
``lcm(z1, z2)`` meshes when both wheels carry every tooth), each with the rigid gaps and the
compliance of its own two teeth and, where a tooth stands off its theoretical place (a single
pitch deviation, :func:`physics.gear.accuracy.tooth_positions_um`), its gaps closed by that much;
the load at each position is shared among the pairs then in mesh, and each contact wears the two
teeth it joins. A tooth ahead carries more, wears faster, and so wears its lead away: Archard
wear levels the teeth (``tests/tribology/test_tooth_wear.py``). A gear whose teeth are carried
alike while the pinion's differ is their mean over the hunting period: exact where ``gcd(z1,
z2) = 1`` and the gear's teeth start alike and stand in their places (every gear tooth meets
every pinion tooth in turn), an approximation otherwise.

Where a tooth truly fails, the run ends and says where and when: a tooth worn to its centre
line, or one thinned until its root stress under the quasi-static load passes the root fatigue
strength (:mod:`physics.gear.tooth_bending`). What it leaves out, said where it matters: the
pressure across the band of a worn contact (a Hertz band of the involutes' radii; the wear per
pass does not depend on its shape, its peak does: no shakedown check here), the dynamic load
(quasi-static mesh force), and wear of the coast flanks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from physics.gear import contact, kinematics
from physics.gear.accuracy import POSITION_BOUND_FP, position_bound_m
from physics.gear.mesh_sequence import meshing_sequence
from physics.gear.stiffness import MeshStiffness, mesh_stiffness
from physics.gear.tooth_bending import check_root_strength
from physics.gear.tooth_contact import (
    NO_CONTACT,
    PairGaps,
    clamped,
    flank_coordinate,
    pair_slots,
    share_load,
)
from physics.params import OutOfScope, Scenario
from physics.scope import ROOT_STRENGTH, check_scope
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
    """Wear of both flanks on the roll grid ``s`` (the whole involute of each flank), one row
    per carried tooth (:class:`physics.gear.mesh_sequence.MeshSequence`: every tooth, or one
    row for teeth alike)."""

    s: np.ndarray  # [m]
    pinion: np.ndarray  # wear depth (pinion teeth carried, grid) [m]
    gear: np.ndarray  # (gear teeth carried, grid) [m]
    cycles: float
    active: np.ndarray  # bool: the grid's points on the theoretical path (the active profiles)
    #: every block's end (and the start): cycles ``(k,)``, pinion and gear wear ``(k, teeth,
    #: grid)`` [m]
    history: tuple[np.ndarray, np.ndarray, np.ndarray]

    def deepest(self) -> np.ndarray:
        """Deepest wear of any tooth's active profile, either wheel, at each block end [m]."""
        _, p, g = self.history
        return np.maximum(p[:, :, self.active].max(axis=(1, 2)),
                          g[:, :, self.active].max(axis=(1, 2)))

    def at_depth(self, depth: float) -> tuple[np.ndarray, np.ndarray, float]:
        """Pinion and gear wear [m] (teeth, grid) and cycles when the deepest point of any active
        profile first reached ``depth`` [m] (linear between block ends: each block wears
        linearly)."""
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
    width / 2`` (each conserves its volume, ``depth * width``, wherever it lands inside the
    grid's cells). A deposit fills the cells it spans and parts of the two it ends in: those
    parts by where it ends, the cells between by a running sum of the deposits entering and
    leaving, in time linear in the deposits (not cells times deposits)."""
    step, cells = grid[1] - grid[0], grid.size
    edges = np.concatenate([grid - 0.5 * step, [grid[-1] + 0.5 * step]])
    lo = np.clip(centre - 0.5 * width, edges[0], edges[-1])
    hi = np.clip(centre + 0.5 * width, edges[0], edges[-1])
    first = np.clip(np.searchsorted(edges, lo, side="right") - 1, 0, cells - 1)
    last = np.clip(np.searchsorted(edges, hi, side="right") - 1, 0, cells - 1)
    one = first == last
    volume = np.bincount(first, depth * np.where(one, hi - lo, edges[first + 1] - lo), cells)
    apart = ~one  # deposits over two cells or more: their last cell's part, the cells between
    start, end, d = first[apart], last[apart], depth[apart]
    volume += np.bincount(end, d * (hi[apart] - edges[end]), cells)
    between = np.bincount(start + 1, d, cells + 1) - np.bincount(end, d, cells + 1)
    volume += np.cumsum(between)[:cells] * np.diff(edges)
    return np.maximum(volume, 0.0) / step  # (rounding leaves -1e-26 where none)


def tooth_wear_per_cycle(scn: Scenario, ms: MeshStiffness, grid: np.ndarray, wear1: np.ndarray,
                         wear2: np.ndarray, force: float,
                         positions: tuple[np.ndarray, np.ndarray] | None = None
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Wear per pinion cycle [m] of each carried tooth, ``(n1, grid)`` and ``(n2, grid)``, for
    teeth worn by ``wear1`` ``(n1, grid)`` and ``wear2`` ``(n2, grid)`` (each wheel one row per
    tooth, in mesh order, or one row for teeth alike) under the normal mesh force ``force``
    [N] (module doc), along the meshing sequence
    (:func:`physics.gear.mesh_sequence.meshing_sequence`).

    Each pair of the sequence passes the mesh with its own rigid gaps and compliance; at each
    position the load is shared among the pairs then in mesh (the one before its entry, the one
    last entered, the two ahead), each with its own teeth; each contact wears the two teeth it
    joins. ``positions``: each carried tooth's position deviation along the line of action [m]
    (ahead of its place towards the mating flank: positive), ``(n1,)`` and ``(n2,)``; a tooth
    ahead meets its mate by that much earlier, so every gap of its pairs is that much smaller
    (:func:`physics.gear.accuracy.tooth_positions_um` draws them)."""
    geom, g, op = ms.geometry, scn.gear, scn.operating
    seq = meshing_sequence(g.z1, g.z2, len(wear1), len(wear2))
    n, slot = len(seq), np.arange(4)
    # a pair's pass through the mesh, in order of roll: the four slots of pair_slots in turn
    passage = pair_slots(geom, geom.mesh_period(POSITIONS)[0]).T.ravel()
    pairs, index = seq.distinct_pairs(wear1, wear2)  # each distinct pair's flanks once
    gap, u1, u2, k = (np.empty((len(pairs), passage.size)) for _ in range(4))
    for d, (i, j) in enumerate(pairs):
        gap[d], u1[d], u2[d] = PairGaps(geom, ms.forms, grid, wear1[i], wear2[j]).contacts(passage)
        k[d] = ms.pair_function(grid, wear1[i], wear2[j])(clamped(geom, passage))
    gap, u1, u2, k = gap[index], u1[index], u2[index], k[index]
    if positions is not None:
        ahead = positions[0][seq.pinion] + positions[1][seq.gear]
        gap = np.where(gap < NO_CONTACT, gap - ahead[:, None], gap)
    # in mesh k, slot q holds the pair of mesh k + 1 - q (pair_slots: the one about to enter
    # first); its load there is the pair's at slot q of its passage
    into_mesh = (np.arange(n)[:, None] + 1 - slot) % n  # (mesh, slot) -> pair
    cells = (n, 4, POSITIONS)

    def by_mesh(x: np.ndarray) -> np.ndarray:  # (pair, passage) -> (mesh x position, slot)
        return x.reshape(cells)[into_mesh, slot].transpose(0, 2, 1).reshape(-1, 4)

    _, shared = share_load(by_mesh(gap), by_mesh(k), force)
    from_mesh = (np.arange(n)[:, None] - 1 + slot) % n  # (pair, slot) -> mesh
    load = shared.reshape(n, POSITIONS, 4).transpose(0, 2, 1)[from_mesh, slot].reshape(n, -1)
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
    # ripples shorter than the band are levelled (the elastic band bears on them as one, which
    # the rigid gap does not see): a Gaussian of the static band's half-width at the pitch
    R1_p, R2_p = geom.curvature_radii(np.array([0.0]))
    b_p = contact.hertz_half_width(force / g.face_width, contact.equivalent_radius(R1_p, R2_p),
                                   e_star)[0]
    sigma = b_p * geom.rb1 / R1_p[0] / (grid[1] - grid[0])
    out = []
    for u, R, rb, fillet, teeth, carried, (num, den) in (
            (u1, R1, geom.rb1, u1 < low1, seq.pinion, len(wear1), seq.per_pinion_cycle()[0]),
            (u2, R2, geom.rb2, u2 > low2, seq.gear, len(wear2), seq.per_pinion_cycle()[1])):
        # arc per unit of the flank coordinate: R / r_b on the involute (dl = R du / r_b), 1 on
        # the fillet (its coordinate is its arc)
        scale = np.where(fillet, 1.0, R / rb)
        moved = np.abs(np.gradient(u, axis=1)) * scale  # arc the contact crosses per position
        arc = np.maximum(moved, band)
        width = arc / scale
        rate = np.empty((carried, grid.size))
        for tooth in range(carried):
            mine = on & (teeth == tooth)[:, None]  # the contacts of this tooth's pairs
            rate[tooth] = _deposit(grid, u[mine], width[mine], volume[mine] / arc[mine])
        out.append(ndimage.gaussian_filter1d(rate, sigma, axis=1, mode="nearest") * num / den)
    return out[0], out[1]


def wear_per_cycle(scn: Scenario, ms: MeshStiffness, grid: np.ndarray, wear1: np.ndarray,
                   wear2: np.ndarray, force: float) -> tuple[np.ndarray, np.ndarray]:
    """Pinion and gear wear per pinion cycle [m] on ``grid`` for the flanks worn by ``wear1,
    wear2`` under the normal mesh force ``force`` [N], every tooth alike
    (:func:`tooth_wear_per_cycle` with one tooth per wheel)."""
    r1, r2 = tooth_wear_per_cycle(scn, ms, grid, np.asarray(wear1)[None], np.asarray(wear2)[None],
                                  force)
    return r1[0], r2[0]


def simulate_contact_wear(scn: Scenario, depth: float, cycles: float = math.inf,
                          stiffness: MeshStiffness | None = None,
                          start: tuple[np.ndarray, np.ndarray] | None = None,
                          positions: tuple[np.ndarray, np.ndarray] | None = None
                          ) -> ContactWear:
    """Wear both flanks until the deepest point of any tooth's active profile reaches ``depth``
    [m] (or ``cycles`` pinion cycles), in blocks that wear no point by more than
    ``solver.update_um`` or by ``RELATIVE_STEP`` of the deepest wear so far (module doc).

    Every tooth alike from new by default. ``start``: the wear to start from, pinion and gear,
    on :func:`whole_flank_grid` [m], each None (new), ``(grid,)`` for teeth alike or ``(z,
    grid)`` with a row per tooth in mesh order (a tooth worn ahead of the rest, damage induced
    on one); ``positions``: each tooth's position deviation [m] (:func:`tooth_wear_per_cycle`),
    ``(z1,)`` and ``(z2,)``, each or None, which makes every tooth of that wheel its own. A
    wheel given neither stays one row.

    A tooth whose root stress at its highest point of single-tooth contact passes the root
    fatigue strength (:func:`physics.gear.tooth_bending.check_root_strength`) ends the run with
    :class:`physics.params.OutOfScope` naming the tooth, the section and the cycles; a contact
    the wear law cannot take (a film parameter outside the mixed-EHL table) with the cycles and
    the depth reached."""
    if not (math.isfinite(depth) and depth > 0):
        raise ValueError(f"depth = {depth!r} must be a finite depth > 0 (m)")
    if not cycles > 0:
        raise ValueError(f"cycles = {cycles!r} must be > 0 (pinion cycles)")
    scn = check_scope(scn)
    ms = stiffness or mesh_stiffness(scn.gear, scn.material)
    grid = whole_flank_grid(ms)
    w1, w2, positions = _tooth_state(scn, grid, start, positions)
    force = quasi_static_force(scn, ms.geometry)
    step = scn.solver.update_um * 1e-6
    active = (grid >= ms.geometry.s_start) & (grid <= ms.geometry.s_end)
    done = 0.0
    ends, hist1, hist2 = [0.0], [w1], [w2]
    while done < cycles and max(w1[:, active].max(), w2[:, active].max()) < depth:
        try:
            r1, r2 = tooth_wear_per_cycle(scn, ms, grid, w1, w2, force, positions)
        except OutOfScope as err:  # the worn flanks' contact: said with when and how deep
            deepest = max(w1[:, active].max(), w2[:, active].max()) * 1e6
            raise OutOfScope(f"after {done:.3g} cycles (deepest wear {deepest:.0f} um): "
                             f"{err}") from None
        peak = max(r1.max(), r2.max())
        if peak <= 0:
            break
        allowed = max(step, RELATIVE_STEP * max(w1.max(), w2.max()))
        block = min(allowed / peak, cycles - done)
        w1, w2, done = w1 + r1 * block, w2 + r2 * block, done + block
        check_root_strength(ms, grid, w1, w2, force, ROOT_STRENGTH, done)
        ends.append(done)
        hist1.append(w1)
        hist2.append(w2)
    return ContactWear(grid, w1, w2, done, active,
                       (np.array(ends), np.array(hist1), np.array(hist2)))


def _tooth_state(scn: Scenario, grid: np.ndarray, start, positions
                 ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray] | None]:
    """The starting wear ``(n1, grid)``, ``(n2, grid)`` and the positions of
    :func:`simulate_contact_wear`, checked: ``ValueError`` naming the argument, its shape or
    value, the rule and the fix, before any work. A wheel carries a row per tooth where its
    positions or its start give one, else one row."""
    g = scn.gear
    z = (g.z1, g.z2)
    names = ("pinion", "gear")
    for what, given in (("positions", positions), ("start", start)):
        if given is not None and (not isinstance(given, tuple | list) or len(given) != 2):
            got = (f"{len(given)} parts" if isinstance(given, tuple | list)
                   else f"a {type(given).__name__}")
            raise ValueError(f"{what} has {got}; give a pair (pinion, gear), each None or an "
                             "array")
    wear, shift = [], []
    for w in range(2):
        p = None if positions is None else positions[w]
        try:
            h = (np.zeros(grid.size) if start is None or start[w] is None
                 else np.asarray(start[w], dtype=float))
        except (TypeError, ValueError) as e:
            raise ValueError(f"start wear of the {names[w]} is no array of depths "
                             f"({type(start[w]).__name__}); give depths >= 0 [m] on "
                             "whole_flank_grid") from e
        try:
            p = None if p is None else np.asarray(p, dtype=float)
        except (TypeError, ValueError) as e:
            raise ValueError(f"positions of the {names[w]} are no numbers; give {z[w]} "
                             "deviations [m], one per tooth in mesh order, or None") from e
        rows = z[w] if p is not None or h.shape == (z[w], grid.size) else 1
        if p is not None:
            if p.shape != (z[w],) or not np.all(np.isfinite(p)):
                raise ValueError(f"positions of the {names[w]} of shape {p.shape}: give "
                                 f"{z[w]} finite deviations [m], one per tooth in mesh "
                                 "order, or None")
            limit = position_bound_m(g.module_mm, g.module_mm * z[w])
            if np.max(np.abs(p)) > limit:
                raise ValueError(f"positions of the {names[w]} reach {np.max(np.abs(p)):g} m, "
                                 f"beyond the {limit:.3g} m of {POSITION_BOUND_FP:g} F_p of "
                                 "ISO 1328-1's coarsest grade; give them in metres (1e-6 x "
                                 "tooth_positions_um)")
        if h.shape == grid.shape:
            h = np.broadcast_to(h, (rows, grid.size))
        if h.shape != (rows, grid.size):
            raise ValueError(f"start wear of the {names[w]} of shape {h.shape}: give "
                             f"{grid.size} depths on whole_flank_grid for teeth alike, or "
                             f"({z[w]}, {grid.size}), a row per tooth in mesh order")
        if not np.all(np.isfinite(h)) or np.any(h < 0):
            raise ValueError(f"start wear of the {names[w]} holds a depth that is negative or "
                             "not finite; give depths >= 0 [m]")
        wear.append(np.array(h, dtype=float))
        shift.append(np.zeros(rows) if p is None else p)
    return wear[0], wear[1], None if positions is None else (shift[0], shift[1])
