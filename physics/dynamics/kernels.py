"""The compiled kernels of the torsional model (:mod:`physics.dynamics.model`): the fixed-step
RK4 integrator over a batch of scenarios (:func:`integrate`), the mesh it reads at every stage
(pairs' stiffness, gaps and force factors interpolated from the model's tables, the backlash dead
zone with damping through the contacts) and the anti-aliasing decimation (:func:`decimate`).

The model builds their inputs: a parameter row per scenario (:func:`physics.dynamics.model.
kernel_parameters`, positions below) and the tables of :class:`physics.dynamics.model.PairModel`
(rows 0-5 pairs A and B: stiffness, gap, force factor; rows 6-11 the off-path pairs'
stiffness and gap, :func:`physics.dynamics.model.off_path_rows`). Equations and sources: the
model's module text.
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: positions of the kernel's per-scenario parameters (numba reads module constants as literals)
(MASS, DAMPING, STATIC_FORCE, HALF_BACKLASH, LONG_ERROR, SHORT_ERROR, OMEGA1, OMEGA_MESH,
 ROLL_SPEED, BASE_PITCH, GEAR_ERROR, OMEGA2, RIPPLE_FORCE, OMEGA_RIPPLE, CELLS_PER_PERIOD,
 CENTRE_RUNOUT, CELLS_PER_METRE, GEAR_MODULATION, GEAR_MODULATION_PHASE, PINION_MODULATION,
 PINION_MODULATION_PHASE, OFF_PATH_PAIRS, N_PARAMETERS) = range(23)


@numba.njit(cache=True, parallel=True, fastmath=True, nogil=True)
def decimate(h, x, n_sub, n_out):
    """``y[r, i] = sum_t h[t] x[r, i n_sub + t]`` (``h`` symmetric: a convolution). The inner
    product runs over a one-dimensional slice of the row, which numba vectorises (indexing the
    2-D array in the loop kept it scalar: five times slower)."""
    y = np.empty((x.shape[0], n_out))
    taps = h.size
    for r in numba.prange(x.shape[0]):
        row, out = x[r], y[r]
        for i in range(n_out):
            window = row[i * n_sub:i * n_sub + taps]
            acc = 0.0
            for t in range(taps):
                acc += h[t] * window[t]
            out[i] = acc
    return y


#: off-path pairs in the kernel's tables (:func:`physics.gear.tooth_contact.pair_slots`)
OFF_PATH = 3


@numba.njit(cache=True, fastmath=True, inline="always")
def _contact(k, x, g, half, c_v):
    """Force of one pair at deflection ``x``: stiffness times the dead-zone deflection plus its
    share of damping.

    ``g`` is the pair's gap on its drive flanks (their wear and form deviation): it moves the
    drive flanks' contact to ``x > half + g`` and leaves the coast flanks' at ``x < -half``
    (the model follows the drive flanks' wear only; material worn off a drive flank widens the
    backlash of that pair, it never closes it). The damping acts through the contact: nothing
    while the flanks are apart, and a contact never pulls (drive flank >= 0, coast flank <= 0).
    """
    if x - g > half:
        return max(k * (x - g - half) + c_v, 0.0)
    if x < -half:
        return min(k * (x + half) + c_v, 0.0)
    return 0.0


@numba.njit(cache=True, fastmath=True, inline="always")
def _lerp(tab, row, i0, i1, frac):
    return tab[row, i0] + (tab[row, i1] - tab[row, i0]) * frac


@numba.njit(cache=True, fastmath=True, inline="always")
def _entry_shift(q, u_in):
    """Share of the entering pair's stiffness that an entry moved by ``u_in`` table cells adds
    (> 0) or removes (< 0) at ``q`` cells from the nearest period boundary.

    The tables' linear interpolation spreads the nominal entry over the cell before the
    boundary (a ramp ``clamp(q + 1, 0, 1)``); the moved entry is the same ramp shifted by
    ``u_in``. Their difference keeps the stiffness continuous in time (so the RK4 step converges
    at its order, wherever the step's instants fall), removes or adds exactly ``u_in`` cells'
    worth of the entering pair and vanishes with the shift.
    """
    return min(1.0, max(0.0, q + 1.0 - u_in)) - min(1.0, max(0.0, q + 1.0))


# The mesh state and the small helpers are inlined into the integrator (numba IR inlining);
# the per-stage functions (_mesh, _accel, _extra) are calls: inlining those too ran the
# integrator about 1.3 times faster but took its first compilation from about 12 s to 48 s,
# paid by every fresh install and every test worker (bench/bench_dynamics.py).
@numba.njit(cache=True, fastmath=True, inline="always")
def _mesh_state(par, tab, pos, da, kf):
    """The pairs at table position ``pos``: stiffness, gap and force factor of pair A, pair B
    and an early-entering pair C (``k_c`` 0 without one), and stiffness and gap of the three
    off-path pairs (:func:`off_path_rows`).

    ``pos`` in [0, n) is the mesh phase in table cells; the tables are interpolated linearly and
    periodically. In the last cell of a mesh period the pairs move on by one slot (the pair
    before its entry becomes A, A becomes B, B past the end becomes the pair after it): where
    the model has off-path pairs each is interpolated to its own value at the next cell, not to
    the next pair's (a slot's table jumps there from one tooth to the next, and a gap that
    jumps from the entering pair's to the far one of the pair behind it would part the entering
    pair within the cell). ``da`` is the centre-distance change [m] (gear run-out): it moves
    the ends of the path of contact (without off-path pairs; with them the entering pair is
    the one before its entry already); ``kf`` a factor on every pair's stiffness (the
    run-outs' modulations, :func:`_pinion_factor` and :func:`_extra`). It depends on the
    instant only, not on the state, so an RK4 step evaluates it at its two new instants
    (``t + dt/2``, shared by stages 2 and 3, and ``t + dt``, also the next step's stage 1).
    """
    n = tab.shape[1]
    i0 = int(pos)
    if i0 >= n:
        i0 = n - 1
    frac = pos - i0
    i1 = i0 + 1 if i0 + 1 < n else 0
    off = par[OFF_PATH_PAIRS] != 0.0
    n_per = int(par[CELLS_PER_PERIOD] + 0.5)
    if off and i1 % n_per == 0:  # the slots move on across this cell
        k_a, g_a = _lerp2(tab, 6, 0, i0, i1, frac), _lerp2(tab, 7, 2, i0, i1, frac)
        k_b, g_b = _lerp2(tab, 0, 1, i0, i1, frac), _lerp2(tab, 2, 3, i0, i1, frac)
        l_a, l_b = tab[4, i1], _lerp2(tab, 4, 5, i0, i1, frac)
        k0, g0, k1, g1 = 0.0, 1.0, 0.0, 1.0
        k2, g2 = _lerp2(tab, 8, 10, i0, i1, frac), _lerp2(tab, 9, 11, i0, i1, frac)
    else:
        k_a, k_b = _lerp(tab, 0, i0, i1, frac), _lerp(tab, 1, i0, i1, frac)
        g_a, g_b = _lerp(tab, 2, i0, i1, frac), _lerp(tab, 3, i0, i1, frac)
        l_a, l_b = _lerp(tab, 4, i0, i1, frac), _lerp(tab, 5, i0, i1, frac)
        k0, g0 = _lerp(tab, 6, i0, i1, frac), _lerp(tab, 7, i0, i1, frac)
        k1, g1 = _lerp(tab, 8, i0, i1, frac), _lerp(tab, 9, i0, i1, frac)
        k2, g2 = _lerp(tab, 10, i0, i1, frac), _lerp(tab, 11, i0, i1, frac)
    if kf != 1.0:
        k_a, k_b, k0, k1, k2 = k_a * kf, k_b * kf, k0 * kf, k1 * kf, k2 * kf
    k_c, g_c, l_c = 0.0, 0.0, 0.0
    if da != 0.0 and not off:
        # in the pinion's roll frame the exit (pinion tip) stays put and the entry (gear tip)
        # moves by d(a sin aw')/da = 1/sin aw' per unit centre distance: pairs enter later
        # when the centres part, earlier (the next pair ahead of time) when they close
        n_cells = par[CELLS_PER_PERIOD]
        q = pos % n_cells  # cells from the nearest period boundary (where a pair enters)
        if q > 0.5 * n_cells:
            q -= n_cells
        j = int(pos - q + 0.5) % n  # the boundary's cell (pos - q >= 0)
        share = _entry_shift(q, da * par[CELLS_PER_METRE])
        if share < 0.0:  # the entering pair (slot a) comes later
            k_a = max(k_a + share * tab[0, j] * kf, 0.0)
        elif share > 0.0:  # it comes earlier, beside the pairs of the tables
            k_c, g_c, l_c = share * tab[0, j] * kf, tab[2, j], tab[4, j]
    return k_a, k_b, k_c, g_a, g_b, g_c, l_a, l_b, l_c, k0, g0, k1, g1, k2, g2


@numba.njit(cache=True, fastmath=True, inline="always")
def _lerp2(tab, row0, row1, i0, i1, frac):
    """From row ``row0`` at cell ``i0`` to row ``row1`` at cell ``i1``: one pair's value as it
    moves from one slot to the next across a period boundary."""
    return tab[row0, i0] + (tab[row1, i1] - tab[row0, i0]) * frac


@numba.njit(cache=True, fastmath=True)
def _mesh(par, st, x, v):
    """Force factors and forces of the pairs (``st``: :func:`_mesh_state`) at deflection ``x``
    and its rate ``v``: pairs A (with an early-entering C) and B, and the off-path pairs'
    summed force (drive flanks only; factor 1). The mesh damping ``c`` is shared by stiffness
    between the pairs in contact at ``x``: a pair whose flanks are apart carries none."""
    k_a, k_b, k_c, g_a, g_b, g_c, l_a, l_b, l_c, k0, g0, k1, g1, k2, g2 = st
    half = par[HALF_BACKLASH]
    coast = x < -half
    engaged = 0.0
    if coast or x - g_a > half:
        engaged += k_a
    if coast or x - g_b > half:
        engaged += k_b
    if k_c > 0.0 and (coast or x - g_c > half):
        engaged += k_c
    if not coast:
        if k0 > 0.0 and x - g0 > half:
            engaged += k0
        if k1 > 0.0 and x - g1 > half:
            engaged += k1
        if k2 > 0.0 and x - g2 > half:
            engaged += k2
    c_v = par[DAMPING] * v / engaged if engaged > 0.0 else 0.0
    f_a = _contact(k_a, x, g_a, half, k_a * c_v)
    f_b = _contact(k_b, x, g_b, half, k_b * c_v)
    if k_c > 0.0:
        f_a += _contact(k_c, x, g_c, half, k_c * c_v) * l_c / l_a
    f_x = 0.0
    if not coast:  # the off-path pairs touch on their drive flanks only
        f_x = (_contact(k0, x, g0, half, k0 * c_v) + _contact(k1, x, g1, half, k1 * c_v)
               + _contact(k2, x, g2, half, k2 * c_v))
    return l_a, l_b, f_a, f_b, f_x


@numba.njit(cache=True, fastmath=True)
def _accel(par, st, x, v, e_dd, w, inv_m):
    """x'' of the reduced model in mesh state ``st``, given e'' and the static force w there
    (``inv_m``: the inverse of the equivalent mass), and the mesh force.

    Each pair's force enters with its factor (1, or the sliding-friction moment factor).
    """
    l_a, l_b, f_a, f_b, f_x = _mesh(par, st, x, v)
    return (w - l_a * f_a - l_b * f_b - f_x) * inv_m - e_dd, f_a + f_b + f_x


@numba.njit(cache=True, fastmath=True)
def _extra(par, t):
    """The effect library's time terms at t: the gear run-out's e'' on the line of action, its
    centre-distance change (the eccentricity's other component) and its modulation of the
    mesh stiffness (a factor), and the static force."""
    e_dd, da, kf = 0.0, 0.0, 1.0
    if par[GEAR_ERROR] != 0.0:
        e_dd = -par[GEAR_ERROR] * par[OMEGA2] ** 2 * math.sin(par[OMEGA2] * t)
        da = par[CENTRE_RUNOUT] * math.cos(par[OMEGA2] * t)
    if par[GEAR_MODULATION] != 0.0:
        kf += par[GEAR_MODULATION] * math.cos(par[OMEGA2] * t + par[GEAR_MODULATION_PHASE])
    w = par[STATIC_FORCE]
    if par[RIPPLE_FORCE] != 0.0:
        w += par[RIPPLE_FORCE] * math.sin(par[OMEGA_RIPPLE] * t)
    return e_dd, w, da, kf


@numba.njit(cache=True, fastmath=True, inline="always")
def _pinion_factor(mu_c, mu_s, s1, c1):
    """The pinion run-out's modulation ``1 + mu cos(w1 t + phi)`` from the sine and cosine of
    ``w1 t`` the kernel tracks (``mu_c``, ``mu_s``: ``mu cos phi``, ``mu sin phi``)."""
    return 1.0 + mu_c * c1 - mu_s * s1


@numba.njit(cache=True, fastmath=True, inline="always")
def _wrap(pos, n):
    return pos - n if pos >= n else pos


@numba.njit(cache=True, parallel=True, fastmath=True, nogil=True)
def integrate(par, tables, x0, dt, n_transient, n_sub, n_out, n_bins, half, step0=0):
    """DTE at every step and the mesh force averaged over every step (the RK4 stages' weights,
    Simpson's rule: a step's record does not alias the force's harmonics above the
    integration rate), from ``(half - 1) n_sub`` steps before the first output instant to
    ``half n_sub`` after the last (for :func:`anti_aliased`); the pairs' loads at the output
    instants; the drive-flank load by mesh phase over the record. The integration starts at
    step ``step0`` (time ``step0 dt``, every excitation at its phase then) from ``x0`` at
    rest."""
    n = par.shape[0]
    k_first = n_sub - half * n_sub  # first and last recorded step, relative to the transient
    k_last = n_out * n_sub + half * n_sub
    n_fine = k_last - k_first + 1
    dte = np.empty((n, n_fine))
    force = np.empty((n, n_fine))
    load_a = np.empty((n, n_out))
    load_b = np.empty((n, n_out))
    phase_sum = np.zeros((n, n_bins))
    phase_count = np.zeros((n, n_bins))
    for j in numba.prange(n):
        _integrate_one(par[j], tables[j], x0[j], dt, n_transient, n_sub, n_out, n_bins, half,
                       step0, dte[j], force[j], load_a[j], load_b[j], phase_sum[j],
                       phase_count[j])
    return dte, force, load_a, load_b, phase_sum, phase_count


@numba.njit(cache=True, fastmath=True, nogil=True)
def _integrate_one(p, tab, x0, dt, n_transient, n_sub, n_out, n_bins, half, step0, dte, force,
                   load_a, load_b, phase_sum, phase_count):
    """One scenario of :func:`integrate` (parameters ``p``, tables ``tab``, start ``x0``) into
    its rows of the outputs. Compiled on its own: the parallel loop around it then stays small,
    which numba's parallel pass compiles in a fraction of the time it takes over this body."""
    k_first = n_sub - half * n_sub
    k_last = n_out * n_sub + half * n_sub
    n_phase = tab.shape[1]
    x, v = x0, 0.0
    inv_m = 1.0 / p[MASS]
    n_tab = float(n_phase)
    n_per = p[CELLS_PER_PERIOD]  # table cells per mesh period
    # mesh phase advance per step, in table cells
    inc = p[ROLL_SPEED] * dt / p[BASE_PITCH] * n_per
    pos = (inc * step0) % n_tab
    # e''(t) = -E_l w1^2 sin(w1 t) - E_s wm^2 sin(wm t): sines advanced by exact rotations
    a_l, a_s = p[LONG_ERROR] * p[OMEGA1] ** 2, p[SHORT_ERROR] * p[OMEGA_MESH] ** 2
    cl, sl = math.cos(0.5 * p[OMEGA1] * dt), math.sin(0.5 * p[OMEGA1] * dt)
    cs, ss = math.cos(0.5 * p[OMEGA_MESH] * dt), math.sin(0.5 * p[OMEGA_MESH] * dt)
    t0 = step0 * dt
    # sin, cos of w1 t and wm t
    s1, c1 = math.sin(p[OMEGA1] * t0), math.cos(p[OMEGA1] * t0)
    s2, c2 = math.sin(p[OMEGA_MESH] * t0), math.cos(p[OMEGA_MESH] * t0)
    total = n_transient + k_last + 1  # the last recorded step's force needs its stages
    mu_c = p[PINION_MODULATION] * math.cos(p[PINION_MODULATION_PHASE])
    mu_s = p[PINION_MODULATION] * math.sin(p[PINION_MODULATION_PHASE])
    # the time terms and the mesh state at the step's start: each instant's are evaluated
    # once (the end of a step is the start of the next)
    x0e, w0, da0, kf0 = _extra(p, t0)
    st0 = _mesh_state(p, tab, pos, da0, kf0 * _pinion_factor(mu_c, mu_s, s1, c1))
    for step in range(step0, total + 1):
        # the mesh at (t, x) serves both the record of the state reached and stage 1 of RK4
        l_a, l_b, f_a, f_b, f_x = _mesh(p, st0, x, v)
        k = step - n_transient
        f = f_a + f_b + f_x
        recorded = k_first <= k <= k_last
        if recorded:
            dte[k - k_first] = x
            if 0 < k <= n_out * n_sub:
                b = int((pos % n_per) / n_per * n_bins)
                if b >= n_bins:
                    b = n_bins - 1
                phase_sum[b] += max(f, 0.0)  # drive flanks only (coast impacts: < 0)
                phase_count[b] += 1.0
                if k % n_sub == 0:
                    i = k // n_sub - 1
                    load_a[i] = f_a
                    load_b[i] = f_b
        if step == total:
            break
        s1h, c1h = s1 * cl + c1 * sl, c1 * cl - s1 * sl  # at t + dt/2
        s2h, c2h = s2 * cs + c2 * ss, c2 * cs - s2 * ss
        s1n, c1n = s1h * cl + c1h * sl, c1h * cl - s1h * sl  # at t + dt
        s2n, c2n = s2h * cs + c2h * ss, c2h * cs - s2h * ss
        t = step * dt
        xhe, wh, dah, kfh = _extra(p, t + 0.5 * dt)
        x1e, w1, da1, kf1 = _extra(p, t + dt)
        e0 = x0e - (a_l * s1 + a_s * s2)
        eh = xhe - (a_l * s1h + a_s * s2h)
        e1 = x1e - (a_l * s1n + a_s * s2n)
        a1 = (w0 - l_a * f_a - l_b * f_b - f_x) * inv_m - e0
        pos_h = _wrap(pos + 0.5 * inc, n_tab)
        pos_1 = _wrap(pos + inc, n_tab)
        st_h = _mesh_state(p, tab, pos_h, dah, kfh * _pinion_factor(mu_c, mu_s, s1h, c1h))
        st1 = _mesh_state(p, tab, pos_1, da1, kf1 * _pinion_factor(mu_c, mu_s, s1n, c1n))
        a2, f2 = _accel(p, st_h, x + 0.5 * dt * v, v + 0.5 * dt * a1, eh, wh, inv_m)
        a3, f3 = _accel(p, st_h, x + 0.5 * dt * (v + 0.5 * dt * a1), v + 0.5 * dt * a2, eh,
                        wh, inv_m)
        a4, f4 = _accel(p, st1, x + dt * (v + 0.5 * dt * a2), v + dt * a3, e1, w1, inv_m)
        if recorded:
            force[k - k_first] = (f + 2.0 * (f2 + f3) + f4) / 6.0
        x += dt * (v + dt * (a1 + a2 + a3) / 6.0)
        v += dt * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
        pos = pos_1
        x0e, w0, st0 = x1e, w1, st1
        s1, c1, s2, c2 = s1n, c1n, s2n, c2n
        if step % 4096 == 0:  # keep the rotations on the unit circle
            r1, r2 = math.hypot(s1, c1), math.hypot(s2, c2)
            s1, c1, s2, c2 = s1 / r1, c1 / r1, s2 / r2, c2 / r2
