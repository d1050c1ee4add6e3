"""The loop's three verdicts: an effect named, an unexplained residual (with the lines no
declared order explains), nothing."""

from __future__ import annotations

import json

import numpy as np
import pytest

from physics.loop import LoopSettings, read_bundle, run_loop
from physics.loop.judge.lines import declared_lines, unexplained_lines
from physics.loop.judge.verdict import entry_kind, summary_line
from physics.loop.report import STABLE_KEYS, write_report
from physics.params import scenario_from_config
from physics.testbeds import make_bundle

FS = 40960.0
F1 = 2000 / 60
F2 = F1 * 18 / 27
# the library's torque ripple only: its orders 1/2, 1 and 2 cannot explain a ripple at 2.6
# detection limits have their own tests (test_detection.py)
FAST = LoopSettings(max_nfev=6, explore=8, refine=1, candidates=("torque_ripple",),
                    detection_limits=False)


def gear_like(seed: int, ripple_order: float | None, seconds: float = 0.5) -> np.ndarray:
    """Mesh harmonics with pinion sidebands, shaft lines, white noise; a line at
    ``ripple_order`` with a mesh sideband if given."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    x = 0.05 * np.sin(2 * np.pi * F1 * t) + 0.03 * np.sin(2 * np.pi * F2 * t + 1)
    for k in range(1, 20):
        for j in (-2, -1, 0, 1, 2):
            x += (1 if j == 0 else 0.1) * np.sin(2 * np.pi * (k * 18 + j) * F1 * t
                                                 + rng.uniform(0, 6))
    if ripple_order is not None:
        for f in (ripple_order * F1, 18 * F1 + ripple_order * F1):
            x += 0.02 * np.sin(2 * np.pi * f * t + rng.uniform(0, 6))
    return x + 0.1 * rng.standard_normal(t.size)


def test_a_line_between_the_declared_orders_is_found_and_nothing_on_clean_records():
    clean = unexplained_lines([gear_like(s, None) for s in range(6)], FS, F1, F2, 18, 0.01)
    assert clean == []
    found = unexplained_lines([gear_like(s, 2.6) for s in range(6)], FS, F1, F2, 18, 0.01)
    orders = sorted(round(x["order"], 1) for x in found)
    assert orders == [2.6, 20.6]  # the ripple's line and its upper sideband of mesh 1
    assert all(x["records"] == 6 and x["level_db"] > x["threshold_db"] for x in found)
    side = next(x for x in found if x["order"] > 18)
    assert side["mesh_harmonic"] == 1 and side["offset_order"] == pytest.approx(2.6, abs=0.05)
    # amplitude of the line, in the record's unit (0.02), within the window's scalloping
    assert found[0]["amplitude"] == pytest.approx(0.02, rel=0.15)
    # a line in one record only does not persist
    lone = [gear_like(s, 2.6 if s == 0 else None) for s in range(6)]
    assert unexplained_lines(lone, FS, F1, F2, 18, 0.01) == []


def test_declared_lines_hold_the_orders_the_model_and_library_make():
    lines = declared_lines(F1, F2, 18, 2000.0)
    for f in (F1, 2 * F1, F1 / 2, F2, 2 * F2, 18 * F1, 18 * F1 - F2, 18 * F1 + F1 / 2):
        assert np.min(np.abs(lines - f)) < 1e-9
    assert np.min(np.abs(lines - 2.6 * F1)) > 10


@pytest.mark.parametrize(("name", "kind"), [("line_mesh3", "mesh harmonic"),
                                            ("line_mesh3-2p", "pinion sideband"),
                                            ("line_mesh1+g", "gear sideband"),
                                            ("line_shaft1/2", "shaft order"),
                                            ("band03", "band"), ("kurtosis", "statistic")])
def test_entry_kinds(name, kind):
    assert entry_kind(name) == kind


@pytest.fixture(scope="module")
def scn():
    return scenario_from_config({"case": 3})


@pytest.mark.slow
def test_a_ripple_at_a_non_integer_order_is_an_unexplained_residual(tmp_path, scn):
    path, truth = make_bundle(tmp_path / "ripple", scn, "torque_ripple", seed=2, records=6,
                              duration_s=0.75, values={"order": 2.6})
    assert truth["values"]["order"] == 2.6
    report = run_loop(read_bundle(path), scn, FAST)
    write_report(report, tmp_path / "run")
    saved = json.loads((tmp_path / "run" / "report.json").read_text())
    assert tuple(saved)[:len(STABLE_KEYS)] == STABLE_KEYS
    assert saved["verdict"] == "unexplained_residual" and saved["chosen_effect"] is None
    (label, where), = saved["unexplained"]["groups"].items()
    assert label == "2000rpm_300Nm_accel_m_s2_40960Hz"
    orders = [x["order"] for x in where["lines"]]
    assert min(abs(o - 2.6) for o in orders) < 0.05  # the ripple's own line ...
    # ... and its mesh sidebands, each 2.6 orders from a mesh harmonic
    assert sum(abs(abs(x["offset_order"]) - 2.6) < 0.05 for x in where["lines"]) >= 10
    assert [c["effect"] for c in saved["unexplained"]["closest"]] == ["torque_ripple"] * 3
    md = (tmp_path / "run" / "report.md").read_text()
    assert "**Verdict: unexplained residual.**" in md and "pinion order 2.600" in md
    assert (tmp_path / "run" / "unexplained.png").stat().st_size > 0


def test_a_clean_bundle_gets_none(tmp_path, scn):
    path, _ = make_bundle(tmp_path / "clean", scn, None, seed=2, records=6, duration_s=0.75)
    report = run_loop(read_bundle(path), scn, FAST)
    assert report["verdict"] == "none" and report["unexplained"] is None
    write_report(report, tmp_path / "run", with_figures=False)
    md = (tmp_path / "run" / "report.md").read_text()
    # without a reference the line says whose scatter it judged against, and what to do
    assert "**Verdict: none.**" in md and "cannot be told from the declared model's form" in md
    assert "reference=first:N" in md


def test_a_none_verdict_says_what_it_rests_on():
    """Against a reference, "none" speaks of the clean reference records; without one, of the
    bundle's own train records, with the held-out error and the reference to read against; on
    a feature table, of its rows."""
    base = {"verdict": "none", "mode": "bundle", "error_before": 5.5,
            "error_unit": "noise units", "form_reference": None}
    own = summary_line(base)
    assert "own train records" in own and "5.5, noise units" in own
    assert "reference=first:N" in own
    ref = summary_line(base | {"form_reference": {"source": "first:2"}})
    assert "clean reference records" in ref and "reference=first:N" not in ref
    table = summary_line(base | {"mode": "feature_table"})
    assert "table's rows" in table and "train records" not in table


def test_an_unexplained_residual_names_what_the_reference_cannot_show():
    """Against the unit's own earliest records (its calibration held) the line says that the
    model's response to the wear since them is part of the residual; against a sister unit,
    the two units' difference; without a reference, neither."""
    base = {"verdict": "unexplained_residual", "form_reference": None,
            "unexplained": {"groups": {"g": {"lines": [], "entries": [
                {"entry": "line_mesh1", "residual_db": -9.0, "z": -12.0}]}}, "closest": []}}
    held = summary_line(base | {"form_reference": {"calibration_held": True}})
    assert "line_mesh1 (-9.0 dB, z -12.0)" in held and "changes with the wear" in held
    assert "units' difference" not in held
    sister = summary_line(base | {"form_reference": {"calibration_held": False}})
    assert "units' difference" in sister and "changes with the wear" not in sister
    alone = summary_line(base)
    assert "changes with the wear" not in alone and "units' difference" not in alone
