"""The independent spur-pair simulator (physics.testbeds.independent_simulator): physics checks,
effects' signatures, determinism, bundles the project's reader accepts, argument errors."""

from __future__ import annotations

import math
import re
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from physics.loop import read_bundle
from physics.signals.order_analysis import mesh_lines
from physics.testbeds import (
    EFFECT_NAMES,
    IndependentPair,
    effect_values,
    make_independent_bundle,
    simulate_record,
    wear_depths,
)

FS = 40960.0
DUR = 0.3  # 10 pinion revolutions at 2000 r/min; 3.3 Hz lines
F1 = 2000 / 60
F2 = F1 * 18 / 27
FM = 600.0


def _rec(seed=1, pair=None, **kw):
    kw = {"snr_db": math.inf, "duration_s": DUR, "fs_hz": FS} | kw
    return simulate_record(pair, rng=np.random.default_rng(seed), **kw)


def _spectrum(x):
    x = x - x.mean()
    w = np.hanning(x.size)
    return np.fft.rfftfreq(x.size, 1 / FS), np.abs(np.fft.rfft(x * w)) * 2 / w.sum()


def _line(f, a, f0, tol=2.0):
    return float(a[np.abs(f - f0) <= tol].max())


@pytest.fixture(scope="module")
def clean():
    return _rec()


FORBIDDEN = (  # the project's model, effects, measurement chain, loops, testbeds and surrogate
    "physics.dynamics", "physics.gear.stiffness", "physics.signals.measurement",
    "physics.testbeds.synthetic", "physics.testbeds.loop_bench", "surrogate",
)
#: of the loop, only the bundle format (the writer) and its lazy packages may be loaded
LOOP_ALLOWED = ("physics.loop", "physics.loop.measured", "physics.loop.measured.bundle")


def test_independent_of_the_project_model():
    """Importing the simulator pulls in none of the project's model, effect, measurement or loop
    code (the bundle writer's own imports aside)."""
    code = ("import sys, physics.testbeds.independent_simulator; "
            "print('\\n'.join(sorted(sys.modules)))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True).stdout.split()
    hits = [m for m in loaded if any(m == f or m.startswith(f + ".") for f in FORBIDDEN)
            or (m.startswith("physics.loop") and m not in LOOP_ALLOWED)]
    assert not hits
    assert "physics.testbeds.independent_simulator" in loaded


def test_iso_stiffness_and_geometry():
    p = IndependentPair()
    assert p.contact_ratio == pytest.approx(1.58, abs=0.01)  # thesis 3.3-3.4 pair
    assert p.k_single == pytest.approx(14.0 * 30 * 1e6)
    assert p.k_mean == pytest.approx(p.k_single * (0.75 * p.contact_ratio + 0.25))
    assert p.k_double == pytest.approx(1.75 * p.k_single)
    assert 0.05 < p.equivalent_mass < 0.5
    # the mesh mode well above the mesh harmonics, the body mode between them
    assert p.omega_mesh_mode / (2 * np.pi) > 5000


def test_mesh_line_dominates_with_harmonics_and_runout_sidebands(clean):
    f, a = _spectrum(clean)
    assert abs(f[np.argmax(a)] - FM) <= f[1]
    floor = float(np.median(a[(f > 100) & (f < 5000)]))
    for h in (1, 2, 3):
        assert _line(f, a, h * FM) > 100 * floor
    # pinion run-out modulates the mesh excitation: f_m +- f_1 sidebands
    f0, a0 = _spectrum(_rec(pair=IndependentPair(runout1_um=0.0)))
    for sb in (FM - F1, FM + F1):
        assert _line(f, a, sb) > 100 * _line(f0, a0, sb)
        assert _line(f, a, sb) > 0.01 * _line(f, a, FM)


def test_mean_dte_is_the_static_deflection(clean):
    p = IndependentPair()
    w = 300.0 / p.radii[3]
    assert clean.mean() == pytest.approx(w / p.k_mean, rel=0.2)


def test_dte_peak_to_peak_and_mean_grow_with_wear():
    wears = (0.0, 0.003, 0.006, 0.009, 0.012, 0.015)
    for n1, torque in ((2000.0, 300.0), (1800.0, 290.0)):
        xs = [_rec(n1_rpm=n1, torque_Nm=torque, wear_mm=w, duration_s=0.34) for w in wears]
        ptp = [np.ptp(x) for x in xs]
        assert ptp[-1] > 1.03 * ptp[0]
        assert np.all(np.diff(ptp[1:]) > 0)  # monotone after the first state
        assert np.all(np.diff([x.mean() for x in xs]) > 0)


def _kurt(x):
    return float(stats.kurtosis(x, fisher=False))


def _band_energy(x, lo, hi):
    f, a = _spectrum(x)
    return float(np.sum(a[(f >= lo) & (f <= hi)] ** 2))


@pytest.mark.parametrize("tip_share", [0.5, 3.0])
def test_wear_depths_integrate_the_archard_profile_by_hand(tip_share):
    """With a vanishing zone transition the profile is piecewise linear in the roll s:
    depth ~ |s| in single contact, |s| / 2 in double contact, times the tip share beyond the
    pitch point, h at the root. Its mean over the path is then a sum of four trapezoids, its
    largest depth the root's or (a large tip share) the tip's."""
    pair = IndependentPair(transition_roll_fraction=0.002, wear_tip_share=tip_share)
    s0, s1 = pair.path
    ld = (pair.contact_ratio - 1.0) * pair.base_pitch
    h, share = 0.01, pair.wear_tip_share
    scale = h / (0.5 * abs(s0))

    def ramp_area(a, b, weight):  # integral of weight |s| over [a, b], a < b, same sign
        return weight * abs(b * abs(b) - a * abs(a)) / 2

    area = (ramp_area(s0, s0 + ld, 0.5) + ramp_area(s0 + ld, 0.0, 1.0)
            + share * (ramp_area(0.0, s1 - ld, 1.0) + ramp_area(s1 - ld, s1, 0.5)))
    d = wear_depths(pair, h)
    assert d["root_wear_mm"] == pytest.approx(h)
    assert d["mean_wear_mm"] == pytest.approx(scale * area / (s1 - s0), rel=2e-3)
    # each zone's largest depth is at its end farthest from the pitch point
    peaks = (0.5 * abs(s0), abs(s0 + ld), share * abs(s1 - ld), share * 0.5 * s1)
    assert d["max_wear_mm"] == pytest.approx(scale * max(peaks), rel=1e-2)
    assert wear_depths(pair, 2 * h)["mean_wear_mm"] == pytest.approx(2 * d["mean_wear_mm"])
    assert wear_depths(pair, 0.0) == {k: 0.0 for k in d}


@pytest.mark.parametrize("effect", EFFECT_NAMES)
def test_each_effect_shows_where_its_signature_lives(effect):
    q = "accel_m_s2" if effect in ("transfer_path", "tooth_defect") else "dte_m"
    base = _rec(quantity=q)
    x = _rec(quantity=q, effect=effect)
    f, a0 = _spectrum(base)
    _, a1 = _spectrum(x)
    if effect == "gear_runout":
        for sb in (FM - F2, FM + F2):
            assert _line(f, a1, sb) > 10 * _line(f, a0, sb)
    elif effect == "friction":  # a mesh-rate square-wave moment: lines at mesh harmonics
        fd, ad = _spectrum(x - base)
        peak = fd[np.argmax(ad)]
        assert abs(peak / FM - round(peak / FM)) * FM <= 2 * fd[1]
        assert round(peak / FM) >= 1
        assert np.std(x - base) > 0.05 * np.std(base)
    elif effect == "tip_relief":  # smaller STE steps: lower mesh harmonics
        assert _line(f, a1, FM) < 0.6 * _line(f, a0, FM)
        assert np.ptp(x) < 0.6 * np.ptp(base)
    elif effect == "tooth_defect":  # once per pinion revolution, impulsive
        assert _kurt(x) > _kurt(base) + 1.0
        fd, ad = _spectrum(x - base)  # periodic in the pinion revolution: lines at k f_1
        near = np.abs(fd / F1 - np.round(fd / F1)) * F1 <= 2 * fd[1]
        assert np.sum(ad[near] ** 2) > 0.95 * np.sum(ad**2)
    elif effect == "transfer_path":  # a housing mode at 3.6 kHz
        assert _band_energy(x, 3300, 3900) > 5 * _band_energy(base, 3300, 3900)
        assert _band_energy(x, 400, 1300) == pytest.approx(_band_energy(base, 400, 1300),
                                                           rel=0.3)
    elif effect == "torque_ripple":  # half the pinion order
        assert _line(f, a1, F1 / 2) > 20 * _line(f, a0, F1 / 2)
    elif effect == "sensor":
        gain = effect_values("sensor")[1]["gain"]
        assert x.mean() / base.mean() == pytest.approx(gain, rel=0.05)
        assert not np.allclose(x / base, gain)  # and a nonlinearity
    else:  # pragma: no cover - a new effect needs its check here
        pytest.fail(f"no signature check for {effect}")


def test_defect_alias_and_effect_sizes():
    assert effect_values("defect")[0] == "tooth_defect"
    small = _rec(effect="gear_runout", effect_size=0.5)
    large = _rec(effect="gear_runout", effect_size=2.0)
    f, a_s = _spectrum(small)
    _, a_l = _spectrum(large)
    assert _line(f, a_l, FM + F2) > 2 * _line(f, a_s, FM + F2)


def test_deterministic_and_seeded_noise():
    a = _rec(seed=3, snr_db=30.0)
    b = _rec(seed=3, snr_db=30.0)
    assert a.dtype == np.float64 and a.ndim == 1 and a.size == round(DUR * FS)
    assert a.tobytes() == b.tobytes()
    assert not np.array_equal(a, _rec(seed=4, snr_db=30.0))
    # the noise sits at the requested SNR relative to the record's AC power
    clean = _rec(seed=3)
    noise = a - clean
    assert np.mean(noise**2) / np.var(clean) == pytest.approx(1e-3, rel=0.1)
    acc = _rec(seed=3, snr_db=30.0, quantity="accel_m_s2")
    assert abs(acc.mean()) < 1e-9 * np.std(acc) * acc.size


def test_a_once_per_revolution_mark_gives_one_gear_sets_records_the_same_lines():
    """Records of one gear set (``gear_set_seed``) started at other angles, each told by its
    mark (``start_angle_rad``), read the same mesh lines at the mark's mesh phase; a worn gear
    set's differ."""
    def lines(angle, gear_set=7, wear=0.0, seed=1):
        x = _rec(seed, gear_set_seed=gear_set, start_angle_rad=angle, wear_mm=wear)
        z = mesh_lines(x, FS, FM, 18 * angle)
        return np.array([z[f"line{k}_re"] + 1j * z[f"line{k}_im"] for k in (1, 2, 3)])

    a, b = lines(0.3), lines(2.9, seed=2)
    assert np.abs(b - a).max() < 1e-3 * np.abs(a).max()
    assert np.abs(lines(0.3, wear=0.01) - a).max() > 0.05 * np.abs(a).max()


def test_bundle_is_read_by_the_project_reader(tmp_path):
    kw = {"effect": "tooth_defect", "wear_mm": (0.0, 0.015),
          "quantities": ("dte_m", "accel_m_s2"), "duration_s": 0.34, "seed": 7}
    path, truth = make_independent_bundle(tmp_path / "b1", **kw)
    bundle = read_bundle(path)
    man = bundle.manifest
    assert len(man) == 2 * 2 * 2
    assert set(man.quantity) == {"dte_m", "accel_m_s2"}
    assert sorted(set(zip(man.n1_rpm, man.torque_Nm, strict=True))) == [(1800.0, 290.0),
                                                                         (2000.0, 300.0)]
    assert set(man.wear_mm) == {0.0, 0.015}
    assert man.cycles.isna().all() and man.split.isna().all()
    assert (man.fs_hz == FS).all()
    assert not (path / "gear.yaml").exists()
    for rec, x in bundle.signals.items():
        assert x.size == round(0.34 * FS), rec
    assert truth["effect"] == "tooth_defect" and truth["values"]["face_share"] > 0
    assert truth["pair"]["z1"] == 18 and truth["effect_to_noise_db"] > -20
    # same arguments: byte-identical files; another seed: other records
    again, _ = make_independent_bundle(tmp_path / "b2", **kw)
    other, _ = make_independent_bundle(tmp_path / "b3", **(kw | {"seed": 8}))
    for rec in man.record:
        one = (path / "signals" / f"{rec}.npy").read_bytes()
        assert one == (again / "signals" / f"{rec}.npy").read_bytes()
        assert one != (other / "signals" / f"{rec}.npy").read_bytes()
    assert (path / "manifest.csv").read_text() == (again / "manifest.csv").read_text()


@pytest.mark.parametrize(("kwargs", "named"), [
    ({"quantity": "velocity"}, "'velocity'"),
    ({"n1_rpm": -5.0}, "-5.0"),
    ({"torque_Nm": float("nan")}, "nan"),
    ({"wear_mm": 0.5}, "0.5"),
    ({"fs_hz": 5000.0}, "5000.0"),
    ({"duration_s": 0.0}, "0.0"),
    ({"effect": "rust"}, "'rust'"),
    ({"effect": "gear_runout", "effect_size": -1.0}, "-1.0"),
    ({"effect": "transfer_path", "quantity": "dte_m"}, "'transfer_path'"),
    ({"snr_db": "30"}, "'30'"),
    ({"start_angle_rad": float("nan")}, "nan"),
    ({"gear_set_seed": -1}, "-1"),
])
def test_bad_record_arguments_name_the_value(kwargs, named):
    with pytest.raises(ValueError, match=re.escape(named)):
        simulate_record(**({"duration_s": 0.1} | kwargs))


@pytest.mark.parametrize(("kwargs", "named"), [
    ({"face_width_mm": -1.0}, "face_width_mm = -1.0"),
    ({"z1": 30, "z2": 27}, "z1 = 30"),
    ({"mesh_damping_ratio": 0.9}, "mesh_damping_ratio = 0.9"),
    ({"profile_harmonics_um": (1.0, -2.0)}, r"profile_harmonics_um\[1\] = -2.0"),
    ({"internal_rate_hz": 60000.0}, "internal_rate_hz = 60000.0"),
])
def test_bad_pair_parameters_name_field_and_value(kwargs, named):
    with pytest.raises(ValueError, match=named):
        IndependentPair(**kwargs)


def test_an_effect_that_appears_during_the_life_leaves_the_earlier_records_clean(tmp_path):
    """With ``onset`` the records below that share of the largest wear are those of the same
    gear set without the effect, byte for byte; the later ones carry it; ``dated`` dates the
    wear states a week apart in order of wear, which orders them for a reference."""
    kw = {"wear_mm": (0.0, 0.004, 0.012), "quantities": ("dte_m",), "duration_s": 0.34,
          "seed": 5}
    clean, _ = make_independent_bundle(tmp_path / "clean", **kw)
    path, truth = make_independent_bundle(tmp_path / "late", effect="gear_runout", onset=0.5,
                                          dated=True, **kw)
    man = read_bundle(path).manifest
    assert truth["onset"] == 0.5 and truth["effect_to_noise_db"] > -20
    days = pd.to_datetime(man.time).map(pd.Timestamp.toordinal).to_numpy()
    assert np.array_equal(np.argsort(days, kind="stable"), np.argsort(man.wear_mm, kind="stable"))
    assert man.cycles.isna().all()
    for rec, wear in zip(man.record, man.wear_mm, strict=True):
        same = ((path / "signals" / f"{rec}.npy").read_bytes()
                == (clean / "signals" / f"{rec}.npy").read_bytes())
        assert same == (wear < 0.5 * 0.012), (rec, wear)
    with pytest.raises(ValueError, match=r"onset = 0\.0"):
        make_independent_bundle(tmp_path / "bad", effect="gear_runout", onset=0.0, **kw)
    assert not (tmp_path / "bad").exists()


def test_bad_bundle_arguments(tmp_path):
    with pytest.raises(ValueError, match=r"duration_s = 0\.2"):  # < 10 revolutions
        make_independent_bundle(tmp_path / "x", duration_s=0.2)
    with pytest.raises(ValueError, match="'transfer_path'"):  # no acceleration records
        make_independent_bundle(tmp_path / "x", effect="transfer_path")
    with pytest.raises(ValueError, match="quantities"):
        make_independent_bundle(tmp_path / "x", quantities=("dte_m", "dte_m"))
    assert not (tmp_path / "x").exists()


@pytest.mark.slow
def test_default_bundle_runtime(tmp_path):
    t0 = time.perf_counter()
    path, truth = make_independent_bundle(tmp_path / "full", effect="gear_runout")
    elapsed = time.perf_counter() - t0
    assert elapsed < 30.0
    bundle = read_bundle(path)
    assert len(bundle.manifest) == 12
    assert all(x.size == round(0.5 * FS) for x in bundle.signals.values())
    assert truth["effect"] == "gear_runout"
