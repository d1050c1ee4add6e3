"""``train(cfg)``: fit the wear surrogate, test it, export it, and return the optimised metric."""

from __future__ import annotations

import copy
import itertools
import json
import logging
import math
import os
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import lightning as L
import numpy as np
import pandas as pd
import torch
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from physics import interrupt
from physics.estimators.empirical_inverse import wear_errors
from physics.files import atomic_write, pyplot
from surrogate import baselines, candidates, fine_tune, settings
from surrogate.conformal import attainable
from surrogate.data import WearDataModule
from surrogate.figures import add_baselines, parity_figure
from surrogate.inference import Chosen, Surrogate, conformal_scale, export, export_chosen
from surrogate.novelty import LEVEL as NOVELTY_LEVEL
from surrogate.novelty import Novelty, envelope_report
from surrogate.schema import FeatureSchema, network_frame
from surrogate.splits import MIN_APART, calibration_split, gearboxes, split_table

log = logging.getLogger(__name__)
# lightning 2.6 calls a torch pytree API that torch 2.13 deprecates; harmless, and once per step
warnings.filterwarnings("ignore", message=r".*LeafSpec.*is deprecated")


class _NoAdvert(logging.Filter):
    """Drops the tip Lightning logs on every Trainer to advertise its cloud logger."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "litlogger" not in record.getMessage()


def quiet_lightning() -> None:
    """Each Lightning log line once, and no advertisement.

    ``import lightning`` gives the ``lightning`` logger a console handler of its own, and its
    records also reach the root logger's handlers (Hydra's console and log file): every line
    printed twice. Where the root logger has handlers (an app run by Hydra), Lightning's own is
    removed so that the root's print each line once, in the app's format; elsewhere (a script
    without logging set up) it stays. Called when a run is prepared, after Hydra set up logging.
    """
    rank_zero = logging.getLogger("lightning.pytorch.utilities.rank_zero")
    if not any(isinstance(f, _NoAdvert) for f in rank_zero.filters):
        rank_zero.addFilter(_NoAdvert())
    if logging.getLogger().handlers:
        own = logging.getLogger("lightning")
        for handler in list(own.handlers):
            own.removeHandler(handler)


@dataclass(frozen=True)
class TrainJob:
    """A checked training run: everything instantiated that needs no data."""

    cfg: DictConfig
    data: WearDataModule
    trainer: L.Trainer
    out: Path
    init: Surrogate | None = None  # the network to fine-tune (``init_from``)


def prepare(cfg: DictConfig) -> TrainJob:
    """Check the whole run before any work: case, model settings, trainer, callbacks, loggers
    and the data module (whose dataset, if missing, is planned and checked but not built)."""
    quiet_lightning()
    settings.check_run(cfg)
    trainer = make_trainer(cfg)
    init = fine_tune.network(cfg)
    fine_tune.check_honoured(cfg, init)
    data = settings.instantiated(cfg.data if init is None else fine_tune.read_as(cfg.data, init),
                                 "data")
    if init is None and cfg.model.get("trainable", "all") != "all":
        raise ValueError(f"model.trainable = {cfg.model.trainable!r} trains the output layers of "
                         "a pre-trained network and needs init_from=<run>/wear_surrogate.pt; "
                         "to train from scratch leave model.trainable at 'all'")
    if init is not None and list(init.schema.inputs) != data.inputs:
        raise ValueError(f"init_from = {cfg.init_from}: that network takes "
                         f"{list(init.schema.inputs)}, this run's data gives {data.inputs}; "
                         "leave data.inputs unset (a fine-tune reads the network's inputs) "
                         "or give those columns")
    if init is not None and init.schema.target != data.target:
        raise ValueError(f"init_from = {cfg.init_from}: that network reads "
                         f"{init.schema.target}, this run's data.target is {data.target}; "
                         "leave data.target unset, or map your wear column onto "
                         f"{init.schema.target} (+data.columns.<yours>={init.schema.target})")
    if init is not None:
        theirs = dict(zip(init.schema.inputs, init.schema.units, strict=True))
        other = {c: (theirs[c], data.units[c]) for c in data.inputs if theirs[c] != data.units[c]}
        if other:
            raise ValueError(f"init_from = {cfg.init_from}: that network takes "
                             + ", ".join(f"{c} in {a}" for c, (a, _) in other.items())
                             + "; this run's data gives "
                             + ", ".join(f"{c} in {b}" for c, (_, b) in other.items())
                             + ": convert the column(s) or train from scratch")
    if init is not None and tuple(init.schema.vectors) != data.vectors:
        raise ValueError(f"init_from = {cfg.init_from}: that network reads "
                         f"{list(init.schema.vectors) or 'no'} inputs as complex lines (their "
                         f"_re and _im columns), this run's data "
                         f"{list(data.vectors) or 'none'}; give the table the same columns")
    if init is not None and tuple(init.schema.baseline) != data.baseline:
        raise ValueError(f"init_from = {cfg.init_from}: that network reads "
                         f"{list(init.schema.baseline) or 'no'} features against a baseline "
                         f"record, this run's data {list(data.baseline) or 'none'}; set "
                         f"data.baseline={str(bool(init.schema.baseline)).lower()}")
    kind = cfg.model.get("kind", "auto")
    if kind == "estimator":
        missing = [c for c in candidates.ESTIMATOR_INPUTS if c not in data.inputs]
        if missing:
            raise ValueError(f"model.kind = estimator reads {list(candidates.ESTIMATOR_INPUTS)} "
                             f"and a cycle count; data.inputs lack {missing}: add them, or "
                             "choose another model.kind")
    return TrainJob(cfg, data, trainer, Path(cfg.paths.output_dir), init)


class InterruptBetweenBatches(L.Callback):
    """Raises a Ctrl-C or SIGTERM that came while Lightning ran (:func:`physics.interrupt.deferred`)
    at the next batch or epoch boundary, where its graceful shutdown (the loggers' closing, the
    checkpoints) finds no operation cut in half."""

    def on_train_batch_end(self, *args, **kwargs) -> None:
        interrupt.check()

    def on_validation_batch_end(self, *args, **kwargs) -> None:
        interrupt.check()

    def on_test_batch_end(self, *args, **kwargs) -> None:
        interrupt.check()

    def on_train_epoch_start(self, *args, **kwargs) -> None:
        interrupt.check()


def make_trainer(cfg: DictConfig) -> L.Trainer:
    """The Lightning trainer of ``cfg`` with its callbacks and loggers (into
    ``cfg.paths.output_dir``)."""
    callbacks = [settings.instantiated(c, "callbacks")
                 for c in (cfg.get("callbacks") or {}).values()]
    callbacks.append(InterruptBetweenBatches())
    loggers = [settings.instantiated(c, "logger") for c in (cfg.get("logger") or {}).values()]
    return settings.instantiated(cfg.trainer, "trainer", callbacks=callbacks,
                                 logger=loggers or False)


def train(cfg: DictConfig) -> float:
    """Check ``cfg`` and train (:func:`prepare`, :func:`fit`)."""
    return fit(prepare(cfg))


def fit(job: TrainJob) -> float:
    """Train; write checkpoint, exported model, metrics, predictions and parity plot to the run
    folder; return ``cfg.optimized_metric``. With ``data.cv=logo``, one such run per fold
    (:func:`cross_validate`)."""
    if job.data.cv:
        return cross_validate(job)
    metrics = fit_metrics(job)
    value = metrics[job.cfg.optimized_metric]
    return float(value) if math.isfinite(value) else float("inf")


def fit_metrics(job: TrainJob) -> dict:
    """:func:`fit`'s run; returns its metrics (``metrics.json``)."""
    cfg, dm, trainer, out = job.cfg, job.data, job.trainer, job.out
    L.seed_everything(cfg.seed, workers=True)
    if cfg.get("threads"):
        torch.set_num_threads(int(cfg.threads))
    start = time.perf_counter()
    dm.setup()  # the dataset read, or built where missing
    data_s = time.perf_counter() - start
    if job.init is None:
        model = new_network(cfg, dm)
    else:  # fine-tune: the pre-trained network, its input scaling and its architecture
        dm.schema = job.init.schema
        shape = {k: job.init.model.hparams[k] for k in ("width", "depth", "members")}
        model = new_network(cfg, dm, **shape)
        model.load_state_dict(job.init.model.state_dict())
    log.info("split%s: %s", f" (fold {dm.group_by} = {dm.fold_label})"
             if dm.fold_label is not None else "", dm.split_summary())
    envelope = job_envelope(job, dm)  # said before training, kept in metrics.json
    try:
        return _fit_and_export(job, dm, trainer, model, out, envelope, data_s)
    except Exception:
        set_aside_checkpoints(out)
        raise


def new_network(cfg: DictConfig, dm: WearDataModule, **shape):
    """The untrained network of ``cfg.model`` for ``dm``'s inputs (the keys that choose the
    model, ``model.kind`` and ``model.folds``, are not the network's)."""
    node = OmegaConf.create({k: v for k, v in OmegaConf.to_container(cfg.model).items()
                             if k not in settings.ModelConfig.CHOICE_KEYS})
    return instantiate(node, n_inputs=len(dm.inputs), schema=dm.schema.to_dict(),
                       _convert_="all", **shape)


def train_network(trainer: L.Trainer, model, dm: WearDataModule) -> tuple[dict, dict]:
    """Train ``model`` on ``dm`` and keep its best epoch's weights; its validation and test
    figures (Lightning's)."""
    with interrupt.deferred():  # a signal is raised between batches (InterruptBetweenBatches)
        trainer.fit(model, dm)
        if trainer.interrupted:
            raise KeyboardInterrupt
        has_best = any(getattr(c, "best_model_path", "") for c in trainer.callbacks)
        ckpt = "best" if has_best and not trainer.fast_dev_run else None
        val = {k: float(v) for k, v in
               trainer.validate(model, dm, ckpt_path=ckpt, verbose=False)[0].items()}
        test = ({k: float(v) for k, v in
                 trainer.test(model, dm, ckpt_path=ckpt, verbose=False)[0].items()}
                if len(dm.frames["test"]) else {})
    return val, test


def compares(cfg: DictConfig, dm: WearDataModule) -> bool:
    """Whether the run chooses its model by cross-validation (a user's table, or a kind other
    than the network forced) rather than training the network alone (the physics dataset's
    default: its figures are the network's)."""
    return dm.table is not None or cfg.model.get("kind", "auto") not in ("auto", "network")


def _fit_and_export(job: TrainJob, dm: WearDataModule, trainer: L.Trainer, model, out: Path,
                    envelope: dict, data_s: float) -> dict:
    """Train, calibrate, choose, export and test; the metrics (``data_s``: the time [s] the
    dataset took to read or build; ``train_s``: the time of all that follows)."""
    cfg = job.cfg
    start = time.perf_counter()
    val, test = train_network(trainer, model, dm)
    scale, novelty = calibrate(model, dm, float(cfg.model.interval))
    choice = select(job, dm, model, out) if compares(cfg, dm) else None
    # the exported model gets its name only at the successful end: a run that fails on the
    # way leaves no wear_surrogate.pt that a later command would take for a finished one
    path, staged = out / "wear_surrogate.pt", out / ".wear_surrogate.pt.staged"
    try:
        export(model, staged, scale, novelty)
        network = Surrogate.load(staged)
        surrogate, chosen = network, {}
        if choice is not None and choice.chosen is not None:  # another model than the network
            os.replace(staged, out / "network_surrogate.pt")
            export_chosen(choice.chosen, staged, novelty)
            surrogate = Surrogate.load(staged)
        if choice is not None:
            chosen = {"model_kind": choice.kind, "model_choice": choice.reason,
                      **{f"cv_{k}_group_mre_pct": c.error for k, c in choice.scored.items()}}
            log.info("model kept: %s: %s", candidates.LABELS[choice.kind], choice.reason)
        metrics = {**val, **test, "epochs": trainer.current_epoch,
                   "train_rows": len(dm.frames["train"]), "interval_scale": scale,
                   "interval_calibrated_apart": dm.calibration_apart,
                   "novelty_radius": novelty.radius, **envelope,
                   "model_kind": surrogate.kind, **chosen}
        if len(dm.frames["test"]):
            metrics.update(report_test(surrogate, dm, out, network, choice))
        metrics.update(data_s=data_s, train_s=time.perf_counter() - start)
        value = metrics.get(cfg.optimized_metric)
        if value is None:
            raise ValueError(f"optimized_metric = {cfg.optimized_metric!r} is not among the "
                             f"logged metrics {sorted(metrics)}")
        text = json.dumps(metrics, indent=2, sort_keys=True)
        atomic_write(out / "metrics.json", lambda p: p.write_text(text + "\n"))
        atomic_write(out / "config.yaml", lambda p: p.write_text(OmegaConf.to_yaml(cfg)))
        os.replace(staged, path)
    except BaseException:
        staged.unlink(missing_ok=True)
        raise
    log.info("model: %s; metrics: %s", path, text)
    return metrics


@dataclass
class Choice:
    """The model a run keeps (:func:`select`): its kind and why, every kind's
    cross-validation over the training groups, the kept model where it is not the network,
    and each non-network kind fitted on all training groups (for the test report)."""

    kind: str
    reason: str
    scored: dict[str, candidates.CrossValidated]
    chosen: Chosen | None = None
    fitted: dict[str, candidates.Candidate] = field(default_factory=dict)
    chosen_y: np.ndarray | None = None  # the training groups' wear and groups (CV+)
    groups: np.ndarray | None = None


def training_pool(dm: WearDataModule) -> pd.DataFrame:
    """Every row that is not a test row (training, validation and calibration groups): what
    the candidates train on and what their cross-validation splits."""
    parts = ["train", "val", "cal"] if dm.calibration_apart else ["train", "val"]
    return pd.concat([dm.frames[k] for k in parts], ignore_index=True)


def select(job: TrainJob, dm: WearDataModule, network, out: Path) -> Choice:
    """Choose the model by grouped cross-validation over the training groups only
    (:func:`training_pool`; the test groups never enter): each non-network kind of
    :mod:`surrogate.candidates` that applies and, with ``model.kind=auto`` on a user's table,
    the network (one training per fold, in ``selection/`` of the run folder). Keeps the least
    error (or ``model.kind``); the kept non-network model is fitted on all training groups,
    with its fold models and out-of-fold residuals for the CV+ interval."""
    cfg = job.cfg
    kind = cfg.model.get("kind", "auto")
    pool = training_pool(dm)
    rows = network_frame(pool, dm.inputs, dm.baseline, dm.vectors, ["case", "replicate"])
    raw = rows[dm.inputs].to_numpy(float)
    x, y, groups = dm.schema.scale(raw), rows[dm.target].to_numpy(float), gearboxes(pool)
    folds = candidates.group_folds(groups, int(cfg.model.get("folds", candidates.FOLDS)))
    why = candidates.applicable(dm.inputs, pool)
    kinds = [k for k in candidates.KINDS[1:] if k not in why and k != "average"]
    scored = {k: candidates.cross_validate(k, x, y, groups, folds, pool, dm.inputs, raw)
              for k in kinds}
    scored = insert_average(scored, candidates.averaged(scored, y, groups))
    if kind == "auto" and dm.table is not None:
        log.info("cross-validating the network over %d folds of the %d training groups",
                 len(folds), np.unique(groups).size)
        scored["network"] = candidates.cross_validate(
            "network", x, y, groups, folds, network=inner_network(job, dm, pool, out))
    kept, reason = candidates.choose(scored, None if kind == "auto" else kind)
    if why:
        reason += "; not compared: " + "; ".join(f"{candidates.LABELS[k]} ({w})"
                                                  for k, w in why.items())
    fitted = {k: candidates.Candidate.fit(k, x, y, groups, pool, dm.inputs, raw) for k in kinds}
    fitted = insert_average(fitted, candidates.Candidate.average(
        [fitted[k] for k in candidates.AVERAGED]))
    chosen = None
    if kept != "network":
        cv = scored[kept]
        chosen = Chosen(dm.schema, fitted[kept], cv.fold_models, cv.fold_of,
                        np.abs(y - cv.oof), groups, float(cfg.model.interval), reason)
    return Choice(kept, reason, scored, chosen, fitted, y, groups)


def insert_average(by_kind: dict, average) -> dict:
    """``by_kind`` (kind -> a candidate's figures or model) with the ``average`` in the
    place :data:`surrogate.candidates.KINDS` gives it."""
    by_kind = {**by_kind, "average": average}
    return {k: by_kind[k] for k in sorted(by_kind, key=candidates.KINDS.index)}


def inner_network(job: TrainJob, dm: WearDataModule, pool: pd.DataFrame, out: Path):
    """The network's reading of a cross-validation fold's held rows of ``pool``, trained on
    its other rows (validation groups drawn from them as the run draws its own) into
    ``selection/network_fold<k>/``: a function of (training row indices, held row indices)."""
    count = itertools.count()

    def read(fit_rows: np.ndarray, held: np.ndarray) -> np.ndarray:
        k = next(count)
        fit = pool.iloc[fit_rows].reset_index(drop=True)
        parts = split_table(fit, None, None, dm.val_replicates, 0, dm.seed, dm.describe)
        parts["test"] = pool.iloc[held].reset_index(drop=True)
        inner = copy.copy(dm)
        inner.cv, inner.folds = None, []
        inner.frames = calibration_split(parts, dm.seed)
        inner.schema = FeatureSchema.fit(inner.network_rows("train"), dm.inputs, dm.units,
                                         dm.target, dm.baseline, dm.vectors,
                                         tuple(dm.operating))
        fold_cfg = copy.deepcopy(job.cfg)
        fold_cfg.paths.output_dir = str(out / "selection" / f"network_fold{k}")
        L.seed_everything(job.cfg.seed, workers=True)
        net = new_network(fold_cfg, inner)
        train_network(make_trainer(fold_cfg), net, inner)
        x = inner.network_rows("test")[dm.inputs].to_numpy(float)
        return np.maximum(Surrogate(net, 1.0).predict_array(x)[0], 0.0)

    return read


def calibrate(model, dm: WearDataModule, level: float) -> tuple[float, Novelty]:
    """The novelty, its radius set on the validation and calibration rows (inputs only: they
    chose nothing by their inputs), and the interval's conformal scale at ``level`` from the
    calibration rows (:func:`~surrogate.splits.calibration_split`); in both each gearbox
    (trajectory) is one exchangeable unit (:mod:`surrogate.conformal`), and the rows are the
    readings, not the baseline records of a model read against them. Says in the log where
    the calibration rows also chose the epoch."""
    held = {}
    for part in ("val", "cal") if dm.calibration_apart else ("cal",):
        rows = dm.network_rows(part)
        held[part] = rows[dm.schema.readings(rows, ["case", "replicate"])]
    if not dm.calibration_apart:
        log.info("the interval is calibrated on the validation trajectories that also chose the "
                 "epoch (fewer than %d): its coverage of new gearboxes may fall short of its "
                 "level", MIN_APART)
    train_rows, all_held, cal = dm.network_rows("train"), pd.concat(held.values()), held["cal"]
    of_held, of_cal = gearboxes(all_held), gearboxes(cal)
    for what, labels, at in (("the interval", of_cal, level),
                             ("the novelty flag", of_held, NOVELTY_LEVEL)):
        units = np.unique(labels).size
        if units and not attainable(at, units):
            log.info("%d held-out gearboxes cannot give %s a %.3g level (at most %.3g): it takes "
                     "their largest score; more validation trajectories (data.val_replicates) "
                     "give the level", units, what, at, units / (units + 1))
    novelty = Novelty.fit(dm.schema.scale(train_rows[dm.inputs].to_numpy(float)),
                          dm.schema.scale(all_held[dm.inputs].to_numpy(float)),
                          train_rows[dm.target].to_numpy(float), groups=of_held)
    x_cal = cal[dm.inputs].to_numpy(float)
    calibrating = Surrogate(model, 1.0, novelty)
    mean, std = calibrating.predict_array(x_cal)
    sigma = calibrating.difficulty(std, calibrating.novelty_score(x_cal))
    return conformal_scale(mean, sigma, cal[dm.target].to_numpy(float), level,
                           groups=of_cal), novelty


def job_envelope(job: TrainJob, dm: WearDataModule) -> dict:
    """For a fine-tune (``init_from``): how far this run's training rows, inputs and wear, lie
    from the data the network to fine-tune was trained on (its novelty, its target range,
    :func:`~surrogate.novelty.envelope_report`); one line in the log where they lie outside
    it, and the figures (``init_*``) for ``metrics.json``. Nothing for a run from scratch."""
    init = job.init
    if init is None or init.novelty is None:
        return {}
    rows = dm.network_rows("train")
    _, flagged = init.flags(rows[list(init.schema.inputs)].to_numpy(float))
    figures, line = envelope_report(flagged, init.novelty,
                                    rows[dm.target].to_numpy(float), "training rows",
                                    init.schema.target_unit)
    if line:
        log.warning("init_from = %s was trained on other data: %s", job.cfg.init_from, line)
    return {f"init_{k}": v for k, v in figures.items()}


def set_aside_checkpoints(out: Path) -> None:
    """After a run failed past its start: its Lightning checkpoints, and those of the model
    choice's network folds (``selection/*/checkpoints``), renamed to ``checkpoints.failed``
    (kept, not deleted, but no ``best.ckpt`` under the usual name)."""
    from physics.files import set_aside

    folders = [f for f in (out / "checkpoints", *sorted(out.glob("selection/*/checkpoints")))
               if f.is_dir()]
    if folders:
        aside = [set_aside(f, ".failed") for f in folders]
        log.warning("the run failed after training started; its checkpoints are set aside as "
                    "%s and nothing is exported", ", ".join(map(str, aside)))


def kept(job: TrainJob) -> str:
    """What an interrupted training kept: while its dataset was being built, the dataset's
    finished chunks; while it trained, its checkpoints (if any were written yet)."""
    ckpts = job.out / "checkpoints"
    if ckpts.is_dir() and any(ckpts.glob("*.ckpt")):
        return (f"the checkpoints so far are in {ckpts}; the run is not exported: run the "
                "command again to train")
    dm = job.data
    if dm.table is None and not Path(dm.dataset).is_file():
        from physics.dataset.generation import chunks_kept
        from surrogate.wear_data import dataset_job

        return (f"no training was done; of the dataset {dm.dataset}, "
                f"{chunks_kept(dataset_job(dm.dataset, dm.generate, dm.jobs))}")
    return "no model was exported and no checkpoint written; run the command again to train"


def report_test(surrogate: Surrogate, dm: WearDataModule, out: Path,
                network: Surrogate | None = None, choice: Choice | None = None) -> dict:
    """Held-out errors in physical units and interval coverage of the model kept
    (``surrogate``: the network, or the model :func:`select` chose), and beside it, on the same
    rows and target, those of every other model (:mod:`surrogate.baselines`): the network,
    the linear and monotone models and their average (fitted on all training groups where
    the run chose by cross-validation, else on the training rows), the thesis's estimator
    where its inputs exist and the median (null) model, and each one's interval coverage
    where it has one (``test_<kind>_interval_coverage``: the network's split-conformal
    interval, the CV+ of the kinds cross-validated). Writes ``test_predictions.csv`` (a user
    table's own columns, else case, replicate and cycles; the true and predicted wear of
    every model) and ``parity.png``; logs the figures, and one line where the network is not
    better than the linear model."""
    test, t, keys = dm.frames["test"], surrogate.schema.target, ["case", "replicate"]
    have = [c for c in surrogate.schema.checked_columns if c in test.columns]
    columns = list(dict.fromkeys([*have, *keys]))
    pred = surrogate.predict(test[columns], gearbox=keys)
    schema = surrogate.schema
    raw_test = dm.network_rows("test")[list(schema.inputs)].to_numpy(float)
    readings, why = baselines.baseline_readings(dm.frames["train"], test, t)
    if choice is not None:
        fitted = choice.fitted
    else:
        train = dm.network_rows("train")
        raw_train = train[list(schema.inputs)].to_numpy(float)
        x = schema.scale(raw_train)
        y, groups = train[t].to_numpy(float), gearboxes(dm.frames["train"])
        fitted = {k: candidates.Candidate.fit(k, x, y, groups, inputs=list(schema.inputs),
                                              raw=raw_train) for k in candidates.AVERAGED}
        fitted["average"] = candidates.Candidate.average(list(fitted.values()))
    readings.update({k: m.predict(schema.scale(raw_test), raw_test) for k, m in fitted.items()})
    cover = {}
    if choice is not None:  # each other candidate's CV+ interval over the same groups
        t_true = test[t].to_numpy(float)
        for k, cv in choice.scored.items():
            if cv.fold_models is None:
                continue
            if k == surrogate.kind:  # the kept model's own interval is this one
                cover[f"test_{k}_interval_coverage"] = surrogate.coverage(pred, test, keys)
                continue
            lo, hi = Surrogate(None, 1.0, None, Chosen(
                schema, fitted[k], cv.fold_models, cv.fold_of,
                np.abs(choice.chosen_y - cv.oof), choice.groups,
                float(dm_level(dm, surrogate)))).bounds(raw_test, None, None, None)
            inside = (t_true >= np.maximum(lo, 0)) & (t_true <= np.maximum(hi, 0))
            cover[f"test_{k}_interval_coverage"] = float(
                inside[surrogate.schema.readings(test, keys)].mean())
    if network is not None and surrogate is not network:
        net_pred = network.predict(test[columns], gearbox=keys)
        readings["network"] = net_pred[f"{t}_pred"].to_numpy()
        cover["test_network_interval_coverage"] = network.coverage(net_pred, test, keys)
    readings = {k: readings[k] for k in baselines.NAMES if k in readings}
    ids = (test[["case", "replicate", "cycles"]].reset_index(drop=True) if dm.labels is None
           else dm.labels.iloc[test.row.to_numpy()].reset_index(drop=True))
    ids = ids.drop(columns=[c for c in ids.columns if c == t or c in pred.columns])
    rows = pd.concat([ids, test[[t]].reset_index(drop=True), pred.reset_index(drop=True),
                      pd.DataFrame({f"{t}_{k}": v for k, v in readings.items()})], axis=1)
    atomic_write(out / "test_predictions.csv", lambda p: rows.to_csv(p, index=False))
    true = rows[t].to_numpy()
    errors = wear_errors(rows[f"{t}_pred"], true)
    others = baselines.scored(readings, true)
    inside = surrogate.coverage(pred, test, keys)
    key, _ = baselines.headline(errors)
    kept = surrogate.kind
    figures = {kept: errors, **others}
    text = "; ".join(f"{baselines.LABELS[k]}{' (kept)' if k == kept else ''} "
                     f"{baselines.shown(key, e[key])}" for k, e in figures.items())
    title = (f"held-out rows ({len(rows)}), {key.replace('_pct', ' [%]').replace('_', ' ')}: "
             f"{text}; kept R2 {errors['r2']:.3f}, coverage {inside:.2f}")
    log.info("%s%s", title, "" if why is None else f" (no thesis estimator: {why})")
    net_errors = others.get("network", errors if kept == "network" else None)
    verdict = (baselines.not_better_line(net_errors, figures["linear"])
               if net_errors is not None and "linear" in figures else None)
    if verdict:
        log.warning(verdict + ("" if kept == "network" else
                               f"; the run keeps the {baselines.LABELS[kept]}"))
    flagged = rows.out_of_range.to_numpy()
    readings_of = surrogate.schema.readings(test, keys)
    missed = ~((true >= rows[f"{t}_lower"].to_numpy()) & (true <= rows[f"{t}_upper"].to_numpy()))
    envelope, line = envelope_report(flagged, surrogate.novelty, true, "test rows",
                                     surrogate.schema.target_unit)
    if line:
        log.warning(line)
    reading = rows[f"{t}_pred"].to_numpy()  # the bars: the interval as predicted (novelty too)
    # a CV+ interval need not contain the full model's reading: bars clipped at it
    fig = parity_figure(true, reading, np.maximum(np.stack(
        [reading - rows[f"{t}_lower"].to_numpy(), rows[f"{t}_upper"].to_numpy() - reading]), 0),
                        title, t, name=baselines.LABELS[kept])
    add_baselines(fig.axes[0], true, readings)
    atomic_write(out / "parity.png", lambda p: fig.savefig(p, dpi=120, format="png"))
    pyplot().close(fig)
    return {**{f"test_{k}": v for k, v in errors.items()},
            **{f"test_{b}_{k}": v for b, e in figures.items() for k, v in e.items()},
            "test_network_better_than_linear": verdict is None,
            "test_interval_coverage": inside,
            **{f"test_{k}": v for k, v in envelope.items()},
            "test_missed_not_flagged_share": float(np.mean((missed & ~flagged)[readings_of])),
            **cover}


def dm_level(dm: WearDataModule, surrogate: Surrogate) -> float:
    """The interval's level of ``surrogate`` (a chosen model's own; the network's 0.95
    unless configured otherwise, read from its hyperparameters)."""
    if surrogate.chosen is not None:
        return surrogate.chosen.level
    return float(surrogate.model.hparams.get("interval", 0.95))


def cross_validate(job: TrainJob) -> float:
    """``data.cv=logo``: one run per value of ``data.group_by`` left out (its rows test, the
    rest train and validate), each in ``fold_<value>/`` of the run folder as a run of its own.
    Each fold chooses its model by cross-validation over its own training groups
    (:func:`select`). Writes ``cv.csv`` (one row per fold: its group, its test rows, the kind
    kept and its errors, every model's errors beside), ``metrics.json`` (each figure's mean
    over the folds, and how often each kind was kept),
    ``test_predictions.csv`` (every fold's held-out rows) and ``parity.png``; logs each fold's
    figures and the mean. Returns the mean of ``cfg.optimized_metric``."""
    cfg, dm, out = job.cfg, job.data, job.out
    by = dm.group_by
    rows, preds = [], []
    for k in dm.folds:
        fold = dm.fold(k)
        folder = out / f"fold_{settings.run_name(str(fold.fold_label), '')}"
        fold_cfg = copy.deepcopy(cfg)
        fold_cfg.paths.output_dir = str(folder)
        log.info("fold %d of %d: %s = %r left out", len(rows) + 1, len(dm.folds), by,
                 fold.fold_label)
        metrics = fit_metrics(TrainJob(fold_cfg, fold, make_trainer(fold_cfg), folder,
                                       job.init))
        rows.append({by: fold.fold_label, "test_rows": len(fold.frames["test"]), **metrics})
        preds.append(pd.read_csv(folder / "test_predictions.csv"))
    table = pd.DataFrame(rows)
    first = [by, "test_rows", "model_kind",
             *(f"test_{p}{k}" for k in ("mean_relative_error_pct", "rmse", "r2")
               for p in ("", *(f"{n}_" for n in baselines.NAMES))),
             "test_interval_coverage"]
    table = table[[c for c in first if c in table.columns]
                  + [c for c in table.columns if c not in first]]
    atomic_write(out / "cv.csv", lambda p: table.to_csv(p, index=False))
    means = {k: float(v) for k, v in table.drop(columns=[by]).mean(numeric_only=True).items()}
    t = dm.target
    kept = {k[len("test_"):]: v for k, v in means.items() if k.startswith("test_")}
    net = {k[len("test_network_"):]: v for k, v in means.items()
           if k.startswith("test_network_")}
    lin = {k[len("test_linear_"):]: v for k, v in means.items() if k.startswith("test_linear_")}
    key, _ = baselines.headline(kept)
    labelled = (("kept", ""), *((n, f"{n}_") for n in baselines.NAMES))
    for row in rows:
        log.info("fold %s = %r (%d test rows): %s", by, row[by], row["test_rows"], "; ".join(
            f"{baselines.LABELS[b]} {baselines.shown(key, row[f'test_{p}{key}'])}"
            for b, p in labelled
            if f"test_{p}{key}" in row and np.isfinite(row[f"test_{p}{key}"])))
    shown = "; ".join(f"{baselines.LABELS[b]} {baselines.shown(key, means[f'test_{p}{key}'])}"
                      for b, p in labelled
                      if f"test_{p}{key}" in means and np.isfinite(means[f"test_{p}{key}"]))
    log.info("leave-one-group-out over %s (%d folds), %s, mean over the folds: %s", by,
             len(rows), key.replace("_pct", " [%]").replace("_", " "), shown)
    verdict = baselines.not_better_line(net or kept, lin)
    if verdict:
        log.warning(verdict.replace("on these test rows", "over the folds' test rows (mean)"))
    means["test_network_better_than_linear"] = verdict is None
    counts = table.model_kind.value_counts().to_dict() if "model_kind" in table else {}
    log.info("models kept by the folds' own cross-validation: %s",
             ", ".join(f"{baselines.LABELS[k]} {n}" for k, n in counts.items()))
    metrics = {"cv": "logo", "group_by": by, "folds": len(rows), **means,
               **{f"folds_kept_{k}": int(n) for k, n in counts.items()}}
    text = json.dumps(metrics, indent=2, sort_keys=True)
    atomic_write(out / "metrics.json", lambda p: p.write_text(text + "\n"))
    atomic_write(out / "config.yaml", lambda p: p.write_text(OmegaConf.to_yaml(cfg)))
    everything = pd.concat(preds, ignore_index=True)
    atomic_write(out / "test_predictions.csv", lambda p: everything.to_csv(p, index=False))
    fig = parity_figure(everything[t].to_numpy(), everything[f"{t}_pred"].to_numpy(), None,
                        f"leave-one-group-out over {by}, {len(rows)} folds: {shown}", t,
                        name="model kept")
    add_baselines(fig.axes[0], everything[t].to_numpy(),
                  {b: everything[f"{t}_{b}"].to_numpy() for b in baselines.NAMES
                   if f"{t}_{b}" in everything.columns})
    atomic_write(out / "parity.png", lambda p: fig.savefig(p, dpi=120, format="png"))
    pyplot().close(fig)
    value = means.get(cfg.optimized_metric, float("nan"))
    return float(value) if math.isfinite(value) else float("inf")
