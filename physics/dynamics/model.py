"""Torsional vibration of the gear pair with backlash and worn teeth (thesis 3.3-3.5).

Two inertias on their base circles (thesis 3.3)

    J1 theta1'' + r_b1 F = T1,        J2 theta2'' - r_b2 F = -T2,
    F = c x' + sum_i k_i(t) f(x - g_i(t)),    x = r_b1 theta1 - r_b2 theta2 - e(t)

reduce, with the equivalent mass ``m_e = J1 J2 / (J1 r_b2^2 + J2 r_b1^2)`` and the static mesh
force ``W0 = T2 / r_b2``, to

    m_e x'' + c x' + sum_i k_i(t) f(x - g_i(t)) = W0 - m_e e''(t).

``f`` is the backlash dead zone of half-width ``Delta_n`` (thesis 3.3). The damping acts through
the contacts, shared by stiffness, and a contact transmits no tension: where the thesis writes
``c x'`` for the whole mesh, a pair out of contact here carries neither spring nor damper force,
so the mesh force never turns negative while the flanks are apart. The pairs in contact are
``i = A`` (the pair that entered at the start of contact, at roll ``s_start + tau``) and ``i = B``
(one base pitch ahead, while it is still on the path), with ``tau = r_b1 omega1 t mod p_b``. Their
stiffnesses ``k_i`` are the potential-energy stiffnesses of the worn teeth
(:mod:`physics.stiffness`) and ``g_i`` their wear gaps (pinion plus gear wear at the contact
point): the wear-induced error of the thesis enters pair by pair, so load sharing and contact loss
follow from the same equation; a gap moves a pair's drive-flank contact only (wear widens its
backlash). With ``dynamics.flank_contact = "exact"`` the gaps are the rigid gaps of the flanks as
they are (:mod:`physics.gear.tooth_contact`) and three more pairs may touch off the path: the one
before its entry, B past the end and the one after it (drive flanks only). ``e(t)`` holds the
long-period (pinion eccentricity on the line of action, shaft rate) and short-period (profile,
mesh rate) errors. The thesis's "combined error" is ``e(t) + sum k_i g_i / sum k_i``.

Integration is the fixed-step classical Runge-Kutta of the thesis, compiled with numba and run in
parallel over a batch of scenarios (:mod:`physics.dynamics.kernels`); the step is
``step_factor / omega_max`` with ``omega_max`` the highest natural frequency
``sqrt(k_max / m_e)``, rounded down to divide the output sample period (at least twice per
sample).

The recorded DTE and mesh force are what a data-acquisition system samples: the integrator's
record (the DTE at every step, the force averaged over every step) passes the anti-aliasing
low-pass every such system has before its converter (:func:`anti_aliased`), then is decimated
to ``sample_rate_hz``. Sampling the integrator's state directly folds the mesh force's
harmonics above ``fs / 2`` (its stiffness steps pass straight into the force above the mesh
resonance) back into the band, and point values of the force at each step fold those above the
integration rate: at 2000 r/min in case 3 together they make lines at ``f_m / 3`` and
``2 f_m / 3`` 6-10 dB above the mesh line itself.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from physics.dynamics.kernels import (
    BASE_PITCH,
    CELLS_PER_METRE,
    CELLS_PER_PERIOD,
    CENTRE_RUNOUT,
    DAMPING,
    GEAR_ERROR,
    GEAR_MODULATION,
    GEAR_MODULATION_PHASE,
    HALF_BACKLASH,
    LONG_ERROR,
    MASS,
    N_PARAMETERS,
    OFF_PATH,
    OFF_PATH_PAIRS,
    OMEGA1,
    OMEGA2,
    OMEGA_MESH,
    OMEGA_RIPPLE,
    PINION_MODULATION,
    PINION_MODULATION_PHASE,
    RIPPLE_FORCE,
    ROLL_SPEED,
    SHORT_ERROR,
    STATIC_FORCE,
    decimate,
    integrate,
)
from physics.dynamics.model_form import FACTORS, with_model_form
from physics.gear.accuracy import form_deviation
from physics.gear.geometry import MeshGeometry
from physics.gear.stiffness import MeshStiffness, mesh_stiffness
from physics.gear.tooth_contact import NO_CONTACT, PairGaps, clamped, pair_slots, share_load
from physics.params import Dynamics, Scenario
from physics.scope import check_scope


@dataclass(frozen=True)
class PairModel:
    """One scenario of the reduced torsional model, ready to integrate (SI units)."""

    geometry: MeshGeometry
    mass: float  # m_e [kg]
    damping: float  # c [N s/m]
    static_force: float  # W0 [N]
    half_backlash: float  # Delta_n [m]
    long_error: float  # amplitude of the shaft-rate error on the line of action [m]
    short_error: float  # amplitude of the mesh-rate error [m]
    omega1: float  # pinion speed [rad/s]
    omega_mesh: float  # mesh frequency [rad/s]
    roll_speed: float  # r_b1 omega1 [m/s]
    k_a: np.ndarray  # stiffness of pair A over `periods` mesh periods (uniform grid) [N/m]
    k_b: np.ndarray  # stiffness of pair B (0 out of contact) [N/m]
    g_a: np.ndarray  # wear gap of pair A [m]
    g_b: np.ndarray  # wear gap of pair B [m]
    inertias: tuple[float, float]  # J1, J2 [kg m^2]
    # --- hooks of the effect library (physics.effects); the defaults are the declared model ---
    periods: int = 1  # mesh periods the tables span (z1: a pinion revolution; lcm(z1, z2))
    lam_a: np.ndarray | None = None  # factor on pair A's force in the equation of motion
    lam_b: np.ndarray | None = None  # (sliding friction); None: 1
    gear_error: float = 0.0  # amplitude of the gear's run-out error on the line of action [m]
    centre_runout: float = 0.0  # amplitude of the centre-distance change it causes [m]
    omega2: float = 0.0  # gear speed [rad/s]
    # the mesh stiffness times 1 + pinion_modulation cos(omega1 t + pinion_modulation_phase)
    # and times 1 + gear_modulation cos(omega2 t + gear_modulation_phase): the run-outs' once-
    # per-revolution modulations (physics.dynamics.model_form.with_modulation)
    pinion_modulation: float = 0.0
    pinion_modulation_phase: float = 0.0  # [rad]
    gear_modulation: float = 0.0
    gear_modulation_phase: float = 0.0  # [rad]
    ripple_force: float = 0.0  # amplitude of the torque ripple as mesh force [N]
    omega_ripple: float = 0.0  # its angular frequency [rad/s]
    # the pairs off the theoretical path that can touch (physics.gear.tooth_contact): the one
    # before its entry, pair B past the end (0 while B is on the path), the one after it;
    # stiffness and rigid gap (OFF_PATH, cells), drive flanks only. None: no off-path contact
    k_off: np.ndarray | None = None  # [N/m]
    g_off: np.ndarray | None = None  # [m]

    @property
    def omega_max(self) -> float:
        """Highest natural frequency of the linearised mesh, ``sqrt(k_max / m_e)`` [rad/s]."""
        k_max = float(np.max(self.k_a + self.k_b)) * ((1.0 + abs(self.pinion_modulation))
                                                      * (1.0 + abs(self.gear_modulation)))
        return math.sqrt(k_max / self.mass)

    @property
    def mesh_frequency_hz(self) -> float:
        return self.omega_mesh / (2 * math.pi)

    def combined_error(self, t: np.ndarray) -> np.ndarray:
        """Thesis 3.3's combined error at times t: manufacturing plus wear-induced [m]."""
        tau = self.phase_index(t)
        k_a, k_b = self.k_a[tau], self.k_b[tau]
        wear = (k_a * self.g_a[tau] + k_b * self.g_b[tau]) / (k_a + k_b)
        return (self.long_error * np.sin(self.omega1 * t)
                + self.short_error * np.sin(self.omega_mesh * t)
                + self.gear_error * np.sin(self.omega2 * t) + wear)

    def phase_index(self, t: np.ndarray) -> np.ndarray:
        """Index into the tables at times ``t`` (they span ``periods`` mesh periods)."""
        n = len(self.k_a)
        span = self.geometry.base_pitch * self.periods
        frac = np.mod(self.roll_speed * np.asarray(t), span) / span
        return np.minimum((frac * n).astype(int), n - 1)

    def force_factors(self) -> tuple[np.ndarray, np.ndarray]:
        """The pairs' force factors in the equation of motion (1 without friction)."""
        ones = np.ones_like(self.k_a)
        return (ones if self.lam_a is None else self.lam_a,
                ones if self.lam_b is None else self.lam_b)


#: mesh phases the exact contact's tables need: its early and late contact engage over a few
#: per cent of the mesh period (a new pair's force spread within 1.2 % of 8192 phases' at 2048,
#: 3.5 % at 1024, 13 % at 512; the path contact's within 0.3 % at 1024)
EXACT_PHASES = 2048


def path_gaps(s_a: np.ndarray, s_b: np.ndarray, s_grid: np.ndarray | None,
              wear1: np.ndarray | None, wear2: np.ndarray | None
              ) -> tuple[np.ndarray, np.ndarray]:
    """Gaps of pairs A and B as the thesis (2.2) has them: the two flanks' wear summed at the
    pair's point of the theoretical path (``s_b`` is held at the end of the path) [m]."""
    if wear1 is None and wear2 is None:
        return np.zeros_like(s_a), np.zeros_like(s_a)
    s_grid = np.asarray(s_grid, dtype=float)
    total = (np.zeros_like(s_grid) if wear1 is None else wear1) + (
        np.zeros_like(s_grid) if wear2 is None else wear2)
    # B's gap past the end of the path holds its value there: the tables' interpolation ramps
    # B's stiffness to 0 over one cell, and a gap that fell to 0 with it would close the
    # flanks for that cell
    return np.interp(s_a, s_grid, total), np.interp(s_b, s_grid, total)


def exact_contact(ms: MeshStiffness, k_of, s_a: np.ndarray, on_b: np.ndarray,
                  s_grid: np.ndarray | None, wear1: np.ndarray | None, wear2: np.ndarray | None):
    """Gaps of pairs A and B and the off-path pairs' stiffness and gaps (``OFF_PATH`` rows)
    from the tooth contact of the flanks as they are (:mod:`physics.gear.tooth_contact`): an
    off-path pair's compliance is the pair's at the nearer end of the path."""
    geom = ms.geometry
    slots = pair_slots(geom, s_a)  # before entry, A, one ahead, two ahead
    pair_gaps = PairGaps(geom, ms.forms, s_grid, wear1, wear2)
    gaps = pair_gaps(slots)
    k_slots = k_of(clamped(geom, slots).ravel()).reshape(slots.shape)
    reach = gaps[:, [0, 2, 3]].T < NO_CONTACT
    reach[1] &= ~on_b  # pair B is past the end of the path
    end = pair_gaps(np.array([geom.s_end]))[0]
    return (gaps[:, 1], np.where(on_b, gaps[:, 2], end),  # B held at the end: path_gaps
            np.where(reach, k_slots[:, [0, 2, 3]].T, 0.0),
            np.where(reach, gaps[:, [0, 2, 3]].T, NO_CONTACT))


def blank_inertia(radius: float, bore: float, width: float, density: float) -> float:
    """Polar moment of a solid steel disc between bore and radius [kg m^2]."""
    return 0.5 * math.pi * density * width * (radius**4 - bore**4)


def build_model(scn: Scenario, stiffness: MeshStiffness | None = None,
                s_grid: np.ndarray | None = None, wear1: np.ndarray | None = None,
                wear2: np.ndarray | None = None, n_phase: int = 1024) -> PairModel:
    """The reduced model of ``scn`` for the teeth worn by ``wear1, wear2`` on ``s_grid``, with
    the scenario's form factors (:mod:`physics.dynamics.model_form`; neutral by default)."""
    dyn, g, op = check_scope(scn).dynamics, scn.gear, scn.operating
    ms = stiffness or mesh_stiffness(g, scn.material)
    geom = ms.geometry
    w0 = op.torque_Nm / geom.rb2
    s_a, s_b, on_b = geom.mesh_period(n_phase)
    k_of = ms.pair_function(s_grid, wear1, wear2)
    k_a = k_of(s_a)
    k_b = np.where(on_b, k_of(s_b), 0.0)
    if dyn.flank_contact == "exact":
        g_a, g_b, k_off, g_off = exact_contact(ms, k_of, s_a, on_b, s_grid, wear1, wear2)
    else:
        g_a, g_b = path_gaps(s_a, s_b, s_grid, wear1, wear2)
        k_off = g_off = None
    if dyn.form_deviation_um > 0:  # the flank's form deviation, a gap like the wear's
        wave = (geom.s_start, geom.path_length, dyn.form_deviation_um, dyn.form_waves,
                dyn.form_phase_rad)
        g_a = g_a + form_deviation(s_a, *wave)
        g_b = g_b + form_deviation(s_b, *wave)  # s_b held at the end of the path
    rho, width = scn.material.density_kg_m3, g.face_width
    j1 = dyn.inertia1_kg_m2 or blank_inertia(geom.r1, g.bore_radius1_mm * 1e-3, width, rho)
    j2 = dyn.inertia2_kg_m2 or blank_inertia(geom.r2, g.bore_radius2_mm * 1e-3, width, rho)
    mass = j1 * j2 / (j1 * geom.rb2**2 + j2 * geom.rb1**2)
    k_mean = float(np.mean(k_a + k_b))
    omega1 = op.omega1
    declared = PairModel(
        geometry=geom, mass=mass, damping=2 * dyn.damping_ratio * math.sqrt(k_mean * mass),
        static_force=w0, half_backlash=dyn.half_backlash_um * 1e-6,
        long_error=dyn.eccentricity1_um * 1e-6 * math.sin(geom.alpha_w),
        short_error=dyn.profile_error_um * 1e-6, omega1=omega1, omega_mesh=omega1 * g.z1,
        roll_speed=geom.rb1 * omega1, k_a=k_a, k_b=k_b, g_a=g_a, g_b=g_b, inertias=(j1, j2),
        k_off=k_off, g_off=g_off,
    )
    return with_model_form(declared, {f: getattr(dyn, f) for f in FACTORS})


@dataclass(frozen=True)
class Response:
    """Steady response of a batch of scenarios, sampled at ``sample_rate_hz`` after the transient.

    Arrays are ``(scenario, sample)``; ``force_by_phase`` is the mean load of the drive flanks
    over the record in each of ``phase_bins`` bins of the mesh period (phase 0 = a pair enters
    contact): where backlash lets the coast flanks strike (a negative mesh force), the drive
    flanks carry nothing, and only drive-flank load wears the drive flanks the wear model
    follows. ``dte`` and ``force`` are the sensors' records, anti-aliased from the integrator's
    (:func:`anti_aliased`) when first read; ``load_a`` and ``load_b`` are the pairs' loads at
    the sample instants.
    """

    time: np.ndarray  # [s] since the start of the integration (transient included)
    dte_steps: np.ndarray  # x [m] at every step (see :func:`physics.dynamics.kernels.integrate`)
    force_steps: np.ndarray  # F_d [N] averaged over every step
    load_a: np.ndarray  # load of pair A [N] (its elastic force and its share of damping)
    load_b: np.ndarray  # load of pair B [N]
    force_by_phase: np.ndarray  # [N]
    time_step: float  # RK4 step [s]
    steps_per_sample: int

    @functools.cached_property
    def dte(self) -> np.ndarray:
        """x [m], the DTE record."""
        return anti_aliased(self.dte_steps, self.steps_per_sample, len(self.time))

    @functools.cached_property
    def force(self) -> np.ndarray:
        """F_d = sum over pairs in contact of k f(x - g) + c_i x' [N], the force record."""
        return anti_aliased(self.force_steps, self.steps_per_sample, len(self.time))


def kernel_parameters(m: PairModel) -> np.ndarray:
    """The parameter row of ``m`` for the compiled kernel, filled by name."""
    row = np.empty(N_PARAMETERS)
    row[MASS], row[DAMPING], row[STATIC_FORCE] = m.mass, m.damping, m.static_force
    row[HALF_BACKLASH], row[LONG_ERROR], row[SHORT_ERROR] = (m.half_backlash, m.long_error,
                                                              m.short_error)
    row[OMEGA1], row[OMEGA_MESH], row[OMEGA2] = m.omega1, m.omega_mesh, m.omega2
    row[ROLL_SPEED], row[BASE_PITCH] = m.roll_speed, m.geometry.base_pitch
    row[GEAR_ERROR], row[CENTRE_RUNOUT] = m.gear_error, m.centre_runout
    row[GEAR_MODULATION], row[GEAR_MODULATION_PHASE] = (m.gear_modulation,
                                                        m.gear_modulation_phase)
    row[PINION_MODULATION], row[PINION_MODULATION_PHASE] = (m.pinion_modulation,
                                                            m.pinion_modulation_phase)
    row[RIPPLE_FORCE], row[OMEGA_RIPPLE] = m.ripple_force, m.omega_ripple
    row[OFF_PATH_PAIRS] = 0.0 if m.k_off is None else 1.0
    row[CELLS_PER_PERIOD] = len(m.k_a) / m.periods
    row[CELLS_PER_METRE] = row[CELLS_PER_PERIOD] / (m.geometry.base_pitch
                                                    * math.sin(m.geometry.alpha_w))
    return row


def time_step(models: Sequence[PairModel], dyn: Dynamics) -> tuple[float, int]:
    """RK4 step and sub-steps per output sample: ``dt <= step_factor / omega_max``, and at
    least two sub-steps (the anti-aliasing filter needs a record above ``fs``)."""
    dt_max = dyn.step_factor / max(m.omega_max for m in models)
    n_sub = max(2, math.ceil(1.0 / (dyn.sample_rate_hz * dt_max)))
    return 1.0 / (dyn.sample_rate_hz * n_sub), n_sub


#: the anti-aliasing filter keeps 0-PASS_EDGE fs (the signatures' band) within 1e-4 and
#: suppresses everything that would fold into it (above ``(1 - PASS_EDGE) fs``) by STOP_DB
PASS_EDGE = 0.45
STOP_DB = 80.0


@functools.lru_cache(maxsize=32)
def anti_aliasing_filter(n_sub: int) -> np.ndarray:
    """Linear-phase low-pass FIR at ``n_sub`` times the output rate (Kaiser window, Oppenheim &
    Schafer, Discrete-Time Signal Processing, 3rd ed., 7.6): pass band to ``PASS_EDGE fs``,
    stop band from ``(1 - PASS_EDGE) fs``, ``2 L n_sub + 1`` taps (a whole number ``L`` of
    output samples either side). Designed once per ``n_sub`` (read-only)."""
    from scipy import signal  # imported on first use: a refusal need not wait for it

    width = (1 - 2 * PASS_EDGE) * 2 / n_sub  # transition, as a fraction of the fine Nyquist
    taps, beta = signal.kaiserord(STOP_DB, width)
    half = math.ceil((taps - 1) / (2 * n_sub))
    h = signal.firwin(2 * half * n_sub + 1, 1.0 / n_sub, window=("kaiser", beta))
    h.flags.writeable = False
    return h


def anti_aliased(fine: np.ndarray, n_sub: int, n_out: int) -> np.ndarray:
    """Output samples of a record taken every integration step: the anti-aliasing FIR
    (:func:`anti_aliasing_filter`, half-length ``L n_sub``) centred on every ``n_sub``-th
    step. ``fine[..., j]`` is step ``j - (L - 1) n_sub`` of the output interval, so output
    sample ``i`` is centred on step ``(i + 1) n_sub``, the instant the point sample had."""
    h = anti_aliasing_filter(n_sub)
    rows = np.ascontiguousarray(fine, dtype=float).reshape(-1, fine.shape[-1])
    return decimate(h, rows, n_sub, n_out).reshape(*fine.shape[:-1], n_out)


def output_samples(dyn: Dynamics) -> int:
    """Samples of a record of ``dyn.duration_s`` (each ``n_sub`` integration steps)."""
    return round(dyn.duration_s * dyn.sample_rate_hz)


def settle_time(models: Sequence[PairModel], decays: float) -> float:
    """``decays`` decay times ``2 m_e / c`` of the slowest-decaying mesh mode of ``models``
    [s] (inf without damping): after it a start's free vibration has fallen to ``e^-decays``."""
    rate = min(m.damping / (2.0 * m.mass) for m in models)
    return decays / rate if rate > 0 else math.inf


def simulate(models: Sequence[PairModel] | PairModel, dyn: Dynamics,
             settle: float | None = None, every_phase: bool = True) -> Response:
    """Integrate a batch of scenarios (parallel over scenarios) and sample their response.

    The record starts ``dyn.transient_s`` after t = 0. With ``settle`` the integration starts
    only ``settle`` decay times of the mesh mode (:func:`settle_time`; within the transient)
    before the record, from the same initial state (the static deflection at rest) with every
    excitation (mesh phase, errors, run-out, ripple) at its phase of that instant: the record
    is the same up to ``e^-settle`` of the start's free vibration (the record's start phase,
    which moves a signature's lines, is kept), at a fraction of the steps (the mesh mode of
    the thesis pair decays within milliseconds). None: from t = 0.

    ``every_phase``: the record must visit every one of ``dyn.phase_bins`` mesh-phase bins (the
    drive-flank load by phase feeds the wear, :func:`force_per_position`); a ``ValueError``
    if it does not (an integration step nearly commensurate with the mesh period revisits the
    same phases). False for a record read for its signals alone: a bin it misses is NaN.
    """
    if isinstance(models, PairModel):
        models = [models]
    if not models:
        raise ValueError("simulate needs at least one scenario")
    n_phase = {(len(m.k_a), m.periods) for m in models}
    if len(n_phase) != 1:
        raise ValueError("all scenarios of a batch need the same phase grid and periods")
    dt, n_sub = time_step(models, dyn)
    n_out = output_samples(dyn)
    half = (len(anti_aliasing_filter(n_sub)) - 1) // (2 * n_sub)
    # the filter reaches (L - 1) n_sub steps before the first sample: inside the transient
    n_transient = max(round(dyn.transient_s / dt), (half - 1) * n_sub)
    # the first integrated step: the settling time before the record's, within the transient
    lead = math.inf if settle is None else settle_time(models, settle)
    step0 = 0 if lead >= n_transient * dt else max(
        0, n_transient - max(math.ceil(lead / dt), (half - 1) * n_sub))
    par = np.stack([kernel_parameters(m) for m in models])
    tables = np.stack([np.concatenate([np.stack([m.k_a, m.k_b, m.g_a, m.g_b,
                                                 *m.force_factors()]), off_path_rows(m)])
                       for m in models])
    x0 = np.array([static_deflection(m) for m in models])
    out = integrate(par, tables, x0, dt, n_transient, n_sub, n_out, dyn.phase_bins, half,
                     step0)
    dte_steps, force_steps, load_a, load_b, phase_sum, phase_count = out
    with np.errstate(invalid="ignore"):
        by_phase = phase_sum / phase_count
    if every_phase and np.any(phase_count == 0):
        raise ValueError(f"dynamics.duration_s = {dyn.duration_s:g} is too short to visit every "
                         f"one of {dyn.phase_bins} phase bins; lengthen it or use fewer bins")
    time = n_transient * dt + (np.arange(n_out) + 1) * n_sub * dt
    return Response(time, dte_steps, force_steps, load_a, load_b, by_phase, dt, n_sub)


def static_deflection(m: PairModel) -> float:
    """The static ``x`` at phase 0: ``sum_i k_i max(x - g_i - Delta_n, 0) = W0`` over the
    pairs of the tables' first cell, off-path ones included
    (:func:`physics.gear.tooth_contact.share_load`): the start of every integration, so that
    a worn pair starts in contact as it stands, not from an impact."""
    off = off_path_rows(m)[:, 0]
    k = np.concatenate([[m.k_a[0], m.k_b[0]], off[0::2]])
    g = np.concatenate([[m.g_a[0], m.g_b[0]], off[1::2]])
    approach, _ = share_load(g[None, :], k[None, :], m.static_force)
    return float(approach[0] + m.half_backlash)


def off_path_rows(m: PairModel) -> np.ndarray:
    """The kernel's rows of the off-path pairs: stiffness and gap of each, interleaved
    (``2 * OFF_PATH`` rows; zero stiffness where the model has none)."""
    rows = np.empty((2 * OFF_PATH, len(m.k_a)))
    rows[0::2] = 0.0 if m.k_off is None else m.k_off
    rows[1::2] = NO_CONTACT if m.g_off is None else m.g_off
    return rows


def force_per_position(model: PairModel, response_force_by_phase: np.ndarray,
                       s: np.ndarray) -> np.ndarray:
    """Mean dynamic mesh force at the instant a pair is at roll coordinate ``s`` [N].

    A pair at ``s`` is at phase ``(s - s_start) mod p_b`` of the mesh period (as pair A in the
    first base pitch of its path, as pair B after it); the force is periodic in that phase.
    """
    geom = model.geometry
    n_bins = len(response_force_by_phase)
    frac = np.mod(np.asarray(s) - geom.s_start, geom.base_pitch) / geom.base_pitch
    centres = (np.arange(n_bins) + 0.5) / n_bins
    return np.interp(frac, centres, response_force_by_phase, period=1.0)


def simulate_two_dof(model: PairModel, t_eval: np.ndarray, rtol: float = 1e-9,
                     atol: float = 1e-13) -> tuple[np.ndarray, np.ndarray]:
    """Reference: the unreduced two-inertia equations of thesis 3.3 by ``solve_ivp`` (DOP853).

    States ``theta1, theta2`` and their rates, with ``T1 = W0 r_b1`` and ``T2 = W0 r_b2``;
    returns the DTE ``x = r_b1 theta1 - r_b2 theta2 - e(t)`` and the mesh force at ``t_eval``.
    Slow (pure Python right-hand side); it exists to check the reduced, compiled integrator,
    for the declared model (no effect of :mod:`physics.effects`).
    """
    from scipy.integrate import solve_ivp

    geom, m = model.geometry, model
    if (m.periods != 1 or m.lam_a is not None or m.lam_b is not None or m.gear_error
            or m.ripple_force or m.centre_runout or m.gear_modulation or m.pinion_modulation):
        raise ValueError("simulate_two_dof checks the declared model only; this one carries "
                         "effects of physics.effects")
    j1, j2 = m.inertias
    rb1, rb2, n = geom.rb1, geom.rb2, len(m.k_a)
    cells = np.arange(n + 1)
    rows = off_path_rows(m)
    tables = [np.append(a, a[0]) for a in (m.k_a, m.k_b, m.g_a, m.g_b, *rows)]

    def error(t):
        return (m.long_error * np.sin(m.omega1 * t), m.long_error * m.omega1
                * np.cos(m.omega1 * t)), (m.short_error * np.sin(m.omega_mesh * t),
                                          m.short_error * m.omega_mesh * np.cos(m.omega_mesh * t))

    def mesh_force(t, th1, th2, w1, w2):
        (el, eld), (es, esd) = error(t)
        x = rb1 * th1 - rb2 * th2 - el - es
        v = rb1 * w1 - rb2 * w2 - eld - esd
        pos = np.mod(m.roll_speed * t, geom.base_pitch) / geom.base_pitch * n
        k_a, k_b, g_a, g_b, *off = (np.interp(pos, cells, tab) for tab in tables)
        if m.k_off is not None:  # the last cell: each pair to its own next value
            frac = pos - (n - 1)
            last = frac >= 0

            def moved(a: np.ndarray, b: np.ndarray) -> np.ndarray:
                return a[n - 1] + (b[0] - a[n - 1]) * frac

            k_a = np.where(last, moved(rows[0], m.k_a), k_a)
            g_a = np.where(last, moved(rows[1], m.g_a), g_a)
            k_b = np.where(last, moved(m.k_a, m.k_b), k_b)
            g_b = np.where(last, moved(m.g_a, m.g_b), g_b)
            off = [np.where(last, v, o) for v, o in zip(
                (0.0, NO_CONTACT, 0.0, NO_CONTACT, moved(rows[2], rows[4]),
                 moved(rows[3], rows[5])), off, strict=True)]
        dz = m.half_backlash
        pairs = [(k_a, g_a, True), (k_b, g_b, True)] + [
            (off[2 * i], off[2 * i + 1], False) for i in range(OFF_PATH)]
        # the damping shared by stiffness among the pairs in contact
        engaged = sum(np.where((x - g > dz) | (coast & (x < -dz)), k, 0.0)
                      for k, g, coast in pairs)
        c_v = np.where(engaged > 0, m.damping * v / np.where(engaged > 0, engaged, 1.0), 0.0)

        def pair(k, g, coast):
            drive = np.where(x - g > dz, np.maximum(k * (x - g - dz + c_v), 0.0), 0.0)
            if not coast:
                return drive
            return np.where(x < -dz, np.minimum(k * (x + dz + c_v), 0.0), drive)

        return x, sum(pair(*p) for p in pairs)

    def rhs(t, y):
        th1, th2, w1, w2 = y
        _, force = mesh_force(t, th1, th2, w1, w2)
        return [w1, w2, (m.static_force * rb1 - rb1 * force) / j1,
                (-m.static_force * rb2 + rb2 * force) / j2]

    x0 = m.half_backlash + m.static_force / (m.k_a[0] + m.k_b[0])
    (_, el_dot), (_, es_dot) = error(0.0)
    w1_0 = (el_dot + es_dot) / rb1  # x'(0) = 0, as in the reduced integrator
    sol = solve_ivp(rhs, (0.0, float(t_eval[-1])), [x0 / rb1, 0.0, w1_0, 0.0],
                    method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    x, force = mesh_force(sol.t, *sol.y)
    return x, force
