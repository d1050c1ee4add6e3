"""The models every run scores beside the one it keeps, on the same test rows and target.

- the **null model** (:func:`typical_wear`): the training rows' median wear, whatever the
  features say; a model that does not beat it has learnt nothing from vibration;
- the thesis's **estimator** (:func:`fit_estimator`, thesis 4.4,
  :class:`physics.estimators.empirical_inverse.EmpiricalInverse`) where its inputs exist in
  the rows: DTE peak-to-peak and kurtosis, and a cycle count in the training rows;
- the linear and monotone models of the same inputs and their average
  (:mod:`surrogate.candidates`, which also fits them as candidates).

Each reading is clipped at zero wear.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from physics.estimators.empirical_inverse import EmpiricalInverse, wear_errors
from surrogate import candidates

#: the models scored beside the one kept, in the order reports list them
NAMES = ("network", "linear", "monotone", "average", "estimator", "median")
#: how the log and the plot name them
LABELS = {**candidates.LABELS, "kept": "model kept"}


def typical_wear(train: pd.DataFrame, target: str) -> float:
    """The null model: the median wear (``target``) of the training rows' worn states (of all
    rows where none is worn), whatever the features say."""
    worn = train.loc[train[target] > 0, target]
    return float((worn if len(worn) else train[target]).median())


def fit_estimator(train: pd.DataFrame, target: str) -> EmpiricalInverse:
    """The thesis's estimator of ``target`` fitted on the training rows (cycles, DTE
    peak-to-peak and kurtosis)."""
    return EmpiricalInverse.fit(train.cycles.to_numpy(), train.dte_peak_to_peak.to_numpy(),
                                train.dte_kurtosis.to_numpy(), train[target].to_numpy())


def estimator_missing(train: pd.DataFrame) -> str | None:
    """Why the estimator cannot be fitted on ``train`` (None where it can)."""
    need = ["cycles", "dte_peak_to_peak", "dte_kurtosis"]
    absent = [c for c in need if c not in train.columns]
    if absent:
        return f"the rows lack {absent}"
    if not np.isfinite(train[need].to_numpy(float)).all():
        return "a cycle count or DTE feature is not given in every training row"
    if len(train) < 6:
        return "fewer than 6 training rows"
    return None


def baseline_readings(train_raw: pd.DataFrame, test_raw: pd.DataFrame, target: str
                      ) -> tuple[dict[str, np.ndarray], str | None]:
    """The median's and the estimator's readings of the test rows, fitted on the training rows
    as measured. Returns the readings (the estimator's only where :func:`estimator_missing`
    finds nothing missing and its fit succeeds) and why the estimator is absent."""
    out = {"median": np.full(len(test_raw), typical_wear(train_raw, target))}
    why = estimator_missing(train_raw)
    dte = list(("dte_peak_to_peak", "dte_kurtosis"))
    if why is None and not (set(dte) <= set(test_raw.columns)
                            and np.isfinite(test_raw[dte].to_numpy(float)).all()):
        why = "a test row lacks a DTE feature"
    if why is None:
        try:
            est = fit_estimator(train_raw, target)
            out["estimator"] = est.predict(test_raw.dte_peak_to_peak.to_numpy(float),
                                           test_raw.dte_kurtosis.to_numpy(float)).wear
        except (ValueError, RuntimeError, np.linalg.LinAlgError) as err:
            why = f"its fit failed ({err})"
    return out, why


def headline(errors: dict[str, float]) -> tuple[str, float]:
    """The figure runs are compared by: the mean relative error [%], or the RMSE where no row
    has nonzero wear."""
    mre = errors.get("mean_relative_error_pct", float("nan"))
    return ("mean_relative_error_pct", mre) if np.isfinite(mre) else ("rmse", errors["rmse"])


def shown(key: str, value: float) -> str:
    return f"{value:.3g} %" if key.endswith("_pct") else f"{value:.3g}"


def not_better_line(network: dict[str, float], linear: dict[str, float]) -> str | None:
    """The one line a run prints when the network is not better than the linear model of
    the same inputs on the same rows (None when it is better); where the run kept another
    model, the line says so (:func:`surrogate.training.report_test`)."""
    key, net = headline(network)
    lin = linear.get(key, float("nan"))
    if not (np.isfinite(net) and np.isfinite(lin)) or net < lin:
        return None
    return (f"the network ({shown(key, net)}) is not better than a linear model of the same "
            f"inputs ({shown(key, lin)}) on these test rows")


def scored(readings: dict[str, np.ndarray], true: np.ndarray) -> dict[str, dict[str, float]]:
    """:func:`wear_errors` of each reading against the true wear."""
    return {name: wear_errors(r, true) for name, r in readings.items()}
