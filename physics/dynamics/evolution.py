"""Wear under dynamic load, and the evolution of pinion root wear with cycles (thesis 3.5, 4.1).

:func:`dynamic_mesh_force` closes the loop of thesis 3.5: at every profile update of the wear
model the torsional model (:mod:`physics.dynamics`) is run for the current worn teeth (their
stiffness and wear gaps), and its mean dynamic mesh force at each mesh position replaces the
quasi-static load. :func:`root_wear_evolution` records the pinion root wear depth against cycles,
and :func:`fit_evolution_models` fits the four candidate laws of 4.1 on ``N <= N_fit`` and judges
them on the cycles beyond.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from physics.dynamics.model import (
    PairModel,
    build_model,
    force_per_position,
    output_samples,
    simulate,
    time_step,
)
from physics.gear.stiffness import MeshStiffness, mesh_stiffness
from physics.params import Dynamics, Scenario
from physics.tribology.wear import MeshForce, WearResult, simulate_wear


def largest_phase_gap(step: float, steps: int) -> float:
    """Largest gap, in mesh periods, between the mesh phases ``k step mod 1`` of ``steps``
    consecutive integration steps. It does not depend on the first step's phase (the
    three-gap theorem: Steinhaus; Sos, Ann. Univ. Sci. Budapest 1 (1958) 127), so a record
    whose gap is below the bin width visits every phase bin whatever its start."""
    phases = np.sort(np.mod(np.arange(steps) * step, 1.0))
    return float(np.max(np.diff(phases, append=phases[0] + 1.0)))


#: revolutions the wear feedback may add to ``dynamics.feedback_revolutions`` to visit every
#: phase bin (a step commensurate with the mesh period revisits the same phases)
EXTRA_REVOLUTIONS = 16


def feedback_dynamics(scn: Scenario, model: PairModel) -> Dynamics:
    """The wear feedback's run: after the declared transient, the fewest whole pinion
    revolutions, at least ``dynamics.feedback_revolutions``, whose steps visit every one of
    the ``dynamics.phase_bins`` mesh-phase bins (:func:`largest_phase_gap`)."""
    dyn = scn.dynamics
    dt, n_sub = time_step([model], dyn)
    revolution = 60.0 / scn.operating.n1_rpm
    step = model.roll_speed * dt / model.geometry.base_pitch  # mesh periods per step
    first = dyn.feedback_revolutions
    for k in range(first, first + EXTRA_REVOLUTIONS + 1):
        run = replace(dyn, duration_s=k * revolution)
        if largest_phase_gap(step, output_samples(run) * n_sub) < 1.0 / dyn.phase_bins:
            return run
    raise ValueError(f"dynamics.phase_bins = {dyn.phase_bins}: {first + EXTRA_REVOLUTIONS} "
                     f"pinion revolutions at n1_rpm = {scn.operating.n1_rpm:g} do not visit "
                     "every mesh-phase bin (the integration step is nearly commensurate with "
                     "the mesh period); use fewer bins or change dynamics.step_factor")


def dynamic_mesh_force(scn: Scenario, stiffness: MeshStiffness | None = None) -> MeshForce:
    """A :data:`physics.wear.MeshForce` that runs the dynamic model for the current wear, over
    whole pinion revolutions (:func:`feedback_dynamics`)."""
    ms = stiffness or mesh_stiffness(scn.gear, scn.material)

    def force(s: np.ndarray, wear1: np.ndarray, wear2: np.ndarray) -> np.ndarray:
        worn = np.any(wear1 > 0) or np.any(wear2 > 0)
        model = build_model(scn, ms, s, wear1, wear2) if worn else build_model(scn, ms)
        response = simulate(model, feedback_dynamics(scn, model))
        return force_per_position(model, response.force_by_phase[0], s)

    return force


def simulate_dynamic_wear(scn: Scenario, cycles: float, snapshots=(),
                          stiffness: MeshStiffness | None = None, until=None) -> WearResult:
    """Wear with the dynamic mesh force fed back at every profile update (thesis 3.5);
    ``stiffness``: the pair's mesh stiffness if already built (else built here); ``snapshots``
    and ``until`` as in :func:`physics.tribology.wear.simulate_wear`."""
    ms = stiffness or mesh_stiffness(scn.gear, scn.material)
    return simulate_wear(scn, cycles, force=dynamic_mesh_force(scn, ms),
                         stiffness=ms.pair_function, snapshots=snapshots, until=until)


def root_wear_evolution(scn: Scenario, cycles: np.ndarray, dynamic: bool = True,
                        stiffness: MeshStiffness | None = None
                        ) -> tuple[np.ndarray, WearResult]:
    """Pinion root wear depth [m] at each of ``cycles`` (block ends land on them);
    ``stiffness`` as in :func:`simulate_dynamic_wear` (the quasi-static run builds its own)."""
    cycles = np.asarray(cycles, dtype=float)
    if dynamic:
        res = simulate_dynamic_wear(scn, float(cycles.max()), snapshots=list(cycles),
                                    stiffness=stiffness)
    else:
        res = simulate_wear(scn, float(cycles.max()), snapshots=list(cycles))
    return np.array([res.snapshots[float(c)][0][0] for c in cycles]), res


@dataclass(frozen=True)
class EvolutionModel:
    """A candidate law of thesis 4.1 as ``h = basis(n; theta) @ coef`` (n = N / 1e7).

    The coefficients enter linearly; only ``theta`` (the rates and exponents) is searched, from
    every start in ``starts`` (variable projection: robust where plain least squares on all the
    parameters stalls, e.g. two exponentials fitted to nearly linear data).
    """

    name: str
    basis: Callable[[np.ndarray, np.ndarray], np.ndarray]  # (n, theta) -> (len(n), n_coef)
    starts: tuple[tuple[float, ...], ...]


CANDIDATES = (
    EvolutionModel("quadratic", lambda n, th: np.stack([n**2, n, np.ones_like(n)], axis=1), ((),)),
    EvolutionModel("exponential",  # h = a exp(b N) + c
                   lambda n, th: np.stack([np.exp(th[0] * n), np.ones_like(n)], axis=1),
                   ((-2.0,), (-0.5,), (0.5,), (2.0,))),
    EvolutionModel("power",  # h = a N^b
                   lambda n, th: np.power(np.maximum(n, 1e-12), th[0])[:, None],
                   ((0.5,), (1.0,), (2.0,))),
    EvolutionModel("empirical",  # thesis 4.1: h = a1 exp(a2 N) + a3 exp(a4 N)
                   lambda n, th: np.stack([np.exp(th[0] * n), np.exp(th[1] * n)], axis=1),
                   ((1.6, -2.6), (0.5, -0.5), (3.0, -1.0), (1.0, -5.0))),
)


def fit_evolution_model(model: EvolutionModel, n: np.ndarray, h: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Best ``(theta, coef)`` of ``model`` for data (n, h) in the fit's scaled units."""
    from scipy.optimize import least_squares

    def coef(theta: np.ndarray) -> np.ndarray:
        return np.linalg.lstsq(model.basis(n, theta), h, rcond=None)[0]

    def residual(theta: np.ndarray) -> np.ndarray:
        return model.basis(n, theta) @ coef(theta) - h

    best = None
    for start in model.starts:
        if not start:  # purely linear model
            theta = np.array([])
        else:
            theta = least_squares(residual, np.array(start), method="lm").x
        cost = float(np.sum(residual(theta) ** 2))
        if best is None or cost < best[0]:
            best = (cost, theta)
    theta = best[1]
    return theta, coef(theta)


def fit_evolution_models(cycles: np.ndarray, wear: np.ndarray, fit_until: float = 1e7
                         ) -> list[dict]:
    """Fit each candidate on ``cycles <= fit_until``; judge it on the cycles beyond.

    Returns one dict per model: RMSE, R^2 and maximum relative error of its prediction on the
    held-out cycles (``N > fit_until``), the RMSE on the fitted range, and the parameters (N in
    cycles, h in the unit of ``wear``: quadratic ``[a, b, c]``, exponential ``[a, b, c]``, power
    ``[a, b]``, empirical ``[a1, a2, a3, a4]``).
    """
    cycles, wear = np.asarray(cycles, float), np.asarray(wear, float)
    fit, test = cycles <= fit_until, cycles > fit_until
    if fit.sum() < 5 or test.sum() < 2:
        raise ValueError(f"need >= 5 points with N <= {fit_until:g} and >= 2 beyond it; got "
                         f"{int(fit.sum())} and {int(test.sum())}")
    scale_n, scale_h = 1e7, float(np.max(np.abs(wear))) or 1.0
    n, h = cycles / scale_n, wear / scale_h
    rows = []
    for model in CANDIDATES:
        theta, coef = fit_evolution_model(model, n[fit], h[fit])
        pred = model.basis(n, theta) @ coef * scale_h
        err = pred[test] - wear[test]
        ss_tot = float(np.sum((wear[test] - wear[test].mean()) ** 2))
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.abs(err) / np.abs(wear[test])
        rows.append({
            "model": model.name,
            "rmse": float(np.sqrt(np.mean(err**2))),
            "r2": float(1 - np.sum(err**2) / ss_tot) if ss_tot > 0 else np.nan,
            "max_relative_error_pct": float(np.max(rel) * 100),
            "fit_rmse": float(np.sqrt(np.mean((pred[fit] - wear[fit]) ** 2))),
            "params": _unscale(model.name, theta, coef, scale_n, scale_h),
        })
    return rows


def _unscale(name: str, theta: np.ndarray, coef: np.ndarray, sn: float, sh: float) -> list[float]:
    """Parameters for N in cycles and h in the caller's unit."""
    if name == "quadratic":
        return [coef[0] * sh / sn**2, coef[1] * sh / sn, coef[2] * sh]
    if name == "exponential":
        return [coef[0] * sh, theta[0] / sn, coef[1] * sh]
    if name == "power":
        return [coef[0] * sh / sn ** theta[0], theta[0]]
    return [coef[0] * sh, theta[0] / sn, coef[1] * sh, theta[1] / sn]
