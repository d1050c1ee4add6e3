"""The loop on a feature table: the gear and operating point beside it, an unknown torque
calibrated under its prior, worn states from new to worn out by the contact-driven wear, a table
it cannot follow refused before work, every nuisance searched within its source's range and a
value at a bound reported; the public rig's 36 stages end to end (slow)."""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from physics.gear.geometry import mesh_geometry
from physics.loop.config import LoopSettings
from physics.loop.measured.bundle import read_measurements
from physics.loop.measured.worn_states import check_table_depths, tip_thickness_mm
from physics.loop.model.declared import (
    SPEED,
    TORQUE,
    at_bounds,
    physical_nuisance,
    with_speed,
    with_torque,
)
from physics.loop.table_loop import PATH_ONLY, folds, parse_columns, run_feature_table
from physics.params import OutOfScope, Scenario, scenario_from_config
from physics.reference import RIG_RECORDS
from tests.acceptance.refusal import refusal, tree

ROOT = Path(__file__).resolve().parents[2]
RIG_GEAR = "module_mm: 3\nz1: 18\nz2: 35\n"


def rig_stages() -> pd.DataFrame:
    """The public rig's stage means of its acceleration RMS, in g, one row per stage."""
    records = pd.read_csv(RIG_RECORDS)
    return (records.groupby("stage_order", sort=True)
            .agg(wear_mm=("wear_mm", "first"), rms_g=("acc_rms_g", "mean"))
            .reset_index(drop=True))


def write_table(folder: Path, table: pd.DataFrame, operating: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    table.to_csv(folder / "table.csv", index=False)
    (folder / "gear.yaml").write_text(RIG_GEAR)
    (folder / "operating.yaml").write_text(operating)
    return folder / "table.csv"


def run_app(tmp: Path, data: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "physics.loop", f"data={data}",
                           f"hydra.run.dir={tmp / 'run'}", "progress=false", *extra], cwd=ROOT,
                          capture_output=True, text=True, timeout=3600)


def test_the_sidecars_set_the_pair_and_operating_point_and_may_leave_torque_and_speed_unknown(
        tmp_path):
    path = write_table(tmp_path, rig_stages().head(3), "n1_rpm: 900\ntorque_Nm: unknown\n")
    table, scn = read_measurements(path, scenario_from_config({}))
    assert (scn.gear.module_mm, scn.gear.z1, scn.gear.z2) == (3, 18, 35)
    assert scn.operating.n1_rpm == 900 and table.torque_unknown and not table.speed_unknown
    assert scn.operating.torque_Nm == Scenario().operating.torque_Nm  # the prior's centre
    (tmp_path / "operating.yaml").write_text("n1_rpm: unknown\n")
    table, scn = read_measurements(path, scenario_from_config({}))
    assert table.speed_unknown and not table.torque_unknown
    assert scn.operating.n1_rpm == Scenario().operating.n1_rpm
    (tmp_path / "operating.yaml").write_text("bulk_temperature_K: unknown\n")
    with pytest.raises(ValueError, match=r"operating.yaml: bulk_temperature_K = 'unknown': only "
                                         r"torque_Nm and n1_rpm may be unknown"):
        read_measurements(path, scenario_from_config({}))
    (tmp_path / "operating.yaml").write_text("torque: 5\n")
    with pytest.raises(ValueError, match=r"operating.yaml: unknown key\(s\) \['torque'\]"):
        read_measurements(path, scenario_from_config({}))


def test_a_feature_in_g_is_acceleration_in_standard_gravities():
    quantity, cols = parse_columns(pd.DataFrame(columns=["wear_mm", "rms_g", "kurtosis"]))
    assert quantity == "accel_m_s2"
    assert cols == {"rms_g": ("rms", 9.80665), "kurtosis": ("kurtosis", 1.0)}


def test_the_folds_leave_one_row_out_up_to_five_rows_and_span_the_wear_beyond():
    small = folds(np.array([0.3, 0.0, 0.1, 0.2]))
    assert sorted(int(f[0]) for f in small) == [0, 1, 2, 3] and all(len(f) == 1 for f in small)
    wear = np.linspace(0, 0.93, 36)[::-1]
    big = folds(wear)
    assert len(big) == 5 and sorted(np.concatenate(big).tolist()) == list(range(36))
    for held in big:  # each fold spans the table's wear: the others predict between rows
        assert np.ptp(wear[held]) > 0.8 * np.ptp(wear)


def test_the_tip_thickness_scales_with_the_module_and_lies_below_the_pitch_thickness():
    scn = Scenario()
    tip = tip_thickness_mm(scn)
    assert 0 < tip < math.pi * scn.gear.module_mm / 2  # the tooth narrows towards its tip
    bigger = dataclasses.replace(scn, gear=dataclasses.replace(scn.gear, module_mm=6.0))
    assert tip_thickness_mm(bigger) == pytest.approx(3 * tip, rel=1e-9)  # similar teeth


def test_a_table_the_loop_cannot_follow_is_refused_in_seconds_naming_the_depth(tmp_path,
                                                                               config_store):
    rig = scenario_from_config({"gear": {"module_mm": 3, "z1": 18, "z2": 35},
                                "operating": {"n1_rpm": 900, "torque_Nm": 100}})
    tip = tip_thickness_mm(rig)
    with pytest.raises(OutOfScope, match=rf"wear_mm = {1.2 * tip:g} mm reaches the "
                                         rf"{tip:.3g} mm .* follows the flanks to below"):
        check_table_depths(rig, np.array([0.0, 0.5, 1.2 * tip]))
    start = time.perf_counter()  # a table within the teeth passes, in seconds
    check_table_depths(rig, np.array([0.0, 0.93]))
    assert time.perf_counter() - start < 10
    path = write_table(tmp_path, pd.DataFrame({"wear_mm": [0.0, 0.5, 1.2 * tip],
                                               "rms_g": [0.1, 0.2, 0.3]}), "n1_rpm: 900\n")
    (tmp_path / "work").mkdir()  # the app refuses it as the table is checked, before work
    start = time.perf_counter()
    err = refusal("loop", [f"data={path}", "tribology.regime=dry"], tmp_path / "work")
    assert time.perf_counter() - start < 10
    assert f"the loop follows the flanks to below {tip:.3g} mm" in str(err)
    assert not tree(tmp_path / "work")


def test_the_nuisance_ranges_follow_the_pair_and_a_fit_at_a_bound_is_named():
    thesis = physical_nuisance(Scenario())
    rig = Scenario(gear=dataclasses.replace(Scenario().gear, module_mm=3.0, z2=35))
    scaled = physical_nuisance(rig)
    for name in ("eccentricity1_um", "profile_error_um"):  # a larger pinion, wider tolerances
        assert scaled[name][0] > thesis[name][0] and scaled[name][1] > thesis[name][1]
    ratio = (mesh_geometry(rig.gear).center_distance
             / mesh_geometry(Scenario().gear).center_distance) ** 3
    assert scaled["housing_mass_kg"][1] == pytest.approx(thesis["housing_mass_kg"][1] * ratio)
    assert scaled["damping_ratio"] == thesis["damping_ratio"]
    lo, hi, _ = thesis["profile_error_um"]
    assert at_bounds({"profile_error_um": hi, "damping_ratio": 0.08}, thesis) == {
        "profile_error_um": ("upper", hi)}
    assert at_bounds({"profile_error_um": lo}, thesis) == {"profile_error_um": ("lower", lo)}


def test_an_unknown_torque_scales_the_static_force_only(rig_models):
    m = rig_models[0]
    scaled = with_torque(m, {"torque_factor": 0.5})
    assert scaled.static_force == pytest.approx(0.5 * m.static_force)
    np.testing.assert_array_equal(scaled.g_a, m.g_a)  # the worn teeth of the configured torque
    assert with_torque(m, {}) is m


def test_an_unknown_speed_scales_the_kinematics_alone(shallow_rig, rig_models):
    """The new pair at 900 r/min run twice as fast is the new pair built at 1800 r/min: its
    tables are given per mesh phase, its rates scale, its damping and load do not."""
    from physics.loop.measured.worn_states import table_models
    table, scn = shallow_rig
    m = rig_models[0]
    fast = table_models(dataclasses.replace(scn, operating=dataclasses.replace(
        scn.operating, n1_rpm=1800.0)), table.wear_mm.to_numpy(float)[:1])[0]
    scaled = with_speed(m, {"speed_factor": 2.0})
    for name in ("omega1", "omega_mesh", "roll_speed", "omega2", "damping", "static_force",
                 "mass"):
        assert getattr(scaled, name) == pytest.approx(getattr(fast, name), rel=1e-12), name
    for name in ("k_a", "k_b", "g_a", "g_b"):
        np.testing.assert_allclose(getattr(scaled, name), getattr(fast, name), rtol=1e-12)
    assert with_speed(m, {}) is m


@pytest.fixture(scope="module")
def shallow_rig():
    """Three stages of the rig's pair within 20 um (a few blocks of the contact-driven wear),
    torque unknown: the code path of the rig's whole table in seconds."""
    table = pd.DataFrame({"wear_mm": [0.0, 0.01, 0.02], "rms_g": [0.14, 0.12, 0.15]})
    scn = scenario_from_config({"gear": {"module_mm": 3, "z1": 18, "z2": 35},
                                "operating": {"n1_rpm": 900, "torque_Nm": 100},
                                "tribology": {"regime": "dry"}})
    return table, scn


@pytest.fixture(scope="module")
def rig_models(shallow_rig):
    from physics.loop.measured.worn_states import table_models
    table, scn = shallow_rig
    return table_models(scn, table.wear_mm.to_numpy(float))


def test_a_few_rig_stages_run_with_the_torque_calibrated_inside_every_range(tmp_path,
                                                                             shallow_rig):
    table, scn = shallow_rig
    path = write_table(tmp_path, table, "torque_Nm: unknown\nn1_rpm: unknown\n")
    data, _ = read_measurements(path, scn)
    report = run_feature_table(data, scn, LoopSettings(max_nfev=2, candidates=("transfer_path",),
                                                       segment_s=0.15)).to_dict()
    speed = report["assumed"]["n1_rpm"]
    assert speed["prior"] == pytest.approx([s * 900 for s in SPEED["speed_factor"][:2]])
    assert speed["prior"][0] <= speed["calibrated"] <= speed["prior"][1]
    assert speed["configured"] == 900 and speed["worn_teeth_at"] == 900
    assert set(report["feature_errors"]["before"]) == {"rms"}
    held = report["feature_errors"]["before"]["rms"]
    assert held == pytest.approx(report["error_before"])  # one feature: the whole error
    torque = report["assumed"]["torque_Nm"]
    assert torque["prior"][0] <= torque["calibrated"] <= torque["prior"][1]
    assert torque["configured"] == 100 and torque["worn_teeth_at"] == 100
    ranges = report["nuisance_ranges"]
    for fit in (report["calibration"], report["nuisance_after"]):
        for name, (lo, hi, _) in ranges.items():
            if name in fit:
                assert lo * (1 - 1e-9) <= fit[name] <= hi * (1 + 1e-9), name
    assert report["at_bound"]["calibration"] == at_bounds(report["calibration"], ranges)
    assert TORQUE["torque_factor"][0] * 100 == pytest.approx(torque["prior"][0])


def test_with_the_exact_contact_the_path_only_effects_are_not_searched(shallow_rig):
    table, scn = shallow_rig
    exact = dataclasses.replace(scn, dynamics=dataclasses.replace(scn.dynamics,
                                                                  flank_contact="exact"))
    report = run_feature_table(table, exact, LoopSettings(
        max_nfev=1, candidates=("tip_relief", "transfer_path"), segment_s=0.15)).to_dict()
    assert set(report["not_searched"]) == set(PATH_ONLY)
    assert [c["effect"] for c in report["ranking"]] == ["transfer_path"]
    assert report["flank_contact"] == "exact"


@pytest.mark.parametrize("after_fits", [0, 1 + (1 + 3) * 2])
def test_an_interrupt_keeps_what_the_table_loop_judged(shallow_rig, tmp_path, monkeypatch,
                                                        after_fits):
    """Ctrl-C during the calibration (no fit done), or after the calibration, the declared
    model and one candidate were judged (a fit on all rows and one per fold of the three, each;
    the calibration one): a report marked
    partial with what was judged, no effect named from a part of the candidates."""
    from physics.loop import table_loop
    from physics.loop.report import write_report

    table, scn = shallow_rig
    real, calls = table_loop._fit, []

    def fit(*args, **kwargs):
        if len(calls) == after_fits:
            raise KeyboardInterrupt
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(table_loop, "_fit", fit)
    stopped = run_feature_table(table, scn, LoopSettings(
        max_nfev=1, candidates=("transfer_path", "friction"), segment_s=0.15))
    report = stopped.to_dict()
    assert report["partial"]["after_round"] == 0 and report["partial"]["interrupted"]
    assert report["verdict"] == "not_judged" and report["chosen_effect"] is None
    if after_fits == 0:
        assert report["calibration"] == {} and report["error_before"] is None
        assert report["ranking"] == []
    else:
        assert report["calibration"] and report["error_before"] > 0
        assert [c["effect"] for c in report["ranking"]] == ["transfer_path"]
        assert report["partial"]["missing"].startswith("1 of 2 candidates were judged")
    write_report(stopped, tmp_path / "run")
    md = (tmp_path / "run" / "report.md").read_text()
    assert "in its first round" in md and not list((tmp_path / "run").glob("*.png"))
    assert ("| transfer_path |" in md) == (after_fits > 0)


@pytest.mark.slow
def test_the_public_rigs_table_runs_from_new_to_its_deepest_stage(tmp_path):
    """The rig's 36 stage means (0-0.93 mm) at 15 rev/s, torque unknown: exit 0, every stage
    judged, an error before and after for its feature, the torque inside its prior, the figure
    of measured against model over wear."""
    stages = rig_stages()
    path = write_table(tmp_path, stages, "n1_rpm: 900\ntorque_Nm: unknown\n")
    run = run_app(tmp_path, path, "operating.torque_Nm=100", "tribology.regime=dry")
    assert run.returncode == 0, run.stderr[-2000:]
    report = json.loads((tmp_path / "run" / "report.json").read_text())
    assert report["wear_mm"] == stages.wear_mm.tolist()
    assert set(report["feature_errors"]["after"]) == {"rms"}
    assert report["error_after"] <= report["error_before"]
    torque = report["assumed"]["torque_Nm"]
    assert torque["prior"][0] <= torque["calibrated"] <= torque["prior"][1]
    assert (tmp_path / "run" / "feature_trends.png").stat().st_size > 0
