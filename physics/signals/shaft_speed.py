"""The pinion speed of a record taken without a tachometer, read off its spectrum.

A gear pair's vibration holds the mesh harmonics ``k z1 f1`` above every other line family:
the sidebands about them (pinion and gear shaft rates) and the shaft orders are weaker
(McFadden & Smith, Tribology Int. 17 (1984) 3; Randall, Vibration-based Condition Monitoring,
Wiley 2011, ch. 2). Given the pinion's tooth number the comb depends on ``f1`` alone:

1. **Lines**: the record's Hann-windowed spectrum, zero-padded to :data:`PAD` points a bin; a
   line is a peak (a maximum within one bin each side), its height taken over the floor (the
   running median over :data:`FLOOR_BINS` bins each side, which the sparse lines do not
   raise); every other point has none. A comb point reads the line within half a bin of it.
2. **Search**: each speed between ``f_low`` and ``f_high`` on a geometric grid, at whose step
   the highest harmonic below 0.45 fs moves by one padded point, scored by the mean height of
   its mesh harmonics below 0.45 fs: half the speed puts half its points between the mesh
   lines, where the spectrum is lower.
3. **Subharmonic rule** (after Hermes, J. Acoust. Soc. Am. 83 (1988) 257): twice or three
   times the speed reads every second or third mesh harmonic and may score as high or higher
   (where the odd harmonics are weaker); the lowest speed a whole number of times slower than
   the best whose extra harmonics, those the best's comb leaves out, are lines in the
   majority is taken.
4. **Refinement**: within the main lobe of the highest harmonic about that grid speed, the
   speed whose mesh harmonics carry the most power by the exact Hann-windowed projection at
   their frequencies (a bounded scalar search).
5. **Judgement**: the comb must have at least :data:`MIN_LINES` lines among its harmonics, a
   mean height of :data:`MIN_COMB_DB` and a lead of :data:`MIN_MARGIN_DB` over the best speed
   that is neither within :data:`SAME_COMB` of it nor of a multiple or a whole fraction of it
   (:attr:`SpeedEstimate.clear`); otherwise the caller refuses to read the record's speed.

A record's speed is taken constant over it, as the order analysis does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: the band the mesh harmonics are read in, as a fraction of the sampling rate: below the
#: anti-aliasing filters' transition (a recorder's is flat to about 0.45 fs)
BAND = 0.45
#: zero padding of the search spectrum (points per FFT bin of the record)
PAD = 4
#: width of the running median of the floor, in FFT bins of the record (each side)
FLOOR_BINS = 64
#: speeds scored at once (memory: speeds x harmonics)
CHUNK = 1024
#: the height over the floor [dB] from which a comb point counts as a line
LINE_DB = 10.0
#: the fewest mesh harmonics that must be lines
MIN_LINES = 3
#: the least mean height [dB] of the comb's harmonics over the floor: above what white
#: noise's best speed reaches (its bins' heights are exponential, about 5.6 dB of scatter;
#: tests/signals/test_shaft_speed.py)
MIN_COMB_DB = 8.0
#: the least lead [dB] of the comb over the best other speed (neither a multiple nor a whole
#: fraction of it)
MIN_MARGIN_DB = 3.0
#: relative distance within which two speeds are one comb
SAME_COMB = 0.02


@dataclass(frozen=True)
class SpeedEstimate:
    """A speed read off a record's spectrum: ``rpm``; ``comb_db``, the mean height of its mesh
    harmonics over the floor; ``lines``, how many of them are lines; ``runner_up_rpm`` and
    ``runner_up_db``, the best other speed (neither a multiple nor a fraction of it) and its
    comb's height."""

    rpm: float
    comb_db: float
    lines: int
    runner_up_rpm: float
    runner_up_db: float

    @property
    def f1_hz(self) -> float:
        return self.rpm / 60.0

    @property
    def clear(self) -> bool:
        """Whether the comb is clear enough to read the speed by (module doc, step 5)."""
        return (self.lines >= MIN_LINES and self.comb_db >= MIN_COMB_DB
                and self.comb_db - self.runner_up_db >= MIN_MARGIN_DB)


def _line_heights(p_db: np.ndarray) -> np.ndarray:
    """Per padded point, the height [dB] over the floor of the line within half an FFT bin of
    it, zero where there is none (module doc, step 1): a comb point scores where a line
    stands, not anywhere in a strong line's main lobe."""
    from scipy import ndimage  # imported on first use
    floor = ndimage.median_filter(p_db, size=2 * FLOOR_BINS * PAD + 1, mode="nearest")
    peak = p_db == ndimage.maximum_filter(p_db, size=2 * PAD + 1, mode="nearest")
    height = np.where(peak, np.maximum(p_db - floor, 0.0), 0.0)
    return ndimage.maximum_filter(height, size=PAD + 1, mode="constant")


def _mesh_heights(f1: np.ndarray, z1: int, height: np.ndarray, df: float, f_band: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Each speed's mean height [dB] over the floor of its mesh harmonics below ``f_band``
    (read at their nearest bins) and how many of them are lines (:data:`LINE_DB`)."""
    k = np.arange(1, int(f_band // (z1 * f1.min())) + 1)
    fm = np.outer(f1, k * z1)  # (speeds, harmonics)
    inside = fm < f_band
    h = np.where(inside, height[np.clip(np.rint(fm / df).astype(int), 0, height.size - 1)], 0.0)
    count = np.maximum(inside.sum(axis=1), 1)
    return h.sum(axis=1) / count, (h >= LINE_DB).sum(axis=1)


def _mesh_power(windowed: np.ndarray, fs: float, f1: float, z1: int, f_top: float) -> float:
    """Summed power of the mesh harmonics of speed ``f1`` below ``f_top`` by the exact
    projection of the Hann-windowed record ``windowed`` sampled at ``fs``: its z-transform on
    the unit circle at those harmonics, ``exp(2 pi i k z1 f1 / fs)``, ``k = 1, 2, ...``, by the
    chirp z-transform (Rabiner, Schafer and Rader 1969; ``scipy.signal.czt``)."""
    from scipy import signal  # imported on first use

    step = np.exp(-2j * np.pi * z1 * f1 / fs)
    z = signal.czt(windowed, m=int(f_top // (z1 * f1)), w=step, a=1 / step)
    return float(np.sum(np.abs(z) ** 2))


def pinion_speed(x: np.ndarray, fs: float, z1: int, f_low: float, f_high: float
                 ) -> SpeedEstimate:
    """The pinion speed of record ``x`` (1-D, sampled at ``fs`` [Hz]) of a pinion of ``z1``
    teeth, sought between ``f_low`` and ``f_high`` [Hz] of the pinion shaft (module doc);
    :attr:`SpeedEstimate.clear` says whether the spectrum's comb is clear enough to read it
    by."""
    from scipy import optimize  # imported on first use

    if not 0 < f_low < f_high or z1 * f_high >= BAND * fs:
        raise ValueError(f"the pinion speed is sought from f_low = {f_low:g} to f_high = "
                         f"{f_high:g} Hz; its mesh line z1 f1 (z1 = {z1}) must lie below "
                         f"{BAND} fs = {BAND * fs:g} Hz, where the harmonics are read: "
                         "give 0 < f_low < f_high, sample faster or check z1")
    x = np.asarray(x, float) - float(np.mean(x))
    n = x.size
    windowed = x * np.hanning(n)
    spec = np.abs(np.fft.rfft(windowed, n=PAD * n)) ** 2
    df = fs / (PAD * n)
    height = _line_heights(10 * np.log10(spec + 1e-30 * spec.max()))
    f_band = BAND * fs
    # a geometric grid: the highest mesh harmonic below f_band moves one padded bin a step
    grid = f_low * (1 + df / f_band) ** np.arange(
        int(math.log(f_high / f_low) / math.log1p(df / f_band)) + 2)
    grid = grid[grid <= f_high * (1 + df / f_band)]
    parts = [_mesh_heights(grid[i:i + CHUNK], z1, height, df, f_band)
             for i in range(0, grid.size, CHUNK)]
    score = np.concatenate([p[0] for p in parts])
    lines = np.concatenate([p[1] for p in parts])
    best = int(np.argmax(score))
    # the lowest speed a whole number of times slower whose extra harmonics (those the best
    # speed's comb leaves out) are lines in the majority (subharmonic rule)
    for m in range(int(grid[best] / f_low), 1, -1):
        near = np.flatnonzero(np.abs(grid * m / grid[best] - 1) <= 2 * PAD * df / f_band)
        if near.size:
            j = int(near[np.argmax(score[near])])
            k = np.arange(1, int(f_band // (z1 * grid[j])) + 1)
            extra = height[np.rint(k[k % m != 0] * z1 * grid[j] / df).astype(int)]
            if extra.size and np.mean(extra >= LINE_DB) >= 0.5:
                best = j
                break
    rel = grid / grid[best]
    ratio = np.maximum(rel, 1 / rel)  # a multiple or a whole fraction: near a whole number
    far = np.abs(ratio - np.rint(ratio)) > SAME_COMB * np.rint(ratio)
    runner = int(np.argmax(np.where(far, score, -np.inf))) if far.any() else best
    reach = 2 * PAD * grid[best] * df / f_band  # the highest harmonic's main lobe
    lo, hi = max(f_low, grid[best] - reach), min(f_high, grid[best] + reach)
    res = optimize.minimize_scalar(lambda f: -_mesh_power(windowed, fs, f, z1, f_band),
                                   bounds=(lo, hi), method="bounded",
                                   options={"xatol": reach * 1e-5})
    return SpeedEstimate(rpm=60.0 * float(res.x), comb_db=float(score[best]),
                         lines=int(lines[best]), runner_up_rpm=60.0 * float(grid[runner]),
                         runner_up_db=float(score[runner]) if far.any() else -math.inf)
