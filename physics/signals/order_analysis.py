"""Order analysis of gear vibration records: lines, time-synchronous average, bands, noise floor.

The *signature* of a record is the vector of quantities the measured-data loop compares between
measurement and model, each in decibels so that gains become offsets:

- amplitudes of the mesh harmonics ``k f_m`` up to 0.45 ``f_s``, of their pinion-shaft sidebands
  ``k f_m +- j f_1`` (j = 1/2, 1, 2) and gear-shaft sidebands ``k f_m +- f_2``, and of the shaft
  orders ``f_1 / 2, f_1, 2 f_1, f_2`` (the half order: a drive-line order upstream of the
  pinion, e.g. a 2:1 stage or belt, or a sub-harmonic of looseness or rub); an amplitude is the
  Hann-windowed projection of the record on ``exp(i 2 pi f t)`` at the exact line frequency
  (order analysis without resampling, valid at constant speed; McFadden & Smith, Tribology Int.
  17 (1984) 3);
- band power in half-octave bands from ``f_m / 2`` to ``0.45 f_s`` (structural resonances);
- RMS, Pearson kurtosis and crest factor of the record, and the kurtosis of the residual of the
  pinion time-synchronous average once its mesh harmonics are removed (a local tooth defect;
  the FM4 idea of Stewart, see McFadden, J. Vib. Acoust. 109 (1987) 168);
- for DTE records (which keep their mean), the mean.

:func:`mesh_harmonic_levels` and :func:`mesh_harmonic_phases` (both at once:
:func:`mesh_harmonics`) give the levels and phases of mesh harmonics 2-6 relative to the first,
the DTE's wear features of the dataset (``dte_mesh<k>_db``, ``dte_mesh<k>_cos``,
``dte_mesh<k>_sin``); :func:`mesh_lines` the complex lines 1-6 against a once-per-revolution mark
(``dte_line<k>_re``, ``dte_line<k>_im``), whose change since a gearbox's first record is its wear's.

A record is cut into segments of ``segment_s``; :func:`signature_segments` gives one signature per
segment (their scatter is the entries' noise), :func:`mean_signatures` their mean, for a batch
of records at once.
"""

from __future__ import annotations

import itertools
import math
from functools import lru_cache

import numpy as np

from physics.signals.features import features

#: samples per block of the line projection (:func:`_blocked_basis`)
_BLOCK = 256


@lru_cache(maxsize=16)
def _blocked_basis(n: int, fs: float, freqs: tuple[float, ...]
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Hann-windowed projection on ``exp(i w t)`` at ``freqs``, factorised by blocks of
    ``B`` samples: with ``t = (a B + b) / fs``, ``exp(i w t) = exp(i w a B / fs) exp(i w b /
    fs)``, so one (B, 2 lines) basis of cosines and sines serves every block and a phase per
    block and line rotates the block sums into place. The whole record's basis of a 0.25 s
    segment at 41 kHz with 310 lines is 25 MB, read from memory at every call; the block
    basis stays in the cache and the product takes half the time. Returns the window weights
    (``2 w / sum w``, zero-padded to ``A B`` samples), the block basis (float32: the record is
    real, two real products cost half of one complex one) and the phases (A, lines)."""
    b = min(_BLOCK, n)
    a = -(-n // b)
    w = np.hanning(n)
    weights = np.zeros(a * b, np.float32)
    weights[:n] = 2 * w / w.sum()
    phase_b = 2 * np.pi * np.outer(np.arange(b) / fs, freqs)
    block = np.hstack([np.cos(phase_b), np.sin(phase_b)]).astype(np.float32)
    rotate = np.exp(2j * np.pi * np.outer(np.arange(a) * b / fs, freqs)).astype(np.complex64)
    for arr in (weights, block, rotate):
        arr.flags.writeable = False
    return weights, block, rotate


def line_amplitudes(x: np.ndarray, fs: float, freqs: np.ndarray) -> np.ndarray:
    """Amplitudes of sinusoids at ``freqs`` [Hz] in ``x`` (..., n): Hann-windowed projection."""
    return _amplitudes(x, float(fs), tuple(float(f) for f in freqs))


#: the mesh harmonics whose level and phase relative to the first are dataset features
MESH_ORDERS = (2, 3, 4, 5, 6)
#: the parts of a harmonic's relative phase (:func:`mesh_harmonic_phases`)
PHASE_PARTS = ("cos", "sin")


def _mesh_lines(x: np.ndarray, fs: float, f_mesh: float, orders: tuple[int, ...]
                ) -> np.ndarray:
    """Complex projections (:func:`_projections`) of the records ``x`` at the mesh frequency
    and at ``orders`` of it (last axis: first, then ``orders``); refused beyond Nyquist."""
    freqs = float(f_mesh) * np.array([1, *orders], float)
    if not (np.isfinite(freqs).all() and 0 < freqs[0] and freqs[-1] < fs / 2):
        raise ValueError(f"mesh harmonics {orders} of f_mesh = {f_mesh!r} Hz must lie in "
                         f"(0, fs/2 = {fs / 2:g}) Hz; lower the orders or raise fs")
    return _projections(np.asarray(x, float), float(fs), tuple(float(f) for f in freqs))


def mesh_harmonic_levels(x: np.ndarray, fs: float, f_mesh: float,
                         orders: tuple[int, ...] = MESH_ORDERS) -> dict[str, np.ndarray]:
    """Level [dB] of each mesh harmonic ``k f_mesh`` (``k`` in ``orders``) of the records
    ``x`` (..., n) relative to the first: ``mesh<k>_db = 20 log10(A_k / A_1)``, the amplitudes
    by :func:`line_amplitudes` (constant speed).

    A ratio of one record's own lines: independent of its gain (a sensor's scale, the mesh
    stiffness level, the load) and of an offset (the DTE's unknown constant). Wear reshapes
    the flanks, and with them the transmission error's harmonic content, which the levels of
    the mesh harmonics follow (Feng, Ji, Ni & Beer, Mech. Syst. Signal Process. 182 (2023)
    109605, sec. 4: the mesh harmonics and sidebands as wear indicators)."""
    return _levels(_mesh_lines(x, fs, f_mesh, orders), orders)


def _levels(z: np.ndarray, orders: tuple[int, ...]) -> dict[str, np.ndarray]:
    a = np.maximum(np.abs(z), np.finfo(np.float32).tiny)
    return {f"mesh{k}_db": 20 * np.log10(a[..., i + 1] / a[..., 0])
            for i, k in enumerate(orders)}


def mesh_harmonic_phases(x: np.ndarray, fs: float, f_mesh: float,
                         orders: tuple[int, ...] = MESH_ORDERS) -> dict[str, np.ndarray]:
    """The phase of each mesh harmonic ``k f_mesh`` of the records ``x`` (..., n) relative to
    the first, ``d_k = phi_k - k phi_1``, as ``mesh<k>_cos = cos d_k`` and ``mesh<k>_sin = sin
    d_k`` (a point on the unit circle: no wrap at +-pi for a network to learn across).

    The levels (:func:`mesh_harmonic_levels`) are half of each line; the phases are the other
    half, and together they are the shape of the transmission error over one mesh period, the
    sum of the flanks' deviations from the involute and their deflection (J. D. Smith, Gear
    Noise and Vibration, 2nd ed., Marcel Dekker 2003), which wear reshapes. ``d_k`` does not
    depend on where the record starts (a delay ``tau`` adds ``k w tau`` to ``phi_k`` and ``w
    tau`` to ``phi_1``), on a positive gain or on an offset; it is the phase a bispectrum's
    harmonic coupling measures (Nikias & Raghuveer, Proc. IEEE 75 (1987) 869). A record of
    the opposite sign convention adds ``(1 - k) pi``: the even orders' cos and sin change sign.
    The dataset's DTE is positive where the pinion leads the gear on the line of action, ``x =
    r_b1 theta1 - r_b2 theta2`` less the errors (:mod:`physics.dynamics.model`); negate a
    record that counts the other way before reading it."""
    return _phases(_mesh_lines(x, fs, f_mesh, orders), orders)


def _phases(z: np.ndarray, orders: tuple[int, ...]) -> dict[str, np.ndarray]:
    out = {}
    for i, k in enumerate(orders):
        d = np.angle(z[..., i + 1]) - k * np.angle(z[..., 0])
        out[f"mesh{k}_cos"], out[f"mesh{k}_sin"] = np.cos(d), np.sin(d)
    return out


#: the mesh harmonics whose complex amplitudes are dataset features (:func:`mesh_lines`)
LINE_ORDERS = (1, *MESH_ORDERS)
#: the parts of a line's complex amplitude in a table: ``<name>_re``, ``<name>_im``
VECTOR_PARTS = ("re", "im")


def mesh_lines(x: np.ndarray, fs: float, f_mesh: float, start_phase_rad: np.ndarray | float,
               orders: tuple[int, ...] = LINE_ORDERS) -> dict[str, np.ndarray]:
    """The complex amplitude of each mesh harmonic ``k f_mesh`` (``k`` in ``orders``) of the
    records ``x`` (..., n) referenced to the mesh phase zero: ``line<k>_re`` and ``line<k>_im``,
    the real and imaginary parts of ``a_k exp(i (p_k - k start_phase_rad))``, in the records'
    unit, where ``a_k cos(2 pi k f_mesh t + p_k)`` is the harmonic, ``t`` from the record's
    first sample, read by the Hann-windowed projection (:func:`line_amplitudes`, constant speed)
    and ``start_phase_rad`` the mesh phase there (``z1`` times the pinion angle since a once-
    per-revolution mark: a tachometer's reading).

    Referenced so, two records of one gearbox give lines whose difference is what changed
    between them (order tracking keeps the phase of each order against a tachometer's reference:
    R. B. Randall, Vibration-based Condition Monitoring, Wiley 2011, ch. 3). The transmission
    error is linear in the flanks' deviations from the involute at a given load (J. D. Smith,
    Gear Noise and Vibration, 2nd ed., Marcel Dekker 2003, ch. 2), so the change since a
    gearbox's first record is the wear's part of its lines, free of the flank form and profile
    errors it was made with: the vector change that condition monitoring trends for a machine's
    synchronous components (ISO 10816-1:1995, Annex D: a change of a component's amplitude and
    phase against its reference value can matter where the magnitude alone hardly moves)."""
    if orders[0] != 1:
        raise ValueError(f"orders = {orders} must start with the mesh frequency itself (1)")
    return _referenced(_mesh_lines(x, fs, f_mesh, orders[1:]), orders, start_phase_rad)


def _referenced(z: np.ndarray, orders: tuple[int, ...], start_phase_rad
                ) -> dict[str, np.ndarray]:
    # the projection on exp(+i w t) reads a cos(w t + p) as a e^(-i p): its conjugate is the
    # phasor a e^(i p)
    k = np.asarray(orders, float)
    z = np.conj(z) * np.exp(-1j * k * np.asarray(start_phase_rad, float)[..., None])
    out = {}
    for i, order in enumerate(orders):
        out[f"line{order}_re"], out[f"line{order}_im"] = z[..., i].real, z[..., i].imag
    return out


def mesh_harmonics(x: np.ndarray, fs: float, f_mesh: float,
                   orders: tuple[int, ...] = MESH_ORDERS,
                   start_phase_rad: np.ndarray | float | None = None) -> dict[str, np.ndarray]:
    """:func:`mesh_harmonic_levels` and :func:`mesh_harmonic_phases` of the records ``x`` from
    one projection of their lines and, given the mesh phase of their first samples
    (``start_phase_rad``), the lines 1 and ``orders`` of :func:`mesh_lines` from the same."""
    z = _mesh_lines(x, fs, f_mesh, orders)
    out = _levels(z, orders) | _phases(z, orders)
    if start_phase_rad is not None:
        out |= _referenced(z, (1, *orders), start_phase_rad)
    return out


def _amplitudes(x: np.ndarray, fs: float, freqs: tuple[float, ...]) -> np.ndarray:
    return np.abs(_projections(x, fs, freqs))


def _projections(x: np.ndarray, fs: float, freqs: tuple[float, ...]) -> np.ndarray:
    """Complex Hann-windowed projections of ``x`` (..., n) at ``freqs``: amplitude and phase
    of each line at the record's first sample."""
    weights, block, rotate = _blocked_basis(x.shape[-1], fs, freqs)
    a, b = rotate.shape[0], block.shape[0]
    y = np.zeros((*x.shape[:-1], a * b), np.float32)
    y[..., :x.shape[-1]] = x - x.mean(axis=-1, keepdims=True)
    y *= weights
    proj = y.reshape(*x.shape[:-1], a, b) @ block  # (..., blocks, 2 lines)
    lines = len(freqs)
    return ((proj[..., :lines] + 1j * proj[..., lines:]) * rotate).sum(axis=-2)


@lru_cache(maxsize=16)
def _hann_power(n: int) -> tuple[np.ndarray, float]:
    w = np.hanning(n + 1)[:n] if n > 1 else np.ones(1)  # periodic Hann, as scipy's "hann"
    w.flags.writeable = False
    return w, float(w.sum()) ** 2


def power_spectrum(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided Hann-windowed power spectrum of a mean-free copy of ``x`` (the power of a line
    in its bin: ``scaling="spectrum"``; the Nyquist bin of an even length not doubled): the
    same as ``scipy.signal.periodogram(x, fs, window="hann", detrend="constant",
    scaling="spectrum")``, with the window built once per length (the loop computes it for
    every simulated record of every evaluation; scipy's general path costs ten times the
    FFT)."""
    n = x.shape[-1]
    w, norm = _hann_power(n)
    spec = np.abs(np.fft.rfft((x - x.mean(axis=-1, keepdims=True)) * w)) ** 2 / norm
    spec[..., 1:n - n // 2] *= 2  # every bin but DC and an even length's Nyquist bin
    return np.fft.rfftfreq(n, 1.0 / fs), spec


def white_noise_std(x: np.ndarray, fs: float, f_low: float) -> float:
    """Standard deviation of the white noise in a record, from its spectral floor.

    Periodogram of the whole record (Blackman-Harris window, sidelobes below -92 dB so the lines
    do not leak into the floor) above ``f_low``; the lines occupy few bins at this resolution,
    so the 10 % quantile of the bins is noise, and for white noise each bin is exponentially
    distributed: mean = q10 / -ln(0.9).
    """
    from scipy import signal as sps  # imported on first use: a refusal need not wait for it
    f, p = sps.periodogram(x, fs=fs, window="blackmanharris", detrend="constant")
    band = p[(f > f_low) & (f < 0.45 * fs)]
    return math.sqrt(np.quantile(band, 0.1) / -math.log(0.9) * fs / 2)


def synchronous_average(x: np.ndarray, fs: float, f_shaft: float, bins: int = 256) -> np.ndarray:
    """Time-synchronous average over whole shaft revolutions (``bins`` angular samples each) of
    each record along the last axis of ``x``.

    The record is resampled to ``bins`` points per revolution by linear interpolation at
    constant speed and the revolutions are averaged; at least one revolution is needed.
    """
    n = x.shape[-1]
    n_rev = int(n / fs * f_shaft)
    if n_rev < 1:
        raise ValueError(f"the record holds {n / fs:.3g} s, less than one revolution "
                         f"at {f_shaft:.3g} Hz: a longer record is needed")
    pos = np.arange(n_rev * bins) * (fs / (bins * f_shaft))  # in samples
    i = np.minimum(pos.astype(int), n - 2)
    frac = np.minimum(pos - i, 1.0)  # held at the last sample, as np.interp does
    resampled = x[..., i] * (1 - frac) + x[..., i + 1] * frac
    return resampled.reshape(*x.shape[:-1], n_rev, bins).mean(axis=-2)


def _tsa_residual_kurtosis(x: np.ndarray, fs: float, f1: float, z1: int) -> np.ndarray:
    avg = synchronous_average(x, fs, f1)
    spec = np.fft.rfft(avg - avg.mean(axis=-1, keepdims=True), axis=-1)
    k = np.arange(spec.shape[-1])
    mesh = np.minimum(k % z1, z1 - k % z1) <= 1  # the mesh harmonics and their first neighbours
    mesh[0] = False
    spec[..., mesh] = 0.0
    res = np.fft.irfft(spec, avg.shape[-1], axis=-1)
    var = np.mean(res**2, axis=-1)
    fourth = np.mean(res**4, axis=-1)
    return np.where(var > 0, fourth / np.where(var > 0, var, 1.0) ** 2, 3.0)


def line_frequencies(f1: float, f2: float, z1: int, fs: float) -> dict[str, float]:
    """The named lines of the signature [Hz]: mesh harmonics below 0.45 fs with sidebands."""
    return dict(_lines(f1, f2, z1, fs))


@lru_cache(maxsize=64)
def _lines(f1: float, f2: float, z1: int, fs: float) -> tuple[tuple[str, float], ...]:
    fm = z1 * f1
    lines = {"shaft1/2": f1 / 2, "shaft1": f1, "shaft1x2": 2 * f1, "shaft2": f2}
    for k in range(1, max(1, int(0.45 * fs / fm)) + 1):
        lines[f"mesh{k}"] = k * fm
        for j, name in ((0.5, "p/2"), (1, "1p"), (2, "2p")):
            lines[f"mesh{k}+{name}"] = k * fm + j * f1
            lines[f"mesh{k}-{name}"] = k * fm - j * f1
        lines[f"mesh{k}+g"] = k * fm + f2
        lines[f"mesh{k}-g"] = k * fm - f2
    return tuple(lines.items())


@lru_cache(maxsize=64)
def _bands(n: int, fs: float, fm: float) -> tuple[tuple[int, int], ...]:
    """The half-octave bands (:func:`band_edges`) as ranges of a record's one-sided spectrum
    bins (``n`` samples): the bins of a band are contiguous."""
    f = np.fft.rfftfreq(n, 1.0 / fs)
    return tuple((int(np.searchsorted(f, lo, "left")), int(np.searchsorted(f, hi, "left")))
                 for lo, hi in itertools.pairwise(band_edges(fm, fs)))


def band_edges(fm: float, fs: float) -> np.ndarray:
    """Half-octave band edges from fm/2 to 0.45 fs [Hz]."""
    n = int(np.floor(2 * np.log2(0.45 * fs / (fm / 2))))
    return fm / 2 * 2 ** (np.arange(n + 1) / 2)


def signature_names(f1: float, f2: float, z1: int, fs: float, dte: bool) -> list[str]:
    names = [f"line_{k}" for k in line_frequencies(f1, f2, z1, fs)]
    names += [f"band{i:02d}" for i in range(len(band_edges(z1 * f1, fs)) - 1)]
    return names + ["rms", "kurtosis", "crest", "tsa_kurtosis"] + (["mean"] if dte else [])


def signatures(x: np.ndarray, fs: float, f1: float, f2: float, z1: int,
               dte: bool) -> np.ndarray:
    """The signature of each row of ``x`` (rows, samples), one analysis segment each [dB]
    (names: :func:`signature_names`); all rows at once."""
    x = np.atleast_2d(np.asarray(x, float))
    amp = _amplitudes(x, float(fs), tuple(f for _, f in _lines(f1, f2, z1, fs)))
    _, spec = power_spectrum(x, fs)
    bands = np.column_stack([spec[:, a:b].sum(axis=1) for a, b in _bands(x.shape[-1], fs, z1 * f1)]
                            or [np.empty((len(x), 0))])
    feat = features(x)
    stats = [feat["rms"], feat["kurtosis"], feat["crest"], _tsa_residual_kurtosis(x, fs, f1, z1)]
    stats += [np.abs(x.mean(axis=1))] if dte else []
    return np.concatenate([20 * np.log10(amp + 1e-30), 10 * np.log10(bands + 1e-300),
                           20 * np.log10(np.column_stack(stats) + 1e-30)], axis=1)


def _segments(x: np.ndarray, fs: float, segment_s: float) -> np.ndarray:
    n = round(segment_s * fs)
    if x.size < n:
        raise ValueError(f"record of {x.size / fs:.3g} s is shorter than one analysis segment "
                         f"({segment_s:g} s)")
    return x[:x.size // n * n].reshape(-1, n)


def signature_segments(x: np.ndarray, fs: float, f1: float, f2: float, z1: int, dte: bool,
                       segment_s: float) -> np.ndarray:
    """Signatures of the whole segments of record ``x``, (segments, entries) [dB]."""
    return signatures(_segments(x, fs, segment_s), fs, f1, f2, z1, dte)


def mean_signatures(xs: list[np.ndarray], fs: float, f1: float, f2: float, z1: int, dte: bool,
                    segment_s: float) -> np.ndarray:
    """The segment-averaged signature [dB] of each record of ``xs`` (one operating point and
    sampling rate), (records, entries): the segments of all records analysed in one batch."""
    cut = [_segments(x, fs, segment_s) for x in xs]
    sig = signatures(np.concatenate(cut), fs, f1, f2, z1, dte)
    ends = np.cumsum([len(c) for c in cut])
    return np.array([s.mean(axis=0) for s in np.split(sig, ends[:-1])])
