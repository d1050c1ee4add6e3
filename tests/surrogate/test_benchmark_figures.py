"""The benchmark's figures, one per question: ``summary.png`` (how far each model reads from
the truth on each test set, beside the estimator and the null model) and one parity figure per
test set in ``parity/`` (the networks on one panel, the estimators on the other); and its
default rig table, the packaged one."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from physics.reference import RIG_RECORDS
from surrogate import benchmark
from surrogate.figures import READERS, TEST_SETS, error_summary, label_of_set, parity_of_set

#: (model, test set) pairs of a small benchmark: two seeds of case3, one of loco2
SCENARIOS = [("case3", "heldout_trajectories", 2), ("case3", "dry_wear_law", 2),
             ("loco2", "heldout_operating_point_inside", 1), ("case3", "a_new_set", 1)]


@pytest.fixture
def bench() -> tuple[pd.DataFrame, dict]:
    rng = np.random.default_rng(0)
    rows, plots = [], {}
    for model, test, seeds in SCENARIOS:
        for seed in range(seeds):
            rows += [{"scenario": f"{model}/{test}", "estimator": reader, "seed": seed,
                      "mean_relative_error_pct": float(rng.uniform(1, 200))}
                     for reader in READERS]
        true = np.linspace(0.0, 0.02, 8)
        plots[(model, test)] = {"true": true, "surrogate": true * 1.05,
                                "estimator": true * 2, "target": "mean_wear_mm"}
    return pd.DataFrame(rows), plots


def test_the_benchmark_writes_a_summary_and_one_parity_figure_per_test_set(bench, tmp_path):
    table, plots = bench
    benchmark.write_figures(tmp_path, table, plots)
    written = {p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*.png")}
    assert written == {"summary.png", *(f"parity/{t}.png" for _, t, _ in SCENARIOS)}
    assert not list(tmp_path.glob("parity.png"))


def test_the_summary_has_a_panel_per_test_set_a_row_per_model_and_a_log_scale(bench):
    table, _ = bench
    fig = error_summary(table)
    shown = [ax for ax in fig.axes if ax.get_visible()]
    # the known sets in their order, an unknown one after them by its name
    assert [ax.get_title() for ax in shown] == [
        TEST_SETS["heldout_trajectories"], TEST_SETS["heldout_operating_point_inside"],
        TEST_SETS["dry_wear_law"], "a new set"]
    assert all(ax.get_xscale() == "log" for ax in shown)
    assert [t.get_text() for t in shown[0].get_yticklabels()] == ["case3"]
    # a dot per reader and model: the seeds' mean
    mean = table[(table.scenario == "case3/heldout_trajectories")
                 & (table.estimator == "surrogate")].mean_relative_error_pct.mean()
    dots = [line for line in shown[0].lines if line.get_marker() == READERS["surrogate"][1]]
    assert [float(d.get_xdata()[0]) for d in dots] == pytest.approx([mean])
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend == [label for label, _, _ in READERS.values()]


def test_a_test_sets_parity_has_the_networks_and_the_estimators_apart(bench):
    _, plots = bench
    fig = parity_of_set("dry_wear_law", {"case3": plots[("case3", "dry_wear_law")]})
    network, estimator = fig.axes
    assert (network.get_title(), estimator.get_title()) == ("network", "thesis's estimator")
    assert fig.get_suptitle() == label_of_set("dry_wear_law")
    # in um: the estimator's readings twice the true wear
    points = next(c for c in estimator.lines if c.get_marker() == "o")
    assert points.get_ydata() == pytest.approx(2 * np.linspace(0, 20, 8))


def test_the_real_rig_is_the_packaged_table_and_a_missing_one_is_refused(tmp_path, capsys,
                                                                           monkeypatch):
    import inspect

    assert RIG_RECORDS.is_file()
    assert inspect.signature(benchmark.real_rig).parameters["table"].default == RIG_RECORDS
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as refused:
        benchmark.main(["--real-rig-only", "--real-rig", "absent.csv"])
    assert refused.value.code == 2
    assert "--real-rig = 'absent.csv' does not exist" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())
