"""Archard wear of pinion and gear flanks in mixed lubrication (thesis 2.6).

The local Archard law ``dh/ds = k p / H`` (thesis 2.6) is integrated over each flank point's pass
through the contact band. The band's pressure comes from the contact of the worn flanks, solved
with the wear depth as a gap (:mod:`physics.tribology.worn_contact`); a point of flank i slides
``|1 - v_j/v_i|`` of each unit of band it crosses, so the wear per pass is

    dh_i(point) = sum over the band's sweep of  k_eff p |1 - v_j / v_i| dx / H

(:meth:`~physics.tribology.worn_contact.WornContact.sweep`; Bajpai, Kahraman & Anderson,
J. Tribol. 126 (2004) 787-796). For an unworn band of constant conditions this is the thesis's
``k p_mean L_i / H`` with ``L_i = 2 b |1 - v_j/v_i|``; a gear tooth meshes ``z1/z2`` times per
pinion cycle.

``k_eff`` is the Archard coefficient on the total load:

- dry (thesis 2.7.5): ``k_eff = k_dry`` (``tribology.dry_wear_coeff``);
- mixed (thesis 2.6): ``k_eff = min(k_a L_a psi, k_dry)``, where ``L_a`` is the asperity share of
  the load (numerical mixed-EHL solver by default, or the Masjedi-Khonsari regression:
  ``tribology.asperity_model``), ``psi`` the oil-film deficiency coefficient (the share of
  asperity contacts left without an adsorbed film, :func:`film_deficiency`) and ``k_a``
  (``tribology.wear_coeff``) the Archard coefficient of those unprotected asperity contacts
  (calibrated once: :mod:`physics.tribology.calibration`). A share of the load cannot wear more
  than all of it: the lubricated coefficient never exceeds the dry one, and at full, unprotected
  asperity contact (``L_a = psi = 1``) it is the dry law;
- ``tribology.boundary_share`` b blends them: ``(1 - b)`` mixed ``+ b`` dry, for a gearbox that
  runs part of its time under boundary lubrication.

Wear is integrated in cycle blocks: each block is as long as it can be without any point of
either flank wearing more than ``solver.update_um``, after which the load sharing (with the wear
gap), the worn contact and every contact quantity are recomputed (thesis 2.6; Flodin &
Andersson, Wear 207 (1997) 16-23). The thesis's update of the radius of curvature
``R_new = R_old - h_w`` is replaced by the gap: ``docs/reproduction.md``.

Cycles count pinion revolutions throughout.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from physics.gear import contact, kinematics
from physics.gear.geometry import MeshGeometry, mesh_geometry
from physics.gear.load_sharing import PairStiffness, pair_loads
from physics.gear.stiffness import mesh_stiffness
from physics.params import R_GAS, Lubricant, OutOfScope, Scenario, Tribology
from physics.scope import check_scope, shakedown_pressure
from physics.tribology.asperity_table import check_scenario
from physics.tribology.contact_state import ContactState, solve_contact_state
from physics.tribology.worn_contact import (
    WornContact,
    band_reach,
    levelling_length,
    solve_worn_contact,
)

#: ``force(s, wear1, wear2) -> F [N]`` on the grid s: the total normal mesh force per mesh
#: position for the current worn profiles (the dynamic model supplies one; default quasi-static).
MeshForce = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
#: ``stiffness(s_grid, wear1, wear2) -> k(s)``: the pair stiffness along the path for the current
#: worn profiles (default: :meth:`physics.stiffness.MeshStiffness.pair_function`).
StiffnessModel = Callable[[np.ndarray, np.ndarray, np.ndarray], PairStiffness]


def film_deficiency(v_s: np.ndarray, T: np.ndarray, lub: Lubricant) -> np.ndarray:
    """Oil-film deficiency coefficient psi: the fraction of the surface left unprotected.

    ``psi = 1 - exp[ -(X / (v_s t0)) exp(-Ea / (R_g T)) ]`` (Stolarski, Tribol. Trans. 33 (1990)
    21-24; Kingsbury's adsorption model): the time a point spends sliding one molecule
    diameter, ``X / v_s``, over the residence time ``t0 exp(Ea / (R_g T))`` of an adsorbed
    molecule. The thesis prints ``1 - exp(-Ea/(R_g T)) exp(-X/(v_s t0))``, which equals 1 to
    machine precision at any gear speed and falls with temperature; see
    ``docs/reproduction.md``. At the pitch point (``v_s = 0``) psi is 1, where the sliding
    distance, and so the wear, is zero.
    """
    v_s = np.asarray(v_s, dtype=float)
    rate = np.exp(-lub.adsorption_heat_J_mol / (R_GAS * np.asarray(T, dtype=float)))
    with np.errstate(divide="ignore"):
        exponent = lub.molecular_diameter_m / (v_s * lub.vibration_time_s) * rate
    return -np.expm1(-exponent)


@dataclass(frozen=True)
class WearRate:
    """Wear per pinion cycle [m] with the state that produced it. ``flank1, flank2`` are on the
    flank grid, which reaches beyond the path of contact (``path`` picks the path's points);
    everything else is per mesh position on the path."""

    flank1: np.ndarray
    flank2: np.ndarray
    path: slice
    load: np.ndarray  # pair load [N]
    psi: np.ndarray
    coefficient: np.ndarray  # Archard coefficient on the total load, k_eff
    contact: WornContact  # pressure across the band of the worn flanks
    state: ContactState

    @property
    def pinion(self) -> np.ndarray:
        """Pinion wear per cycle at the path's points [m]."""
        return self.flank1[self.path]

    @property
    def gear(self) -> np.ndarray:
        """Gear wear per cycle at the path's points [m]."""
        return self.flank2[self.path]


def wear_coefficient(tri: Tribology, asperity_ratio: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Archard coefficient on the total load (module text): dry ``k_dry``; mixed
    ``min(k_a L_a psi, k_dry)``; blended by the boundary share."""
    if tri.regime == "dry":
        return np.full_like(np.asarray(psi, dtype=float), tri.dry_wear_coeff)
    mixed = np.minimum(tri.wear_coeff * asperity_ratio * psi, tri.dry_wear_coeff)
    b = tri.boundary_share
    return (1 - b) * mixed + b * tri.dry_wear_coeff


@dataclass(frozen=True)
class Flank:
    """Where the wear is tracked: ``grid``, the path's grid extended at both ends (``path`` picks
    the path's points), and ``level`` [m], the arc over which wear ripples are levelled
    (:func:`physics.tribology.worn_contact.levelling_length`); constants of the scenario."""

    grid: np.ndarray
    path: slice
    level: float


def flank_grid(scn: Scenario, geom: MeshGeometry, s: np.ndarray) -> Flank:
    """The flank of the scenario on the path's grid ``s``: extended, at its spacing, by the roll
    distance a band of twice the static load presses beyond the path's ends, within the
    involutes (:func:`physics.tribology.worn_contact.band_reach`); ripples levelled over half
    the smallest band of a pair carrying half the static load (the double-contact zones)."""
    R1, R2 = geom.curvature_radii(s)
    R = contact.equivalent_radius(R1, R2)
    e_star = contact.reduced_modulus(scn.material, scn.material)
    w = quasi_static_force(scn, geom) / scn.gear.face_width
    b = contact.hertz_half_width(2 * w, R, e_star)
    ds = s[1] - s[0]
    before, after = band_reach(b, R1, R2, geom.rb1, geom.rb2)
    n0, n1 = int(before // ds), int(after // ds)
    grid = np.concatenate([s[0] - np.arange(n0, 0, -1) * ds, s, s[-1] + np.arange(1, n1 + 1) * ds])
    return Flank(grid, slice(n0, n0 + s.size), levelling_length(0.5 * w, R, e_star))


def wear_rate(
    scn: Scenario, geom: MeshGeometry, s: np.ndarray, wear1: np.ndarray, wear2: np.ndarray,
    force: np.ndarray, stiffness: PairStiffness, flank: Flank,
) -> WearRate:
    """Wear depth per pinion cycle on both flanks for the current worn profiles (module doc).

    ``wear1, wear2`` [m] are on the flank's grid (:func:`flank_grid`)."""
    R1, R2 = geom.curvature_radii(s)  # the unworn involutes; the wear enters as a gap
    R = contact.equivalent_radius(R1, R2)
    v1, v2 = kinematics.surface_velocities(R1, R2, scn.operating.omega1, scn.gear.z1,
                                           scn.gear.z2)
    total = wear1[flank.path] + wear2[flank.path]

    def gap(x: np.ndarray) -> np.ndarray:
        return np.interp(x, s, total)

    load = pair_loads(geom, s, force, gap, stiffness)
    e_star = contact.reduced_modulus(scn.material, scn.material)
    band = solve_worn_contact(s, load / scn.gear.face_width, R1, R2, geom.rb1, geom.rb2, e_star,
                              flank.grid, wear1, wear2, flank.level)
    # the film forms in the inlet, whose geometry the involutes' curvature sets: the film, the
    # asperity share and the flash temperature are those of the band at the pair's load
    state = solve_contact_state(scn, load, R, v1, v2)
    tri = scn.tribology
    psi = (np.ones_like(s) if tri.regime == "dry"
           else film_deficiency(state.v_s, state.temperature, scn.lubricant))
    k_eff = wear_coefficient(tri, state.asperity_ratio, psi)
    slide = np.abs(v1 - v2)
    per_hardness = k_eff / scn.material.hardness
    pinion = band.sweep(s, flank.grid, R1 / geom.rb1, per_hardness * slide / v1)
    gear = band.sweep(s, flank.grid, R2 / geom.rb2, per_hardness * slide / v2) * (scn.gear.z1
                                                                                / scn.gear.z2)
    return WearRate(pinion, gear, flank.path, load, psi, k_eff, band, state)


@dataclass(frozen=True)
class WearResult:
    """Wear of both flanks on the roll-coordinate grid after ``cycles`` pinion cycles."""

    geometry: MeshGeometry
    s: np.ndarray  # roll coordinate [m]
    pinion: np.ndarray  # wear depth [m]
    gear: np.ndarray
    cycles: float
    blocks: int  # profile updates performed
    first_rate: WearRate  # rate and contact state of the unworn profile
    last_rate: WearRate  # rate and contact state of the final profile
    snapshots: dict[float, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    #: every block's end (and the start): cycles ``(k,)``, pinion and gear wear ``(k, n)`` [m].
    #: Within a block the explicit update wears every point linearly in cycles, so linear
    #: interpolation between these rows is the run's own wear at any cycle count
    history: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    @property
    def double(self) -> np.ndarray:
        return self.geometry.is_double(self.s)

    def mean_depth(self, side: str = "pinion") -> float:
        """Mean wear depth over the active flank, in the roll coordinate [m]."""
        h = getattr(self, side)
        return float(np.trapezoid(h, self.s) / (self.s[-1] - self.s[0]))

    def worn_area(self, side: str = "pinion") -> float:
        """Worn area of the flank section, ``integral h ds`` [m^2] (volume per unit width)."""
        return float(np.trapezoid(getattr(self, side), self.s))


def check_shakedown(p_max: np.ndarray, s: np.ndarray, limit: float, w1: np.ndarray,
                    w2: np.ndarray, cycles: float) -> None:
    """Raise :class:`OutOfScope` when the largest contact pressure on the current (worn) flanks,
    from the worn contact's pressure field, passes the shakedown ``limit`` [Pa]
    (:func:`physics.scope.shakedown_pressure`), naming where and when."""
    p_max = np.nan_to_num(np.asarray(p_max, dtype=float), nan=0.0)
    at = int(np.argmax(p_max))
    if p_max[at] > limit:
        deepest = max(w1.max(), w2.max()) * 1e6
        raise OutOfScope(
            f"after {cycles:.3g} cycles the worn flanks (deepest wear {deepest:.0f} um) carry a "
            f"contact pressure of {p_max[at] / 1e9:.2f} GPa at roll coordinate "
            f"{s[at] * 1e3:+.2f} mm from the pitch point, above the {limit / 1e9:.2f} GPa "
            "shakedown limit of rolling contact: the flank would yield at every cycle; the wear "
            "model is outside its scope")


def quasi_static_force(scn: Scenario, geom: MeshGeometry) -> float:
    """Static normal mesh force ``F_n = T_2 / r_b2`` [N] (thesis 2.2)."""
    return scn.operating.torque_Nm / geom.rb2


#: largest rise of any position's peak pressure over its Hertz pressure in one block before
#: the block is redone with half the wear step
PRESSURE_STEP = 0.25
#: shortest step, as a share of ``solver.update_um``, that step control may reach
MIN_UPDATE = 1 / 64


def _overshoots(old: WornContact, new: WornContact) -> bool:
    """Whether a block raised some band's peak pressure, over the Hertz pressure of its own
    load, by more than ``PRESSURE_STEP``: the sign of a step too long for the wear's levelling
    of the flank, which an explicit update must resolve (it shrinks the step; it does not
    change the converged wear, see ``tests/tribology/test_wear.py``). A change of the load
    alone (the dynamic force, the load sharing) moves the Hertz pressure with it and is not
    counted."""
    # bands that carry a real share of the load in both states (a pair shedding its load to
    # the wear gap, or taking it up, changes its band's shape without any instability)
    w_old, w_new = old.p_hertz * old.half_width, new.p_hertz * new.half_width
    loaded = (w_old > 0.1 * w_old.max()) & (w_new > 0.1 * w_new.max())
    rise = new.peak_ratio - old.peak_ratio
    return bool(np.max(rise[loaded], initial=0.0) > PRESSURE_STEP)


def simulate_wear(
    scn: Scenario,
    cycles: float,
    force: MeshForce | None = None,
    stiffness: StiffnessModel | None = None,
    snapshots: Sequence[float] = (),
    until: Callable[[np.ndarray, np.ndarray], bool] | None = None,
) -> WearResult:
    """Integrate flank wear over ``cycles`` pinion cycles (thesis 2.6).

    Parameters
    ----------
    scn : Scenario
        The scenario; validated on construction.
    cycles : float
        Pinion load cycles, >= 0.
    force : MeshForce, optional
        Mesh force per mesh position for the current profiles; quasi-static by default
        (:func:`quasi_static_force`, ``F_n = T_2 / r_b2``: thesis 2.2).
    stiffness : StiffnessModel, optional
        Pair stiffness along the path for the current wear; by default the potential-energy
        stiffness of the worn teeth, recomputed at every profile update.
    snapshots : sequence of float
        Cycle counts at which the wear profiles are also recorded (block ends land on them
        exactly).
    until : callable, optional
        ``until(cycles, pinion)`` of the block ends so far (``(k,)`` and ``(k, n)`` [m]); the
        run ends after the first block at which it is true (``cycles`` is then the most it may
        run). Without snapshots, the blocks do not depend on where the run ends: a longer run's
        history begins with a shorter one's.

    Returns
    -------
    WearResult
        Pinion and gear wear depth [m] on the roll-coordinate grid of the path of contact, the
        cycles run, the blocks taken, the wear rates of the first and last profiles, the
        snapshots and the history of every block's end.

    Raises
    ------
    ValueError
        For ``cycles`` negative or not finite, snapshots outside ``[0, cycles]``, a mesh force
        of the wrong shape or with negative or non-finite values, or a scenario outside the
        model's scope from the start (:mod:`physics.scope`).
    OutOfScope
        When a run leaves the model's scope (a tooth worn through, a worn flank past the
        shakedown limit, the mixed-EHL table's range exceeded), carrying the accepted blocks as
        ``err.history``: ``(s, cycles, pinion, gear)``, the grid and
        :attr:`WearResult.history`, the wear as far as the model can follow it.

    Notes
    -----
    Each block wears the fastest point by at most ``solver.update_um``; a block after which some
    band's peak pressure rose by more than ``PRESSURE_STEP`` of its Hertz pressure is redone at
    half the step (step control: the explicit update would otherwise overshoot the wear's own
    levelling of the flank), and the step grows back by half after each accepted block.

    Examples
    --------
    A short run of the thesis baseline (case 3, quasi-static load): 1e5 pinion cycles wear
    the flanks by a few hundredths of a micrometre, deepest near the pinion root, in the first
    double-tooth zone (between the start of contact and the single-tooth zone), where the
    sliding is fast; at the pitch point, where the sliding speed is zero
    (:func:`physics.gear.kinematics.sliding_velocity`), the flank hardly wears:

    >>> from physics.params import Scenario
    >>> res = simulate_wear(Scenario(), 1e5)
    >>> res.cycles
    100000.0
    >>> deepest = float(res.pinion.max())
    >>> 1e-9 < deepest < 1e-7  # [m]
    True
    >>> s_max = float(res.s[np.argmax(res.pinion)])  # roll coordinate of the deepest wear
    >>> bool(res.geometry.s_start <= s_max < res.geometry.single_zone[0] < 0)
    True
    >>> i0 = int(np.argmin(np.abs(res.s)))  # the grid point nearest the pitch point
    >>> bool(res.pinion[i0] < 0.05 * deepest)
    True
    """
    if not (isinstance(cycles, int | float) and np.isfinite(cycles) and cycles >= 0):
        raise ValueError(f"cycles = {cycles!r} must be a finite number >= 0 (pinion cycles)")
    marks = sorted({float(c) for c in snapshots})
    if marks and (marks[0] < 0 or marks[-1] > cycles):
        raise ValueError(f"snapshots {marks} must lie in [0, cycles = {cycles:g}]")
    check_scenario(check_scope(scn))
    geom = mesh_geometry(scn.gear)
    s = geom.grid(scn.solver.n_points)
    if force is None:
        f_static = quasi_static_force(scn, geom)

        def force(s: np.ndarray, _w1: np.ndarray, _w2: np.ndarray) -> np.ndarray:
            return np.full_like(s, f_static)

    if stiffness is None:
        stiffness = mesh_stiffness(scn.gear, scn.material).pair_function

    step = scn.solver.update_um * 1e-6
    limit = shakedown_pressure(scn.material.hardness)
    flank = flank_grid(scn, geom, s)
    path = flank.path

    def rate_at(f1: np.ndarray, f2: np.ndarray) -> WearRate:
        w1, w2 = f1[path], f2[path]
        f = np.asarray(force(s, w1, w2), dtype=float)
        if f.shape != s.shape or not np.all(np.isfinite(f)) or np.any(f < 0):
            raise ValueError(
                f"mesh force has shape {f.shape} (grid {s.shape}) or non-finite/negative values; "
                "give one force per grid point, finite and >= 0 [N]")
        return wear_rate(scn, geom, s, f1, f2, f, stiffness(s, w1, w2), flank)

    f1, f2 = np.zeros_like(flank.grid), np.zeros_like(flank.grid)  # wear on the flank grid
    done, blocks, taken, pending = 0.0, 0, {}, list(marks)
    ends, wear1, wear2 = [done], [f1[path].copy()], [f2[path].copy()]
    try:
        rate = first = rate_at(f1, f2)
        check_shakedown(rate.contact.p_max, s, limit, f1[path], f2[path], done)
        allowed = step
        while True:
            while pending and pending[0] <= done:
                taken[pending.pop(0)] = (f1[path].copy(), f2[path].copy())
            if done >= cycles or (blocks and until is not None
                                  and until(np.array(ends), np.array(wear1))):
                break
            peak = max(rate.flank1.max(), rate.flank2.max())
            block = cycles - done if peak <= 0 else min(cycles - done, allowed / peak)
            if pending:
                block = min(block, pending[0] - done)
            n1, n2 = f1 + rate.flank1 * block, f2 + rate.flank2 * block
            end = cycles if cycles - (done + block) <= 1e-9 * cycles else done + block
            new = rate_at(n1, n2)
            if _overshoots(rate.contact, new.contact) and peak * block > MIN_UPDATE * step:
                allowed = 0.5 * min(allowed, peak * block)  # redo the block, shorter
                continue
            f1, f2, rate, done = n1, n2, new, end
            check_shakedown(rate.contact.p_max, s, limit, f1[path], f2[path], done)
            allowed = min(step, 1.5 * allowed)
            blocks += 1
            ends.append(done)
            wear1.append(f1[path].copy())
            wear2.append(f2[path].copy())
    except OutOfScope as err:  # the wear as far as the model follows it
        err.history = (s, np.array(ends), np.array(wear1), np.array(wear2))
        raise
    w1, w2 = f1[path], f2[path]
    return WearResult(geom, s, w1, w2, float(done), blocks, first, rate, taken,
                      (np.array(ends), np.array(wear1), np.array(wear2)))
