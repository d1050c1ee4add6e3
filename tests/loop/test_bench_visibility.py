"""The loop bench's reading of where a bundle's residual stands out from the model-form error
(:mod:`physics.testbeds.loop_bench`)."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from physics.testbeds import loop_bench

GROUP = "2000rpm_300Nm_accel_m_s2_40960Hz"


@pytest.fixture(scope="module")
def bench():
    return loop_bench


def write(out: Path, label: str, residual: dict[str, float]) -> None:
    folder = out / "reports" / label
    folder.mkdir(parents=True)
    (folder / "report.json").write_text(json.dumps({"residual_before": {GROUP: residual}}))


def test_cells_are_families_and_mesh_harmonics_with_their_sidebands(bench, tmp_path):
    write(tmp_path, "b", {"line_mesh1": 3.0, "line_mesh1+g": -4.0, "line_mesh2": 0.0,
                          "line_mesh2+g": 0.0, "kurtosis": 2.0})
    cells = bench.residual_cells(tmp_path / "reports" / "b" / "report.json")
    assert cells[(GROUP, "family line_mesh")] == pytest.approx((9 / 2) ** 0.5)
    assert cells[(GROUP, "family line_mesh+g")] == pytest.approx((16 / 2) ** 0.5)
    assert cells[(GROUP, "mesh harmonic 1")] == pytest.approx(5 / 2 ** 0.5)
    assert cells[(GROUP, "mesh harmonic 2")] == 0.0
    assert cells[(GROUP, "family kurtosis")] == 2.0
    assert len(cells) == 5


def test_a_bundle_stands_out_only_above_every_other_clean_bundle_of_its_quantity(bench,
                                                                                   tmp_path):
    """The excess is over the largest other clean bundle of the same quantity (a clean bundle
    against the others: the chance level); clean bundles of the other quantity do not count;
    a sharp mode shows as one harmonic with all its sidebands, not as a family."""
    q = "accel_m_s2"
    flat = {f"line_mesh{k}{s}": 2.0 for k in (5, 6, 7) for s in ("", "+g", "-g")}
    write(tmp_path, bench.report_label("independent", None, 100, q), flat)
    write(tmp_path, bench.report_label("independent", None, 101, q),
          flat | {"line_mesh7": 3.0})
    write(tmp_path, bench.report_label("independent", None, 100, "dte_m"),
          {k: 40.0 for k in flat})
    write(tmp_path, bench.report_label("independent", "transfer_path", 0, q),
          flat | {"line_mesh6": 12.0, "line_mesh6+g": 12.0, "line_mesh6-g": 12.0})
    runs = pd.DataFrame({"generator": "independent",
                         "truth": ["none", "none", "none", "transfer_path"],
                         "seed": [100, 101, 100, 0], "quantity": [q, q, "dte_m", q]})
    seen = bench.visibility(runs, tmp_path).set_index(["truth", "seed"])
    assert seen.loc[("transfer_path", 0), "cell"] == "mesh harmonic 6"
    assert seen.loc[("transfer_path", 0), "excess_db"] == pytest.approx(10.0)
    # each clean bundle against the other: harmonic 7 of bundle 101 by (9+4+4)/3 against 4
    assert seen.loc[("none", 101), "excess_db"] == pytest.approx(round((17 / 3) ** 0.5 - 2, 1))
    assert seen.loc[("none", 100), "excess_db"] <= 0.0
    assert ("none", 100) in seen.index and len(seen) == 3  # the DTE bundle has no other clean one


def test_halving_is_attainable_only_where_the_effect_stands_twice_above_the_clean_floor(bench):
    """The floor is the smallest clean bundle's error of the same quantity: a perfect fit of
    the effect leaves at best what the declared model misses without any effect; the chance
    level is the largest."""
    runs = pd.DataFrame({
        "truth": ["none", "none", "none", "friction", "tip_relief", "sensor"],
        "quantity": ["accel_m_s2", "accel_m_s2", "dte_m", "accel_m_s2", "accel_m_s2", "dte_m"],
        "error_before": [3.3, 3.9, 3.4, 6.6, 6.5, 3.7]})
    out = bench.attainable(runs)
    assert out.clean_floor.tolist() == [3.3, 3.3, 3.4, 3.3, 3.3, 3.4]
    assert out.halving_attainable.tolist() == [False, False, False, True, False, False]
    # beyond the largest clean error of the quantity (3.9 acceleration, 3.4 DTE)
    assert out.beyond_chance.tolist() == [False, False, False, True, True, True]
