"""The conformal quantile of scores from exchangeable rows or from exchangeable gearboxes.

Both the interval's scale (:func:`surrogate.inference.conformal_scale`) and the novelty flag's
radius (:meth:`surrogate.novelty.Novelty.fit`) are a quantile of scores of held-out rows that a
new row's score must exceed with probability at most ``1 - level``:

- rows exchangeable one by one: the ``ceil((n + 1) level) / n`` empirical quantile (split
  conformal; Angelopoulos & Bates, "A gentle introduction to conformal prediction", 2021,
  sec. 2.3);
- rows in ``groups`` (a gearbox's readings, which vary together): the gearboxes are the
  exchangeable units, so each of the ``K`` gets mass ``1 / (K + 1)`` spread evenly over its
  rows and the new gearbox's ``1 / (K + 1)`` sits at infinity; the ``level`` quantile of that
  mixture bounds a random row of a new gearbox with probability at least ``level`` (CDF
  pooling of Dunn, Wasserman & Ramdas, JASA 118 (2023) 2491, with the finite-sample term of
  exchangeable groups: Lee, Barber & Willett, arXiv:2306.06342).

Where ``level`` exceeds what the rows can give (``K / (K + 1)``, or ``n / (n + 1)``), the
largest score.
"""

from __future__ import annotations

import math

import numpy as np


def exchangeable_quantile(scores: np.ndarray, level: float,
                          groups: np.ndarray | None = None) -> float:
    """The conformal ``level`` quantile of ``scores`` (module text); ``groups`` labels each
    score's gearbox (None: every row its own)."""
    scores = np.asarray(scores, float).ravel()
    n = scores.size
    if n == 0:
        raise ValueError("no held-out rows to take a conformal quantile of")
    if not 0 < level < 1:
        raise ValueError(f"level = {level!r} must lie in (0, 1)")
    order = np.argsort(scores, kind="stable")
    if groups is None:
        return float(scores[order][min(math.ceil((n + 1) * level), n) - 1])
    groups = np.asarray(groups).ravel()
    if groups.size != n:
        raise ValueError(f"{groups.size} group labels for {n} scores")
    _, of_row, sizes = np.unique(groups, return_inverse=True, return_counts=True)
    weight = 1.0 / ((len(sizes) + 1) * sizes[of_row])
    reached = np.cumsum(weight[order]) >= level * (1 - 1e-12)
    return float(scores[order][int(np.argmax(reached)) if reached.any() else n - 1])
