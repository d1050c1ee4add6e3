"""The rig comparison: its files' shape, the figures docs/reproduction.md quotes from them, and
the command's refusals."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest

from physics.reproduce import rig

ROOT = Path(__file__).resolve().parents[2]
FIGURES = ROOT / "docs" / "figures"
DOC = ROOT / "docs" / "reproduction.md"


@pytest.fixture(scope="module")
def stages() -> pd.DataFrame:
    return pd.read_csv(FIGURES / "rig_comparison.csv")


@pytest.fixture(scope="module")
def summary() -> pd.DataFrame:
    return pd.read_csv(FIGURES / "rig_summary.csv")


def _section() -> str:
    text = DOC.read_text()
    start = text.index("### Against a real rig")
    return text[start:text.index("\n## ", start)]


def test_the_comparison_has_a_row_per_stage_each_over_its_new_value(stages):
    assert len(stages) == 36 and stages["wear_mm"].is_monotonic_increasing
    for col in ("rms_measured", "rms_model", *(f"rms_model_{t:g}Nm" for t in rig.TORQUES_NM)):
        assert stages.loc[stages["wear_mm"] == 0, col].item() == pytest.approx(1.0)


def test_the_docs_summary_table_is_the_files(summary):
    """Every row of the summary table in the docs is the file's, to the digits printed."""
    rows = [line for line in _section().splitlines() if re.match(r"\| (exact|path) \|", line)]
    assert len(rows) == len(summary) == 2 * len(rig.TORQUES_NM)
    for line, (_, row) in zip(rows, summary.iterrows(), strict=True):
        cells = [c.strip() for c in line.strip("|").split("|")]
        expected = [row["contact"], f"{row['torque_Nm']:g}", f"{row['rank_correlation']:.2f}",
                    *(f"{row[f'{k}_{at:g}mm']:.2f}" for at in rig.RISE_AT_MM
                      for k in ("rise_measured", "rise_model", "model_over_measured"))]
        assert cells == expected


def test_the_docs_prose_figures_are_the_files(stages, summary):
    text = _section()
    first = stages.loc[stages["wear_mm"] > 0].iloc[0]
    late = stages["wear_mm"] >= 0.5
    exact = [f"rms_model_{t:g}Nm" for t in rig.TORQUES_NM]
    path = [f"rms_path_{t:g}Nm" for t in rig.TORQUES_NM]
    corr = summary.groupby("contact")["rank_correlation"]
    quoted = {
        "rig at its first worn stage": f"{first['rms_measured']:.2f} at "
                                       f"{first['wear_mm'] * 1e3:.0f} um",
        "rig's largest stage mean": f"{stages['rms_measured'].max():.2f}",
        "exact at the first stage": f"{first[exact].min():.2f}-{first[exact].max():.2f} at 40 um",
        "exact's late medians": f"{stages.loc[late, exact].median().min():.1f}-"
                                f"{stages.loc[late, exact].median().max():.1f} times new",
        "rig's late median": f"{stages.loc[late, 'rms_measured'].median():.1f}",
        "exact's largest": f"{stages[exact].max().max():.2f}",
        "exact's rank correlations": f"{corr.min()['exact']:.2f}-{corr.max()['exact']:.2f}",
        "path's rank correlations": f"{corr.min()['path']:.2f}-{corr.max()['path']:.2f}",
        "path at 20 N m": f"{stages['rms_path_20Nm'].max():.2f} times new",
        "path at 100-200 N m": f"at most {stages[path[2:]].max().max():.2f} times new",
        "path's first relief": f"{first[path[1:]].min():.2f}-{first[path[1:]].max():.2f} at 40 um",
    }
    missing = {k: v for k, v in quoted.items() if v not in text}
    assert not missing, f"figures the docs do not quote as the files give them: {missing}"
    at50 = summary[(summary.contact == "path") & (summary.torque_Nm == 50)].iloc[0]
    assert at50.rank_correlation >= 0.9
    assert all(1 / 1.5 <= at50[f"model_over_measured_{a:g}mm"] <= 1.5 for a in rig.RISE_AT_MM)
    below = stages.loc[stages.wear_mm > 0, path[2:]].lt(
        stages.loc[stages.wear_mm > 0, "rms_measured"], axis=0).all().all()
    assert below  # "stays below the rig at every stage"


def test_the_command_refuses_a_missing_table(tmp_path, capsys):
    assert rig.main(["--table", str(tmp_path / "none.csv"), "--out", str(tmp_path)]) == 2
    assert "is not a file" in capsys.readouterr().err


def test_the_command_refuses_a_table_without_its_columns(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("stage,wear_mm\nHealthy,0\n")
    assert rig.main(["--table", str(bad), "--out", str(tmp_path / "out")]) == 2
    assert "columns ['acc_rms_g', 'stage_order'] are missing" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_the_loop_table_is_the_stage_means_with_the_rigs_stated_data(tmp_path):
    """The loop's feature table: per stage, the mean of its records' RMS (hand-computed here
    by a loop over the stages), read by the loop's reader with the rig's module, teeth and
    speed, and its torque unknown."""
    from physics.loop.measured.bundle import read_measurements
    from physics.params import Scenario

    records = rig.read_rig_table(rig.default_table())
    rig.loop_table(records, tmp_path)
    table, scn = read_measurements(tmp_path / "rig_stage_means.csv", Scenario())
    frame = table.frame
    orders = sorted(records.stage_order.unique())
    assert len(frame) == len(orders) == 36 and frame.wear_mm.is_monotonic_increasing
    for row, order in zip(frame.itertuples(), orders, strict=True):
        mine = records[records.stage_order == order]
        assert row.wear_mm == mine.wear_mm.iloc[0]
        assert row.rms_g == pytest.approx(mine.acc_rms_g.sum() / len(mine), rel=1e-12)
    assert (scn.gear.module_mm, scn.gear.z1, scn.gear.z2, scn.operating.n1_rpm) == (
        3.0, 18, 35, 900.0)
    assert table.torque_unknown
