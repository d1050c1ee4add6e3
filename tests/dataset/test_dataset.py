"""Dataset generator: rows, determinism, chunking, resume and refusal of bad input."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from omegaconf import OmegaConf

from physics.dataset.generation import (
    SCHEMA_VERSION,
    DatasetSpec,
    NuisanceRanges,
    build_dataset,
    chunk_folder,
    chunk_path,
    plan_dataset,
    spec_from_config,
    unit_draw,
    unit_scenario,
    units,
)
from physics.params import Dynamics, Scenario, Tribology, WearSolver, case_values
from physics.signals.measurement import add_noise, housing_acceleration

BASE = Scenario(solver=WearSolver(n_points=51),
                dynamics=Dynamics(duration_s=0.02, transient_s=0.005, phase_bins=64))
SMALL = {"cases": [2, 3], "wear_states": 3, "replicates": 2, "cycles_max": 1e6}


def generate(out: Path, chunk: int | None = None, jobs: int = 1, store_signals: bool = False,
             **spec):
    """The dataset API as ``python -m physics.dataset`` runs it (small sizes)."""
    job = plan_dataset(BASE, spec_from_config({**SMALL, **spec}), out, chunk=chunk, jobs=jobs,
                       store_signals=store_signals, progress=False)
    return build_dataset(job)


@pytest.fixture(scope="module")
def single(tmp_path_factory):
    out = tmp_path_factory.mktemp("single")
    return generate(out, chunks=1)


def test_rows_columns_and_sidecar(single):
    df = pd.read_parquet(single)
    assert len(df) == 2 * 2 * 3
    assert list(df.columns) == list(units())
    assert df.select_dtypes("number").notna().all().all()
    side = json.loads(single.with_suffix(".json").read_text())
    assert side["rows"] == len(df) and side["schema_version"] == SCHEMA_VERSION
    assert side["units"]["dte_rms"] == "m" and side["units"]["acc_rms"] == "m/s^2"
    assert all(side["units"][f"dte_mesh{k}_db"] == "dB" for k in (2, 3, 4, 5, 6))
    assert all(side["units"][f"dte_mesh{k}_{f}"] == "1" for k in (2, 3, 4, 5, 6)
               for f in ("cos", "sin"))
    for k in (2, 3, 4, 5, 6):  # a point on the unit circle
        assert np.allclose(df[f"dte_mesh{k}_cos"] ** 2 + df[f"dte_mesh{k}_sin"] ** 2, 1.0)
    assert side["config"]["data"]["seed"] == 0 and "package_version" in side
    assert side["config"]["scenario"]["tribology"]["regime"] == "mixed"
    for _, traj in df.groupby(["case", "replicate"]):
        assert np.all(np.diff(traj.root_wear_mm) > 0)  # wear only grows
        assert traj.root_wear_mm.iloc[0] == 0.0
        assert traj.n1_rpm.nunique() == 1  # one operating point per replicate


def test_draws_stay_within_their_documented_ranges(single):
    df = pd.read_parquet(single)
    ranges = NuisanceRanges()
    for case in (2, 3):
        rows = df[df.case == case]
        table = case_values(case)
        assert np.all(np.abs(rows.n1_rpm / table["n1_rpm"] - 1) <= ranges.speed_pct / 100)
        assert np.all(np.abs(rows.torque_Nm / table["torque_Nm"] - 1) <= ranges.torque_pct / 100)
        assert rows.n1_rpm.nunique() == 2  # one draw per trajectory
    for name in NuisanceRanges.LIMITS:
        lo, hi = getattr(ranges, name)
        assert df[name].between(lo, hi).all(), name
        assert df.groupby(["case", "replicate"])[name].nunique().eq(1).all()  # per trajectory


def test_a_trajectorys_draws_reach_its_physics():
    spec = spec_from_config({**SMALL, "chunks": 1, "nuisance": {
        "boundary_share": [0.2, 0.8], "stiffness_factor": [0.6, 1.6],
        "resonance_factor": [0.9, 0.9]}})
    d = unit_draw(spec, 3, 1)
    scn = unit_scenario(BASE, spec, 3, 1)
    assert 0.6 <= scn.dynamics.stiffness_factor == d["stiffness_factor"] <= 1.6
    assert scn.dynamics.resonance_factor == pytest.approx(0.9)
    low, high = NuisanceRanges().double_contact_factor  # its default range
    assert low <= scn.dynamics.double_contact_factor == d["double_contact_factor"] <= high
    assert scn.dynamics.damping_ratio == d["damping_ratio"]
    assert scn.dynamics.housing_mass_kg == d["housing_mass_kg"]
    assert scn.tribology.dry_wear_coeff == pytest.approx(
        BASE.tribology.dry_wear_coeff * d["wear_coeff_factor"])
    assert 0.2 <= scn.tribology.boundary_share == d["boundary_share"] <= 0.8
    assert scn.operating.n1_rpm == pytest.approx(case_values(3)["n1_rpm"] * d["speed_factor"])


def test_ranges_come_from_a_hydra_config_as_from_a_dict():
    """``python train.py +data.generate.nuisance.boundary_share=[0,1]`` hands the ranges over
    as an OmegaConf node, not a dict."""
    cfg = OmegaConf.create({**SMALL, "chunks": 1, "nuisance": {"boundary_share": [0.2, 0.8]}})
    spec = spec_from_config(cfg)
    assert isinstance(spec.nuisance, NuisanceRanges)
    assert spec.nuisance.boundary_share == [0.2, 0.8]
    assert unit_draw(spec, 3, 1) == unit_draw(spec_from_config(
        {**SMALL, "chunks": 1, "nuisance": {"boundary_share": [0.2, 0.8]}}), 3, 1)


def test_ranges_are_refused_outside_their_limits():
    with pytest.raises(ValueError, match=r"data.nuisance.damping_ratio = \[0.2, 0.1\]"):
        NuisanceRanges(damping_ratio=[0.2, 0.1])
    with pytest.raises(ValueError, match=r"data.nuisance.snr_db = \[nan, 30.0\]"):
        NuisanceRanges(snr_db=[float("nan"), 30.0])


def test_the_default_chunk_count_follows_a_smaller_unit_count():
    """Five chunks by default, one per unit where there are fewer (two replicates of one
    case: two chunks); a count given beyond the units is refused naming them."""
    assert DatasetSpec().chunks == 5
    assert DatasetSpec(cases=(3,), replicates=2).chunks == 2
    with pytest.raises(ValueError, match=r"data.chunks = 5 must lie in \[1, 2\]"):
        DatasetSpec(cases=(3,), replicates=2, chunks=5)


def test_chunked_equals_single_and_rerun_is_byte_identical(tmp_path, single):
    path = generate(tmp_path / "a", chunks=3, jobs=2)
    pd.testing.assert_frame_equal(pd.read_parquet(path), pd.read_parquet(single))
    again = generate(tmp_path / "b", chunks=3)
    assert again.read_bytes() == path.read_bytes()
    assert again.with_suffix(".json").read_text() == path.with_suffix(".json").read_text()


def test_killed_run_resumes_and_keeps_finished_chunks(tmp_path, single):
    out = tmp_path / "resume"
    assert generate(out, chunks=2, chunk=0) is None  # one job of a multirun
    done = chunk_path(chunk_folder(out, "dataset"), 0)
    stamp = done.stat().st_mtime_ns
    # a killed job's leftover is unreadable, so it is computed again
    chunk_path(chunk_folder(out, "dataset"), 1).write_bytes(b"half-written by a killed job")
    path = generate(out, chunks=2)
    assert done.stat().st_mtime_ns == stamp
    pd.testing.assert_frame_equal(pd.read_parquet(path), pd.read_parquet(single))
    assert not list(out.rglob("*.tmp"))


def test_changed_config_recomputes_finished_chunks(tmp_path):
    out = tmp_path / "hash"
    generate(out, chunks=1)
    path = chunk_path(chunk_folder(out, "dataset"), 0)
    first = pq.read_schema(path).metadata[b"gearwear_hash"]
    generate(out, chunks=1, nuisance={"snr_db": [15.0, 25.0]})
    assert pq.read_schema(path).metadata[b"gearwear_hash"] != first


def test_signals_are_stored_beside_the_table(tmp_path):
    path = generate(tmp_path, chunks=2, store_signals=True, cases=[3])
    sig = np.load(path.parent / "dataset_signals.npy")
    df = pd.read_parquet(path)
    assert sig.shape[:2] == (len(df), 2) and sig.dtype == np.float32
    rms = np.sqrt(np.mean((sig[:, 1] - sig[:, 1].mean(-1, keepdims=True)) ** 2, axis=-1))
    assert np.allclose(rms, df.acc_rms, rtol=1e-4)  # the rows and records line up


def test_noise_has_the_stated_snr_and_housing_acceleration_is_force_over_mass():
    rng = np.random.default_rng(1)
    x = np.sin(np.linspace(0, 200 * np.pi, 200_000)) + 5.0
    noisy = add_noise(x, 20.0, rng)
    snr = 10 * np.log10(np.mean((x - 5) ** 2) / np.mean((noisy - x) ** 2))
    assert snr == pytest.approx(20.0, abs=0.1)
    assert add_noise(x, np.inf, rng) is x
    f = np.array([[100.0, 300.0, 200.0]])
    assert np.allclose(housing_acceleration(f, 20.0), [[-5.0, 5.0, 0.0]])
    with pytest.raises(ValueError, match="housing_mass_kg"):
        housing_acceleration(f, 0.0)


@pytest.mark.parametrize(("override", "message"), [
    ({"cases": [3, 9]}, r"case.*9.*1, 2, 3, 4, 5"),
    ({"chunk": 7}, r"chunk = 7 must lie in \[0, 0\]"),
    ({"bogus": 1}, r"unknown key.*bogus"),
    ({"wear_states": 1}, r"wear_states = 1 must be a whole number in \[2, "),
    ({"jobs": 0}, r"jobs = 0 must be a whole number >= 1"),
    ({"nuisance": {"snr_db": [float("nan"), 30.0]}}, r"snr_db = \[nan, 30.0\] must be"),
])
def test_bad_input_is_refused_before_work(tmp_path, override, message):
    with pytest.raises(ValueError, match=message):
        generate(tmp_path, chunks=1, **override)
    assert not chunk_folder(tmp_path, "dataset").exists()


def test_spec_rejects_more_chunks_than_units():
    with pytest.raises(ValueError, match="chunks = 9"):
        DatasetSpec(cases=(3,), replicates=2, chunks=9)


@pytest.mark.slow
def test_a_gearbox_worn_through_is_recorded_not_a_row(tmp_path, caplog):
    # a wear coefficient 1e4 times the calibrated one wears the teeth through within the life
    # of every trajectory: each is listed in the sidecar with its reason, none is a row
    worn = dataclasses.replace(BASE, tribology=Tribology(regime="dry", dry_wear_coeff=2e-4),
                               solver=WearSolver(n_points=51, update_um=50.0))
    spec = spec_from_config({**SMALL, "cases": [3], "chunks": 2})
    with caplog.at_level("WARNING"):
        path = build_dataset(plan_dataset(worn, spec, tmp_path, progress=False))
    side = json.loads(path.with_suffix(".json").read_text())
    assert len(pd.read_parquet(path)) == 0 and side["rows"] == 0
    assert sorted((u["case"], u["replicate"]) for u in side["left_scope"]) == [
        (3, r) for r in range(SMALL["replicates"])]
    assert all("worn through" in u["reason"] or "table" in u["reason"]
               or "shakedown" in u["reason"] for u in side["left_scope"])
    assert "2 of 2 trajectories left the model's scope" in caplog.text


def test_default_ranges_are_those_of_their_sources():
    """Run-out and profile form: ISO 1328 grades 4 to 9 of the thesis's pinion, halved;
    backlash: ISO/TR 10064-2's minimum to a grade-9 pair's maximum, halved; damping: Kasuba &
    Evans's 0.03-0.17 (NuisanceRanges)."""
    from physics.gear.accuracy import (
        maximum_backlash_um,
        minimum_backlash_um,
        profile_form_tolerance_um,
        runout_tolerance_um,
    )
    from physics.params import GearPair

    g, r = GearPair(), NuisanceRanges()
    d1, d2 = g.module_mm * g.z1, g.module_mm * g.z2
    a = g.standard_center_distance_mm
    assert r.eccentricity1_um == [runout_tolerance_um(q, g.module_mm, d1) / 2 for q in (4, 9)]
    assert r.profile_error_um == [profile_form_tolerance_um(q, g.module_mm, d1) / 2
                                  for q in (4, 9)]
    assert r.half_backlash_um[0] == pytest.approx(minimum_backlash_um(a, g.module_mm) / 2)
    assert r.half_backlash_um[1] == pytest.approx(maximum_backlash_um(
        9, g.module_mm, d1, d2, a, g.pressure_angle_deg) / 2, abs=0.5)
    assert r.damping_ratio == [0.03, 0.17]
    # the declared (thesis) gearbox lies inside every range
    dyn = Dynamics()
    for name in ("damping_ratio", "eccentricity1_um", "profile_error_um", "half_backlash_um"):
        low, high = getattr(r, name)
        assert low <= getattr(dyn, name) <= high, name


def test_a_default_dataset_draws_the_model_form_and_the_wear_law_across_their_ranges():
    """By default every trajectory draws the form factors around the declared model (1) and
    the share of dry-law running between the lubricated (0) and the dry (1) law; a few dozen
    trajectories reach both ends of each range."""
    spec = DatasetSpec()
    draws = pd.DataFrame([unit_draw(spec, c, r) for c in spec.cases for r in range(12)])
    for name in ("stiffness_factor", "double_contact_factor", "resonance_factor",
                 "boundary_share"):
        low, high = getattr(spec.nuisance, name)
        width = high - low
        assert draws[name].between(low, high).all(), name
        assert draws[name].min() < low + 0.2 * width and draws[name].max() > high - 0.2 * width
    assert (draws.stiffness_factor < 1).any() and (draws.stiffness_factor > 1).any()
    scn = unit_scenario(BASE, spec, 3, 0)
    d = unit_draw(spec, 3, 0)
    assert scn.tribology.boundary_share == d["boundary_share"]
    assert scn.dynamics.resonance_factor == d["resonance_factor"]
