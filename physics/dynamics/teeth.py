"""Each pinion tooth its own flank, over one pinion revolution (the mesh sequence).

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

The gear's teeth are alike here (a gear tooth's own wear would need the hunting period,
``lcm(z1, z2)`` mesh periods).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from physics.dynamics.model import PairModel
from physics.gear.tooth_contact import NO_CONTACT


def per_tooth_model(teeth: Sequence[PairModel]) -> PairModel:
    """The revolution model whose pinion tooth ``i`` is ``teeth[i]``'s (one-period models of the
    same pair and operating point, one per pinion tooth, in mesh order; module doc). Damping,
    inertias, errors and the other scalars are the first tooth's."""
    z1 = len(teeth)
    first = teeth[0]
    z = round(first.omega_mesh / first.omega1)
    if z1 != z:
        raise ValueError(f"{z1} tooth models for a pinion of {z} teeth; give one per pinion tooth")
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


def with_tooth_positions(teeth: Sequence[PairModel], positions_m: Sequence[float]
                         ) -> list[PairModel]:
    """The one-period tooth models of :func:`per_tooth_model` with pinion tooth ``i`` standing
    ``positions_m[i]`` [m] ahead of its theoretical place along the line of action (behind
    where negative): its drive flank meets the mate earlier, so every gap of its pair (on the
    path and off it, wherever the tooth stands in the mesh sequence) is smaller by that much,
    as worn material makes it larger. Gaps of pairs out of reach stay so."""
    if len(positions_m) != len(teeth):
        raise ValueError(f"{len(positions_m)} tooth positions for {len(teeth)} tooth models; "
                         "give one per pinion tooth")

    def moved(g: np.ndarray | None, d: float) -> np.ndarray | None:
        return None if g is None else np.where(g < NO_CONTACT, g - d, g)

    return [dataclasses.replace(m, g_a=moved(m.g_a, d), g_b=moved(m.g_b, d),
                                g_off=moved(m.g_off, d))
            for m, d in zip(teeth, (float(x) for x in positions_m), strict=True)]

