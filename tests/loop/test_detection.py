"""Detection limits: beside every candidate not named, the smallest size the rule would name on
the bundle's own records (physics.loop.search.detection)."""

from __future__ import annotations

import pytest

from physics.loop import EFFECTS, LoopSettings, read_bundle, run_loop, write_report
from physics.loop.judge.adoption import holds
from physics.loop.model.discrepancy import with_discrepancy
from physics.loop.model.simulation import model_signals
from physics.loop.search.detection import judged_at, size_param
from physics.params import scenario_from_config
from physics.testbeds import make_bundle

FAST = LoopSettings(max_nfev=6, explore=8, refine=1,
                    candidates=("torque_ripple", "transfer_path"))


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    scn = scenario_from_config({"case": 3})
    path, _ = make_bundle(tmp_path_factory.mktemp("clean") / "b", scn, None, seed=2, records=6,
                          duration_s=0.75)
    return run_loop(read_bundle(path), scn, FAST)


@pytest.mark.slow
def test_each_candidate_not_named_has_its_limit_in_the_report(clean, tmp_path):
    assert clean["verdict"] == "none"
    limits = clean["detection_limits"]
    assert [(d["effect"], d["option"]) for d in limits] == [
        ("torque_ripple", {"order": 1}), ("torque_ripple", {"order": 2}),
        ("torque_ripple", {"order": 0.5}), ("transfer_path", {})]
    for d in limits:
        p = size_param(EFFECTS[d["effect"]])
        assert d["parameter"] == p.name and 1 <= d["sizes_tried"] <= 6
        assert d["limit"] is not None or d["not_named_at"] is not None
        if d["limit"] is not None:
            assert p.low <= d["limit"] <= p.high
        if d["limit"] is not None and d["not_named_at"] is not None:
            assert d["not_named_at"] < d["limit"]
    for row in clean["ranking"]:  # beside each candidate of the ranking
        assert row["detection_limit"] in limits
    write_report(clean, tmp_path, with_figures=False)
    md = (tmp_path / "report.md").read_text()
    assert "## Detection limits" in md and "| transfer_path |  | residue" in md


@pytest.mark.slow
def test_the_limit_is_where_the_rule_starts_naming(clean):
    """At the reported limit the null test holds on the injected records, at the largest
    size tried below it it does not."""
    rec = clean.signals["rec"]
    nuisance = clean["calibration"]
    judged = with_discrepancy(rec, nuisance)
    base_train = model_signals(rec, rec.train, nuisance, None, {})
    base_test = model_signals(rec, rec.test, nuisance, None, {})
    bracketed = [d for d in clean["detection_limits"]
                 if d["limit"] is not None and d["not_named_at"] is not None]
    assert bracketed  # the transfer path's residue is bracketed on these records
    for d in bracketed:
        eff = EFFECTS[d["effect"]]

        def named(size, eff=eff, d=d):
            values = eff.defaults() | d["option"] | {d["parameter"]: size}
            return holds(judged_at(rec, judged, nuisance, eff, values, base_train, base_test,
                                   len(clean["ranking"])))

        assert named(d["limit"]) and not named(d["not_named_at"])


def test_the_option_is_a_boolean():
    with pytest.raises(ValueError, match=r"loop\.detection_limits = 'yes' must be true or false"):
        LoopSettings(detection_limits="yes")
