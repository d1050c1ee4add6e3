"""Gear condition indicators read from the time-synchronous average (TSA) of a vibration record.

The TSA of the gear under watch (:func:`time_synchronous_average`, the resampling and averaging of
:func:`physics.signals.order_analysis.synchronous_average`) is one revolution long, so bin ``m``
of its DFT is shaft order ``m`` exactly: the orders are separated by the DFT itself, with no window
and no leakage (Braun, Acustica 32 (1975) 69; McFadden, Mech. Syst. Signal Process. 1 (1987) 83:
the TSA keeps the orders of the shaft and averages everything else out). For a gear of ``z``
teeth the orders of one revolution of ``N`` samples (``m = 0 .. N // 2``) split into

==========================  ==============================  =====================================
part                        orders                          source
==========================  ==============================  =====================================
mesh harmonics              ``k z``, ``k >= 1``             Stewart 1977
first-order sidebands       ``k z - 1``, ``k z + 1``        Zakrajsek, Townsend & Decker 1993
shaft orders (optional)     ``1 .. shaft_orders``           Zakrajsek, Townsend & Decker 1993
==========================  ==============================  =====================================

and the signals the indicators read are (each without its mean, order 0):

- *regular* signal: the mesh harmonics, their first-order sidebands and the chosen shaft orders;
- *difference* signal ``d``: the TSA less its regular signal (Stewart 1977; Zakrajsek, Townsend
  & Decker 1993, who name the sidebands);
- *residual* signal ``r``: the TSA less its mesh harmonics (and the chosen shaft orders) only,
  sidebands kept (Zakrajsek, Townsend & Decker 1993).

The indicators (all dimensionless ratios, so independent of the sensor's gain; Pearson moments,
normal kurtosis 3):

==================  =================================================  ==========================
name                definition                                         source
==================  =================================================  ==========================
``fm0``             ``(max TSA - min TSA) / sum_k A(k z)``             Stewart 1977
``fm4``             ``m4(d) / m2(d)^2``                                Stewart 1977
``na4``             ``m4(r) / (mean_j m2(r_j))^2``, j over the run     Zakrajsek et al. 1993
``m6a``             ``m6(d) / m2(d)^3``                                Martin 1989
``m8a``             ``m8(d) / m2(d)^4``                                Martin 1989
``energy_ratio``    ``rms(d) / rms(regular)``                          Swansson 1980
``sideband_level``  ``sqrt(sum A(k z +- 1)^2 / sum A(k z)^2)``         this module (see below)
==================  =================================================  ==========================

``A(m)`` is the amplitude of order ``m`` of the TSA, ``m_p`` the ``p``-th central moment over
the revolution. The sources: R. M. Stewart, *Some useful data analysis techniques for gearbox
diagnostics*, ISVR Univ. Southampton report MHM/R/10/77 (1977); J. J. Zakrajsek, D. P. Townsend
& H. J. Decker, *An analysis of gear fault detection methods as applied to pitting fatigue
failure data*, NASA TM-105950 (1993), which also gives M6A and M8A after R. L. Martin,
*Detection of gear damage by statistical vibration analysis*, IMechE C418/032 (1989), and the
energy ratio after N. S. Swansson, *Application of vibration signal analysis techniques to
signal monitoring*, Conf. Friction and Wear in Engineering, IEAust (1980).

Without a tachometer, the shaft rate is read from the record's spectrum
(:func:`shaft_rate_from_spectrum`): the speed within ``rel_band`` of ``f_nominal`` whose mesh
comb ``k z f_shaft`` the spectrum holds best, by :func:`physics.signals.shaft_speed.pinion_speed`;
constant speed is assumed.
"""

from __future__ import annotations

import math

import numpy as np

from physics.signals.features import _name
from physics.signals.order_analysis import synchronous_average
from physics.signals.shaft_speed import BAND, pinion_speed

#: the indicators of :func:`indicators`, in its order
INDICATORS = ("fm0", "fm4", "na4", "m6a", "m8a", "energy_ratio", "sideband_level")
#: fewest teeth: below, the first-order sidebands ``z +- 1`` run into the low shaft orders
MIN_TEETH = 5
#: fewest whole revolutions a record must hold to be averaged
MIN_REVOLUTIONS = 2
#: a part whose variance is below this fraction of the TSA's is numerically zero (FFT round-off)
_ZERO = 1e-20


def indicator_units() -> dict[str, str]:
    """Unit of each indicator of :data:`INDICATORS`: all are ratios, ``"1"``."""
    return dict.fromkeys(INDICATORS, "1")


def _records(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.ndim == 0 or x.shape[-1] < 2:
        raise ValueError(f"x of shape {x.shape} is not a record: give samples along the last "
                         "axis (records along the leading axes)")
    bad = ~np.all(np.isfinite(x), axis=-1)
    if np.any(bad):
        raise ValueError(f"{_name(bad)} holds NaN or infinite samples: a TSA needs every sample; "
                         "clean the record (or drop it) before computing indicators")
    return x


def _positive(name: str, value: float, fix: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} = {value!r} must be finite and positive; {fix}")
    return v


def _teeth(z: int) -> int:
    if isinstance(z, bool) or int(z) != z or z < MIN_TEETH:
        raise ValueError(f"z = {z!r} must be an integer >= {MIN_TEETH} (the tooth count of the "
                         "gear on the shaft turning at f_shaft): with fewer teeth the sidebands "
                         "z +- 1 fall on the shaft orders; give the analysed gear's tooth count")
    return int(z)


def _bins(bins: int | None, fs: float, f_shaft: float) -> int:
    if bins is None:  # a sample per sample of the record: the TSA keeps the record's band
        return math.ceil(fs / f_shaft - 1e-9)
    if isinstance(bins, bool) or int(bins) != bins or bins < 4:
        raise ValueError(f"bins = {bins!r} must be an integer >= 4 (samples per revolution of "
                         "the TSA); leave it None for one per sample of the record")
    return int(bins)


def time_synchronous_average(x: np.ndarray, fs: float, f_shaft: float,
                             bins: int | None = None) -> np.ndarray:
    """The time-synchronous average of each record of ``x`` (..., n) over its whole revolutions
    at the shaft rate ``f_shaft`` [Hz], ``bins`` samples per revolution (..., bins).

    Each record is resampled to ``bins`` points per revolution by linear interpolation at
    constant speed and its whole revolutions are averaged (Braun, Acustica 32 (1975) 69; the
    resampling of :func:`physics.signals.order_analysis.synchronous_average`). ``bins=None``
    takes ``ceil(fs / f_shaft)``, as many as the record has samples per revolution, so the TSA
    keeps the record's band. The average over ``R`` revolutions keeps the shaft's orders and
    divides the power of anything asynchronous by ``R`` (McFadden, Mech. Syst. Signal Process.
    1 (1987) 83). Linear interpolation attenuates order ``m`` by up to ``cos(pi m f_shaft /
    fs)`` where the sample grid does not fall on whole revolutions (0.95 at ``fs / 10``).

    Without a tachometer, ``f_shaft`` is :func:`shaft_rate_from_spectrum`.

    Parameters
    ----------
    x : array_like
        Records along the last axis (..., n); leading axes are a batch.
    fs : float
        Sampling rate [Hz].
    f_shaft : float
        Rotation rate of the shaft whose average is taken [Hz].
    bins : int, optional
        Samples per revolution of the TSA, >= 4; ``None``: ``ceil(fs / f_shaft)``.

    Returns
    -------
    numpy.ndarray
        The TSA, one revolution of each record (..., bins), in the record's unit.

    Raises
    ------
    ValueError
        NaN or infinite samples, ``fs`` or ``f_shaft`` not positive, ``bins`` not an integer
        >= 4, or a record shorter than two revolutions.

    Examples
    --------
    Ten revolutions of a shaft at 10 Hz sampled at 1 kHz, 100 samples a revolution: a signal
    periodic in the revolution plus a component at the non-integer order 2.5, which the average
    over an even number of revolutions cancels (its phase turns by pi a revolution):

    >>> fs, f_shaft = 1000.0, 10.0
    >>> t = np.arange(1000) / fs
    >>> periodic = np.sin(2 * np.pi * 3 * f_shaft * t) + 0.5 * np.cos(2 * np.pi * 7 * f_shaft * t)
    >>> x = periodic + 0.5 * np.sin(2 * np.pi * 2.5 * f_shaft * t)
    >>> tsa = time_synchronous_average(x, fs, f_shaft)
    >>> tsa.shape  # one revolution
    (100,)
    >>> bool(np.allclose(tsa, periodic[:100]))  # the periodic part, one period of it
    True
    """
    x = _records(x)
    fs = _positive("fs", fs, "give the sampling rate in Hz")
    f_shaft = _positive("f_shaft", f_shaft, "give the shaft rate in Hz (a tachometer's, or "
                        "shaft_rate_from_spectrum's)")
    revolutions = x.shape[-1] / fs * f_shaft  # the count synchronous_average takes
    if int(revolutions) < MIN_REVOLUTIONS:
        raise ValueError(f"a record of {x.shape[-1]} samples at fs = {fs:g} Hz holds "
                         f"{revolutions:.3g} revolutions at f_shaft = {f_shaft:g} Hz; a TSA "
                         f"averages at least {MIN_REVOLUTIONS} whole revolutions: give a record "
                         f"of at least {math.ceil(MIN_REVOLUTIONS * fs / f_shaft)} samples")
    return synchronous_average(x, fs, f_shaft, _bins(bins, fs, f_shaft))


def _order_masks(n: int, z: int, shaft_orders: int) -> dict[str, np.ndarray]:
    """Masks over the one-sided orders ``0 .. n // 2`` of a TSA of ``n`` samples."""
    m = np.arange(n // 2 + 1)
    r = m % z
    return {"dc": m == 0, "mesh": (m > 0) & (r == 0),
            "sidebands": (m >= z - 1) & ((r == 1) | (r == z - 1)),
            "shaft": (m >= 1) & (m <= shaft_orders)}


def _decompose(x: np.ndarray, fs: float, f_shaft: float, z: int, bins: int | None,
               shaft_orders: int) -> tuple[dict[str, np.ndarray], np.ndarray,
                                           dict[str, np.ndarray]]:
    """The parts of the TSA (module table), its order amplitudes and the order masks."""
    x = _records(x)
    fs = _positive("fs", fs, "give the sampling rate in Hz")
    f_shaft = _positive("f_shaft", f_shaft, "give the shaft rate in Hz (a tachometer's, or "
                        "shaft_rate_from_spectrum's)")
    z = _teeth(z)
    if isinstance(shaft_orders, bool) or int(shaft_orders) != shaft_orders or not (
            0 <= shaft_orders <= z - 2):
        raise ValueError(f"shaft_orders = {shaft_orders!r} must be an integer in [0, z - 2 = "
                         f"{z - 2}]: the low shaft orders removed with the meshing components")
    if (z + 1) * f_shaft >= fs / 2:
        raise ValueError(f"the mesh order z = {z} and its upper sideband need (z + 1) f_shaft = "
                         f"{(z + 1) * f_shaft:g} Hz below fs / 2 = {fs / 2:g} Hz; sample faster "
                         "or check z and f_shaft")
    n = _bins(bins, fs, f_shaft)
    if n <= 2 * (z + 1):
        raise ValueError(f"bins = {n} resolves orders up to {n // 2}, not the mesh order z = {z} "
                         f"and its sideband z + 1; take bins > {2 * (z + 1)} (or None)")
    scale = np.max(np.abs(x), axis=-1)
    const = np.ptp(x, axis=-1) <= 1e-12 * np.maximum(scale, np.finfo(float).tiny)
    if np.any(const):
        raise ValueError(f"{_name(const)} is constant: it holds no vibration to read "
                         "(a sensor stuck or not connected?)")
    tsa = time_synchronous_average(x, fs, f_shaft, n)
    spec = np.fft.rfft(tsa, axis=-1)
    masks = _order_masks(n, z, int(shaft_orders))
    regular = masks["mesh"] | masks["sidebands"] | masks["shaft"]
    parts = {"tsa": tsa}
    for name, keep in (("regular", regular), ("difference", ~(regular | masks["dc"])),
                       ("residual", ~(masks["mesh"] | masks["shaft"] | masks["dc"]))):
        parts[name] = np.fft.irfft(spec * keep, n, axis=-1)
    weight = np.full(spec.shape[-1], 2.0)  # one-sided amplitude: DC and Nyquist bins once
    weight[0] = 1.0
    if n % 2 == 0:
        weight[-1] = 1.0
    return parts, np.abs(spec) * weight / n, masks


def tsa_components(x: np.ndarray, fs: float, f_shaft: float, z: int, bins: int | None = None,
                   shaft_orders: int = 0) -> dict[str, np.ndarray]:
    """The TSA of each record of ``x`` (..., n) and its parts, each (..., bins) in the
    record's unit: ``tsa``, ``regular`` (mesh harmonics ``k z``, their first-order sidebands
    ``k z +- 1`` and shaft orders ``1 .. shaft_orders``), ``difference`` (the TSA less its mean
    and regular part: Stewart 1977; Zakrajsek, Townsend & Decker, NASA TM-105950, 1993) and
    ``residual`` (the TSA less its mean, mesh harmonics and those shaft orders: Zakrajsek et
    al. 1993). The orders are separated exactly by the DFT of the one-revolution TSA (module
    docstring). ``tsa - mean = regular + difference``.

    ``z`` is the tooth count of the gear on the shaft turning at ``f_shaft``. Arguments are
    checked as in :func:`indicators`."""
    return _decompose(x, fs, f_shaft, z, bins, shaft_orders)[0]


def _ratio(num: np.ndarray, den: np.ndarray, defined: np.ndarray | bool = True) -> np.ndarray:
    """``num / den``, NaN where ``den`` is zero or ``defined`` is False."""
    ok = np.asarray(defined) & (den > 0)
    return np.where(ok, num / np.where(ok, den, 1.0), np.nan)


def na4(residual: np.ndarray, prior_variances: np.ndarray | None = None, *,
        run_axis: int | None = None) -> np.ndarray:
    """NA4 of each residual signal in ``residual`` (..., N) [1].

    ``NA4 = m4(r_M) / ((1 / M) sum_{j=1..M} m2(r_j))^2`` (Zakrajsek, Townsend & Decker,
    NASA TM-105950, 1993): the fourth central moment of the current record's residual over the
    squared mean of the variances of the residuals of the run so far, the current one included,
    so that a growing fault raises NA4 instead of being normalised away as in FM4.

    ``prior_variances`` (..., M - 1): the residual variances of the run's earlier records (in
    the signal's unit squared), broadcast against the batch ``residual.shape[:-1]``; or
    ``run_axis``: an axis of the batch along which the records are a run in time order, each
    read against the records up to itself. With neither, NA4 is the residual's Pearson
    kurtosis (3 for Gaussian noise). NaN where the mean variance is zero.

    Parameters
    ----------
    residual : array_like
        Residual signals (..., N) (:func:`tsa_components`), in the signal's unit.
    prior_variances : array_like, optional
        The residual variances of the run's earlier records (..., M - 1).
    run_axis : int, optional
        The batch axis along which the records are the run, in time order.

    Returns
    -------
    numpy.ndarray
        NA4 of each record (...,), dimensionless.

    Raises
    ------
    ValueError
        For both ``prior_variances`` and ``run_axis`` given, a ``run_axis`` that is not an axis
        of the batch, or prior variances that are negative, not finite or a scalar.

    Examples
    --------
    A Gaussian-like residual on its own: its kurtosis, 3.

    >>> r = np.random.default_rng(0).standard_normal(100_000)
    >>> round(float(na4(r)), 1)
    3.0

    The same residual grown to twice its amplitude, read against an earlier record of the
    first variance ``v``: ``m4 = 16 m4(r)`` over ``((v + 4 v) / 2)^2``, so NA4 rises by
    ``16 / 2.5^2 = 2.56`` where the kurtosis (FM4's normalisation) would not move:

    >>> round(float(na4(2 * r, [np.var(r)]) / na4(r)), 3)
    2.56
    >>> round(float(na4(2 * r) / na4(r)), 3)
    1.0
    """
    from scipy import stats  # imported on first use: a refusal need not wait for it
    r = np.asarray(residual, dtype=float)
    m2 = stats.moment(r, 2, axis=-1)
    m4 = stats.moment(r, 4, axis=-1)
    if prior_variances is not None and run_axis is not None:
        raise ValueError("give prior_variances (the run's earlier records) or run_axis (the "
                         "batch is the run), not both")
    if run_axis is not None:
        if not -m2.ndim <= run_axis < m2.ndim:
            raise ValueError(f"run_axis = {run_axis} is not an axis of the batch of shape "
                             f"{m2.shape} (the residuals' leading axes)")
        axis = run_axis % m2.ndim
        count = np.arange(1, m2.shape[axis] + 1).reshape(
            [-1 if a == axis else 1 for a in range(m2.ndim)])
        mean_var = np.cumsum(m2, axis=axis) / count
    elif prior_variances is not None:
        prior = np.asarray(prior_variances, dtype=float)
        if prior.ndim == 0 or not np.all(np.isfinite(prior) & (prior >= 0)):
            raise ValueError(f"prior_variances of shape {prior.shape} must be finite, >= 0 and "
                             "hold the earlier records along the last axis (the variances of "
                             "their residual signals)")
        mean_var = (prior.sum(axis=-1) + m2) / (prior.shape[-1] + 1)
    else:
        mean_var = m2
    return _ratio(m4, mean_var**2)


def indicators(x: np.ndarray, fs: float, f_shaft: float, z: int, *, bins: int | None = None,
               shaft_orders: int = 0, prior_residual_variances: np.ndarray | None = None,
               run_axis: int | None = None) -> dict[str, np.ndarray]:
    """The gear condition indicators :data:`INDICATORS` of each record of ``x`` (..., n)
    sampled at ``fs`` [Hz], for the gear of ``z`` teeth on the shaft turning at ``f_shaft``
    [Hz]; each (...,), dimensionless (:func:`indicator_units`). Definitions and sources: the
    module docstring.

    - ``fm0``: peak-to-peak of the TSA over the sum of its mesh-harmonic amplitudes (Stewart
      1977): grows with a major fault (a heavy-wear or broken-tooth signature), barely moves
      when every tooth's contribution scales alike.
    - ``fm4``: Pearson kurtosis of the difference signal (Stewart 1977; the sidebands removed
      too, per Zakrajsek et al. 1993): 3 for a healthy gear's Gaussian-like difference signal,
      more when one or two teeth carry a local fault.
    - ``na4``: :func:`na4` of the residual signal; ``prior_residual_variances`` or ``run_axis``
      give the run (with neither, the residual's kurtosis).
    - ``m6a``, ``m8a``: sixth and eighth moments of the difference signal over its variance
      cubed and to the fourth (Martin 1989, per Zakrajsek et al. 1993); 15 and 105 for
      Gaussian noise.
    - ``energy_ratio``: RMS of the difference signal over RMS of the regular signal (Swansson
      1980, per Zakrajsek et al. 1993): rises as heavy, spread damage moves energy out of the
      meshing components.
    - ``sideband_level``: RMS of the first-order sidebands ``k z +- 1`` over RMS of the mesh
      harmonics ``k z``, all ``k`` below the TSA's Nyquist order. A mesh signal amplitude-
      modulated once per revolution with depth ``mu`` gives ``mu / sqrt(2)`` (each sideband
      ``mu / 2`` of its carrier: Randall, J. Mech. Des. 104 (1982) 259), whatever the mesh
      waveform; a ratio of line energies as the energy ratio is. Unlike the sideband level
      factor (the two sidebands of the first mesh harmonic over the TSA's standard deviation;
      Lebold et al., MFPT 54 (2000) 623), it reads every harmonic's sidebands and depends
      neither on the broadband part of the TSA nor on how the mesh energy splits between
      harmonics.

    ``shaft_orders`` (default 0): the low shaft orders ``1 .. shaft_orders`` removed from the
    difference and residual signals as regular components (Zakrajsek et al. 1993 remove "the
    shaft frequency and harmonics"; MATLAB's ``tsaresidual`` two). ``bins``: samples per
    revolution of the TSA (default: one per sample of the record). Moments of a numerically
    zero difference or residual signal (a TSA of mesh lines only) are NaN.

    Parameters
    ----------
    x : array_like
        Records along the last axis (..., n); leading axes are a batch.
    fs : float
        Sampling rate [Hz].
    f_shaft : float
        Rotation rate of the shaft of the gear under watch [Hz].
    z : int
        Tooth count of that gear, >= 5.
    bins : int, optional
        Samples per revolution of the TSA; ``None``: one per sample of the record.
    shaft_orders : int
        Low shaft orders ``1 .. shaft_orders`` removed as regular components (default 0).
    prior_residual_variances : array_like, optional
        Residual variances of the run's earlier records, for ``na4`` (:func:`na4`).
    run_axis : int, optional
        The batch axis along which the records are the run, for ``na4`` (:func:`na4`).

    Returns
    -------
    dict of str to numpy.ndarray
        Each indicator of :data:`INDICATORS`, shape ``x.shape[:-1]``, dimensionless.

    Raises
    ------
    ValueError
        NaN or infinite samples, a constant record, ``fs`` or ``f_shaft`` not positive, ``z``
        not an integer >= 5, ``(z + 1) f_shaft >= fs / 2``, a record shorter than two
        revolutions, ``bins <= 2 (z + 1)``, ``shaft_orders`` outside ``[0, z - 2]``; each
        message names the value, the rule and the fix.

    Examples
    --------
    A gear of 18 teeth on a 10 Hz shaft, 20 revolutions at 40.96 kHz: a mesh tone in Gaussian
    noise, whose difference signal is Gaussian-like (FM4 near 3, M6A near 15), and the same
    record with one impact a revolution, a local tooth fault that FM4 picks out:

    >>> fs, f_shaft, z = 40960.0, 10.0, 18
    >>> t = np.arange(20 * 4096) / fs
    >>> rng = np.random.default_rng(0)
    >>> healthy = np.sin(2 * np.pi * z * f_shaft * t) + 0.3 * rng.standard_normal(t.size)
    >>> ind = indicators(healthy, fs, f_shaft, z)
    >>> bool(2.5 < ind["fm4"] < 3.5), bool(12 < ind["m6a"] < 18)
    (True, True)
    >>> faulty = healthy.copy()
    >>> faulty[::4096] += 3.0  # one impact at the same tooth every revolution
    >>> bool(indicators(faulty, fs, f_shaft, z)["fm4"] > 30)
    True
    """
    from scipy import stats  # imported on first use: a refusal need not wait for it
    parts, amp, masks = _decompose(x, fs, f_shaft, z, bins, shaft_orders)
    tsa, d, r, reg = parts["tsa"], parts["difference"], parts["residual"], parts["regular"]
    floor = _ZERO * np.var(tsa, axis=-1)
    m2 = stats.moment(d, 2, axis=-1)
    has_d = m2 > floor
    mesh_power = np.sum(amp[..., masks["mesh"]] ** 2, axis=-1)
    side_power = np.sum(amp[..., masks["sidebands"]] ** 2, axis=-1)
    has_r = stats.moment(r, 2, axis=-1) > floor
    return {
        "fm0": _ratio(np.ptp(tsa, axis=-1), np.sum(amp[..., masks["mesh"]], axis=-1)),
        "fm4": _ratio(stats.moment(d, 4, axis=-1), m2**2, has_d),
        "na4": np.where(has_r, na4(r, prior_residual_variances, run_axis=run_axis), np.nan),
        "m6a": _ratio(stats.moment(d, 6, axis=-1), m2**3, has_d),
        "m8a": _ratio(stats.moment(d, 8, axis=-1), m2**4, has_d),
        "energy_ratio": _ratio(np.sqrt(m2), np.sqrt(np.mean(reg**2, axis=-1))),
        "sideband_level": _ratio(np.sqrt(side_power), np.sqrt(mesh_power)),
    }


def shaft_rate_from_spectrum(x: np.ndarray, fs: float, z: int, f_nominal: float,
                             rel_band: float = 0.1) -> np.ndarray:
    """The shaft rate [Hz] of each record of ``x`` (..., n) without a tachometer: the mesh
    line ``z f_shaft`` read from the record's spectrum, over ``z``; (...,).

    The rule: the speed within ``f_nominal (1 +- rel_band)`` whose mesh comb ``k z f_shaft``
    (every harmonic below 0.45 fs) the spectrum holds best, located by the exact projection
    on its harmonics (:func:`physics.signals.shaft_speed.pinion_speed`), ``f_nominal`` the
    nominal shaft rate [Hz] (a drive's set speed, or ``f_shaft`` given elsewhere to refine).
    The mesh comb is shared by both gears of the pair (``z1 f1 = z2 f2``), so ``z`` and
    ``f_nominal`` name the gear whose rate is wanted. The speed must be constant over the
    record; ``rel_band`` must exclude other strong combs (another stage's mesh).

    Raises
    ------
    ValueError
        NaN samples, ``fs`` or ``f_nominal`` not positive, ``z`` not an integer >= 5,
        ``rel_band`` outside (0, 1), a band reaching 0.45 fs (the band the harmonics are read
        in, :data:`physics.signals.shaft_speed.BAND`), or a band holding fewer than three
        spectral bins (the record is too short).
    """
    x = _records(x)
    fs = _positive("fs", fs, "give the sampling rate in Hz")
    z = _teeth(z)
    f_nominal = _positive("f_nominal", f_nominal, "give the nominal shaft rate in Hz")
    if not 0 < rel_band < 1:
        raise ValueError(f"rel_band = {rel_band!r} must lie in (0, 1): the search band is "
                         "z f_nominal (1 +- rel_band); 0.1 suits a speed known within 10 %")
    lo, hi = z * f_nominal * (1 - rel_band), z * f_nominal * (1 + rel_band)
    if hi >= BAND * fs:
        raise ValueError(f"the search band of the mesh line reaches {hi:g} Hz, not below "
                         f"{BAND} fs = {BAND * fs:g} Hz, where the mesh harmonics are read (z = "
                         f"{z}, f_nominal = {f_nominal:g} Hz); sample faster, narrow rel_band "
                         "or check z and f_nominal")
    n = x.shape[-1]
    bins = int(np.floor(hi * n / fs) - np.ceil(lo * n / fs)) + 1
    if bins < 3:
        raise ValueError(f"the band {lo:g}-{hi:g} Hz holds {max(bins, 0)} bins of fs / n = "
                         f"{fs / n:g} Hz (n = {n}); give a longer record or widen rel_band")
    rates = [pinion_speed(r, fs, z, lo / z, hi / z).f1_hz for r in x.reshape(-1, n)]
    return np.array(rates).reshape(x.shape[:-1])
