"""Gear condition indicators of the TSA (physics.signals.indicators): hand calculations on a
synthetic revolution, Gaussian limits from sampling theory, the response to a local fault, the
invariances (gain, start of the record, angle of the revolution), NA4 over a run, the speed read
from the spectrum and the refusal of bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.signals.indicators import (
    INDICATORS,
    indicator_units,
    indicators,
    na4,
    shaft_rate_from_spectrum,
    time_synchronous_average,
    tsa_components,
)
from physics.signals.order_analysis import synchronous_average

F1 = 10.0  # shaft rate [Hz]
N = 256  # samples per revolution: fs / F1, whole, so the TSA reads the samples themselves
FS = N * F1
Z = 16  # teeth: mesh orders 16, 32, ..., 128 (the TSA's Nyquist order)
MESH = ((1.0, 0.3), (0.5, -1.1), (0.2, 2.0))  # (amplitude, phase) of mesh harmonics 1-3
H, J = 2.0, 37  # an impulse of H at sample J of every revolution: one tooth's local fault


def revolution(mesh=MESH, h=H, j=J) -> np.ndarray:
    n = np.arange(N)
    w = sum(a * np.cos(2 * np.pi * (k + 1) * Z * n / N + p) for k, (a, p) in enumerate(mesh))
    w = w + np.zeros(N)
    w[j] += h
    return w


def removed_cosines(orders, j=J) -> np.ndarray:
    """sum over ``orders`` of g_m cos(2 pi m (n - j) / N), g_m = 2 / N (1 / N at Nyquist): the
    part of a unit impulse at j in those orders (its DFT written out, no FFT)."""
    n = np.arange(N)
    return sum((1.0 if m == N // 2 else 2.0) / N * np.cos(2 * np.pi * m * (n - j) / N)
               for m in orders)


MESH_ORDERS = [m for m in range(1, N // 2 + 1) if m % Z == 0]
SIDEBANDS = [m for k in range(1, N // (2 * Z) + 1) for m in (k * Z - 1, k * Z + 1)
             if m <= N // 2]


def pearson(d: np.ndarray, p: int) -> float:
    return float(np.mean(d**p) / np.mean(d**2) ** (p // 2))


def test_every_indicator_against_a_hand_calculation():
    """Mesh harmonics 1-3 plus one impulse per revolution, three revolutions. The TSA is the
    revolution itself; each indicator is computed here from its definition, the orders' parts
    written as cosine sums (no FFT): FM0 from the phasors of the mesh orders, the difference and
    residual signals as the impulse less its mesh (and sideband) orders."""
    w = revolution()
    out = indicators(np.tile(w, 3), FS, F1, Z)
    # mesh order amplitudes: mesh phasor + impulse phasor 2H/N e^{-i 2 pi m J / N}
    amps = []
    for m in MESH_ORDERS:
        k = m // Z
        a, p = MESH[k - 1] if k <= len(MESH) else (0.0, 0.0)
        if m == N // 2:  # the Nyquist order is real: (a cos p + H/N (-1)^J) (-1)^n
            amps.append(abs(a * math.cos(p) + H / N * (-1) ** J))
        else:
            amps.append(abs(a * np.exp(1j * p) + 2 * H / N * np.exp(-2j * np.pi * m * J / N)))
    assert out["fm0"] == pytest.approx(np.ptp(w) / sum(amps), rel=1e-12)
    impulse = np.zeros(N)
    impulse[J] = 1.0
    d = H * (impulse - 1 / N - removed_cosines(MESH_ORDERS + SIDEBANDS))
    r = H * (impulse - 1 / N - removed_cosines(MESH_ORDERS))
    assert out["fm4"] == pytest.approx(pearson(d, 4), rel=1e-9)
    assert out["m6a"] == pytest.approx(pearson(d, 6), rel=1e-9)
    assert out["m8a"] == pytest.approx(pearson(d, 8), rel=1e-9)
    assert out["na4"] == pytest.approx(pearson(r, 4), rel=1e-9)
    regular = w - H / N - d  # the TSA less its mean and its difference signal
    assert out["energy_ratio"] == pytest.approx(
        np.sqrt(np.mean(d**2) / np.mean(regular**2)), rel=1e-9)
    side = len(SIDEBANDS) * (2 * H / N) ** 2
    assert out["sideband_level"] == pytest.approx(np.sqrt(side / np.sum(np.square(amps))),
                                                  rel=1e-9)


def test_sideband_level_reads_the_depth_of_a_once_per_revolution_modulation():
    """A mesh waveform (three harmonics) amplitude-modulated once per revolution with depth mu:
    each harmonic's sidebands are mu / 2 of it, so the level is mu / sqrt(2) whatever the
    waveform (Randall 1982); everything is regular, the energy ratio is zero and the moments of
    the (empty) difference signal are undefined (NaN)."""
    mu = 0.3
    theta = np.arange(4 * N) / N
    mesh = sum(a * np.cos(2 * np.pi * (k + 1) * Z * theta + p) for k, (a, p) in enumerate(MESH))
    out = indicators(mesh * (1 + mu * np.cos(2 * np.pi * theta + 0.7)), FS, F1, Z)
    assert out["sideband_level"] == pytest.approx(mu / math.sqrt(2), rel=1e-9)
    assert out["energy_ratio"] < 1e-12
    assert np.isnan(out["fm4"]) and np.isnan(out["m6a"]) and np.isnan(out["m8a"])


def test_gaussian_noise_gives_the_gaussian_moments():
    """White Gaussian noise: its TSA and the TSA's difference signal are Gaussian, so FM4 and
    NA4 (no history) are 3 within the sampling error of a kurtosis, sd sqrt(24 / n) for n
    samples (here the samples left once the removed orders are, averaged over the batch), and
    M6A and M8A near 15 and 105 (E[x^6] = 15 s^6, E[x^8] = 105 s^8)."""
    x = np.random.default_rng(7).standard_normal((400, 2 * N))
    out = indicators(x, FS, F1, Z)
    n_eff = N - 1 - 2 * (len(MESH_ORDERS) + len(SIDEBANDS))
    tol = 4 * math.sqrt(24 / n_eff / len(x)) + 6 / n_eff  # 4 sd + the estimator's bias
    assert abs(out["fm4"].mean() - 3) < tol
    assert abs(out["na4"].mean() - 3) < tol
    assert out["m6a"].mean() == pytest.approx(15, rel=0.1)
    assert out["m8a"].mean() == pytest.approx(105, rel=0.25)


def test_a_local_fault_raises_fm4_and_na4_a_uniform_change_leaves_fm0():
    """A healthy gear (mesh harmonics and measurement noise) against the same gear with one
    tooth carrying a short pulse (a local fault: FM4's and NA4's case, Stewart 1977) and with
    every tooth's mesh vibration 1.5 times larger (a uniform change: FM0 a ratio of the two)."""
    rng = np.random.default_rng(3)
    theta = np.arange(8 * N) / N
    mesh = sum(a * np.cos(2 * np.pi * (k + 1) * Z * theta + p) for k, (a, p) in enumerate(MESH))
    noise = 0.05 * rng.standard_normal(theta.size)
    phase = (theta % 1.0) * N  # sample within the revolution
    pulse = 0.8 * np.exp(-0.5 * ((phase - 100.0) / 1.5) ** 2)  # a twentieth of a tooth wide
    healthy, faulty, uniform = (indicators(s, FS, F1, Z) for s in (
        mesh + noise, mesh + pulse + noise, 1.5 * mesh + noise))
    sd = math.sqrt(24 / (N - 1 - 2 * (len(MESH_ORDERS) + len(SIDEBANDS))))  # a kurtosis's
    assert abs(healthy["fm4"] - 3) < 4 * sd and abs(healthy["na4"] - 3) < 4 * sd  # noise: 3
    assert faulty["fm4"] > 3 * healthy["fm4"]
    assert faulty["na4"] > 3 * healthy["na4"]
    assert uniform["fm0"] == pytest.approx(healthy["fm0"], rel=0.03)


SIGNAL = np.tile(revolution(), 4) + 0.05 * np.random.default_rng(11).standard_normal(4 * N)


@settings(max_examples=15, deadline=None)
@given(scale=st.floats(1e-6, 1e6), sign=st.sampled_from([-1.0, 1.0]))
def test_every_indicator_is_independent_of_the_signal_scale(scale, sign):
    """All indicators are ratios of like quantities: a sensor's gain (or polarity) drops out."""
    ref, out = indicators(SIGNAL, FS, F1, Z), indicators(sign * scale * SIGNAL, FS, F1, Z)
    for name in INDICATORS:
        assert out[name] == pytest.approx(ref[name], rel=1e-9), name


@settings(max_examples=10, deadline=None)
@given(revolutions=st.integers(1, 5), samples=st.integers(0, N - 1))
def test_indicators_do_not_depend_on_where_the_record_starts(revolutions, samples):
    """A periodic gear signal read from whole revolutions later, or from any sample of the
    revolution (the TSA rotated: its lines' amplitudes and its moments stay), gives the same
    indicators."""
    w = revolution() + 0.1 * np.random.default_rng(5).standard_normal(N)  # a rich revolution
    series = np.tile(w, 12)
    ref = indicators(series[:3 * N], FS, F1, Z)
    for start in (revolutions * N, revolutions * N + samples):
        out = indicators(series[start:start + 3 * N], FS, F1, Z)
        for name in INDICATORS:
            assert out[name] == pytest.approx(ref[name], rel=1e-9), (name, start)


def test_a_batch_gives_each_records_indicators():
    x = np.random.default_rng(2).standard_normal((2, 3, 3 * N)) + np.tile(revolution(), 3)
    out = indicators(x, FS, F1, Z)
    assert tuple(out) == INDICATORS and indicator_units() == dict.fromkeys(INDICATORS, "1")
    for name in INDICATORS:
        assert out[name].shape == (2, 3)
        assert out[name][1, 2] == pytest.approx(indicators(x[1, 2], FS, F1, Z)[name], rel=1e-12)


def test_the_tsa_is_the_existing_synchronous_average_and_splits_into_its_parts():
    x = np.random.default_rng(1).standard_normal((2, int(0.55 * 9000)))
    fs, f1 = 9000.0, 23.3  # 386.3 samples per revolution: interpolated
    np.testing.assert_array_equal(time_synchronous_average(x, fs, f1, bins=64),
                                  synchronous_average(x, fs, f1, bins=64))
    assert time_synchronous_average(x, fs, f1).shape == (2, math.ceil(fs / f1))
    parts = tsa_components(x, fs, f1, Z)
    tsa = parts["tsa"]
    np.testing.assert_allclose(tsa - tsa.mean(axis=-1, keepdims=True),
                               parts["regular"] + parts["difference"], atol=1e-12)
    spec = np.abs(np.fft.rfft(parts["residual"] - parts["difference"], axis=-1))
    lines = spec.max(axis=0) > 1e-9  # the residual less the difference: the sidebands only
    assert set(np.flatnonzero(lines)) <= {m for k in range(1, 20) for m in (k * Z - 1, k * Z + 1)}
    assert lines[Z - 1] and lines[Z + 1]


def test_na4_normalises_by_the_mean_variance_of_the_run_so_far():
    """NA4 = m4(r_M) / (mean_j m2(r_j))^2 (Zakrajsek et al. 1993): the kurtosis alone, or
    against earlier variances, or along a run, each as the formula says."""
    rng = np.random.default_rng(9)
    run = rng.standard_normal((5, N)) * np.arange(1, 6)[:, None]  # a growing residual
    m2, m4 = run.var(axis=-1), np.mean((run - run.mean(axis=-1, keepdims=True)) ** 4, axis=-1)
    np.testing.assert_allclose(na4(run), m4 / m2**2, rtol=1e-12)
    np.testing.assert_allclose(na4(run[4], m2[:4]), m4[4] / m2.mean() ** 2, rtol=1e-12)
    along = na4(run, run_axis=0)
    expected = [m4[j] / m2[:j + 1].mean() ** 2 for j in range(5)]
    np.testing.assert_allclose(along, expected, rtol=1e-12)
    assert along[0] == pytest.approx(m4[0] / m2[0] ** 2)
    assert np.all(along[1:] > m4[1:] / m2[1:] ** 2)  # a growing variance raises NA4 over FM4
    same = na4(run[2], np.full(3, m2[2]))
    assert same == pytest.approx(m4[2] / m2[2] ** 2, rel=1e-12)
    x = np.tile(revolution(), (3, 3))
    out = indicators(x, FS, F1, Z, run_axis=0)
    res = tsa_components(x, FS, F1, Z)["residual"]
    np.testing.assert_allclose(out["na4"], na4(res, run_axis=0), rtol=1e-12)
    with pytest.raises(ValueError, match="not both"):
        na4(run, m2[:2], run_axis=0)


def test_the_shaft_rate_is_read_from_the_mesh_line():
    """Records at 9.7, 10.0 and 10.6 Hz (nominal 10 Hz; off-bin mesh lines), with a second mesh
    harmonic, a shaft line and noise: the speed within a fraction of the mesh line's resolution
    fs / (n z) (the exact projection on its mesh comb)."""
    rng = np.random.default_rng(4)
    true = np.array([9.7, 10.0, 10.6])
    n = 4096
    t = np.arange(n) / FS
    f = true[:, None]
    x = (np.cos(2 * np.pi * Z * f * t + 0.4) + 0.4 * np.cos(2 * np.pi * 2 * Z * f * t)
         + 0.3 * np.cos(2 * np.pi * f * t) + 0.05 * rng.standard_normal((3, n)))
    est = shaft_rate_from_spectrum(x, FS, Z, 10.0)
    resolution = FS / n / Z
    assert np.all(np.abs(est - true) < 0.05 * resolution)
    assert shaft_rate_from_spectrum(x[1], FS, Z, 9.6) == pytest.approx(est[1])


def test_shaft_orders_take_a_run_out_out_of_the_difference_and_residual_signals():
    """A strong once-per-revolution run-out stays in the difference signal by default and
    pulls FM4 towards a sine's 1.5; shaft_orders=1 removes order 1 (Zakrajsek et al. 1993:
    "shaft frequency and harmonics") and FM4 reads the local fault again."""
    theta = np.arange(3 * N) / N
    x = np.tile(revolution(), 3) + 5.0 * np.cos(2 * np.pi * theta + 0.2)
    kept, removed = (indicators(x, FS, F1, Z, shaft_orders=s) for s in (0, 1))
    parts = tsa_components(x, FS, F1, Z, shaft_orders=1)
    for name in ("difference", "residual"):
        assert abs(np.fft.rfft(parts[name])[1]) < 1e-9
    assert kept["fm4"] < 2.0 < 10.0 < removed["fm4"]
    assert removed["fm4"] == pytest.approx(indicators(np.tile(revolution(), 3), FS, F1, Z,
                                                      shaft_orders=1)["fm4"], rel=1e-9)
    prior = np.var(parts["residual"]) * np.ones(4)  # a run of four like records before
    assert indicators(x, FS, F1, Z, shaft_orders=1, prior_residual_variances=prior)["na4"] == (
        pytest.approx(removed["na4"], rel=1e-9))


GOOD = {"x": np.tile(revolution(), 3), "fs": FS, "f_shaft": F1, "z": Z}
BAD = [
    ({"x": np.where(np.arange(3 * N) == 5, np.nan, 1.0)}, "NaN"),
    ({"x": np.tile(revolution(), 3)[:N + 10]}, "revolutions"),
    ({"fs": 0.0}, "fs = 0.0"),
    ({"fs": -FS}, "fs = "),
    ({"f_shaft": float("nan")}, "f_shaft = nan"),
    ({"z": 4}, "z = 4"),
    ({"z": 16.5}, "z = 16.5"),
    ({"z": 200}, "below fs / 2"),
    ({"x": np.zeros(3 * N)}, "constant"),
]


@pytest.mark.parametrize(("change", "message"), BAD)
def test_bad_input_is_refused_naming_the_value_and_the_fix(change, message):
    args = GOOD | change
    with pytest.raises(ValueError, match=message):
        indicators(args["x"], args["fs"], args["f_shaft"], args["z"])


def test_bad_options_are_refused():
    x = GOOD["x"]
    with pytest.raises(ValueError, match="bins = 20"):
        indicators(x, FS, F1, Z, bins=20)
    with pytest.raises(ValueError, match="shaft_orders = 15"):
        indicators(x, FS, F1, Z, shaft_orders=15)
    with pytest.raises(ValueError, match="rel_band = 0"):
        shaft_rate_from_spectrum(x, FS, Z, F1, rel_band=0)
    with pytest.raises(ValueError, match="longer record"):
        shaft_rate_from_spectrum(x[:64], FS, Z, F1)
    with pytest.raises(ValueError, match=r"below 0\.45 fs"):
        shaft_rate_from_spectrum(x, FS, Z, 80.0)
    # a mesh line between 0.45 and 0.5 fs: no harmonic in the band the comb is read in
    with pytest.raises(ValueError, match="where the mesh harmonics are read"):
        shaft_rate_from_spectrum(x, FS, Z, 0.47 * FS / Z, rel_band=0.02)
