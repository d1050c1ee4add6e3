"""The line contact of worn flanks, solved with the wear as a gap (thesis 2.6, done numerically).

A worn flank is no longer an involute: its wear depth varies over tens of micrometres of profile
arc, as narrow as the Hertz band itself, so no radius of curvature describes it (the thesis's
``R_new = R_old - h_w`` treats a depth as a radius). Here the wear enters the contact as what it
is, a gap. Across the band, at tangent offset ``x`` from the contact point at roll coordinate
``s``, the two flanks stand apart by

    g(x) = x^2 / (2 R) + [h1(s1(x)) - h1(s)] + [h2(s2(x)) - h2(s)],

where ``R`` is the unworn involutes' equivalent radius and ``s_i(x) = s + x r_bi / R_i`` the
roll coordinate at which flank i's point at arc offset ``x`` meets the line of action (on an
involute ``dl = R dR / r_b``, and ``R_i`` grows with ``s`` on both flanks' path). The normal
pressure ``p(x) >= 0`` then solves the elastic half-space line contact

    g(x) + u(x) - delta >= 0,  p (g + u - delta) = 0,  int p dx = w,
    u(x) = -(2 / (pi E*)) int p(x') ln|x - x'| dx'     (Johnson, Contact Mechanics, eq. 2.25b)

by the projected conjugate-gradient method of Polonsky & Keer (Wear 231 (1999) 206-219), the
deflection as the product of the cell pressures with the influence matrix of piecewise-constant
pressure cells (the kernel of :mod:`physics.tribology.mixed_ehl`; a symmetric Toeplitz matrix of
64 to 512 cells, whose product is faster than an FFT convolution at these sizes:
``bench/bench_wear.py``). Every position is solved at once, in Hertz units of its unworn
contact (``X = x / b``, ``P = p / p_max``, gap over ``b^2 / R``): the cells have one width for
all positions, so one matrix serves the whole batch. An unworn position (gap correction
below ``GAP_TOL`` of ``b^2/R`` once its tilt is removed, which only shifts the band) keeps the
closed-form Hertz ellipse; this also makes the zero-wear result exact.

Each flank point wears as the band sweeps over it: the per-pass wear of a point is the Archard
integral over the pressure it meets (Bajpai, Kahraman & Anderson, J. Tribol. 126 (2004)
787-796). :meth:`WornContact.sweep` carries that out with the cumulative load of each position's
pressure, so the load is conserved however few flank points fall inside a band.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numba
import numpy as np
from scipy.interpolate import make_interp_spline
from scipy.linalg import toeplitz

from physics.blas import one_blas_thread
from physics.gear import contact
from physics.params import OutOfScope

#: half-length of the solution window, in unworn Hertz half-widths, around the gap's minimum
#: (doubled for the positions whose contact reaches the window's edge)
WINDOW = 2.5
#: cells across the window (2 WINDOW / CELLS = 0.078 b: Hertz p_max within 0.1 %)
CELLS = 64
#: a position whose gap correction (tilt removed) stays below this share of b^2/R keeps Hertz
#: (the pressure moves by about that share of p_max)
GAP_TOL = 2e-3
#: wear ripples shorter than this share of the pair's smallest Hertz half-width are levelled
#: (:func:`flank_profile`, :func:`levelling_length`)
LEVEL = 0.5
#: positions carrying less than this share of the path's largest load keep a Hertz band
LIGHT = 0.02
#: convergence of the pressure: relative change of P between two iterations
TOL = 1e-6
MAX_ITER = 400


@lru_cache(maxsize=4)
def influence_matrix(n: int, dx: float) -> np.ndarray:
    """Influence matrix of uniform cells: ``K[i, j] = -(1/pi) int_cell_j ln|X_i - X'| dX'``,
    so that ``P @ K`` is the deflection (Hertz units) of each row's cell pressures ``P``."""
    m = np.arange(n, dtype=float)

    def prim(t: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(t == 0, 0.0, t * np.log(np.abs(t)) - t)

    K = toeplitz(-(prim((m + 0.5) * dx) - prim((m - 0.5) * dx)) / math.pi)
    K.setflags(write=False)
    return K


def solve_gap_contact(gap: np.ndarray, dX: float, load: float = math.pi / 2,
                      tol: float = TOL, max_iter: int = MAX_ITER) -> tuple[np.ndarray, int]:
    """Pressure of elastic line contacts with rigid gaps ``gap`` (rows, Hertz units).

    Every row is a contact on cells of width ``dX``; ``gap`` is ``g / (b^2/R)``; the pressure
    ``P`` (over ``p_max`` of Hertz) carries ``int P dX = load`` (pi/2 for the Hertz load) and
    satisfies the contact conditions with the deflection ``-(1/pi) int P ln|X - X'|``.
    Polonsky & Keer's constrained conjugate gradient (:func:`_polonsky_keer`), compiled, every
    row at once; returns ``P`` and the most iterations a row took. Raises ``RuntimeError``
    when a row does not converge.
    """
    gap = np.ascontiguousarray(np.atleast_2d(np.asarray(gap, dtype=float)))
    K = influence_matrix(gap.shape[1], float(dX))
    with one_blas_thread():  # products this small
        P, iterations, change = _polonsky_keer(gap, K, float(dX), float(load), float(tol),
                                               int(max_iter))
    failed = np.flatnonzero(iterations < 0)
    if failed.size:
        worst = int(failed[np.argmax(change[failed])])
        raise RuntimeError(f"the worn contact did not converge in {max_iter} iterations (row "
                           f"{worst}: relative change {change[worst]:.2g})")
    return P, int(iterations.max(initial=0))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _polonsky_keer(gap, K, dX, load, tol, max_iter):
    """Polonsky & Keer (Wear 231 (1999) 206-219) on every row of ``gap``, without the FFT: the
    influence matrix ``K`` is symmetric and small, and each iteration's deflections of all rows
    still iterating are one matrix product. From a uniform pressure where the rigid gap lies
    within half a Hertz approach of its least value, an iteration takes a conjugate-gradient
    step on the cells in contact (:func:`_direction`, :func:`_step`) and leaves a row alone
    once its pressure moved by less than ``tol`` (relative). Returns the pressures, the
    iterations each row took (-1: not converged in ``max_iter``) and its last relative change.
    IEEE arithmetic in a fixed order (no fast-math): the same on every run, whether compiled or
    read from the cache."""
    m, n = gap.shape
    P = np.zeros((m, n))
    for k in range(m):
        _start(gap[k], load, dX, P[k])
    t = np.zeros((m, n))
    g_old = np.ones(m)
    delta = np.zeros(m)
    change = np.full(m, np.inf)
    iterations = np.full(m, -1)
    active = np.arange(m)
    for it in range(1, max_iter + 1):
        na = active.size
        Pa = np.empty((na, n))
        ta = np.empty((na, n))
        for a in range(na):
            Pa[a] = P[active[a]]
            ta[a] = t[active[a]]
        g_raw = np.dot(Pa, K)  # the deflections (K symmetric)
        approach = np.empty(na)
        for a in range(na):
            k = active[a]
            approach[a], g_old[k] = _direction(g_raw[a], gap[k], Pa[a], ta[a], delta[k],
                                               g_old[k])
        r = np.dot(ta, K)
        kept = 0
        for a in range(na):
            k = active[a]
            delta[k], change[k] = _step(g_raw[a], approach[a], r[a], Pa[a], ta[a], load, dX,
                                        P[k], t[k])
            if change[k] < tol:
                iterations[k] = it
            else:
                active[kept] = k
                kept += 1
        active = active[:kept]
        if kept == 0:
            break
    return P, iterations, change


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _start(gap, load, dX, P):
    """A uniform pressure carrying ``load`` where ``gap`` lies within half a Hertz approach of
    its least value, into ``P``."""
    least = gap.min()
    total = 0.0
    for i in range(gap.size):
        if gap[i] - least < 0.5:
            P[i] = 1.0
            total += 1.0
    for i in range(gap.size):
        P[i] *= load / (total * dX)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _direction(g_raw, gap, P, t, delta, g_old):
    """The gap under pressure ``P`` (``g_raw``, deflections in, gap added in place) and the
    conjugate direction ``t`` (in place) on the cells in contact; returns the approach (the
    gap's mean over them) and the squared gap norm for the next step's ``beta``."""
    n = gap.size
    count, mean = 0, 0.0
    for i in range(n):
        g_raw[i] += gap[i]
        if P[i] > 0:
            count += 1
            mean += g_raw[i]
    approach = mean / count
    G = 0.0
    for i in range(n):
        g = g_raw[i] - approach if P[i] > 0 else 0.0
        G += g * g
    beta = delta * G / g_old
    for i in range(n):
        t[i] = (g_raw[i] - approach) + beta * t[i] if P[i] > 0 else 0.0
    return approach, (G if G > 0 else 1.0)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _step(g_raw, approach, r, P, t, load, dX, P_out, t_out):
    """The step along ``t`` (``r``: its deflections), clipped at zero, open cells that
    interpenetrate joining the contact (the method's overlap step, which restarts the conjugate
    directions: returned ``delta`` 0), scaled to carry ``load``, into ``P_out`` and ``t_out``;
    returns ``delta`` and the pressure's relative change."""
    n = P.size
    count, mean = 0, 0.0
    for i in range(n):
        if P[i] > 0:
            count += 1
            mean += r[i]
    mean /= count
    rt, gt = 0.0, 0.0
    for i in range(n):
        ri = r[i] - mean if P[i] > 0 else 0.0
        gi = g_raw[i] - approach if P[i] > 0 else 0.0
        rt += ri * t[i]
        gt += gi * t[i]
    tau = gt / rt if rt > 0 else 0.0
    overlap, total = False, 0.0
    new = np.empty(n)
    for i in range(n):
        v = max(P[i] - tau * t[i], 0.0)
        opened = g_raw[i] - approach
        if v == 0.0 and opened < 0.0:
            overlap = True
            v = -tau * opened
        new[i] = v
        total += v
    scale = load / (total * dX)
    moved, total = 0.0, 0.0
    for i in range(n):
        v = new[i] * scale
        moved += abs(v - P[i])
        total += v
        P_out[i] = v
        t_out[i] = t[i]
    return (0.0 if overlap else 1.0), moved / total


@numba.njit(cache=True, nogil=True, inline="always")
def _hertz_passed(X):
    """``int_{-inf}^X sqrt(1 - t^2) dt`` of the Hertz ellipse (Hertz units): 0 to pi/2."""
    c = min(max(X, -1.0), 1.0)
    return 0.5 * (c * math.sqrt(1.0 - c * c) + math.asin(c)) + math.pi / 4


@dataclass(frozen=True)
class WornContact:
    """Pressure across the band at every mesh position, in Hertz units of the unworn contact.

    ``solved`` marks the positions solved numerically (the others are Hertz ellipses centred at
    ``centre``); for those, ``P`` holds the cell pressures on ``X = X0 + (i + 1/2) dX``.
    """

    half_width: np.ndarray  # unworn Hertz half-width b [m] (0 where unloaded)
    p_hertz: np.ndarray  # unworn Hertz p_max [Pa]
    centre: np.ndarray  # band centre for Hertz rows, window start X0 for solved rows [-]
    solved: np.ndarray  # bool per position
    P: np.ndarray  # (solved rows, CELLS) cell pressures / p_hertz
    dX: float

    @property
    def peak_ratio(self) -> np.ndarray:
        """Largest pressure at each position over its unworn Hertz pressure [-]."""
        peak = np.ones_like(self.p_hertz)
        peak[self.solved] = self.P.max(axis=1)
        return peak

    @property
    def p_max(self) -> np.ndarray:
        """Largest pressure at each position [Pa]."""
        return self.peak_ratio * self.p_hertz

    @cached_property
    def _passed(self) -> np.ndarray:
        """Load passed up to each cell edge of the solved rows (Hertz units)."""
        return np.concatenate([np.zeros((self.P.shape[0], 1)),
                               np.cumsum(self.P, axis=1) * self.dX], axis=1)

    def sweep(self, s: np.ndarray, points: np.ndarray, scale: np.ndarray, weight: np.ndarray
              ) -> np.ndarray:
        """Per-pass integral ``sum_j weight_j int p_j dx`` over the band's sweep of each flank
        point at roll coordinates ``points`` (uniformly spaced, like ``s``), for contact centres
        at ``s``: ``scale_j = R_j / r_b`` maps a roll offset to an arc offset of the flank.
        Contact centres are cells ``[s_{j-1/2}, s_{j+1/2}]``, cut at the path's ends;
        ``points`` may reach beyond them, where the band still presses the flank."""
        b = np.where(self.half_width > 0, self.half_width, 1.0)
        to_X = scale / b
        # each position presses the points within its window's reach (a band of the matrix)
        span = np.abs(self.centre) + 1.0  # a Hertz band presses |X - centre| <= 1
        width = self.P.shape[1] * self.dX
        span[self.solved] = np.maximum(np.abs(self.centre[self.solved]),
                                       np.abs(self.centre[self.solved] + width))
        step = points[1] - points[0]
        # an unloaded position (no band; b stands at 1 m) presses nothing and sets no reach
        reach = np.where(self.half_width > 0, span / to_X, 0.0)
        k = int(np.ceil(np.max(reach) / step)) + 1
        row = np.full(s.size, -1)
        row[self.solved] = np.arange(int(self.solved.sum()))
        load = self.p_hertz * self.half_width * weight  # p_max b carries P
        return _sweep(np.asarray(s, dtype=float), np.asarray(points, dtype=float),
                      np.asarray(to_X, dtype=float), self.centre, row, self._passed,
                      float(self.dX), np.asarray(load, dtype=float), k)


@numba.njit(cache=True, nogil=True)
def _sweep(s, points, to_X, centre, row, Q, dX, load, k):
    """:meth:`WornContact.sweep` compiled: each position ``i`` adds to the ``2 k + 1`` points
    nearest it (clipped at the grid's ends, each point once) the load its band passes over the
    point's stretch, ``load_i`` times the passed share at the cell's lower edge less that at
    its upper edge; the share is the Hertz ellipse's (``row[i] < 0``) or the solved cells'
    cumulative pressure ``Q[row[i]]``, linear within a cell."""
    n, m = points.size, s.size
    step = points[1] - points[0]
    out = np.zeros(n)
    for i in range(m):
        low = s[0] if i == 0 else 0.5 * (s[i] + s[i - 1])
        high = s[m - 1] if i == m - 1 else 0.5 * (s[i + 1] + s[i])
        c = int(np.rint((s[i] - points[0]) / step))
        last = -1
        for j in range(-k, k + 1):
            at = min(max(c + j, 0), n - 1)
            if at == last:
                continue
            last = at
            passed = _passed_at(row[i], Q, (points[at] - low) * to_X[i] - centre[i], dX) \
                - _passed_at(row[i], Q, (points[at] - high) * to_X[i] - centre[i], dX)
            out[at] += load[i] * passed
    return out


@numba.njit(cache=True, nogil=True, inline="always")
def _passed_at(r, Q, X, dX):
    """Load passed up to offset ``X`` from a band's centre (Hertz units): the ellipse's where
    ``r < 0``, else row ``r`` of the cumulative cell loads ``Q``, linear within a cell."""
    if r < 0:
        return _hertz_passed(X)
    q = Q[r]
    f = X / dX
    cell = min(max(math.floor(f), 0), q.size - 2)
    f = min(max(f - cell, 0.0), 1.0)
    return q[cell] + f * (q[cell + 1] - q[cell])


def worn_gap(at: np.ndarray, X: np.ndarray, half_width: np.ndarray, R: np.ndarray,
             scale1: np.ndarray, scale2: np.ndarray,
             h1: Callable[[np.ndarray], np.ndarray], h2: Callable[[np.ndarray], np.ndarray]
             ) -> np.ndarray:
    """The wear's part of the gap, over ``b^2/R``, at offsets ``X`` (rows: the positions
    ``at``) for the worn flanks ``h1, h2`` (:func:`flank_profile`)."""
    x = X * half_width[:, None]
    here = (h1(at) + h2(at))[:, None]
    worn = h1(at[:, None] + x * scale1[:, None]) + h2(at[:, None] + x * scale2[:, None])
    return (worn - here) * (R / half_width**2)[:, None]


def flank_profile(s: np.ndarray, wear: np.ndarray, arc: np.ndarray, level: float
                  ) -> Callable[[np.ndarray], np.ndarray]:
    """The worn flank as the band feels it: the wear depths on the grid ``s`` levelled over
    ``level`` [m] of profile arc, then a cubic spline, constant beyond the grid.

    ``arc`` is the profile arc length at the grid points (on an involute ``R^2 / (2 r_b)``).
    A wear ripple of wavelength ``lambda`` under the band raises the pressure by about ``pi E*
    delta / lambda`` (Johnson, Contact Mechanics, 13.2) and so wears itself away at a rate
    ``pi E* / (lambda p_mean)`` times the mean wear rate: ripples shorter than the band vanish
    within a small part of one profile update, so their end state, a level flank, is what the
    band sees (a Gaussian of standard deviation ``level`` in arc length). Without it an explicit
    update step would have to resolve that decay (well below 0.1 um). The spline avoids the
    corners of straight segments, each a wedge with a log-singular pressure (Johnson, 5.2).
    """
    if level > 0:
        weight, total = _levelling_weights(np.ascontiguousarray(arc, dtype=float).tobytes(),
                                           float(level))
        wear = weight @ wear / total
    spline = make_interp_spline(s, wear, k=3)

    def h(x: np.ndarray) -> np.ndarray:
        return spline(np.clip(x, s[0], s[-1]))

    return h


@lru_cache(maxsize=8)
def _levelling_weights(arc: bytes, level: float) -> tuple[np.ndarray, np.ndarray]:
    """The Gaussian weights of :func:`flank_profile` on the arc lengths ``arc`` (the bytes of a
    float array: one grid serves every wear update of a run) and their row sums."""
    a = np.frombuffer(arc)
    cell = np.gradient(a)  # arc length each point stands for (|d arc| on either flank)
    weight = np.exp(-0.5 * ((a[:, None] - a[None, :]) / level)**2) * np.abs(cell)
    weight.setflags(write=False)
    total = weight.sum(axis=1)
    total.setflags(write=False)
    return weight, total


def solve_worn_contact(s: np.ndarray, load_per_width: np.ndarray, R1: np.ndarray,
                       R2: np.ndarray, rb1: float, rb2: float, e_star: float,
                       flank: np.ndarray, wear1: np.ndarray, wear2: np.ndarray,
                       level: float, cells: int = CELLS) -> WornContact:
    """Pressure across the band at each roll coordinate ``s`` for loads ``w`` [N/m] on unworn
    involutes of radii ``R1, R2`` [m] worn by ``wear1, wear2`` [m], given on the flank grid
    ``flank`` (roll coordinates that reach beyond the path by the band's sweep; module text),
    levelled over ``level`` [m] of arc (:func:`flank_profile`, :func:`levelling_length`), on
    ``cells`` cells across the window."""
    w = np.asarray(load_per_width, dtype=float)
    loaded = w > 0
    R = contact.equivalent_radius(R1, R2)
    hertz = contact.hertz_half_width(np.where(loaded, w, 0.0), R, e_star)
    b = np.where(loaded, hertz, 0.0)
    bb = np.where(loaded, hertz, 1.0)  # 1 m where unloaded: a divisor, never a band
    p_h = np.where(loaded, contact.hertz_max_pressure(w, bb), 0.0)
    scale1, scale2 = rb1 / R1, rb2 / R2
    # the flanks' arc lengths on the flank grid (R grows with s on the pinion, falls on the gear)
    h1 = flank_profile(flank, wear1, (R1[0] + flank - s[0])**2 / (2 * rb1), level)
    h2 = flank_profile(flank, wear2, (R2[0] - flank + s[0])**2 / (2 * rb2), level)
    # a coarse look at the gap correction: its tilt only shifts the band
    probe = np.linspace(-WINDOW, WINDOW, 61)
    corr = worn_gap(s, np.broadcast_to(probe, (s.size, probe.size)), bb, R, scale1, scale2,
                    h1, h2)
    tilt = (corr[:, -1] - corr[:, 0]) / (2 * WINDOW)
    rest = corr - tilt[:, None] * probe
    # a pair that carries almost nothing (its partner took the load over the wear gap) keeps a
    # Hertz band at the least gap: its band is narrow against the wear's features, and its wear
    # is negligible beside the loaded pairs'
    light = w < LIGHT * w.max() if loaded.any() else loaded
    solved = loaded & ~light & (np.abs(rest).max(axis=1) > GAP_TOL)
    centre = np.where(loaded, np.where(light, probe[np.argmin(probe**2 / 2 + corr, axis=1)],
                                       -tilt), 0.0)  # X^2/2 + tilt X is least at X = -tilt
    dX = 2 * WINDOW / cells
    rows = np.flatnonzero(solved)
    P = np.zeros((rows.size, cells))
    if rows.size:
        # centre each window on the least total rigid gap within reach of the band
        low = probe[np.argmin(probe**2 / 2 + corr[rows], axis=1)]
        P, centre[rows] = _solve_rows(s[rows], low, bb[rows], R[rows], scale1[rows],
                                      scale2[rows], h1, h2, dX, cells)
    return WornContact(b, p_h, centre, solved, P, dX)


def _solve_rows(at: np.ndarray, low: np.ndarray, b: np.ndarray, R: np.ndarray,
                scale1: np.ndarray, scale2: np.ndarray, h1: Callable, h2: Callable, dX: float,
                cells: int) -> tuple[np.ndarray, np.ndarray]:
    """Cell pressures and window starts of the positions ``at`` whose gap is least at ``low``.
    A contact that reaches its window's edge is solved again in a window twice as wide; the
    other rows are then padded with open cells to the same width."""
    x0 = low - cells * dX / 2
    X = x0[:, None] + (np.arange(cells) + 0.5) * dX
    gap = X**2 / 2 + worn_gap(at, X, b, R, scale1, scale2, h1, h2)
    try:
        P, _ = solve_gap_contact(gap, dX)
    except RuntimeError as err:  # a stated end of the model's scope, not a crash
        raise OutOfScope(f"{err}: the worn flanks no longer meet as one line contact (positions "
                         f"at {at.min() * 1e3:+.3f} to {at.max() * 1e3:+.3f} mm of roll); "
                         "physics.tribology.contact_wear follows wear beyond it") from None
    edge = (P[:, 0] > 0) | (P[:, -1] > 0)
    if not edge.any():
        return P, x0
    if cells * dX >= 16 * WINDOW:
        raise OutOfScope(f"the worn contact at roll coordinate {at[edge][0] * 1e3:+.3f} mm "
                         f"spreads beyond {cells * dX / 2:g} Hertz half-widths of its load: the "
                         "worn flanks no longer meet as one line contact")
    wide, wide_x0 = _solve_rows(at[edge], low[edge], b[edge], R[edge], scale1[edge],
                                scale2[edge], h1, h2, dX, 2 * cells)
    pad = (wide.shape[1] - cells) // 2
    out = np.pad(P, ((0, 0), (pad, wide.shape[1] - cells - pad)))
    out[edge] = wide
    start = x0 - pad * dX
    start[edge] = wide_x0
    return out, start


def band_reach(half_width: np.ndarray, R1: np.ndarray, R2: np.ndarray, rb1: float, rb2: float
               ) -> tuple[float, float]:
    """Roll distances [m] before the path's start and after its end that a band of these
    half-widths presses (the solution window, in roll coordinates), each at most half the
    radius of curvature there: the involute ends at the base circle, and the band's linear map
    of arc to roll distance holds only where the curvature changes little over it."""
    reach = WINDOW * half_width * np.maximum(rb1 / R1, rb2 / R2)
    return float(min(reach[0], 0.5 * R1[0])), float(min(reach[-1], 0.5 * R2[-1]))


def levelling_length(load_per_width: float, R: np.ndarray, e_star: float) -> float:
    """Arc length [m] over which wear ripples are levelled (:func:`flank_profile`):
    ``LEVEL`` times the smallest Hertz half-width along the path at the load per width
    ``load_per_width`` [N/m]; a property of the pair and its load, whatever positions a call
    solves."""
    return float(LEVEL * contact.hertz_half_width(load_per_width, np.min(R), e_star))
