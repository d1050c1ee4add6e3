"""The loop's inputs: record values checked against what their quantity allows, records larger
than the loop analyses refused before loading, a stated wear or cycle count no gear can have
refused before work, a constant record, a read-only working folder and a binary sidecar named
in one line, a FIFO or device given as a signal file and a malformed ``reference=`` said to be
so; impossible feature values in a table, and command-line settings a sidecar or manifest
would override without a word."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import time
import types
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import physics.loop.measured.bundle as bundle_mod
from physics.loop import LoopSettings, check_usable, read_bundle, write_bundle
from physics.loop.measured.bundle import FeatureTable, read_measurements
from physics.loop.measured.usable import check_reference_folder, check_stated_once
from physics.loop.measured.worn_states import tip_thickness_mm
from physics.loop.table_loop import check_table
from physics.params import Scenario
from tests.acceptance.refusal import refusal, tree

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(Path(__file__).parent))
from test_safety_early_refusals import read_only  # noqa: E402

FS = 50_000.0
TABLE = ("wear_mm,rms_m_per_s2,peak_to_peak_m_per_s2,kurtosis,crest\n"
         "0,1.066,16.67,4.336,8.931\n0.01,1.1,17,4.4,9\n0.02,1.2,18,4.5,9.1\n")


def manifest(n=4, **over):
    d = {"record": [f"r{i}" for i in range(n)], "quantity": "accel_m_s2", "fs_hz": FS,
         "n1_rpm": 2000.0, "torque_Nm": 300.0, "wear_mm": "", "cycles": "", "split": ""}
    d.update(over)
    return pd.DataFrame(d)


def signals(n=4, scale=1.0, mean=0.0, seconds=0.6):
    rng = np.random.default_rng(0)
    return {f"r{i}": mean + scale * rng.standard_normal(int(seconds * FS)) for i in range(n)}


def one_line(err: pytest.ExceptionInfo) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text


def app(tmp_path: Path, *args: str, cwd: Path = ROOT) -> tuple[subprocess.CompletedProcess, float]:
    start = time.monotonic()
    run = subprocess.run([sys.executable, "-m", "physics.loop", *args,
                          *([] if cwd != ROOT else [f"hydra.run.dir={tmp_path / 'run'}"])],
                         cwd=cwd, capture_output=True, text=True, timeout=120)
    return run, time.monotonic() - start


# --- units and sizes -----------------------------------------------------------------------------

def test_acceptance_acceleration_in_raw_counts_is_refused_naming_record_value_and_rule(tmp_path):
    """The user's probe: counts of about 1e9 were accepted without a word."""
    sig = signals()
    sig["r2"] = sig["r2"] * 1e9
    path = write_bundle(tmp_path / "b", manifest(), sig)
    with pytest.raises(ValueError) as err:
        read_bundle(path)
    text = one_line(err)
    assert "record 'r2': accel_m_s2 of RMS 1e+09 m/s^2 lies above 4903 m/s^2 (500 g)" in text
    assert "not in m/s^2" in text and "raw ADC counts" in text


def test_integer_counts_within_the_range_are_refused_as_counts(tmp_path):
    path = write_bundle(tmp_path / "b", manifest(), signals())
    np.save(path / "signals" / "r1.npy", (signals()["r1"] * 300).astype(np.int16))
    with pytest.raises(ValueError, match=r"record 'r1': every sample of this accel_m_s2 record "
                                         r"is a whole number .* raw ADC counts"):
        read_bundle(path)


@pytest.mark.parametrize("scale, mean, shown", [(0.1, 20.0, "20.4 m"), (1e-4, 0.02, "0.0204 m")])
def test_a_dte_in_um_or_mm_is_refused(tmp_path, scale, mean, shown):
    path = write_bundle(tmp_path / "b", manifest(quantity="dte_m"), signals(scale=scale,
                                                                            mean=mean))
    with pytest.raises(ValueError) as err:
        read_bundle(path)
    text = one_line(err)
    assert f"record 'r0': dte_m reaches {shown}, above 0.0002 m, a tenth of the module" in text
    assert "not in metres" in text


def test_plausible_records_still_read(tmp_path):
    accel = write_bundle(tmp_path / "a", manifest(), signals(scale=4e3))
    dte = write_bundle(tmp_path / "d", manifest(quantity="dte_m"), signals(scale=1e-7, mean=2e-5))
    assert len(read_bundle(accel).records) == len(read_bundle(dte).records) == 4


def test_a_record_above_the_analysed_size_is_refused_before_loading(tmp_path, monkeypatch):
    """A header claiming 1e8 samples (a sparse file of 800 MB): refused from its header, the
    record never loaded (it took 8 GB)."""
    path = write_bundle(tmp_path / "b", manifest(), signals())
    f = path / "signals" / "r3.npy"
    with f.open("wb") as fp:
        np.lib.format.write_array_header_1_0(
            fp, {"descr": "<f8", "fortran_order": False, "shape": (100_000_000,)})
        offset = fp.tell()
    os.truncate(f, offset + 8 * 100_000_000)
    monkeypatch.setattr(bundle_mod.np, "load", lambda *a, **k: pytest.fail("loaded"))
    with pytest.raises(ValueError) as err:
        read_bundle(path)
    text = one_line(err)
    assert "record 'r3': 100,000,000 samples (2000 s at fs_hz = 50000), above the " \
           "16,777,216 a record may hold" in text
    assert "at most 335.5 s at this rate" in text


# --- refusals before work ------------------------------------------------------------------------

@pytest.mark.parametrize("column, cells, shown", [
    ("wear_mm", [0, 0, 0, 5.0], "wear_mm = 5 reaches the 1.15 mm the thinner tooth is thick"),
    ("cycles", [0, 0, 0, 1e30], "cycles = 1e+30 lies beyond 1e+12 pinion load cycles"),
])
def test_acceptance_impossible_wear_or_cycles_are_refused_before_work(tmp_path, config_store,
                                                                      column, cells, shown):
    """A wear or cycle count no gear can have: the record named, by the app's checks, in
    seconds and before any work (a refusal's exit path: tests/acceptance/test_bad_input.py)."""
    path = write_bundle(tmp_path / "b", manifest(**{column: cells}), signals())
    with pytest.raises(ValueError) as err:
        check_usable(read_bundle(path), Scenario(), LoopSettings())
    assert f"record 'r3': {shown}" in one_line(err)
    (tmp_path / "work").mkdir()
    start = time.monotonic()
    err = refusal("loop", [f"data={path}"], tmp_path / "work")
    assert isinstance(err, ValueError) and time.monotonic() - start < 30
    assert f"record 'r3': {shown}" in str(err) and "\n" not in str(err)
    assert not tree(tmp_path / "work")


def test_the_tip_thickness_follows_the_bundles_gear(tmp_path):
    path = write_bundle(tmp_path / "b", manifest(wear_mm=[0, 0, 0, 1.5]), signals(),
                        gear={"module_mm": 3.0, "bore_radius1_mm": 10.0})
    bundle = read_bundle(path)
    check_usable(bundle, Scenario(), LoopSettings())  # 1.5 mm lies within a module-3 tip
    assert tip_thickness_mm(Scenario()) < 1.5


# --- constant records, read-only folders, binary sidecars ----------------------------------------

def test_acceptance_an_all_zero_record_is_named(tmp_path):
    sig = signals()
    sig["r1"] = np.zeros_like(sig["r1"])
    with pytest.raises(ValueError) as err:
        read_bundle(write_bundle(tmp_path / "b", manifest(), sig))
    assert "record 'r1': every sample is 0: a constant record" in one_line(err)


def test_a_record_with_a_constant_segment_is_named_with_the_segment(tmp_path):
    sig = signals()
    sig["r2"][15000:] = 0.0
    bundle = read_bundle(write_bundle(tmp_path / "b", manifest(), sig))
    with pytest.raises(ValueError) as err:
        check_usable(bundle, Scenario(), LoopSettings(segment_s=0.1))
    assert "record 'r2': its analysis segment 4 of 6 (0.3-0.4 s" in one_line(err)


def test_acceptance_the_loop_from_a_read_only_folder_is_one_line(tmp_path):
    path = write_bundle(tmp_path / "b", manifest(), signals())
    ro = tmp_path / "ro"
    ro.mkdir()
    with read_only(ro):
        run, _ = app(tmp_path, f"data={path}", cwd=ro)
    assert run.returncode == 2, run.stderr[-2000:]
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in run.stderr
    assert f"hydra.run.dir = '{ro}/logs/loop/runs': cannot write in {ro}" in lines[0]
    assert "give hydra.run.dir=" in lines[0]
    assert not any(ro.iterdir())


@pytest.mark.parametrize("sidecar", ["gear", "operating"])
def test_a_binary_sidecar_is_named(tmp_path, sidecar):
    (tmp_path / "t.csv").write_text(TABLE)
    (tmp_path / f"{sidecar}.yaml").write_bytes(bytes(range(128, 256)))
    with pytest.raises(ValueError) as err:
        read_measurements(tmp_path / "t.csv", Scenario())
    assert f"{tmp_path / sidecar}.yaml is not UTF-8 text (byte 0x80 at offset 0)" in \
        one_line(err)


# --- messages that point the right way -----------------------------------------------------------

@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_fifo_or_device_as_a_signal_file_is_said_to_be_so(tmp_path, kind):
    path = write_bundle(tmp_path / "b", manifest(), signals())
    f = path / "signals" / "r1.npy"
    f.unlink()
    os.mkfifo(f) if kind == "fifo" else f.symlink_to("/dev/zero")
    with pytest.raises(ValueError) as err:
        read_bundle(path)
    assert "record 'r1': signals/r1.npy is not a regular file (a FIFO, a device or a socket)" \
        in one_line(err)


def test_a_gear_yaml_that_is_no_file_is_not_silently_ignored(tmp_path):
    path = write_bundle(tmp_path / "b", manifest(), signals())
    os.mkfifo(path / "gear.yaml")
    with pytest.raises(ValueError, match=r"gear.yaml is not a regular file"):
        read_bundle(path)


def test_data_as_a_device_is_said_to_be_so():
    with pytest.raises(ValueError, match=r"data = '/dev/zero' is not a regular file"):
        read_measurements("/dev/zero", Scenario())


@pytest.mark.parametrize("spec, said", [("after:2", "'after:2' does not exist"),
                                        ("t.csv", "is a feature table, not a bundle")])
def test_a_malformed_reference_blames_reference_and_gives_its_forms(tmp_path, monkeypatch,
                                                                    spec, said):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text(TABLE)
    with pytest.raises(ValueError) as err:
        check_reference_folder(spec)
    text = one_line(err)
    assert text.startswith(f"reference={spec}: neither first:N, before:X nor a bundle folder")
    assert said in text and "e.g. reference=first:2" in text and "data=" not in text


# --- values and settings -------------------------------------------------------------------------

def _table(tmp_path, text=TABLE) -> FeatureTable:
    (tmp_path / "t.csv").write_text(text)
    return read_measurements(tmp_path / "t.csv", Scenario())[0]


@pytest.mark.parametrize("old, new, said", [
    ("1.066", "1e9", "column 'rms_m_per_s2' = 1e+09 must be positive and at most 4.9e+03 "
                     "m/s^2"),
    ("4.336", "0.2", "column 'kurtosis' = 0.2 must be 1 at least"),
    ("8.931", "0.5", "column 'crest' = 0.5 must be 1 at least"),
    ("16.67", "0.1", "peak_to_peak 0.1 m/s^2 is below twice the RMS 1.066"),
])
def test_impossible_feature_values_in_a_table_are_refused(tmp_path, old, new, said):
    table = _table(tmp_path, TABLE.replace(old, new))
    with pytest.raises(ValueError) as err:
        check_table(table, Scenario())
    assert f"row 1, {said}" in one_line(err) or said in one_line(err)


def test_a_dte_table_in_metres_nonsense_is_refused(tmp_path):
    text = "wear_mm,rms_m,kurtosis\n0,5,3\n0.01,5.1,3.1\n0.02,5.2,3.2\n"
    with pytest.raises(ValueError, match=r"row 1, column 'rms_m' = 5 must be positive and at "
                                         r"most 0.0002 m"):
        check_table(_table(tmp_path, text), Scenario())


def test_a_command_line_value_a_sidecar_overrides_is_refused(tmp_path):
    (tmp_path / "operating.yaml").write_text("n1_rpm: 1000\ntorque_Nm: unknown\n")
    table = _table(tmp_path)
    cfg = types.SimpleNamespace(case=None, data=str(tmp_path / "t.csv"))
    base = Scenario()
    base = dataclasses.replace(base, operating=dataclasses.replace(base.operating, n1_rpm=1500.0))
    with pytest.raises(ValueError, match=r"operating.n1_rpm=1500 on the command line and "
                                         r"n1_rpm: 1000 in the operating.yaml"):
        check_stated_once(cfg, table, base, {"operating.n1_rpm"})
    # the centre of an unknown torque's prior
    check_stated_once(cfg, table, Scenario(), {"operating.torque_Nm"})


def test_a_bundles_speed_on_the_command_line_is_refused(tmp_path):
    bundle = read_bundle(write_bundle(tmp_path / "b", manifest(), signals()))
    cfg = types.SimpleNamespace(case=None, data=str(bundle.path))
    with pytest.raises(ValueError, match=r"a bundle's records state their own speed"):
        check_stated_once(cfg, bundle, Scenario(), {"operating.n1_rpm"})
    with pytest.raises(ValueError, match=r"every record .* states its torque"):
        check_stated_once(cfg, bundle, Scenario(), {"operating.torque_Nm"})


@pytest.mark.parametrize("key", ["data", "reference"])
def test_an_empty_data_or_reference_is_not_the_working_folder(tmp_path, config_store, key):
    path = write_bundle(tmp_path / "b", manifest(), signals())
    args = [f"data={path}", "reference=''"] if key == "reference" else ["data=''"]
    (tmp_path / "work").mkdir()
    err = refusal("loop", args, tmp_path / "work")
    assert f"{key}= is empty (it was read as the working folder)" in str(err)
    assert not tree(tmp_path / "work")


def test_negative_cycles_in_a_table_are_refused(tmp_path):
    text = "cycles," + TABLE.replace("\n0", "\n-5,0", 1).replace("\n0.0", "\n1,0.0")
    with pytest.raises(ValueError, match=r"row 1, column 'cycles' = -5 must be >= 0"):
        check_table(_table(tmp_path, text), Scenario())


def test_a_stated_wear_the_model_does_not_reach_at_the_stated_cycles_is_said(caplog):
    """A record stating both cycles and wear_mm is read at its cycles; where the stated depth
    is far from the model's there (1.0 mm against about 10 um, or worn at 0 cycles) the run
    says so, naming the record and both depths, instead of ignoring the stated wear."""
    from physics.loop.measured.worn_states import WearHistory, check_stated_wear

    s = np.linspace(0.0, 1.0, 5)
    pinion = np.array([[0.0] * 5, [10e-6] * 5, [20e-6] * 5])  # 10 um per 1e6 cycles
    h = WearHistory(s, np.array([0.0, 1e6, 2e6]), pinion, np.zeros_like(pinion))
    rows = pd.DataFrame({"record": ["a", "b", "c", "d"], "cycles": [1e6, 1e6, 2e6, np.nan],
                         "wear_mm": [1.0, 0.012, np.nan, 0.5]})
    with caplog.at_level("WARNING"):
        said = check_stated_wear(h, rows)
    assert len(said) == 1 and said[0].startswith("record 'a': wear_mm = 1 mm stated, the "
                                                 "model's 0.01 mm"), said
    assert "leave cycles empty" in caplog.text
    new = pd.DataFrame({"record": ["n"], "cycles": [0.0], "wear_mm": [0.3]})
    assert check_stated_wear(None, new) == ["record 'n': wear_mm = 0.3 mm stated, the model's "
                                            "0 mm at its 0 stated cycles"]
    agree = pd.DataFrame({"record": ["z"], "cycles": [0.0], "wear_mm": [0.0]})
    assert check_stated_wear(None, agree) == []
