"""Every accepted bundle runs to the end: ranges clipped to what the records show, an unknown
torque calibrated, a partial report after the first round, refusals before work."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import physics.loop.bundle_loop as bundle_loop
from physics.loop import EFFECTS, LoopSettings, check_usable, read_bundle, run_loop, write_bundle
from physics.loop.measured.records import group_label
from physics.loop.measured.usable import shown_candidates
from physics.loop.report import write_report
from physics.loop.search import attribution
from physics.loop.search.attribution import candidates_for
from physics.loop.threads import TimeLimit
from physics.params import scenario_from_config
from physics.testbeds import make_bundle
from tests.acceptance.refusal import refusal, tree

ROOT = Path(__file__).resolve().parents[2]
#: a public gearbox's acceleration records: 12.9 kHz
FS = 12900.0
SETTINGS = LoopSettings(max_nfev=4, explore=4, refine=1,
                        candidates=("transfer_path", "friction"))


def manifest(n=4, **over):
    d = {"record": [f"r{i}" for i in range(n)], "quantity": "accel_m_s2", "fs_hz": FS,
         "n1_rpm": 2000.0, "torque_Nm": 300.0, "wear_mm": "", "cycles": "", "split": ""}
    d.update(over)
    return pd.DataFrame(d)


def noise(n=4, seconds=0.6, fs=FS):
    rng = np.random.default_rng(0)
    return {f"r{i}": rng.standard_normal(int(seconds * fs)) for i in range(n)}


@pytest.mark.parametrize("cell", ["", "unknown", "Unknown", "null", "NaN"])
def test_the_torque_may_be_unknown(tmp_path, cell):
    b = read_bundle(write_bundle(tmp_path / "b", manifest(torque_Nm=cell), noise()))
    assert b.manifest.torque_Nm.isna().all()
    assert group_label((2000.0, None, "accel_m_s2", FS)) == "2000rpm_unknownNm_accel_m_s2_12900Hz"


def test_a_bad_torque_is_refused_naming_value_rule_and_fix(tmp_path):
    path = write_bundle(tmp_path / "b", manifest(torque_Nm="abc"), noise())
    with pytest.raises(ValueError, match=r"record 'r0': torque_Nm = 'abc' must be a positive "
                                         r"number, or empty or 'unknown'"):
        read_bundle(path)


def test_gear_data_the_signature_does_not_need_may_be_unknown(tmp_path):
    b = read_bundle(write_bundle(tmp_path / "b", manifest(), noise(),
                                 gear={"face_width_mm": "unknown", "z1": 18}))
    assert b.gear == {"z1": 18} and b.unknown_gear == ("face_width_mm",)
    bad = write_bundle(tmp_path / "c", manifest(), noise(), gear={"z1": "unknown"})
    with pytest.raises(ValueError, match=r"tooth numbers .* cannot be unknown"):
        read_bundle(bad)


def test_each_range_is_clipped_to_what_the_records_show(tmp_path):
    b = read_bundle(write_bundle(tmp_path / "b", manifest(), noise()))
    scn = scenario_from_config({"case": 3})
    kept, dropped = shown_candidates(candidates_for({"accel_m_s2"}, LoopSettings()), b, scn,
                                     LoopSettings())
    path = next(e for e, _ in kept if e.name == "transfer_path")
    fn = next(p for p in path.params if p.name == "fn_hz")
    assert fn.high == pytest.approx(0.45 * FS) and fn.low < fn.typical < fn.high
    assert dropped == {}
    assert next(p for p in EFFECTS["transfer_path"].params if p.name == "fn_hz").high == 15000
    # at 200 r/min a half-order ripple (1.7 Hz) and the gear's sidebands are not resolved in
    # 0.25 s segments; the whole-order ripples are left too
    slow = read_bundle(write_bundle(tmp_path / "s", manifest(n1_rpm=200.0), noise(seconds=4)))
    kept, dropped = shown_candidates(candidates_for({"accel_m_s2"}, LoopSettings()), slow, scn,
                                     LoopSettings())
    assert "gear_runout" in dropped and "torque_ripple {'order': 0.5}" in dropped
    assert "friction" in {e.name for e, _ in kept}


def test_a_bundle_the_loop_cannot_use_is_refused_before_work(tmp_path):
    scn = scenario_from_config({"case": 3})
    b = read_bundle(write_bundle(tmp_path / "b", manifest(), noise()))
    with pytest.raises(ValueError, match=r"record 'r0': an analysis segment of loop.segment_s "
                                         r"= 0.02 s holds 0.67 pinion revolutions .* set "
                                         r"loop.segment_s >= 0.03"):
        check_usable(b, scn, LoopSettings(segment_s=0.02))
    with pytest.raises(ValueError, match=r"less than two analysis segments .* set "
                                         r"loop.segment_s <= 0.3"):
        check_usable(b, scn, LoopSettings(segment_s=0.4))


def test_the_app_refuses_in_one_line(tmp_path, config_store):
    """The app's checks refuse it before work (a refusal's exit path, one line on stderr and
    exit code 2: tests/acceptance/test_bad_input.py)."""
    path = write_bundle(tmp_path / "b", manifest(), noise())
    (tmp_path / "work").mkdir()
    err = refusal("loop", [f"data={path}", "loop.segment_s=0.02"], tmp_path / "work")
    assert isinstance(err, ValueError) and "\n" not in str(err)
    assert str(err).startswith("bundle") and "loop.segment_s >= 0.03" in str(err)
    assert not tree(tmp_path / "work")


@pytest.fixture(scope="module")
def public_like(tmp_path_factory):
    """Acceleration records at 12.9 kHz with a housing mode, of a speed and a torque the
    manifest leaves unknown, and a gear.yaml whose face width is unknown."""
    scn = scenario_from_config({"case": 3, "dynamics": {"sample_rate_hz": FS}})
    folder = tmp_path_factory.mktemp("public")
    path, truth = make_bundle(folder / "made", scn, "transfer_path", seed=2, records=6,
                              duration_s=0.75)
    b = read_bundle(path)
    man = b.manifest.assign(n1_rpm="unknown", torque_Nm="unknown", wear_mm="", cycles="")
    path = write_bundle(folder / "b", man, b.signals, gear={"face_width_mm": None})
    return read_bundle(path), scenario_from_config({"case": 3}), truth


def second_round_raises(monkeypatch, stop: type[BaseException]) -> list:
    """The loop's attribution as it is for the first round, raising ``stop`` when the second
    starts; returns the list of its calls."""
    real, calls = bundle_loop.attribute, []

    def attribute(*args, **kwargs):
        calls.append(1)
        if len(calls) > 1:
            raise stop
        return real(*args, **kwargs)

    monkeypatch.setattr(bundle_loop, "attribute", attribute)
    return calls


def test_a_public_like_bundle_runs_to_the_end_and_stops_after_round_one(public_like,
                                                                        tmp_path, monkeypatch):
    """The time limit passes in the second round (its attribution raises it): the first
    round's report, marked partial."""
    bundle, scn, _ = public_like
    calls = second_round_raises(monkeypatch, TimeLimit)
    report = run_loop(bundle, scn, dataclasses.replace(SETTINGS, time_limit_s=600.0))
    assert len(calls) == 2
    assert report["verdict"] == "effect" and report["chosen_effect"] == "transfer_path"
    assert report["chosen_parameters"]["fn_hz"] < 0.45 * FS
    assert report["partial"]["stopped"].startswith("time limit")
    assert report["partial"]["after_round"] == 1 and report["second_round"] is None
    torque = report["assumed"]["torque_Nm"]
    assert torque["records"] == bundle.records and torque["prior"] == [60.0, 1500.0]
    assert 60 <= torque["calibrated"] <= 1500
    assert report["assumed"]["gear"] == {"face_width_mm": scn.gear.face_width_mm}
    speed = report["assumed"]["n1_rpm"]  # made at 2000 r/min, read off the spectra
    assert speed["records"] == bundle.records
    assert all(abs(v / 2000 - 1) < 2e-6 for v in speed["read_rpm"].values())
    assert set(speed["used_rpm"].values()) == {float(bundle.manifest.n1_rpm.iloc[0])}
    assert set(report["groups"]) == {"2000rpm_unknownNm_accel_m_s2_12900Hz"}
    write_report(report, tmp_path / "run", with_figures=False)
    saved = json.loads((tmp_path / "run" / "report.json").read_text())
    assert saved["partial"]["stopped"].startswith("time limit")
    md = (tmp_path / "run" / "report.md").read_text()
    assert "**Partial report:**" in md and "Torque unknown for 6 records" in md
    assert "Speed unknown for 6 records: read off each one's spectrum" in md


def test_an_interrupt_after_round_one_keeps_its_report(public_like, monkeypatch):
    bundle, scn, _ = public_like
    calls = second_round_raises(monkeypatch, KeyboardInterrupt)
    report = run_loop(bundle, scn, SETTINGS)
    assert len(calls) == 2
    assert report["partial"] == {"stopped": "interrupted", "after_round": 1,
                                 "interrupted": True,
                                 "missing": report["partial"]["missing"]}
    assert report["chosen_effect"] == "transfer_path"


@pytest.mark.parametrize("stop", ["interrupt", "time_limit"])
def test_a_stop_in_the_first_round_keeps_the_calibration_and_the_candidates_fitted(
        public_like, monkeypatch, tmp_path, stop):
    """Ctrl-C after two candidates were screened, or a time limit already passed when the
    screening starts: a report marked partial after round 0 with the calibration and the
    candidates fitted by then (none judged, no effect named, no held-out error made up),
    written as report.json and report.md; nothing more is simulated after the stop."""
    bundle, scn, _ = public_like
    settings = dataclasses.replace(SETTINGS, candidates=None)
    real, screened = attribution.screen_effect, []

    def screen_effect(*args, **kwargs):
        if stop == "interrupt" and len(screened) >= 2:
            raise KeyboardInterrupt
        out = real(*args, **kwargs)
        screened.append(out)
        return out

    monkeypatch.setattr(attribution, "screen_effect", screen_effect)
    if stop == "time_limit":
        settings = dataclasses.replace(settings, time_limit_s=1e-6)
    report = run_loop(bundle, scn, settings)
    p = report["partial"]
    assert p["after_round"] == 0 and p["interrupted"] == (stop == "interrupt")
    assert p["stopped"] == ("interrupted" if stop == "interrupt" else "time limit of 1e-06 s")
    assert report["verdict"] == "not_judged" and report["chosen_effect"] is None
    assert report["error_before"] is None and report["null_bic"] is None
    assert set(report["calibration"]) >= {"housing_mass_kg", "torque_factor"}
    fitted = {(c["effect"], str(c["option"])) for c in report["ranking"]}
    assert fitted == {(c.name, str(c.option)) for c in screened}
    assert len(fitted) == (2 if stop == "interrupt" else 0)
    assert all(not c["refined"] and c["train_rss"] > 0 for c in report["ranking"])
    write_report(report, tmp_path / "run")
    saved = json.loads((tmp_path / "run" / "report.json").read_text())
    assert saved["partial"]["after_round"] == 0 and saved["verdict"] == "not_judged"
    md = (tmp_path / "run" / "report.md").read_text()
    assert "in its first round" in md and "Calibrated nuisance parameters (the train" in md
    assert ("Candidates fitted by then" in md) == (stop == "interrupt")
    assert not list((tmp_path / "run").glob("*.png"))  # no figure of what was not computed


def test_the_app_stopped_by_its_time_limit_in_the_first_round_writes_the_partial_report(
        public_like, tmp_path):
    """``loop.time_limit_s`` already passed when the screening starts: exit 0, one line
    saying what is kept, report.json and report.md of the first round's calibration, no
    traceback and no figure."""
    bundle, _, _ = public_like
    run = subprocess.run([sys.executable, "-m", "physics.loop", f"data={bundle.path}",
                          "loop.time_limit_s=1e-6", "loop.max_nfev=4", "loop.explore=4",
                          "loop.candidates=[transfer_path,friction]", "progress=false",
                          f"hydra.run.dir={tmp_path / 'run'}"],
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    said = run.stdout + run.stderr  # the log goes to the console and the run folder
    assert "Traceback" not in said
    assert "the time limit of 1e-06 s passed in the first round" in said
    saved = json.loads((tmp_path / "run" / "report.json").read_text())
    assert saved["partial"]["after_round"] == 0 and saved["verdict"] == "not_judged"
    assert saved["calibration"] and saved["ranking"] == []
    assert "in its first round" in (tmp_path / "run" / "report.md").read_text()
    assert not list((tmp_path / "run").glob("*.png"))


def test_a_stop_during_the_calibration_keeps_no_calibration_and_says_so(public_like,
                                                                        monkeypatch):
    bundle, scn, _ = public_like

    def calibrate(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(bundle_loop, "calibrate", calibrate)
    report = run_loop(bundle, scn, SETTINGS)
    assert report["partial"]["after_round"] == 0 and report["partial"]["interrupted"]
    assert report["partial"]["missing"] == ("the calibration was not finished: no candidate "
                                            "was searched")
    assert report["calibration"] == {} and report["ranking"] == []
    assert report["calibrated_on"].startswith("not calibrated")
