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

:func:`cv_plus` is the interval of CV+ (Barber, Candes, Ramdas & Tibshirani, "Predictive
inference with the jackknife+", Ann. Statist. 49 (2021) 486, sec. 2.3 and 3) with the same
weights: each held-out row ``i`` of cross-validation fold ``k(i)`` gives ``mu_-k(i)(x) - R_i``
and ``mu_-k(i)(x) + R_i``, ``R_i`` its out-of-fold residual, and the bounds are the weighted
``level`` quantiles of those values from below and above, each group (a wear stage, a
gearbox) weighing ``1 / (K + 1)`` however many rows it holds. MAPIE's ``CrossConformalRegressor``
splits by group but weighs every row alike (its documentation: "conformity scores are still
uniformly weighted"), so a group of 250 rows would count 250 times.
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


def unit_weights(n: int, groups: np.ndarray | None = None) -> np.ndarray:
    """Each of ``n`` held-out rows' weight: ``1 / ((K + 1) rows of its group)`` for ``K``
    groups (``groups`` None: every row its own), so that each group sums to ``1 / (K + 1)``."""
    if groups is None:
        of_row = np.arange(n)
    else:
        labels = pd.Series(list(groups))
        if len(labels) != n:
            raise ValueError(f"{len(labels)} group labels for {n} scores")
        of_row, _ = pd.factorize(labels, use_na_sentinel=False)
    sizes = np.bincount(of_row)
    return 1.0 / ((len(sizes) + 1) * sizes[of_row])


def exchangeable_quantile(scores: np.ndarray, level: float,
                          groups: np.ndarray | None = None) -> float | np.ndarray:
    """The conformal ``level`` quantile of ``scores`` (module text); ``groups`` labels each
    score's gearbox (any hashable labels; None: every row its own). ``scores`` of shape
    ``(m, n)``: the quantile of each of the ``m`` rows over the same ``n`` held-out units."""
    scores = np.asarray(scores, float)
    if scores.ndim not in (1, 2) or scores.size == 0:
        raise ValueError("the held-out scores must be a non-empty 1-D (or 2-D) array")
    if not np.isfinite(scores).all():
        raise ValueError(f"{int((~np.isfinite(scores)).sum())} held-out scores are not finite")
    if not 0 < level < 1:
        raise ValueError(f"level = {level!r} must lie in (0, 1)")
    n = scores.shape[-1]
    weight = unit_weights(n, groups)
    flat = scores.reshape(-1, n)
    order = np.argsort(flat, axis=1, kind="stable")
    reached = np.cumsum(weight[order], axis=1) >= level * (1 - SLACK)
    at = np.where(reached.any(axis=1), np.argmax(reached, axis=1), n - 1)
    value = np.take_along_axis(flat, order, axis=1)[np.arange(len(flat)), at]
    return float(value[0]) if scores.ndim == 1 else value


def cv_plus(fold_means: np.ndarray, fold_of: np.ndarray, residuals: np.ndarray, level: float,
            groups: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The CV+ interval (module text) of ``m`` new rows: ``fold_means`` ``(m, K)`` each fold
    model's reading of them, ``fold_of`` the fold of each of the ``n`` held-out rows,
    ``residuals`` their out-of-fold ``|y - mu_-k(x)|``, ``groups`` their groups. Returns the
    lower and upper bounds (``level`` quantiles of ``mu - R`` from below, ``mu + R`` from
    above)."""
    means = np.asarray(fold_means, float)[:, np.asarray(fold_of, int)]  # (m, n)
    r = np.asarray(residuals, float)[None, :]
    upper = exchangeable_quantile(means + r, level, groups)
    lower = -exchangeable_quantile(-(means - r), level, groups)
    return np.atleast_1d(lower), np.atleast_1d(upper)
