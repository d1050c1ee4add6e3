"""Surrogate against the analytic empirical-inverse estimator: ``python -m surrogate.benchmark``.

Models (:data:`MODELS`): ``case3`` (the main job, ``case=3``: the mean wear depth from the
vector change of the DTE's mesh lines since each gearbox's first, unworn record, which every
test set has: :func:`gearbox_keys`) and ``all`` (``case=all``), ``loco2`` / ``loco5`` (all
cases but one); their absolute twins (``data.baseline=false``, one record alone):
``case3_absolute`` (root wear, the thesis's Table 13 features), ``case3_absolute_mean`` (its
mean-depth twin), ``all_absolute``, ``all_absolute_mean``, ``all_acc`` (housing acceleration
only), ``loco2_absolute`` / ``loco5_absolute``. Those of :data:`SEEDED` are trained once per
seed of ``--seeds`` (the seed draws the trajectory split and the start, and one seed's figures
can mislead), the others with seed 0.
Every model and estimator is scored on its own target (the mean depth for the main job's
reading, ``case3``, ``all``, ``loco*``; the root wear for the absolute ones unless ``_mean``).
Test sets:

- ``heldout_trajectories``: the model's own test trajectories (never seen in training);
- ``heldout_operating_point_inside`` / ``_outside``: case 2 (2000 r/min, 290 N m, surrounded by
  the other cases' envelope) or case 5 (2200 r/min, at the envelope's edge) left out of training;
- ``nuisance_shifted``: a dataset drawn with another seed from the upper 40 % of every documented
  nuisance range (:func:`shifted_ranges`): a gearbox inside the ranges, away from most training
  trajectories;
- ``beyond_ranges``: gearboxes drawn with another seed just beyond every documented nuisance
  range, ``[high, high + 0.25 (high - low)]`` (:func:`beyond_ranges`; a range that reaches
  its physical limit stays as it is): inputs the network never trained on, which its flag
  should catch;
- ``new_gearboxes``: 32 more case-3 gearboxes of the default ranges drawn with another seed
  (:data:`NEW_GEARBOXES`): gearboxes like the training ones, enough of them to measure the
  interval's coverage;
- ``model_form_off``: case-3 gearboxes of our model whose mesh stiffness, stiffness ratio and
  mesh resonance lie well off the declared model's, 25-50 % above it or 15-30 % below
  (:data:`MODEL_FORM_OFF`; inside the drawn form ranges of :class:`NuisanceRanges`, at their
  far ends for the declared model's own stated uncertainty);
- ``dry_wear_law``: gearboxes of our model worn by the thesis's dry Archard law
  (``boundary_share`` 0.99, :data:`DRY_LAW`; another seed, the documented nuisance ranges
  otherwise): one end member of the drawn wear-law share;
- ``independent_simulator``: features of records of the independent spur-pair simulator
  (:mod:`physics.testbeds.independent_simulator`, another model form) at 2000/300 and 1800/290;
- ``independent_fleet``: the same for all ten gearboxes of a fleet of the independent simulator
  (:func:`independent_fleet`), none of which a physics-trained network saw;
- ``independent_fleet_heldout``: gearboxes of a fleet of the independent simulator
  (:func:`independent_fleet`) that neither network saw, scored for the absolute
  physics-trained network (``case3_absolute``, ``all_absolute``: the fleet's rows read one by
  one) and for networks trained on the fleet's other labelled gearboxes
  (:data:`FLEET_NETWORKS`): the physics-trained one fine-tuned, all its weights
  (``case3_absolute_finetuned``, ``all_absolute_finetuned``) or its output layers only
  (``..._head``), and one of the DTE features trained on those gearboxes alone
  (``..._dte_scratch``): what a user with a few labelled records of his own gearbox type gets
  (docs/own-data.md). Per training seed of ``case3_absolute`` (the seed draws the fleet's
  split too), once for ``all_absolute``.

The estimator (thesis 4.4: cubics of DTE peak-to-peak and kurtosis in cycles and the empirical
wear law, :class:`physics.estimators.empirical_inverse.EmpiricalInverse`) is fitted on the same
training trajectories as the network; so is the null model ``training_median``
(:func:`typical_wear`); beside a network trained on the fleet they are refitted on the fleet's
labelled gearboxes it trained on (:func:`fit_fleet_estimator`). Columns: RMSE [mm], R2, mean
and maximum relative error [%], the conformal interval's coverage (surrogate), out-of-range
(surrogate: the network's own flag, :mod:`surrogate.novelty`) or invalid (estimator) flag
rate, the share of rows missed by the interval and not flagged (``missed_not_flagged``),
the median reading of the unworn rows [mm] and the mean relative error of the readings
referenced to each gearbox's unworn record [%] (:func:`referenced`), batch throughput [rows/s]
and single-row latency [us] on the CPU. Writes ``benchmark.csv``, its figures (``summary.png``:
every model's, the estimator's and the null model's mean relative error on each test set;
``parity/<test set>.png``: each test set's readings against the true wear, :func:`write_figures`)
and the trained models into ``--out`` (default ``logs/benchmark/<time>``), and
``labelled_counts.csv``: how many labelled gearboxes of the independent simulator a network trained
on them needs to beat the estimator refitted on the same (:func:`labelled_counts`); and
``one_rig.csv``: a user's table of one rig of the independent simulator, two speeds and 32 wear
stages, the acceleration RMS and one other feature, trained at one speed and tested at the other,
with stages left out, and cross-validated leaving each stage out in turn, beside the linear model
and the estimator (:func:`one_rig`; its table ``one_rig_table.csv``); and ``real_rig.csv``
(``real_rig_stages.csv``): the public rig's measured table left out one stage at a time, every
model's figures side by side (:func:`real_rig`; ``--real-rig-only`` runs this part alone). Apart,
``--few-labels-only`` writes ``few_labels.csv``: the rig read from its healthy and three labelled
stages, the physics model's curves calibrated on them beside the same calibration without
physics and a straight line (:mod:`surrogate.few_labels`).
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import logging
import math
import os
import tempfile
import time
from datetime import datetime
from pathlib import Path

import numpy as np
import pandas as pd
from hydra import compose, initialize_config_module
from hydra.errors import HydraException
from hydra.utils import instantiate

from physics.dataset.generation import NuisanceRanges
from physics.dynamics.model_form import FACTORS
from physics.estimators.empirical_inverse import EmpiricalInverse, wear_errors
from physics.files import (
    atomic_write,
    check_fresh,
    check_unrepeated,
    check_writable,
    existing_file,
    pyplot,
    read_csv_table,
)
from physics.params import Dynamics
from physics.reference import RIG_RECORDS
from physics.signals.features import features
from physics.signals.order_analysis import mesh_harmonics
from physics.testbeds import IndependentPair, simulate_record, wear_depths
from surrogate import few_labels, settings
from surrogate.baselines import fit_estimator, typical_wear
from surrogate.figures import error_summary, parity_of_set
from surrogate.inference import Surrogate
from surrogate.schema import FeatureSchema
from surrogate.training import prepare, train
from surrogate.wear_data import load_dataset

log = logging.getLogger(__name__)


def train_config(root: Path, out: Path, *overrides: str):
    settings.register()
    with initialize_config_module("gearwear_conf.train", version_base="1.3"):
        return compose("train", overrides=[
            f"paths.root_dir={root}", f"paths.output_dir={out}", "logger=csv",
            "trainer.enable_progress_bar=false", *overrides])


def fit_fleet_estimator(labelled: pd.DataFrame, target: str) -> EmpiricalInverse:
    """The estimator of ``target`` refitted on a fleet's labelled gearboxes, the rows a
    network trained on the fleet learnt from. The independent simulator's records carry wear
    depths, not cycle counts; at each operating point, with its profile shape fixed (the
    fleet draws no geometry), its Archard depths, root and mean alike, grow in proportion to
    the cycles, and the estimator's cubics and wear law do not depend on the unit of N, so the
    root depth stands in for the cycle count (1 um per 1e6 cycles) whichever is the target."""
    return fit_estimator(labelled.assign(cycles=labelled.root_wear_mm * 1e9), target)


def throughput(fn, x: np.ndarray) -> tuple[float, float]:
    """Rows per second on ``x`` as one batch, and the latency of one row [us] (median of 200)."""
    fn(x[:8])
    t = time.perf_counter()
    fn(x)
    rate = len(x) / (time.perf_counter() - t)
    times = []
    for i in range(200):
        t = time.perf_counter()
        fn(x[i:i + 1])
        times.append(time.perf_counter() - t)
    return rate, float(np.median(times)) * 1e6


#: the columns that name one gearbox at one operating point in a test set (those present)
GEARBOX_KEYS = ("case", "replicate", "gearbox", "n1_rpm", "torque_Nm")


def gearbox_keys(test: pd.DataFrame) -> list[str]:
    """The columns of :data:`GEARBOX_KEYS` that ``test`` has: its rows of one gearbox at one
    operating point, first the unworn one (the baseline record of a baseline model)."""
    return [c for c in GEARBOX_KEYS if c in test.columns]


def network_columns(schema: FeatureSchema, test: pd.DataFrame) -> pd.DataFrame:
    """The columns of ``test`` a network reads: its inputs, its operating point (checked) and
    the gearbox keys."""
    have = [c for c in schema.checked_columns if c in test.columns]
    return test[list(dict.fromkeys([*have, *gearbox_keys(test)]))]


def referenced(test: pd.DataFrame, wear: np.ndarray, target: str) -> tuple[float, float]:
    """How a wear reading depends on the gearbox's unworn state: the median reading of the
    unworn rows (each gearbox's record at zero wear), and the mean relative error [%] of the
    readings referenced to them (each gearbox's reading minus that of its unworn record, as a
    condition-monitoring system trends against its commissioning baseline). NaN where no row
    is unworn. An estimator that reads the change of wear right but not its level has a large
    unworn reading and a small referenced error."""
    true = test[target].to_numpy()
    gearbox = test.groupby(gearbox_keys(test), sort=False).ngroup().to_numpy()
    unworn = true == 0
    if not unworn.any():
        return math.nan, math.nan
    base = pd.Series(wear[unworn]).groupby(gearbox[unworn]).mean()
    worn = (true > 0) & np.isin(gearbox, base.index)
    delta = wear[worn] - base.reindex(gearbox[worn]).to_numpy()
    mre = float(np.mean(np.abs(delta - true[worn]) / true[worn]) * 100) if worn.any() else math.nan
    return float(np.median(wear[unworn])), mre


def trained(cfg, folder: Path) -> tuple[Surrogate, object, EmpiricalInverse, float]:
    """Train ``cfg`` into ``folder``: the network, its data module (set up), and the estimator
    and the typical wear (:func:`typical_wear`) of its training rows and target."""
    train(cfg)
    dm = instantiate(cfg.data)
    dm.setup()
    net = Surrogate.load(folder / "wear_surrogate.pt")
    rows, target = dm.frames["train"], net.schema.target
    return net, dm, fit_estimator(rows, target), typical_wear(rows, target)


def evaluate(name: str, surrogate: Surrogate, est: EmpiricalInverse, typical: float,
             test: pd.DataFrame, speed: bool) -> tuple[list[dict], dict]:
    """The network, the estimator and the null model (both fitted by the caller on the
    network's target) on ``test``: one row each of :func:`wear_errors` and the columns of the
    module text, and the parity plot's data."""
    schema, keys = surrogate.schema, gearbox_keys(test)
    target, true = schema.target, test[schema.target].to_numpy()
    readings = schema.readings(test, keys)
    if schema.baseline and np.any(true[~readings] != 0):
        raise ValueError(f"{name}: a gearbox's first row is worn; a baseline model needs it "
                         "unworn")
    pred = surrogate.predict(network_columns(schema, test), gearbox=keys)
    e = est.predict(test.dte_peak_to_peak.to_numpy(), test.dte_kurtosis.to_numpy())
    inside = surrogate.coverage(pred, test, keys)
    flagged = pred.out_of_range.to_numpy()
    missed = ~((true >= pred[f"{target}_lower"].to_numpy())
               & (true <= pred[f"{target}_upper"].to_numpy()))
    net_unworn, net_ref = referenced(test, pred[f"{target}_pred"].to_numpy(), target)
    est_unworn, est_ref = referenced(test, e.wear, target)
    rows = [{"scenario": name, "estimator": "surrogate", "test_rows": len(test),
             **wear_errors(pred[f"{target}_pred"], true), "interval_coverage": inside,
             "flag_rate": float(flagged[readings].mean()),
             "missed_not_flagged": float((missed & ~flagged)[readings].mean()),
             "unworn_reading": net_unworn, "referenced_mre_pct": net_ref},
            {"scenario": name, "estimator": "empirical_inverse", "test_rows": len(test),
             **wear_errors(e.wear, true), "interval_coverage": np.nan,
             "flag_rate": float(np.mean(~e.valid)), "unworn_reading": est_unworn,
             "referenced_mre_pct": est_ref},
            {"scenario": name, "estimator": "training_median", "test_rows": len(test),
             **wear_errors(np.full_like(true, typical), true), "interval_coverage": np.nan,
             "flag_rate": np.nan}]
    if speed:
        read = schema.network_rows(network_columns(schema, test), keys)
        x = np.repeat(read[list(schema.inputs)].to_numpy(float),
                      -(-1_000_000 // len(test)), axis=0)[:1_000_000]
        rows[0]["rows_per_s"], rows[0]["latency_us"] = throughput(
            lambda a: surrogate.predict_array(a)[0], x)
        p, k = test.dte_peak_to_peak.to_numpy(), test.dte_kurtosis.to_numpy()
        pk = np.repeat(np.stack([p, k], 1), -(-200_000 // len(test)), axis=0)[:200_000]
        rows[1]["rows_per_s"], rows[1]["latency_us"] = throughput(
            lambda a: est.predict(a[:, 0], a[:, 1]).wear, pk)
    plot = {"true": true, "surrogate": pred[f"{target}_pred"].to_numpy(), "estimator": e.wear,
            "target": target}
    return rows, plot


#: trained models: name -> train.py overrides
MODELS = {
    "case3": ["case=3"],
    "case3_absolute": ["case=3", "data.baseline=false"],
    "case3_absolute_mean": ["case=3", "data.baseline=false", "data.target=mean_wear_mm"],
    "all": ["case=all"],
    "all_absolute": ["case=all", "data.baseline=false"],
    "all_absolute_mean": ["case=all", "data.baseline=false", "data.target=mean_wear_mm"],
    "all_acc": ["case=all", "data.baseline=false", "data.sensors=[acc]"],
    "loco2": ["case=all", "data.holdout_case=2"],
    "loco5": ["case=all", "data.holdout_case=5"],
    "loco2_absolute": ["case=all", "data.baseline=false", "data.holdout_case=2"],
    "loco5_absolute": ["case=all", "data.baseline=false", "data.holdout_case=5"],
}
#: the dry-law test set: the dataset spec's values (8 gearboxes per case)
DRY_LAW = {"seed": 2, "replicates": 8, "nuisance": {"boundary_share": [0.99, 0.99]}}
#: the beyond-the-ranges test set: the dataset spec's values (8 gearboxes per case)
BEYOND = {"seed": 4, "replicates": 8}
#: the new-gearboxes test set: 32 more case-3 gearboxes of the default ranges (another seed),
#: enough to measure the interval's coverage of gearboxes like the training ones
NEW_GEARBOXES = {"cases": [3], "seed": 9, "replicates": 32}
#: the model-form-off test set: case-3 gearboxes of our physics whose mesh stiffness level,
#: double/single stiffness ratio and mesh resonance (:mod:`physics.dynamics.model_form`) lie
#: off the declared model's, 8 above it and 8 below (the dataset spec's values of each half)
MODEL_FORM_OFF = {
    "high": {"cases": [3], "seed": 3, "replicates": 8, "nuisance": {
        "stiffness_factor": [1.25, 1.5], "double_contact_factor": [1.15, 1.4],
        "resonance_factor": [1.25, 1.5]}},
    "low": {"cases": [3], "seed": 3, "replicates": 8, "nuisance": {
        "stiffness_factor": [0.7, 0.8], "double_contact_factor": [0.75, 0.85],
        "resonance_factor": [0.7, 0.8]}}}
#: models trained once per seed of ``--seeds``; the others train with seed 0
SEEDED = ("case3", "all", "case3_absolute", "case3_absolute_mean")
#: the independent simulator's operating points and wear states
INDEPENDENT_POINTS = ((2000.0, 300.0), (1800.0, 290.0))
INDEPENDENT_WEAR_MM = (0.0, 0.003, 0.006, 0.009, 0.012, 0.015)
#: the independent simulator's records' sampling rate [Hz] (the physics dataset's)
INDEPENDENT_FS = Dynamics().sample_rate_hz
#: the fleet of independent gearboxes: these fields of ``IndependentPair`` times U(1 -+ spread)
FLEET_FIELDS = ("runout1_um", "mesh_damping_ratio", "single_stiffness_N_mm_um",
                "housing_mass_kg", "half_backlash_um")
FLEET_SPREAD = 0.25
#: fleet gearboxes: labelled (trained on), validating (the interval) and held out
FLEET_SPLIT = {"train": 4, "val": 2, "test": 4}
#: networks trained on the fleet's labelled gearboxes: label -> (train.py overrides, whether
#: they start from the physics-trained network): every weight fine-tuned at a tenth of the
#: learning rate, the output layers only at the default rate, or a network of the DTE
#: features (and the operating point) trained on the labelled gearboxes alone
FLEET_NETWORKS = {"finetuned": (["model.lr=0.0003"], True),
                  "head": (["model.trainable=head"], True),
                  "dte_scratch": (["data.sensors=[dte]"], False)}
#: labelled gearboxes (and draws of them) for :func:`labelled_counts`
LABEL_COUNTS, LABEL_DRAWS = (1, 2, 3, 4), 5


def shifted_ranges(share: float = 0.4, base: NuisanceRanges | None = None) -> dict:
    """The nuisance ranges ``base`` (default: the documented ones) narrowed to their upper
    ``share``: a gearbox inside the ranges but away from where most training trajectories
    lie."""
    base = base or NuisanceRanges()
    out = {}
    for name in NuisanceRanges.LIMITS:
        lo, hi = getattr(base, name)
        out[name] = [lo + (1 - share) * (hi - lo), hi]
    return out


def beyond_ranges(share: float = 0.25, base: NuisanceRanges | None = None) -> dict:
    """The nuisance ranges ``base`` (default: the documented ones) moved just beyond their
    upper ends, ``[high, high + share (high - low)]``: gearboxes of a kind the network never
    saw. A range whose upper end is its physical limit (:attr:`NuisanceRanges.LIMITS`, the
    wear-law share's 1) stays as it is."""
    base = base or NuisanceRanges()
    out = {}
    for name, (_, limit) in NuisanceRanges.LIMITS.items():
        lo, hi = getattr(base, name)
        out[name] = [lo, hi] if hi >= limit else [hi, min(hi + share * (hi - lo), limit)]
    return out


def model_form_off(root: Path) -> pd.DataFrame:
    """The model-form-off test set (:data:`MODEL_FORM_OFF`), built into ``root/data`` once;
    the low half's replicates numbered after the high half's."""
    parts = [load_dataset(root / "data" / f"dataset_model_form_{k}.parquet", spec)
             for k, spec in MODEL_FORM_OFF.items()]
    parts[1] = parts[1].assign(replicate=parts[1].replicate + parts[0].replicate.max() + 1)
    return pd.concat(parts, ignore_index=True)


def independent_rows(seed: int = 0, pair: IndependentPair | None = None) -> pd.DataFrame:
    """Feature rows of the independent spur-pair simulator (a model form other than ours):
    DTE and housing acceleration records of one gear set at two operating points and six root
    wear depths, each record at its own start angle told by a once-per-revolution mark (for
    the mesh lines), labelled with the root, largest and mean depth of its wear profile
    (:func:`wear_depths`)."""
    rows, pair = [], pair or IndependentPair()
    for k, (n1, torque) in enumerate(INDEPENDENT_POINTS):
        for w, wear in enumerate(INDEPENDENT_WEAR_MM):
            rng = np.random.default_rng([seed, k, w])
            angle = float(rng.uniform(0.0, 2 * np.pi))
            rec = {q: simulate_record(pair, n1_rpm=n1, torque_Nm=torque, wear_mm=wear,
                                      quantity=q, fs_hz=INDEPENDENT_FS, rng=rng,
                                      gear_set_seed=seed, start_angle_rad=angle)[None]
                   for q in ("dte_m", "accel_m_s2")}
            f_dte, f_acc = features(rec["dte_m"]), features(rec["accel_m_s2"])
            f_mesh = mesh_harmonics(rec["dte_m"], INDEPENDENT_FS, pair.mesh_frequency_hz(n1),
                                    start_phase_rad=pair.z1 * angle)
            rows.append({"case": 3 if (n1, torque) == (2000.0, 300.0) else 1, "cycles": np.nan,
                         "n1_rpm": n1, "torque_Nm": torque, **wear_depths(pair, wear),
                         **{f"dte_{n}": float(v[0]) for n, v in f_dte.items()},
                         **{f"acc_{n}": float(v[0]) for n, v in f_acc.items()},
                         **{f"dte_{n}": float(v[0]) for n, v in f_mesh.items()}})
    return pd.DataFrame(rows)


def independent_fleet(gearboxes: int, seed: int = 1) -> pd.DataFrame:
    """Labelled rows of ``gearboxes`` gearboxes of the independent simulator (column
    ``gearbox``), each with the fields of :data:`FLEET_FIELDS` drawn within +-25 % of the
    simulator's defaults: a user's labelled records of his own gearbox type."""
    base, frames = IndependentPair(), []
    for g in range(gearboxes):
        rng = np.random.default_rng([seed, g])
        pair = dataclasses.replace(base, **{
            f: getattr(base, f) * (1 + FLEET_SPREAD * rng.uniform(-1, 1)) for f in FLEET_FIELDS})
        frames.append(independent_rows(seed=1000 * seed + g, pair=pair).assign(gearbox=g))
    return pd.concat(frames, ignore_index=True)


def train_on_fleet(root: Path, folder: Path, name: str, table: Path, extra: list[str],
                   label: str, seed: int, physics: Path | None
                   ) -> tuple[Surrogate, pd.DataFrame, pd.DataFrame]:
    """Train model ``name`` into ``folder`` on the labelled gearboxes of the fleet table
    ``table`` the way a user would (``data.table``, the overrides of ``FLEET_NETWORKS[label]``
    and, where it says so, ``init_from`` the physics-trained network in folder ``physics``;
    ``seed`` draws the fleet's split); returns the network, the fleet's rows it trained on and
    its held-out rows (every column of the table, whatever the network's inputs)."""
    fleet = pd.read_csv(table)
    overrides, from_physics = FLEET_NETWORKS[label]
    if from_physics:
        overrides = [f"init_from={physics / 'wear_surrogate.pt'}", *overrides]
    cfg = train_config(root, folder, *MODELS[name], *extra, f"seed={seed}",
                       f"data.table={table}", "data.group=gearbox",
                       f"data.val_replicates={FLEET_SPLIT['val']}",
                       f"data.test_replicates={FLEET_SPLIT['test']}",
                       *overrides)
    log.info("model %s: %s on the labelled gearboxes of %s", name, label, table.name)
    train(cfg)
    dm = prepare(cfg).data  # read as train() read it (a fine-tune takes its network's reading)
    dm.setup()
    ids = np.sort(fleet.gearbox.unique())  # the table's groups in the data module's order

    def rows(split: str) -> pd.DataFrame:
        return fleet[fleet.gearbox.isin(ids[dm.frames[split].replicate.unique()])]

    return Surrogate.load(folder / "wear_surrogate.pt"), rows("train"), rows("test")


def labelled_counts(root: Path, out: Path, fleet: pd.DataFrame, extra: list[str]
                    ) -> pd.DataFrame:
    """How many labelled gearboxes of a type our model does not describe a network needs: for
    each count ``n`` of :data:`LABEL_COUNTS` and each of :data:`LABEL_DRAWS` draws, ``n`` plus
    the validating and held-out gearboxes of :data:`FLEET_SPLIT` drawn from the case-3 fleet,
    the DTE network of ``FLEET_NETWORKS["dte_scratch"]`` trained on the ``n`` and the
    estimator refitted on them, both scored on the held-out ones (the draw is the split's
    seed; with all ten gearboxes it is the benchmark's own fleet split)."""
    mine = fleet[fleet.case == 3]
    others = FLEET_SPLIT["val"] + FLEET_SPLIT["test"]
    rows = []
    for n, draw in itertools.product(LABEL_COUNTS, range(LABEL_DRAWS)):
        # 7: a random stream of its own, apart from the fleet's (seed 1) and the split's (draw)
        chosen = np.random.default_rng([7, n, draw]).permutation(mine.gearbox.unique())
        table = out / "labelled_counts" / f"fleet_{n}_{draw}.csv"
        table.parent.mkdir(parents=True, exist_ok=True)
        subset = mine[mine.gearbox.isin(chosen[:n + others])]
        atomic_write(table, lambda p, frame=subset: frame.to_csv(p, index=False))
        net, labelled, held = train_on_fleet(root, table.with_suffix(""), "case3_absolute",
                                             table, extra, "dte_scratch", draw, None)
        target = net.schema.target
        (mine_net, mine_est, _), _ = evaluate(
            f"dte_scratch_{n}_{draw}", net, fit_fleet_estimator(labelled, target),
            typical_wear(labelled, target), held, speed=False)
        rows.append({"labelled_gearboxes": n, "draw": draw, "heldout_rows": len(held),
                     "network_mre_pct": mine_net["mean_relative_error_pct"],
                     "network_rmse": mine_net["rmse"],
                     "network_coverage": mine_net["interval_coverage"],
                     "estimator_mre_pct": mine_est["mean_relative_error_pct"],
                     "estimator_rmse": mine_est["rmse"]})
    return pd.DataFrame(rows)


#: the one-rig table: shaft speeds [rev/s], torque [N m], wear stages up to a root depth [mm]
ONE_RIG_SPEEDS, ONE_RIG_TORQUE, ONE_RIG_STAGES, ONE_RIG_WEAR_MM = (15, 45), 200.0, 32, 0.03
#: its splits: name -> train.py overrides (train at 15 rev/s and test at 45; six stages held
#: out and four validating, drawn by the seed, at both speeds; every stage left out in turn,
#: the leave-one-group-out cross-validation of ``data.cv=logo``, four validating in each fold)
ONE_RIG_SPLITS = {
    "by_speed": ["data.group=stage", "data.group_by=speed", "data.test_groups=[45]",
                 "data.val_replicates=4"],
    "stages_out": ["data.group=stage", "data.test_replicates=6", "data.val_replicates=4"],
    "stage_cv": ["data.group=stage", "data.group_by=stage", "data.cv=logo",
                 "data.val_replicates=4"]}
#: its network's inputs, the acceleration RMS and one other feature, with their units
ONE_RIG_INPUTS = ["data.inputs=[acc_rms,dte_peak_to_peak]", "data.target=root_wear_mm"]


def one_rig_table(stages: int = ONE_RIG_STAGES, seed: int = 0) -> pd.DataFrame:
    """A user's table of one rig: one gearbox of the independent simulator
    (:mod:`physics.testbeds.independent_simulator`, another model form than ours) at two shaft
    speeds, ``stages`` wear stages from new to :data:`ONE_RIG_WEAR_MM` of root wear, one
    record per stage and speed: the acceleration RMS and the DTE peak-to-peak value (the
    network's inputs), the DTE kurtosis and a cycle count (the thesis's estimator's; the
    Archard depth of one operating point grows in proportion to the cycles, 1 um per 1e6, as
    in :func:`fit_fleet_estimator`) and the root wear."""
    pair, rows = IndependentPair(), []
    for speed in ONE_RIG_SPEEDS:
        for stage in range(stages):
            wear = ONE_RIG_WEAR_MM * stage / (stages - 1)
            rng = np.random.default_rng([seed, speed, stage])
            rec = {q: simulate_record(pair, n1_rpm=60.0 * speed, torque_Nm=ONE_RIG_TORQUE,
                                      wear_mm=wear, quantity=q, rng=rng, duration_s=0.25)[None]
                   for q in ("dte_m", "accel_m_s2")}
            f_dte, f_acc = features(rec["dte_m"]), features(rec["accel_m_s2"])
            rows.append({"rig": "independent", "speed": speed, "stage": stage,
                         "cycles": wear * 1e9, "acc_rms": float(f_acc["rms"][0]),
                         "dte_peak_to_peak": float(f_dte["peak_to_peak"][0]),
                         "dte_kurtosis": float(f_dte["kurtosis"][0]), "root_wear_mm": wear})
    return pd.DataFrame(rows)


def one_rig(root: Path, out: Path, extra: list[str], seed: int = 0) -> list[dict]:
    """The one-rig table (:func:`one_rig_table`) written to ``out`` and trained on as a user
    would, once per split of :data:`ONE_RIG_SPLITS`; per split a row of the network's, the
    linear model's and the estimator's test errors (their ``metrics.json``), the interval's
    coverage, the flagged share and the share missed and not flagged; ``kept`` the kind the
    run kept (``data.cv=logo``: each kind and how many folds kept it, ``linear:30 network:2``)."""
    table = out / "one_rig_table.csv"
    frame = one_rig_table()
    atomic_write(table, lambda p: frame.to_csv(p, index=False))
    rows = []
    for split, overrides in ONE_RIG_SPLITS.items():
        folder = out / "models" / f"one_rig_{split}"
        train(train_config(root, folder, f"data.table={table}", *ONE_RIG_INPUTS, *overrides,
                           *extra, f"seed={seed}"))
        m = json.loads((folder / "metrics.json").read_text())
        rows.append({"scenario": f"one_rig/{split}", "seed": seed,
                     "kept": m.get("model_kind") or " ".join(  # logo: each fold's own
                         f"{k[len('folds_kept_'):]}:{n}" for k, n in sorted(m.items())
                         if k.startswith("folds_kept_")),
                     **{f"{who}_mre_pct": m.get(f"test_{p}mean_relative_error_pct", math.nan)
                        for who, p in (("kept", ""), ("network", "network_"),
                                       ("linear", "linear_"), ("monotone", "monotone_"),
                                       ("average", "average_"), ("estimator", "estimator_"),
                                       ("median", "median_"))},
                     "interval_coverage": m["test_interval_coverage"],
                     "flag_rate": m["test_flagged_share"],
                     "missed_not_flagged": m["test_missed_not_flagged_share"]})
    return rows


#: the public rig's run as a user types it (its records: :data:`physics.reference.RIG_RECORDS`),
#: every stage left out in turn (train.py overrides)
REAL_RIG_RUN = ["data.inputs=[acc_rms_g,fm_energy]", "data.target=wear_mm",
                "data.units={acc_rms_g: g, fm_energy: '1', wear_mm: mm}", "data.group=stage",
                "data.group_by=stage", "data.cv=logo", "data.val_replicates=4"]
#: the models real_rig.csv lists, the kept one first
REAL_RIG_MODELS = ("kept", "network", "linear", "monotone", "average", "median")


def real_rig(root: Path, out: Path, extra: list[str], table: Path = RIG_RECORDS
             ) -> pd.DataFrame:
    """The real rig's table (by default the packaged one,
    :data:`physics.reference.RIG_RECORDS`) left out one stage at a time as a user runs it
    (:data:`REAL_RIG_RUN`; each fold chooses its model by cross-validation over its own
    training stages): one row per model of its mean relative error over the worn stages'
    folds and its 95 % interval's coverage over every fold's rows (the kept model's own
    interval; the linear, monotone and average models' CV+ intervals), and how many folds kept each
    kind. Writes ``real_rig.csv`` and ``real_rig_stages.csv`` (each stage's errors)."""
    folder = out / "models" / "real_rig"
    start = time.perf_counter()
    train(train_config(root, folder, f"data.table={table}", *REAL_RIG_RUN, *extra))
    seconds = time.perf_counter() - start
    cv = pd.read_csv(folder / "cv.csv")
    rows = []
    for who in REAL_RIG_MODELS:
        p = "" if who == "kept" else f"{who}_"
        mre = cv.get(f"test_{p}mean_relative_error_pct")
        cover = cv.get(f"test_{p}interval_coverage")
        weights = cv.test_rows
        rows.append({"model": who, "mean_relative_error_pct":
                     float(mre.mean()) if mre is not None else math.nan,
                     "interval_coverage_rows": float(np.average(cover, weights=weights))
                     if cover is not None and cover.notna().all() else math.nan,
                     "interval_coverage_stages": float(cover.mean())
                     if cover is not None and cover.notna().all() else math.nan,
                     "folds_kept": int((cv.model_kind == who).sum()) if who != "kept"
                     else len(cv), "seconds": seconds})
    summary = pd.DataFrame(rows)
    stages = cv[["stage", "test_rows", "model_kind",
                 *[c for who in REAL_RIG_MODELS
                   for c in [f"test_{'' if who == 'kept' else who + '_'}mean_relative_error_pct"]
                   if c in cv.columns], "test_interval_coverage"]]
    atomic_write(out / "real_rig.csv", lambda p: summary.to_csv(p, index=False))
    atomic_write(out / "real_rig_stages.csv", lambda p: stages.to_csv(p, index=False))
    return summary


def write_figures(out: Path, table: pd.DataFrame, plots: dict[tuple[str, str], dict]) -> None:
    """The benchmark's figures into ``out``: ``summary.png``, every model's, estimator's and
    null model's mean relative error on each test set (:func:`error_summary`, from ``table``),
    and ``parity/<test set>.png``, each test set's readings against its true wear
    (:func:`parity_of_set`; ``plots``: (model, test set) -> :func:`evaluate`'s plot data)."""
    plt = pyplot()

    def save(name: str, fig) -> None:
        atomic_write(out / name, lambda p: fig.savefig(p, dpi=110, format="png"))
        plt.close(fig)

    save("summary.png", error_summary(table))
    for test in dict.fromkeys(s for _, s in plots):
        save(f"parity/{test}.png",
             parity_of_set(test, {m: d for (m, s), d in plots.items() if s == test}))


def run(out: Path, root: Path, extra: list[str], seeds: int = 5, real: Path = RIG_RECORDS
        ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Train the models of :data:`MODELS` (those of :data:`SEEDED` once per training seed: the
    seed draws their split and start, and one seed's figure says little) and, for
    ``case3_absolute`` and ``all_absolute``, the networks of :data:`FLEET_NETWORKS` on the
    fleet's labelled gearboxes;
    score them, the estimator and the null model (refitted on the fleet beside a network
    trained on it) on the test sets (column ``seed``); and :func:`labelled_counts`. Writes
    ``benchmark.csv``, ``labelled_counts.csv`` and the figures (:func:`write_figures`);
    returns the two tables.
    ``extra``: train.py overrides for every network."""
    shifted = load_dataset(root / "data" / "dataset_shifted.parquet",
                           {"seed": 1, "replicates": 8, "nuisance": shifted_ranges()})
    dry = load_dataset(root / "data" / "dataset_dry_law.parquet", DRY_LAW)
    beyond = load_dataset(root / "data" / "dataset_beyond.parquet",
                          {**BEYOND, "nuisance": beyond_ranges()})
    form_off = model_form_off(root)
    new = load_dataset(root / "data" / "dataset_new_gearboxes.parquet", NEW_GEARBOXES)
    foreign = independent_rows()
    fleet = independent_fleet(sum(FLEET_SPLIT.values()))
    rows, plots = [], {}
    for name, seed in [(m, s) for m in MODELS for s in range(seeds if m in SEEDED else 1)]:
        folder = out / "models" / (name if seed == 0 else f"{name}_seed{seed}")
        cfg = train_config(root, folder, *MODELS[name], *extra, f"seed={seed}")
        log.info("model %s: training (seed %d)", name, seed)
        surrogate, dm, est, typical = trained(cfg, folder)
        cases = set(dm.cases)
        loco = name.startswith("loco")
        sets = {"heldout_trajectories" if not loco else
                f"heldout_operating_point_{'inside' if name[:5] == 'loco2' else 'outside'}":
                dm.frames["test"]}
        if not loco:
            sets["nuisance_shifted"] = shifted[shifted.case.isin(cases)]
            sets["beyond_ranges"] = beyond[beyond.case.isin(cases)]
        if not loco and 3 in cases:
            sets["model_form_off"] = form_off
            sets["new_gearboxes"] = new
        if not loco:
            sets["dry_wear_law"] = dry[dry.case.isin(cases)]
            sets["independent_simulator"] = foreign[foreign.case.isin(cases)]
            sets["independent_fleet"] = fleet[fleet.case.isin(cases)]
        for set_name, test in sets.items():
            r, plot = evaluate(f"{name}/{set_name}", surrogate, est, typical, test,
                               speed=(name, seed, set_name) == ("case3", 0,
                                                                "heldout_trajectories"))
            rows += [{**row, "seed": seed} for row in r]
            if seed == 0:
                plots[(name, set_name)] = plot
        if name in ("case3_absolute", "all_absolute"):
            table, mine = out / f"fleet_{name}.csv", fleet[fleet.case.isin(cases)]
            if seed == 0:  # the same gearboxes for every seed
                atomic_write(table, lambda p, frame=mine: frame.to_csv(p, index=False))
            nets, splits = {name: surrogate}, set()
            for label in FLEET_NETWORKS:
                nets[f"{name}_{label}"], labelled, held = train_on_fleet(
                    root, folder.parent / f"{folder.name}_{label}", name, table, extra, label,
                    seed, folder)
                splits.add((tuple(labelled.index), tuple(held.index)))
            if len(splits) != 1:  # the split is the seed's, whatever the network's overrides
                raise RuntimeError(f"the fleet networks of {name} (seed {seed}) were split "
                                   "differently; their scores would not be comparable")
            # a network trained on the fleet against the estimator and null model given the
            # same labelled gearboxes; the physics-trained one against those fitted on its rows
            refit = {m: (fit_fleet_estimator(labelled, m), typical_wear(labelled, m))
                     for m in {n.schema.target for label, n in nets.items() if label != name}}
            for label, net in nets.items():
                own = label == name
                e, t = (est, typical) if own else refit[net.schema.target]
                r, plot = evaluate(f"{label}/independent_fleet_heldout", net, e, t, held,
                                   speed=False)
                rows += [{**row, "seed": seed} for row in r]
                if seed == 0:
                    plots[(label, "independent_fleet_heldout")] = plot
    table = pd.DataFrame(rows)
    atomic_write(out / "benchmark.csv", lambda p: table.to_csv(p, index=False))
    write_figures(out, table, plots)
    counts = labelled_counts(root, out, fleet, extra)
    atomic_write(out / "labelled_counts.csv", lambda p: counts.to_csv(p, index=False))
    rig = pd.DataFrame(one_rig(root, out, extra))
    atomic_write(out / "one_rig.csv", lambda p: rig.to_csv(p, index=False))
    real_rig(root, out, extra, real)
    return table, counts


#: narrow nuisance ranges where they differ from the defaults (:class:`NuisanceRanges`): a
#: middle part of each source's span, the lubricated wear law alone and the declared model's
#: form
NARROW_RANGES = {"damping_ratio": [0.03, 0.12], "eccentricity1_um": [5.0, 15.0],
                 "profile_error_um": [1.5, 4.5], "form_deviation_um": [1.5, 4.5],
                 "half_backlash_um": [30.0, 70.0],
                 "boundary_share": [0.0, 0.0], **{f: [1.0, 1.0] for f in FACTORS}}
#: the training ranges :func:`narrow_ranges` compares, each as its changes to the defaults:
#: the narrow ones, the default tolerances (damping, run-out, profile, backlash) with the
#: narrow wear law and form, those with the default wear-law share too, and the defaults
RANGE_VARIANTS = {
    "narrow": NARROW_RANGES,
    "tolerances": {k: NARROW_RANGES[k] for k in ("boundary_share", *FACTORS)},
    "tolerances_wear_law": {f: NARROW_RANGES[f] for f in FACTORS},
    "default": {}}
#: the held-out gearboxes of :func:`narrow_ranges`: case 3, a seed no training set uses,
#: drawn inside the narrow ranges and inside the defaults (the dataset spec's values)
RANGE_TESTS = {"inside_narrow_ranges": {"cases": [3], "seed": 6, "replicates": 16,
                                          "nuisance": NARROW_RANGES},
               "inside_default_ranges": {"cases": [3], "seed": 6, "replicates": 16}}


def narrow_ranges(root: Path, out: Path, extra: list[str], seeds: int) -> pd.DataFrame:
    """What training over the default nuisance ranges costs on gearboxes inside narrow ones
    (:data:`NARROW_RANGES`), and what it buys on gearboxes of the defaults: per training seed, a
    case-3 network per training ranges of :data:`RANGE_VARIANTS` (each but the defaults its own
    dataset file; read absolutely, of root wear: ``case3_absolute``), all scored on the same
    held-out gearboxes of :data:`RANGE_TESTS` (one row per
    network, seed, test set and estimator: :func:`evaluate`'s columns)."""
    tests = {k: load_dataset(root / "data" / f"dataset_{k}.parquet", spec)
             for k, spec in RANGE_TESTS.items()}
    rows = []
    for seed, (label, ranges) in itertools.product(range(seeds), RANGE_VARIANTS.items()):
        nuisance = ",".join(f"{k}:[{lo},{hi}]" for k, (lo, hi) in ranges.items())
        overrides = [f"data.dataset={root / 'data' / f'dataset_case3_{label}.parquet'}",
                     f"+data.generate.nuisance={{{nuisance}}}"] if ranges else []
        folder = out / "models" / f"case3_{label}_seed{seed}"
        cfg = train_config(root, folder, *MODELS["case3_absolute"], *overrides, *extra,
                           f"seed={seed}")
        log.info("case 3 over the %s ranges: training (seed %d)", label, seed)
        net, _, est, typical = trained(cfg, folder)
        for test_name, test in tests.items():
            r, _ = evaluate(f"case3_{label}/{test_name}", net, est, typical, test, speed=False)
            rows += [{**row, "trained_on": label, "test": test_name, "seed": seed}
                     for row in r]
    return pd.DataFrame(rows)


def range_summary(table: pd.DataFrame) -> pd.DataFrame:
    """:func:`narrow_ranges`' networks per training ranges and test set, over the seeds:
    mean relative error [%], R2, coverage, flagged share and share missed and not flagged
    (mean, min, max)."""
    net = table[table.estimator == "surrogate"]
    cols = ["mean_relative_error_pct", "r2", "interval_coverage", "flag_rate",
            "missed_not_flagged"]
    return net.groupby(["trained_on", "test"], sort=False)[cols].agg(
        ["mean", "min", "max"]).round(3)


def seed_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per model, test set and estimator: the seeds, the mean and largest mean relative
    error [%] and the smallest interval coverage over the training seeds."""
    return table.groupby(["scenario", "estimator"], sort=False).agg(
        seeds=("seed", "nunique"), mre_mean=("mean_relative_error_pct", "mean"),
        mre_max=("mean_relative_error_pct", "max"),
        coverage_min=("interval_coverage", "min")).round(3)


#: train.py keys each of the benchmark's studies sets itself (its case, seed, dataset, inputs
#: and target): an override of one would change what a study measures, or break it
STUDY_KEYS = ("case", "seed", "data")


def refusal(extra: list[str]) -> str | None:
    """Why the train.py overrides ``extra`` cannot train the benchmark's networks (a key of
    :data:`STUDY_KEYS`, an unknown key, a value its check refuses), None if they can: checked
    by composing and preparing the case-3 run in a temporary folder, before any dataset is
    built."""
    for override in extra:
        key = override.lstrip("+~").split("=", 1)[0].strip()
        if key.split(".", 1)[0] in STUDY_KEYS:
            return (f"{key} is set by each of the benchmark's studies (its case, seed, data and "
                    "inputs); override model.* or trainer.* keys, or train such a network with "
                    "train.py")
    with tempfile.TemporaryDirectory() as tmp:
        try:
            prepare(train_config(Path.cwd(), Path(tmp), *MODELS["case3"], *extra))
        except (HydraException, ValueError) as err:
            return " ".join(str(err).splitlines()[:2])
    return None


#: the model's curves of the rig's pair the few-label study calibrates, as a checkout holds them
#: (``python -m physics.reproduce.rig --out docs/figures`` writes them)
RIG_COMPARISON = Path("docs/figures/rig_comparison.csv")


#: the tables --real-rig-only copies into --figures
FIGURE_TABLES = ("real_rig.csv", "real_rig_stages.csv")


def copy_figures(out: Path, figures: Path | None,
                 names: tuple[str, ...] = FIGURE_TABLES) -> None:
    """Copy the real rig's tables from ``out`` into ``figures`` (``--figures``), atomically."""
    if figures is None:
        return
    figures.mkdir(parents=True, exist_ok=True)
    for name in names:
        if (out / name).is_file():
            data = (out / name).read_bytes()
            atomic_write(figures / name, lambda p, data=data: Path(p).write_bytes(data))
            print(f"-> {figures / name}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m surrogate.benchmark",
                                     description=__doc__.split("\n\n")[0],
                                     epilog="Takes about 20 minutes on 2 cores once the "
                                            "case-3, all-case, shifted, beyond-range, dry-law, "
                                            "model-form-off and new-gearbox datasets are in "
                                            "data/ (the "
                                            "first run generates them): 27 trainings on the "
                                            "physics, 18 on the fleet's labelled gearboxes, 20 "
                                            "on draws of them and 34 on the one-rig table.")
    parser.add_argument("--out", type=Path, default=None,
                        help="output folder (default: logs/benchmark/<time>)")
    parser.add_argument("--seeds", type=int, default=5,
                        help="training seeds of the main job (case 3) and the all-case "
                             "network, both read against each gearbox's first record, and of "
                             "the case-3 absolute ones of root and mean wear (their split and "
                             "start; default 5); the other models train with seed 0")
    parser.add_argument("--max-epochs", type=int, default=None,
                        help="cap the training epochs (quick looks; the default config's "
                             "early stopping otherwise)")
    parser.add_argument("--override", action="append", default=[], metavar="KEY=VALUE",
                        help="a train.py override for every network trained (repeatable; "
                             "e.g. model.interval=0.975; not case, seed or data.*, which each "
                             "study sets), checked before any work")
    parser.add_argument("--real-rig", type=Path, default=RIG_RECORDS, metavar="PATH",
                        help="the real rig's record table left out one stage at a time "
                             "(real_rig.csv; default the packaged copy, "
                             "physics/reference/institute_rig/rig_15rps_records.csv)")
    parser.add_argument("--real-rig-only", action="store_true",
                        help="instead: only the real rig's part (about 15 min on 2 cores)")
    parser.add_argument("--one-rig-only", action="store_true",
                        help="instead: only the one-rig part (one_rig.csv, seed 0; about "
                             "22 min on 2 cores)")
    parser.add_argument("--few-labels-only", action="store_true",
                        help="instead: only the few-label study on the real rig (the healthy "
                             "stage and 3 worn ones labelled, 200 draws; few_labels.csv, "
                             "few_labels_draws.csv; seconds): the physics model's curves of "
                             "--rig-comparison calibrated on them, beside the same calibration "
                             "without physics and a straight line (surrogate.few_labels)")
    parser.add_argument("--rig-comparison", type=Path, default=None, metavar="PATH",
                        help="the model's curves of the rig's pair, the rig_comparison.csv "
                             "written by python -m physics.reproduce.rig (default: "
                             f"{RIG_COMPARISON}, in a checkout of the repository)")
    parser.add_argument("--figures", type=Path, default=None, metavar="DIR",
                        help="with --real-rig-only, --one-rig-only or --few-labels-only: "
                             "also copy the tables "
                             "it writes into DIR (docs/figures: the tables docs/benchmark.md "
                             "quotes, checked by tests/surrogate/test_doc_figures.py)")
    parser.add_argument("--overwrite", action="store_true",
                        help="let the run replace the files an earlier run (or you) left in "
                             "--out or --figures DIR (refused otherwise, before any work)")
    parser.add_argument("--narrow-ranges", action="store_true",
                        help="instead: case-3 networks of the default nuisance ranges, of "
                             "narrow ones (NARROW_RANGES) and of two steps between, --seeds "
                             "each, scored on held-out gearboxes inside the narrow and the "
                             "default ranges (narrow_ranges.csv)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    out = args.out or Path("logs/benchmark") / datetime.now().strftime("%Y-%m-%d_%H-%M-%S")
    if args.seeds < 1:
        parser.error(f"--seeds {args.seeds}: give at least 1")
    only = [f for f, on in (("--real-rig-only", args.real_rig_only),
                            ("--one-rig-only", args.one_rig_only),
                            ("--few-labels-only", args.few_labels_only),
                            ("--narrow-ranges", args.narrow_ranges)) if on]
    if len(only) > 1:
        parser.error(f"{' '.join(only)}: each runs one part instead of the whole benchmark; "
                     "give one of them")
    if args.rig_comparison is not None and not args.few_labels_only:
        parser.error(f"--rig-comparison {args.rig_comparison}: is read by --few-labels-only "
                     "alone; add it, or leave --rig-comparison out")
    for key, folder in (("--out", out), ("--figures", args.figures)):
        try:
            if folder is not None:
                check_writable(folder, key)
        except ValueError as err:
            parser.error(str(err))
    if args.figures is not None and not (args.real_rig_only or args.one_rig_only
                                         or args.few_labels_only):
        parser.error(f"--figures {args.figures}: copies the tables of --real-rig-only, "
                     "--one-rig-only or --few-labels-only; add one of them")
    copied = (("few_labels.csv",) if args.few_labels_only else ("one_rig.csv",)
              if args.one_rig_only else FIGURE_TABLES)
    try:
        check_fresh(out, "--out", ("*",), args.overwrite, "add --overwrite")
        if args.figures is not None:
            check_fresh(args.figures, "--figures", copied, args.overwrite, "add --overwrite")
    except ValueError as err:
        parser.error(str(err))
    given = {**({f"--max-epochs {args.max_epochs}": f"trainer.max_epochs={args.max_epochs}"}
                 if args.max_epochs else {}),
             **{f"--override {o}": o for o in args.override}}
    extra = list(given.values())
    try:
        existing_file(args.real_rig, "--real-rig", "give the rig's record table (a .csv)")
    except ValueError as err:
        parser.error(str(err))
    refused = refusal(extra)
    if refused:
        parser.error(f"{' '.join(given)}: {refused}")
    if args.few_labels_only:
        comparison = args.rig_comparison or RIG_COMPARISON
        out = out.resolve()
        written = [out / "few_labels.csv", out / "few_labels_draws.csv",
                   *([args.figures / "few_labels.csv"] if args.figures is not None else [])]
        for target in written:
            for key, given in (("--rig-comparison", comparison), ("--real-rig", args.real_rig)):
                if target.is_file() and Path(given).is_file() and os.path.samefile(target,
                                                                                     given):
                    parser.error(f"{key} {given} is a file this run writes ({target}): it "
                                 "would replace what it reads; give another --out or "
                                 "--figures folder")
        try:
            records = read_csv_table(args.real_rig, "--real-rig", "give the rig's record "
                                     "table (stage, wear_mm, acc_rms_g)",
                                     columns=few_labels.RECORD_COLUMNS,
                                     numeric=few_labels.RECORD_COLUMNS[1:])
            curves = read_csv_table(comparison, "--rig-comparison",
                                    "give the rig_comparison.csv of python -m "
                                    "physics.reproduce.rig", columns=("wear_mm",))
            check_unrepeated(comparison, f"--rig-comparison {comparison}")
            few_labels.check_comparison(curves, records, f"--rig-comparison {comparison}")
            table = few_labels.summary(draws := few_labels.few_label_study(records, curves))
        except ValueError as err:
            parser.error(str(err))
        out.mkdir(parents=True, exist_ok=True)
        atomic_write(out / "few_labels.csv", lambda p: table.to_csv(p, index=False))
        atomic_write(out / "few_labels_draws.csv", lambda p: draws.to_csv(p, index=False))
        copy_figures(out, args.figures, ("few_labels.csv",))
        print(table.to_string(index=False))
        print(f"\n-> {out / 'few_labels.csv'}, {out / 'few_labels_draws.csv'}")
        return
    if args.real_rig_only:
        summary = real_rig(Path.cwd(), out.resolve(), extra, args.real_rig)
        copy_figures(out.resolve(), args.figures)
        print(summary.to_string(index=False))
        print(f"\n-> {out / 'real_rig.csv'}, {out / 'real_rig_stages.csv'}")
        return
    if args.one_rig_only:
        rig = pd.DataFrame(one_rig(Path.cwd(), out.resolve(), extra))
        atomic_write(out.resolve() / "one_rig.csv", lambda p: rig.to_csv(p, index=False))
        copy_figures(out.resolve(), args.figures, ("one_rig.csv",))
        with pd.option_context("display.width", 200, "display.float_format", "{:.4g}".format):
            print(rig.to_string(index=False))
        print(f"\n-> {out / 'one_rig.csv'}")
        return
    if args.narrow_ranges:
        table = narrow_ranges(Path.cwd(), out.resolve(), extra, args.seeds)
        atomic_write(out.resolve() / "narrow_ranges.csv",
                     lambda p: table.to_csv(p, index=False))
        with pd.option_context("display.width", 200, "display.float_format", "{:.4g}".format):
            print(range_summary(table).to_string())
        print(f"\n-> {out / 'narrow_ranges.csv'}")
        return
    table, counts = run(out.resolve(), Path.cwd(), extra, args.seeds, args.real_rig)
    rig = pd.read_csv(out.resolve() / "one_rig.csv")
    cols = ["scenario", "estimator", "seed", "rmse", "r2", "mean_relative_error_pct",
            "max_relative_error_pct", "interval_coverage", "flag_rate", "missed_not_flagged",
            "unworn_reading", "referenced_mre_pct", "rows_per_s", "latency_us"]
    with pd.option_context("display.width", 200, "display.float_format", "{:.4g}".format):
        print(table[[c for c in cols if c in table.columns]].to_string(index=False))
        print("\nover the training seeds:")
        print(seed_summary(table).to_string())
        print("\nlabelled gearboxes of the independent simulator, over the draws:")
        print(counts.drop(columns=["draw", "heldout_rows"]).groupby("labelled_gearboxes").agg(
            ["mean", "min", "max"]).to_string())
        print("\none rig of the independent simulator (a user's table, acc_rms and "
              "dte_peak_to_peak):")
        print(rig.to_string(index=False))
    print(f"\n-> {out / 'benchmark.csv'}, {out / 'labelled_counts.csv'}, {out / 'summary.png'}, "
          f"{out / 'parity'}/")


if __name__ == "__main__":
    from physics import interrupt

    interrupt.note(lambda: "the datasets built so far are kept in data/ and reused; the "
                           "benchmark's tables are written at its end: run it again")
    interrupt.guard(main)
