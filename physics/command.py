"""What every command-line app of the package shares: its config schema and how it ends.

- :func:`register_schema` puts a dataclass into Hydra's ConfigStore as the schema of an app's
  config (a *structured config*): the YAML files under ``conf/`` only choose values, while the
  types and defaults come from the dataclass, so ``cycles=abc`` or ``gear.z1=abc`` is refused by
  Hydra while it composes the config, before the app runs.
- :func:`run_command` runs an app in two phases. ``prepare(cfg)`` validates everything (ranges,
  files, records) and raises ``ValueError`` for bad input; nothing has been computed or written
  yet, so the refusal is one line on stderr (no traceback), what Hydra made for it is removed
  (only what this run made, by the record :class:`RunRecord` took before it started), and the
  exit code is 2. ``execute(plan)`` then does the work; a run that leaves the model's scope
  there (:class:`~physics.params.OutOfScope`: the physics has stopped, not the code) ends with
  one line on stderr and exit code 1, its folder and log kept, as does a file that cannot be
  written (:class:`~physics.files.WriteFailed`: the disk full); any other error there is a bug
  and keeps its traceback.
- :func:`entry` is an app's console entry around its ``@hydra.main`` function: Ctrl-C (SIGINT)
  or SIGTERM, in any phase (start-up, checks, numba kernels, joblib workers, Lightning's fit
  loop), ends the app with one line on stderr saying what was kept and how to resume, without
  a traceback, exit code 130 (143 for SIGTERM). A run interrupted during its checks removes
  what it made, as a refused one does.
- :func:`check_keys`: a key the app does not have (``+foo=1``) is refused before any work.
- Sweeps (``-m``): :class:`RunRecord` checks every job's config before the first job starts
  (the whole sweep is refused in one line naming the bad job's overrides); at run time a job
  that fails is recorded (``failed.txt`` in its folder) and the others run on; the sweep ends
  with one line naming the failed jobs (exit code 1).
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import logging
import os
import shutil
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf, open_dict, read_write
from omegaconf.errors import MissingMandatoryValue

from physics import interrupt
from physics.files import WriteFailed, check_writable, first_and_more, resolved
from physics.params import OutOfScope, check_case

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


def _absolute(path: Path) -> Path:
    """``path`` absolute with ``..`` folded (as the folder it names, not as it is spelled)."""
    return Path(os.path.abspath(path))


def _record_before(folder: Path) -> None:
    """Record which of ``folder`` and its ancestors exist and what they hold, before any write.
    A folder spelled with ``..`` (``logs/../../x``) is made through each folder it passes, so
    every one of them is recorded."""
    spelled = Path(folder).absolute()
    passed = {_absolute(Path(*spelled.parts[:i])) for i in range(2, len(spelled.parts))}
    folder = _absolute(spelled)
    for path in (folder, *folder.parents):
        _BEFORE[path] = frozenset(c.name for c in path.iterdir()) if path.is_dir() else None
        if path.is_dir():  # the first existing ancestor ends the chain of folders to be made
            break
    for path in passed - set(_BEFORE):
        _BEFORE[path] = None if not path.is_dir() else frozenset()


class RunRecord(Callback):
    """Hydra callback (``hydra.callbacks.run_record`` of every app): records, before Hydra makes
    the run folder, what already exists there, so that a refused run removes only what it made."""

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        global _RUN_DIR
        _RUN_DIR = Path(str(config.hydra.run.dir))
        check_single_run(config)
        check_run_folder(_RUN_DIR, "hydra.run.dir")
        _record_before(_RUN_DIR)
        interrupt.started()

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        check_run_folder(Path(str(config.hydra.sweep.dir)), "hydra.sweep.dir")
        _record_before(Path(str(config.hydra.sweep.dir)))
        interrupt.started()
        try:
            check_launcher(config)
        except ValueError as err:
            refuse(err, Path(str(config.hydra.sweep.dir)))
        if "joblib" in str(config.hydra.launcher.get("_target_", "")):
            interrupt.quiet_workers()
        check_sweep(config)  # every job's config, before the first starts
        sweep = Path(str(config.hydra.sweep.dir))
        interrupt.note(lambda: sweep_kept(sweep))

    def on_job_end(self, config: DictConfig, job_return: Any, **kwargs: Any) -> None:
        """A failed job of a basic sweep is recorded and reported at the sweep's end: the
        basic sweeper would otherwise raise its error after the batch and stop the sweep."""
        from hydra.core.utils import JobStatus
        from hydra.types import RunMode

        if (config.hydra.mode != RunMode.MULTIRUN or job_return.status != JobStatus.FAILED
                or not str(config.hydra.sweeper.get("_target_", "")).endswith(".BasicSweeper")):
            return
        folder = Path(str(config.hydra.runtime.output_dir))
        if not (folder / FAILED).is_file():
            err = job_return._return_value
            _record_failure(folder, f"failed: {type(err).__name__}: {err}")
        job_return.status, job_return.return_value = JobStatus.COMPLETED, None

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        summary = sweep_summary()
        if summary is not None:
            print(f"error: {summary}", file=sys.stderr)
            raise SystemExit(1)


def check_single_run(config: DictConfig) -> None:
    """End a single run (one line, exit code 2, before Hydra makes its folder) whose command
    line chooses a launcher or a sweeper (``hydra/launcher=cluster``, ``hydra.sweeper.*``):
    they act on sweeps only (``-m``), so the run went on here without them, unsaid."""
    given = [str(o) for o in (config.hydra.get("overrides", {}).get("hydra") or [])]
    sweep_only = [o for o in given if o.lstrip("+~").startswith(
        ("hydra/launcher", "hydra/sweeper", "hydra.launcher.", "hydra.sweeper."))]
    if sweep_only:
        print(f"error: {sweep_only[0]} sets how a sweep's jobs run (-m), and this is a single "
              "run, which runs here without it: add -m to run it as a sweep (of one job, or "
              "more), or drop the setting", file=sys.stderr)
        raise SystemExit(2)


#: the free space a run folder's disk must have before Hydra writes its record and log there
ROOM_BYTES = 4 * 1024**2


def check_run_folder(folder: Path, key: str) -> None:
    """End the app (one line, exit code 2) where its run folder ``folder`` (``key``:
    ``hydra.run.dir``, or ``hydra.sweep.dir`` with ``-m``; under the working folder by default)
    cannot be made, before Hydra makes it: from a read-only working folder Hydra's own attempt
    ended in a PermissionError traceback, as its writes on a full disk did (less than
    ``ROOM_BYTES`` free); or where it already holds anything (a folder the user
    chose, an earlier run's): Hydra's record, the log and the results would go among files this
    run did not make, and replace those of the same name. Called by :class:`RunRecord` for every
    app."""
    try:
        check_writable(folder, key)
    except ValueError as err:
        reason = str(err).removesuffix("; choose a folder you can write to")
        print(f"error: {reason}: the run's folder is made there (working folder {Path.cwd()}); "
              f"run from a folder you can write to, or give {key}=<such a folder>",
              file=sys.stderr)
        raise SystemExit(2) from None
    real = resolved(folder)
    existing = next(p for p in (real, *real.parents) if p.exists())
    free = shutil.disk_usage(existing).free
    if free < ROOM_BYTES:  # Hydra's own writes of .hydra/ there ended in its traceback
        print(f"error: {key} = {str(folder)!r}: the disk holding {existing} has "
              f"{free / 1024:.0f} KiB free, less than the {ROOM_BYTES // 1024**2} MiB a run's "
              f"record and log need; make room, or give {key}=<a folder on another disk>",
              file=sys.stderr)
        raise SystemExit(2)
    held = sorted(p.name for p in real.iterdir()) if real.is_dir() else []
    if held:  # a folder a user chose (or an earlier run's): its files are not this run's
        print(f"error: {key} = {str(folder)!r} already holds {first_and_more(held)}: this run "
              f"writes its files (.hydra/, its log, its results) there and would replace files it "
              f"did not make; give {key} a new or empty folder, or leave {key} out (each run then "
              "gets its own)", file=sys.stderr)
        raise SystemExit(2)


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
    folder = _absolute(folder)
    record = _record_of(folder)
    if record is None:
        return
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
    made = [p for p, held in record.items() if held is None and p.is_dir()]
    for path in sorted(made, key=lambda p: len(p.parts), reverse=True):
        try:  # a folder made on the way to a run folder spelled with '..'
            path.rmdir()
        except OSError:
            pass


def refuse(err: BaseException, folder: Path | None = None) -> None:
    """End a run that was refused for bad input: one line, no traceback, nothing left."""
    _remove_what_the_run_made(folder if folder is not None else _run_folder())
    print(f"error: {err}", file=sys.stderr)
    raise SystemExit(2)


def run_command(cfg: DictConfig, prepare: Callable[[DictConfig], Plan],
                execute: Callable[[Plan], Any], kept: Callable[[Plan], str] | None = None
                ) -> Any:
    """Validate with ``prepare``, then work with ``execute`` (see the module text).

    ``kept(plan)`` says, after Ctrl-C or SIGTERM, what was kept and how to resume; the line is
    printed by :func:`entry`. In a sweep's job a refusal or failure is recorded and raised as
    an ordinary exception, so that Hydra marks that job failed and runs the others.
    """
    interrupt.started()  # (an app without the run_record callback)
    folder = _run_folder()
    job = _sweep_job()
    if job is not None and folder is not None:
        (folder / FAILED).unlink(missing_ok=True)  # an earlier job's, where jobs share a folder
    try:
        check_keys(cfg)
        check_case(cfg, _command_line_keys())
        plan = prepare(cfg)
    except (ValueError, MissingMandatoryValue) as err:
        if isinstance(err, MissingMandatoryValue):  # a setting without default, not given
            err = ValueError(f"{err.full_key} is not given and has no default: give "
                             f"{err.full_key}=... on the command line (--help says what it "
                             "takes)")
        if job is None:
            refuse(err, folder)
        _record_failure(folder, f"refused: {err}")
        logging.getLogger(__name__).error("job %d refused: %s", job, err)
        raise JobFailed(str(err)) from None
    except BaseException as err:
        if not interrupt.interrupted(err):
            raise
        raise KeyboardInterrupt from None  # the entry undoes the run (nothing was done yet)
    global _WORK_STARTED
    _WORK_STARTED = True
    if job is None and kept is not None:
        interrupt.note(lambda: kept(plan))
    try:
        result = execute(plan)
    except BaseException as err:
        if interrupt.interrupted(err):
            raise KeyboardInterrupt from None
        if job is not None:
            _record_failure(folder, f"failed: {type(err).__name__}: {err}")
            logging.getLogger(__name__).exception("job %d failed", job)
        elif isinstance(err, OutOfScope):
            logging.getLogger(__name__).error("out of the model's scope: %s", err)
            print(f"error: out of the model's scope: {err}", file=sys.stderr)
            raise SystemExit(1) from None
        elif isinstance(err, WriteFailed):
            logging.getLogger(__name__).error("%s", err.strerror)
            print(f"error: {err.strerror}; that file is left as it was: make room (or "
                  "choose another folder) and run the command again", file=sys.stderr)
            raise SystemExit(1) from None
        raise
    if job is None:
        interrupt.note(lambda: "the run had finished; its results are kept")
    return result


# --- the console entry -------------------------------------------------------------------

def entry(task: Callable[[], Any], check: Callable[[DictConfig], Any] | str | None = None,
          quick: Callable[[DictConfig], Any] | None = None) -> Callable[[], Any]:
    """The console entry of an app around its ``@hydra.main`` function ``task``: Ctrl-C and
    SIGTERM as :func:`physics.interrupt.guard` ends them. ``check(cfg)`` (or
    ``"module:function"``) validates a job's config without side effects: a sweep's jobs are
    checked with it before any starts (:class:`RunRecord`); ``quick(cfg)``, checks that need
    no slow import, runs on every job before the first job's ``check``."""
    def main() -> Any:
        global _CHECK, _QUICK
        _CHECK, _QUICK = check, quick
        try:
            check_spelling(sys.argv[1:])
        except ValueError as err:
            print(f"error: {err}", file=sys.stderr)
            raise SystemExit(2) from None
        try:
            return interrupt.guard(task, undo=_undo_unstarted, composing=True)
        except BrokenPipeError:  # the reader of the output left (python train.py --help | head)
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no flush error
            raise SystemExit(1) from None

    main.__doc__ = task.__doc__
    return main


def check_spelling(argv: list[str]) -> None:
    """Refuse (ValueError, one line) a command-line override that Hydra's grammar cannot read
    but would read quoted: a value holding a character beyond ASCII (a path
    ``data.table=/tmp/mé.csv``) or one of the grammar's own (``data.table=a(1).csv``, ``=``,
    a quote), with the way to write it: Hydra's own error names its lexer and no fix. A key
    beyond ASCII is refused with the rule for keys. Other overrides, and other errors, are
    left to Hydra."""
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.errors import OverrideParseException

    parser = OverridesParser.create()

    def reads(override: str) -> bool:
        try:
            parser.parse_overrides([override])
        except OverrideParseException:
            return False
        return True

    for arg in argv:
        if arg.startswith("-") or "=" not in arg or reads(arg):
            continue
        key, _, value = arg.partition("=")
        if not key.isascii():
            key = key.lstrip("+~")
            raise ValueError(f"{arg}: the key {key!r} holds a character beyond ASCII, which "
                             "no key given on the command line may hold (letters a-z, "
                             "digits, '_', '-', '.'); rename that column in your table")
        if value.startswith(("[", "{")):
            if not value.isascii():
                raise ValueError(f"{arg}: an item holding a character beyond ASCII must be "
                                 f"quoted for Hydra, each such item: {key}=[a,'é'] (in the "
                                 f"shell: \"{key}=[a,'é']\")")
            continue
        both = '"' in value and "'" in value  # then quoted in ', each ' escaped
        quote = "'" if both or "'" not in value else '"'
        inner = value.replace("'", "\\'") if both else value
        quoted = f"{key}={quote}{inner}{quote}"
        if not reads(quoted):
            continue
        odd = sorted({c for c in value if not c.isascii() or not (c.isalnum() or c in SAFE)})
        shown = " ".join(repr(c) for c in odd)
        raise ValueError(f"{arg}: the value holds {shown}, which Hydra's override grammar "
                         f"reads as its own or cannot read unquoted; quote the value: "
                         f"{quoted} (in the shell: {_shell(quoted)})")


#: characters an unquoted override value may hold besides letters and digits
SAFE = "_-./:+~@%*?^"


def _shell(text: str) -> str:
    """``text`` as one word for a POSIX shell: in double quotes where none of them would
    change it, else as :func:`shlex.quote` writes it."""
    import shlex

    return f'"{text}"' if not any(c in text for c in '$`"\\!') else shlex.quote(text)


#: the folder of this single run (RunRecord.on_run_start), and whether its work has started
_RUN_DIR: Path | None = None
_WORK_STARTED = False


def _undo_unstarted() -> None:
    """An interrupted single run whose work had not started: what it made goes, as for a
    refusal (a sweep keeps its folders: its jobs' records)."""
    if _RUN_DIR is not None and not _WORK_STARTED:
        _remove_what_the_run_made(_RUN_DIR)


# --- sweeps -----------------------------------------------------------------------------------

#: the record a failed job of a sweep leaves in its folder: one line, why it failed
FAILED = "failed.txt"
#: the check of a job's config for a sweep, and its part that needs no slow import (set by
#: :func:`entry`)
_CHECK: Callable[[DictConfig], Any] | str | None = None
_QUICK: Callable[[DictConfig], Any] | None = None


class JobFailed(Exception):
    """A sweep's job refused its config (an Exception, not SystemExit: the sweep goes on)."""


@dataclasses.dataclass(frozen=True)
class SweepJob:
    num: int
    overrides: tuple[str, ...]
    folder: Path


#: the jobs of the running sweep (filled by RunRecord.on_multirun_start)
_JOBS: list[SweepJob] = []


def _sweep_job() -> int | None:
    """The number of this process's job when it runs in a sweep, else None."""
    try:
        from hydra.core.hydra_config import HydraConfig
        from hydra.types import RunMode

        hc = HydraConfig.get()
        return int(hc.job.num) if hc.mode == RunMode.MULTIRUN else None
    except (ImportError, ValueError, TypeError, AttributeError):
        return None


def _command_line_keys() -> list[str]:
    """The overrides of this run's command line (``hydra.overrides.task``; none outside an
    app)."""
    try:
        from hydra.core.hydra_config import HydraConfig

        return [str(o) for o in HydraConfig.get().overrides.task]
    except (ImportError, ValueError, AttributeError):
        return []


def _record_failure(folder: Path | None, why: str) -> None:
    if folder is not None:
        from physics.files import write_text

        write_text(folder / FAILED, " ".join(why.split()) + "\n")


def _resolve(check: Callable[[DictConfig], Any] | str) -> Callable[[DictConfig], Any]:
    if callable(check):
        return check
    import importlib

    module, name = check.split(":")
    with interrupt.deferred():  # a slow import: a signal is raised after it
        return getattr(importlib.import_module(module), name)


def _sweep_jobs(config: DictConfig) -> list[SweepJob] | None:
    """The jobs a basic sweeper will launch for ``config`` (None for another sweeper, e.g.
    Optuna's, whose jobs are drawn as it goes)."""
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
    from hydra.core.override_parser.overrides_parser import OverridesParser

    if not str(config.hydra.sweeper.get("_target_", "")).endswith(".BasicSweeper"):
        return None
    params = [f"{k}={v}" for k, v in (config.hydra.sweeper.get("params") or {}).items()]
    arguments = [*params, *OmegaConf.to_container(config.hydra.overrides.task, resolve=False)]
    parsed = OverridesParser.create().parse_overrides(arguments)
    batches = BasicSweeper.split_arguments(parsed, None)
    return [SweepJob(num, tuple(overrides), Path())
            for num, overrides in enumerate(o for batch in batches for o in batch)]


def check_launcher(config: DictConfig) -> None:
    """Refuse (ValueError, one line) a sweep's launcher that this machine cannot run, before any
    job: the SLURM launcher (``hydra/launcher=cluster``, hydra-submitit-launcher) where no SLURM
    client (``srun``) is on the PATH; submitit raised its RuntimeError after the sweep's
    folder was made."""
    target = str(config.hydra.launcher.get("_target_", ""))
    if "submitit" in target and "Slurm" in target and shutil.which("srun") is None:
        raise ValueError(f"hydra.launcher = {target}: the sweep's jobs go to SLURM, and this "
                         "machine has no SLURM client (no srun on the PATH); run the sweep "
                         "here with the default launcher (drop hydra/launcher=cluster) or on "
                         "a SLURM login node")


def check_sweep(config: DictConfig) -> None:
    """Compose every job of the sweep ``config`` and check it before any job starts: first
    every job by :func:`check_keys`, :func:`check_case` and the app's quick check, then every
    job by the app's check (a bad value in the last job is refused before the slow imports
    the first job's check may need); a bad job refuses the whole sweep in one line naming its
    overrides (exit code 2). Also notes each job's folder for the sweep's summary."""
    from hydra.core.global_hydra import GlobalHydra
    from hydra.core.hydra_config import HydraConfig

    _JOBS.clear()
    jobs = _sweep_jobs(config)
    if jobs is None or not GlobalHydra.instance().is_initialized():
        return
    loader = GlobalHydra.instance().config_loader()
    saved = HydraConfig.instance().cfg
    composed = []
    try:
        for job in jobs:
            with _refusing_the_sweep(job):
                cfg = loader.load_sweep_config(config, list(job.overrides))
                with open_dict(cfg):
                    cfg.hydra.job.num = job.num
                    cfg.hydra.job.id = str(job.num)
                    folder = Path(str(cfg.hydra.sweep.dir)) / str(cfg.hydra.sweep.subdir)
                    cfg.hydra.runtime.output_dir = str(folder.absolute())
                _JOBS.append(dataclasses.replace(job, folder=folder))
                HydraConfig.instance().set_config(cfg)
                task = copy.deepcopy(cfg)
                with read_write(task), open_dict(task):
                    del task["hydra"]
                check_keys(task)
                check_case(task, job.overrides)
                if _QUICK is not None:
                    _QUICK(task)
                composed.append((job, cfg, task))
        check = _resolve(_CHECK) if _CHECK is not None else None
        for job, cfg, task in composed if check is not None else ():
            with _refusing_the_sweep(job):
                HydraConfig.instance().set_config(cfg)
                check(task)
    finally:
        HydraConfig.instance().cfg = saved


@contextlib.contextmanager
def _refusing_the_sweep(job: SweepJob) -> Iterator[None]:
    """A ValueError of the block refuses the sweep in one line naming ``job`` (exit code 2)."""
    try:
        yield
    except ValueError as err:
        overrides = " ".join(job.overrides) or "no overrides"
        print(f"error: job {job.num} of the sweep ({overrides}): {err}; no job was "
              "started: fix or drop that value and run the sweep again", file=sys.stderr)
        raise SystemExit(2) from None


def sweep_kept(sweep: Path) -> str:
    """What an interrupted sweep keeps, said truly: none of its jobs' folders made yet (an
    interrupt before the first job), or how many of them there are in ``sweep``."""
    folders = ([j.folder for j in _JOBS] if _JOBS else
               [p for p in sweep.iterdir() if p.is_dir() and p.name != ".hydra"]
               if sweep.is_dir() else [])
    started = [f for f in folders if f.is_dir()]
    if not started:
        return "no job of the sweep had started; nothing was computed"
    of = f" of {len(_JOBS)}" if _JOBS else ""
    return (f"{len(started)}{of} of the sweep's jobs had started; their folders are kept in "
            f"{sweep} (one stopped mid-run keeps what it had written); run the jobs that did "
            "not finish again, into a new hydra.sweep.dir")


def sweep_summary() -> str | None:
    """One line naming the sweep's failed jobs (from their records), None if none failed."""
    failed = [(job, (job.folder / FAILED).read_text().strip()) for job in _JOBS
              if (job.folder / FAILED).is_file()]
    if not failed:
        return None
    names = "; ".join(f"job {job.num} ({' '.join(job.overrides)}) {why}" for job, why in failed)
    return (f"{len(failed)} of {len(_JOBS)} jobs of the sweep failed: {names}; the others "
            f"finished in {_JOBS[0].folder.parent}; each failed job's log is in its folder")


# --- keys the app does not have ---------------------------------------------------------------

def _root_keys(cfg: DictConfig) -> set[str] | None:
    """The top-level keys an app whose root has no schema allows: its primary config's keys
    and its config groups (None where Hydra does not tell them)."""
    try:
        from hydra.core.global_hydra import GlobalHydra
        from hydra.core.hydra_config import HydraConfig

        hc = HydraConfig.get()
        groups = {k for k, v in hc.runtime.choices.items()
                  if "/" not in k and k != "hydra" and v is not None}
        primary = GlobalHydra.instance().config_loader().repository.load_config(
            hc.job.config_name)
    except (ImportError, ValueError, AttributeError):
        return None
    if primary is None or primary.config is None:
        return None
    return groups | (set(primary.config.keys()) - {"defaults", "hydra"})


def check_keys(cfg: DictConfig) -> None:
    """Refuse (ValueError, one line) a key that the app's config does not have, as
    ``+foo=1`` adds it: each node with a schema (a dataclass) is checked against its fields,
    and a root without one against its primary config's keys and groups."""
    root = _root_keys(cfg) if not dataclasses.is_dataclass(OmegaConf.get_type(cfg)) else None
    _check_node(cfg, "", root)


def _check_node(node: DictConfig, path: str, allowed: set[str] | None) -> None:
    kind = OmegaConf.get_type(node)
    if dataclasses.is_dataclass(kind):
        allowed = {f.name for f in dataclasses.fields(kind)}
    keys = [k for k in node.keys() if not (path == "" and k == "hydra")]
    if allowed is not None:
        unknown = [k for k in keys if k not in allowed]
        if unknown:
            key = f"{path}{unknown[0]}"
            where = f"the keys of {path[:-1]}" if path else "the top-level keys"
            raise ValueError(f"{key} = {node._get_node(unknown[0])._value()!r}: this command "
                             f"has no key {key}; {where} are {', '.join(sorted(allowed))} "
                             f"(drop +{key}=..., or check its spelling; --cfg job prints the "
                             "config)")
    for k in keys:
        child = node._get_node(k)
        if isinstance(child, DictConfig) and not child._is_missing() and not child._is_none():
            _check_node(child, f"{path}{k}.", None)
