"""Numerical mixed-EHL solver of the steady, isothermal line contact (thesis 2.4).

This module solves the rough-surface elastohydrodynamic line-contact problem that the
Masjedi-Khonsari regressions of :mod:`physics.tribology.lubrication` were fitted to (M. Masjedi,
M.M. Khonsari, ASME J. Tribol. 134 (2012) 011503), so that the load share carried by the
asperities can be computed instead of read off a regression. The wear model reads it through
the precomputed table of :mod:`physics.tribology.asperity_table` (the default,
``tribology.asperity_model = "solver"``).

Problem (dimensionless in Hertz units, Venner & Lubrecht, *Multilevel Methods in Lubrication*,
Elsevier 2000, ch. 7)
------------------------------------------------------------------------------------------
``X = x/b``, ``P = p/p_H``, ``H = h R / b^2`` with the Hertz half-width ``b = sqrt(8 w R /
(pi E'))`` and maximum pressure ``p_H = 2 w / (pi b) = E' b / (4 R)``; ``E'`` is Hamrock's
reduced modulus (``2/E' = (1-v1^2)/E1 + (1-v2^2)/E2``), ``w`` the load per unit face width,
``u_e`` the entraining (mean rolling) velocity. Domain ``X in [x_in, x_out]`` (default
``[-4.5, 1.5]``), uniform grid of ``n`` nodes.

1. Average (modified) Reynolds equation of Patir & Cheng, steady, rolling/sliding::

       d/dX( phi_x rho_bar H^3 / (eta_bar lambda_bar) dP/dX ) = d(rho_bar H_T)/dX,
       lambda_bar = 12 eta0 u_e R^2 / (b^3 p_H)

   - pressure flow factor, isotropic Gaussian roughness (Peklenik number gamma = 1):
     ``phi_x = 1 - 0.90 exp(-0.56 h/sigma)`` (N. Patir, H.S. Cheng, "An average flow model for
     determining effects of three-dimensional roughness on partial hydrodynamic lubrication",
     ASME J. Lubr. Technol. 100 (1978) 12-17, Table 1; fitted for ``h/sigma > 0.5``; below
     0.5 we keep the formula, which tends to 0.1 at ``h = 0``, and no Poiseuille flow is
     admitted for ``h <= 0``);
   - shear (sliding) flow: the shear flow factor enters as ``(u_s sigma / 2) d(rho Phi_s)/dx``
     with ``Phi_s`` proportional to ``(sigma1/sigma)^2 - (sigma2/sigma)^2`` for surfaces of the
     same texture (N. Patir, H.S. Cheng, ASME J. Lubr. Technol. 101 (1979) 220-229). Both
     flanks are ground gear steel of the same finish, so the term vanishes and the solution
     does not depend on the slide-roll ratio (isothermal);
   - Couette flow through the average gap ``h_T = E[max(h + delta, 0)]`` of a Gaussian
     composite roughness ``delta`` of RMS ``sigma`` (Patir & Cheng 1978, eq. for h_T):
     ``h_T = h Phi(h/sigma) + sigma phi(h/sigma)`` with ``Phi``/``phi`` the standard normal CDF
     and density; ``dh_T/dh = Phi(h/sigma)`` is the contact factor ``phi_c`` of C. Wu, L. Zheng,
     "An average Reynolds equation for partial film lubrication with a contact factor", ASME J.
     Tribol. 111 (1989) 188-191. For ``h >> sigma``, ``h_T -> h`` and ``phi_x -> 1``.

   ``h`` is the nominal film: the separation of the mean planes of the two rough surfaces.

2. Film thickness with the elastic deflection of the line contact,
   ``H = H0 + X^2/2 - (1/pi) int (P + P_a) ln|X - X'| dX'``: the influence coefficients of a
   piecewise-constant pressure on each cell (exact integrals of the log kernel) form a
   Toeplitz matrix; the deflection is evaluated as a zero-padded FFT convolution,
   ``O(n log n)``. The asperity pressure ``P_a`` deforms the bodies as the fluid pressure does.

3. Roelands viscosity and Dowson-Higginson density from :mod:`physics.tribology.lubrication` (not
   re-implemented here), at the given film temperature.

4. Asperity pressure of Greenwood & Tripp (J.A. Greenwood, J.H. Tripp, "The contact of two
   nominally flat rough surfaces", Proc. IMechE 185 (1970-71) 625-633), built on the
   Greenwood-Williamson summit model (Proc. R. Soc. A 295 (1966) 300-319) with Gaussian summit
   heights::

       p_a = K E* F_{5/2}(h/sigma),
       K = (16 sqrt(2) pi / 15) (eta_s beta sigma)^2 sqrt(sigma/beta),
       F_n(t) = (2 pi)^(-1/2) int_t^inf (s - t)^n exp(-s^2/2) ds.

   ``E*`` is Greenwood's reduced modulus ``1/E* = (1-v1^2)/E1 + (1-v2^2)/E2`` (Greenwood &
   Williamson and Greenwood & Tripp call it E'): ``E* = E'/2`` in Hamrock's convention used
   for every other group here. The factor follows from summing Hertz contacts of spherical
   summits of radius ``beta`` on both surfaces (density ``eta_s`` each) over their lateral
   offsets; several EHL papers multiply the same ``K`` by Hamrock's ``E'`` instead, which
   doubles ``p_a``. ``sigma`` is the composite RMS roughness, taken for the summit-height
   deviation as usual (e.g. I.R.G. Gelinck, D.J. Schipper, "Calculation of Stribeck curves for
   line contacts", Tribol. Int. 33 (2000) 175-181). ``F_n`` is evaluated in closed form with
   the parabolic cylinder function, ``F_n(t) = Gamma(n+1) (2 pi)^(-1/2) exp(-t^2/4)
   D_{-n-1}(t)`` (from ``int_0^inf u^n exp(-u^2/2 - t u) du = Gamma(n+1) exp(t^2/4)
   D_{-n-1}(t)``), vectorised through :func:`scipy.special.pbdv`; ``F_n' = -n F_{n-1}``.

5. Load balance: ``int (P + P_a) dX = pi/2`` (hydrodynamic plus asperity load equals ``w``),
   the equation that fixes ``H0``.

Numerical method
----------------
Newton-Raphson on the fully coupled system (all nodal pressures and ``H0``), as in L.G.
Houpert, B.J. Hamrock, "Fast approach for calculating film thicknesses and pressures in
elastohydrodynamically lubricated contacts at high loads", ASME J. Tribol. 108 (1986)
411-420, which converges at Hertz pressures of several GPa where point relaxation stalls.

- Finite volumes: second-order central Poiseuille fluxes with arithmetic face averages of
  ``phi_x rho H^3 / (eta lambda_bar)``, second-order upstream Couette fluxes (first order at
  the first face), as Venner & Lubrecht (2000) recommend for heavily loaded contacts.
- Cavitation (Reynolds condition ``P >= 0``) as the complementarity problem of M.M. Kostreva
  ("Elasto-hydrodynamic lubrication: a non-linear complementarity problem", Int. J. Numer.
  Methods Fluids 4 (1984) 377-397): ``P >= 0``, ``-R >= 0``, ``P R = 0`` with ``R`` the
  discrete Reynolds residual, solved by the primal-dual active-set (semi-smooth Newton) form
  of ``min(P, -c R) = 0`` with ``c -> 0``: a node is held at ``P = 0`` while ``P = 0`` and
  ``R <= 0``. The active set moves by one node per step, so the problem is first solved on
  grids of about n/2, n/4, ... (nested iteration, down to ~160 nodes) and interpolated up.
- Jacobian: the Reynolds derivatives are banded in ``P`` and ``H``; ``dH/dP`` is the dense
  Toeplitz influence matrix (or ``(I - K diag(dP_a/dH))^-1 K`` where the asperity pressure
  deforms the surfaces noticeably). Assembly is ``O(n^2)`` and the LU solve ``O(n^3)``,
  a few ms at n = 512; every residual uses the FFT deflection. ``H`` for given ``P, H0`` is
  found by fixed-point iteration on ``P_a(H)`` (Newton if that is slow).
- Damping: a Newton step may change ``P`` by at most 0.5 at a node and lower ``H`` by at most
  half its value (plus one ``sigma`` for rough surfaces, whose mean planes may pass).
- Start: Hertz pressure and the central film of Pan & Hamrock (1989); on failure from the
  nested start, a second attempt from the Hertz start.

Typically 5-8 Newton steps on each grid; 0.05-0.3 s per solve at n = 512 on one core, over
``W = 5e-5 .. 1e-3`` (p_H up to 2.9 GPa), ``U = 5e-12 .. 2e-9``, ``G = 5660`` and
``sigma/R = 1e-5 .. 5e-4``. Inside ``F_{5/2}`` and ``F_{3/2}`` are interpolated from a table
of ``ln F`` (step 0.005, relative error < 1e-5).

Verification (``tests/tribology/test_mixed_ehl.py``)
-------------------------------------------------------
Smooth surfaces with Barus viscosity and an incompressible lubricant reproduce the central
film of Moes' formula (H. Moes, "Optimum similarity analysis with applications to
elastohydrodynamic lubrication", Wear 159 (1992) 57-66, in the form of Venner & Lubrecht
2000) within 7 % (2.5-6.5 % at n = 512 over M = 13-112, L = 12-32). With Roelands and
Dowson-Higginson, as used here, the minimum film is 1.0-1.17 times and the central film
1.09-1.26 times the Pan-Hamrock formulas (:func:`pan_hamrock_film`) for ``W = 1e-4 .. 5e-4``,
``U = 1e-11 .. 5.4e-10``; compressibility alone lowers the central film by 20-25 % at 2 GPa,
and the Pan-Hamrock fits carry their own scatter.

Comparison with the Masjedi-Khonsari regression
-----------------------------------------------
``physics.tribology.lubrication.asperity_load_ratio_pct`` (M-K 2012; their asperity model
brings in the hardness through ``V``) varies weakly with the operating point (``U^-0.088``);
this solver's share follows the film ratio ``lambda = h_min/sigma`` through ``F_{5/2}``. At
the thesis pitch point (w = 394 kN/m, R = 3.694 mm, u_e = 1.289 m/s, sigma = 0.5 um,
lambda = 2.1) it gives 0.0045 % of the load against 0.027 % from M-K (0.17 times); at
``lambda = 0.1 .. 0.9`` (W = 1e-4 .. 4.7e-4, U = 1e-11 .. 1e-10) 0.27-2.0 % against
0.02-0.06 % (9-35 times). The asperity share stays small at gear loads for any lambda:
with the constants above, ``K E* F_{5/2}(0)`` is about 17 MPa against p_H ~ 2 GPa, and the
lubricant held in the roughness valleys (``h_T >= sigma/sqrt(2 pi)``) keeps carrying the
load.

Units and scope
---------------
Inputs and outputs are SI. The solver is isothermal at ``temperature`` (default the
reference temperature ``t0`` of ``eta0``): a caller can pass the flash temperature, but no
energy equation is solved. Non-Newtonian (limiting shear) behaviour is not modelled; it does
not change the film much in rolling-dominated contacts. The asperity contacts are elastic
(Greenwood-Tripp): unlike the Masjedi-Khonsari regression, the hardness does not enter. The
Patir-Cheng flow factors are fitted for ``h/sigma > 0.5``; below that (and for ``h < 0``)
results depend on the extension stated in 1.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy import fft as sfft
from scipy import linalg, special

from physics.blas import one_blas_thread
from physics.tribology import lubrication

# --- Greenwood-Tripp roughness constants -------------------------------------------------------
# eta_s beta sigma (summit density x summit radius x RMS roughness): 0.03-0.05 for the wide
# range of engineering surfaces Greenwood & Williamson (1966) measured; Greenwood & Tripp (1970)
# and the mixed-EHL studies that use their model (e.g. Gelinck & Schipper 2000; Masjedi &
# Khonsari 2012) take values in this band. We use its middle.
ETA_BETA_SIGMA = 0.04
# sigma / beta (RMS roughness over summit radius): of order 1e-3 for ground and finished steel
# (Greenwood & Tripp 1970; the 1e-4 .. 1e-2 range of the mixed-EHL literature cited above).
SIGMA_OVER_BETA = 1.0e-3
# Prefactor of the Greenwood-Tripp pressure (see the module docstring for its derivation).
GT_PREFACTOR = 16.0 * math.sqrt(2.0) * math.pi / 15.0

# --- Patir & Cheng (1978), Table 1, isotropic roughness (gamma = 1) ---------------------------
PATIR_CHENG_C = 0.90
PATIR_CHENG_R = 0.56

# Numerical settings
DEFAULT_N = 512
_STEP_P_MAX = 0.5  # largest nodal change of P = p/p_H per Newton step
_H_DROP = 0.5  # H may fall by at most this fraction of its value per Newton step


# One BLAS thread inside the solver: its dense LU solves (n ~ 512) gain little from a second
# thread and lose up to tenfold when the cores are shared (measured on the 2-core target:
# 4 ms single-threaded, 20-90 ms with two OpenBLAS threads under load). Set to False to keep
# the process-wide BLAS threading.
LIMIT_BLAS_THREADS = True


@contextlib.contextmanager
def _single_blas_thread():
    """Run the block with one BLAS thread (threadpoolctl), if LIMIT_BLAS_THREADS."""
    if not LIMIT_BLAS_THREADS:
        yield
        return
    with one_blas_thread():
        yield


# ------------------------------------------------------------------------------------------------
# Roughness models
# ------------------------------------------------------------------------------------------------
def greenwood_tripp_integral(t: np.ndarray, order: float = 2.5) -> np.ndarray:
    """``F_n(t) = (2 pi)^(-1/2) int_t^inf (s - t)^n exp(-s^2/2) ds`` (Greenwood-Williamson).

    Closed form through the parabolic cylinder function (module docstring), vectorised. Values
    below ``t = -20`` are taken at -20 (a gap twenty RMS below the mean plane: never reached);
    above ``t = 37`` the integral underflows and is returned as 0.
    """
    t = np.asarray(t, dtype=float)
    tc = np.clip(t, -20.0, 37.0)
    d, _ = special.pbdv(-order - 1.0, tc)
    f = special.gamma(order + 1.0) / math.sqrt(2.0 * math.pi) * np.exp(-0.25 * tc * tc) * d
    return np.where(t > 37.0, 0.0, f)


def asperity_pressure(
    h: np.ndarray, sigma: float, e_prime: float,
    eta_beta_sigma: float = ETA_BETA_SIGMA, sigma_over_beta: float = SIGMA_OVER_BETA,
) -> np.ndarray:
    """Greenwood-Tripp asperity pressure [Pa] at nominal gap ``h`` [m] (module docstring, 4).

    ``e_prime`` is Hamrock's reduced modulus; the Greenwood-Tripp modulus is ``E* = E'/2``.
    """
    k = GT_PREFACTOR * eta_beta_sigma**2 * math.sqrt(sigma_over_beta)
    return k * 0.5 * e_prime * greenwood_tripp_integral(np.asarray(h, dtype=float) / sigma)


def pressure_flow_factor(h_over_sigma: np.ndarray) -> np.ndarray:
    """Patir-Cheng pressure flow factor ``1 - 0.90 exp(-0.56 h/sigma)`` for gamma = 1 (1978)."""
    hs = np.maximum(np.asarray(h_over_sigma, dtype=float), 0.0)
    return 1.0 - PATIR_CHENG_C * np.exp(-PATIR_CHENG_R * hs)


def average_gap(h: np.ndarray, sigma: float) -> np.ndarray:
    """Expected local gap ``h_T = h Phi(h/sigma) + sigma phi(h/sigma)`` of Gaussian roughness."""
    h = np.asarray(h, dtype=float)
    t = h / sigma
    return h * special.ndtr(t) + sigma * np.exp(-0.5 * t * t) / math.sqrt(2.0 * math.pi)


# ------------------------------------------------------------------------------------------------
# Reference formulas for smooth surfaces (used for the initial guess and in the tests)
# ------------------------------------------------------------------------------------------------
def pan_hamrock_film(W: float, U: float, G: float) -> tuple[float, float]:
    """Pan & Hamrock (1989) smooth line-contact films ``(h_min/R, h_c/R)``.

    ``H_min = 1.714 W^-0.128 U^0.694 G^0.568``, ``H_c = 2.922 W^-0.166 U^0.692 G^0.470`` with
    ``W = w/(E'R)``, ``U = eta0 u_e/(E'R)``, ``G = alpha E'`` (P. Pan, B.J. Hamrock, "Simple
    formulas for performance parameters used in elastohydrodynamically lubricated line
    contacts", ASME J. Tribol. 111 (1989) 246-251; also Hamrock, Schmid & Jacobson,
    *Fundamentals of Machine Elements*). Fitted to isothermal Newtonian solutions with Roelands
    viscosity and Dowson-Higginson density.
    """
    h_min = 1.714 * W**-0.128 * U**0.694 * G**0.568
    h_c = 2.922 * W**-0.166 * U**0.692 * G**0.470
    return h_min, h_c


# ------------------------------------------------------------------------------------------------
# Elastic deflection operator
# ------------------------------------------------------------------------------------------------
@lru_cache(maxsize=8)
def _elastic_operator(n: int, dx: float) -> tuple[np.ndarray, int, np.ndarray]:
    """Deflection coefficients ``D_i = sum_j k[|i-j|] P_j`` for ``-(1/pi) int P ln|X-X'| dX'``.

    Returns the FFT of the zero-padded kernel, its FFT length, and the dense Toeplitz matrix
    (for the Newton Jacobian). Cell ``j`` carries a constant pressure on ``[X_j - dx/2, X_j +
    dx/2]``; ``int ln|t| dt = t ln|t| - t``.
    """
    m = np.arange(n, dtype=float)

    def prim(t: np.ndarray) -> np.ndarray:
        return t * np.log(np.abs(t)) - t

    k = -(prim((m + 0.5) * dx) - prim((m - 0.5) * dx)) / math.pi
    full = np.concatenate([k[:0:-1], k])  # offsets -(n-1) .. n-1
    nfft = sfft.next_fast_len(3 * n - 2, real=True)
    kf = sfft.rfft(full, nfft)
    dense = linalg.toeplitz(k)
    kf.setflags(write=False)
    dense.setflags(write=False)
    return kf, nfft, dense


def _deflection(p: np.ndarray, kf: np.ndarray, nfft: int) -> np.ndarray:
    """FFT convolution of the nodal pressure with the kernel (linear, zero-padded)."""
    n = p.size
    return sfft.irfft(sfft.rfft(p, nfft) * kf, nfft)[n - 1: 2 * n - 1]


# ------------------------------------------------------------------------------------------------
# Results
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class EHLSolution:
    """Solution of :func:`solve_line_contact` (SI units).

    ``x`` [m] grid (``x = 0`` at the Hertz centre, entrainment towards +x); ``p_h`` fluid and
    ``p_a`` asperity pressure [Pa]; ``h`` nominal film (mean-plane separation) [m]; ``h_min``
    its minimum and ``h_central`` its value at ``x = 0`` [m]; ``asperity_load_share`` the
    fraction of ``w`` carried by ``p_a`` (0-1); ``load_error`` the relative mismatch of
    ``int (p_h + p_a) dx`` and ``w``; ``converged`` whether Newton's method met its tolerance
    (with the active set settled); ``iterations`` the Newton steps on the finest grid;
    ``residual`` the largest discrete Reynolds residual on the pressurised nodes over the
    largest Couette flux ``rho h_T``; ``hertz_half_width`` ``b`` [m], ``hertz_pressure`` ``p_H``
    [Pa], ``sigma`` the composite roughness [m]; ``dimensionless`` the groups ``W, U, G,
    sigma_bar``, Moes' ``M, L``, ``lambda_bar`` and ``H0``. Arrays are read-only.
    """

    x: np.ndarray
    p_h: np.ndarray
    p_a: np.ndarray
    h: np.ndarray
    h_min: float
    h_central: float
    asperity_load_share: float
    converged: bool
    iterations: int
    residual: float
    load_error: float
    hertz_half_width: float
    hertz_pressure: float
    sigma: float
    dimensionless: dict = field(default_factory=dict, repr=False)

    @property
    def film_ratio_min(self) -> float:
        """``lambda = h_min / sigma`` (inf for smooth surfaces)."""
        return self.h_min / self.sigma if self.sigma > 0 else math.inf

    @property
    def film_ratio_central(self) -> float:
        """``h_central / sigma`` (inf for smooth surfaces)."""
        return self.h_central / self.sigma if self.sigma > 0 else math.inf


# ------------------------------------------------------------------------------------------------
# Input validation
# ------------------------------------------------------------------------------------------------
def _check(name: str, value: float, lo: float, hi: float, hint: str, lo_open: bool = True) -> float:
    ok = isinstance(value, int | float | np.floating | np.integer) and not isinstance(value, bool)
    v = float(value) if ok else math.nan
    inside = (lo < v if lo_open else lo <= v) and v < hi
    if not (ok and math.isfinite(v) and inside):
        bracket = "(" if lo_open else "["
        raise ValueError(
            f"{name} = {value!r} must be a finite number in {bracket}{lo:g}, {hi:g}); {hint}"
        )
    return v


# ------------------------------------------------------------------------------------------------
# Dimensionless Newton solver
# ------------------------------------------------------------------------------------------------
@dataclass
class _Problem:
    x: np.ndarray
    dx: float
    lam: float  # lambda_bar
    p_hertz: float
    temperature: float
    eta0: float
    alpha: float
    beta0: float
    t0: float
    rho0: float
    s: float  # sigma in film units (sigma R / b^2); 0 for smooth surfaces
    flow_factors: bool
    asp_coef: float  # K E* / p_H (0 without asperity contact)
    second_order: bool = True


def _rheology(pb: _Problem, P: np.ndarray) -> tuple[np.ndarray, ...]:
    """rho/rho0, d(rho/rho0)/dP, eta/eta0 and d ln(eta)/dP from physics.lubrication."""
    dP = 1e-6
    p = pb.p_hertz * P
    dp = pb.p_hertz * dP
    T = pb.temperature
    eta = lubrication.viscosity(p, T, pb.eta0, pb.alpha, pb.beta0, pb.t0)
    eta_d = lubrication.viscosity(p + dp, T, pb.eta0, pb.alpha, pb.beta0, pb.t0)
    rho = lubrication.density(p, T, pb.rho0, pb.t0)
    rho_d = lubrication.density(p + dp, T, pb.rho0, pb.t0)
    return (rho / pb.rho0, (rho_d - rho) / (pb.rho0 * dP), eta / pb.eta0,
            (np.log(eta_d) - np.log(eta)) / dP)


_GT_T = np.linspace(-20.0, 37.0, 11401)  # table step 0.005


@lru_cache(maxsize=4)
def _gt_log_table(order: float) -> np.ndarray:
    """ln F_order on ``_GT_T`` (closed form), for fast interpolation inside the solver."""
    with np.errstate(divide="ignore"):
        table = np.log(greenwood_tripp_integral(_GT_T, order))
    table = np.maximum(table, -745.0)  # exp(-745) underflows to 0
    table.setflags(write=False)
    return table


def _gt_fast(t: np.ndarray, order: float) -> np.ndarray:
    """F_order(t) by linear interpolation of ln F (relative error below 1e-5)."""
    return np.exp(np.interp(t, _GT_T, _gt_log_table(order)))


def _asperity(pb: _Problem, H: np.ndarray, slope: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Dimensionless asperity pressure P_a(H) and (if ``slope``) dP_a/dH."""
    if pb.asp_coef == 0.0:
        z = np.zeros_like(H)
        return z, z
    t = H / pb.s
    pa = pb.asp_coef * _gt_fast(t, 2.5)
    dpa = -2.5 * pb.asp_coef * _gt_fast(t, 1.5) / pb.s if slope else None
    return pa, dpa


def _film(pb: _Problem, P: np.ndarray, H0: float, pa: np.ndarray,
          op: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Film H with the deflection of P + P_a(H), P_a and dP_a/dH.

    ``H = H0 + X^2/2 + K (P + P_a(H))`` is solved for H by fixed-point iteration (a contraction
    while the asperity pressure is a small part of the load), switching to Newton's method on
    it (dense, ``I - K diag(dP_a/dH)``) if the fixed point is slow.
    """
    kf, nfft, K = op
    base = H0 + 0.5 * pb.x**2
    H = base + _deflection(P + pa, kf, nfft)
    if pb.asp_coef == 0.0:
        return H, pa, np.zeros_like(P)
    tol = 1e-13 * max(1.0, float(np.max(np.abs(H))))
    for _ in range(12):
        pa, _ = _asperity(pb, H, slope=False)
        H_new = base + _deflection(P + pa, kf, nfft)
        change = float(np.max(np.abs(H_new - H)))
        H = H_new
        if change < tol:
            break
    else:
        for _ in range(30):
            pa, dpa = _asperity(pb, H)
            g = H - base - _deflection(P + pa, kf, nfft)
            H = H - np.linalg.solve(np.eye(H.size) - K * dpa[None, :], g)
            if float(np.max(np.abs(g))) < tol:
                break
    pa, dpa = _asperity(pb, H)
    return H, pa, dpa


def _coefficients(pb: _Problem, P: np.ndarray, H: np.ndarray) -> tuple[np.ndarray, ...]:
    """eps, d eps/dP, d eps/dH, f = rho H_T, df/dP, df/dH at the nodes."""
    rho, drho, eta, dlneta = _rheology(pb, P)
    Hp = np.maximum(H, 0.0)
    if pb.s > 0.0 and pb.flow_factors:
        t = H / pb.s
        ex = PATIR_CHENG_C * np.exp(-PATIR_CHENG_R * np.maximum(t, 0.0))
        phi = 1.0 - ex
        dphi = np.where(t > 0.0, PATIR_CHENG_R * ex / pb.s, 0.0)
        g = phi * Hp**3
        dg = dphi * Hp**3 + 3.0 * phi * Hp**2
        cdf = special.ndtr(t)
        HT = H * cdf + pb.s * np.exp(-0.5 * t * t) / math.sqrt(2.0 * math.pi)
        dHT = cdf
    else:
        g = Hp**3
        dg = 3.0 * Hp**2
        HT = H
        dHT = np.ones_like(H)
    eps = rho * g / (eta * pb.lam)
    deps_p = eps * (drho / rho - dlneta)
    deps_h = rho * dg / (eta * pb.lam)
    f = rho * HT
    return eps, deps_p, deps_h, f, drho * HT, rho * dHT


def _couette_weights(n: int, second_order: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Weights c0, c1, c2 of q_{i+1/2} - q_{i-1/2} = c0 f_i + c1 f_{i-1} + c2 f_{i-2}."""
    c0, c1, c2 = np.ones(n), -np.ones(n), np.zeros(n)
    if second_order:
        c0[2:], c1[2:], c2[2:] = 1.5, -2.0, 0.5
        c0[1], c1[1] = 1.5, -1.5
    return c0, c1, c2


def _residual(pb: _Problem, P, H, coeffs, cw) -> np.ndarray:
    """Discrete Reynolds residual R_i at every node (zero at the two boundary nodes)."""
    eps, _, _, f, _, _ = coeffs
    c0, c1, c2 = cw
    a = np.diff(P) / pb.dx
    e = 0.5 * (eps[:-1] + eps[1:])
    Q = e * a
    R = np.zeros_like(P)
    i = np.arange(1, P.size - 1)
    couette = c0[i] * f[i] + c1[i] * f[i - 1] + c2[i] * f[np.maximum(i - 2, 0)]
    R[i] = Q[i] - Q[i - 1] - couette
    return R


def _newton(pb: _Problem, P: np.ndarray, H0: float, *, tol: float, max_iter: int,
            verbose: bool = False) -> dict:
    n = P.size
    op = _elastic_operator(n, pb.dx)
    kf, nfft, K = op
    kpad = np.zeros((n + 3, n + 1))  # rows: dH_k/d(P_j, H0), shifted by 2, zero outside
    kpad[2:-1, :n] = K
    kpad[2:-1, n] = 1.0
    kscale = float(np.max(np.sum(np.abs(K), axis=1)))
    cw = _couette_weights(n, pb.second_order)
    c0, c1, c2 = cw
    cscale = 1e-6  # min(P, -c R): c -> 0 makes a node cavitated iff P = 0 and R <= 0
    pa = np.zeros(n)
    interior = np.arange(1, n - 1)
    converged = False
    last_active = None
    it = 0
    step_norm = math.inf
    for it in range(1, max_iter + 1):
        H, pa, dpa = _film(pb, P, H0, pa, op)
        coeffs = _coefficients(pb, P, H)
        eps, deps_p, deps_h, _, df_p, df_h = coeffs
        R = _residual(pb, P, H, coeffs, cw)
        active = P[interior] <= -cscale * R[interior]
        load = pb.dx * np.sum(P + pa) - 0.5 * math.pi

        # --- Jacobian of R (rows: all nodes, columns: all nodes), explicit part in P
        a = np.diff(P) / pb.dx
        e = 0.5 * (eps[:-1] + eps[1:])
        i = interior
        ap, am = a[i], a[i - 1]  # a_{i+1/2}, a_{i-1/2}
        ep, em = e[i], e[i - 1]
        m = n - 2
        J = np.zeros((m + 1, m + 1))
        # banded explicit (pressure) derivatives
        d_up = ep / pb.dx + 0.5 * deps_p[i + 1] * ap
        d_mid = -(ep + em) / pb.dx + 0.5 * deps_p[i] * (ap - am) - c0[i] * df_p[i]
        d_lo = em / pb.dx - 0.5 * deps_p[i - 1] * am - c1[i] * df_p[i - 1]
        d_lo2 = -c2[i] * df_p[np.maximum(i - 2, 0)]
        # film (H) derivatives, chained through dH/dP = K (+ dH/dH0 = 1)
        jh_up = 0.5 * deps_h[i + 1] * ap
        jh_mid = 0.5 * deps_h[i] * (ap - am) - c0[i] * df_h[i]
        jh_lo = -0.5 * deps_h[i - 1] * am - c1[i] * df_h[i - 1]
        jh_lo2 = -c2[i] * df_h[np.maximum(i - 2, 0)]
        # dH/d(P, H0): K and 1, or, where the asperity pressure deforms the surfaces
        # noticeably, (I - K diag(dP_a/dH))^-1 [K, 1]
        if np.max(np.abs(dpa)) * kscale > 0.05:
            sens = kpad.copy()
            sens[2:-1] = np.linalg.solve(np.eye(n) - K * dpa[None, :], kpad[2:-1])
        else:
            sens = kpad
        M = (jh_up[:, None] * sens[i + 3] + jh_mid[:, None] * sens[i + 2]
             + jh_lo[:, None] * sens[i + 1] + jh_lo2[:, None] * sens[i])
        JR = M[:, 1:n - 1]
        r = np.arange(m)
        JR[r, r] += d_mid
        JR[r[:-1], r[:-1] + 1] += d_up[:-1]
        JR[r[1:], r[1:] - 1] += d_lo[1:]
        JR[r[2:], r[2:] - 2] += d_lo2[2:]
        J[:m, :m] = JR
        J[:m, m] = M[:, n]
        rhs = np.empty(m + 1)
        rhs[:m] = R[i]
        # complementarity: active nodes take the equation P_i = 0
        if np.any(active):
            ia = np.nonzero(active)[0]
            J[ia, :] = 0.0
            J[ia, ia] = 1.0
            rhs[ia] = P[i][active]
        # load balance row
        dload = pb.dx * (dpa @ sens[2:-1])
        J[m, :m] = pb.dx + dload[1:n - 1]
        J[m, m] = dload[n]
        rhs[m] = load
        try:
            delta = np.linalg.solve(J, -rhs)
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(delta)):
            break
        dP = np.zeros(n)
        dP[1:-1] = delta[:m]
        dH0 = delta[m]
        # damping: bounded pressure change; H may not fall by more than _H_DROP per step
        omega = min(1.0, _STEP_P_MAX / max(np.max(np.abs(dP)), 1e-300))
        dH = dH0 + _deflection(dP, kf, nfft)
        # allowed fall of H per step: half its value; rough surfaces may also pass below the
        # mean plane (h < 0, asperities flattened), by at most one sigma per step
        allowed = _H_DROP * np.maximum(H, 0.0) + pb.s
        falling = (dH < 0) & (allowed > 0)
        if np.any(falling):
            omega = min(omega, float(np.min(allowed[falling] / -dH[falling])))
        P = np.maximum(P + omega * dP, 0.0)
        H0 = H0 + omega * dH0
        step_norm = max(np.max(np.abs(omega * dP)), abs(omega * dH0) / max(abs(H0), 1e-12))
        if verbose:
            print(f"it {it:3d} |R|={np.max(np.abs(rhs[:m])):.3e} load={load:+.3e} "
                  f"omega={omega:.3f} step={step_norm:.3e} H0={H0:.5f} nact={active.sum()}")
        same_set = last_active is not None and np.array_equal(active, last_active)
        last_active = active
        if omega == 1.0 and step_norm < tol and same_set:
            converged = True
            break
    if last_active is not None:  # nodes held at P = 0 by the complementarity condition
        P[1:-1][last_active] = 0.0
    H, pa, _ = _film(pb, P, H0, pa, op)
    coeffs = _coefficients(pb, P, H)
    R = _residual(pb, P, H, coeffs, cw)
    fluid = P[1:-1] > 0
    scale = max(np.max(np.abs(coeffs[3])), 1e-300)
    res = float(np.max(np.abs(R[1:-1][fluid])) / scale) if np.any(fluid) else 0.0
    return {"P": P, "H0": H0, "H": H, "Pa": pa, "converged": converged, "iterations": it,
            "residual": res, "step": step_norm}


# ------------------------------------------------------------------------------------------------
# Public solver
# ------------------------------------------------------------------------------------------------
def solve_line_contact(
    w: float, R: float, u_e: float, e_prime: float, eta0: float, alpha: float, beta0: float,
    rho0: float, t0: float, sigma: float, *, temperature: float | None = None,
    n: int = DEFAULT_N, x_in: float = -4.5, x_out: float = 1.5, flow_factors: bool = True,
    asperity: bool = True, eta_beta_sigma: float = ETA_BETA_SIGMA,
    sigma_over_beta: float = SIGMA_OVER_BETA, tol: float = 1e-9, max_iter: int = 100,
    verbose: bool = False,
) -> EHLSolution:
    """Solve the isothermal (mixed-)EHL line contact; all inputs SI (module docstring).

    w: load per unit face width [N/m]; R: reduced radius of curvature [m]; u_e: entraining
    velocity (u1 + u2)/2 [m/s]; e_prime: Hamrock's reduced modulus E' = 2 E* [Pa]; eta0 [Pa s],
    alpha [1/Pa], beta0 [1/K], rho0 [kg/m^3]: lubricant at the reference temperature t0 [K];
    sigma: composite RMS roughness [m] (0: smooth surfaces, which switches the flow factors and
    the asperity contact off). ``temperature`` [K] is the (isothermal) film temperature, ``t0``
    if None. ``flow_factors`` / ``asperity`` switch the Patir-Cheng factors and the
    Greenwood-Tripp contact on and off independently. ``n`` grid nodes on ``[x_in, x_out]``
    (in Hertz half-widths).
    """
    w = _check("w", w, 0.0, 1e9, "give the load per unit face width in N/m")
    R = _check("R", R, 0.0, 10.0, "give the reduced radius of curvature in m")
    u_e = _check("u_e", u_e, 0.0, 1e3, "give the entraining velocity (u1+u2)/2 in m/s, > 0")
    e_prime = _check("e_prime", e_prime, 1e6, 1e13,
                     "give Hamrock's reduced modulus E' = 2 E* in Pa, e.g. 2.264e11 for steel")
    eta0 = _check("eta0", eta0, 0.0, 1e3, "give the dynamic viscosity at t0 in Pa s")
    alpha = _check("alpha", alpha, 0.0, 1e-6, "give the pressure-viscosity coefficient in 1/Pa")
    beta0 = _check("beta0", beta0, 0.0, 1.0, "give the viscosity-temperature coefficient in 1/K",
                   lo_open=False)
    rho0 = _check("rho0", rho0, 0.0, 1e5, "give the density at t0 in kg/m^3")
    t0 = _check("t0", t0, 138.0, 1000.0, "give the reference temperature in K (above 138 K)")
    sigma = _check("sigma", sigma, 0.0, 1e-3, "give the composite RMS roughness in m (0: smooth)",
                   lo_open=False)
    temp = t0 if temperature is None else _check(
        "temperature", temperature, 138.0, 1000.0, "give the film temperature in K")
    if not isinstance(n, int | np.integer) or isinstance(n, bool) or not 64 <= n <= 8192:
        raise ValueError(f"n = {n!r} must be a whole number of grid nodes in [64, 8192]; "
                         "512 resolves the film to about 1 % at gear loads")
    x_in = _check("x_in", x_in, -100.0, -1.0, "the inlet must lie upstream of the Hertz zone "
                  "(X = x/b < -1); -4.5 is usual")
    x_out = _check("x_out", x_out, 1.0, 100.0, "the outlet must lie downstream of the Hertz "
                   "zone (X > 1); 1.5 is usual")
    for name, v in (("eta_beta_sigma", eta_beta_sigma), ("sigma_over_beta", sigma_over_beta)):
        _check(name, v, 0.0, 1.0, "Greenwood-Tripp roughness constant, see the module constants")
    _check("tol", tol, 0.0, 1e-3, "Newton step tolerance on P = p/p_H, e.g. 1e-9")
    if not isinstance(max_iter, int) or isinstance(max_iter, bool) or max_iter < 1:
        raise ValueError(f"max_iter = {max_iter!r} must be a whole number >= 1 (Newton steps)")
    if w / (e_prime * R) > 0.05:
        raise ValueError(f"w/(E'R) = {w / (e_prime * R):.3g} > 0.05: the contact is not "
                         "slender (b ~ R); check that w is per unit width and R in metres")

    b = math.sqrt(8.0 * w * R / (math.pi * e_prime))
    p_hertz = 2.0 * w / (math.pi * b)
    W = w / (e_prime * R)
    U = eta0 * u_e / (e_prime * R)
    G = alpha * e_prime
    film_scale = b * b / R  # h = H * film_scale
    rough = sigma > 0.0
    pb = _Problem(
        x=np.linspace(x_in, x_out, int(n)), dx=(x_out - x_in) / (int(n) - 1),
        lam=12.0 * eta0 * u_e * R * R / (b**3 * p_hertz), p_hertz=p_hertz, temperature=temp,
        eta0=eta0, alpha=alpha, beta0=beta0, t0=t0, rho0=rho0,
        s=sigma / film_scale if rough else 0.0, flow_factors=bool(flow_factors) and rough,
        asp_coef=(GT_PREFACTOR * eta_beta_sigma**2 * math.sqrt(sigma_over_beta) * 0.5 * e_prime
                  / p_hertz) if (rough and asperity) else 0.0,
    )
    with _single_blas_thread():
        out = _solve_dimensionless(pb, W, U, G, tol=tol, max_iter=max_iter, verbose=verbose)
    return _to_solution(out, pb, b, p_hertz, R, sigma, W, U, G)


def _initial_guess(pb: _Problem, W: float, U: float, G: float) -> tuple[np.ndarray, float]:
    """Hertz pressure and the H0 that puts the Pan-Hamrock central film at X = 0."""
    x = pb.x
    P = np.sqrt(np.maximum(1.0 - x * x, 0.0))
    P[0] = P[-1] = 0.0
    kf, nfft, _ = _elastic_operator(x.size, pb.dx)
    d = _deflection(P, kf, nfft) + 0.5 * x**2
    _, hc = pan_hamrock_film(W, U, G)
    Hc = hc * math.pi / (8.0 * W)  # h/R -> H = h R / b^2, (R/b)^2 = pi / (8 W)
    Hc = max(Hc, 0.5 * pb.s)  # rough surfaces: a nominal gap of at least sigma/2 to start
    return P, Hc - float(np.interp(0.0, x, d))


_COARSEST = 160  # nested iteration stops refining below this many nodes


def _solve_dimensionless(pb: _Problem, W: float, U: float, G: float, *, tol: float,
                         max_iter: int, verbose: bool = False,
                         start: tuple[np.ndarray, np.ndarray, float] | None = None) -> dict:
    """Newton solve, started from ``start = (x, P, H0)`` or by nested iteration.

    Nested iteration: the problem is first solved on a grid of about half the nodes (down to
    ~``_COARSEST``), whose pressure, interpolated, starts the fine grid. The cavitation
    boundary then needs to move only a node or two on each grid (the active-set update
    moves it one node per Newton step).
    """
    n = pb.x.size
    if start is None and n >= 2 * _COARSEST:
        nc = (n + 1) // 2
        x_c = np.linspace(pb.x[0], pb.x[-1], nc)
        pbc = dataclasses.replace(pb, x=x_c, dx=float(x_c[1] - x_c[0]))
        coarse = _solve_dimensionless(pbc, W, U, G, tol=max(tol, 1e-7), max_iter=min(max_iter, 60),
                                      verbose=verbose)
        if coarse["converged"]:
            start = (x_c, coarse["P"], coarse["H0"])
    if start is None:
        P, H0 = _initial_guess(pb, W, U, G)
    else:
        P = np.interp(pb.x, start[0], start[1])
        P[0] = P[-1] = 0.0
        H0 = float(start[2])
    if verbose:
        print(f"-- n = {n}")
    out = _newton(pb, P, H0, tol=tol, max_iter=max_iter, verbose=verbose)
    if not out["converged"] and start is not None:  # fall back on the Hertz start
        P, H0 = _initial_guess(pb, W, U, G)
        retry = _newton(pb, P, H0, tol=tol, max_iter=max_iter, verbose=verbose)
        if retry["converged"]:
            retry["iterations"] += out["iterations"]
            out = retry
    return out


def _to_solution(out: dict, pb: _Problem, b: float, p_hertz: float, R: float, sigma: float,
                 W: float, U: float, G: float) -> EHLSolution:
    x = pb.x
    film_scale = b * b / R
    P, Pa, H = out["P"], out["Pa"], out["H"]
    load_h = pb.dx * float(np.sum(P))
    load_a = pb.dx * float(np.sum(Pa))
    total = load_h + load_a
    arrays = {"x": x * b, "p_h": P * p_hertz, "p_a": Pa * p_hertz, "h": H * film_scale}
    for v in arrays.values():
        v.setflags(write=False)
    return EHLSolution(
        **arrays,
        h_min=float(np.min(H)) * film_scale,
        h_central=float(np.interp(0.0, x, H)) * film_scale,
        asperity_load_share=load_a / total if total > 0 else math.nan,
        converged=bool(out["converged"]), iterations=int(out["iterations"]),
        residual=float(out["residual"]), load_error=total / (0.5 * math.pi) - 1.0,
        hertz_half_width=b, hertz_pressure=p_hertz, sigma=sigma,
        dimensionless={"W": W, "U": U, "G": G, "sigma_bar": sigma / R, "H0": float(out["H0"]),
                       "lambda_bar": pb.lam, "M": W * (2 * U) ** -0.5, "L": G * (2 * U) ** 0.25},
    )


def log_gt_integral(t: np.ndarray, order: float = 2.5) -> np.ndarray:
    """``ln F_order(t)`` of the Greenwood-Tripp integral (:func:`greenwood_tripp_integral`) by
    interpolation of its closed-form table on ``t`` in [-20, 37] (step 0.005; relative error of
    ``F`` below 1e-5); ``t`` outside is held at the ends (``ln F = -745`` at the top, where
    ``F`` underflows)."""
    return np.interp(np.asarray(t, dtype=float), _GT_T, _gt_log_table(order))
