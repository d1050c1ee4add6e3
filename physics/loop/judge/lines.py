"""Spectral lines of the measured records that no declared order explains
(:func:`unexplained_lines`): a torque ripple at a non-integer shaft order and its mesh
sidebands, a bearing tone, a supply frequency. The signature
(:mod:`physics.signals.order_analysis`) names the declared orders only; such a line falls
between its named lines, below its lowest band or is diluted in a half-octave band.

Each record's periodogram (whole record, 4-term Blackman-Harris window: sidelobes below -92 dB,
so a strong mesh harmonic leaks no peak beside it; main lobe +-4 bins) is compared with its
local floor, a running median over :data:`FLOOR_BINS` bins divided by ``ln 2`` (a bin of white
noise is exponentially distributed, its median ``ln 2`` times its mean). A peak is a local
maximum above ``t`` times the floor; it is *unexplained* if it lies further than the window's
main lobe (:data:`LOBE_BINS` bins plus half a bin) from every declared line
(:func:`declared_lines`). A line is reported if such peaks persist, within
:data:`MATCH_BINS` bins, in at least half of a group's records (two at least, where the group
has two). ``t`` is set from the stated false-alarm rate: a noise bin exceeds ``t`` times the
mean with probability ``exp(-t)`` (Kay, Fundamentals of Statistical Signal Processing II, 1998,
7.3 for the periodogram detector), and the chance that any window of the searched band holds
such peaks in the required number of records, Bonferroni over windows and groups, is kept at
the rate (:func:`crossing_probability`).
"""

from __future__ import annotations

import math

import numpy as np

#: bins of the running median that is each record's local floor
FLOOR_BINS = 61
#: half-width of the Blackman-Harris main lobe [bins]: a peak within it of a declared line is
#: that line's
LOBE_BINS = 4.5
#: peaks of two records within this many bins are the same line
MATCH_BINS = 2


def declared_lines(f1: float, f2: float, z1: int, f_high: float) -> np.ndarray:
    """The frequencies [Hz] the declared model and the effect library make lines at, up to
    ``f_high``: every pinion order (run-out, its mesh modulation, a pit, the mesh harmonics and
    their pinion sidebands), the half orders 1/2 and 3/2 with the mesh harmonics' sidebands at
    +-1/2 and +-3/2 (a ripple at order 1/2), the gear's orders 1 and 2 with the mesh harmonics'
    gear sidebands +-1 and +-2 (a gear run-out)."""
    fm = z1 * f1
    out = [np.arange(1, int(f_high / f1) + 2) * f1, [f1 / 2, 1.5 * f1, f2, 2 * f2]]
    k = np.arange(1, int(f_high / fm) + 2) * fm
    for d in (0.5 * f1, 1.5 * f1, f2, 2 * f2):
        out += [k - d, k + d]
    return np.sort(np.concatenate([np.asarray(a, float) for a in out]))


def crossing_probability(windows: int, records: int, need: int, rate: float) -> float:
    """The per-bin crossing probability ``p`` at which the chance of a false line in any of
    ``windows`` windows of ``2 MATCH_BINS + 1`` bins is ``rate``: a record crosses somewhere in
    a window with probability at most ``(2 MATCH_BINS + 1) p``, and ``need`` of ``records`` must
    (binomial tail), by bisection on ``log p``."""
    from scipy.stats import binom  # imported on first use: a refusal need not wait for it
    width = 2 * MATCH_BINS + 1

    def false_rate(p: float) -> float:
        return windows * binom.sf(need - 1, records, min(1.0, width * p))

    lo, hi = -60.0, 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if false_rate(math.exp(mid)) < rate else (lo, mid)
    return math.exp(lo)


def record_spectrum(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frequencies, power per bin (a line of amplitude ``A`` on a bin: ``A^2 / 2``) and the
    local mean floor of the white noise of record ``x``."""
    from scipy import ndimage, signal  # imported on first use: a refusal need not wait for it
    f, p = signal.periodogram(x, fs=fs, window="blackmanharris", detrend="constant",
                              scaling="spectrum")
    floor = ndimage.median_filter(p, size=FLOOR_BINS, mode="nearest") / math.log(2)
    return f, p, np.maximum(floor, np.finfo(float).tiny)


def record_peaks(x: np.ndarray, fs: float, f_low: float, f_high: float, t: float,
                 declared: np.ndarray) -> list[tuple[float, float, float]]:
    """Unexplained peaks of one record: (frequency [Hz], power, floor) of each local maximum
    in ``(f_low, f_high)`` above ``t`` times its floor and off the ``declared`` lines."""
    f, p, floor = record_spectrum(x, fs)
    df = f[1] - f[0]
    ratio = p / floor
    peak = np.zeros_like(ratio, bool)
    peak[1:-1] = (ratio[1:-1] > t) & (p[1:-1] >= p[:-2]) & (p[1:-1] > p[2:])
    peak &= (f > f_low) & (f < f_high)
    out = []
    for i in np.flatnonzero(peak):
        near = np.min(np.abs(declared - f[i])) if declared.size else np.inf
        if near > LOBE_BINS * df:
            out.append((float(f[i]), float(p[i]), float(floor[i])))
    return out


def unexplained_lines(signals: list[np.ndarray], fs: float, f1: float, f2: float, z1: int,
                      rate: float, groups: int = 1) -> list[dict]:
    """Lines that persist across the records ``signals`` of one group (one speed and sampling
    rate) and that no declared order explains (see the module text); ``rate`` is the false-alarm
    rate per bundle, shared by its ``groups``. Each: frequency [Hz], pinion order, level above
    the local floor [dB] and amplitude (record units; means over the records that hold it), and
    in how many of the records it stands; the nearest mesh harmonic and the line's offset from
    it in pinion orders (a ripple at order q and its mesh sidebands share ``|offset| = q``)."""
    n = len(signals)
    if n == 0:
        return []
    length = min(x.size for x in signals)
    df = fs / length
    f_low, f_high = max(0.25 * f1, 2 * LOBE_BINS * df), 0.45 * fs
    need = 1 if n == 1 else max(2, math.ceil(n / 2))
    windows = max(1, int((f_high - f_low) / df / (2 * MATCH_BINS + 1)))
    p = crossing_probability(windows * groups, n, need, rate)
    t = -math.log(p)
    declared = declared_lines(f1, f2, z1, f_high + fs / 2)
    peaks = [record_peaks(x, fs, f_low, f_high, t, declared) for x in signals]
    pooled = sorted((fr, k, pw, fl) for k, pk in enumerate(peaks) for fr, pw, fl in pk)
    lines, used = [], set()
    for j, (fr, _, _, _) in enumerate(pooled):
        if j in used:
            continue
        members = [i for i in range(j, len(pooled)) if i not in used
                   and abs(pooled[i][0] - fr) <= MATCH_BINS * df]
        by_record: dict[int, tuple] = {}
        for i in members:  # each record's strongest peak of the cluster
            k, pw = pooled[i][1:3]
            if k not in by_record or pw > by_record[k][2]:
                by_record[k] = pooled[i]
        if len(by_record) < need:
            continue
        used.update(members)
        held = list(by_record.values())
        freq = float(np.mean([h[0] for h in held]))
        k = round(freq / (z1 * f1))  # the nearest mesh harmonic (0: a shaft-rate line)
        lines.append({"frequency_hz": freq, "order": freq / f1, "mesh_harmonic": k,
                      "offset_order": freq / f1 - k * z1,
                      "level_db": float(np.mean([10 * math.log10(h[2] / h[3]) for h in held])),
                      "amplitude": float(np.mean([math.sqrt(2 * h[2]) for h in held])),
                      "records": len(held), "of": n, "threshold_db": 10 * math.log10(t)})
    return sorted(lines, key=lambda d: -d["level_db"])
