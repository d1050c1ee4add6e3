"""The reproduction app writes every table named and shaped like the thesis reference."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

REF = Path(__file__).resolve().parents[2] / "shared" / "reference" / "thesis_tables"
FAST = ["solver.n_points=101", "stiffness.fem_refine=1", "stiffness.fem_refines=[1]",
        "stiffness.positions=50"]
TABLES = ["table02_speed", "table03_torque", "table04_roughness", "table05_lubricant",
          "table06_center_distance", "table07_tvms_energy_vs_fem", "table08_wear_vs_stiffness"]


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    out = tmp_path_factory.mktemp("repro")
    subprocess.run(
        [sys.executable, "-m", "physics.reproduce", f"out_dir={out}", *FAST,
         f"hydra.run.dir={out / 'hydra'}"],
        check=True, cwd=Path(__file__).resolve().parents[1],
    )
    return out


@pytest.mark.parametrize("name", TABLES)
def test_table_shape_matches_reference(out, name):
    ours = pd.read_csv(out / f"{name}.csv")
    if not REF.is_dir():
        pytest.skip("shared/reference is not beside this checkout")
    ref = pd.read_csv(REF / f"{name}.csv")
    assert list(ours.columns) == list(ref.columns)
    assert ours.iloc[:, 0].astype(str).str.lower().tolist() == \
        ref.iloc[:, 0].astype(str).str.lower().tolist()
    assert ours.select_dtypes("number").notna().all().all()


def test_wear_profile_outputs(out):
    df = pd.read_csv(out / "wear_profile.csv")
    assert list(df.columns) == ["side", "roll_mm", "radius_mm", "zone", "wear_um"]
    assert set(df.side) == {"pinion", "gear"} and set(df.zone) == {"single", "double"}
    assert (df.wear_um >= 0).all()
    assert (out / "wear_profile.png").stat().st_size > 10_000
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporaries


def test_overrides_reach_the_physics(tmp_path):
    subprocess.run(
        [sys.executable, "-m", "physics.reproduce", f"out_dir={tmp_path}", *FAST,
         "gear.module_mm=3", "gear.bore_radius1_mm=12",
         "gear.bore_radius2_mm=20", f"hydra.run.dir={tmp_path / 'hydra'}"],
        check=True, cwd=Path(__file__).resolve().parents[1],
    )
    df = pd.read_csv(tmp_path / "wear_profile.csv")
    assert df.radius_mm.max() == pytest.approx(3 * 27 / 2 + 3, rel=1e-6)  # gear tip radius


def test_bad_override_fails_before_writing(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "physics.reproduce", f"out_dir={tmp_path / 'x'}",
         "operating.torque_Nm=-5", f"hydra.run.dir={tmp_path / 'hydra'}"],
        cwd=Path(__file__).resolve().parents[1], capture_output=True, text=True,
    )
    assert proc.returncode != 0
    assert "operating.torque_Nm = -5.0 must lie in" in proc.stderr
    assert not (tmp_path / "x").exists()
