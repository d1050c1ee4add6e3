"""The loop bench's reading of where an effect stands out from the model-form discrepancy."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_loop", ROOT / "bench" / "bench_loop.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def write(out: Path, label: str, groups: list[dict[str, float]]) -> None:
    folder = out / "reports" / label
    folder.mkdir(parents=True)
    report = {"groups": {f"g{i}": {"discrepancy_db": g} for i, g in enumerate(groups)}}
    (folder / "report.json").write_text(json.dumps(report))


def test_an_effect_stands_out_only_above_every_clean_bundle_of_its_quantity(bench, tmp_path):
    """Families are averaged over a bundle's groups and compared with the largest clean bundle
    of the same quantity; a family above the clean ones by less than nothing is no excess, and
    clean bundles of the other quantity do not count."""
    q = "accel_m_s2"
    write(tmp_path, bench.report_label("independent", None, 100, q),
          [{"line_mesh": 11.0, "line_mesh+g": 4.0}, {"line_mesh": 13.0, "line_mesh+g": 4.0}])
    write(tmp_path, bench.report_label("independent", None, 101, q),
          [{"line_mesh": 10.0, "line_mesh+g": 5.0}])
    write(tmp_path, bench.report_label("independent", None, 100, "dte_m"),
          [{"line_mesh": 30.0, "line_mesh+g": 30.0}])
    write(tmp_path, bench.report_label("independent", "gear_runout", 0, q),
          [{"line_mesh": 12.0, "line_mesh+g": 18.0}, {"line_mesh": 12.0, "line_mesh+g": 12.0}])
    write(tmp_path, bench.report_label("independent", "tip_relief", 0, q),
          [{"line_mesh": 11.0, "line_mesh+g": 3.0}])
    runs = pd.DataFrame({"generator": "independent",
                         "truth": ["none", "none", "none", "gear_runout", "tip_relief"],
                         "seed": [100, 101, 100, 0, 0],
                         "quantity": [q, q, "dte_m", q, q]})
    seen = bench.visibility(runs, tmp_path).set_index("truth")
    assert seen.loc["gear_runout", "family"] == "line_mesh+g"
    assert seen.loc["gear_runout", "excess_db"] == pytest.approx(15.0 - 5.0)
    assert seen.loc["tip_relief", "excess_db"] == pytest.approx(-1.0)  # 11 against 12
