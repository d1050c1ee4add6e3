"""New to worn out (``python -m physics.reproduce.worn_out``): a short run's row, the scope
ends it names with their cycles, the command's refusals, and the figures docs/reproduction.md
quotes from the stored run."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from physics.gear.stiffness import mesh_stiffness
from physics.gear.tooth_bending import check_root_strength
from physics.params import OutOfScope
from physics.reproduce import worn_out

ROOT = Path(__file__).resolve().parents[2]
STORED = ROOT / "docs" / "figures" / "worn_out.csv"


def test_a_short_dry_run_reaches_its_depth_and_keeps_the_root_below_its_strength():
    row = worn_out.worn_out_run("thesis", 300.0, "dry", "solver", 0.02)
    assert row["outcome"] == "reached"
    assert 20 <= max(row["pinion_max_um"], row["gear_max_um"]) < 21  # the last block overshoots
    assert 0 < row["root_stress_new_MPa"] < row["root_strength_MPa"]
    assert row["root_stress_worn_MPa"] >= row["root_stress_new_MPa"]  # the largest over the life
    assert set(row) == set(worn_out.COLUMNS)


def test_a_lubricated_run_outside_the_mixed_ehl_table_is_a_named_scope_end():
    """Worn tens of micrometres, the flanks' contacts of small radius (a tip corner on the worn
    root) lie outside the solver table's film parameters: the run ends there, the row says when,
    how deep and how to go on."""
    row = worn_out.worn_out_run("thesis", 300.0, "mixed", "solver", 0.1)
    found = re.match(r"left the scope: after (\S+) cycles \(deepest wear (\d+) um\): "
                     r"mixed-EHL table", row["outcome"])
    assert found and 20 < int(found.group(2)) < 100 and float(found.group(1)) > 0, row["outcome"]
    assert "asperity_model=regression" in row["outcome"] and math.isnan(row["cycles"])


def test_a_tooth_worn_to_its_centre_line_is_named_with_the_cycles():
    scn = worn_out.scenario("rig", 20.0, "dry", "solver")
    ms = mesh_stiffness(scn.gear, scn.material)
    g = ms.geometry
    s = np.linspace(g.s_start, g.s_end, 300)
    rows = np.zeros((1, s.size))
    rows[0, -5:] = 2e-3  # the pinion's tip worn away
    with pytest.raises(OutOfScope, match=r"after 3e\+09 cycles every pinion tooth: wear of .* "
                                         r"reaches the tooth centre line"):
        check_root_strength(ms, s, rows, np.zeros((1, s.size)), 1e3, 1e9, 3e9)


def test_the_command_keeps_an_earlier_runs_file_unless_overwrite(tmp_path, capsys):
    (tmp_path / "worn_out.csv").write_text("mine\n")
    assert worn_out.main(["--out", str(tmp_path)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert (tmp_path / "worn_out.csv").read_text() == "mine\n"


def test_the_docs_quote_the_stored_run():
    """The table of docs/reproduction.md's "New to worn out" is the stored run, row by row."""
    stored = pd.read_csv(STORED)
    assert list(stored.columns) == list(worn_out.COLUMNS)
    assert [tuple(r) for r in stored[["pair", "torque_Nm", "regime", "asperity_model",
                                      "target_mm"]].itertuples(index=False)] == [
        (p, t, r, m, d) for p, t, r, m, d in worn_out.RUNS]
    text = (ROOT / "docs" / "reproduction.md").read_text()
    start = text.index("### New to worn out")
    section = text[start:text.index("\n#", start + 1)]
    rows = [[c.strip() for c in line.strip("|").split("|")]
            for line in section.splitlines() if re.match(r"\| (thesis|rig) \| ", line)]
    assert len(rows) == len(stored)

    def cell(v: float, fmt: str) -> str:
        return "-" if math.isnan(v) else format(v, fmt)

    for cells, r in zip(rows, stored.itertuples(index=False), strict=True):
        outcome = "reached" if r.outcome == "reached" else (
            "tooth worn to its centre line" if "centre line" in r.outcome else
            "outside the mixed-EHL table" if "mixed-EHL table" in r.outcome else r.outcome)
        assert cells == [r.pair, f"{r.torque_Nm:g}", r.regime, r.asperity_model,
                         f"{r.target_mm:g}", cell(r.cycles, ".3g"),
                         cell(r.pinion_max_um, ".0f"), cell(r.gear_max_um, ".0f"),
                         f"{r.root_stress_new_MPa:.0f}", cell(r.root_stress_worn_MPa, ".0f"),
                         outcome], cells
    quoted = " ".join(section.split())
    strength = stored.root_strength_MPa.iloc[0]
    assert f"{strength:.0f} MPa root fatigue strength" in quoted
    reached = stored[stored.outcome == "reached"]
    share = reached[["root_stress_new_MPa", "root_stress_worn_MPa"]].max(axis=1) / strength
    assert f"at {share.min():.2f}-{share.max():.2f} of its strength" in quoted
    tip = stored[stored.outcome.str.contains("centre line")].iloc[0]
    cycles = _e(float(re.search(r"after (\S+) cycles", tip.outcome).group(1)), ".3g")
    assert f"centre line after {cycles} cycles at {tip.torque_Nm:g} N m" in quoted
    thesis = stored[(stored.pair == "thesis") & (stored.outcome == "reached")].set_index("regime")
    assert (f"thesis pair {_e(thesis.cycles['mixed'], '.3g')} cycles to 0.3 mm (dry "
            f"{_e(thesis.cycles['dry'], '.2g')})" in quoted)
    depths = [int(re.search(r"deepest wear (\d+) um\): mixed-EHL", o).group(1))
              for o in stored.outcome if "mixed-EHL" in o]
    assert f"leave it at {depths[0]} um (thesis pair) and {depths[1]} um (rig)" in quoted


def _e(value: float, fmt: str) -> str:
    """A number as the docs write it: 1.2e9, not 1.2e+09."""
    mantissa, _, exponent = format(value, fmt).partition("e")
    return f"{mantissa}e{int(exponent)}" if exponent else mantissa
