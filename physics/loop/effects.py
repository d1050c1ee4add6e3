"""The effect library: physical effects the declared model leaves out, each switchable.

The declared model is the torsional pair of :mod:`physics.dynamics` with its calibrated nuisance
parameters (damping ratio, pinion run-out, profile error) and the declared measurement chain of
:mod:`physics.measurement` (DTE on the line of action; rigid-housing acceleration with the
calibrated effective mass ``m_h``). Each effect below is off by default and acts either on the
dynamic model (before integration) or on the measurement chain (after it), never as a fit of the
output. Its physical signature says where the loop will see it.

=================  =========  =====================================================================
effect             acts on    signature
=================  =========  =====================================================================
gear_runout        dynamics   radial run-out of the gear (eccentricity = half of it): a kinematic
                              error at ``f_2`` on the line of action, a centre-distance change
                              that shifts the start of contact once per gear revolution, and the
                              mesh stiffness modulated as the pinion's run-out modulates it (its
                              calibrated depth per unit eccentricity,
                              :func:`physics.dynamics.model_form.with_modulation`);
                              sidebands ``k f_m +- f_2``, strongest at the harmonics near the
                              mesh resonance (the pinion's run-out is declared and calibrated)
friction           dynamics   Coulomb sliding friction ``mu`` reversing at the pitch point: a
                              force factor on each pair (moment arms of the friction force about
                              both centres, Vaishya & Singh, JSV 248 (2001) 671) that changes the
                              mesh harmonics, the 2nd and 3rd most
tip_relief         dynamics   linear tip relief ``C_a`` of both gears over the double-contact
                              zones (long relief): lower mesh harmonics at and below design load
tooth_defect       dynamics   a pit or spall of depth ``d`` on one pinion tooth over a share ``s``
                              of its face and a length ``l`` of its profile, all three fitted
                              (material loss as separation, stiffness lowered by ``s``; a
                              shallow wide spall and a deep narrow pit differ in how much of
                              each they make, ``l`` in how sharp their impulse is): once per
                              pinion revolution, a family of pinion sidebands
                              ``k f_m +- j f_1``, raised kurtosis of the synchronous-average
                              residual
transfer_path      measure    a structural mode (``f_n``, ``zeta`` 0.01-0.1, residue ``g``
                              -1 to 1) between mesh and accelerometer, the rigid path plus the
                              mode's accelerance (``g = 1``: a sensor on a base-excited
                              sub-structure, the band above ``f_n`` cut; ``g < 0``: a housing
                              mode beside the rigid path, the band above ``f_n`` kept): raised
                              bands around ``f_n``, higher kurtosis and crest (ringing)
backlash_growth    dynamics   backlash grown by ``kappa`` times the wear thickness lost: visible
                              only where the teeth separate (light load, rattle)
torque_ripple      dynamics   input torque ripple ``r`` at a drive-line order ``q`` of the pinion
                              shaft, 1/2, 1 or 2 (a 2:1 stage or belt upstream, a motor, a
                              Cardan joint): lines at ``q f_1``, sidebands ``k f_m +- q f_1``
sensor             measure    sensor gain ``G`` on the record (for acceleration it is absorbed by
                              the calibrated ``m_h``; only DTE records show it)
=================  =========  =====================================================================
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from physics.dynamics.model import PairModel
from physics.dynamics.teeth import per_tooth_model
from physics.signals.measurement import transfer_path


@dataclass(frozen=True)
class Param:
    """One fitted parameter of an effect: bounds, a realistic size, fitted in log if ``log``."""

    name: str
    unit: str
    low: float
    high: float
    typical: float  # a realistic size (used by the bundle generator)
    log: bool = True
    shape: bool = False  # a shape (a length), not a size: kept as a wear-grown effect grows


@dataclass(frozen=True)
class Effect:
    name: str
    params: tuple[Param, ...]
    options: tuple[dict, ...] = ({},)  # discrete alternatives, each fitted separately
    grows_with_wear: bool = False  # in feature-table mode its size scales with the wear depth
    quantities: tuple[str, ...] = ("dte_m", "accel_m_s2")  # records it can show in
    model: Callable[[PairModel, dict], PairModel] | None = None
    record: Callable[[np.ndarray, float, dict], np.ndarray] | None = None
    #: where a stacked candidate of the second round is judged: the quantities its added
    #: effect shows in (its ``quantities`` are then those the first effect's measurement stage
    #: acts on)
    shows_in: tuple[str, ...] = ()

    def judged_in(self) -> tuple[str, ...]:
        """The quantities whose records can show this candidate's own change."""
        return self.shows_in or self.quantities

    def defaults(self) -> dict:
        return {p.name: p.typical for p in self.params} | dict(self.options[0])

    def scaled(self, values: dict, share: float) -> dict:
        """``values`` with the effect's sizes times ``share``; its shapes (a pit's length) and
        options kept."""
        sizes = {p.name for p in self.params if not p.shape}
        return {k: v * share if k in sizes else v for k, v in values.items()}

    def bounds(self) -> list[tuple[str, float, float, bool]]:
        """(name, low, high, log) of each parameter: the free-parameter form of the fits."""
        return [(p.name, p.low, p.high, p.log) for p in self.params]


def _gear_runout(m: PairModel, v: dict) -> PairModel:
    """Eccentricity e of the gear: its line-of-action component e sin(aw) is a kinematic error
    at the gear's rate; the component along the line of centres changes the centre distance
    by e cos(w2 t), which moves the start of the path of contact (see dynamics._mesh)."""
    g = m.geometry
    e = 0.5 * v["runout_um"] * 1e-6  # eccentricity is half the radial run-out
    return dataclasses.replace(m, gear_error=e * math.sin(g.alpha_w), centre_runout=e,
                               omega2=m.omega1 * g.rb1 / g.rb2)


def _roll_positions(m: PairModel) -> tuple[np.ndarray, np.ndarray]:
    """Roll coordinates of pairs A and B over the tables (period-folded), and B's mask."""
    g = m.geometry
    s_a = np.tile(g.mesh_period(len(m.k_a) // m.periods)[0], m.periods)
    return s_a, s_a + g.base_pitch


def _friction(m: PairModel, v: dict) -> PairModel:
    g = m.geometry
    j1, j2 = m.inertias
    s_a, s_b = _roll_positions(m)

    def factor(s):
        x1 = g.rb1 * math.tan(g.alpha_w) + s  # contact to the pinion's base tangent point
        x2 = g.rb2 * math.tan(g.alpha_w) - s
        sign = -np.sign(s)  # approach (s < 0): the pinion flank slides slower than the gear's
        return 1.0 - v["mu"] * sign * m.mass * (g.rb1 * x1 / j1 + g.rb2 * x2 / j2)

    return dataclasses.replace(m, lam_a=factor(s_a), lam_b=factor(s_b))


def _tip_relief(m: PairModel, v: dict) -> PairModel:
    g = m.geometry
    s_a, s_b = _roll_positions(m)
    start = g.s_end - g.base_pitch  # long relief: the double-contact zones at both ends
    length = max(g.s_end - (g.s_start + g.base_pitch), 1e-9)

    def relief(s):
        pinion_tip = np.clip((s - (g.s_start + g.base_pitch)) / length, 0, 1)
        gear_tip = np.clip((start - s) / length, 0, 1)
        return v["relief_um"] * 1e-6 * (pinion_tip + gear_tip)

    on_b = m.k_b > 0
    return dataclasses.replace(m, g_a=m.g_a + relief(s_a),
                               g_b=np.where(on_b, m.g_b + relief(s_b), m.g_b))


def _tooth_defect(m: PairModel, v: dict) -> PairModel:
    """Pinion tooth 0 pitted (its own flank: the pit's gap and lost face on its tables), the
    other teeth as ``m``, over a pinion revolution in mesh order
    (:func:`physics.dynamics.teeth.per_tooth_model`)."""
    if m.periods != 1:
        raise ValueError("tooth_defect needs a model with one-period tables")
    g = m.geometry
    n = len(m.k_a)
    tau = g.base_pitch * np.arange(n) / n
    s_a, s_b = g.s_start + tau, g.s_start + tau + g.base_pitch
    half = 0.5 * v["length_mm"] * 1e-3

    def bump(s):  # cos^2 profile of the pit along the roll coordinate
        u = np.clip((s - v["centre_mm"] * 1e-3) / half, -1, 1)
        return np.cos(0.5 * np.pi * u) ** 2

    depth, share = v["depth_um"] * 1e-6, v["face_share"]
    pit_b = np.where(m.k_b > 0, bump(s_b), 0.0)  # pair B only where it is in mesh
    pitted = dataclasses.replace(m, g_a=m.g_a + depth * bump(s_a),
                                 k_a=m.k_a * (1 - share * bump(s_a)),
                                 g_b=m.g_b + depth * pit_b, k_b=m.k_b * (1 - share * pit_b))
    return per_tooth_model([pitted] + [m] * (g.gear.z1 - 1))


def _backlash_growth(m: PairModel, v: dict) -> PairModel:
    lost = float(np.mean(m.g_a))  # mean wear thickness lost along the path (both gears)
    return dataclasses.replace(m, half_backlash=m.half_backlash + 0.5 * v["kappa"] * lost)


def _torque_ripple(m: PairModel, v: dict) -> PairModel:
    return dataclasses.replace(m, ripple_force=v["ripple_pct"] / 100 * m.static_force,
                               omega_ripple=v["order"] * m.omega1)


def _transfer_path(x: np.ndarray, fs: float, v: dict) -> np.ndarray:
    return transfer_path(x, fs, v["fn_hz"], v["zeta"], v["residue"])


def _sensor(x: np.ndarray, fs: float, v: dict) -> np.ndarray:
    return v["gain"] * x


EFFECTS: dict[str, Effect] = {e.name: e for e in (
    Effect("gear_runout", (Param("runout_um", "um", 0.5, 80.0, 15.0),),
           model=_gear_runout),
    Effect("friction", (Param("mu", "1", 0.003, 0.3, 0.06),), model=_friction),
    Effect("tip_relief", (Param("relief_um", "um", 0.5, 60.0, 15.0),),
           model=_tip_relief),
    # the pit's length along the profile sets how sharp its once-per-revolution impulse is:
    # from about the finest a record resolves (at case 3's speed a sample at 41 kHz is 0.09 mm
    # of roll) to beyond the single-contact zone (2.5 mm of case 3's 9.3 mm path of contact)
    Effect("tooth_defect", (Param("depth_um", "um", 0.5, 100.0, 20.0),
                            Param("face_share", "1", 0.05, 0.9, 0.3, log=False),
                            Param("length_mm", "mm", 0.2, 4.0, 1.5, shape=True)),
           options=({"centre_mm": -0.5},),
           grows_with_wear=True, model=_tooth_defect),
    # a structural mode's damping: 1-10 %, the range the datasets draw for the same mode
    # (``physics.dataset.generation.NuisanceRanges.transfer_zeta``: first plate modes of small
    # cast housings); beyond it the filter is a broad spectral tilt, not a mode
    Effect("transfer_path", (Param("fn_hz", "Hz", 800.0, 15000.0, 3200.0),
                             Param("zeta", "1", 0.01, 0.1, 0.04),
                             Param("residue", "1", -1.0, 1.0, 1.0, log=False)),
           quantities=("accel_m_s2",), record=_transfer_path),
    Effect("backlash_growth", (Param("kappa", "1", 0.1, 20.0, 1.0),),
           grows_with_wear=True, model=_backlash_growth),
    Effect("torque_ripple", (Param("ripple_pct", "%", 0.2, 30.0, 5.0),),
           options=({"order": 1}, {"order": 2}, {"order": 0.5}), model=_torque_ripple),
    Effect("sensor", (Param("gain", "1", 0.3, 3.0, 1.3),),
           quantities=("dte_m",), record=_sensor),
)}


def effect(name: str) -> Effect:
    if name not in EFFECTS:
        raise ValueError(f"effect {name!r} is not in the library; choose from {sorted(EFFECTS)}")
    return EFFECTS[name]
