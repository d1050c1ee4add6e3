"""The figures docs/loop.md quotes from the loop's runs stored in ``docs/figures/loop/`` (each
run's ``report.json``, written by ``python -m physics.loop`` with the command the page gives):
each quote is rebuilt from its file at the digits shown, so changing a file or the page alone
fails."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RUNS = ROOT / "docs" / "figures" / "loop"


def _page() -> str:
    return " ".join((ROOT / "docs" / "loop.md").read_text().split())


def _report(run: str) -> dict:
    return json.loads((RUNS / run / "report.json").read_text())


def test_table15_at_the_configured_torque():
    r = _report("table15_configured")
    assert r["chosen_effect"] == "tip_relief" and r["verdict"] == "effect"
    cal = r["calibration"]
    rise, measured = r["rise_after"], r["rise_measured"]
    quotes = [
        f"(damping {cal['damping_ratio']:.2f}, profile error {cal['profile_error_um']:.0f} um, "
        f"`m_h` {cal['housing_mass_kg']:.0f} kg:",
        f"a {r['chosen_parameters']['relief_um']:.0f} um tip relief is adopted (held-out error "
        f"{r['error_before']:.3f} -> {r['error_after']:.3f})",
        f"RMS x{rise['rms']:.2f} (measured x{measured['rms']:.2f}), peak-to-peak "
        f"x{rise['peak_to_peak']:.2f} (x{measured['peak_to_peak']:.2f}) and kurtosis "
        f"x{rise['kurtosis']:.2f} (x{measured['kurtosis']:.1f})",
    ]
    page = _page()
    for quote in quotes:
        assert quote in page, quote


def _tooth_defect_not_adopted(run: str) -> tuple[dict, dict, dict, float]:
    """A stored run whose best candidate, a tooth defect, missed the BIC condition: the
    report, that candidate, its BIC check and the share of the held-out error it cut."""
    r = _report(run)
    assert r["chosen_effect"] is None and r["verdict"] == "none"
    best = r["ranking"][0]
    check = r["verdicts"][0]["checks"]["delta_bic"]
    assert best["effect"] == "tooth_defect" and not check["holds"]
    return r, best, check, 1 - best["heldout_error"] / r["error_before"]


def test_table15_with_its_torque_unknown():
    r, best, check, cut = _tooth_defect_not_adopted("table15_unknown")
    quote = (f"torque {r['assumed']['torque_Nm']['calibrated']:.0f} N m; a tooth defect cuts the "
             f"held-out error by {cut:.0%} ({r['error_before']:.3f} -> "
             f"{best['heldout_error']:.3f}), its BIC by {-check['value']:.0f} of the "
             f"{-check['bound']:.0f} required").replace("%", " %")
    assert quote in _page(), quote


def test_table15_with_its_torque_and_speed_unknown():
    r, best, check, cut = _tooth_defect_not_adopted("table15_operating_unknown")
    assert set(r["assumed"]) == {"torque_Nm", "n1_rpm"}
    low, _ = r["assumed"]["torque_Nm"]["prior"]
    torque = best["nuisance"]["torque_factor"] * r["assumed"]["torque_Nm"]["configured"]
    speed = best["nuisance"]["speed_factor"] * r["assumed"]["n1_rpm"]["configured"]
    assert torque == pytest.approx(low, rel=1e-3)  # at its bound
    quote = (f"a tooth defect cuts it by {cut:.0%} ({r['error_before']:.3f} -> "
             f"{best['heldout_error']:.3f}) at {speed:.0f} r/min, the torque at its {low:.0f} "
             f"N m bound, its BIC by {-check['value']:.1f} of the {-check['bound']:.0f} "
             "required").replace("%", " %")
    assert quote in _page(), quote


@pytest.mark.parametrize("run", ["table15_configured", "table15_unknown",
                                 "table15_operating_unknown"])
def test_each_stored_run_is_a_feature_table_run(run):
    r = _report(run)
    assert r["mode"] == "feature_table" and r["wear_mm"] == [0.0, 0.005, 0.01, 0.015]


def test_the_public_rigs_stage_means():
    r = _report("rig")
    torque = r["assumed"]["torque_Nm"]
    low = r["at_bound"]["before"]["housing_mass_kg"]
    defect = r["chosen_parameters"]
    quotes = [
        f"torque {torque['calibrated']:.0f} N m (prior {torque['prior'][0]:.0f}-"
        f"{torque['prior'][1]:.0f}), the null's `m_h` at its {low[1]:.0f} kg bound",
        f"a tooth defect growing with the wear adopted ({r['error_before']:.3f} -> "
        f"{r['error_after']:.3f}; mean relative {r['feature_error_before_pct']:.1f} -> "
        f"{r['feature_error_after_pct']:.1f} %; RMS rise to the last stage "
        f"{r['rise_measured']['rms']:.2f}, model {r['rise_before']['rms']:.2f} -> "
        f"{r['rise_after']['rms']:.2f})",
        f"its depth at its bound ({defect['depth_um']:.0f} of "
        f"{r['at_bound']['chosen effect']['depth_um'][1]:.0f} um, {defect['face_share']:.2f} of "
        f"the face), the torque refitted to {torque['after']:.0f} N m",
    ]
    assert r["chosen_effect"] == "tooth_defect" and len(r["wear_mm"]) == 36
    assert low[0] == "lower"
    page = _page()
    for quote in quotes:
        assert quote in page, quote
