"""The measured-data loop: bundles, order analysis, the effect library's signatures, the loop."""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import signal

from physics.dynamics.model import build_model, simulate
from physics.loop import (
    EFFECTS,
    STABLE_KEYS,
    LoopSettings,
    effect,
    read_bundle,
    read_feature_table,
    run_loop,
    write_bundle,
)
from physics.loop.measured.records import prepare, shaft_rates, split_records
from physics.loop.model.comparison import residuals, residuals_db, rms
from physics.loop.model.declared import (
    DYNAMIC_NUISANCE,
    completed,
    declared_modes,
    declared_nuisance,
)
from physics.loop.model.simulation import model_signals, responses
from physics.loop.search import fit
from physics.loop.search.attribution import (
    candidates_for,
    free_directions,
    lowest_fits,
    separable_share,
)
from physics.loop.search.fit import (
    Candidate,
    calibrate,
    identifiable,
    recalibrated,
    search,
    train_cost,
    with_level,
)
from physics.loop.search.wear_reading import wear_skill
from physics.loop.table_loop import parse_columns
from physics.params import scenario_from_config
from physics.signals.order_analysis import (
    line_amplitudes,
    mean_signatures,
    power_spectrum,
    signature_names,
    signature_segments,
    synchronous_average,
    white_noise_std,
)
from physics.testbeds import make_bundle
from tests.acceptance.refusal import refusal, tree

ROOT = Path(__file__).resolve().parents[2]
FS = 40960.0


@pytest.fixture(scope="module")
def scn():
    return scenario_from_config({"case": 3})


@pytest.fixture(scope="module")
def healthy(scn):
    return build_model(scn)


def response(models, scn, seconds=0.25):
    dyn = dataclasses.replace(scn.dynamics, duration_s=seconds, transient_s=0.05, phase_bins=16)
    return simulate(models, dyn)


# --- bundles ---------------------------------------------------------------------------------

def manifest(n=3, **over):
    d = {"record": [f"r{i}" for i in range(n)], "quantity": "accel_m_s2", "fs_hz": FS,
         "n1_rpm": 2000.0, "torque_Nm": 300.0, "wear_mm": 0.0, "cycles": 0.0, "split": ""}
    d.update(over)
    return pd.DataFrame(d)


def good_signals(n=3, seconds=0.5):
    rng = np.random.default_rng(0)
    return {f"r{i}": rng.standard_normal(int(seconds * FS)) for i in range(n)}


def test_bundle_round_trip(tmp_path):
    path = write_bundle(tmp_path / "b", manifest(), good_signals(), gear={"z1": 18})
    b = read_bundle(path)
    assert b.records == ["r0", "r1", "r2"] and b.gear == {"z1": 18}
    np.testing.assert_array_equal(b.signals["r1"], good_signals()["r1"])


def _drop_signal(m, s):
    del s["r2"]
    return m


def _nan_sample(m, s):
    s["r0"][5] = np.nan
    return m


def _short(m, s):
    s["r1"] = s["r1"][:1000]
    return m


@pytest.mark.parametrize("change, rule", [
    (lambda m, s: m.drop(columns="fs_hz"), "column(s) ['fs_hz'] missing"),
    (lambda m, s: m.assign(quantity=["accel_m_s2", "velocity", "accel_m_s2"]),
     "record 'r1': quantity 'velocity'"),
    (_drop_signal, "record 'r2': signals/r2.npy is missing"),
    (_nan_sample, "record 'r0': non-finite sample at index 5"),
    (_short, "record 'r1': 0.8 pinion revolutions"),
    (lambda m, s: m.assign(fs_hz=[FS, FS, 5000.0]), "record 'r2': fs_hz = 5000 is below 4 x"),
    (lambda m, s: m.assign(record=["r0", "r0", "r2"]), "record 'r0': record names must be unique"),
    (lambda m, s: m.assign(split=["train", "valid", ""]), "record 'r1': split 'valid'"),
    (lambda m, s: m.assign(wear_mm=[0.0, -1.0, 0.0]), "record 'r1': wear_mm = -1.0"),
])
def test_bad_bundle_is_refused_naming_record_and_rule(tmp_path, change, rule):
    sig = good_signals()
    man = change(manifest(), sig)
    path = write_bundle(tmp_path / "b", man, sig)
    with pytest.raises(ValueError) as err:
        read_bundle(path)
    assert rule in str(err.value)


def test_write_bundle_leaves_nothing_on_failure(tmp_path):
    with pytest.raises(ValueError):
        write_bundle(tmp_path / "b", manifest(), {"r0": np.zeros(10), "r1": "not a signal"})
    assert list(tmp_path.iterdir()) == []


def test_split_is_by_record_and_honours_the_manifest():
    man = manifest(10, split=["test"] + [""] * 8 + ["train"])
    train, test = split_records(man, 0.3, seed=1)
    assert 0 in test and 9 in train
    assert set(train).isdisjoint(test) and len(train) + len(test) == 10
    with pytest.raises(ValueError, match="at least one train and one test"):
        split_records(manifest(2, split=["train", "train"]), 0.3, 0)


def test_feature_tables_of_the_thesis_parse(tmp_path):
    # the headers of thesis Tables 15 (housing acceleration) and 14 (DTE, in 1e-5 m)
    table15 = tmp_path / "t15.csv"
    table15.write_text("wear_mm,rms_m_per_s2,peak_to_peak_m_per_s2,kurtosis,crest,margin,impulse\n"
                       "0,1.0,16.0,4.3,8.9,14.0,11.6\n")
    q, cols = parse_columns(read_feature_table(table15))
    assert q == "accel_m_s2" and cols["peak_to_peak_m_per_s2"] == ("peak_to_peak", 1.0)
    table14 = pd.DataFrame(columns=["cycles_1e6", "wear_mm", "rms_1e-5_m", "peak_to_peak_1e-5_m",
                                    "kurtosis", "crest", "margin", "impulse"])
    q, cols = parse_columns(table14)
    assert q == "dte_m" and cols["rms_1e-5_m"] == ("rms", 1e-5)
    with pytest.raises(ValueError, match="'energy' is not a Table 13 feature"):
        parse_columns(pd.DataFrame({"wear_mm": [0.0], "energy": [1.0], "rms_m": [1.0]}))


# --- order analysis --------------------------------------------------------------------------

@settings(max_examples=25, deadline=None)
@given(st.floats(20.0, 2500.0), st.floats(0.1, 10.0), st.floats(0.0, 2 * math.pi))
def test_line_amplitude_of_an_off_bin_sinusoid(f, a, phase):
    # both tones below 0.45 fs (7.3 x 2500 Hz = 18.3 kHz): above Nyquist the second one
    # aliases, at f = 4934 Hz to 8 Hz from the first
    t = np.arange(8192) / FS
    x = a * np.sin(2 * np.pi * f * t + phase) + 0.5 * a * np.sin(2 * np.pi * 7.3 * f * t)
    amp = line_amplitudes(x, FS, np.array([f, 7.3 * f]))
    np.testing.assert_allclose(amp, [a, 0.5 * a], rtol=0.02)

@settings(max_examples=25, deadline=None)
@given(st.integers(3, 3000), st.integers(1, 40), st.integers(0, 2**32 - 1))
def test_the_blocked_line_projection_is_the_whole_records_projection(n, lines, seed):
    # any length (shorter than a block, not a multiple of it): the same amplitudes as the
    # Hann-windowed projection on exp(i w t) over the whole record, in double precision
    rng = np.random.default_rng(seed)
    x = rng.standard_normal((2, n)) + 3.0
    freqs = rng.uniform(0.0, FS / 2, lines)
    t = np.arange(n) / FS
    w = np.hanning(n)
    direct = np.abs((x - x.mean(axis=1, keepdims=True))
                    @ (np.exp(2j * np.pi * np.outer(t, freqs)) * (2 * w / w.sum())[:, None]))
    np.testing.assert_allclose(line_amplitudes(x, FS, freqs), direct, rtol=1e-4, atol=1e-6)



@settings(max_examples=25, deadline=None)
@given(st.integers(1, 5000), st.floats(-1e3, 1e3), st.integers(0, 2**32 - 1))
def test_power_spectrum_is_scipys_hann_periodogram(n, offset, seed):
    x = offset + np.random.default_rng(seed).standard_normal(n)
    f, p = power_spectrum(x, FS)
    f_ref, p_ref = signal.periodogram(x, FS, window="hann", detrend="constant",
                                      scaling="spectrum")
    np.testing.assert_allclose(f, f_ref)
    np.testing.assert_allclose(p, p_ref, rtol=1e-9, atol=1e-12 * max(p_ref.max(), 1e-300))


@pytest.mark.parametrize("bin_", [7, 100, 2000])
def test_power_spectrum_peak_of_an_on_bin_sinusoid_is_its_mean_square(bin_):
    n, a = 4096, 3.0
    x = a * np.cos(2 * np.pi * bin_ * np.arange(n) / n + 0.4)
    _, p = power_spectrum(x, FS)
    assert p[bin_] == pytest.approx(a**2 / 2, rel=1e-12)  # the 'spectrum' scaling
    # periodic Hann: each neighbour has half the peak's amplitude, the other bins nothing
    np.testing.assert_allclose(p[[bin_ - 1, bin_ + 1]], a**2 / 2 / 4, rtol=1e-9)
    assert np.delete(p, [bin_ - 1, bin_, bin_ + 1]).max() < 1e-20 * a**2


def test_noise_floor_under_dense_lines():
    rng = np.random.default_rng(3)
    t = np.arange(int(FS)) / FS
    lines = sum(np.sin(2 * np.pi * 33.3 * k * t + k) * 50 / k for k in range(1, 400))
    est = white_noise_std(lines + 2.0 * rng.standard_normal(t.size), FS, 300.0)
    assert est == pytest.approx(2.0, rel=0.1)


def test_synchronous_average_keeps_the_periodic_part_and_averages_noise_out():
    rng = np.random.default_rng(4)
    f1, t = 25.0, np.arange(int(2 * FS)) / FS
    periodic = np.sin(2 * np.pi * 18 * f1 * t)
    avg = synchronous_average(periodic + rng.standard_normal(t.size), FS, f1, bins=256)
    ref = np.sin(2 * np.pi * 18 * np.arange(256) / 256)
    assert np.sqrt(np.mean((avg - ref) ** 2)) < 0.25  # noise 1 averaged over 50 revolutions


@settings(max_examples=15, deadline=None)
@given(rows=st.integers(1, 4), f1=st.floats(10.0, 60.0), seed=st.integers(0, 2**16))
def test_synchronous_average_of_a_batch_is_linear_interpolation_row_by_row(rows, f1, seed):
    """Against np.interp (an independent resampler) row by row: the vectorised resampling
    reads the same points, the last revolution included."""
    x = np.random.default_rng(seed).standard_normal((rows, int(0.3 * FS)))
    t = np.arange(x.shape[1]) / FS
    n_rev = int(x.shape[1] / FS * f1)
    grid = np.arange(n_rev * 64) / (64 * f1)
    ref = [np.interp(grid, t, r).reshape(n_rev, 64).mean(axis=0) for r in x]
    np.testing.assert_allclose(synchronous_average(x, FS, f1, bins=64), ref, atol=1e-12)


def test_signatures_of_a_batch_equal_those_of_each_record_alone():
    """Batching is a matter of speed: each record's mean signature is the same whether its
    segments are analysed with other records' or alone (to the single-precision rounding of
    the line projection, far below an entry's noise scatter of tenths of a dB)."""
    rng = np.random.default_rng(5)
    f1, f2, z1 = 25.0, 25.0 * 18 / 27, 18
    t = np.arange(int(0.5 * FS)) / FS
    xs = [np.sin(2 * np.pi * z1 * f1 * t + k) * (1 + k) + 0.3 * rng.standard_normal(t.size)
          for k in range(3)] + [rng.standard_normal(int(0.25 * FS))]
    batch = mean_signatures(xs, FS, f1, f2, z1, False, 0.25)
    alone = [signature_segments(x, FS, f1, f2, z1, False, 0.25).mean(axis=0) for x in xs]
    assert batch.shape == (4, len(signature_names(f1, f2, z1, FS, False)))
    np.testing.assert_allclose(batch, alone, atol=1e-3)


# --- the effect library: each effect's physical signature -------------------------------------

def test_friction_reverses_at_the_pitch_point(healthy):
    m = effect("friction").model(healthy, {"mu": 0.06})
    g = healthy.geometry
    n = len(healthy.k_a)
    s_a = g.s_start + g.base_pitch * np.arange(n) / n
    lam = m.lam_a - 1
    # approach (s < 0): the pinion flank is the slower one, friction aids the pinion and brakes
    # the gear, so the pair's force counts less in the relative equation; recess: the reverse
    assert np.all(lam[s_a < -1e-5] < 0) and np.all(lam[s_a > 1e-5] > 0)
    assert np.abs(lam).max() < 0.2  # a few per cent of the mesh force for mu = 0.06


def test_tip_relief_lowers_the_mesh_harmonic_at_design_load(scn, healthy):
    relieved = effect("tip_relief").model(healthy, {"relief_um": 10.0})
    r = response([healthy, relieved], scn)
    fm = healthy.mesh_frequency_hz
    a = line_amplitudes(r.dte, FS, np.array([fm]))[:, 0]
    assert a[1] < 0.8 * a[0]


def test_gear_runout_raises_the_gear_sidebands(scn, healthy):
    ran = effect("gear_runout").model(healthy, {"runout_um": 20.0})
    r = response([healthy, ran], scn, 0.5)
    f2 = healthy.omega1 * healthy.geometry.rb1 / healthy.geometry.rb2 / (2 * np.pi)
    fm = healthy.mesh_frequency_hz
    side = np.array([k * fm + s * f2 for k in range(8, 20) for s in (-1, 1)])
    a = line_amplitudes(r.force, FS, side).sum(axis=1)
    assert a[1] > 10 * a[0]


def test_gear_runout_converges_under_step_halving(scn, healthy):
    """The run-out moves the entry of each pair along the path of contact (later while the
    centres part, earlier while they close: both within 0.07 s). The moved entry keeps the
    stiffness continuous in time, so halving the RK4 step shrinks the change by at least
    3 (it is second order at the entry's kinks; measured 4.1, and 0.5 % of the DTE's range).
    A switch at the step's instants gave 2.0 and 3.3 %."""
    ran = effect("gear_runout").model(healthy, {"runout_um": 50.0})
    dte = []
    for factor in (0.5, 0.25, 0.125):
        dyn = dataclasses.replace(scn.dynamics, duration_s=0.05, transient_s=0.02,
                                  step_factor=factor)
        dte.append(simulate(ran, dyn).dte[0])
    d1, d2 = np.max(np.abs(dte[0] - dte[1])), np.max(np.abs(dte[1] - dte[2]))
    assert d2 < d1 / 3
    assert d2 < 1e-2 * np.ptp(dte[2])


def test_torque_ripple_shows_at_its_shaft_order(scn, healthy):
    rip = effect("torque_ripple").model(healthy, {"ripple_pct": 5.0, "order": 2})
    r = response([healthy, rip], scn, 0.5)
    a = line_amplitudes(r.force, FS, np.array([2 * healthy.omega1 / (2 * np.pi)]))[:, 0]
    assert a[1] > 0.5 * 0.05 * healthy.static_force > 20 * a[0]


def test_tooth_defect_is_once_per_revolution(scn, healthy):
    pit = effect("tooth_defect").model(healthy, EFFECTS["tooth_defect"].defaults())
    assert pit.periods == 18 and len(pit.k_a) == 18 * len(healthy.k_a)
    f1, fm = healthy.omega1 / (2 * np.pi), healthy.mesh_frequency_hz
    # below the mesh resonance the force cannot follow a once-per-revolution event; it shows
    # as pinion sidebands of the mesh harmonics near the resonance
    side = np.array([k * fm + j * f1 for k in range(8, 20) for j in (-2, -1, 1, 2)])
    a = [line_amplitudes(response([m], scn, 0.5).force[0], FS, side).sum()
         for m in (healthy, pit)]
    assert a[1] > 3 * a[0]


def test_a_shorter_pit_is_a_sharper_impulse(healthy):
    """The stiffness a pit takes over the pinion's revolution is a cos^2 bump in roll: its
    spectrum's centroid over the revolution's orders scales as one over the pit's length."""

    def centroid(length_mm):
        values = EFFECTS["tooth_defect"].defaults() | {"length_mm": length_mm}
        pit = effect("tooth_defect").model(healthy, values)
        lost = sum(np.tile(getattr(healthy, k), pit.periods) - getattr(pit, k)
                   for k in ("k_a", "k_b"))
        power = np.abs(np.fft.rfft(lost))[1:] ** 2
        order = np.arange(1, len(power) + 1)
        return float(np.sum(order * power) / np.sum(power))

    assert centroid(0.5) / centroid(2.0) == pytest.approx(4.0, rel=0.05)


def test_a_grown_pit_keeps_its_length():
    """A feature table's wear-grown pit scales its depth and face share with the wear; its
    length along the profile, a shape, and its centre stay."""
    pit = EFFECTS["tooth_defect"]
    v = pit.defaults()
    half = pit.scaled(v, 0.5)
    assert half["depth_um"] == 0.5 * v["depth_um"] and half["face_share"] == 0.5 * v["face_share"]
    assert half["length_mm"] == v["length_mm"] and half["centre_mm"] == v["centre_mm"]


@pytest.mark.parametrize("centre_mm", [-3.0, -2.0, -0.5])  # on pair A's stretch
def test_tooth_defect_sits_where_its_centre_says_and_spans_its_length(healthy, centre_mm):
    """The pit lowers tooth 0's stiffness around its centre on the roll coordinate, over its
    length, and nowhere else on the flank."""
    g = healthy.geometry
    values = EFFECTS["tooth_defect"].defaults() | {"centre_mm": centre_mm, "length_mm": 1.0}
    pit = effect("tooth_defect").model(healthy, values)
    n = len(healthy.k_a)
    s = g.s_start + g.base_pitch * np.arange(n) / n  # roll of pair A over one mesh period
    lost = 1 - pit.k_a[:n] / healthy.k_a  # tooth 0 is pair A of the first period
    assert s[np.argmax(lost)] == pytest.approx(centre_mm * 1e-3, abs=g.base_pitch / n)
    off = np.abs(s - centre_mm * 1e-3)
    assert np.all(lost[off >= 0.5e-3] < 1e-12)
    assert np.all(lost[off < 0.45e-3] > 0.0)  # over its whole length
    assert lost.max() == pytest.approx(values["face_share"], rel=1e-2)


def test_the_pit_is_on_one_tooth_of_the_mesh_sequence(healthy):
    """The pitted tooth is pinion tooth 0 of the mesh sequence (physics.dynamics.teeth): pair A
    of the first mesh period and pair B of the second, where it has moved on; every other
    period's tables are the healthy tooth's, and a pit of no depth on no face is no pit."""
    from physics.dynamics.model_form import revolution_tables

    n, rev, g = len(healthy.k_a), revolution_tables(healthy), healthy.geometry
    across = {"centre_mm": (g.s_start + g.base_pitch) * 1e3}  # on both pairs' stretches
    pit = effect("tooth_defect").model(healthy, EFFECTS["tooth_defect"].defaults() | across)
    for name, period in (("k_a", 0), ("g_a", 0), ("k_b", 1), ("g_b", 1)):
        moved = np.flatnonzero(np.any((getattr(pit, name) != getattr(rev, name)).reshape(-1, n),
                                      axis=1))
        assert moved.tolist() == [period], name
    none = EFFECTS["tooth_defect"].defaults() | {"depth_um": 0.0, "face_share": 0.0}
    nothing = effect("tooth_defect").model(healthy, none)
    for name in ("k_a", "k_b", "g_a", "g_b"):
        np.testing.assert_array_equal(getattr(nothing, name), getattr(rev, name))


def test_transfer_path_peaks_at_its_mode():
    fn, zeta = 3000.0, 0.05
    t = np.arange(int(FS)) / FS
    amp = []
    for f in (300.0, fn):
        y = effect("transfer_path").record(np.sin(2 * np.pi * f * t), FS,
                                           {"fn_hz": fn, "zeta": zeta, "residue": 1.0})
        amp.append(line_amplitudes(y[4096:], FS, np.array([f]))[0])
    # base-excited SDOF transmissibility: ~1 well below f_n, sqrt(1 + (2 zeta)^2) / (2 zeta) at f_n
    assert amp[0] == pytest.approx(1.0, abs=0.02)
    assert amp[1] == pytest.approx(math.sqrt(1 + (2 * zeta) ** 2) / (2 * zeta), rel=0.03)


def test_backlash_growth_and_sensor_gain(healthy):
    worn = dataclasses.replace(healthy, g_a=healthy.g_a + 10e-6)
    grown = effect("backlash_growth").model(worn, {"kappa": 2.0})
    assert grown.half_backlash - worn.half_backlash == pytest.approx(10e-6)
    x = np.arange(5.0)
    np.testing.assert_allclose(effect("sensor").record(x, FS, {"gain": 1.3}), 1.3 * x)


def test_unknown_effect_and_candidates_are_refused():
    with pytest.raises(ValueError, match="'rust' is not in the library"):
        effect("rust")
    with pytest.raises(ValueError, match=r"loop.candidates = \['rust'\]"):
        candidates_for({"accel_m_s2"}, LoopSettings(candidates=("rust",)))
    names = {e.name for e, _ in candidates_for({"accel_m_s2"}, LoopSettings())}
    assert "sensor" not in names and "transfer_path" in names


# --- calibration and search ------------------------------------------------------------------

@pytest.fixture(scope="module")
def clean_records(tmp_path_factory, scn):
    """A clean acceleration bundle (nuisance off its defaults) prepared for the loop."""
    path, truth = make_bundle(tmp_path_factory.mktemp("clean") / "b", scn, None, seed=3,
                              records=4, duration_s=0.5)
    return prepare(read_bundle(path), scn, LoopSettings(seed=3)), truth


def test_shaft_rate_error_on_the_line_of_action_is_not_identifiable(clean_records, scn):
    # far below the mesh resonance the gears follow a once-per-revolution error as rigid
    # bodies: it makes no force, so the calibration must hold it, not fit noise into it
    rec, _ = clean_records
    free = identifiable(rec, declared_nuisance(scn), DYNAMIC_NUISANCE)
    assert free[:2] == ["damping_ratio", "profile_error_um"]
    # nor is the backlash where the flanks never part (acceleration records do not see the
    # DTE's datum), nor the phase of a mesh modulation that is not there
    assert not {"eccentricity1_um", "half_backlash_um", "modulation_phase_rad"} & set(free)
    # the mesh's form moves every record: level, ratio, resonance and its modulation
    assert free[2:] == ["stiffness_factor", "resonance_factor", "double_contact_factor",
                        "mesh_modulation"]


def test_level_step_recovers_the_housing_mass(clean_records):
    # m_h only scales the record: one level step from a factor of 4 off lands within 30 % of
    # the truth (the model's noise does not scale with it: a start, not the fit)
    rec, truth = clean_records
    m_h = truth["nuisance"]["housing_mass_kg"]
    for factor in (0.25, 4.0):
        levelled = with_level(rec, truth["nuisance"] | {"housing_mass_kg": factor * m_h}, None,
                              {})
        assert 1 / 1.3 < levelled["housing_mass_kg"] / m_h < 1.3


def test_chain_parameters_reuse_the_simulation(clean_records):
    rec, truth = clean_records
    nui = truth["nuisance"]
    rec.cache.clear()
    first = responses(rec, rec.train, nui, None, {})
    assert len(rec.cache) == 1
    again = responses(rec, rec.train, nui | {"housing_mass_kg": 3.0}, None, {})
    assert again is first  # m_h acts after the dynamics: no new simulation
    moved = responses(rec, rec.train, nui | {"damping_ratio": 0.5 * nui["damping_ratio"]},
                      None, {})
    assert moved is not first
    # the residual over all records is smallest at the true nuisance (one record alone can
    # favour a neighbour: its segments' scatter is the only noise estimate)
    every = np.arange(len(rec.models))

    def misfit(n):
        return rms(residuals(rec, every, model_signals(rec, every, n, None, {})))

    for moved in ({"damping_ratio": 0.5 * nui["damping_ratio"]},
                  {"damping_ratio": 2 * nui["damping_ratio"]},
                  {"housing_mass_kg": 2 * nui["housing_mass_kg"]}):
        assert misfit(nui) < misfit(nui | moved)


def test_a_calibration_off_its_best_fit_is_moved_by_a_candidates_nuisance(clean_records):
    """The null test weighs a candidate against the declared model's best fit: where the
    declared model refitted from a candidate's nuisance fits the train records better than
    the calibration, that refit replaces it; from its own minimum a refit gains nothing."""
    rec, truth = clean_records
    free = ["damping_ratio", "profile_error_um", "housing_mass_kg"]
    best = truth["nuisance"]
    off = best | {"damping_ratio": 3.0 * best["damping_ratio"],
                  "profile_error_um": 0.3 * best["profile_error_um"]}
    moved = recalibrated(rec, off, best, free)
    assert moved is not None and set(moved) == set(best)
    assert train_cost(rec, moved, None, {}) < 0.5 * train_cost(rec, off, None, {})
    assert moved["damping_ratio"] == pytest.approx(best["damping_ratio"], rel=0.2)
    assert recalibrated(rec, moved, moved, free) is None
    assert recalibrated(rec, off, best, []) is None  # nothing free (a held calibration)


def test_a_rerun_round_keeps_each_candidates_lower_fit():
    """After a recalibration every candidate is fitted again from the new calibration; where
    its fit of the earlier round is lower on the same train records, that one is kept (a
    copy: its judgement is made afresh), matched by effect and option."""
    def cand(name, option, rss):
        return Candidate(name, option, {"x": rss}, {}, rss, 1, heldout=rss)

    now = [cand("friction", {}, 10.0), cand("torque_ripple", {"order": 1}, 5.0),
           cand("torque_ripple", {"order": 2}, 7.0)]
    before = [cand("friction", {}, 8.0), cand("torque_ripple", {"order": 1}, 6.0),
              cand("tip_relief", {}, 1.0)]
    kept = lowest_fits(now, before)
    assert [c.train_rss for c in kept] == [8.0, 5.0, 7.0]
    assert kept[0] is not before[0] and kept[0].values == {"x": 8.0}
    assert kept[1] is now[1] and kept[2] is now[2]
    assert [c.name for c in kept] == ["friction", "torque_ripple", "torque_ripple"]
    assert lowest_fits(now, ()) == now


def test_calibration_finds_a_declared_support_mode(tmp_path):
    # the records carry a bearing-support mode 0.6-1.6 times the declared one; calibrated with
    # m_h (explored around the declared value), it is found where the records have it
    scn = scenario_from_config({"case": 3, "dynamics": {"support_hz": 3000.0}})
    path, truth = make_bundle(tmp_path / "b", scn, None, seed=4, records=4, duration_s=0.5)
    rec = prepare(read_bundle(path), scn, LoopSettings(seed=4, explore=8, max_nfev=8))
    nuisance, free = calibrate(rec, declared_nuisance(scn) | declared_modes(scn))
    assert {"housing_mass_kg", "support_hz", "support_damping"} <= set(free)
    assert nuisance["support_hz"] == pytest.approx(truth["nuisance"]["support_hz"], rel=0.05)
    assert declared_modes(scenario_from_config({"case": 3})) == {}  # rigid by default


def test_a_support_mode_outside_the_loop_bounds_is_refused_before_work(clean_records):
    rec, _ = clean_records
    bad = scenario_from_config({"case": 3, "dynamics": {"support_hz": 50.0}})
    with pytest.raises(ValueError, match=r"dynamics.support_hz = 50.0 must lie in \[200, "
                                         r"20000\].*support_hz=0"):
        run_loop(rec.bundle, bad)
    bad = scenario_from_config({"case": 3, "dynamics": {"mount_hz": 150.0,
                                                        "mount_damping": 0.9}})
    with pytest.raises(ValueError, match=r"dynamics.mount_damping = 0.9 must lie in \[0.02, "
                                         r"0.5\].*mount_hz=0"):
        run_loop(rec.bundle, bad)


def test_a_stated_mounting_mode_is_held_and_lowers_the_shaft_lines(tmp_path):
    # a housing on mounts at 90 Hz: the mode is stated, not calibrated (m_h is); the model's
    # shaft-order lines fall with it, its mesh harmonics stay
    scn = scenario_from_config({"case": 3, "dynamics": {"mount_hz": 90.0}})
    path, _ = make_bundle(tmp_path / "b", scn, None, seed=4, records=4, duration_s=0.5)
    rec = prepare(read_bundle(path), scn, LoopSettings(seed=4, explore=8, max_nfev=8))
    nuisance, free = calibrate(rec, declared_nuisance(scn) | declared_modes(scn))
    assert "housing_mass_kg" in free and not {"mount_hz", "mount_damping"} & set(free)
    assert (nuisance["mount_hz"], nuisance["mount_damping"]) == (90.0, 0.1)
    # a torque ripple at the pinion order puts a line at f1 into the mesh force
    free_housing = {k: v for k, v in nuisance.items() if not k.startswith("mount")}
    ripple, values = effect("torque_ripple"), {"ripple_pct": 10.0, "order": 1}
    idx = rec.train[:1]
    mounted, free_res = (residuals_db(rec, idx, model_signals(rec, idx, n, ripple, values))[0]
                         for n in (nuisance, free_housing))
    names = rec.group(idx[0]).names
    shaft, mesh = names.index("line_shaft1"), names.index("line_mesh1")
    f1 = shaft_rates(rec.scenarios[idx[0]])[0]
    # measured minus model: the model's line lower by the mount's gain, by hand
    r = f1 / 90.0
    gain = r * r / math.hypot(1 - r * r, 2 * 0.1 * r)
    assert mounted[shaft] - free_res[shaft] == pytest.approx(-20 * math.log10(gain), abs=0.5)
    assert mounted[mesh] == pytest.approx(free_res[mesh], abs=0.5)


@settings(max_examples=40, deadline=None)
@given(st.integers(20, 60), st.integers(1, 5), st.floats(0.0, 10.0), st.integers(0, 2**31))
def test_separable_share_is_the_part_outside_the_span(n, k, weight, seed):
    rng = np.random.default_rng(seed)
    d = rng.standard_normal((n, k))
    inside = d @ rng.standard_normal(k)
    q, _ = np.linalg.qr(np.column_stack([d, rng.standard_normal(n)]))
    outside = q[:, -1] * np.linalg.norm(inside)  # orthogonal to every column of d
    assert separable_share(d, inside) < 1e-9
    assert separable_share(d, outside) == pytest.approx(1.0)
    expected = weight**2 / (1 + weight**2)  # Pythagoras: the parts are orthogonal
    assert separable_share(d, 3.0 * (inside + weight * outside)) == pytest.approx(expected)
    assert separable_share(d[:, :0], inside) == 1.0


def test_a_dte_gain_is_not_separable_from_the_stiffness_level(tmp_path, scn):
    """The lengths scale out of the equation of motion (tests/dynamics): on unworn DTE
    records, a sensor gain is a stiffness level with the errors and the backlash scaled, so
    its change of the residuals lies in the span of those free parameters' directions; a
    once-per-revolution tooth defect's does not."""
    path, truth = make_bundle(tmp_path / "b", scn, None, seed=3, quantity="dte_m", records=4,
                              duration_s=0.5, cycles_max=1.0)
    rec = prepare(read_bundle(path), scn, LoopSettings(seed=3, model_form=True))
    nui = completed(truth["nuisance"], scn)  # the model form at its neutral values
    free = ["stiffness_factor", "eccentricity1_um", "profile_error_um", "half_backlash_um"]
    directions = free_directions(rec, nui, None, {}, free)
    base = residuals(rec, rec.train, model_signals(rec, rec.train, nui, None, {}))

    def share(name, values):
        moved = residuals(rec, rec.train, model_signals(rec, rec.train, nui, EFFECTS[name],
                                                        values))
        return separable_share(directions, moved - base)

    # (not exactly 0: the model's noise, added after the chain, is not scaled by the gain, and
    # the half-order lines of unworn records sit near that floor)
    assert share("sensor", {"gain": 1.3}) < 0.02
    assert share("tooth_defect", EFFECTS["tooth_defect"].defaults() | {"depth_um": 20.0}) > 0.9


def test_search_never_ends_above_its_start(clean_records, scn):
    # the declared model from a start off the truth: exploration keeps the best point, least
    # squares only accepts steps that lower the cost
    rec, truth = clean_records
    rec = dataclasses.replace(rec, settings=LoopSettings(seed=3, explore=4, max_nfev=3))
    start = truth["nuisance"] | {"damping_ratio": 2.5 * truth["nuisance"]["damping_ratio"]}
    c = Candidate("declared", {}, {}, start, train_cost(rec, start, None, {}), 0)
    fitted = search(rec, None, c, ["damping_ratio", "housing_mass_kg"])
    assert fitted.refined and fitted.train_rss <= c.train_rss
    assert train_cost(rec, fitted.nuisance, None, {}) == pytest.approx(fitted.train_rss)
    assert fitted.nuisance["profile_error_um"] == start["profile_error_um"]  # not free: kept


def test_a_second_start_never_ends_above_one(clean_records, monkeypatch):
    # the candidate's fit from the best explored point alone, and from the best two with the
    # lower fit kept: the first start is among the two, so two never end higher
    rec, truth = clean_records
    eff = EFFECTS["friction"]
    c = Candidate(eff.name, {}, eff.defaults(), truth["nuisance"], math.inf, 1)
    starts_fitted = []
    least_squares = fit.least_squares

    def counted(*args, **kwargs):
        starts_fitted.append(args[3])
        return least_squares(*args, **kwargs)

    monkeypatch.setattr(fit, "least_squares", counted)

    def fitted(starts: int) -> Candidate:
        settings = LoopSettings(seed=3, explore=4, max_nfev=3, starts=starts)
        return search(dataclasses.replace(rec, settings=settings), eff, c, ["damping_ratio"])

    one = fitted(1)
    assert len(starts_fitted) == 1
    two = fitted(2)
    # the second search refines the same first start and one more, a point of its own
    assert len(starts_fitted) == 3 and starts_fitted[1] == starts_fitted[0] != starts_fitted[2]
    assert two.train_rss <= one.train_rss
    assert train_cost(rec, two.nuisance, eff, two.values) == pytest.approx(two.train_rss)


@pytest.mark.parametrize("bad", [{"explore": 24}, {"explore": -2}, {"refine": 0},
                                 {"starts": 0}, {"starts": 1.5}])
def test_bad_search_settings_are_refused(bad):
    with pytest.raises(ValueError, match=rf"loop\.{next(iter(bad))} = "):
        LoopSettings(**bad)


def test_backlash_growth_leaves_records_without_contact_loss_unchanged(tmp_path, scn):
    # the flanks never separate at the Table 11 loads: the dead zone's width does not matter
    _, truth = make_bundle(tmp_path / "b", scn, "backlash_growth", seed=0, records=3,
                           duration_s=0.3, cycles_max=1e7)
    assert truth["effect_to_noise_db"] < -100
    _, truth = make_bundle(tmp_path / "t", scn, "tip_relief", seed=0, records=3,
                           duration_s=0.3, cycles_max=1e7)
    assert truth["effect_to_noise_db"] > 10


# --- the loop --------------------------------------------------------------------------------

# one candidate: no second round to stack on it (the loop must still report)
FAST = ["loop.max_nfev=6", "loop.explore=8", "loop.refine=1", "loop.candidates=[transfer_path]",
        "progress=false"]


def run_app(tmp: Path, data: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "physics.loop", f"data={data}",
                           f"hydra.run.dir={tmp / 'run'}", *extra], cwd=ROOT,
                          capture_output=True, text=True, timeout=600)


@pytest.mark.slow
def test_loop_app_finds_an_undeclared_transfer_path(tmp_path, scn):
    path, truth = make_bundle(tmp_path / "bundle", scn, "transfer_path", seed=2, records=6,
                              duration_s=0.75)
    run = run_app(tmp_path, path, *FAST)
    assert run.returncode == 0, run.stderr[-2000:]
    report = json.loads((tmp_path / "run" / "report.json").read_text())
    assert tuple(report)[:len(STABLE_KEYS)] == STABLE_KEYS  # one report type, stable keys
    assert report["chosen_effect"] == "transfer_path"
    assert report["verdict"] == "effect" and report["unexplained"] is None
    assert report["partial"] is None
    assert report["second_round"] is None
    # an effect named: no detection limits are sought
    assert report["detection_limits"] is None
    assert all(c["detection_limit"] is None for c in report["ranking"])
    verdict = report["verdicts"][0]  # every condition held
    assert verdict["adopted"] and all(c["holds"] for c in verdict["checks"].values())
    assert verdict["also_passing"] == []  # the only candidate
    # the adopted effect reads the wear: it kept the estimate's leave-one-out skill on the
    # train records
    reading = verdict["wear_reading"]
    assert reading["measure"] == "skill" and reading["holds"]
    assert reading["reads_with"] == report["wear_read_by"] == "the model with transfer_path"
    assert reading["value"] >= reading["before"] - report["decision_rule"]["max_wear_loss"]
    # read against the train records of its group, the held-out wear estimate is not taken
    # away by the undeclared effect (the same in every record) and the adopted one reads it at
    # least as well (measured: skill 0.72 -> 0.83)
    assert report["wear_skill_after"] > 0.8
    assert report["wear_skill_after"] >= report["wear_skill_before"]
    assert report["error_after"] < 0.5 * report["error_before"]
    # the run-out on the line of action is dynamically inert, and no amplitude of the signature
    # sees the phase of its mesh modulation without another once-per-revolution feature
    assert report["not_identifiable"] == ["eccentricity1_um", "modulation_phase_rad"]
    assert set(report["nuisance_after"]) == set(report["calibration"])
    fitted = report["chosen_parameters"]["fn_hz"]
    assert fitted == pytest.approx(truth["values"]["fn_hz"], rel=0.15)
    # each held-out record's estimate, as the skill was computed from (the guess: the mean
    # known wear of the train records)
    est = report["wear_estimates"]
    true, after = np.array(est["true_mm"]), np.array(est["after_mm"])
    assert est["records"] == report["test_records"] and len(est["before_mm"]) == len(true)
    man = read_bundle(path).manifest.set_index("record")
    train = man.loc[report["train_records"], "wear_mm"].to_numpy(float)
    assert wear_skill(after, true, train) == pytest.approx(report["wear_skill_after"])
    for name in ("report.md", "order_spectra.png", "residuals.png", "wear_estimates.png"):
        assert (tmp_path / "run" / name).stat().st_size > 0
    assert "| wear estimate's skill" in (tmp_path / "run" / "report.md").read_text()


def test_loop_app_refuses_bad_data_before_work(tmp_path, config_store):
    (tmp_path / "work").mkdir()
    err = refusal("loop", [f"data={tmp_path / 'nowhere'}"], tmp_path / "work")
    assert "is neither a bundle folder nor a feature-table .csv" in str(err)
    assert not tree(tmp_path / "work")


@pytest.mark.slow
def test_loop_adds_nothing_to_a_clean_bundle(tmp_path, scn):
    # the default fit: cut short (max_nfev=10), the calibration leaves a misfit that the
    # smallest pit of the library (0.5 um over 0.05 of the face) takes up in a few entries
    path, _ = make_bundle(tmp_path / "clean", scn, None, seed=5, records=8)
    report = run_loop(read_bundle(path), scn, LoopSettings())
    assert report["chosen_effect"] is None
    assert report["error_before"] < 1.6  # the calibrated model is at the noise


@pytest.mark.slow
@pytest.mark.parametrize("name", ["gear_runout", "friction", "tip_relief", "tooth_defect",
                                  "torque_ripple"])
def test_loop_names_the_undeclared_effect(tmp_path, scn, name):
    """Named, and the held-out error halved or brought to within 10 % of the data-generating
    model's own (where the effect raises it less than twofold, as a tip relief does, halving
    is not attainable: docs/loop.md)."""
    path, truth = make_bundle(tmp_path / name, scn, name, seed=7, records=10)
    report = run_loop(read_bundle(path), scn, LoopSettings(max_nfev=15))
    assert report["chosen_effect"] == name
    rec = report.signals["rec"]
    floor = rms(residuals(rec, rec.test, model_signals(rec, rec.test, truth["nuisance"],
                                                       EFFECTS[name], truth["values"])))
    assert report["error_after"] <= max(0.5 * report["error_before"], 1.1 * floor)


def test_a_candidate_that_only_moves_the_nuisance_is_judged_against_the_refitted_null(
        clean_records, scn, monkeypatch):
    """A clean bundle whose calibration is left off its best fit (damping three times the
    truth's): the candidate that takes the nuisance back is adopted against that calibration,
    the declared model refitted from its nuisance replaces it, and against the refit nothing
    is added; the report says the calibration was refitted."""
    import physics.loop.bundle_loop as loop

    rec, truth = clean_records
    best = truth["nuisance"]
    off = best | {"damping_ratio": 3.0 * best["damping_ratio"],
                  "profile_error_um": 0.3 * best["profile_error_um"]}
    free = ["damping_ratio", "profile_error_um", "housing_mass_kg"]
    monkeypatch.setattr(loop, "calibrate", lambda r, start: (dict(off), list(free)))
    settings = LoopSettings(seed=3, max_nfev=6, explore=8, refine=1, candidates=("friction",),
                            detection_limits=False)
    report = run_loop(rec.bundle, scn, settings)
    assert report["calibrated_on"].startswith("the train records, then refitted from the "
                                              "nuisance of friction")
    assert report["verdict"] != "effect" and report["chosen_effect"] is None
    cal = report["calibration"]
    assert train_cost(rec, cal, None, {}) < 0.5 * train_cost(rec, off, None, {})
