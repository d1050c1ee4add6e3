"""The unit's own earliest records as the form reference (``reference=first:N`` /
``before:X``): how the bundle is cut, what is refused, and an effect that appears over the
bundle's life named against them."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from physics.loop import Bundle, LoopSettings, read_bundle, run_loop
from physics.loop.measured.records import Group, prepare
from physics.loop.search.fit import held, with_level
from physics.loop.search.form_error import _spread
from physics.loop.search.own_history import own_reference, parse_history, split_history
from physics.params import scenario_from_config
from physics.testbeds import make_bundle


def day(k: int) -> str:
    """An ISO 8601 date ``k`` days after the Unix epoch: the records' dates of these tests."""
    return (pd.Timestamp(0) + pd.Timedelta(days=k)).date().isoformat()


def _bundle(cycles, speeds, time=None) -> Bundle:
    n = len(cycles)
    names = [f"r{k}" for k in range(n)]
    man = pd.DataFrame({"record": names, "quantity": "accel_m_s2", "fs_hz": 40960.0,
                        "n1_rpm": speeds, "torque_Nm": 300.0, "wear_mm": np.nan,
                        "cycles": cycles, "split": ""})
    if time is not None:
        man["time"] = time
    return Bundle(Path("."), man, {r: np.zeros(4) for r in names}, {})


def test_the_forms_are_read_and_a_folder_is_not_one():
    assert parse_history("first:2").first == 2
    assert parse_history(" first : 3 ").first == 3
    assert parse_history("before:2e6").cycles == 2e6
    assert parse_history(f"before:{day(60)}").time == pd.Timestamp(day(60))
    assert parse_history("path/to/sister") is None and parse_history(None) is None


@pytest.mark.parametrize("spec, rule", [
    ("first:0", "whole number N >= 1"), ("first:two", "whole number N >= 1"),
    ("before:-5", "number of load cycles > 0"), ("before:yesterday", "neither a number")])
def test_a_malformed_form_is_refused_naming_value_rule_and_fix(spec, rule):
    with pytest.raises(ValueError, match=rule) as err:
        parse_history(spec)
    assert f"reference={spec}" in str(err.value) and "e.g. reference=" in str(err.value)


def test_first_n_takes_the_earliest_records_of_each_group_by_cycles():
    # two operating points, records out of order in the manifest
    b = _bundle([5e6, 0.0, 3e6, 1e6, 4e6, 2e6, 0.0, 9e6], [2000] * 4 + [1800] * 4)
    ref, rest = split_history(b, parse_history("first:2"))
    assert ref.records == ["r1", "r3", "r5", "r6"]
    assert rest.records == ["r0", "r2", "r4", "r7"]
    assert set(rest.signals) == set(rest.records) and (ref.manifest.split == "").all()


def test_without_cycles_the_time_column_orders_and_dates_the_records():
    times = [day(2), day(0), day(1), day(31), day(60)]
    b = _bundle([np.nan] * 5, [2000] * 5, times)
    assert split_history(b, parse_history("first:1")).__getitem__(0).records == ["r1"]
    ref, rest = split_history(b, parse_history(f"before:{day(14)}"))
    assert ref.records == ["r0", "r1", "r2"] and rest.records == ["r3", "r4"]


@pytest.mark.parametrize("cycles, time, spec, rule", [
    ([0, 1, 2], None, "first:2", "leaves 1 record"),
    ([0, 1, np.nan, 3], None, "first:1", "has no cycles and the manifest no 'time'"),
    ([0, 1, 2, 3], None, f"before:{day(0)}", "no 'time' column"),
    ([5, 6, 7, 8], None, "before:3", "takes no record of group"),
    ([0, 1, 2, 3], [day(0), "soon", day(2), day(3)], f"before:{day(1)}",
     "record 'r1': time = 'soon'")])
def test_a_cut_the_loop_cannot_use_is_refused_before_work(cycles, time, spec, rule):
    b = _bundle(cycles, [2000] * len(cycles), time)
    with pytest.raises(ValueError, match=rule) as err:
        split_history(b, parse_history(spec))
    assert f"reference={spec}" in str(err.value)


@pytest.mark.slow
def test_an_effect_that_appears_over_the_life_is_named_against_the_first_records(tmp_path):
    """A torque ripple that appears at a third of the life: the first two records (clean) are
    the reference, left out of the analysis, and the ripple in the others is named."""
    scn = scenario_from_config({"case": 3})
    path, truth = make_bundle(tmp_path / "b", scn, "torque_ripple", seed=4, records=8,
                              duration_s=0.75, onset=0.3)
    assert truth["with_effect"] == [f"r{k:02d}" for k in range(3, 8)]
    settings = LoopSettings(max_nfev=6, explore=8, refine=2,
                            candidates=("torque_ripple", "friction"))
    ref, analysed = own_reference(read_bundle(path), "first:2", scn, settings)
    assert ref.names == ("r00", "r01") and analysed.records == [f"r{k:02d}" for k in
                                                                 range(2, 8)]
    # the unit's own records also give the discrepancy about their mean, per entry
    assert set(ref.spread) == set(ref.offsets)
    assert all(np.all(np.isfinite(d) & (d >= 0)) and d.shape == ref.offsets[k].shape
               for k, d in ref.spread.items())
    report = run_loop(analysed, scn, settings, reference=ref)
    assert report["verdict"] == "effect" and report["chosen_effect"] == "torque_ripple"
    # the same unit: its first records' calibration is held, nothing recalibrated
    assert report["calibration"] == ref.calibration and report.signals["rec"].held
    assert report["error_after"] < 0.5 * report["error_before"]
    judged = ref.judging(report.signals["rec"])  # the unexplained test's discrepancy
    assert all(np.array_equal(g.discrepancy_sd, ref.spread[g.key]) for g in judged.groups)
    summary = report.details["form_reference"]
    assert summary["source"] == "this unit's own earliest records (first:2)"
    assert summary["reference_records"] == ["r00", "r01"] and summary["calibration_held"]
    assert not set(summary["reference_records"]) & set(report.details["train_records"]
                                                       + report.details["test_records"])


def test_the_units_calibration_is_held_for_its_later_records(tmp_path):
    """Against its own first records the unit's nuisance and measurement chain are those
    records' calibration, held: recalibrated on the later records they would absorb what
    changed since. ``m_h`` is levelled by nothing; a torque the manifest leaves unknown (an
    operating condition) is the one parameter refitted."""
    scn = scenario_from_config({"case": 3})
    path, _ = make_bundle(tmp_path / "b", scn, None, seed=3, records=6, duration_s=0.5)
    settings = LoopSettings(max_nfev=3, explore=8)
    ref, analysed = own_reference(read_bundle(path), "first:2", scn, settings)
    rec = prepare(analysed, scn, settings)
    kept, nuisance, free = held(rec, ref.calibration)
    assert kept.held and not rec.held
    assert nuisance == ref.calibration and free == []
    moved = nuisance | {"housing_mass_kg": 10 * nuisance["housing_mass_kg"]}
    assert with_level(kept, moved, None, {}) == moved
    # the same records not held: the level pulls m_h back towards the measured records'
    assert with_level(rec, moved, None, {})["housing_mass_kg"] < moved["housing_mass_kg"] / 3
    unknown = dataclasses.replace(rec, torque_unknown=np.ones(len(rec.models), bool))
    _, nuisance, free = held(unknown, ref.calibration)
    assert free == ["torque_factor"] and 0.2 <= nuisance.pop("torque_factor") <= 5
    assert nuisance == ref.calibration


def test_the_app_cuts_the_units_first_records_off_as_its_reference(tmp_path, monkeypatch,
                                                                   config_store):
    """``python -m physics.loop data=B reference=first:2`` as the app prepares it: the first two
    records of the group are the reference, the rest the analysed bundle."""
    from tests.acceptance.refusal import APPS, composed

    scn = scenario_from_config({"case": 3})
    path, _ = make_bundle(tmp_path / "b", scn, None, seed=3, records=6, duration_s=0.5)
    monkeypatch.chdir(tmp_path)
    spec = APPS["loop"]
    job = spec.prepare()(composed(spec, [f"data={path}", "reference=first:2", "case=3"],
                                  tmp_path / "run"))
    assert job.history == "first:2"
    assert job.reference.records == ["r00", "r01"]
    assert job.data.records == ["r02", "r03", "r04", "r05"]


def test_a_pit_that_appears_during_the_life_is_written(tmp_path):
    """A pit's tables span a pinion revolution, a clean record's one mesh period: the bundle
    maker simulates them apart, and only the records after the onset carry the pit."""
    scn = scenario_from_config({"case": 3})
    _, truth = make_bundle(tmp_path / "b", scn, "tooth_defect", seed=1, records=4,
                           duration_s=0.3, onset=0.5)
    assert truth["with_effect"] == ["r02", "r03"]
    assert truth["effect_to_noise_db"] > -20


def test_the_reference_scatter_holds_the_error_of_its_mean_and_ignores_single_records():
    """A reference group of ``n`` records scattered about their mean by ``d`` (zero-mean
    Gaussian offsets, noise ``e``): a record referred to that mean is off by ``d`` of its own
    plus the mean's error, ``(d^2 + e^2) / n``. A group of one record, whose scatter cannot be
    measured, leaves the other groups' estimate as it is."""
    rng = np.random.default_rng(3)
    n, m, d, e = 6, 400, 2.0, 0.5
    names = [f"band{k:02d}" for k in range(m)]

    def group(key, records):
        return Group(key=key, records=np.asarray(records), names=names,
                     entry_sd=np.full(m, e), discrepancy_sd=np.zeros(m))

    res = [*(d * rng.standard_normal((n, m)) + e * rng.standard_normal((n, m))),
           5.0 * rng.standard_normal(m)]
    many = group((2000.0, 300.0, "accel_m_s2", 40960.0), range(n))
    one = group((1800.0, 290.0, "accel_m_s2", 40960.0), [n])
    offsets = {many.key: np.mean(res[:n], axis=0), one.key: res[n]}
    settings = SimpleNamespace(discrepancy_prior=LoopSettings().discrepancy_prior)
    alone = _spread(SimpleNamespace(groups=[many], settings=settings), res, offsets)
    both = _spread(SimpleNamespace(groups=[many, one], settings=settings), res, offsets)
    assert np.array_equal(alone[many.key], both[many.key]) and one.key not in both
    expected = np.sqrt(d**2 * (1 + 1 / n) + e**2 / n)
    assert np.median(alone[many.key]) == pytest.approx(expected, rel=0.1)
