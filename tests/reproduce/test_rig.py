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
    rows = [line for line in _section().splitlines() if re.match(r"\| \d+ \|", line)]
    assert len(rows) == len(summary)
    for line, (_, row) in zip(rows, summary.iterrows(), strict=True):
        cells = [c.strip() for c in line.strip("|").split("|")]
        expected = [f"{row['torque_Nm']:g}", f"{row['rank_correlation']:.2f}",
                    *(f"{row[f'{k}_{at:g}mm']:.2f}" for at in rig.RISE_AT_MM
                      for k in ("rise_measured", "rise_model", "model_over_measured"))]
        assert cells == expected


def test_the_docs_prose_figures_are_the_files(stages):
    text = _section()
    first = stages.loc[stages["wear_mm"] > 0].iloc[0]
    quoted = {
        "rig at its first worn stage": f"{first['rms_measured']:.2f} at "
                                       f"{first['wear_mm'] * 1e3:.0f} um",
        "rig's largest stage mean": f"{stages['rms_measured'].max():.2f}",
        "model's largest at 50-200 N m": f"{max(stages[f'rms_model_{t:g}Nm'].max() for t in (50, 100, 200)):.2f}",  # noqa: E501
        "path contact's largest at 20 N m": f"{stages['rms_path_20Nm'].max():.1f}",
        "path contact's largest at 200 N m": f"{stages['rms_path_200Nm'].max():.2f}",
    }
    missing = {k: v for k, v in quoted.items() if v not in text}
    assert not missing, f"figures the docs do not quote as the files give them: {missing}"


def test_the_command_refuses_a_missing_table(tmp_path, capsys):
    assert rig.main(["--table", str(tmp_path / "none.csv"), "--out", str(tmp_path)]) == 2
    assert "is not a file" in capsys.readouterr().err


def test_the_command_refuses_a_table_without_its_columns(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("stage,wear_mm\nHealthy,0\n")
    assert rig.main(["--table", str(bad), "--out", str(tmp_path / "out")]) == 2
    assert "columns ['acc_rms_g', 'stage_order'] are missing" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
