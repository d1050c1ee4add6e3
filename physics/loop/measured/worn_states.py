"""The declared model's worn states at the records' operating points: one dynamically coupled
wear run (:mod:`physics.dynamics.evolution`) per operating point, every profile update kept
(:class:`WearHistory`), read at the records' cycle counts (or, where only a record's wear depth
is known, at the cycle count of that depth), and the grid of wear states the model-based wear
estimate reads a record by (:mod:`physics.loop.search.wear_reading`).

A feature table's rows give depths only, from new to worn out: their states are the pair worn by
the contact its worn flanks make (:func:`table_models`, the machinery of
:mod:`physics.reproduce.rig`), which follows the flanks to the tooth's tip thickness
(:func:`check_table_depths`), where the on-path run stops at tens to a few hundred
micrometres."""

from __future__ import annotations

import dataclasses
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from physics.dynamics.evolution import simulate_dynamic_wear
from physics.dynamics.model import PairModel, build_model
from physics.gear.stiffness import MeshStiffness, mesh_stiffness
from physics.params import OutOfScope, Scenario
from physics.reproduce.rig import worn_models as contact_models
from physics.reproduce.rig import worn_states as contact_states
from physics.tribology.contact_wear import wear_per_cycle, whole_flank_grid
from physics.tribology.wear import quasi_static_force

log = logging.getLogger(__name__)

#: the most pinion cycles a run goes to in search of a wear depth (beyond any gear's life)
MAX_CYCLES = 1e13
#: the grid of wear states reaches this many times the most worn record's root wear
GRID_REACH = 1.2
#: operating points whose runs are kept (:func:`wear_history`)
KEPT = 16
#: records deeper than this [mm] or older than ``PROBE_FROM_CYCLES`` are first checked against a
#: coarse run's reach (:func:`probe_reach`): the run at the solver's own step takes minutes to
#: reach a few hundred micrometres (887 s to the 0.26 mm where case 3's worn flanks pass the
#: shakedown limit, on two shared cores), the coarse one 31 s
PROBE_FROM_MM = 0.05
PROBE_FROM_CYCLES = 1e9
#: the coarse run: a 20 um wear step on 101 points
PROBE_SOLVER = {"update_um": 20.0, "n_points": 101}
#: a record is refused when it lies beyond this many times the coarse run's reach; measured at
#: 1800 r/min / 290 N m, the coarse run stops 8 % short of the solver's own in depth and in
#: cycles (0.239 against 0.260 mm, 4.55e10 against 4.94e10 cycles)
PROBE_MARGIN = 1.25

_kept: dict[Scenario, WearHistory] = {}
_KEPT_LOCK = threading.Lock()  # operating points' runs on parallel threads


@dataclass(frozen=True)
class WearHistory:
    """One operating point's wear run, read at any cycle count: its block ends' cycles
    ``(k,)`` and pinion and gear wear ``(k, n)`` [m] on the roll coordinate ``s``. Within a
    block the explicit update wears every point linearly in cycles, so the linear
    interpolation between block ends is the run's own wear (not an approximation of it)."""

    s: np.ndarray
    cycles: np.ndarray
    pinion: np.ndarray
    gear: np.ndarray
    #: why the run ended where the model's scope ends (:class:`physics.params.OutOfScope`),
    #: else None: no run of this operating point goes further
    left_scope: str | None = None

    @property
    def root_mm(self) -> np.ndarray:
        """Pinion root wear [mm] at the block ends."""
        return self.pinion[:, 0] * 1e3

    def root_at(self, cycles: float) -> float:
        return float(np.interp(cycles, self.cycles, self.root_mm))

    def cycles_at(self, root_mm: np.ndarray) -> np.ndarray:
        """Cycle counts at which the pinion root wear reaches ``root_mm``."""
        return np.interp(root_mm, self.root_mm, self.cycles)

    def profiles(self, cycles: float) -> tuple[np.ndarray, np.ndarray]:
        """Pinion and gear wear [m] at ``cycles`` (within the run)."""
        k = int(np.clip(np.searchsorted(self.cycles, cycles) - 1, 0, len(self.cycles) - 2))
        frac = (cycles - self.cycles[k]) / (self.cycles[k + 1] - self.cycles[k])
        return tuple(w[k] + frac * (w[k + 1] - w[k]) for w in (self.pinion, self.gear))


def wear_history(scn: Scenario, enough: Callable[[np.ndarray, np.ndarray], bool]
                 ) -> WearHistory:
    """The dynamically coupled wear run of ``scn`` until ``enough(cycles, root_mm)`` of its
    block ends (at most ``MAX_CYCLES``).

    A run that leaves the model's scope ends there (:attr:`WearHistory.left_scope`).

    A run without snapshots does not depend on where it ends, so the longest run of each
    operating point is kept (for the last ``KEPT`` points) and serves every shorter need: a
    bundle and its sister unit at the same operating points, or a table and its worn models,
    share one run."""
    def done(h: WearHistory) -> bool:
        return h.left_scope is not None or (len(h.cycles) > 1 and enough(h.cycles, h.root_mm))

    with _KEPT_LOCK:
        kept = _kept.get(scn)
    if kept is not None and done(kept):
        return kept
    try:
        res = simulate_dynamic_wear(scn, MAX_CYCLES,
                                    stiffness=mesh_stiffness(scn.gear, scn.material),
                                    until=lambda c, w1: enough(c, w1[:, 0] * 1e3))
        history = WearHistory(res.s, *res.history)
    except OutOfScope as err:
        history = WearHistory(*err.history, left_scope=str(err))
    for a in (history.s, history.cycles, history.pinion, history.gear):
        a.flags.writeable = False
    with _KEPT_LOCK:
        _kept.pop(scn, None)
        if len(_kept) >= KEPT:
            _kept.pop(next(iter(_kept)))  # the oldest
        _kept[scn] = history
    return history


def _reached(h: WearHistory, root_mm: float, what: str) -> None:
    if h.root_mm[-1] >= root_mm:
        return
    why = (f"there the model leaves its scope: {h.left_scope}" if h.left_scope else
           "check the operating point and tribology.regime")
    raise OutOfScope(f"the model's root wear reaches only {h.root_mm[-1]:.4g} mm in "
                     f"{h.cycles[-1]:.3g} cycles, below {root_mm:.4g} mm ({what}); {why}")


def records_history(scn: Scenario, rows: pd.DataFrame) -> WearHistory | None:
    """The run of one operating point that covers its records (their stated cycles, else
    their stated wear) and the grid of wear states beyond the most worn (``GRID_REACH`` times
    its root wear, or as far as the model follows); None where no record is worn. Records
    beyond the model's reach are refused (:class:`OutOfScope`)."""
    stated = rows.cycles.to_numpy(float)
    c_max = float(np.nanmax(stated, initial=0.0))
    w_max = float(np.nanmax(rows.wear_mm.to_numpy(float)[np.isnan(stated)], initial=0.0))
    if c_max <= 0 and w_max <= 0:
        return None

    def enough(c: np.ndarray, root: np.ndarray) -> bool:
        top = max(w_max, float(np.interp(c_max, c, root)))
        return c[-1] >= c_max and root[-1] >= GRID_REACH * top

    if w_max > PROBE_FROM_MM or c_max > PROBE_FROM_CYCLES:
        probe_reach(scn, rows, w_max, c_max)
    h = wear_history(scn, enough)
    if h.left_scope is None:
        _reached(h, GRID_REACH * max(w_max, h.root_at(c_max)), "the wear-state grid's top")
        return h
    if h.root_mm[-1] < w_max:
        _reached(h, w_max, f"the most worn record{_most(rows, 'wear_mm', np.isnan(stated))}")
    if c_max > h.cycles[-1]:
        raise OutOfScope(f"records at {c_max:.3g} cycles{_most(rows, 'cycles')} lie beyond the "
                         f"{h.cycles[-1]:.3g} cycles at which the model leaves its scope: "
                         f"{h.left_scope}")
    return h


def probe_reach(scn: Scenario, rows: pd.DataFrame, w_max: float, c_max: float) -> None:
    """Refuse records far beyond the model's reach after a coarse run (``PROBE_SOLVER``), before
    the run at the solver's own step: a stated wear ``w_max`` [mm] or cycle count ``c_max``
    more than ``PROBE_MARGIN`` times what the coarse run reaches before it leaves the model's
    scope (:class:`OutOfScope`, naming the record). Records within that margin are left to
    the run itself."""
    coarse = dataclasses.replace(scn, solver=dataclasses.replace(scn.solver, **PROBE_SOLVER))
    h = wear_history(coarse, lambda c, root: (root[-1] * PROBE_MARGIN >= w_max
                                              and c[-1] * PROBE_MARGIN >= c_max))
    if h.left_scope is None:
        return
    stated = rows.cycles.to_numpy(float)
    if h.root_mm[-1] * PROBE_MARGIN < w_max:
        raise OutOfScope(f"the model's root wear reaches about {h.root_mm[-1]:.3g} mm (a run "
                         f"with a {PROBE_SOLVER['update_um']:g} um wear step), far below the "
                         f"{w_max:.4g} mm of the most worn record"
                         f"{_most(rows, 'wear_mm', np.isnan(stated))}; there the model leaves "
                         f"its scope: {h.left_scope}; leave out the records beyond it")
    if h.cycles[-1] * PROBE_MARGIN < c_max:
        raise OutOfScope(f"records at {c_max:.3g} cycles{_most(rows, 'cycles')} lie far beyond "
                         f"the about {h.cycles[-1]:.3g} cycles at which the model leaves its "
                         f"scope (a run with a {PROBE_SOLVER['update_um']:g} um wear step): "
                         f"{h.left_scope}; leave out the records beyond it")


def _most(rows: pd.DataFrame, column: str, among: np.ndarray | None = None) -> str:
    """`` (record 'NAME')``: the record of ``rows`` (``among`` them) with the largest
    ``column``; empty where the rows are not named."""
    values = rows[column].to_numpy(float).copy()
    if among is not None:
        values[~among] = np.nan
    if "record" not in rows or not np.isfinite(values).any():
        return ""
    return f" (record {rows.record.iloc[int(np.nanargmax(values))]!r})"


def records_cycles(h: WearHistory | None, rows: pd.DataFrame) -> np.ndarray:
    """Load cycles of records of one operating point: stated, else those at which the model
    (its run ``h``, :func:`records_history`) reaches their wear, else 0."""
    cycles = rows.cycles.to_numpy(float).copy()
    wear = rows.wear_mm.to_numpy(float)
    find = np.isnan(cycles) & (np.nan_to_num(wear) > 0)
    if find.any():
        cycles[find] = h.cycles_at(wear[find])
    check_stated_wear(h, rows)
    return np.nan_to_num(cycles)


#: a record's stated wear and the model's at its stated cycles disagree beyond this ratio
#: (either way) and ``WEAR_SAID_FROM_MM`` of difference: said in the run's log
WEAR_RATIO_SAID = 2.0
WEAR_SAID_FROM_MM = 1e-3


def check_stated_wear(h: WearHistory | None, rows: pd.DataFrame) -> list[str]:
    """Records of one operating point that state both ``cycles`` and ``wear_mm``, where the
    model's pinion root wear at those cycles (its run ``h``; none worn: 0) and the stated one
    differ by more than ``WEAR_RATIO_SAID`` times and ``WEAR_SAID_FROM_MM``: said as a warning
    (the loop reads such a record at its cycles, so the stated depth is not the state it
    compares). Returns the lines said."""
    cycles, wear = rows.cycles.to_numpy(float), rows.wear_mm.to_numpy(float)
    both = np.isfinite(cycles) & np.isfinite(wear)
    if not both.any():
        return []
    model = np.zeros(both.sum()) if h is None else np.array(
        [h.root_at(c) for c in cycles[both]], float)
    stated = wear[both]
    far = (np.abs(model - stated) > WEAR_SAID_FROM_MM) & (
        (stated > WEAR_RATIO_SAID * model) | (model > WEAR_RATIO_SAID * stated))
    said = [f"record {r!r}: wear_mm = {w:.4g} mm stated, the model's {m:.3g} mm at its "
            f"{c:.3g} stated cycles" for r, w, m, c in zip(
                rows.record.to_numpy()[both][far], stated[far], model[far], cycles[both][far],
                strict=True)]
    if said:
        log.warning("%d record(s) state a wear the model does not reach at their cycles (%s%s): "
                    "the loop reads each at its stated cycles, so the difference is the wear "
                    "model's error at this operating point, not corrected; leave cycles empty to "
                    "read a record at its stated wear", len(said), "; ".join(said[:3]),
                    "; ..." if len(said) > 3 else "")
    return said


def wear_grid_cycles(h: WearHistory | None, cycles_max: float, n: int) -> list[float]:
    """Cycle counts of ``n`` wear states of one operating point whose pinion root wear is
    spread evenly from 0 to ``GRID_REACH`` times the model's at ``cycles_max`` (the most worn
    record), or to the run's end where the model leaves its scope before; none if no record
    is worn. Even in wear, not in cycles: the lubricated law wears the root fastest while it
    runs in, so states even in cycles leave the records below that without a state to read
    them by."""
    if cycles_max <= 0:
        return []
    top = min(GRID_REACH * h.root_at(cycles_max), float(h.root_mm[-1]))
    return [float(c) for c in h.cycles_at(np.linspace(0.0, top, n))]


def worn_models(scn: Scenario, ms: MeshStiffness, cycles: list[float],
                history: WearHistory | None = None
                ) -> tuple[dict[float, PairModel], dict[float, float]]:
    """Declared models and pinion root wear [mm] at each cycle count of one operating point,
    read off ``history`` (by default the run to the last of ``cycles``)."""
    last = max([float(c) for c in cycles], default=0.0)
    if history is None and last > 0:
        history = wear_history(scn, lambda c, _: c[-1] >= last)
    models, root = {0.0: build_model(scn, ms)}, {0.0: 0.0}
    for c in sorted({float(c) for c in cycles} - {0.0}):
        w1, w2 = history.profiles(c)
        models[c] = build_model(scn, ms, history.s, w1, w2)
        root[c] = float(w1[0]) * 1e3
    return models, root


def tip_thickness_mm(scn: Scenario) -> float:
    """The thinner tooth's thickness at its tip along its drive flank's normal [mm]
    (:attr:`physics.gear.geometry.MeshGeometry.tip_thickness`): the contact-driven wear cannot
    follow a flank that deep."""
    return mesh_stiffness(scn.gear, scn.material).geometry.tip_thickness * 1e3


def check_table_depths(scn: Scenario, wear_mm: np.ndarray) -> None:
    """Refuse, before any work, a feature table whose worn states the contact-driven wear
    cannot give: a depth [mm] at or beyond the tip thickness (:func:`tip_thickness_mm`), or a
    wear law out of its scope at the new flanks (its first block, a fraction of a second;
    :class:`OutOfScope`, naming the depth it can follow: none)."""
    tip = tip_thickness_mm(scn)
    deep = wear_mm >= tip
    if deep.any():
        row = int(np.argmax(wear_mm)) + 1  # the deepest, counted from 1 as in the file
        raise OutOfScope(f"feature table: row {row}: wear_mm = {float(wear_mm[deep].max()):g} "
                         f"mm reaches the {tip:.3g} mm the thinner tooth is thick at its tip "
                         "(along its flank's normal): a flank worn that deep has no tip left to "
                         f"mesh; the loop follows the flanks to below {tip:.3g} mm: leave out "
                         "the deeper rows, or check that wear_mm is in mm")
    if wear_mm.max() <= 0:
        return
    ms = mesh_stiffness(scn.gear, scn.material)
    grid = whole_flank_grid(ms)
    new = np.zeros_like(grid)
    try:
        wear_per_cycle(scn, ms, grid, new, new, quasi_static_force(scn, ms.geometry))
    except OutOfScope as err:
        raise OutOfScope(f"feature table: the wear law leaves its scope at the new flanks, so "
                         f"the loop follows no depth at this operating point (0 of "
                         f"{float(wear_mm.max()):g} mm): {err}; or wear the flanks by the dry "
                         "law, tribology.regime=dry") from None


def table_models(scn: Scenario, wear_mm: np.ndarray, rows: np.ndarray | None = None
                 ) -> list[PairModel]:
    """The declared models of a feature table's rows: the pair worn from new by the contact its
    worn flanks make to each row's depth (the deepest point of either active profile), with
    the scenario's contact in the dynamics (``dynamics.flank_contact``).

    How deep the contact-driven wear follows the flanks before they leave the model's scope
    (a tooth worn to its centre line somewhere on the flank) is known only by running it, to
    the deepest row: where it leaves the scope first, the refusal (:class:`OutOfScope`, one
    line) names that row (``rows``: the rows' numbers in the file, counted from 1; by default
    their order here) and its depth."""
    wear_mm = np.asarray(wear_mm, float)
    try:
        s, states = contact_states(scn, wear_mm)
        return contact_models(scn, scn.dynamics.flank_contact, s, states)
    except OutOfScope as err:
        rows = np.arange(1, wear_mm.size + 1) if rows is None else np.asarray(rows)
        i = int(np.argmax(wear_mm))
        shallower = wear_mm[wear_mm < wear_mm[i]]
        keep = (f"; the next deepest row is at {float(shallower.max()):g} mm"
                if shallower.size else "")
        raise OutOfScope(f"feature table: row {int(rows[i])} (wear_mm = {wear_mm[i]:g} mm, the "
                         "deepest) lies beyond what the contact-driven wear follows at this "
                         "operating point: on the way there the worn flanks leave the model's "
                         f"scope ({' '.join(str(err).split())}); leave out the deepest "
                         f"row(s){keep}, and run again") from None
