"""Wear tooth by tooth (``python -m physics.reproduce.teeth``): a small study's physics, the
command's refusals, and the figures docs/reproduction.md quotes from the stored run."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from physics.reproduce import teeth

ROOT = Path(__file__).resolve().parents[2]
STORED = ROOT / "docs" / "figures" / "tooth_wear.csv"


def test_teeth_off_their_places_reach_a_depth_sooner(monkeypatch):
    """The tooth that stands ahead carries more and reaches a depth before the pair worn alike
    does, while the least worn tooth lags; every feature stays finite and positive."""
    monkeypatch.setattr(teeth, "DEPTHS_UM", (2.0,))
    scn = teeth.scenario()
    # the path contact's dynamics (the wear, which the assertions read, is the same) over one
    # hunting period: two whole gear revolutions for the gear's synchronous average
    dyn = dataclasses.replace(teeth.whole_record(scn.dynamics, 3, 2000.0), flank_contact="path")
    scn = dataclasses.replace(scn, solver=dataclasses.replace(scn.solver, update_um=1.0),
                              dynamics=dyn)
    table = teeth.tooth_study(scn, [(9, 0, False)], None)
    assert list(table.columns) == list(teeth.COLUMNS)
    assert set(table.feature) == set(teeth.FEATURES)
    row = table.iloc[0]
    assert 0 < row.cycles_ratio < 0.9 and 0 < row.least_tooth_um < 2.0
    assert np.all(np.isfinite(table[["rise_own", "rise_alike"]])) and np.all(table.rise_own > 0)
    assert table.rise_measured.isna().all()


@pytest.mark.parametrize(("args", "message"), [
    (["--grades", "3"], "--grades 3: the datasets' ISO 1328 grades are 4-9"),
    (["--seeds", "0"], "--seeds 0: give at least one gearbox"),
])
def test_the_command_refuses_before_any_work(args, message, tmp_path, capsys):
    assert teeth.main([*args, "--out", str(tmp_path)]) == 2
    assert message in capsys.readouterr().err


def test_an_earlier_runs_files_are_kept_unless_overwrite(tmp_path, capsys):
    (tmp_path / "tooth_wear.csv").write_text("mine\n")
    assert teeth.main(["--out", str(tmp_path)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert (tmp_path / "tooth_wear.csv").read_text() == "mine\n"


def test_the_docs_quote_the_stored_run():
    """The tooth-by-tooth table of docs/reproduction.md is the stored run's at Table 15's
    deepest wear, per grade: the mean over the seeds, the pinion's teeth each their own, and
    the run with both wheels'; and the prose's figures."""
    stored = pd.read_csv(STORED)
    text = (ROOT / "docs" / "reproduction.md").read_text()
    start = text.index("### Tooth by tooth")
    section = text[start:text.index("\n#", start + 1)]
    quoted = " ".join(section.split())
    rows = [[c.strip() for c in line.strip("|").split("|")]
            for line in section.splitlines() if re.match(r"\| (pinion|both) \| ", line)]
    deepest = stored[stored.wear_um == stored.wear_um.max()]
    by = ["wheels", "grade"]
    rms = deepest[deepest.feature == "rms"].groupby(by).mean(numeric_only=True)
    kurt = deepest[deepest.feature == "kurtosis"].groupby(by).mean(numeric_only=True)
    assert len(rows) == len(rms)
    for cells in rows:
        key = (cells[0], int(cells[1]))
        r, k = rms.loc[key], kurt.loc[key]
        assert cells[2:] == [f"{r.cycles_ratio:.2f}", f"{r.least_tooth_um:.1f}",
                             f"{r.position_range_um:.1f}", f"{r.rise_own:.2f}",
                             f"{r.rise_alike:.2f}", f"{k.rise_own:.2f}", f"{k.rise_alike:.2f}"], key
    measured = deepest[deepest.feature == "rms"].rise_measured.iloc[0]
    assert f"RMS x{measured:.2f}" in quoted
    pinion = rms.loc["pinion"]
    assert (f"{pinion.cycles_ratio.min():.2f}-{pinion.cycles_ratio.max():.2f} of the cycles"
            in quoted)
    lag = stored.wear_um.max() - pinion.least_tooth_um
    assert f"lags by {lag.min():.1f}-{lag.max():.1f} um" in quoted
    assert (lag < pinion.position_range_um).all()  # "within the pinion positions' range"
    both = rms.loc[("both", 7)]
    assert stored.wear_um.max() - both.least_tooth_um > both.position_range_um  # "beyond it"
    # "every feature falls (less tooth by tooth)" of Table 15's three, "the sideband level falls
    # as wear levels the teeth, rises where they stay off (alike)"
    means = deepest.groupby(["feature", *by]).mean(numeric_only=True)  # the seeds' means
    table15 = means.loc[["rms", "peak_to_peak", "kurtosis"]]
    assert (table15.rise_own < 1).all() and (table15.rise_alike < 1).all()
    assert (rms.rise_own > rms.rise_alike).all()
    sideband = means.loc["sideband_level"]
    assert (sideband.rise_own < 1).all() and (sideband.rise_alike > 1).all()
