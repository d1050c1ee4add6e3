"""Statistical vibration features of thesis Table 13, vectorised over a batch of signals.

All features are taken over the last axis of the signal array, on the signal as given: a DTE
record keeps its mean (as in thesis Table 14, whose RMS exceeds its peak-to-peak), an acceleration
record arrives with its mean removed. Peak is ``max |x|``; kurtosis is Pearson's (normal = 3).

=============  ========================================  ===============
feature        definition (N samples)                    unit
=============  ========================================  ===============
rms            sqrt(mean(x^2))                           signal's
peak_to_peak   max(x) - min(x)                           signal's
kurtosis       mean((x - mean x)^4) / std(x)^4           1
crest          max|x| / rms                              1
margin         max|x| / mean(sqrt|x|)^2                  1
impulse        max|x| / mean|x|                          1
shape          rms / mean|x|                             1
=============  ========================================  ===============
"""

from __future__ import annotations

import numpy as np

FEATURES = ("rms", "peak_to_peak", "kurtosis", "crest", "margin", "impulse", "shape")
#: features that carry the signal's unit; the others are dimensionless
DIMENSIONAL = ("rms", "peak_to_peak")


def feature_units(signal_unit: str) -> dict[str, str]:
    """Unit of each feature for a signal measured in ``signal_unit`` (e.g. ``"m"``)."""
    return {f: (signal_unit if f in DIMENSIONAL else "1") for f in FEATURES}


def _name(mask: np.ndarray) -> str:
    """'signal (i, j)' for the first True entry of a per-signal mask, 'the signal' for one."""
    if mask.ndim == 0:
        return "the signal"
    return f"signal {tuple(int(i) for i in np.argwhere(mask)[0])}"


def _validate(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim == 0 or x.shape[-1] < 2:
        raise ValueError(f"a signal needs at least 2 samples along its last axis; got shape "
                         f"{x.shape}")
    bad = ~np.all(np.isfinite(x), axis=-1)
    if np.any(bad):
        raise ValueError(f"{_name(bad)} holds NaN or infinite samples; clean or drop it before "
                         "computing features")
    scale = np.maximum(np.max(np.abs(x), axis=-1), np.finfo(float).tiny)
    const = np.ptp(x, axis=-1) <= 1e-12 * scale
    if np.any(const):
        raise ValueError(f"{_name(const)} is constant: its kurtosis and shape features are "
                         "undefined (a sensor stuck or not connected?)")
    return x


def features(x: np.ndarray) -> dict[str, np.ndarray]:
    """The features of each signal in ``x`` (shape ``(..., n_samples)``); see the module table.

    Parameters
    ----------
    x : array_like
        Signals along the last axis, at least 2 samples each; any leading axes are a batch.

    Returns
    -------
    dict of str to numpy.ndarray
        Each feature of :data:`FEATURES` (thesis Table 13), shape ``x.shape[:-1]``; units
        from :func:`feature_units`.

    Raises
    ------
    ValueError
        For an empty or one-sample signal, NaN or infinite samples, or a constant signal, naming
        the first offending signal's index.

    Examples
    --------
    A pure sine of amplitude ``A`` over whole periods: RMS ``A / sqrt(2)``, peak-to-peak ``2 A``,
    kurtosis ``mean(sin^4) / mean(sin^2)^2 = (3/8) / (1/2)^2 = 1.5``, crest ``sqrt(2)``, and,
    with ``mean|sin| = 2 / pi``, impulse ``pi / 2`` and shape ``pi / (2 sqrt(2))``:

    >>> t = np.arange(1000) / 1000.0  # 1 s at 1 kHz
    >>> x = 3.0 * np.sin(2 * np.pi * 5.0 * t)  # A = 3, five whole periods
    >>> f = features(x)
    >>> {k: round(float(f[k]), 3) for k in ("rms", "peak_to_peak", "kurtosis", "crest")}
    {'rms': 2.121, 'peak_to_peak': 6.0, 'kurtosis': 1.5, 'crest': 1.414}
    >>> round(3.0 / 2**0.5, 3), round(2**0.5, 3)  # by hand
    (2.121, 1.414)
    >>> round(float(f["impulse"]), 3), round(float(f["shape"]), 3)
    (1.571, 1.111)
    >>> round(np.pi / 2, 3), round(np.pi / (2 * 2**0.5), 3)  # by hand
    (1.571, 1.111)

    A batch: one feature value per signal; the dimensionless features ignore the gain.

    >>> f = features(np.stack([x, 10 * x]))
    >>> f["rms"].shape, [round(float(c), 3) for c in f["crest"]]
    ((2,), [1.414, 1.414])
    """
    x = _validate(x)
    absx = np.abs(x)
    peak = absx.max(axis=-1)
    mean_abs = absx.mean(axis=-1)
    rms = np.sqrt(np.mean(x * x, axis=-1))
    centred = x - x.mean(axis=-1, keepdims=True)
    squared = centred * centred  # ``centred**4`` would call pow(): ten times the time
    var = np.mean(squared, axis=-1)
    return {
        "rms": rms,
        "peak_to_peak": x.max(axis=-1) - x.min(axis=-1),
        "kurtosis": np.mean(squared * squared, axis=-1) / var**2,
        "crest": peak / rms,
        "margin": peak / np.mean(np.sqrt(absx), axis=-1) ** 2,
        "impulse": peak / mean_abs,
        "shape": rms / mean_abs,
    }
