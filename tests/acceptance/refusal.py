"""The apps' first phase run in-process, as their processes run it: Hydra composes the app's
config with a command line's overrides (a wrong type is refused there) and the app's
``prepare`` checks the rest (a ``ValueError``, the text of the app's one-line refusal).

A refusal's exit path (exit code 2, the one line on stderr, no traceback, nothing left in the
folder) is the same code in every app (:func:`physics.command.run_command`); it runs as a
subprocess once per app in ``tests/acceptance/test_bad_input.py``. Every other refusal is
checked here, in the test's process: :func:`refusal` gives its text, and the caller checks that
the working folder took nothing.
"""

from __future__ import annotations

import contextlib
import importlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest
from hydra import compose, initialize_config_module
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, open_dict, read_write

ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class App:
    argv: tuple[str, ...]  # how a user starts it
    config: str  # its config module (``gearwear_conf.<config>``) and primary config
    prepare: Callable[[], Callable[[DictConfig], object]]  # its first phase


def _main_prepare(package: str) -> Callable[[], Callable]:
    """The ``prepare`` of ``python -m <package>``, as ``runpy`` would find it (the import also
    registers the app's config schema)."""
    return lambda: importlib.import_module(f"{package}.__main__").prepare


def _train_prepare() -> Callable:
    from surrogate import settings
    from surrogate.training import prepare

    settings.register()  # as train.py does
    return prepare


def _predict_prepare() -> Callable:
    from surrogate.predict import prepare

    return prepare


APPS = {
    "reproduce": App(("-m", "physics.reproduce"), "reproduce",
                     _main_prepare("physics.reproduce")),
    "dataset": App(("-m", "physics.dataset"), "dataset", _main_prepare("physics.dataset")),
    "loop": App(("-m", "physics.loop"), "loop", _main_prepare("physics.loop")),
    "train": App((str(ROOT / "train.py"),), "train", _train_prepare),
    "predict": App(("-m", "surrogate.predict"), "predict", _predict_prepare),
}


def chain(err: BaseException) -> str:
    """The text of an exception and of every exception it came from."""
    parts = []
    while err is not None:
        parts.append(str(err))
        err = err.__cause__ or err.__context__
    return "\n".join(parts)


def tree(folder: Path) -> set[Path]:
    return {p.relative_to(folder) for p in folder.rglob("*")}


def composed(app: App, overrides: list[str], out: Path) -> DictConfig:
    """The app's config as Hydra gives it to the app's main, with ``out`` as the run folder
    (not made: ``prepare`` writes nothing)."""
    with initialize_config_module(f"gearwear_conf.{app.config}", version_base="1.3"):
        cfg = compose(app.config, overrides=overrides, return_hydra_config=True)
    with read_write(cfg.hydra.runtime), open_dict(cfg.hydra.runtime):
        cfg.hydra.runtime.output_dir = str(out)
    HydraConfig.instance().set_config(cfg)
    with read_write(cfg), open_dict(cfg):
        del cfg["hydra"]
    return cfg


def refusal(app: str, overrides: list[str], work: Path) -> BaseException:
    """The exception by which ``app`` (a key of :data:`APPS`) refuses the command line
    ``overrides`` typed in the folder ``work``, before any work (fails the test where the app
    accepts it). Its config is composed as a fresh process composes it: the caller takes the
    ``config_store`` fixture where ``app`` is not the train app."""
    spec = APPS[app]
    prepare = spec.prepare()  # registers the app's config schema, as its process does
    with contextlib.chdir(work), pytest.raises(Exception) as refused:
        prepare(composed(spec, overrides, work / "logs" / "run"))
    return refused.value
