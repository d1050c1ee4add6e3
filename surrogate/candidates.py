"""The models a run compares with the network on a user's table, and how it chooses.

Candidates (:data:`KINDS`), each fitted so that what users judge, the relative error, is what
it minimises: every training row weighs ``1 / (rows of its group)`` (a group of 250 healthy
records counts as one group) times ``1 / max(y, y_least)``, ``y_least`` the least nonzero
training wear (a zero wear, whose relative error is undefined, is read relative to the least
worn stage), with an absolute-error loss where the learner has one (:func:`relative_weights`):
sample weights, not a log target, so that the loss is the relative error itself.

- ``linear``: scikit-learn's ``QuantileRegressor`` (the median, no penalty, ``highs``): the
  weighted absolute error, i.e. the group-weighted mean relative error, minimised exactly. A
  measured feature that is positive in every training row (an RMS, an energy, a peak-to-peak
  value) enters as its logarithm, its level (:func:`level_columns`): vibration severity is read
  by ratios (levels in dB), and a feature that grows exponentially as a part degrades is
  linear in its logarithm (Gebraeel, Lawley, Li & Ryan, IIE Trans. 37 (2005) 543). The
  operating point (:data:`surrogate.inputs.CONDITIONS`) and any feature that reaches zero or
  below enter as given;
- ``monotone``: one input, ``IsotonicRegression`` (direction of the training rows' Spearman
  correlation; squared loss, so the weights are squared: the relative squared error); several,
  ``HistGradientBoostingRegressor(loss="absolute_error", monotonic_cst=...)``, each input's
  direction its Spearman correlation's sign (trees do not depend on a monotone transform of
  an input, so levels change nothing here);
- ``average``: the mean of the linear and the monotone models' readings, with equal weights
  (a combination of forecasts: Bates & Granger, Oper. Res. Q. 20 (1969) 451; equal weights,
  which estimate nothing, are hard to beat: Clemen, Int. J. Forecast. 5 (1989) 559). Where the
  two read different stages well, their mean reads most stages near the better one; where
  cross-validation over a few dozen groups cannot tell them apart, the choice between them
  follows which group is held out, and the mean does not (docs/surrogate.md, The real rig);
- ``estimator``: the thesis's (4.4, :class:`physics.estimators.empirical_inverse.EmpiricalInverse`)
  where the inputs hold DTE peak-to-peak and kurtosis and the rows a cycle count (its own
  least-squares fit);
- ``network``: the deep ensemble (trained by :mod:`surrogate.training`; its Gaussian likelihood
  is not reweighted).

:func:`group_folds` splits the training groups with scikit-learn's ``GroupKFold``;
:func:`choose` keeps the kind of the least cross-validated error (:func:`group_error`: each
worn group's mean relative error, averaged over the groups; a tie to the simpler). The
average's cross-validation is its members' (:func:`averaged`: the same folds, the mean of
their out-of-fold readings), not a second fit. A fitted candidate is written without pickle
(:meth:`Candidate.payload`: arrays and numbers; the boosted trees as their node arrays,
walked by :func:`_walk`), so that ``torch.load(weights_only=True)`` reads it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from physics.estimators.empirical_inverse import EmpiricalInverse
from surrogate.conformal import unit_weights
from surrogate.inputs import CONDITIONS

#: the kinds a run compares, in the order reports list them; ``model.kind`` forces one
KINDS = ("network", "linear", "monotone", "average", "estimator")
#: the order a tie of cross-validated errors is broken in
SIMPLEST_FIRST = ("linear", "monotone", "average", "estimator", "network")
#: the kinds the ``average`` takes the mean of, with equal weights
AVERAGED = ("linear", "monotone")
#: how logs and plots name them
LABELS = {"network": "network", "linear": "linear model", "monotone": "monotone model",
          "average": "average of the linear and monotone models",
          "estimator": "thesis estimator", "median": "median (null model)"}
#: the estimator's inputs (it reads a cycle count from the rows when fitted)
ESTIMATOR_INPUTS = ("dte_peak_to_peak", "dte_kurtosis")
#: inner cross-validation folds over the training groups (``GroupKFold``)
FOLDS = 5


def relative_weights(y: np.ndarray, groups: np.ndarray, power: int = 1) -> np.ndarray:
    """Each row's weight in a fit that minimises the group-weighted relative error (module
    text): ``1 / (rows of its group) / max(y, least nonzero y) ** power`` (``power`` 2 for a
    squared loss), normalised to a mean of 1."""
    y = np.asarray(y, float)
    worn = y[y > 0]
    least = float(worn.min()) if worn.size else 1.0
    w = unit_weights(len(y), groups) / np.maximum(y, least) ** power  # each group once
    return w / w.mean()


def group_error(pred: np.ndarray, true: np.ndarray, groups: np.ndarray) -> float:
    """The figure candidates are chosen by: each group's mean relative error [%] over its rows
    of nonzero wear, averaged over the groups that have such rows (each group once, the
    relative error of zero wear undefined, as in :func:`~physics.estimators.empirical_inverse.
    wear_errors`); the RMSE where no row is worn."""
    pred, true = np.asarray(pred, float), np.asarray(true, float)
    nz = true != 0
    if not nz.any():
        return float(np.sqrt(np.mean((pred - true) ** 2)))
    rel = pd.Series(np.abs(pred[nz] - true[nz]) / true[nz] * 100)
    return float(rel.groupby(np.asarray(groups)[nz]).mean().mean())


def group_folds(groups: np.ndarray, folds: int = FOLDS) -> list[tuple[np.ndarray, np.ndarray]]:
    """``GroupKFold`` of the rows by ``groups`` (at most one fold per group)."""
    from sklearn.model_selection import GroupKFold

    n = np.unique(groups).size
    if n < 2:
        raise ValueError(f"{n} training group(s): cross-validation needs two or more")
    return list(GroupKFold(n_splits=min(folds, n)).split(np.zeros(len(groups)),
                                                           groups=groups))


def level_columns(raw: np.ndarray | None, inputs: list[str] | None) -> np.ndarray:
    """The columns of the unscaled training rows ``raw`` the linear model reads as logarithms
    (module text): measured features (not :data:`~surrogate.inputs.CONDITIONS`) positive in
    every row. None of them without ``raw`` or ``inputs``."""
    if raw is None or inputs is None:
        return np.zeros(0, np.int64)
    raw = np.asarray(raw, float)
    return np.asarray([j for j, name in enumerate(inputs)
                       if name not in CONDITIONS and bool(np.all(raw[:, j] > 0))], np.int64)


def _linear_rows(p: dict, x: np.ndarray, raw: np.ndarray | None) -> np.ndarray:
    """The linear model's inputs of standardised rows ``x``: its level columns replaced by
    their standardised logarithms of the unscaled rows ``raw`` (a value below the least
    training value read as that value: the logarithm of zero is not a number)."""
    cols = np.asarray(p.get("levels", np.zeros(0)), np.int64)
    if cols.size == 0:
        return x
    if raw is None:
        raise ValueError("this linear model reads some inputs as logarithms: it needs the "
                         "unscaled rows")
    out = np.array(x, float, copy=True)
    logs = np.log(np.maximum(np.asarray(raw, float)[:, cols], np.asarray(p["floor"], float)))
    out[:, cols] = (logs - np.asarray(p["log_shift"], float)) / np.asarray(p["log_scale"], float)
    return out


def _directions(x: np.ndarray, y: np.ndarray) -> list[int]:
    from scipy.stats import spearmanr  # imported on first use: a prediction need not wait for it

    out = []
    for j in range(x.shape[1]):
        rho = spearmanr(x[:, j], y).statistic if np.ptp(x[:, j]) > 0 else 0.0
        out.append(-1 if np.isfinite(rho) and rho < 0 else 1)
    return out


def _walk(nodes: dict[str, np.ndarray], x: np.ndarray) -> np.ndarray:
    """The leaf value each row of ``x`` reaches in one tree of node arrays (a numeric split
    sends ``x <= threshold`` left, as scikit-learn's predictor does for finite values)."""
    at = np.zeros(len(x), int)
    leaf = nodes["is_leaf"].astype(bool)
    while True:
        open_ = ~leaf[at]
        if not open_.any():
            return nodes["value"][at]
        rows = np.flatnonzero(open_)
        n = at[rows]
        left = x[rows, nodes["feature_idx"][n]] <= nodes["num_threshold"][n]
        at[rows] = np.where(left, nodes["left"][n], nodes["right"][n])


@dataclass
class Candidate:
    """One fitted candidate of ``kind`` on standardised inputs: ``params`` its arrays and
    numbers (:meth:`payload`)."""

    kind: str
    params: dict

    @classmethod
    def fit(cls, kind: str, x: np.ndarray, y: np.ndarray, groups: np.ndarray,
            rows: pd.DataFrame | None = None, inputs: list[str] | None = None,
            raw: np.ndarray | None = None) -> Candidate:
        """Fit ``kind`` (not the network) on standardised ``x`` and wear ``y`` (module text);
        ``rows`` and ``inputs`` give the estimator its cycle count and columns, ``raw`` (the
        rows unscaled) and ``inputs`` the linear model its levels (:func:`level_columns`)."""
        x, y = np.asarray(x, float), np.asarray(y, float)
        w = relative_weights(y, groups)
        if kind == "linear":
            from sklearn.linear_model import QuantileRegressor

            cols = level_columns(raw, inputs)
            p = {}
            if cols.size:
                logs = np.log(np.asarray(raw, float)[:, cols])
                spread = logs.std(axis=0)
                p = {"levels": cols, "floor": np.asarray(raw, float)[:, cols].min(axis=0),
                     "log_shift": logs.mean(axis=0),
                     "log_scale": np.where(spread > 0, spread, 1.0)}
            m = QuantileRegressor(quantile=0.5, alpha=0.0, solver="highs")
            m.fit(_linear_rows(p, x, raw), y, sample_weight=w)
            return cls(kind, {"coef": m.coef_.astype(float), "intercept": float(m.intercept_),
                              **p})
        if kind == "average":
            return cls.average([cls.fit(k, x, y, groups, rows, inputs, raw) for k in AVERAGED])
        if kind == "monotone" and x.shape[1] == 1:
            from sklearn.isotonic import IsotonicRegression

            up = _directions(x, y)[0] > 0
            m = IsotonicRegression(increasing=up, out_of_bounds="clip").fit(
                x[:, 0], y, sample_weight=relative_weights(y, groups, 2))
            return cls(kind, {"x": m.X_thresholds_.astype(float),
                              "y": m.y_thresholds_.astype(float)})
        if kind == "monotone":
            from sklearn.ensemble import HistGradientBoostingRegressor

            m = HistGradientBoostingRegressor(loss="absolute_error", min_samples_leaf=5,
                                              monotonic_cst=_directions(x, y), random_state=0)
            with threadpool_limits(1):  # OpenMP on a shared machine: one thread is fastest
                m.fit(x, y, sample_weight=w)
            fields = ("value", "feature_idx", "num_threshold", "left", "right", "is_leaf")
            trees = [{f: np.asarray(p.nodes[f]).astype(float if f in ("value", "num_threshold")
                                                        else np.int64) for f in fields}
                     for it in m._predictors for p in it]
            return cls(kind, {"baseline": float(np.ravel(m._baseline_prediction)[0]),
                              "trees": trees})
        if kind == "estimator":
            need = [inputs.index(c) for c in ESTIMATOR_INPUTS]
            measured = rows[list(ESTIMATOR_INPUTS)].to_numpy(float)
            est = EmpiricalInverse.fit(rows.cycles.to_numpy(float), measured[:, 0],
                                       measured[:, 1], y)
            return cls(kind, {"columns": np.asarray(need, np.int64),
                              "p2p_cubic": est.p2p_cubic, "kurtosis_cubic": est.kurtosis_cubic,
                              "wear_law": est.wear_law, "cycles_max": est.cycles_max,
                              "cycles_unit": est.cycles_unit, "p2p_tol": est.p2p_tol,
                              "kurtosis_tol": est.kurtosis_tol})
        raise ValueError(f"model.kind = {kind!r}: no such candidate; choose from {KINDS}")

    @classmethod
    def average(cls, members: list[Candidate]) -> Candidate:
        """The equal-weight mean of fitted ``members`` (the ``average`` kind)."""
        return cls("average", {"members": [{"kind": m.kind, "params": m.params}
                                           for m in members]})

    def predict(self, x: np.ndarray, raw: np.ndarray | None = None) -> np.ndarray:
        """The wear of standardised rows ``x`` (``raw``: the same unscaled, which the
        estimator and the linear model's levels read), clipped at zero."""
        p, x = self.params, np.asarray(x, float)
        if self.kind == "linear":
            out = p["intercept"] + _linear_rows(p, x, raw) @ np.asarray(p["coef"], float)
        elif self.kind == "average":
            out = np.mean([Candidate(m["kind"], m["params"]).predict(x, raw)
                           for m in p["members"]], axis=0)
        elif self.kind == "monotone" and "x" in p:
            out = np.interp(x[:, 0], p["x"], p["y"])
        elif self.kind == "monotone":
            out = p["baseline"] + sum(_walk(t, x) for t in p["trees"])
        else:
            est = EmpiricalInverse(*(np.asarray(p[k], float) for k in
                                     ("p2p_cubic", "kurtosis_cubic", "wear_law")),
                                   float(p["cycles_max"]), float(p["cycles_unit"]),
                                   float(p["p2p_tol"]), float(p["kurtosis_tol"]))
            cols = np.asarray(p["columns"], int)
            out = est.predict(raw[:, cols[0]], raw[:, cols[1]]).wear
        return np.maximum(np.asarray(out, float), 0.0)

    def payload(self) -> dict:
        """Plain values and arrays (``torch.load(weights_only=True)`` reads them back)."""
        import torch

        def plain(v):
            if isinstance(v, np.ndarray):
                return torch.as_tensor(v)
            if isinstance(v, dict):
                return {k: plain(u) for k, u in v.items()}
            if isinstance(v, list):
                return [plain(u) for u in v]
            return v

        return {"kind": self.kind, "params": plain(self.params)}

    @classmethod
    def from_payload(cls, d: dict) -> Candidate:
        def arrays(v):
            if hasattr(v, "numpy"):
                return v.numpy()
            if isinstance(v, dict):
                return {k: arrays(u) for k, u in v.items()}
            if isinstance(v, list):
                return [arrays(u) for u in v]
            return v

        if d.get("kind") not in KINDS[1:]:
            raise ValueError(f"unknown model kind {d.get('kind')!r}")
        return cls(d["kind"], arrays(d["params"]))


def applicable(inputs: list[str], rows: pd.DataFrame) -> dict[str, str]:
    """Why each non-network kind cannot be fitted on ``rows`` (absent where it can)."""
    why = {}
    if not set(ESTIMATOR_INPUTS) <= set(inputs):
        why["estimator"] = f"the inputs lack {[c for c in ESTIMATOR_INPUTS if c not in inputs]}"
    elif "cycles" not in rows.columns or not np.isfinite(rows.cycles.to_numpy(float)).all():
        why["estimator"] = "the training rows lack a cycle count"
    return why


@dataclass
class CrossValidated:
    """A kind's cross-validation over the training groups: its fold models (None for the
    network), each row's fold and out-of-fold reading, and its error (:func:`group_error`)."""

    kind: str
    fold_models: list[Candidate] | None
    fold_of: np.ndarray
    oof: np.ndarray
    error: float


def cross_validate(kind: str, x: np.ndarray, y: np.ndarray, groups: np.ndarray,
                   folds: list[tuple[np.ndarray, np.ndarray]], rows: pd.DataFrame | None = None,
                   inputs: list[str] | None = None, raw: np.ndarray | None = None,
                   network=None) -> CrossValidated:
    """``kind`` fitted on each fold's training rows and read on its held rows; ``network``
    (for the network) maps (training row indices, held row indices) to the held readings."""
    oof, fold_of, models = np.full(len(y), np.nan), np.full(len(y), -1), []
    for k, (fit_rows, held) in enumerate(folds):
        fold_of[held] = k
        if kind == "network":
            oof[held] = network(fit_rows, held)
            continue
        m = Candidate.fit(kind, x[fit_rows], y[fit_rows], groups[fit_rows],
                          None if rows is None else rows.iloc[fit_rows], inputs,
                          None if raw is None else raw[fit_rows])
        models.append(m)
        oof[held] = m.predict(x[held], None if raw is None else raw[held])
    return CrossValidated(kind, None if kind == "network" else models, fold_of, oof,
                          group_error(oof, y, groups))


def averaged(scored: dict[str, CrossValidated], y: np.ndarray, groups: np.ndarray
             ) -> CrossValidated:
    """The ``average``'s cross-validation from its members' (:data:`AVERAGED`, cross-validated
    over the same folds): each fold's members averaged, the mean of their out-of-fold
    readings, and its error (:func:`group_error`)."""
    parts = [scored[k] for k in AVERAGED]
    if any(not np.array_equal(parts[0].fold_of, c.fold_of) for c in parts[1:]):
        raise ValueError("the average's members were cross-validated over different folds")
    models = [Candidate.average(list(ms))
              for ms in zip(*(c.fold_models for c in parts), strict=True)]
    oof = np.mean([c.oof for c in parts], axis=0)
    return CrossValidated("average", models, parts[0].fold_of, oof, group_error(oof, y, groups))


def choose(scored: dict[str, CrossValidated], forced: str | None = None) -> tuple[str, str]:
    """The kind kept and why: ``forced`` (``model.kind``) where given, else the least
    cross-validated error (a tie goes to the simpler: :data:`SIMPLEST_FIRST`)."""
    shown = ", ".join(f"{LABELS[k]} {c.error:.3g}" for k, c in scored.items())
    if forced and forced != "auto":
        return forced, f"model.kind={forced} (cross-validated over the training groups: {shown})"
    simple = sorted(scored, key=lambda k: (round(scored[k].error, 9), SIMPLEST_FIRST.index(k)))
    best = simple[0]
    return best, (f"least cross-validated error over the training groups ({shown}; "
                  "group-mean relative error [%], RMSE where no row is worn)")
