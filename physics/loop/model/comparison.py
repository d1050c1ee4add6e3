"""Residuals of the model's records against the measured ones: the signature of
:mod:`physics.signals.order_analysis` (mesh harmonics with pinion and gear sidebands up to
0.45 fs, half-octave bands, statistics, synchronous-average kurtosis, all in dB) of measurement
minus model, per entry, standardised by the group's scatter
(:attr:`physics.loop.measured.records.Group.sd`: noise and model discrepancy, or the noise alone);
their RMS per group, and the Table 13 features' relative error."""

from __future__ import annotations

import numpy as np

from physics.loop.measured.records import Records, by_group, shaft_rates
from physics.signals.features import FEATURES, features
from physics.signals.order_analysis import mean_signatures


def residuals_db(rec: Records, idx: np.ndarray, signals: list[np.ndarray]
                 ) -> list[np.ndarray]:
    """Measured minus model signature of each of records ``idx`` (its group's entries) [dB];
    the records of one operating point, quantity and sampling rate analysed in one batch."""
    man = rec.bundle.manifest
    fs, dte = man.fs_hz.to_numpy(float), man.quantity.to_numpy() == "dte_m"
    batches: dict[tuple, list[int]] = {}
    for k, i in enumerate(idx):
        scn = rec.scenarios[i]
        key = (float(fs[i]), *shaft_rates(scn), scn.gear.z1, bool(dte[i]))
        batches.setdefault(key, []).append(k)
    res: list[np.ndarray] = [np.empty(0)] * len(idx)
    for key, ks in batches.items():
        sig = mean_signatures([signals[k] for k in ks], *key, rec.settings.segment_s)
        for k, s in zip(ks, sig, strict=True):
            res[k] = rec.measured[idx[k]] - s
    return res


def standardised(rec: Records, idx: np.ndarray, signals: list[np.ndarray],
                 discrepancy: bool = True) -> list[np.ndarray]:
    """Each record's dB residual over its group's noise and discrepancy
    (:attr:`~physics.loop.measured.records.Group.sd`), or over the noise alone
    (``Group.entry_sd``)."""
    return [r / (rec.group(i).sd if discrepancy else rec.group(i).entry_sd)
            for r, i in zip(residuals_db(rec, idx, signals), idx, strict=True)]


def residuals(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> np.ndarray:
    """Standardised residuals of records ``idx``, concatenated (groups of different lengths)."""
    return np.concatenate(standardised(rec, idx, signals))


def noise_only(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> float:
    """RMS residual of records ``idx`` in units of the noise alone (no discrepancy)."""
    return rms(np.concatenate(standardised(rec, idx, signals, discrepancy=False)))


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x**2)))


def feature_error(rec: Records, idx: np.ndarray, signals: list[np.ndarray]) -> float:
    """Mean relative error of the Table 13 features, model against measurement [%]."""
    errs = []
    for k, i in enumerate(idx):
        meas = features(rec.bundle.signals[rec.bundle.records[i]])
        mod = features(signals[k])
        errs += [abs(float(mod[f]) / float(meas[f]) - 1) * 100 for f in FEATURES]
    return float(np.mean(errs))


def residual_table(rec: Records, idx: np.ndarray, signals: list[np.ndarray]
                   ) -> dict[str, dict[str, float]]:
    """Mean dB residual of each signature entry over records ``idx``, per group label."""
    res = residuals_db(rec, idx, signals)
    return {rec.groups[k].label: dict(zip(rec.groups[k].names,
                                          np.mean([res[j] for j in pos], axis=0).tolist(),
                                          strict=True))
            for k, pos in by_group(rec, idx).items()}


def group_errors(rec: Records, idx: np.ndarray, signals: list[np.ndarray],
                 discrepancy: bool = True) -> dict[str, float]:
    """RMS standardised residual (:func:`standardised`) over records ``idx``, per group."""
    z = standardised(rec, idx, signals, discrepancy)
    return {rec.groups[k].label: rms(np.concatenate([z[j] for j in pos]))
            for k, pos in by_group(rec, idx).items()}
