"""The declared model's worn states at the records' operating points: the dynamically coupled
wear evolution (:mod:`physics.dynamics.evolution`) run once per operating point to the records'
cycle counts (or, where only a record's wear depth is known, to the cycle count of that depth),
and the grid of wear states the model-based wear estimate reads a record by
(:mod:`physics.loop.wear_reading`)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd

from physics.dynamics.evolution import root_wear_evolution, simulate_dynamic_wear
from physics.dynamics.model import PairModel, build_model
from physics.gear.stiffness import MeshStiffness, mesh_stiffness
from physics.params import Scenario


def worn_models(scn: Scenario, ms: MeshStiffness, cycles: list[float]
                ) -> tuple[dict[float, PairModel], dict[float, float]]:
    """Declared models and pinion root wear [mm] at each cycle count of one operating point."""
    grid = sorted({0.0, *[float(c) for c in cycles]})
    models, root = {0.0: build_model(scn, ms)}, {0.0: 0.0}
    if grid[-1] > 0:
        res = simulate_dynamic_wear(scn, grid[-1], snapshots=grid[1:],
                                    stiffness=mesh_stiffness(scn.gear, scn.material))
        for c in grid[1:]:
            w1, w2 = res.snapshots[c]
            models[c] = build_model(scn, ms, res.s, w1, w2)
            root[c] = float(w1[0]) * 1e3
    return models, root


def wear_curve(scn: Scenario, span: float, points: int, power: float,
               enough: Callable[[np.ndarray, np.ndarray], bool],
               grow: Callable[[np.ndarray, np.ndarray], float] | None = None
               ) -> tuple[np.ndarray, np.ndarray, bool]:
    """The model's pinion root wear [m] on the life grid ``span * u**power`` (``points`` values
    of u from 0 to 1), the span grown (by ``grow(life, root)``, at least doubled; doubled by
    default) up to seven times until ``enough(life, root)``; returns the last grid, its wear and
    whether it was enough."""
    for _ in range(8):
        life = span * np.linspace(0.0, 1.0, points) ** power
        root = root_wear_evolution(scn, life,
                                   stiffness=mesh_stiffness(scn.gear, scn.material))[0]
        if enough(life, root):
            return life, root, True
        span *= max(2.0, grow(life, root) if grow is not None else 2.0)
    return life, root, False


def cycles_for_wear(scn: Scenario, wear_mm: np.ndarray, cycles_max: float = 1.5e7
                    ) -> np.ndarray:
    """Cycle counts at which the model's pinion root wear reaches ``wear_mm``. Where a span
    falls short the next is extrapolated from the wear it reached, by the power law of its
    second half (``root ~ N^p``: the span times ``(target / reached)^(1/p)``, a fifth to
    spare), so that one more span usually suffices."""
    target = float(np.max(wear_mm))

    def grow(life: np.ndarray, root: np.ndarray) -> float:
        mid = len(life) // 2
        if root[-1] <= 0 or root[mid] <= 0:
            return 2.0
        p = np.log(root[-1] / root[mid]) / np.log(life[-1] / life[mid])
        return float(min(8.0, 1.2 * (target / (root[-1] * 1e3)) ** (1 / max(p, 0.2))))

    life, root_m, ok = wear_curve(scn, cycles_max, 16, 1,
                                  lambda _, root: root[-1] * 1e3 >= target, grow)
    root = root_m * 1e3
    if not ok:
        raise ValueError(f"the model's root wear reaches only {root[-1]:.4g} mm in "
                         f"{life[-1]:.3g} cycles, below {target:g} mm: check the "
                         "operating point and tribology.regime")
    return np.interp(wear_mm, root, life)


def wear_grid_cycles(scn: Scenario, cycles_max: float, n: int) -> list[float]:
    """Cycle counts of ``n`` wear states of one operating point whose pinion root wear is
    spread evenly from 0 to 1.2 times the model's at ``cycles_max`` (the most worn record);
    none if no record is worn. Even in wear, not in cycles: the lubricated law wears the root
    fastest while it runs in (case 3: 6.9 of 15.7 um in the first ninth of its cycles), so states
    even in cycles leave the records below that without a state to read them by."""
    if cycles_max <= 0:
        return []

    def top(life: np.ndarray, root: np.ndarray) -> float:
        return 1.2 * float(np.interp(cycles_max, life, root))

    # the life grid dense where the wear rises fastest
    life, root, ok = wear_curve(scn, 2.0 * cycles_max, 33, 2,
                                lambda life, root: root[-1] >= top(life, root))
    if not ok:
        raise ValueError(f"the model's root wear does not grow by a fifth beyond its value at "
                         f"{cycles_max:.3g} cycles within {life[-1]:.3g}: check the operating "
                         "point and tribology.regime")
    return [float(c) for c in np.interp(np.linspace(0.0, top(life, root), n), root, life)]


def records_cycles(scn: Scenario, rows: pd.DataFrame) -> np.ndarray:
    """Load cycles of records of one operating point: stated, else those at which the model
    reaches their wear (one wear simulation for them all), else 0."""
    cycles = rows.cycles.to_numpy(float).copy()
    wear = rows.wear_mm.to_numpy(float)
    find = np.isnan(cycles) & (np.nan_to_num(wear) > 0)
    if find.any():
        cycles[find] = cycles_for_wear(scn, wear[find])
    return np.nan_to_num(cycles)
