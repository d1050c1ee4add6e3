"""Surrogate: configs, trajectory split, training, sweeps, safe checkpoints, checked inference."""

from __future__ import annotations

import dataclasses
import json
import logging
from pathlib import Path

import hypothesis
import numpy as np
import pandas as pd
import pytest
import torch
from hydra import compose, initialize_config_module
from hydra.errors import InstantiationException
from hydra.utils import get_class, instantiate
from hypothesis import strategies as st

from physics.dataset.generation import (
    DatasetSpec,
    NuisanceRanges,
    build_dataset,
    plan_dataset,
    spec_from_config,
)
from physics.dynamics.model_form import FACTORS
from physics.params import Dynamics, Scenario, WearSolver
from physics.signals.order_analysis import LINE_ORDERS
from surrogate import predict, settings
from surrogate.conformal import attainable, exchangeable_quantile
from surrogate.inference import (
    ScaledEnsemble,
    Surrogate,
    conformal_scale,
    export,
    gearbox_columns,
    torch_predict,
)
from surrogate.inputs import DEFAULT_INPUTS
from surrogate.model import WearRegressor
from surrogate.network import EnsembleMLP, mixture
from surrogate.predict import predict_file
from surrogate.schema import FeatureSchema, baseline_changes, vector_magnitudes
from surrogate.splits import split_trajectories, validation_count
from surrogate.training import prepare, train
from surrogate.wear_data import BUILD_CHUNKS, load_dataset, replicates_per_case, stale_dataset

ROOT = Path(__file__).resolve().parents[2]
TINY_BASE = Scenario(solver=WearSolver(n_points=51),
                     dynamics=Dynamics(duration_s=0.02, transient_s=0.005, phase_bins=64))
#: the plumbing is tested on one gearbox (nuisance fixed at the declared values), not robustness
ONE_GEARBOX = NuisanceRanges(
    speed_pct=1.0, torque_pct=2.0, damping_ratio=[0.07, 0.07], eccentricity1_um=[7.5, 7.5],
    profile_error_um=[3.0, 3.0], half_backlash_um=[47.5, 47.5], housing_mass_kg=[20.0, 20.0],
    transfer_fn_hz=[4000.0, 4000.0], transfer_zeta=[0.05, 0.05], snr_db=[30.0, 30.0],
    wear_coeff_factor=[1.0, 1.0], boundary_share=[0.0, 0.0], stiffness_factor=[1.0, 1.0],
    double_contact_factor=[1.0, 1.0], resonance_factor=[1.0, 1.0],
    form_deviation_um=[0.0, 0.0])
TINY = DatasetSpec(cases=(3, 4), wear_states=5, replicates=4, chunks=1, nuisance=ONE_GEARBOX)


def groups(name: str) -> list[str]:
    return sorted(p.stem for p in (ROOT / "conf" / "train" / name).glob("*.yaml"))


def train_cfg(tmp: Path, dataset: Path, *overrides: str):
    settings.register()
    with initialize_config_module("gearwear_conf.train", version_base="1.3"):
        return compose("train", overrides=[
            f"paths.root_dir={tmp}", f"paths.output_dir={tmp / 'run'}", f"data.dataset={dataset}",
            "data.val_replicates=1",
            "trainer.enable_progress_bar=false", *overrides])


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("data") / "tiny.parquet"
    build_dataset(plan_dataset(TINY_BASE, TINY, path.parent, path.stem, progress=False))
    return path


@pytest.fixture(scope="module")
def trained(tmp_path_factory, dataset) -> Path:
    tmp = tmp_path_factory.mktemp("train")
    value = train(train_cfg(tmp, dataset, "case=3", "data.test_replicates=1",
                            "data.baseline=false", "data.operating_point=false",
                            "trainer.max_epochs=100",
                            "model.members=3", "logger=csv"))
    assert np.isfinite(value)
    return tmp / "run"


@pytest.mark.parametrize(("group", "choice"), [(g, c) for g in
                         ("model", "trainer", "callbacks", "logger", "data", "paths")
                         for c in groups(g)])
def test_every_config_group_composes_and_instantiates(tmp_path, group, choice):
    cfg = train_cfg(tmp_path, tmp_path / "none.parquet", f"{group}={choice}")
    instantiate(cfg.data)
    instantiate(cfg.model, n_inputs=3, schema={"target_scale": 1.0})
    for c in (cfg.callbacks or {}).values():
        instantiate(c)
    for c in (cfg.logger or {}).values():
        instantiate(c)
    instantiate(cfg.trainer, logger=False)


@pytest.mark.parametrize("experiment", groups("experiment"))
def test_experiments_compose(tmp_path, experiment):
    """Every named experiment composes into a data module whose dataset build is valid."""
    cfg = train_cfg(tmp_path, tmp_path / "x.parquet", f"experiment={experiment}")
    assert str(cfg.data.case) == str(cfg.case)
    instantiate(cfg.data)  # checks the build's settings (cases, nuisance ranges) before work


def test_the_main_job_trains_over_the_model_form_and_both_wear_laws(tmp_path):
    """``python train.py case=3`` builds its dataset over the declared model's form uncertainty
    and the wear-law share (docs/dataset.md): each range straddles the declared model (1) or
    spans the lubricated (0) to the dry (1) law."""
    cfg = train_cfg(tmp_path, tmp_path / "x.parquet")
    spec = spec_from_config(dict(cfg.data.generate))
    for name in FACTORS:
        low, high = getattr(spec.nuisance, name)
        assert low < 1.0 < high, name
    assert spec.nuisance.boundary_share == [0.0, 1.0]
    assert "model_form" not in groups("experiment")  # the defaults do what it did


def test_the_declared_form_experiment_holds_the_form_and_the_lubricated_law(tmp_path):
    """``experiment=declared_form``: the form factors at the declared model's (1) and the
    lubricated law alone, the tolerance ranges as by default."""
    default = spec_from_config(dict(train_cfg(tmp_path, tmp_path / "x.parquet").data.generate))
    cfg = train_cfg(tmp_path, tmp_path / "x.parquet", "experiment=declared_form")
    spec = spec_from_config(dict(cfg.data.generate))
    for name in FACTORS:
        assert getattr(spec.nuisance, name) == [1.0, 1.0], name
    assert spec.nuisance.boundary_share == [0.0, 0.0]
    for name in ("damping_ratio", "eccentricity1_um", "profile_error_um", "half_backlash_um"):
        assert getattr(spec.nuisance, name) == getattr(default.nuisance, name), name


def test_optuna_search_composes_with_a_failure_budget(tmp_path):
    settings.register()
    with initialize_config_module("gearwear_conf.train", version_base="1.3"):
        cfg = compose("train", overrides=["hparams_search=optuna"], return_hydra_config=True)
    sweeper = cfg.hydra.sweeper
    assert get_class(sweeper._target_).__name__ == "OptunaSweeper"
    assert 0 < sweeper.max_failure_rate < 1 and set(sweeper.params) >= {"model.lr"}


def test_split_is_by_trajectory_and_the_scaling_uses_training_rows(dataset):
    df = pd.read_parquet(dataset)
    parts = split_trajectories(df, 1, 2, seed=0)
    keys = {k: set(map(tuple, v[["case", "replicate"]].drop_duplicates().to_numpy()))
            for k, v in parts.items()}
    assert not (keys["train"] & keys["val"] or keys["train"] & keys["test"]
                or keys["val"] & keys["test"])
    assert sum(len(v) for v in parts.values()) == len(df)
    loco = split_trajectories(df, 1, 2, seed=0, holdout_case=4)
    assert set(loco["test"].case) == {4} and 4 not in set(loco["train"].case)
    with pytest.raises(ValueError, match="replicates"):
        split_trajectories(df, 2, 2, seed=0)


def test_a_built_dataset_holds_enough_gearboxes_and_a_sixth_validates(tmp_path):
    """The default training set: 256 gearboxes for one case, 128 per case for all five (the
    floor), an explicit ``data.generate.replicates`` wins; a sixth of a case's trajectories
    validates (8 at least), and the split takes it when ``val_replicates`` is left null."""
    assert replicates_per_case(256, 1) == 256 and replicates_per_case(256, 5) == 128
    assert replicates_per_case(1280, 5) == 256 and replicates_per_case(1, 3) == 128
    assert validation_count(256) == 43 and validation_count(128) == 21
    assert validation_count(40) == 8
    cfg = train_cfg(tmp_path, tmp_path / "x.parquet", "case=3", "data.val_replicates=null")
    dm = instantiate(cfg.data)
    assert dm.generate["replicates"] == 256 and dm.val_replicates is None
    cfg = train_cfg(tmp_path, tmp_path / "x.parquet", "case=all", "+data.generate.replicates=4")
    with pytest.raises(Exception, match=r"case 1 has 4 trajectories; a split with 1 "
                                        r"validation and 8 test"):  # before the build
        instantiate(cfg.data)
    cfg = train_cfg(tmp_path, tmp_path / "x.parquet", "case=all", "+data.generate.replicates=4",
                    "data.test_replicates=1", "data.val_replicates=1")
    small = instantiate(cfg.data).generate
    assert small["replicates"] == 4 and small["chunks"] == 20  # one chunk per trajectory
    assert dm.generate["chunks"] == BUILD_CHUNKS  # many chunks: both processes busy to the end
    cfg = train_cfg(tmp_path, tmp_path / "x.parquet", "case=3", "+data.generate.chunks=3")
    assert instantiate(cfg.data).generate["chunks"] == 3  # a user's count wins


def test_fewer_gearboxes_than_the_floor_are_said_not_built_silently(tmp_path, caplog):
    """``data.gearboxes`` below the 128 per case a built dataset simulates: the run says how
    many it builds instead; the default (256) and an explicit count per case say nothing."""
    with caplog.at_level("WARNING", logger="surrogate.wear_data"):
        dm = instantiate(train_cfg(tmp_path, tmp_path / "x.parquet", "case=3",
                                   "data.gearboxes=4").data)
    assert dm.generate["replicates"] == 128
    (line,) = [r.getMessage() for r in caplog.records]
    assert line.startswith("data.gearboxes = 4: a dataset built here simulates at least 128 "
                           "gearboxes per trained case"), line
    caplog.clear()
    with caplog.at_level("WARNING", logger="surrogate.wear_data"):
        instantiate(train_cfg(tmp_path, tmp_path / "x.parquet", "case=3").data)
        instantiate(train_cfg(tmp_path, tmp_path / "x.parquet", "case=3", "data.gearboxes=4",
                              "+data.generate.replicates=8", "data.test_replicates=1",
                              "data.val_replicates=1").data)
    assert not caplog.records
    cfg = train_cfg(tmp_path, tmp_path / "x.parquet", "case=3", "+data.generate.replicates=0")
    with pytest.raises(Exception, match=r"data\.replicates = 0 must"):  # not a chunks error
        instantiate(cfg.data)
    reps = np.repeat(np.arange(100), 2)
    df = pd.DataFrame({"case": 3, "replicate": reps, "x": np.arange(200.0)})
    parts = split_trajectories(df, None, 8, seed=0)
    assert {k: v.replicate.nunique() for k, v in parts.items()} == {
        "train": 75, "val": 17, "test": 8}


def test_a_dataset_built_with_other_settings_is_named_not_silently_used(dataset, caplog):
    """A dataset file from other settings (an older default, another case list) is read as it
    is, with a warning that names what differs and how to rebuild."""
    with caplog.at_level("WARNING", logger="surrogate.wear_data"):
        load_dataset(dataset, {"cases": [3, 4], "replicates": 9})
    text = caplog.text
    assert "data.replicates: 4 -> 9" in text and "delete it" in text
    assert "scenario.solver" in text  # the tiny test scenario is not the default physics
    # the same rows cut into other chunks (the training build's count) are the same dataset
    for chunks in (1, 2):
        job = plan_dataset(TINY_BASE, dataclasses.replace(TINY, chunks=chunks), dataset.parent,
                           dataset.stem, progress=False)
        assert stale_dataset(dataset, job) is None
    job = plan_dataset(TINY_BASE, dataclasses.replace(TINY, replicates=5, chunks=2),
                       dataset.parent, dataset.stem, progress=False)
    diff = stale_dataset(dataset, job)
    assert "data.replicates: 4 -> 5" in diff and "chunks" not in diff


def test_a_dataset_of_an_older_layout_is_refused_naming_the_fix(dataset, tmp_path):
    """A dataset file written before the mesh-harmonic levels existed lacks columns the
    default inputs need: refused before any work, with the fix (delete it to rebuild)."""
    old = tmp_path / "old.parquet"
    pd.read_parquet(dataset).drop(columns=["dte_mesh3_db"]).to_parquet(old)
    cfg = train_cfg(tmp_path, old, "case=3", "data.test_replicates=1",
                    "data.baseline=false")
    with pytest.raises(InstantiationException, match=r"\['dte_mesh3_db'\] are not in .*older "
                       r"version of the dataset API.*delete it to build it again"):
        instantiate(cfg.data)
    # before the mesh lines: the baseline network's inputs, named by their parts
    pd.read_parquet(dataset).drop(columns=["dte_line2_re", "dte_line2_im"]).to_parquet(old)
    cfg = train_cfg(tmp_path, old, "case=3", "data.test_replicates=1")
    with pytest.raises(InstantiationException, match=r"\['dte_line2_re', 'dte_line2_im'\] are not "
                       r"in .*older version of the dataset API"):
        instantiate(cfg.data)


def test_ensemble_members_differ_and_the_mixture_is_right():
    torch.manual_seed(0)
    net = EnsembleMLP(4, [8, 8], members=3)
    with torch.no_grad():
        out = net(torch.randn(5, 4))
    assert out.shape == (3, 5, 2) and not torch.allclose(out[0], out[1])
    x = torch.randn(5, 4)
    with torch.no_grad():  # each member is the plain MLP x W + b, SiLU between layers
        for m in range(3):
            h = x
            for i, (w, b) in enumerate(zip(net.weights, net.biases, strict=True)):
                h = h @ w[m] + b[m]
                h = h * torch.sigmoid(h) if i < 2 else h
            assert torch.allclose(net(x)[m], h, atol=1e-6)
    mean, var = mixture(out)
    mu, v = out[..., 0].numpy(), np.exp(out[..., 1].numpy())
    assert np.allclose(mean.detach(), mu.mean(0), atol=1e-6)
    assert np.allclose(var.detach(), (v + mu**2).mean(0) - mu.mean(0) ** 2, atol=1e-5)


def test_onnx_runtime_predicts_what_torch_predicts():
    """A loaded model predicts in torch (:class:`ScaledEnsemble`: scaling folded into the first
    layer, members, mixture); served (``serve()``), the same graph in ONNX Runtime gives the
    same readings, and both the unfolded computation's (inputs scaled, then the network), on a
    row count that is not a multiple of the batch, one row and none; a matrix of the wrong
    width, or a thread count that is not one, is refused before any work."""
    torch.manual_seed(1)
    rng = np.random.default_rng(1)
    cols = [f"f{i}" for i in range(4)]
    offset = np.array([0.0, 0.0, 0.0, 2000.0])  # an operating point: mean / std of 20
    train = pd.DataFrame(rng.normal(3.0, 2.0, (64, 4)) * [1, 1, 1, 50] + offset, columns=cols)
    train["y"] = rng.uniform(0.0, 0.02, 64)
    schema = FeatureSchema.fit(train, cols, dict.fromkeys([*cols, "y"], "1"), "y")
    model = WearRegressor(4, schema.to_dict(), width=8, depth=2, members=3)
    loaded = Surrogate(model, interval_scale=1.645)
    x = rng.normal(3.0, 3.0, (1000, 4)) * [1, 1, 1, 50] + offset
    ref_mean, ref_std = torch_predict(ScaledEnsemble(model, schema), x)
    as_loaded = loaded.predict_array(x, batch=384)
    assert np.array_equal(as_loaded[0], ref_mean) and np.array_equal(as_loaded[1], ref_std)
    for bad in (0, 1.5, True):
        with pytest.raises(ValueError, match=rf"serve\(threads = {bad!r}\)"):
            loaded.serve(bad)
    s = Surrogate(model, interval_scale=1.645).serve(1)
    assert s.serve() is s and s._session is not None
    mean, std = s.predict_array(x, batch=384)
    scale = schema.target_scale
    assert np.allclose(mean, ref_mean, rtol=1e-5, atol=1e-6 * scale)
    assert np.allclose(std, ref_std, rtol=1e-4, atol=1e-6 * scale)
    assert np.all(std > 0)
    with torch.no_grad():  # unfolded: (x - mean) / std into the network as trained
        scaled = (x - np.array(schema.mean)) / np.array(schema.std)
        plain_mean, plain_var = mixture(model.net(torch.as_tensor(scaled, dtype=torch.float32)))
    assert np.allclose(mean, plain_mean.numpy() * scale, rtol=1e-4, atol=1e-5 * scale)
    assert np.allclose(std, plain_var.clamp_min(0).sqrt().numpy() * scale, rtol=1e-3,
                       atol=1e-5 * scale)
    one, _ = s.predict_array(x[5:6])
    assert one[0] == pytest.approx(ref_mean[5], rel=1e-5, abs=1e-6 * scale)
    assert s.predict_array(x[:0])[0].shape == (0,)
    with pytest.raises(ValueError, match=r"\(rows, 4\)"):
        s.predict_array(x[:, :3])


def test_fast_dev_run(tmp_path, dataset):
    value = train(train_cfg(tmp_path, dataset, "case=3", "data.test_replicates=1",
                            "trainer.fast_dev_run=true", "logger=csv"))
    assert np.isfinite(value) and (tmp_path / "run" / "wear_surrogate.pt").is_file()


def test_training_writes_its_outputs_and_learns(trained):
    for name in ("wear_surrogate.pt", "metrics.json", "parity.png", "test_predictions.csv",
                 "config.yaml"):
        assert (trained / name).is_file(), name
    assert list((trained / "checkpoints").glob("*.ckpt"))
    assert (trained / "csv").is_dir()
    rows = pd.read_csv(trained / "test_predictions.csv")
    metrics = json.loads((trained / "metrics.json").read_text())
    for name in ("linear", "median", "estimator"):  # the baselines, on the same rows
        assert np.isfinite(metrics[f"test_{name}_mean_relative_error_pct"]), name
        assert rows[f"root_wear_mm_{name}"].notna().all(), name
    assert {"case", "replicate", "cycles"} <= set(rows.columns)
    # better than predicting the mean wear of the test rows for every row
    err = np.mean(np.abs(rows.root_wear_mm_pred - rows.root_wear_mm))
    assert err < 0.5 * np.mean(np.abs(rows.root_wear_mm - rows.root_wear_mm.mean()))


def test_predict_round_trip_from_the_saved_checkpoint(trained, dataset, tmp_path):
    df = pd.read_parquet(dataset)
    src = tmp_path / "features.csv"
    df[["case", "cycles", *DEFAULT_INPUTS]].assign(oil_temp=40.0).to_csv(src, index=False)
    out = predict_file(trained / "wear_surrogate.pt", src, tmp_path / "wear.csv")
    assert len(out) == len(df) and (tmp_path / "wear.csv").is_file()
    assert (out.oil_temp == 40.0).all()  # a column the model does not read passes through
    s = Surrogate.load(trained / "wear_surrogate.pt")
    mean, _ = s.predict_array(df[DEFAULT_INPUTS].to_numpy(float))
    assert np.allclose(out.root_wear_mm_pred, np.maximum(mean, 0), rtol=1e-5, atol=1e-9)
    single = s.predict(df[DEFAULT_INPUTS].iloc[[7]])
    assert single.root_wear_mm_pred.iloc[0] == pytest.approx(out.root_wear_mm_pred.iloc[7],
                                                             rel=1e-5, abs=1e-9)
    assert np.all(out.root_wear_mm_lower <= out.root_wear_mm_pred)
    assert np.all(out.root_wear_mm_pred <= out.root_wear_mm_upper)
    far = df[DEFAULT_INPUTS].iloc[[0]].copy()
    j = s.schema.inputs.index("dte_kurtosis")
    lo, hi = s.schema.low[j], s.schema.high[j]
    far["dte_kurtosis"] = hi + 0.5 * (hi - lo)  # inside the unit check, outside the envelope
    assert bool(s.predict(far).out_of_range.iloc[0])


@pytest.mark.parametrize(("change", "message"), [
    (lambda d: d.drop(columns="dte_kurtosis"), r"lacks column.*dte_kurtosis"),
    (lambda d: d.assign(dte_peak_to_peak=np.where(d.index == 2, np.nan, d.dte_peak_to_peak)),
     r"row 3 column dte_peak_to_peak is nan"),
    (lambda d: d.assign(dte_peak_to_peak=d.dte_peak_to_peak * 1e6),
     r"dte_peak_to_peak.*another unit.*expects m"),
    (lambda d: d.iloc[:0], r"no rows"),
    (lambda d: d.assign(dte_peak_to_peak=np.where(d.index == 3, d.dte_peak_to_peak * 1e6,
                                                  d.dte_peak_to_peak)),
     r"row 4 column dte_peak_to_peak .* transcription error"),
])
def test_bad_input_is_refused(trained, dataset, change, message):
    df = pd.read_parquet(dataset)[DEFAULT_INPUTS].reset_index(drop=True)
    with pytest.raises(ValueError, match=message):
        Surrogate.load(trained / "wear_surrogate.pt").predict(change(df))


def test_foreign_and_unsafe_checkpoints_are_refused(trained, tmp_path):
    payload = torch.load(trained / "wear_surrogate.pt", weights_only=True)
    payload["hparams"]["schema"]["version"] = 99
    torch.save(payload, tmp_path / "other.pt")
    with pytest.raises(ValueError, match="schema version 99"):
        Surrogate.load(tmp_path / "other.pt")
    lightning_ckpt = next((trained / "checkpoints").glob("*.ckpt"))
    with pytest.raises(ValueError, match="not a"):
        Surrogate.load(lightning_ckpt)
    with pytest.raises(ValueError, match="does not exist"):
        Surrogate.load(tmp_path / "missing.pt")


def test_non_finite_weights_are_refused_and_nothing_is_predicted(trained, tmp_path):
    payload = torch.load(trained / "wear_surrogate.pt", weights_only=True)
    name = next(iter(payload["state_dict"]))
    payload["state_dict"][name] = payload["state_dict"][name].clone().fill_(float("nan"))
    torch.save(payload, tmp_path / "nan.pt")
    with pytest.raises(ValueError, match="non-finite weights"):
        Surrogate.load(tmp_path / "nan.pt")


def test_training_on_a_users_table_from_scratch_and_fine_tuned(trained, dataset, tmp_path):
    """A user's labelled table: own column names mapped, own trajectory column; trained from
    scratch and fine-tuned from the physics-trained network."""
    df = pd.read_parquet(dataset)
    mine = df[df.case == 3].rename(columns={"dte_peak_to_peak": "p2p"})
    mine = mine.assign(gearbox=["rig" + str(r) for r in mine.replicate])
    mine.drop(columns=["case", "replicate"]).to_csv(tmp_path / "mine.csv", index=False)
    common = [f"data.table={tmp_path / 'mine.csv'}", "data.group=gearbox",
              "+data.columns.p2p=dte_peak_to_peak", "data.operating_point=false",
              "data.test_replicates=1", "trainer.max_epochs=5", "logger=csv",
              "model.kind=network"]  # the network's fine-tuning, whichever model CV prefers
    assert np.isfinite(train(train_cfg(tmp_path / "a", dataset, "model.members=3", *common)))
    tuned = train_cfg(tmp_path / "b", dataset, f"init_from={trained / 'wear_surrogate.pt'}",
                      "model.lr=0.0003", *common)
    assert np.isfinite(train(tuned))
    s = Surrogate.load(tmp_path / "b" / "run" / "wear_surrogate.pt")
    base = Surrogate.load(trained / "wear_surrogate.pt")
    assert s.schema == base.schema  # fine-tuned in the pre-trained network's scaling
    with pytest.raises(ValueError, match=r"data\.group"):
        train(train_cfg(tmp_path / "c", dataset, *common[:1], *common[2:]))
    # the output layers only: the hidden layers (the physics-trained features) stay as they
    # were, the output layer moves
    assert np.isfinite(train(train_cfg(tmp_path / "d", dataset,
                                       f"init_from={trained / 'wear_surrogate.pt'}",
                                       "model.trainable=head", *common)))
    head = Surrogate.load(tmp_path / "d" / "run" / "wear_surrogate.pt").model.net
    for i, (w, b) in enumerate(zip(head.weights, head.biases, strict=True)):
        same = (torch.equal(w, base.model.net.weights[i])
                and torch.equal(b, base.model.net.biases[i]))
        assert same == (i < len(head.weights) - 1), f"layer {i}"
    with pytest.raises(ValueError, match="needs init_from"):  # random hidden layers, frozen
        train(train_cfg(tmp_path / "e", dataset, "model.trainable=head", *common))


def test_conformal_scale_covers_the_level_on_exchangeable_scores():
    """Split conformal: on fresh draws from the calibration law the interval covers the level
    (Gaussian scores here, so the scale also approaches the normal quantile)."""
    rng = np.random.default_rng(0)
    mean, std = np.zeros(4000), np.full(4000, 2.0)
    scale = conformal_scale(mean, std, rng.normal(0, 2.0, 4000), 0.9)
    assert scale == pytest.approx(1.645, abs=0.08)
    fresh = rng.normal(0, 2.0, 20000)
    assert np.mean(np.abs(fresh) <= scale * 2.0) == pytest.approx(0.9, abs=0.015)


def test_conformal_scale_by_gearbox_hand_values_and_one_row_each_is_the_row_formula():
    """Three gearboxes of two rows: each row weighs 1 / (4 * 2); the 0.5 level is reached at
    the fourth smallest score. One row per gearbox gives the row formula exactly; too few
    gearboxes for the level give the largest score."""
    scores = np.array([0.3, 1.2, 0.1, 0.9, 2.5, 0.6])
    zero, one = np.zeros(6), np.ones(6)
    gearbox = np.array([0, 0, 1, 1, 2, 2])
    assert conformal_scale(zero, one, scores, 0.5, groups=gearbox) == pytest.approx(0.9)
    assert conformal_scale(zero, one, scores, 0.9, groups=gearbox) == pytest.approx(2.5)
    rng = np.random.default_rng(3)
    for n, level in ((7, 0.5), (40, 0.9), (200, 0.95)):
        x = rng.exponential(1.0, n)
        assert conformal_scale(np.zeros(n), np.ones(n), x, level, groups=np.arange(n)) == (
            conformal_scale(np.zeros(n), np.ones(n), x, level))


def test_a_level_is_attainable_from_as_many_units_as_it_needs_and_the_run_says_when_not(
        tmp_path, dataset, caplog):
    """``K`` held-out units leave ``K / (K + 1)`` below the new unit's mass at infinity: 0.95
    needs 19 (reached at their largest score), 0.9 needs 9. A run with fewer validation
    gearboxes says, for the interval and for the novelty flag, that it took the largest."""
    assert attainable(0.95, 19) and not attainable(0.95, 18)
    assert attainable(0.9, 9) and not attainable(0.9, 8)
    # 19 or 20 units give the level at their largest score (19 / 20, 20 / 21 >= 0.95); 40 at
    # their 39th (39 / 41 >= 0.95 > 38 / 41)
    x = np.arange(1.0, 41.0)
    assert exchangeable_quantile(x[:19], 0.95) == 19.0
    assert exchangeable_quantile(x[:20], 0.95) == 20.0
    assert exchangeable_quantile(x, 0.95) == 39.0
    with caplog.at_level(logging.INFO, logger="surrogate.training"):
        train(train_cfg(tmp_path, dataset, "case=3", "data.test_replicates=1",
                        "data.baseline=false", "trainer.max_epochs=2", "model.members=2",
                        "logger=csv"))
    said = [r.getMessage() for r in caplog.records if "cannot give" in r.getMessage()]
    assert len(said) == 2 and "the interval a 0.95 level" in said[0]
    assert "the novelty flag a 0.95 level" in said[1] and "data.val_replicates" in said[1]


def test_conformal_scale_by_gearbox_covers_a_new_gearbox_where_rows_alone_do_not():
    """Readings of a gearbox err together (a gearbox offset beside each reading's own error):
    over many draws of 13 calibration gearboxes of 7 readings, the interval scaled by
    gearbox covers a new gearbox's reading at least at the level; scaled row by row it
    falls short (the finite-sample term counts 91 readings where 13 units vary)."""
    rng = np.random.default_rng(0)
    draws, k, rows, level = 4000, 13, 7, 0.9
    gearbox = np.repeat(np.arange(k), rows)
    covered = {"gearbox": [], "rows": []}
    for _ in range(draws):
        y = rng.normal(0, 1, (k, 1)) + 0.05 * rng.normal(0, 1, (k, rows))
        new = rng.normal() + 0.05 * rng.normal()
        zero, one = np.zeros(k * rows), np.ones(k * rows)
        covered["gearbox"].append(abs(new) <= conformal_scale(zero, one, y.ravel(), level,
                                                              groups=gearbox))
        covered["rows"].append(abs(new) <= conformal_scale(zero, one, y.ravel(), level))
    assert np.mean(covered["gearbox"]) >= level - 0.01  # MC error 0.005
    assert np.mean(covered["rows"]) < level - 0.02


def test_model_rejects_bad_settings():
    with pytest.raises(ValueError, match="interval"):
        WearRegressor(3, {}, interval=1.5)
    with pytest.raises(ValueError, match="width"):
        WearRegressor(3, {}, width=0)
    with pytest.raises(ValueError, match="trainable"):
        WearRegressor(3, {}, trainable="hidden")


def test_export_is_atomic_and_loadable_without_pickle(trained, tmp_path):
    s = Surrogate.load(trained / "wear_surrogate.pt")
    path = export(s.model, tmp_path / "copy.pt", s.interval_scale, s.novelty)
    torch.load(path, weights_only=True)
    assert not list(tmp_path.glob("*.tmp"))


@pytest.fixture(scope="module")
def fleet() -> pd.DataFrame:
    """The first eight gearboxes of the benchmark's fleet of the independent simulator (as many
    as the labelled-count study below draws); its first ``n`` gearboxes are
    ``independent_fleet(n)`` (each gearbox is drawn from its own seed)."""
    from surrogate.benchmark import independent_fleet

    return independent_fleet(8)


def _first(fleet: pd.DataFrame, n: int) -> pd.DataFrame:
    return fleet[fleet.gearbox < n].reset_index(drop=True)


def test_the_benchmarks_fleet_is_labelled_gearboxes_that_differ(fleet):
    """The fleet used for fine-tuning in the benchmark: every gearbox its own drawn pair (so
    their DTE differ at equal wear), six wear labels per operating point, a group column."""
    from surrogate.benchmark import INDEPENDENT_WEAR_MM, independent_fleet

    np.testing.assert_array_equal(_first(fleet, 1).to_numpy(float),
                                  independent_fleet(1).to_numpy(float))
    fleet = _first(fleet, 2)
    assert len(fleet) == 2 * 2 * len(INDEPENDENT_WEAR_MM)
    assert fleet.groupby("gearbox").root_wear_mm.apply(sorted).map(tuple).nunique() == 1
    new = fleet[fleet.root_wear_mm == 0].groupby("gearbox").dte_peak_to_peak.mean()
    assert abs(new[0] / new[1] - 1) > 0.01
    assert np.isfinite(fleet.drop(columns="cycles").to_numpy(float)).all()
    # its rows carry the profile's summaries as the physics rows do; the fleet draws no
    # geometry, so every gearbox's profile has one shape: mean / root fixed, below 1
    worn = fleet[fleet.root_wear_mm > 0]
    shape = worn.mean_wear_mm / worn.root_wear_mm
    assert shape.max() - shape.min() < 1e-9 and 0 < shape.iloc[0] < 1


def test_the_estimator_refitted_on_a_fleet_ignores_the_cycle_unit_and_reads_its_gearboxes(
        fleet):
    """Beside a fine-tuned network the estimator gets the same labelled gearboxes, the wear
    depth standing in for the cycle count: its readings do not depend on that stand-in's unit,
    and on a gearbox it did not see they rise with the wear."""
    from surrogate.benchmark import fit_estimator, fit_fleet_estimator

    fleet = _first(fleet, 3)
    fleet = fleet[fleet.case == 3]
    labelled, held = fleet[fleet.gearbox < 2], fleet[fleet.gearbox == 2]
    p2p, kurt = held.dte_peak_to_peak.to_numpy(), held.dte_kurtosis.to_numpy()
    read = fit_fleet_estimator(labelled, "root_wear_mm").predict(p2p, kurt).wear
    other = fit_estimator(labelled.assign(cycles=labelled.root_wear_mm * 4e8), "root_wear_mm")
    np.testing.assert_allclose(other.predict(p2p, kurt).wear, read, rtol=1e-3, atol=1e-5)
    true = held.root_wear_mm.to_numpy()
    assert np.corrcoef(read, true)[0, 1] > 0.8
    assert abs(read[true == true.max()][0] - true.max()) < 0.5 * true.max()


def test_the_labelled_count_study_trains_on_the_drawn_gearboxes_alone(tmp_path, monkeypatch,
                                                                     fleet):
    """One draw of two labelled gearboxes: the network and the refitted estimator are scored
    on the draw's four held-out gearboxes (24 rows at 2000 r/min), from a table that holds the
    drawn eight gearboxes and nothing else."""
    from surrogate import benchmark

    monkeypatch.setattr(benchmark, "LABEL_COUNTS", (2,))
    monkeypatch.setattr(benchmark, "LABEL_DRAWS", 1)
    out = benchmark.labelled_counts(ROOT, tmp_path, fleet, [
        "trainer.max_epochs=2", "trainer.min_epochs=1", "model.members=2"])
    assert out[["labelled_gearboxes", "draw", "heldout_rows"]].values.tolist() == [[2, 0, 24]]
    assert np.isfinite(out.to_numpy(float)).all()
    assert 0 <= out.network_coverage[0] <= 1
    table = pd.read_csv(tmp_path / "labelled_counts" / "fleet_2_0.csv")
    assert table.gearbox.nunique() == 2 + 2 + 4 and set(table.case) == {3}


def test_a_mean_wear_network_is_scored_with_estimators_of_its_own_target(tmp_path, fleet):
    """The benchmark's mean-wear model trained on fleet rows: it, the estimator and the null
    model are all scored against the mean depth, not the root depth."""
    from surrogate import benchmark

    fleet = _first(fleet, 8)
    fleet = fleet[fleet.case == 3]
    table = tmp_path / "fleet.csv"
    fleet.to_csv(table, index=False)
    net, labelled, held = benchmark.train_on_fleet(
        ROOT, tmp_path / "net", "case3_absolute_mean", table,
        ["trainer.max_epochs=2", "trainer.min_epochs=1", "model.members=2"], "dte_scratch", 0,
        None)
    assert net.schema.target == "mean_wear_mm"
    rows, plot = benchmark.evaluate(
        "t", net, benchmark.fit_fleet_estimator(labelled, "mean_wear_mm"),
        benchmark.typical_wear(labelled, "mean_wear_mm"), held, speed=True)
    assert rows[0]["rows_per_s"] > 0 and rows[1]["latency_us"] > 0  # the speed rows too
    np.testing.assert_array_equal(plot["true"], held.mean_wear_mm.to_numpy())
    assert plot["target"] == "mean_wear_mm"
    # the estimator reads the mean depth, 0.4 times the root depth on this geometry: on the
    # held-out gearboxes' worn states it is nearer the mean labels than the root labels
    worn = held.root_wear_mm.to_numpy() > 0
    est = plot["estimator"][worn]
    assert (np.abs(est - held.mean_wear_mm.to_numpy()[worn]).mean()
            < 0.5 * np.abs(est - held.root_wear_mm.to_numpy()[worn]).mean())
    assert rows[1]["rmse"] == pytest.approx(
        np.sqrt(np.mean((plot["estimator"] - plot["true"]) ** 2)), rel=1e-6)
    null = rows[2]
    expected = benchmark.wear_errors(
        np.full(len(held), labelled.mean_wear_mm[labelled.mean_wear_mm > 0].median()),
        held.mean_wear_mm.to_numpy())
    assert null["mean_relative_error_pct"] == pytest.approx(expected["mean_relative_error_pct"])


def test_the_dry_law_test_set_wears_a_flatter_deeper_profile():
    """The benchmark's ``dry_wear_law`` gearboxes are the premise of that test set: the same
    draw of every other nuisance, worn by the dry law, has its root a smaller multiple of the
    mean depth and a larger mean depth than under the lubricated law."""
    from physics.dataset.generation import run_unit
    from surrogate.benchmark import DRY_LAW

    dry = spec_from_config({**DRY_LAW, "cases": [3], "replicates": 1, "wear_states": 2,
                            "chunks": 1})
    wet = dataclasses.replace(dry, nuisance=dataclasses.replace(dry.nuisance,
                                                                boundary_share=[0.0, 0.0]))
    (a, _), (b, _) = (run_unit(Scenario(), s, 3, 0) for s in (dry, wet))
    a, b = a.iloc[-1], b.iloc[-1]
    assert a.root_wear_mm / a.mean_wear_mm < 0.6 * b.root_wear_mm / b.mean_wear_mm
    assert a.mean_wear_mm > 1.5 * b.mean_wear_mm


def test_the_beyond_range_set_lies_past_every_range_the_network_trained_on():
    """``beyond_ranges``: each range starts at the default's upper end and reaches a quarter of its
    width past it; one whose upper end is its physical limit stays as it is."""
    from surrogate.benchmark import beyond_ranges

    default, beyond = NuisanceRanges(), NuisanceRanges(**beyond_ranges())
    for name, (_, limit) in NuisanceRanges.LIMITS.items():
        (lo, hi), (b_lo, b_hi) = getattr(default, name), getattr(beyond, name)
        if hi < limit:
            assert b_lo == hi and b_hi == pytest.approx(min(hi + 0.25 * (hi - lo), limit)), name
        else:
            assert [b_lo, b_hi] == [lo, hi], name


def test_the_default_ranges_are_at_least_as_wide_as_the_narrow_ones():
    """The comparison of ``--narrow-ranges``: every training range it tries is valid, and the
    defaults span at least the narrow ones' width and upper end."""
    from surrogate.benchmark import NARROW_RANGES, RANGE_VARIANTS

    default, narrow = NuisanceRanges(), NuisanceRanges(**NARROW_RANGES)
    for name in NARROW_RANGES:
        (lo, hi), (p_lo, p_hi) = getattr(default, name), getattr(narrow, name)
        assert hi - lo > p_hi - p_lo and hi >= p_hi, name
    for ranges in RANGE_VARIANTS.values():
        NuisanceRanges(**ranges)  # valid
    assert RANGE_VARIANTS["default"] == {} and RANGE_VARIANTS["narrow"] == NARROW_RANGES


def test_the_benchmark_summarises_seeds_and_scores_a_null_model():
    """Over training seeds: the mean and the worst error and the smallest coverage per model,
    test set and estimator; the null model is the median of the worn training rows."""
    from surrogate.benchmark import seed_summary, typical_wear

    rows = pd.DataFrame({"scenario": ["case3/x"] * 4, "estimator": ["surrogate"] * 2 + ["null"] * 2,
                         "seed": [0, 1, 0, 1], "mean_relative_error_pct": [2.0, 6.0, 14.0, 15.0],
                         "interval_coverage": [0.9, 0.8, np.nan, np.nan]})
    out = seed_summary(rows)
    assert out.loc[("case3/x", "surrogate")].tolist() == [2, 4.0, 6.0, 0.8]
    assert out.loc[("case3/x", "null"), "mre_max"] == 15.0
    train = pd.DataFrame({"root_wear_mm": [0.0, 0.0, 0.01, 0.02, 0.04]})
    assert typical_wear(train, "root_wear_mm") == 0.02  # the unworn rows do not pull it to 0


@hypothesis.settings(max_examples=25, deadline=None)
@hypothesis.given(offsets=st.lists(st.floats(0.0, 0.02), min_size=1, max_size=4),
                  slope=st.floats(0.5, 2.0))
def test_a_reading_referenced_to_the_unworn_record_loses_its_offset_not_its_slope(offsets,
                                                                                  slope):
    """Readings ``c_g + slope w`` of gearboxes g: the unworn rows read the median offset, and
    referenced to its unworn record every gearbox reads ``slope w``, whose relative error is
    ``|slope - 1|`` on every worn row, whatever the offsets."""
    from surrogate.benchmark import referenced

    wear = np.array([0.0, 0.003, 0.009, 0.015])
    test = pd.DataFrame({"replicate": np.repeat(np.arange(len(offsets)), wear.size),
                         "root_wear_mm": np.tile(wear, len(offsets))})
    reading = np.repeat(offsets, wear.size) + slope * test.root_wear_mm.to_numpy()
    unworn, mre = referenced(test, reading, "root_wear_mm")
    assert unworn == pytest.approx(np.median(offsets), abs=1e-15)
    assert mre == pytest.approx(100 * abs(slope - 1), abs=1e-9)
    assert all(np.isnan(referenced(test[test.root_wear_mm > 0],
                                   reading[test.root_wear_mm.to_numpy() > 0], "root_wear_mm")))


@hypothesis.settings(max_examples=40, deadline=None)
@hypothesis.given(levels=st.lists(st.floats(-1e3, 1e3), min_size=1, max_size=5),
                  rows=st.integers(1, 6), seed=st.integers(0, 2**16))
def test_baseline_changes_are_zero_at_each_baseline_and_blind_to_a_gearboxs_level(levels, rows,
                                                                                   seed):
    """Gearboxes g whose feature reads ``level_g + f(t)``, their rows interleaved: the change
    since each gearbox's first row is ``f(t) - f(t_0)`` whatever the levels, zero at the first
    row, and the other columns stay as they were."""
    rng = np.random.default_rng(seed)
    g = np.repeat(np.arange(len(levels)), rows)
    t = np.tile(np.arange(rows, dtype=float), len(levels))
    order = np.argsort(rng.random(g.size), kind="stable")  # interleave the gearboxes ...
    order = order[np.lexsort((t[order],))]  # ... keeping each one's rows in time order
    f = rng.normal(size=g.size)
    df = pd.DataFrame({"g": g, "t": t, "a": f + np.asarray(levels)[g], "b": f})[
        ["g", "t", "a", "b"]].iloc[order].reset_index(drop=True)
    out = baseline_changes(df, ["a"], ["g"])
    first = df.groupby("g").b.transform("first")
    np.testing.assert_allclose(out.a, df.b - first, atol=1e-9)
    assert (out.a[df.t == 0] == 0).all()
    pd.testing.assert_frame_equal(out.drop(columns="a"), df.drop(columns="a"))


@hypothesis.settings(max_examples=40, deadline=None)
@hypothesis.given(gearboxes=st.integers(1, 4), rows=st.integers(1, 5), seed=st.integers(0, 2**16))
def test_a_lines_vector_change_ignores_the_gearboxs_own_line_and_its_marks_angle(gearboxes, rows,
                                                                                 seed):
    """A line ``c_g + w(t)`` (the flank form's constant vector and the wear's), its phase
    turned by another once-per-revolution mark's angle per gearbox: the magnitude of the
    change since the first row is ``|w(t) - w(t_0)|``, zero at the first row; without a
    gearbox, the line's own magnitude."""
    rng = np.random.default_rng(seed)
    g = np.repeat(np.arange(gearboxes), rows)
    w = rng.normal(size=g.size) + 1j * rng.normal(size=g.size)
    z = (rng.normal(size=gearboxes)[g] + 1j * rng.normal(size=gearboxes)[g] + w) * np.exp(
        1j * rng.uniform(0, 2 * np.pi, gearboxes)[g])
    df = pd.DataFrame({"g": g, "x_re": z.real, "x_im": z.imag})
    out = vector_magnitudes(df, ["x"], ["g"])
    first = w[g * rows]  # each gearbox's first row
    np.testing.assert_allclose(out.x, np.abs(w - first), atol=1e-9)
    np.testing.assert_allclose(vector_magnitudes(df, ["x"]).x, np.abs(z), atol=1e-12)
    assert set(out.columns) == {"g", "x_re", "x_im", "x"}


def test_a_baseline_network_reads_changes_and_needs_the_gearbox(dataset, tmp_path):
    """The main job's default reading: the DTE's mesh lines, not the operating point, enter as their
    vector change since each trajectory's unworn record; the model then reads a gearbox
    whatever its lines before wear (its flank form, its profile error), and refuses rows it
    cannot reference."""
    cfg = train_cfg(tmp_path, dataset, "case=3", "data.test_replicates=1",
                    "trainer.max_epochs=20", "model.members=2", "logger=csv")
    assert np.isfinite(train(cfg))
    s = Surrogate.load(tmp_path / "run" / "wear_surrogate.pt")
    lines = [f"dte_line{k}" for k in LINE_ORDERS]
    assert s.schema.target == "mean_wear_mm"
    assert set(s.schema.baseline) == set(s.schema.vectors) == set(lines)
    assert {"n1_rpm", "torque_Nm"} <= set(s.schema.inputs) - set(s.schema.baseline)
    assert pd.read_csv(tmp_path / "run" / "test_predictions.csv").mean_wear_mm_pred.notna().all()
    # the interval is calibrated on the worn validation rows: the baseline records are not
    # readings
    dm = instantiate(cfg.data)
    dm.setup()
    val = dm.frames["cal"]
    worn = vector_magnitudes(val, lines, ["case", "replicate"])[val.cycles > 0]
    x = worn[list(s.schema.inputs)].to_numpy(float)
    mean, std = s.predict_array(x)
    # normalised conformal: the residuals over the ensemble's spread widened by the novelty
    sigma = s.difficulty(std, s.novelty_score(x))
    assert s.interval_scale == pytest.approx(
        conformal_scale(mean, sigma, worn.mean_wear_mm.to_numpy(), 0.9,
                        groups=worn.groupby(["case", "replicate"]).ngroup().to_numpy()),
        rel=1e-5)
    df = pd.read_parquet(dataset)
    df = df[df.case == 3].reset_index(drop=True)
    cols, keys = s.schema.columns, ["case", "replicate"]
    assert cols == [f"{c}_{p}" for c in lines for p in ("re", "im")] + ["n1_rpm", "torque_Nm"]
    with pytest.raises(ValueError, match="name the column"):
        s.predict(df[cols])
    with pytest.raises(ValueError, match=r"gearbox column\(s\) \['rig'\]"):
        s.predict(df[cols], gearbox=["rig"])
    with pytest.raises(ValueError, match=r"dte_line3_im.*real and imaginary parts"):
        s.predict(df[[*cols, *keys]].drop(columns="dte_line3_im"), gearbox=keys)
    nan = df[[*cols, *keys]].copy()
    nan.loc[3, "dte_line2_re"] = np.nan
    with pytest.raises(ValueError, match=r"dte_line2 \(its parts \['dte_line2_re', "):
        s.predict(nan, gearbox=keys)
    wear = s.predict(df[[*cols, *keys]], gearbox=keys).mean_wear_mm_pred
    # another flank form per gearbox adds a constant vector to each of its lines: the same
    # reading
    rng = np.random.default_rng(0)
    form = {r: rng.normal(0, 3e-6, (len(lines), 2)) for r in df.replicate.unique()}
    add = np.stack(df.replicate.map(form).to_list()).reshape(len(df), -1)
    other = df.assign(**{c: df[c] + add[:, j] for j, c in enumerate(cols[:2 * len(lines)])})
    np.testing.assert_allclose(s.predict(other[[*cols, *keys]], gearbox=keys).mean_wear_mm_pred,
                               wear, rtol=1e-5, atol=1e-9)
    # the baseline rows all read as a row of no change at their operating point
    zero = df.assign(**dict.fromkeys(lines, 0.0))
    mean, _ = s.predict_array(zero[list(s.schema.inputs)].to_numpy(float))
    base = (df.cycles == 0).to_numpy()
    np.testing.assert_allclose(wear[base], np.maximum(mean[base], 0), rtol=1e-5, atol=1e-9)
    # the predict app keeps the gearbox columns it was given
    src = tmp_path / "f.csv"
    df.assign(rig=df.replicate)[[*cols, "rig"]].to_csv(src, index=False)
    with initialize_config_module("gearwear_conf.predict", version_base="1.3"):
        predict_cfg = compose("predict", overrides=[
            f"ckpt={tmp_path / 'run' / 'wear_surrogate.pt'}", f"input={src}", "gearbox=rig",
            f"output={tmp_path / 'w.csv'}"])
    predict.execute(predict.prepare(predict_cfg))
    out = pd.read_csv(tmp_path / "w.csv")
    np.testing.assert_allclose(out.mean_wear_mm_pred, wear, rtol=1e-5, atol=1e-9)
    assert (out.rig == df.replicate).all()
    # a fine-tune must read its features the way the pre-trained network did: told otherwise
    # it is refused; left null it reads as that network (inputs, target, baseline)
    init = f"init_from={tmp_path / 'run' / 'wear_surrogate.pt'}"
    with pytest.raises(ValueError, match=r"data\.baseline=true"):
        train(train_cfg(tmp_path / "b", dataset, "case=3", init,
                        f"data.inputs=[{','.join(s.schema.inputs)}]", "data.baseline=false",
                        "data.target=mean_wear_mm", "data.test_replicates=1"))
    job = prepare(train_cfg(tmp_path / "c", dataset, "case=3", init, "data.test_replicates=1"))
    assert job.data.inputs == list(s.schema.inputs) and job.data.target == s.schema.target
    assert job.data.baseline == tuple(s.schema.baseline)
    # a setting that would choose other inputs is refused, not silently dropped
    with pytest.raises(ValueError, match=r"a fine-tune reads that network's inputs .*, and "
                                         r"data\.sensors = \['acc'\] asks for others"):
        prepare(train_cfg(tmp_path / "c", dataset, "case=3", init, "data.test_replicates=1",
                          "data.sensors=[acc]"))
    with pytest.raises(ValueError, match=r"reads mean_wear_mm, this run's data.target is "
                                         r"root_wear_mm; leave data.target unset"):
        prepare(train_cfg(tmp_path / "d", dataset, "case=3", init, "data.test_replicates=1",
                          "data.target=root_wear_mm"))
    # predict_file takes the gearbox columns too
    again = predict_file(tmp_path / "run" / "wear_surrogate.pt", src, tmp_path / "w2.csv",
                         gearbox=("rig",))
    np.testing.assert_allclose(again.mean_wear_mm_pred, wear, rtol=1e-5, atol=1e-9)


def test_a_baseline_network_refuses_trajectories_that_do_not_start_unworn(dataset, tmp_path):
    shuffled = tmp_path / "shuffled.parquet"
    pd.read_parquet(dataset).sort_values("cycles", ascending=False).to_parquet(shuffled)
    dm = instantiate(train_cfg(tmp_path, shuffled, "case=3",
                               "data.test_replicates=1", "data.val_replicates=1").data)
    with pytest.raises(ValueError, match=r"trajectory \{'case': 3, 'replicate': \d+\}.* starts "
                                         r"at mean_wear_mm = [\d.e-]+, above its least \(0\)"):
        dm.setup()


@pytest.mark.parametrize(("change", "message"), [
    (lambda d: d.assign(g=[0.0, np.nan, 1.0, 1.0]), r"1 row\(s\) have no value in the gearbox"),
    (lambda d: d.assign(n1_rpm=[2000.0, 1800.0, 2000.0, 2000.0]),
     r"row 1, gearbox \{'g': 0\}: n1_rpm = 1800 against 2000.*one operating point per gearbox"),
    (lambda d: d.assign(cycles=[5.0, 0.0, 0.0, 1.0]),
     r"row 1.*cycles = 0 against 5.*sort each gearbox's rows by cycles"),
])
def test_baseline_changes_refuse_rows_they_cannot_reference(change, message):
    rows = pd.DataFrame({"g": [0, 0, 1, 1], "cycles": [0.0, 1.0, 0.0, 1.0], "a": [1.0, 2, 3, 5],
                         "n1_rpm": 2000.0})
    np.testing.assert_array_equal(
        baseline_changes(rows, ["a"], ["g"], fixed=["n1_rpm"]).a, [0.0, 1, 0, 2])
    with pytest.raises(ValueError, match=message):
        baseline_changes(change(rows), ["a"], ["g"], fixed=["n1_rpm"])


def test_a_baseline_table_must_start_each_group_at_its_baseline(dataset, tmp_path):
    """A user's table for data.baseline: each group's first row is read as its baseline
    record, so a group that starts worn is refused, naming the rule; duplicated columns and
    a gearbox option that is no column name are refused too."""
    df = pd.read_parquet(dataset)
    mine = df[df.case == 3].assign(rig=lambda d: d.replicate)
    mine = pd.concat([mine.iloc[1:], mine.iloc[:1]])  # the first gearbox's baseline moved last
    mine.to_csv(tmp_path / "mine.csv", index=False)
    cfg = train_cfg(tmp_path, dataset, f"data.table={tmp_path / 'mine.csv'}", "data.group=rig",
                    "data.baseline=true", "data.test_replicates=1", "data.val_replicates=1")
    # refused as the table is read, before the split is drawn
    with pytest.raises(Exception, match=r"mine\.csv: trajectory \{'rig': 0\} starts at "
                                        r"mean_wear_mm"):
        instantiate(cfg.data)
    twice = pd.concat([df[DEFAULT_INPUTS], df[["dte_kurtosis"]]], axis=1)
    with pytest.raises(ValueError, match=r"\['dte_kurtosis'\] more than once"):
        FeatureSchema.fit(df, DEFAULT_INPUTS, dict.fromkeys([*DEFAULT_INPUTS, "root_wear_mm"],
                                                            "1"), "root_wear_mm").check(twice)
    for bad in (5, [], [""]):
        with pytest.raises(ValueError, match="must be a column name or a list of them"):
            gearbox_columns(bad)


def test_a_users_table_of_mesh_lines_trains_a_baseline_network_and_is_read_by_parts(dataset,
                                                                                    tmp_path):
    """A user's table with the lines' parts (any phase: a part's median differs widely between
    gearboxes, which is no unit mix) trains the baseline network; a table without the parts is
    told to give them, parts in two units are refused, and a fine-tune must read its inputs as
    the same lines."""
    df = pd.read_parquet(dataset)
    mine = df[df.case == 3].assign(rig=lambda d: d.replicate)
    mine.to_csv(tmp_path / "mine.csv", index=False)
    common = [f"data.table={tmp_path / 'mine.csv'}", "data.group=rig", "data.baseline=true",
              "data.test_replicates=1", "trainer.max_epochs=5", "model.members=2",
              "logger=csv"]
    assert np.isfinite(train(train_cfg(tmp_path, dataset, "model.kind=network", *common)))
    s = Surrogate.load(tmp_path / "run" / "wear_surrogate.pt")
    assert set(s.schema.vectors) == {f"dte_line{k}" for k in LINE_ORDERS}
    mine.drop(columns=["dte_line4_re", "dte_line4_im"]).to_csv(tmp_path / "less.csv", index=False)
    with pytest.raises(Exception, match=r"lacks column\(s\) \['dte_line4_re', 'dte_line4_im'\]"):
        instantiate(train_cfg(tmp_path, dataset, *common,
                              f"data.table={tmp_path / 'less.csv'}").data)
    with pytest.raises(Exception, match=r"dte_line2_im'\] of the line input dte_line2 have units"):
        instantiate(train_cfg(tmp_path, dataset, *common, "data.units={dte_line2_im: um}").data)
    flat = mine.assign(dte_line1=np.hypot(mine.dte_line1_re, mine.dte_line1_im)).drop(
        columns=["dte_line1_re", "dte_line1_im"])
    flat.to_csv(tmp_path / "flat.csv", index=False)
    with pytest.raises(ValueError, match=r"as complex lines .*give the table the same columns"):
        train(train_cfg(tmp_path / "b", dataset, *common, f"data.table={tmp_path / 'flat.csv'}",
                        "data.units={dte_line1: m}",
                        f"init_from={tmp_path / 'run' / 'wear_surrogate.pt'}"))


def test_a_change_since_baseline_far_beyond_training_is_read_and_a_unit_error_is_not():
    """A baseline network's inputs are changes since the gearbox's first record: a gearbox of
    another kind may change 40 times more than the training gearboxes did (read, and left to
    the novelty flag), while a factor of a unit's size (1e3) is still refused."""
    from surrogate.schema import FeatureSchema

    train = pd.DataFrame({"dte_kurtosis": np.linspace(-0.09, 0.08, 50),
                          "root_wear_mm": np.linspace(0, 1e-3, 50)})
    schema = FeatureSchema.fit(train, ["dte_kurtosis"], {"dte_kurtosis": "1",
                                                         "root_wear_mm": "mm"},
                               "root_wear_mm", baseline=("dte_kurtosis",))
    wide = pd.DataFrame({"dte_kurtosis": [0.0, 0.05, 3.3]})
    assert schema.check(wide)[2, 0] == 3.3
    with pytest.raises(ValueError, match=r"row 3 column dte_kurtosis .* transcription error"):
        schema.check(wide.assign(dte_kurtosis=[0.0, 0.05, 3.3e3]))


def test_a_checkpoint_whose_schema_and_network_disagree_is_refused(trained, tmp_path):
    """A schema of one input fewer than the network's weights take is refused at load, naming
    both counts, not left to fail inside the network."""
    payload = torch.load(trained / "wear_surrogate.pt", weights_only=True)
    schema = payload["hparams"]["schema"]
    for key in ("inputs", "units", "mean", "std", "low", "high"):
        schema[key] = list(schema[key])[:-1]
    torch.save(payload, tmp_path / "short.pt")
    n = payload["hparams"]["n_inputs"]
    with pytest.raises(ValueError, match=rf"schema names {n - 1} inputs, its network takes {n}"):
        Surrogate.load(tmp_path / "short.pt")
