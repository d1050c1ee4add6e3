"""Structured configs of the surrogate's Hydra groups (``conf/train/data``, ``conf/train/model``).

Kept free of torch so that ``python train.py --help`` stays fast. :func:`register` puts them in
Hydra's ConfigStore; the YAML files name them in their defaults list and only choose values.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import Any

from omegaconf import MISSING

from physics.command import register_schema


@dataclass
class DataConfig:
    """Schema of ``conf/train/data/`` (the arguments of :class:`WearDataModule`)."""

    _target_: str = "surrogate.data.WearDataModule"
    dataset: str = MISSING  # the parquet dataset; built with physics.dataset if missing
    case: str = "3"  # operating case of Table 11 (1-5) or all
    inputs: list[str] | None = None  # null: the Table 13 features of the DTE and acceleration
    conditions: bool | None = None  # speed and torque as inputs; null: only with case=all
    target: str = "root_wear_mm"
    val_replicates: int = 1  # whole trajectories (case, replicate), never rows of one
    test_replicates: int = 2
    holdout_case: int | None = None  # a case number: leave that case out (test on it alone)
    batch_size: int = 64
    seed: int = 0
    generate: dict[str, Any] = field(default_factory=dict)  # DatasetSpec values if built
    jobs: int = 2  # parallel processes when the dataset is built


@dataclass
class ModelConfig:
    """Schema of ``conf/train/model/`` (the network's settings), checked by :meth:`check`."""

    _target_: str = "surrogate.model.WearRegressor"
    width: int = 16  # 16: 3e6 rows/s on 2 cores; 32 is 0.6 points of MRE better and 5x slower
    depth: int = 2
    members: int = 5  # ensemble size: the spread of the members is the epistemic uncertainty
    lr: float = 3e-3
    weight_decay: float = 1e-5
    interval: float = 0.9  # level of the predictive interval (calibrated on validation)

    def check(self) -> None:
        """Raise ``ValueError`` naming the first setting outside its range."""
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


def register() -> None:
    """Register the schemas (before Hydra composes a train config)."""
    register_schema("wear_schema", DataConfig, group="data")
    register_schema("ensemble_schema", ModelConfig, group="model")
