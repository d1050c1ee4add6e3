"""The declared model's worn states: one dynamically coupled wear run per operating point, read
at any cycle count, kept for the next need of the same operating point, ending where the model
leaves its scope."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from physics.dynamics.evolution import root_wear_evolution
from physics.gear.stiffness import mesh_stiffness
from physics.loop.measured import worn_states
from physics.loop.measured.worn_states import (
    GRID_REACH,
    records_cycles,
    records_history,
    wear_grid_cycles,
    wear_history,
    worn_models,
)
from physics.params import OutOfScope, scenario_from_config


@pytest.fixture(scope="module")
def scn():
    return scenario_from_config({"case": 3})


def test_a_shorter_need_reuses_the_run_and_a_longer_one_extends_it(scn):
    scn = dataclasses.replace(scn, operating=dataclasses.replace(  # a point no other test runs
        scn.operating, torque_Nm=scn.operating.torque_Nm + 1.0))
    first = wear_history(scn, lambda c, root: root[-1] >= 1e-3)
    assert first.root_mm[-1] >= 1e-3 > first.root_mm[-2]
    assert wear_history(scn, lambda c, root: root[-1] >= 0.5e-3) is first
    longer = wear_history(scn, lambda c, root: root[-1] >= 2e-3)
    assert longer.root_mm[-1] >= 2e-3 and len(longer.cycles) > len(first.cycles)
    n = len(first.cycles)
    np.testing.assert_array_equal(longer.cycles[:n], first.cycles)
    np.testing.assert_array_equal(longer.pinion[:n], first.pinion)


def test_the_teeth_read_off_the_run_agree_with_a_run_ending_its_blocks_there(scn):
    """The root wear at 5e6 and 1e7 cycles read off one run against a run whose blocks end on
    them exactly: the same scheme with other block ends, so within its first-order step error
    (1 um per block: a few per cent)."""
    cycles = [5e6, 1e7]
    _, root = worn_models(scn, mesh_stiffness(scn.gear, scn.material), cycles)
    exact, _ = root_wear_evolution(scn, np.array(cycles),
                                   stiffness=mesh_stiffness(scn.gear, scn.material))
    np.testing.assert_allclose([root[c] for c in cycles], exact * 1e3, rtol=0.03)


def test_records_of_known_wear_sit_at_their_wear_and_the_grid_reaches_beyond(scn):
    rows = pd.DataFrame({"cycles": [np.nan, np.nan, 2e6], "wear_mm": [0.0, 2e-3, np.nan]})
    h = records_history(scn, rows)
    cycles = records_cycles(h, rows)
    assert cycles[0] == 0.0 and cycles[2] == 2e6
    assert h.root_at(cycles[1]) == pytest.approx(2e-3, rel=1e-9)
    grid = wear_grid_cycles(h, cycles.max(), 5)
    tops = [h.root_at(c) for c in grid]
    np.testing.assert_allclose(tops, np.linspace(0.0, GRID_REACH * 2e-3, 5), atol=1e-12)
    models, root = worn_models(scn, mesh_stiffness(scn.gear, scn.material), grid, h)
    assert root[grid[-1]] == pytest.approx(GRID_REACH * 2e-3, rel=1e-9)
    assert not np.allclose(models[grid[-1]].k_a, models[0.0].k_a)  # worn teeth, other mesh
    new = pd.DataFrame({"cycles": [0.0, np.nan], "wear_mm": [np.nan, 0.0]})
    assert records_history(scn, new) is None and list(records_cycles(None, new)) == [0.0, 0.0]


def test_a_run_that_leaves_the_scope_ends_there_and_serves_every_deeper_need(scn, monkeypatch):
    """The run stops where the model leaves its scope (the wear it followed kept, the reason
    given); a deeper need gets that run, not a new one, and reads its reach; records within it
    are read (the grid of wear states ends at the reach); a depth or a cycle count beyond it
    is refused naming the reason."""
    scn = dataclasses.replace(scn, operating=dataclasses.replace(  # a point no other test runs
        scn.operating, torque_Nm=scn.operating.torque_Nm + 2.0))
    s = np.linspace(-1e-3, 1e-3, 5)
    followed = (s, np.array([0.0, 1e6, 2e6]), np.outer([0.0, 1e-6, 3e-6], np.ones(5)),
                np.zeros((3, 5)))
    runs = []

    def leaves(*args, **kwargs):
        runs.append(args)
        err = OutOfScope("the worn flanks no longer meet as one line contact")
        err.history = followed
        raise err

    monkeypatch.setattr(worn_states, "simulate_dynamic_wear", leaves)
    h = wear_history(scn, lambda c, root: root[-1] >= 1.0)
    assert h.left_scope == "the worn flanks no longer meet as one line contact"
    np.testing.assert_array_equal(h.root_mm, [0.0, 1e-3, 3e-3])
    # records: those within the reach are read, the grid of wear states ends at the reach
    within = pd.DataFrame({"cycles": [np.nan, 1.9e6], "wear_mm": [2.8e-3, np.nan]})
    assert records_history(scn, within) is h
    grid = wear_grid_cycles(h, 1.9e6, 4)  # 1.2 times 2.8 um lies beyond the reach
    np.testing.assert_allclose([h.root_at(c) for c in grid], [0.0, 1e-3, 2e-3, 3e-3])
    for deep, what in (({"cycles": [np.nan], "wear_mm": [0.9]},
                        "the 0.9 mm of the most worn record"),
                       ({"cycles": [3e6], "wear_mm": [np.nan]}, r"records at 3e\+06 cycles")):
        with pytest.raises(OutOfScope, match=what):
            records_history(scn, pd.DataFrame(deep))
    # the run once, and once the coarse run that refuses records far beyond its reach
    assert len(runs) == 2 and runs[1][0].solver.update_um == worn_states.PROBE_SOLVER["update_um"]
