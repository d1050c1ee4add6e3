"""The pinion speed read off a record's spectrum (records without a tachometer): exact on a
comb made by hand whatever its speed, tooth number and phases (odd harmonics weaker: the
subharmonic rule), on records of a simulator none of the loop's code shares, never a wrong
speed judged clear, and white noise never read; a bundle's unknown speeds read and merged
into operating points, or refused naming what was found."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.loop.measured.bundle import SAME_SPEED, read_bundle, write_bundle
from physics.signals.shaft_speed import (
    MIN_COMB_DB,
    MIN_LINES,
    MIN_MARGIN_DB,
    pinion_speed,
)
from physics.testbeds.independent_simulator import (
    IndependentPair,
    make_independent_bundle,
    simulate_record,
)

FS = 40960.0
N = 20480  # 0.5 s


def _range(z1: int, n: int = N) -> tuple[float, float]:
    """The bundle's search range: 10 revolutions in the record, fs >= 12 z1 f1."""
    return 10 * FS / n, FS / (12 * z1)


def _comb(f1: float, z1: int, odd_db: float, rng: np.random.Generator) -> np.ndarray:
    """Mesh harmonics of ``f1`` below 0.45 fs (odd ones ``odd_db`` weaker), first sidebands
    at -20 dB, random phases, white noise 40 dB below the first harmonic's power."""
    t = np.arange(N) / FS
    x = np.zeros(N)
    for k in range(1, int(0.45 * FS // (z1 * f1)) + 1):
        a = 10 ** (-odd_db / 20) if k % 2 else 1.0
        for off, rel in ((0.0, 1.0), (-f1, 0.1), (f1, 0.1)):
            x += a * rel * np.cos(2 * np.pi * (k * z1 * f1 + off) * t + rng.uniform(0, 6.3))
    return x + 10 ** (-40 / 20) / np.sqrt(2) * rng.standard_normal(N)


@settings(max_examples=20, deadline=None)
@given(share=st.floats(0.0, 1.0), z1=st.integers(12, 40), odd_db=st.floats(0.0, 20.0),
       seed=st.integers(0, 2**16))
def test_a_comb_made_by_hand_is_read_at_its_speed(share, z1, odd_db, seed):
    """Any speed of the search range, any tooth number, odd mesh harmonics up to 20 dB weaker
    than the even ones (a speed twice as high would read the even ones alone)."""
    f_low, f_high = _range(z1)
    f1 = f_low + share * (f_high - f_low) * 0.98 + 0.01 * (f_high - f_low)
    est = pinion_speed(_comb(f1, z1, odd_db, np.random.default_rng(seed)), FS, z1, f_low,
                       f_high)
    assert est.clear
    assert abs(est.f1_hz / f1 - 1) < 1e-6


@pytest.mark.parametrize("quantity", ["accel_m_s2", "dte_m"])
def test_records_of_the_independent_simulator_are_read_or_refused_never_misread(quantity):
    """30 dB: every speed read within 1e-6; 10 dB: a speed judged clear is right within 1e-5
    (the others are refused, not misread)."""
    f_low, f_high = _range(18)
    read = refused = 0
    for snr in (30.0, 10.0):
        for n1 in np.linspace(1300.0, 3300.0, 5):
            x = simulate_record(IndependentPair(), float(n1), 250.0, 0.006, quantity, FS, 0.5,
                                snr_db=snr, rng=np.random.default_rng(int(n1)))
            est = pinion_speed(x, FS, 18, f_low, f_high)
            if snr == 30.0:
                assert est.clear and abs(est.rpm / n1 - 1) < 1e-6, (n1, est)
            if est.clear:
                read += 1
                assert abs(est.rpm / n1 - 1) < 1e-5, (snr, n1, est)
            else:
                refused += 1
    assert read >= 7, (read, refused)


def test_white_noise_is_never_read():
    f_low, f_high = _range(18)
    rng = np.random.default_rng(3)
    for _ in range(8):
        est = pinion_speed(rng.standard_normal(N), FS, 18, f_low, f_high)
        assert not est.clear and est.comb_db < MIN_COMB_DB


@pytest.fixture(scope="module")
def unknown_speeds(tmp_path_factory):
    """An independent bundle of both quantities at 2000 and 1800 r/min, its speeds left
    unknown in the manifest."""
    path, _ = make_independent_bundle(tmp_path_factory.mktemp("speed") / "b",
                                      quantities=("accel_m_s2", "dte_m"),
                                      wear_mm=(0.0, 0.006, 0.012))
    b = read_bundle(path)
    return b, b.manifest.n1_rpm.to_numpy(float)


def test_unknown_speeds_are_read_and_merged_into_operating_points(unknown_speeds, tmp_path):
    b, true = unknown_speeds
    path = write_bundle(tmp_path / "u", b.manifest.assign(n1_rpm="unknown"), b.signals)
    got = read_bundle(path)
    used = got.manifest.n1_rpm.to_numpy(float)
    assert len(set(used)) == 2  # one speed for each operating point's records
    assert np.all(np.abs(used / true - 1) < 1e-6)
    assert set(got.speeds) == set(b.records)
    for rec, t in zip(b.records, true, strict=True):
        assert abs(got.speeds[rec].rpm / t - 1) < SAME_SPEED / 2


def test_a_record_without_a_mesh_comb_and_a_bad_speed_cell_are_refused(unknown_speeds,
                                                                       tmp_path):
    b, _ = unknown_speeds
    man = b.manifest.assign(n1_rpm=b.manifest.n1_rpm.astype(object))
    first = man.record.iloc[0]
    man.loc[0, "n1_rpm"] = "unknown"
    noise = dict(b.signals) | {first: np.random.default_rng(0).standard_normal(N)}
    path = write_bundle(tmp_path / "noise", man, noise)
    with pytest.raises(ValueError, match=f"record '{first}': n1_rpm unknown and no clear mesh "
                                         "comb of z1 = 18"):
        read_bundle(path)
    man.loc[0, "n1_rpm"] = "-5"
    path = write_bundle(tmp_path / "bad", man, b.signals)
    with pytest.raises(ValueError, match=r"n1_rpm = -5\.0 must be a positive number, or empty "
                                         r"or 'unknown' .*\(then read off the record's "):
        read_bundle(path)


def test_the_docs_state_the_reader_s_rules_as_the_code_has_them():
    text = " ".join((Path(__file__).parents[2] / "docs" / "own-data.md").read_text().split())
    assert (f"at least {MIN_LINES} lines, a mean height of {MIN_COMB_DB:g} dB over the floor "
            f"and a lead of {MIN_MARGIN_DB:g} dB") in text
    assert f"agree within {SAME_SPEED:.0e} are one operating point".replace("e-05", "e-5") in text
    assert "within 1e-6 at 30 dB SNR; at 10 dB a reading judged clear is within 1e-5" in text


def test_a_search_whose_mesh_line_leaves_the_read_band_is_refused():
    """The comb is read below 0.45 fs: a search band whose mesh line reaches it, or an empty
    band, is refused before any work, naming the values."""
    x = np.random.default_rng(0).standard_normal(4096)
    with pytest.raises(ValueError, match=r"z1 = 20\) must lie below 0\.45 fs = 1843\.2 Hz"):
        pinion_speed(x, 4096.0, 20, 5.0, 100.0)
    with pytest.raises(ValueError, match="f_low = 10 to f_high = 5 Hz"):
        pinion_speed(x, 4096.0, 20, 10.0, 5.0)
