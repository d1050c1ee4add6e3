"""The conformal quantile of scores from exchangeable rows or from exchangeable gearboxes.

Both the interval's scale (:func:`surrogate.inference.conformal_scale`) and the novelty flag's
radius (:meth:`surrogate.novelty.Novelty.fit`) are a quantile of scores of held-out rows that a
new row's score must exceed with probability at most ``1 - level``, on average over the draw
of the held-out rows:

- rows exchangeable one by one: the ``ceil((n + 1) level) / n`` empirical quantile (split
  conformal; Angelopoulos & Bates, "A gentle introduction to conformal prediction", 2021,
  sec. 2.3);
- rows in ``groups`` (a gearbox's readings, which vary together): the gearboxes are the
  exchangeable units, so each of the ``K`` gets mass ``1 / (K + 1)`` spread evenly over its
  rows and the new gearbox's ``1 / (K + 1)`` sits at infinity; the ``level`` quantile of that
  mixture bounds a random row of a new gearbox with probability at least ``level`` (CDF
  pooling of Dunn, Wasserman & Ramdas, JASA 118 (2023) 2491, with the finite-sample term of
  exchangeable groups: Lee, Barber & Willett, arXiv:2306.06342).

Rows one by one are groups of one row each: one computation serves both. Where ``level``
exceeds what the units can give (``K / (K + 1)``: :func:`attainable`), the largest score.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: relative slack of the cumulative weight against the level (float round-off of the sums)
SLACK = 1e-12


def attainable(level: float, units: int) -> bool:
    """Whether ``units`` exchangeable held-out units (gearboxes, or rows one by one) give a
    quantile at ``level``: the new unit's ``1 / (units + 1)`` at infinity leaves at most
    ``units / (units + 1)`` below it."""
    return units / (units + 1) >= level * (1 - SLACK)


def exchangeable_quantile(scores: np.ndarray, level: float,
                          groups: np.ndarray | None = None) -> float:
    """The conformal ``level`` quantile of ``scores`` (module text); ``groups`` labels each
    score's gearbox (any hashable labels; None: every row its own)."""
    scores = np.asarray(scores, float)
    if scores.ndim != 1 or scores.size == 0:
        raise ValueError("the held-out scores must be a non-empty 1-D array")
    if not np.isfinite(scores).all():
        raise ValueError(f"{int((~np.isfinite(scores)).sum())} held-out scores are not finite")
    if not 0 < level < 1:
        raise ValueError(f"level = {level!r} must lie in (0, 1)")
    n = scores.size
    if groups is None:
        of_row = np.arange(n)
    else:
        labels = pd.Series(list(groups))
        if len(labels) != n:
            raise ValueError(f"{len(labels)} group labels for {n} scores")
        of_row, _ = pd.factorize(labels, use_na_sentinel=False)
    sizes = np.bincount(of_row)
    order = np.argsort(scores, kind="stable")
    weight = 1.0 / ((len(sizes) + 1) * sizes[of_row])
    reached = np.cumsum(weight[order]) >= level * (1 - SLACK)
    return float(scores[order][int(np.argmax(reached)) if reached.any() else n - 1])
