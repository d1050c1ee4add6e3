"""Each tooth its own flank, over a pinion revolution or the hunting period (the mesh sequence).

A model built for one wear state (:func:`physics.dynamics.model.build_model`) holds one mesh
period: every tooth pair alike. Here the tables span the ``z1`` mesh periods of a pinion
revolution and each pinion tooth brings its own tables: in period ``p`` pinion tooth ``p`` is
pair A (it entered at the period's start), tooth ``p - 1`` pair B and the pair past the end of
the path, tooth ``p + 1`` the pair before its entry and tooth ``p - 2`` the one after B (the
kernel's off-path pairs, :func:`physics.gear.tooth_contact.pair_slots`). A tooth's tables are
those of a model of the whole gear worn as that tooth is, so a uniform set of teeth is the
one-period model tiled, table for table.

Each pinion tooth may also stand off its theoretical place (:func:`with_tooth_positions`: the
single pitch deviations of ISO 1328-1, drawn per gear by
:func:`physics.gear.accuracy.tooth_positions_um`): a tooth ahead meets its mate earlier and
carries more of the load, the pattern that repeats once per pinion revolution.

A state worn tooth by tooth (:func:`physics.tribology.contact_wear.simulate_contact_wear`)
becomes such a model by :func:`sequence_model`: one table set per mesh of its meshing sequence
(:mod:`physics.gear.mesh_sequence`), over the z1 meshes of a pinion revolution where the gear's
teeth are carried alike, over the hunting period ``lcm(z1, z2)`` where the gear's teeth are
each their own; in period ``p`` the models are then those of meshes ``p``, ``p - 1``, ...
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from physics.dynamics.model import EXACT_PHASES, PairModel, build_model
from physics.gear.accuracy import POSITION_BOUND_FP, position_bound_m
from physics.gear.mesh_sequence import hunting_period, meshing_sequence
from physics.gear.stiffness import MeshStiffness
from physics.gear.tooth_contact import NO_CONTACT
from physics.params import Scenario


def _shown(value: Any) -> str:
    """``repr(value)`` on one line and at most 60 characters (an array's repr wraps)."""
    text = " ".join(repr(value).split())
    return text if len(text) <= 60 else text[:57] + "..."


def _tooth_models(teeth: Any, name: str = "teeth") -> list[PairModel]:
    """``teeth`` as a list when it is a non-empty sequence of :class:`PairModel`; ``TypeError``
    naming the argument, the offending value and what is allowed otherwise."""
    fix = ("give a list of one-period PairModel, one per pinion tooth or per mesh of the "
           "hunting period (physics.dynamics.model.build_model)")
    if isinstance(teeth, str | bytes | PairModel) or not isinstance(teeth, Sequence):
        raise TypeError(f"{name} = {_shown(teeth)} ({type(teeth).__name__}) must be a sequence "
                        f"of PairModel; {fix}")
    if len(teeth) == 0:
        raise ValueError(f"{name} = {_shown(teeth)} is empty; {fix}")
    for i, m in enumerate(teeth):
        if not isinstance(m, PairModel):
            raise TypeError(f"{name}[{i}] = {_shown(m)} ({type(m).__name__}) is not a PairModel; "
                            f"{fix}")
    return list(teeth)


def _finite_tables(teeth: list[PairModel]) -> None:
    """Refuse a tooth model whose stiffness or gap tables hold NaN or infinities (gaps out of
    reach are ``NO_CONTACT``, finite)."""
    for i, m in enumerate(teeth):
        for field in ("k_a", "k_b", "g_a", "g_b", "k_off", "g_off"):
            table = getattr(m, field)
            if table is not None and not np.all(np.isfinite(table)):
                raise ValueError(f"teeth[{i}].{field} holds NaN or infinite values; build the "
                                 "tooth models from finite wear depths and tooth positions")


def per_tooth_model(teeth: Sequence[PairModel]) -> PairModel:
    """The model whose mesh ``i`` is ``teeth[i]``'s: one-period models of the same pair and
    operating point in mesh order, one per pinion tooth (a pinion revolution) or one per mesh
    of the hunting period ``lcm(z1, z2)`` (module doc). Damping, inertias, errors and the other
    scalars are the first's.

    ``teeth`` that is no sequence of :class:`PairModel` is refused (``TypeError``), as are
    tables with NaN or infinite values (``ValueError``)."""
    teeth = _tooth_models(teeth)
    _finite_tables(teeth)
    z1 = len(teeth)
    first = teeth[0]
    z, z2 = first.geometry.gear.z1, first.geometry.gear.z2
    if z1 not in (z, hunting_period(z, z2)):
        raise ValueError(f"{z1} tooth models for a {z}/{z2} pair; give one per pinion tooth "
                         f"({z}) or one per mesh of the hunting period "
                         f"({hunting_period(z, z2)}, sequence_model)")
    if any(m.periods != 1 or len(m.k_a) != len(first.k_a) for m in teeth):
        raise ValueError("every tooth model needs one mesh period of the same phase grid")

    def seq(name: str, shift: int, row: int | None = None) -> np.ndarray | None:
        parts = [getattr(teeth[(p + shift) % z1], name) for p in range(z1)]
        if any(x is None for x in parts):
            return None
        return np.concatenate([x if row is None else x[row] for x in parts])

    off = None
    if all(m.k_off is not None for m in teeth):
        off = {name: np.stack([seq(name, 1, 0), seq(name, -1, 1), seq(name, -2, 2)])
               for name in ("k_off", "g_off")}
    return dataclasses.replace(
        first, periods=z1, k_a=seq("k_a", 0), g_a=seq("g_a", 0), lam_a=seq("lam_a", 0),
        k_b=seq("k_b", -1), g_b=seq("g_b", -1), lam_b=seq("lam_b", -1),
        k_off=None if off is None else off["k_off"], g_off=None if off is None else off["g_off"])


def sequence_model(scn: Scenario, ms: MeshStiffness, grid: np.ndarray, wear1: np.ndarray,
                   wear2: np.ndarray, positions: tuple[np.ndarray, np.ndarray] | None = None,
                   n_phase: int = EXACT_PHASES) -> PairModel:
    """The model of ``scn`` over one repeat of the meshing sequence of teeth worn tooth by
    tooth (module doc): ``wear1`` ``(n1, grid)`` and ``wear2`` ``(n2, grid)`` on ``grid`` [m],
    a row per tooth in mesh order or one for teeth alike, as
    :class:`physics.tribology.contact_wear.ContactWear` holds them; ``positions`` the teeth's
    position deviations [m], ``(n1,)`` and ``(n2,)``, as there. Each mesh's tables are those of
    a model of the whole pair worn as that mesh's two teeth are (:func:`build_model`), its gaps
    closed by the two teeth's positions. Teeth alike on both wheels give the one-period model
    tiled over a pinion revolution."""
    wear1, wear2 = np.asarray(wear1, dtype=float), np.asarray(wear2, dtype=float)
    if wear1.ndim != 2 or wear2.ndim != 2:
        raise ValueError(f"wear1 of shape {wear1.shape} and wear2 of shape {wear2.shape}: give "
                         "a row per tooth (or one row for teeth alike) on the grid")
    seq = meshing_sequence(scn.gear.z1, scn.gear.z2, len(wear1), len(wear2))
    if positions is not None:
        if len(positions) != 2:
            raise ValueError(f"positions has {len(positions)} parts; give (pinion, gear), one "
                             "deviation [m] per row of wear1 and wear2, or None for a wheel")
        positions = tuple(np.zeros(len(w)) if p is None else np.asarray(p, dtype=float)
                          for p, w in zip(positions, (wear1, wear2), strict=True))
        for name, p, w in zip(("pinion", "gear"), positions, (wear1, wear2), strict=True):
            if p.shape != (len(w),):
                raise ValueError(f"positions of the {name} of shape {p.shape}: give one per "
                                 f"row of its wear ({len(w)})")
    pairs, index = seq.distinct_pairs(wear1, wear2)  # each distinct pair's tables once
    built = [build_model(scn, ms, grid, wear1[i], wear2[j], n_phase=n_phase) for i, j in pairs]
    models = [built[d] for d in index]
    if positions is not None:
        models = with_tooth_positions(models, positions[0][seq.pinion] + positions[1][seq.gear])
    z1 = scn.gear.z1
    # a repeat shorter than a pinion revolution (teeth alike) is tiled to one, or to the
    # hunting period where only the gear's teeth are carried
    span = z1 if z1 % len(models) == 0 else hunting_period(z1, scn.gear.z2)
    return per_tooth_model(models * (span // len(models)))


def with_tooth_positions(teeth: Sequence[PairModel], positions_m: Sequence[float]
                         ) -> list[PairModel]:
    """The one-period tooth models of :func:`per_tooth_model` with pinion tooth ``i`` standing
    ``positions_m[i]`` [m] ahead of its theoretical place along the line of action (behind
    where negative): its drive flank meets the mate earlier, so every gap of its pair (on the
    path and off it, wherever the tooth stands in the mesh sequence) is smaller by that much,
    as worn material makes it larger. Gaps of pairs out of reach stay so.

    ``teeth`` must be a sequence of :class:`PairModel` and ``positions_m`` a one-dimensional
    sequence of finite real numbers [m], one per tooth model, each within twice the cumulative
    pitch tolerance ``F_p`` of the coarsest ISO 1328-1 grade for the pinion
    (:data:`POSITION_BOUND_FP`; 0.32 mm for the thesis pinion): positions in um, such as
    :func:`physics.gear.accuracy.tooth_positions_um` gives, are scaled by ``1e-6`` first.
    Anything else is refused before any work."""
    teeth = _tooth_models(teeth)
    positions = _positions_m(positions_m, teeth)
    if len(positions) != len(teeth):
        raise ValueError(f"{len(positions)} tooth positions for {len(teeth)} tooth models; "
                         "give one per tooth model")

    def moved(g: np.ndarray | None, d: float) -> np.ndarray | None:
        return None if g is None else np.where(g < NO_CONTACT, g - d, g)

    return [dataclasses.replace(m, g_a=moved(m.g_a, d), g_b=moved(m.g_b, d),
                                g_off=moved(m.g_off, d))
            for m, d in zip(teeth, (float(x) for x in positions), strict=True)]


def _positions_m(positions_m: Any, teeth: list[PairModel]) -> np.ndarray:
    """``positions_m`` as a float array when it is a one-dimensional sequence of finite real
    numbers [m] within the bound of :data:`POSITION_BOUND_FP`; otherwise ``TypeError`` (no
    sequence of numbers) or ``ValueError``, naming the argument, the value, the rule and the
    fix."""
    what = "must be a 1-D sequence of finite numbers [m], one per tooth model"
    fix = "give one position per tooth model in metres"
    if positions_m is None or isinstance(positions_m, str | bytes | dict | set):
        raise TypeError(f"positions_m = {_shown(positions_m)} "
                        f"({type(positions_m).__name__}) {what}; {fix}")
    try:
        x = np.asarray(positions_m)
    except (TypeError, ValueError) as e:  # ragged nesting
        raise TypeError(f"positions_m = {_shown(positions_m)} {what}; {fix}") from e
    if x.ndim == 0:
        raise TypeError(f"positions_m = {_shown(positions_m)} is a single value: it {what}; "
                        f"{fix}")
    if x.ndim != 1:
        raise ValueError(f"positions_m = {_shown(positions_m)} has shape {x.shape}: it {what}; "
                         f"{fix}")
    if x.dtype.kind not in "iuf":
        raise TypeError(f"positions_m = {_shown(positions_m)} holds {x.dtype} values: it "
                        f"{what} (not bools, text or None); {fix}")
    x = x.astype(float)
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        raise ValueError(f"positions_m[{bad[0]}] = {float(x[bad[0]])!r}: positions_m {what}; "
                         f"{fix}")
    g = teeth[0].geometry.gear
    limit = position_bound_m(g.module_mm, g.module_mm * g.z1)
    worst = int(np.argmax(np.abs(x)))
    if abs(x[worst]) > limit:
        raise ValueError(
            f"positions_m[{worst}] = {x[worst]:g} m lies beyond +-{limit:.3g} m, "
            f"{POSITION_BOUND_FP:g} x the cumulative pitch tolerance F_p of ISO 1328-1's "
            "coarsest grade (12) for this pinion; give the positions in metres "
            "(1e-6 x the um of tooth_positions_um)")
    return x

