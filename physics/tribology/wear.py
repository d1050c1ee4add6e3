"""Archard wear of pinion and gear flanks in mixed lubrication (thesis 2.6).

Local Archard law ``dh/ds = k p / H`` applied to the asperity share of the pressure. A flank point
of the pinion crosses the Hertz band once per pinion revolution and slides ``L1 = 2b|1 - v2/v1|``
against the gear; integrating the law over the band gives the wear per pass

    dh1 = k psi L_a p_mean L1 / H        (per pinion cycle)
    dh2 = (z1/z2) k psi L_a p_mean L2 / H (a gear tooth meshes z1/z2 times per pinion cycle)

with ``p_mean = w / (2b)``, ``L_a`` the fraction of the load carried by asperities (from the
numerical mixed-EHL solver by default, or the Masjedi-Khonsari regression: ``tribology.
asperity_model``, see :mod:`physics.tribology.contact_state`) and ``psi`` the oil-film
deficiency coefficient; ``k`` is ``tribology.wear_coeff`` (calibrated, see
:class:`physics.params.Tribology`). The dry mode (thesis 2.7.5) uses ``L_a = psi = 1`` and the
dry coefficient; ``tribology.boundary_share`` b blends the two laws, ``(1 - b)`` lubricated
``+ b`` dry, for a gearbox that runs part of its time under boundary lubrication. Wear is
integrated in cycle blocks: each block is as long as it can be without any point of either
flank wearing more than ``solver.update_um``, after which the profile (radii of
curvature ``R_new = R_old - h_w`` and the wear gap of the load sharing) and every contact quantity
are recomputed (thesis 2.6; Flodin & Andersson, Wear 207 (1997) 16-23).

Cycles count pinion revolutions throughout.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from physics.gear import kinematics
from physics.gear.geometry import MeshGeometry, mesh_geometry
from physics.gear.load_sharing import PairStiffness, pair_loads
from physics.gear.stiffness import MeshStiffness
from physics.params import R_GAS, Lubricant, OutOfScope, Scenario
from physics.scope import check_scope, shakedown_pressure
from physics.tribology.asperity_table import check_scenario
from physics.tribology.contact_state import ContactState, solve_contact_state

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
    """Wear per pinion cycle [m] at each grid point, with the state that produced it."""

    pinion: np.ndarray
    gear: np.ndarray
    load: np.ndarray  # pair load [N]
    psi: np.ndarray
    state: ContactState


def wear_rate(
    scn: Scenario, geom: MeshGeometry, s: np.ndarray, wear1: np.ndarray, wear2: np.ndarray,
    force: np.ndarray, stiffness: PairStiffness,
) -> WearRate:
    """Wear depth per pinion cycle on both flanks for the current worn profiles (module doc)."""
    R1, R2 = geom.curvature_radii(s)
    # rolling velocities follow the (unchanged) base-circle kinematics; the worn flank's radius
    # of curvature is the involute's minus the wear depth (thesis 2.6: R_new = R_old - h_w)
    v1, v2 = kinematics.surface_velocities(R1, R2, scn.operating.omega1, scn.gear.z1,
                                           scn.gear.z2)
    total = wear1 + wear2

    def gap(x: np.ndarray) -> np.ndarray:
        return np.interp(x, s, total)

    load = pair_loads(geom, s, force, gap, stiffness)
    state = solve_contact_state(scn, load, R1 - wear1, R2 - wear2, v1, v2)
    L1, L2 = kinematics.sliding_distances(state.half_width, state.v1, state.v2)
    tri = scn.tribology
    if tri.regime == "dry":
        k, psi = tri.dry_wear_coeff, np.ones_like(s)
        share = np.ones_like(s)
    else:
        k, psi = tri.wear_coeff, film_deficiency(state.v_s, state.temperature, scn.lubricant)
        share = state.asperity_ratio * psi
        if tri.boundary_share:  # time under boundary lubrication wears by the dry law
            b = tri.boundary_share
            k, share = 1.0, (1 - b) * tri.wear_coeff * share + b * tri.dry_wear_coeff
    base = k * share * state.p_mean / scn.material.hardness
    return WearRate(base * L1, base * L2 * scn.gear.z1 / scn.gear.z2, load, psi, state)


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


def check_shakedown(state: ContactState, limit: float, w1: np.ndarray, w2: np.ndarray,
                    cycles: float) -> None:
    """Raise :class:`OutOfScope` when the largest Hertz pressure on the current (worn) flanks
    passes the shakedown ``limit`` [Pa] (:func:`physics.scope.shakedown_pressure`)."""
    p, deepest = float(np.nanmax(state.p_max)), max(w1.max(), w2.max()) * 1e6
    if p > limit:
        raise OutOfScope(
            f"after {cycles:.3g} cycles the worn flanks (deepest wear {deepest:.0f} um) carry a "
            f"Hertz pressure of {p / 1e9:.2f} GPa, above the {limit / 1e9:.2f} GPa "
            "shakedown limit of rolling contact: the flank would yield at every cycle; the wear "
            "model is outside its scope")


def quasi_static_force(scn: Scenario, geom: MeshGeometry) -> float:
    """Static normal mesh force ``F_n = T_2 / r_b2`` [N] (thesis 2.2)."""
    return scn.operating.torque_Nm / geom.rb2


def simulate_wear(
    scn: Scenario,
    cycles: float,
    force: MeshForce | None = None,
    stiffness: StiffnessModel | None = None,
    snapshots: Sequence[float] = (),
) -> WearResult:
    """Integrate flank wear over ``cycles`` pinion cycles (thesis 2.6).

    Parameters
    ----------
    scn : the scenario; validated on construction.
    cycles : pinion load cycles, >= 0.
    force : mesh force per mesh position for the current profiles; quasi-static by default.
    stiffness : pair stiffness along the path for the current wear; by default the potential-
        energy stiffness of the worn teeth, recomputed at every profile update.
    snapshots : cycle counts at which the wear profiles are also recorded (block ends land on
        them exactly).
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
        stiffness = MeshStiffness(scn.gear, scn.material).pair_function

    step = scn.solver.update_um * 1e-6
    limit = shakedown_pressure(scn.material.hardness)
    w1, w2 = np.zeros_like(s), np.zeros_like(s)
    done, blocks, taken = 0.0, 0, {}
    pending = list(marks)
    first = None
    while True:
        while pending and pending[0] <= done:
            taken[pending.pop(0)] = (w1.copy(), w2.copy())
        f = np.asarray(force(s, w1, w2), dtype=float)
        if f.shape != s.shape or not np.all(np.isfinite(f)) or np.any(f < 0):
            raise ValueError(
                f"mesh force has shape {f.shape} (grid {s.shape}) or non-finite/negative values; "
                "give one force per grid point, finite and >= 0 [N]")
        rate = wear_rate(scn, geom, s, w1, w2, f, stiffness(s, w1, w2))
        first = first or rate
        check_shakedown(rate.state, limit, w1, w2, done)
        if done >= cycles:
            break
        peak = max(rate.pinion.max(), rate.gear.max())
        block = cycles - done if peak <= 0 else min(cycles - done, step / peak)
        if pending:
            block = min(block, pending[0] - done)
        w1, w2 = w1 + rate.pinion * block, w2 + rate.gear * block
        done = cycles if cycles - (done + block) <= 1e-9 * cycles else done + block
        blocks += 1
    return WearResult(geom, s, w1, w2, float(cycles), blocks, first, rate, taken)
