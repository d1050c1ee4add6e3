"""Severe wear (``python -m physics.reproduce.severe``): the runs stay finite and in scope, far
beyond the thesis's depths."""

from __future__ import annotations

import pytest

from physics.reproduce import severe


def test_the_runs_are_the_documented_ones():
    labels = [label for label, *_ in severe.runs()]
    assert labels[:2] == ["thesis pair, dry, quasi-static", "module 3, dry, quasi-static"]
    assert all(cycles >= 1.5e7 for _, _, cycles, _ in severe.runs())


@pytest.mark.slow
def test_severe_dry_wear_of_both_pairs_stays_in_scope():
    """Over a hundred micrometres of flank wear under the dry law, quasi-static, on the thesis's
    pair and on a module-3 pair: finite pressures below the shakedown limit."""
    runs = severe.runs()[:2]
    assert len(runs) == 2
    for _, scn, _, integrate in runs:
        row = severe.run_one(scn, 3e8, integrate)
        assert row["outcome"] == "in scope"
        assert row["pinion_max_um"] > 100 and row["p_max_GPa"] < 5.39


@pytest.mark.slow
def test_the_dynamically_loaded_dry_run_wears_deep_in_scope():
    """The dynamic load fed back at every update, dry law: over a hundred micrometres, every
    pressure below the shakedown limit."""
    _, scn, cycles, integrate = severe.runs()[2]
    row = severe.run_one(scn, cycles, integrate)
    assert row["outcome"] == "in scope" and row["pinion_max_um"] > 100
