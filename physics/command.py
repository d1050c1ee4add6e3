"""What every command-line app of the package shares: its config schema and how it ends.

- :func:`register_schema` puts a dataclass into Hydra's ConfigStore as the schema of an app's
  config (a *structured config*): the YAML files under ``conf/`` only choose values, while the
  types and defaults come from the dataclass, so ``cycles=abc`` or ``gear.z1=abc`` is refused by
  Hydra while it composes the config, before the app runs.
- :func:`run_command` runs an app in two phases. ``prepare(cfg)`` validates everything (ranges,
  files, records) and raises ``ValueError`` for bad input; nothing has been computed or written
  yet, so the refusal is one line on stderr (no traceback), what Hydra made for it is removed
  (only what this run made, by the record :class:`RunRecord` took before it started), and the
  exit code is 2. ``execute(plan)`` then does the work; an error there is a bug and keeps its
  traceback. Ctrl-C during the work ends with one line naming what was kept and
  how to resume (exit code 130).
"""

from __future__ import annotations

import shutil
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from hydra.experimental.callback import Callback
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


#: what existed, before Hydra made the run folder, of the folder and each of its ancestors:
#: ``{folder: names inside it then, or None where it did not exist}`` (filled by RunRecord)
_BEFORE: dict[Path, frozenset[str] | None] = {}


def _record_before(folder: Path) -> None:
    """Record which of ``folder`` and its ancestors exist and what they hold, before any write."""
    folder = folder.absolute()
    for path in (folder, *folder.parents):
        _BEFORE[path] = frozenset(c.name for c in path.iterdir()) if path.is_dir() else None
        if path.is_dir():  # the first existing ancestor ends the chain of folders to be made
            break


class RunRecord(Callback):
    """Hydra callback (``hydra.callbacks.run_record`` of every app): records, before Hydra makes
    the run folder, what already exists there, so that a refused run removes only what it made."""

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        _record_before(Path(str(config.hydra.run.dir)))

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        _record_before(Path(str(config.hydra.sweep.dir)))


def _record_of(folder: Path) -> dict[Path, frozenset[str] | None] | None:
    """The record of ``folder`` and its chain; a job folder inside a recorded sweep folder that
    did not hold it before counts as made by this run, with every folder between. None where
    nothing is known of the folder."""
    if folder in _BEFORE:
        return _BEFORE
    made = [folder]
    for parent in folder.parents:
        if parent in _BEFORE:
            if _BEFORE[parent] is not None and made[-1].name in _BEFORE[parent]:
                return None
            return {**_BEFORE, **dict.fromkeys(made)}
        made.append(parent)
    return None


def _remove_what_the_run_made(folder: Path | None) -> None:
    """Undo a refused run's files by the record taken before it started (:class:`RunRecord`):
    inside the run folder only the entries that were not there before, then each folder of the
    chain that did not exist before, if it is now empty. Without a record nothing is removed."""
    if folder is None:
        return
    record = _record_of(folder.absolute())
    if record is None:
        return
    folder = folder.absolute()
    before = record[folder]
    if folder.is_dir():
        for entry in folder.iterdir():
            if before is None or entry.name not in before:
                if entry.is_dir() and not entry.is_symlink():
                    shutil.rmtree(entry, ignore_errors=True)
                else:
                    entry.unlink(missing_ok=True)
    for path in (folder, *folder.parents):
        if path not in record or record[path] is not None:
            break
        try:
            path.rmdir()  # only if empty: anything a user put there since stays
        except OSError:
            break


def refuse(err: BaseException, folder: Path | None = None) -> None:
    """End a run that was refused for bad input: one line, no traceback, nothing left."""
    _remove_what_the_run_made(folder if folder is not None else _run_folder())
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
