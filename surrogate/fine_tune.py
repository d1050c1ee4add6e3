"""What a run that fine-tunes a pre-trained network (``init_from``) reads and may not change,
and the settings a run would silently not honour: checked with torch alone, before Lightning's
import (``train.py``) and again by :func:`surrogate.training.prepare` (the Python API's way in).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from omegaconf import DictConfig, OmegaConf

from surrogate import settings

if TYPE_CHECKING:
    from surrogate.inference import Surrogate


def network(cfg: DictConfig) -> Surrogate | None:
    """The network ``cfg.init_from`` names (None without it), refused where that file holds
    another kind of model."""
    if not cfg.get("init_from"):
        return None
    from surrogate.inference import Surrogate  # torch: only for a fine-tune

    init = Surrogate.load(cfg.init_from, key="init_from")
    if init.model is None:
        raise ValueError(f"init_from = {cfg.init_from} holds a {init.kind} model, not a "
                         "network; fine-tune from a run that kept the network "
                         "(its wear_surrogate.pt, or network_surrogate.pt beside another kind)")
    return init


def given(node: DictConfig, schema: type, keys: tuple[str, ...]) -> dict[str, object]:
    """The ``keys`` of ``node`` set to other values than their schema's defaults (so asked
    for: by the command line, an experiment or the Python API), as plain values."""
    default = schema()
    values = {k: OmegaConf.to_container(node[k]) if OmegaConf.is_config(node[k]) else node[k]
              for k in keys}
    return {k: v for k, v in values.items() if v != getattr(default, k)}


def shown(values: dict[str, object], prefix: str) -> str:
    """``values`` as the keys under ``prefix`` a message names: ``data.a = 1 and data.b = 2``."""
    return " and ".join(f"{prefix}.{k} = {v!r}" for k, v in values.items())


def check_honoured(cfg: DictConfig, init: Surrogate | None) -> None:
    """Refuse (ValueError, one line) a setting this run would silently not honour, naming it and
    the fix:

    - ``data.sensors`` and ``data.operating_point`` choose the default inputs: not where
      ``data.inputs`` names them, nor in a fine-tune (``init_from``) whose network reads
      other inputs (a fine-tune reads its network's: :func:`read_as`);
    - ``model.width``, ``model.depth`` and ``model.members`` of a fine-tune: it keeps its
      network's shape;
    - ``data.generate`` and ``data.gearboxes`` build the physics dataset: not with a table of
      one's own (``data.table``).

    A setting counts as given where it differs from its schema's default
    (:mod:`surrogate.settings`)."""
    data = cfg.data
    choose = given(data, settings.DataConfig, ("sensors", "operating_point"))
    if choose and data.get("inputs") is not None:
        raise ValueError(f"{shown(choose, 'data')} choose the default inputs, but data.inputs "
                         f"names the inputs ({list(data.inputs)}): drop "
                         f"{' and '.join(f'data.{k}' for k in choose)}, or data.inputs")
    if choose and init is not None:
        from surrogate.inputs import input_columns

        baseline = init.schema.baseline if data.get("baseline") is None else data.baseline
        try:
            chosen = input_columns(list(data.sensors), bool(data.operating_point),
                                   bool(baseline))
        except ValueError:  # no inputs of that reading: not the network's either
            chosen = None
        if chosen != list(init.schema.inputs):
            raise ValueError(f"init_from = {cfg.init_from}: a fine-tune reads that network's "
                             f"inputs {list(init.schema.inputs)}, and {shown(choose, 'data')} "
                             f"asks for others: drop {' and '.join(f'data.{k}' for k in choose)}"
                             ", or train from scratch on them (without init_from)")
    if init is not None:
        shape = given(cfg.model, settings.ModelConfig, ("width", "depth", "members"))
        other = {k: v for k, v in shape.items() if v != init.model.hparams[k]}
        if other:
            theirs = ", ".join(f"{k} {init.model.hparams[k]}" for k in other)
            raise ValueError(f"{shown(other, 'model')}: a fine-tune keeps the shape of its "
                             f"network (init_from = {cfg.init_from}: {theirs}); drop "
                             f"{' and '.join(f'model.{k}' for k in other)}, or train from "
                             "scratch (without init_from)")
    if data.get("table") is not None:
        physics = given(data, settings.DataConfig, ("generate", "gearboxes"))
        if physics:
            raise ValueError(f"{shown(physics, 'data')} set how the physics dataset is built, "
                             f"and this run reads your table (data.table = {data.table}): drop "
                             f"{' and '.join(f'data.{k}' for k in physics)}")


def read_as(data: DictConfig, init: Surrogate) -> DictConfig:
    """The data settings of a fine-tune of ``init``: where ``data.inputs``, ``data.target`` or
    ``data.baseline`` are left null, the pre-trained network's (a fine-tune reads as the
    network it starts from; a value given is kept and checked against it by :func:`prepare`)."""
    schema = init.schema
    theirs = {"inputs": list(schema.inputs), "target": schema.target,
              "baseline": bool(schema.baseline)}
    out = data.copy()
    for key, value in theirs.items():
        if out.get(key) is None:
            out[key] = value
    return out
