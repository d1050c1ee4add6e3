"""Precomputed mixed-EHL film and asperity load share for the wear model (thesis 2.4).

The wear loop needs the contact state at every grid point of the path of contact (401 by
default) at every profile update; one solve of the numerical line-contact problem
(:func:`physics.tribology.mixed_ehl.solve_line_contact`) takes about 0.1 s. The solver's results
are therefore computed once on a grid of the dimensionless groups, shipped with the package as
``mixed_ehl_table.npz`` beside this module, and interpolated (:class:`MixedEHLTable`, over the
load, speed, roughness, material and viscosity axes, for the share and the film fields).

Axes
----
Hamrock's groups as in :mod:`physics.tribology.lubrication`: ``W = w/(E'R)``, ``U = eta0
u_e/(E'R)``, ``sigma_bar = sigma/R``, ``G = alpha E'``; and ``eta0`` [Pa s] itself. The
isothermal Roelands law is not a function of ``G`` alone: at fixed ``G`` its pressure index
``Z = alpha p0 / ln(eta0/eta_inf)`` and the multiplier ``ln(eta0/eta_inf)`` depend on
``eta0`` (Hamrock, *Fundamentals of Fluid Film Lubrication*, 1994, eq. 4.9). Measured at the
thesis pitch point, the share changes by 8 % and the film by 1.2 % between eta0 = 0.35 and
0.08 Pa s at the same ``W, U, G, sigma_bar``: a weak dependence, resolved by three nodes.

The table does not depend on ``t0``, ``beta0`` or ``rho0``: the solver runs at the inlet
(bulk) temperature ``t0``, where the Roelands temperature factor is 1 and the Dowson-Higginson
density enters only as ``rho/rho0`` (tested). It is built for one reduced modulus, that of the
default steel (:class:`physics.params.Material`): ``E'`` sets the absolute pressure ``p_H =
E' sqrt(W / 2 pi)`` at which the viscosity and density are evaluated. A material whose ``E'``
differs by more than :data:`E_PRIME_TOLERANCE` is refused.

Fields at each node: the asperity load share (0-1), the film ratios ``h_min/sigma`` and
``h_c/sigma`` (nominal film: the separation of the mean planes), and the pressure peak
``max(p_h + p_a) / p_H``, with the solver's convergence flag.

Interpolation
-------------
Multilinear in the logarithms of the five axes (:class:`scipy.interpolate.
RegularGridInterpolator`), of four smooth fields: ``ln(h_min/sigma)`` and ``ln(h_c/sigma)``
(nearly linear in the log axes, the film being close to a power law of the groups; through a
softplus of width :data:`SOFT_WIDTH` that equals the ratio above 0.3 and stays positive
where the nominal film is not), ``ln r`` with ``share = r F_{5/2}(lambda_m)``, and
``ln(peak)``. ``F_{5/2}`` is Greenwood & Tripp's integral and ``lambda_m = (h_min + h_c) /
(2 sigma)``: it carries the orders of magnitude by which the share falls between nodes, so
that ``r`` varies slowly (with ``h_min`` alone, or ``h_c`` alone
the interpolation error of the share is twice as large: the asperity load comes from both the
Hertz plateau and the outlet constriction). Where ``lambda_m`` exceeds :data:`LAMBDA_R_MAX`
the share is below 1e-30 and ``r`` is held at its value on the thinner side of the U axis.
The grid reproduces its nodes exactly; between nodes the error against direct solves is
stated in ``tests/tribology/test_asperity_table.py``.

Outside the grid
----------------
- ``W`` (the load) is clipped to the grid: a pair carrying less than ``W = 3e-5`` (6 % of
  the baseline pitch-point load) is evaluated at 3e-5, one above ``W = 2e-3`` (a Hertz
  pressure of 4 GPa on steel, far beyond the 2.4 GPa static capacity of
  :mod:`physics.scope`) at 2e-3. Light pairs occur where a worn flank takes its pair out of
  contact; their wear is negligible either way.
- ``U``, ``sigma_bar``, ``G`` and ``eta0`` are fixed by the operating point, the lubricant and
  the flank geometry; a value outside the grid raises ``ValueError`` naming the group, its
  value, the grid range and the fix (``tribology.asperity_model=regression``, or a wider table
  built with this module). :func:`check_scenario` runs that check before a wear run starts.
- A point in a grid cell with a corner where the solver did not converge is refused the same
  way. Those nodes (69 of 9828 in the shipped table) lie where the film ratio is near zero
  (below 0.12: the roughest surfaces at the lowest speeds): the boundary-lubrication limit,
  where the Patir-Cheng flow factors (fitted for ``h/sigma > 0.5``) no longer describe the
  flow.

Build and check
---------------
``python -m physics.tribology.asperity_table`` rebuilds the shipped file (9828 solves; 21 min
with ``--workers 2`` on two shared cores); ``--check N`` re-solves N random nodes and compares
them with the shipped file. The solver runs with its default grid (``n = 512``) and up to 300
Newton steps (:data:`SOLVER`; converged nodes take 5-10, the thin-film corners up to ~150).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed
from scipy.interpolate import RegularGridInterpolator

from physics.params import Material, OutOfScope, Scenario
from physics.tribology import mixed_ehl

#: the shipped table (package data of physics.tribology)
TABLE_FILE = Path(__file__).with_name("mixed_ehl_table.npz")

AXES = ("W", "U", "sigma_bar", "G", "eta0")

#: the grid of the shipped table: log-spaced, covering the thesis's studies (2.7.2-2.7.6, the
#: Table 11 cases, dynamic loads) with margin. On the thesis pair (equivalent radii 1.23-3.85
#: mm along the path): W from 6 % of the baseline pitch-point load to a Hertz pressure of
#: 4 GPa; U from 19 to 14000 r/min with the thesis oil (eta0 0.35 Pa s), 84 to 63000 r/min
#: with the published VG 100 oils (0.078-0.08 Pa s), 7 to 5000 r/min at 1 Pa s; sigma_bar for
#: sigma 0.08-1.8 um; G for alpha 1.1e-8 to 3.5e-8 m^2/N on steel (mineral oils 2.0-3.5e-8:
#: Stachowiak & Batchelor, Engineering Tribology, 4th ed., Table 2.3; PAO 1.8e-8:
#: conf/physics/lubricant/pao.yaml); eta0 0.03-1 Pa s.
GRID: dict[str, tuple[float, ...]] = {
    "W": tuple(np.geomspace(3e-5, 2e-3, 7).tolist()),
    "U": tuple(np.geomspace(5e-12, 1e-8, 13).tolist()),
    "sigma_bar": tuple(np.geomspace(2e-5, 1.5e-3, 9).tolist()),
    "G": tuple(np.geomspace(2500.0, 8000.0, 4).tolist()),
    "eta0": tuple(np.geomspace(0.03, 1.0, 3).tolist()),
}

#: relative difference of E' from the table's above which a material is refused
E_PRIME_TOLERANCE = 0.02
#: film ratio above which the share (< 1e-30) no longer fixes r (module docstring)
LAMBDA_R_MAX = 12.0
#: width of the softplus that keeps the interpolated film ratio positive (module docstring)
SOFT_WIDTH = 0.05
#: the solver's settings for the table
SOLVER = {"n": mixed_ehl.DEFAULT_N, "max_iter": 300}

#: the inlet state at which nodes are solved: any (t0, beta0, rho0) gives the same table
#: (module docstring); these are the thesis baseline's, recorded in the file
_REF_T0, _REF_BETA0, _REF_RHO0 = 315.0, 0.03, 870.0
_R = 0.01  # m: any radius; the dimensionless problem depends on the groups only


def steel_e_prime() -> float:
    """Hamrock's reduced modulus ``E' = E/(1 - nu^2)`` of two default steel flanks [Pa]."""
    m = Material()
    return m.E / (1.0 - m.poisson**2)


@dataclass(frozen=True)
class EHLValues:
    """Interpolated solver results at each queried point (arrays of the broadcast shape)."""

    share: np.ndarray  # asperity load share, 0-1
    film_ratio_min: np.ndarray  # h_min / sigma
    film_ratio_central: np.ndarray  # h_c / sigma
    peak_ratio: np.ndarray  # max(p_h + p_a) / p_H


def _soft(lam: np.ndarray) -> np.ndarray:
    """Softplus ``c ln(1 + exp(lam/c))`` with ``c =`` :data:`SOFT_WIDTH`: equal to ``lam``
    (relative error < 1e-3) for film ratios above 0.3, positive below, so that its logarithm
    can be interpolated where the nominal film is negative."""
    lam = np.asarray(lam, dtype=float)
    return SOFT_WIDTH * np.logaddexp(0.0, lam / SOFT_WIDTH)


def _soft_inverse(y: np.ndarray) -> np.ndarray:
    """Inverse of :func:`_soft` (``y > 0``)."""
    y = np.asarray(y, dtype=float)
    return y + SOFT_WIDTH * np.log(-np.expm1(-y / SOFT_WIDTH))


def solve_node(W: float, U: float, sigma_bar: float, G: float, eta0: float,
               e_prime: float, n: int = SOLVER["n"], max_iter: int = SOLVER["max_iter"]
               ) -> tuple[float, float, float, float, bool]:
    """One node: (share, h_min/sigma, h_c/sigma, peak/p_H, converged) from the solver."""
    sol = mixed_ehl.solve_line_contact(
        W * e_prime * _R, _R, U * e_prime * _R / eta0, e_prime, eta0, G / e_prime, _REF_BETA0,
        _REF_RHO0, _REF_T0, sigma_bar * _R, n=n, max_iter=max_iter)
    peak = float(np.max(sol.p_h + sol.p_a)) / sol.hertz_pressure
    return (sol.asperity_load_share, sol.film_ratio_min, sol.film_ratio_central, peak,
            sol.converged)


def _row(args: tuple) -> list[tuple[float, float, float, float, bool]]:
    """The nodes along the U axis of one (W, sigma_bar, G, eta0): one task of the build."""
    W, U_grid, sigma_bar, G, eta0, e_prime = args
    return [solve_node(W, U, sigma_bar, G, eta0, e_prime) for U in U_grid]


def _run(tasks: list[tuple], workers: int, progress: bool) -> list:
    """The rows of ``tasks`` in order, in ``workers`` processes (joblib's loky backend keeps
    each worker's BLAS to its share of the cores)."""
    rows = []
    runs = Parallel(n_jobs=workers, return_as="generator")(delayed(_row)(t) for t in tasks)
    for i, r in enumerate(runs):
        rows.append(r)
        if progress and (i + 1) % 20 == 0:
            print(f"  {i + 1}/{len(tasks)} rows", file=sys.stderr, flush=True)
    return rows


def _axis(name: str, values: Sequence[float]) -> np.ndarray:
    g = np.asarray(values, dtype=float)
    if g.ndim != 1 or g.size < 2 or not np.all(np.isfinite(g)) or np.any(g <= 0) or np.any(
            np.diff(g) <= 0):
        raise ValueError(f"grid axis {name} = {values!r} must hold at least 2 positive, finite, "
                         "strictly increasing values")
    return g


class MixedEHLTable:
    """Interpolated solver results over ``(W, U, sigma_bar, G, eta0)`` (module docstring).

    ``grid`` maps each name of :data:`AXES` to its nodes; ``share``, ``film_ratio_min``,
    ``film_ratio_central``, ``peak_ratio`` and ``converged`` are arrays of the grid's shape.
    Call :meth:`__call__` with arrays (broadcast); a few thousand points take about a
    millisecond.
    """

    def __init__(self, grid: dict[str, Sequence[float]], share: np.ndarray,
                 film_ratio_min: np.ndarray, film_ratio_central: np.ndarray,
                 peak_ratio: np.ndarray, converged: np.ndarray, e_prime: float) -> None:
        self.grid = {a: _axis(a, grid[a]) for a in AXES}
        shape = tuple(g.size for g in self.grid.values())
        arrays = {"share": share, "film_ratio_min": film_ratio_min,
                  "film_ratio_central": film_ratio_central, "peak_ratio": peak_ratio}
        for name, v in arrays.items():
            v = np.asarray(v, dtype=float)
            if v.shape != shape or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be finite with the grid's shape {shape}")
            arrays[name] = v
        if np.any(arrays["share"] < 0) or np.any(arrays["share"] > 1):
            raise ValueError("share must hold fractions in [0, 1]")
        self.share = arrays["share"]
        self.film_ratio_min = arrays["film_ratio_min"]
        self.film_ratio_central = arrays["film_ratio_central"]
        self.peak_ratio = arrays["peak_ratio"]
        self.converged = np.asarray(converged, dtype=bool).reshape(shape)
        self.e_prime = float(e_prime)
        # a cell may be used only if the solver converged at all its corners
        ok = self.converged
        for k in range(ok.ndim):
            ok = np.minimum(np.take(ok, range(ok.shape[k] - 1), axis=k),
                            np.take(ok, range(1, ok.shape[k]), axis=k))
        self._cell_ok = ok
        self._lo = np.array([math.log(g[0]) for g in self.grid.values()])
        self._hi = np.array([math.log(g[-1]) for g in self.grid.values()])
        self._interp = RegularGridInterpolator(
            tuple(np.log(g) for g in self.grid.values()), self._fields(), method="linear",
            bounds_error=False, fill_value=None)

    def _fields(self) -> np.ndarray:
        lam_min, lam_c = self.film_ratio_min, self.film_ratio_central
        lam_mid = 0.5 * (lam_min + lam_c)
        log_r = (np.log(np.maximum(self.share, 1e-300))
                 - mixed_ehl.log_gt_integral(lam_mid, 2.5))
        # beyond LAMBDA_R_MAX hold r at its value on the thinner-film (lower U) side
        u_axis = AXES.index("U")
        log_r = np.moveaxis(log_r, u_axis, -1).copy()
        thick = np.moveaxis(lam_mid > LAMBDA_R_MAX, u_axis, -1)
        for j in range(1, log_r.shape[-1]):
            log_r[..., j] = np.where(thick[..., j], log_r[..., j - 1], log_r[..., j])
        log_r = np.moveaxis(log_r, -1, u_axis)
        return np.stack([np.log(_soft(lam_min)), np.log(_soft(lam_c)), log_r,
                         np.log(self.peak_ratio)], axis=-1)

    def check(self, **groups: np.ndarray) -> None:
        """Raise ``ValueError`` if any of ``U``, ``sigma_bar``, ``G``, ``eta0`` given lies
        outside the grid (``W`` is clipped, never refused)."""
        hints = {"U": "the operating speed and viscosity", "sigma_bar": "the roughness",
                 "G": "the pressure-viscosity coefficient", "eta0": "the viscosity"}
        for name, v in groups.items():
            if name == "W":
                continue
            g = self.grid[name]
            v = np.asarray(v, dtype=float)
            bad = (v < g[0] * (1 - 1e-9)) | (v > g[-1] * (1 + 1e-9)) | ~np.isfinite(v)
            if np.any(bad):
                x = v[bad].flat[0]
                raise OutOfScope(
                    f"mixed-EHL table: {name} = {x:.4g} lies outside the solver table's range "
                    f"[{g[0]:.4g}, {g[-1]:.4g}] (set by {hints[name]}); use "
                    "tribology.asperity_model=regression, or build a wider table with "
                    "python -m physics.tribology.asperity_table")

    def __call__(self, W, U, sigma_bar, G, eta0) -> EHLValues:
        """Interpolated values at the points (``W`` clipped to the grid; the other groups
        outside it raise ``ValueError``, see :meth:`check`)."""
        arrs = np.broadcast_arrays(*(np.asarray(a, dtype=float)
                                     for a in (W, U, sigma_bar, G, eta0)))
        if any(np.any(~(a > 0)) for a in arrs):
            raise ValueError("W, U, sigma_bar, G and eta0 must be positive and finite")
        self.check(**dict(zip(AXES[1:], arrs[1:], strict=True)))
        shape = arrs[0].shape
        pts = np.stack([np.log(a).ravel() for a in arrs], axis=-1)
        pts = np.clip(pts, self._lo, self._hi)  # W only: the others are inside (checked)
        if not self._cell_ok.all():
            cell = tuple(np.clip(np.searchsorted(np.log(g), pts[:, k], side="right") - 1, 0,
                                 g.size - 2) for k, g in enumerate(self.grid.values()))
            bad = ~self._cell_ok[cell]
            if np.any(bad):
                i = int(np.argmax(bad))
                where = ", ".join(f"{a} = {math.exp(pts[i, k]):.3g}"
                                  for k, a in enumerate(AXES))
                raise ValueError(
                    f"mixed-EHL table: at {where} the solver did not converge at a neighbouring "
                    "node (a film ratio near 0: the boundary-lubrication limit of the "
                    "flow-factor model); use tribology.asperity_model=regression or a smoother "
                    "surface")
        f = self._interp(pts)
        lam_min = _soft_inverse(np.exp(f[:, 0]))
        lam_c = _soft_inverse(np.exp(f[:, 1]))
        log_share = f[:, 2] + mixed_ehl.log_gt_integral(0.5 * (lam_min + lam_c), 2.5)
        share = np.minimum(np.exp(log_share), 1.0)
        return EHLValues(share.reshape(shape), lam_min.reshape(shape), lam_c.reshape(shape),
                         np.exp(f[:, 3]).reshape(shape))

    # --- build, save, load -------------------------------------------------------------------
    @classmethod
    def build(cls, grid: dict[str, Sequence[float]] | None = None, *,
              e_prime: float | None = None, workers: int = 1,
              progress: bool = False) -> MixedEHLTable:
        """Solve every node of ``grid`` (default :data:`GRID`) and wrap the results."""
        grid = {a: _axis(a, (grid or GRID)[a]) for a in AXES}
        e_prime = steel_e_prime() if e_prime is None else float(e_prime)
        if not isinstance(workers, int) or isinstance(workers, bool) or workers < 1:
            raise ValueError(f"workers = {workers!r} must be a whole number >= 1")
        Ug = tuple(grid["U"].tolist())
        keys = [(W, sb, G, eta0) for W in grid["W"] for sb in grid["sigma_bar"]
                for G in grid["G"] for eta0 in grid["eta0"]]
        rows = _run([(W, Ug, sb, G, eta0, e_prime) for W, sb, G, eta0 in keys], workers,
                    progress)
        nW, nU, nS, nG, nE = (grid[a].size for a in AXES)
        data = np.array(rows, dtype=float).reshape(nW, nS, nG, nE, nU, 5)
        data = np.moveaxis(data, 4, 1)  # -> (W, U, sigma_bar, G, eta0, field)
        return cls(grid, data[..., 0], data[..., 1], data[..., 2], data[..., 3],
                   data[..., 4] > 0.5, e_prime)

    def save(self, path: str | os.PathLike) -> None:
        """Write the grid and the node values to an ``.npz`` file (atomic)."""
        from physics.files import atomic_write

        def write(p: Path) -> None:
            with open(p, "wb") as fh:
                np.savez_compressed(
                    fh, **{f"axis_{a}": g for a, g in self.grid.items()}, share=self.share,
                    film_ratio_min=self.film_ratio_min,
                    film_ratio_central=self.film_ratio_central, peak_ratio=self.peak_ratio,
                    converged=self.converged, e_prime=self.e_prime,
                    reference=np.array([_REF_T0, _REF_BETA0, _REF_RHO0]))

        atomic_write(path, write)

    @classmethod
    def load(cls, path: str | os.PathLike) -> MixedEHLTable:
        """Read a table written by :meth:`save`."""
        with np.load(path) as d:
            return cls({a: d[f"axis_{a}"] for a in AXES}, d["share"], d["film_ratio_min"],
                       d["film_ratio_central"], d["peak_ratio"], d["converged"],
                       float(d["e_prime"]))


@lru_cache(maxsize=1)
def shipped_table() -> MixedEHLTable:
    """The table shipped with the package (:data:`TABLE_FILE`), read once per process."""
    if not TABLE_FILE.is_file():
        raise FileNotFoundError(
            f"{TABLE_FILE} is missing: build it with python -m physics.tribology.asperity_table "
            "(or select tribology.asperity_model=regression)")
    return MixedEHLTable.load(TABLE_FILE)


def check_e_prime(e_prime: float, table: MixedEHLTable) -> None:
    """Refuse a reduced modulus more than :data:`E_PRIME_TOLERANCE` from the table's."""
    if abs(e_prime / table.e_prime - 1.0) > E_PRIME_TOLERANCE:
        raise ValueError(
            f"material: the reduced modulus E' = {e_prime / 1e9:.1f} GPa differs by more than "
            f"{E_PRIME_TOLERANCE:.0%} from the {table.e_prime / 1e9:.1f} GPa of the mixed-EHL "
            "table (steel); use tribology.asperity_model=regression or build a table for this "
            "material (MixedEHLTable.build(e_prime=...))")


def lookup(W: np.ndarray, U: np.ndarray, sigma_bar: np.ndarray, alpha: float, eta0: float,
           e_prime: float, table: MixedEHLTable | None = None) -> EHLValues:
    """The solver's share and films at the groups ``W, U, sigma_bar`` (arrays) for a lubricant
    of pressure-viscosity coefficient ``alpha`` [1/Pa] and viscosity ``eta0`` [Pa s] on flanks of
    reduced modulus ``e_prime`` [Pa], from ``table`` (default: the shipped one)."""
    table = shipped_table() if table is None else table
    check_e_prime(e_prime, table)
    return table(W, U, sigma_bar, alpha * e_prime, eta0)


def path_groups(scn: Scenario) -> dict[str, np.ndarray]:
    """``W, U, sigma_bar`` along the path of contact of the unworn pair of ``scn`` (one pair
    carrying the whole quasi-static load), and ``G``, ``eta0`` and ``e_prime``."""
    from physics.gear import contact, kinematics
    from physics.gear.geometry import mesh_geometry

    geom = mesh_geometry(scn.gear)
    s = geom.grid(scn.solver.n_points)
    R1, R2 = geom.curvature_radii(s)
    v1, v2 = kinematics.surface_velocities(R1, R2, scn.operating.omega1, scn.gear.z1,
                                           scn.gear.z2)
    e_prime = 2.0 * contact.reduced_modulus(scn.material, scn.material)
    R = contact.equivalent_radius(R1, R2)
    w = scn.operating.torque_Nm / geom.rb2 / scn.gear.face_width
    lub = scn.lubricant
    return {"W": w / (e_prime * R),
            "U": lub.eta0_Pa_s * kinematics.entraining_velocity(v1, v2) / (e_prime * R),
            "sigma_bar": scn.tribology.sigma_um * 1e-6 / R,
            "G": np.asarray(lub.alpha_m2_per_N * e_prime), "eta0": np.asarray(lub.eta0_Pa_s),
            "e_prime": np.asarray(e_prime)}


def check_scenario(scn: Scenario) -> Scenario:
    """Return ``scn`` if the solver table covers it (speed, viscosity, roughness, lubricant and
    material along the whole path of contact), or if it does not use the table (dry regime,
    regression); raise ``ValueError`` naming the group, the value, the range and the fix."""
    tri = scn.tribology
    if tri.regime == "dry" or tri.asperity_model != "solver":
        return scn
    table = shipped_table()
    g = path_groups(scn)
    check_e_prime(float(g.pop("e_prime")), table)
    table.check(**g)
    return scn


def compare_nodes(table: MixedEHLTable, count: int, seed: int = 0) -> list[dict]:
    """Re-solve ``count`` random nodes of ``table`` and return each with both values."""
    rng = np.random.default_rng(seed)
    shape = table.share.shape
    out = []
    for flat in rng.choice(table.share.size, size=count, replace=False):
        idx = np.unravel_index(int(flat), shape)
        g = {a: float(table.grid[a][i]) for a, i in zip(AXES, idx, strict=True)}
        node = solve_node(**g, e_prime=table.e_prime)
        out.append({**g, "share": node[0], "share_table": float(table.share[idx]),
                    "film_ratio_min": node[1],
                    "film_ratio_min_table": float(table.film_ratio_min[idx])})
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: build the shipped table, or check it against fresh solves."""
    ap = argparse.ArgumentParser(
        prog="python -m physics.tribology.asperity_table",
        description="Build the mixed-EHL table of the wear model (physics/tribology/"
                    "mixed_ehl_table.npz) from the numerical line-contact solver, or check "
                    "the shipped one against fresh solves.")
    ap.add_argument("--out", default=str(TABLE_FILE), help="output file (default: the shipped "
                    "table)")
    ap.add_argument("--workers", type=int, default=1, help="processes (default 1)")
    ap.add_argument("--check", type=int, default=0, metavar="N",
                    help="do not build: re-solve N random nodes of the shipped table and "
                    "compare")
    args = ap.parse_args(argv)
    if args.workers < 1 or args.check < 0:
        ap.error("--workers must be >= 1 and --check >= 0")
    if args.check:
        rows = compare_nodes(shipped_table(), args.check)
        worst = 0.0
        for r in rows:
            err = abs(r["share"] - r["share_table"]) / max(r["share_table"], 1e-300)
            worst = max(worst, err if r["share_table"] > 1e-30 else 0.0)
            print(f"W {r['W']:.3g} U {r['U']:.3g} sigma_bar {r['sigma_bar']:.3g} G {r['G']:.4g} "
                  f"eta0 {r['eta0']:.3g}: share {r['share']:.6g} (table {r['share_table']:.6g})"
                  f", h_min/sigma {r['film_ratio_min']:.6g} "
                  f"(table {r['film_ratio_min_table']:.6g})")
        print(f"largest relative difference of the share (shares above 1e-30): {worst:.2e}")
        return 0
    t = time.perf_counter()
    size = math.prod(len(v) for v in GRID.values())
    print(f"solving {size} nodes on {args.workers} process(es) ...", file=sys.stderr)
    table = MixedEHLTable.build(workers=args.workers, progress=True)
    table.save(args.out)
    failed = int((~table.converged).sum())
    print(f"wrote {args.out}: {size} nodes in {time.perf_counter() - t:.0f} s; {failed} did not "
          "meet the Newton tolerance (kept, flagged in 'converged')")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
