"""What every command-line app of the package shares: its config schema and how it ends.

- :func:`register_schema` puts a dataclass into Hydra's ConfigStore as the schema of an app's
  config (a *structured config*): the YAML files under ``conf/`` only choose values, while the
  types and defaults come from the dataclass, so ``cycles=abc`` or ``gear.z1=abc`` is refused by
  Hydra while it composes the config, before the app runs.
- :func:`run_command` runs an app in two phases. ``prepare(cfg)`` validates everything (ranges,
  files, records) and raises ``ValueError`` for bad input; nothing has been computed or written
  yet, so the refusal is one line on stderr (no traceback), the run folder Hydra made for it is
  removed, and the exit code is 2. ``execute(plan)`` then does the work; an error there is a bug
  and keeps its traceback. Ctrl-C during the work ends with one line naming what was kept and
  how to resume (exit code 130).
"""

from __future__ import annotations

import shutil
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from omegaconf import DictConfig, OmegaConf

Plan = TypeVar("Plan")


def register_schema(name: str, cls: type, group: str | None = None) -> None:
    """Register dataclass ``cls`` in Hydra's ConfigStore under ``name`` (in ``group``).

    Frozen dataclasses (the physics parameters) make read-only nodes; the schema is made
    writable so that the YAML choices and command-line overrides can fill it.
    """
    from hydra.core.config_store import ConfigStore

    node = OmegaConf.structured(cls)
    _writable(node)
    ConfigStore.instance().store(name=name, node=node, group=group)


def _writable(node: Any) -> None:
    OmegaConf.set_readonly(node, False)
    if OmegaConf.is_dict(node):
        for key in node:
            child = node._get_node(key)
            if OmegaConf.is_config(child):
                _writable(child)


def _run_folder() -> Path | None:
    try:
        from hydra.core.hydra_config import HydraConfig

        return Path(HydraConfig.get().runtime.output_dir)
    except (ImportError, ValueError):
        return None


def _remove_if_only_hydra(folder: Path | None) -> None:
    """Remove Hydra's run folder of a refused run if it holds nothing but Hydra's own files."""
    if folder is None or not folder.is_dir():
        return
    own = {".hydra", f"{Path(sys.argv[0]).stem}.log", "__main__.log"}
    if all(p.name in own or p.name.endswith(".log") for p in folder.iterdir()):
        shutil.rmtree(folder, ignore_errors=True)
        cwd = Path.cwd().resolve()
        for parent in folder.resolve().parents:  # date folders Hydra made for it, if now empty
            if parent == cwd or cwd.is_relative_to(parent):
                break
            try:
                parent.rmdir()
            except OSError:
                break


def refuse(err: BaseException, folder: Path | None = None) -> None:
    """End a run that was refused for bad input: one line, no traceback, nothing left."""
    _remove_if_only_hydra(folder if folder is not None else _run_folder())
    print(f"error: {err}", file=sys.stderr)
    raise SystemExit(2)


def run_command(cfg: DictConfig, prepare: Callable[[DictConfig], Plan],
                execute: Callable[[Plan], Any], kept: Callable[[Plan], str] | None = None
                ) -> Any:
    """Validate with ``prepare``, then work with ``execute`` (see the module text).

    ``kept(plan)`` says, after Ctrl-C, what was kept and how to resume.
    """
    folder = _run_folder()
    try:
        plan = prepare(cfg)
    except ValueError as err:
        refuse(err, folder)
    try:
        return execute(plan)
    except KeyboardInterrupt:
        note = kept(plan) if kept is not None else "nothing was kept; run the command again"
        print(f"interrupted: {note}", file=sys.stderr)
        raise SystemExit(130) from None
