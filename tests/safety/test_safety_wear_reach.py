"""Records the declared model cannot wear to are refused after a coarse run
(:func:`physics.loop.measured.worn_states.probe_reach`), not after the run at the solver's own
step that takes minutes to find its reach: a record stating wear or cycles far beyond what the
coarse run reaches before the model leaves its scope is named; records within the margin go on
to the run itself; shallow, young records skip the probe."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

import physics.loop.measured.worn_states as ws
from physics.params import OutOfScope, Scenario


def _rows(wear_mm: list[float], cycles: list[float]) -> pd.DataFrame:
    return pd.DataFrame({"record": [f"r{i}" for i in range(len(wear_mm))],
                         "wear_mm": wear_mm, "cycles": cycles})


@pytest.fixture
def runs(monkeypatch):
    """The wear runs asked for, each answered by a run that leaves the model's scope at 0.2 mm
    and 4e10 cycles (``runs`` lists the solvers' steps)."""
    asked = []

    def fake(scn, enough):
        asked.append(scn.solver.update_um)
        s = np.linspace(-1e-3, 1e-3, 5)
        cycles = np.array([0.0, 2e10, 4e10])
        root = np.array([0.0, 0.1, 0.2]) * 1e-3
        wear = np.outer(root, np.ones_like(s))
        return ws.WearHistory(s, cycles, wear, wear * 0.5, left_scope="past shakedown")

    monkeypatch.setattr(ws, "wear_history", fake)
    return asked


def test_a_record_far_beyond_the_coarse_reach_is_refused_by_name(runs):
    with pytest.raises(OutOfScope) as err:
        ws.records_history(Scenario(), _rows([0.0, 0.01, 0.5], [np.nan] * 3))
    text = str(err.value)
    assert "reaches about 0.2 mm" in text and "0.5 mm of the most worn record (record 'r2')" in text
    assert "past shakedown" in text and "leave out the records beyond it" in text
    assert runs == [ws.PROBE_SOLVER["update_um"]]  # the solver's own run was not started


def test_cycles_far_beyond_the_coarse_reach_are_refused_by_name(runs):
    with pytest.raises(OutOfScope, match=r"records at 1e\+11 cycles \(record 'r1'\) lie far "
                                         r"beyond the about 4e\+10 cycles"):
        ws.records_history(Scenario(), _rows([np.nan, np.nan], [1e6, 1e11]))
    assert runs == [ws.PROBE_SOLVER["update_um"]]


def test_a_record_within_the_margin_goes_on_to_the_run_itself(runs):
    """0.24 mm is within 1.25 times the coarse reach: the solver's own run decides (and here,
    leaving scope at 0.2 mm, refuses it)."""
    with pytest.raises(OutOfScope, match=r"reaches only 0\.2 mm"):
        ws.records_history(Scenario(), _rows([0.0, 0.24], [np.nan, np.nan]))
    assert runs == [ws.PROBE_SOLVER["update_um"], Scenario().solver.update_um]


def test_shallow_young_records_skip_the_probe(runs):
    ws.records_history(Scenario(), _rows([0.0, 0.02], [np.nan, 1e7]))
    assert runs == [Scenario().solver.update_um]


def test_the_coarse_solver_is_a_valid_coarser_one():
    base = Scenario().solver
    coarse = dataclasses.replace(base, **ws.PROBE_SOLVER)
    assert coarse.update_um > base.update_um and coarse.n_points < base.n_points
