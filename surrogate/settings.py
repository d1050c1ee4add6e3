"""Structured configs of the surrogate's Hydra groups (``conf/train/data``, ``model``, ``trainer``).

Kept free of torch so that ``python train.py --help`` stays fast. :func:`register` puts them in
Hydra's ConfigStore; the YAML files name them in their defaults list and only choose values.
"""

from __future__ import annotations

import math
import numbers
import re
from dataclasses import dataclass, field
from pathlib import Path, PurePath
from typing import Any

from omegaconf import MISSING, OmegaConf

from physics.command import register_schema
from physics.files import check_inside, existing_file
from physics.params import operating_cases


@dataclass
class DataConfig:
    """Schema of ``conf/train/data/`` (the arguments of :class:`WearDataModule`)."""

    _target_: str = "surrogate.data.WearDataModule"
    dataset: str = MISSING  # the parquet dataset; built with physics.dataset if missing
    case: str = "3"  # operating case of Table 11 (1-5) or all
    #: dte, acc or both: whose Table 13 features the absolute reading takes by default
    sensors: list[str] = field(default_factory=lambda: ["dte", "acc"])
    operating_point: bool = True  # speed and torque as inputs (a user knows them)
    #: explicit input columns (a user's own table); null: the reading's default inputs: the
    #: DTE's mesh lines 1-6 when read against the baseline record, else data.sensors'
    #: Table 13 features and mesh-harmonic levels; with data.operating_point, speed and
    #: torque beside. With init_from, null inputs, target and baseline are that network's
    inputs: list[str] | None = None
    #: the wear column to read: root_wear_mm (the thesis's), or mean_wear_mm (the flank's mean
    #: depth over the path of contact; docs/surrogate.md, Method, Target); null: the mean depth
    #: when read against the baseline record, the root wear otherwise
    target: str | None = None
    #: read the features as changes since each gearbox's baseline record (its first: unworn in
    #: the physics dataset, the first row of each group in a user's table); the operating point
    #: stays as measured. Needs that record at inference (docs/surrogate.md, Method, Baseline
    #: mode). null: true on the physics dataset (the main job), false on a user's table
    baseline: bool | None = None
    # whole trajectories (case, replicate) per case, never rows of one; the validation ones
    # choose the epoch and calibrate the interval (of 16 or more, half each).
    # null: a sixth of each case's trajectories, at least 8
    val_replicates: int | None = None
    test_replicates: int = 8
    holdout_case: int | None = None  # a case number: leave that case out (test on it alone)
    batch_size: int = 64
    seed: int = 0
    generate: dict[str, Any] = field(default_factory=dict)  # DatasetSpec values if built
    #: gearboxes (trajectories) a built dataset simulates, shared by the trained cases and
    #: never fewer than 128 per case (``data.generate.replicates`` sets the count per case
    #: instead). 256 for one case: docs/surrogate.md measures 64 against 256 over seeds
    gearboxes: int = 256
    jobs: int = 2  # parallel processes when the dataset is built
    #: a user's own labelled feature table (CSV or parquet) instead of the physics dataset
    table: str | None = None
    columns: dict[str, str] = field(default_factory=dict)  # +data.columns.THEIRS=OURS
    group: str | None = None  # the table's trajectory column (one gearbox or test run)
    #: units of the table's own columns, {fme15: m/s2} (else from <table>.units.yaml beside it;
    #: our column names have the dataset's units)
    #: (a plain value, not a typed dict: so that data.units={...} replaces it on the command
    #: line; checked when the table is read)
    units: Any = None
    #: the table's column whose values the test and validation groups are named by (default:
    #: data.group); trajectories are then the pairs of its values and data.group's
    group_by: str | None = None
    test_groups: list[Any] | None = None  # values of data.group_by that test: [45]
    val_groups: list[Any] | None = None  # values of data.group_by that validate
    #: logo: leave-one-group-out cross-validation, one fold per value of data.group_by
    cv: str | None = None


@dataclass
class ModelConfig:
    """Schema of ``conf/train/model/`` (the network's settings), checked by :meth:`check`."""

    _target_: str = "surrogate.model.WearRegressor"
    width: int = 16  # units per hidden layer
    depth: int = 2
    members: int = 5  # ensemble size: the spread of the members is the epistemic uncertainty
    lr: float = 3e-3
    weight_decay: float = 1e-5
    interval: float = 0.95  # level of the predictive interval (calibrated on validation)
    # which weights train: "all", or "head" (each member's output layer only: a fine-tune on a
    # few labelled gearboxes that keeps the physics-trained features, ``init_from``)
    trainable: str = "all"
    #: which model a run keeps: auto (on a table of your own, the least error of a grouped
    #: cross-validation over the training groups among the network, a linear model, a
    #: monotone one, the average of those two and, where its inputs exist, the thesis's
    #: estimator; on the physics dataset the network), or network, linear, monotone,
    #: average, estimator (surrogate.candidates)
    kind: str = "auto"
    folds: int = 5  # GroupKFold folds of that cross-validation (at most one per group)

    #: the keys that choose the model, not the network's settings
    CHOICE_KEYS = ("kind", "folds")

    def check(self) -> None:
        """Raise ``ValueError`` naming the first setting outside its range."""
        kinds = ("auto", "network", "linear", "monotone", "average", "estimator")
        if self.kind not in kinds:
            raise ValueError(f"model.kind = {self.kind!r} must be one of {list(kinds)}")
        if isinstance(self.folds, bool) or not isinstance(self.folds, int) or self.folds < 2:
            raise ValueError(f"model.folds = {self.folds!r} must be a whole number >= 2")
        if self.trainable not in ("all", "head"):
            raise ValueError(f"model.trainable = {self.trainable!r} must be 'all' or 'head' "
                             "(the output layers only, for fine-tuning with init_from)")
        for name, lo, hi in (("width", 1, 4096), ("depth", 1, 64), ("members", 1, 256)):
            v = getattr(self, name)
            if not (isinstance(v, numbers.Integral) and not isinstance(v, bool) and lo <= v <= hi):
                raise ValueError(f"model.{name} = {v!r} must be a whole number in [{lo}, {hi}]")
        for name, lo, hi in (("lr", 0.0, 1.0), ("interval", 0.0, 1.0), ("weight_decay", 0, 1)):
            v = getattr(self, name)
            closed = name == "weight_decay"
            ok = isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)
            if not (ok and (lo <= v < hi if closed else lo < v < hi)):
                raise ValueError(f"model.{name} = {v!r} must lie in {'[' if closed else '('}"
                                 f"{lo:g}, {hi:g})")


@dataclass
class TrainerConfig:
    """Schema of ``conf/train/trainer/`` (the Lightning Trainer arguments the configs set)."""

    _target_: str = "lightning.pytorch.trainer.Trainer"
    default_root_dir: str = "${paths.output_dir}"
    accelerator: str = "cpu"
    devices: int = 1
    min_epochs: int = 20
    max_epochs: int = 600
    check_val_every_n_epoch: int = 1
    log_every_n_steps: int = 1
    deterministic: bool = True
    enable_model_summary: bool = False
    enable_progress_bar: bool = True
    fast_dev_run: bool = False  # one batch of each stage: a smoke test

    def check(self) -> None:
        """Raise ``ValueError`` for epochs or intervals out of range."""
        if self.min_epochs < 0:  # above max_epochs it gives way to max_epochs
            raise ValueError(f"trainer.min_epochs = {self.min_epochs} must be >= 0")
        for name in ("max_epochs", "devices", "check_val_every_n_epoch", "log_every_n_steps"):
            if getattr(self, name) < 1:
                raise ValueError(f"trainer.{name} = {getattr(self, name)} must be >= 1")


def cases_of(case: str | int) -> list[int]:
    """``case`` of the train config: one operating case of Table 11 (1-5) or ``all``."""
    valid = sorted(operating_cases())
    if str(case).strip() == "all":
        return valid
    if str(case).strip() in {str(c) for c in valid}:
        return [int(case)]
    raise ValueError(f"case = {case!r} is not an operating case; use one of {valid} (thesis "
                     "Table 11) or all")


def check_run(cfg: Any) -> None:
    """Raise ``ValueError`` for a train config's settings that need no data, no model and no
    Lightning to judge: the run folder's task name, the seed, the thread count, the model's and
    the trainer's settings, the operating case, a user's table that is not a table file.
    ``train.py`` checks them before its slow imports (such a refusal does not wait for them);
    :func:`surrogate.training.prepare` starts with them."""
    root = Path(str(cfg.paths.root_dir)) / "logs"
    check_inside(root / str(cfg.task_name), root, f"task_name = {cfg.task_name!r}")
    if isinstance(cfg.seed, bool) or not isinstance(cfg.seed, int) or cfg.seed < 0:
        raise ValueError(f"seed = {cfg.seed!r} must be a whole number >= 0")
    if cfg.get("threads") is not None and not (isinstance(cfg.threads, int) and cfg.threads > 0):
        raise ValueError(f"threads = {cfg.threads!r} must be a whole number >= 1 or null")
    OmegaConf.to_object(cfg.model).check()
    OmegaConf.to_object(cfg.trainer).check()
    cases_of(cfg.data.case)
    if cfg.data.get("table") is not None:
        table_file(cfg.data.table)


def instantiated(node: Any, what: str, **kwargs):
    """``node`` instantiated by Hydra (``kwargs`` override its keys), a failure to make it a
    ``ValueError`` naming ``what`` (``data: ...``): one line, without Hydra's wrapping."""
    from hydra.errors import InstantiationException
    from hydra.utils import instantiate

    try:
        return instantiate(node, **kwargs)
    except InstantiationException as err:
        raise ValueError(f"{what}: {err.__cause__ or err}") from None


def table_file(value: object) -> Path:
    """``value`` as the path of a user's table: an existing ``.csv`` or ``.parquet`` file."""
    path = existing_file(value, "data.table", "give your .csv or .parquet table")
    if path.suffix not in (".csv", ".parquet"):
        raise ValueError(f"data.table = {str(path)!r} must be an existing .csv or .parquet file")
    return path


def model_file(value: object, key: str) -> Path:
    """``value`` as the path of an existing file, for an exported model given as ``key``
    (:func:`physics.files.existing_file`): judged before torch is imported to read it."""
    return existing_file(value, key, "pass the wear_surrogate.pt of a training run "
                                     "(`python train.py` writes it in its run folder)")


def run_name(table: str | None, case) -> str:
    """The run folder's name: after a user's table (its file name without the suffix), else
    ``case<case>`` (``conf/train/hydra/default.yaml``)."""
    if not table:
        return f"case{case}"
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", PurePath(str(table)).stem).strip("._")
    return stem or "table"


def register() -> None:
    """Register the schemas (before Hydra composes a train config) and the ``run_name``
    resolver the run folder's name uses."""
    if not OmegaConf.has_resolver("run_name"):
        OmegaConf.register_new_resolver("run_name", run_name)
    register_schema("wear_schema", DataConfig, group="data")
    register_schema("ensemble_schema", ModelConfig, group="model")
    register_schema("cpu_schema", TrainerConfig, group="trainer")
