"""Atomic file output: write to a temporary name in the target folder, then rename.

An interrupted run therefore never leaves a half-written file that a later run would trust.
"""

from __future__ import annotations

import csv
import os
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # (not imported: an app's start, physics.command, imports this module)
    import pandas as pd


class WriteFailed(OSError):
    """A file could not be written (the disk full, a quota reached, the folder made read-only
    meanwhile): raised by :func:`atomic_write` naming the file, which is left as it was (no
    half-written file); an app ends with its one line (:func:`physics.command.run_command`)."""


def atomic_write(path: str | os.PathLike, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp_path)`` and move the result to ``path`` in one rename; an OSError on
    the way is raised as :class:`WriteFailed`, the temporary file removed."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file the usual permissions
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    except BaseException as err:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(err, OSError) and not isinstance(err, WriteFailed):
            raise WriteFailed(err.errno, f"{path} could not be written "
                                         f"({err.strerror or err})") from err
        raise
    return path


def write_csv(df: pd.DataFrame, path: str | os.PathLike) -> Path:
    """Write ``df`` as CSV without the index, atomically."""
    return atomic_write(path, lambda p: df.to_csv(p, index=False))


def save_figure(fig, path: str | os.PathLike) -> Path:
    """Save a matplotlib figure atomically (format from the target suffix)."""
    fmt = Path(path).suffix.lstrip(".") or "png"
    return atomic_write(path, lambda p: fig.savefig(p, format=fmt, dpi=130, bbox_inches="tight"))


def pyplot():
    """``matplotlib.pyplot`` on the non-interactive Agg backend (figures go to files only)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def sha256_file(path: str | os.PathLike) -> str:
    """The sha256 (hex) of a file's bytes, read in blocks."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` to ``path`` atomically."""
    return atomic_write(path, lambda p: p.write_text(text))


def set_aside(path: str | os.PathLike, suffix: str = ".damaged") -> Path:
    """Rename ``path`` to ``<path><suffix>`` (``<path><suffix>.1``, ... if taken); nothing is
    deleted. Returns the new name."""
    path = Path(path)
    target, i = path.with_name(path.name + suffix), 0
    while target.exists():
        i += 1
        target = path.with_name(f"{path.name}{suffix}.{i}")
    os.replace(path, target)
    return target


# --- one writer per output ------------------------------------------------------------------

def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    except OverflowError:
        return False
    return True


def read_lock(path: str | os.PathLike) -> dict | None:
    """The holder written in lock file ``path`` (pid, host, command, ...), None if absent.
    An unreadable lock counts as held by an unknown process."""
    import json

    try:
        return json.loads(Path(path).read_text())
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return {"pid": None, "host": None, "command": "?"}


def lock_is_live(holder: dict) -> bool:
    """Whether the holder of a lock still runs (on another host: assumed so)."""
    import socket

    pid = holder.get("pid")
    if holder.get("host") != socket.gethostname() or not isinstance(pid, int):
        return True
    return pid == os.getpid() or _pid_alive(pid)


def take_lock(path: str | os.PathLike, what: str, extra: dict | None = None) -> Path:
    """Create lock file ``path`` atomically (``O_CREAT | O_EXCL``) holding this process's pid,
    host and command line (and ``extra``). A lock left by a dead process on this host is taken
    over with a warning; a live one raises ValueError naming its pid and the lock's path; a
    lock that cannot be written (a full disk) is removed and raised as :class:`WriteFailed`."""
    import json
    import logging
    import socket
    import sys

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    body = json.dumps({"pid": os.getpid(), "host": socket.gethostname(),
                       "command": " ".join(sys.argv), **(extra or {})}, sort_keys=True)
    for _ in range(3):
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            holder = read_lock(path)
            if holder is None:
                continue  # released meanwhile
            if lock_is_live(holder):
                raise ValueError(lock_message(path, holder, what)) from None
            logging.getLogger(__name__).warning(
                "taking over the stale lock %s of %s (pid %s on %s, no longer running)", path,
                what, holder.get("pid"), holder.get("host"))
            path.unlink(missing_ok=True)
            continue
        try:
            with os.fdopen(fd, "w") as f:
                f.write(body + "\n")
        except OSError as err:  # a full disk: no empty lock left for the next run to trip on
            path.unlink(missing_ok=True)
            raise WriteFailed(err.errno, f"the lock {path} of {what} could not be written "
                                         f"({err.strerror or err})") from err
        return path
    raise ValueError(f"could not take the lock {path} of {what}; another run keeps taking it: "
                     "wait until it ends")


def lock_message(path: Path, holder: dict, what: str) -> str:
    return (f"{what} is being written by another run (pid {holder.get('pid')} on "
            f"{holder.get('host')}: {holder.get('command')}), lock {path}; wait until it ends, "
            "or remove the lock file if that run is gone")


def release_lock(path: str | os.PathLike) -> None:
    """Remove lock file ``path`` if this process holds it."""
    holder = read_lock(path)
    if holder is not None and holder.get("pid") == os.getpid():
        Path(path).unlink(missing_ok=True)


def check_writable(path: str | os.PathLike, key: str) -> None:
    """Refuse (ValueError, one line) an output folder ``path`` that cannot be written, before
    any work: the nearest existing folder of its chain must be a folder and must take a file
    (tried with a temporary file that is removed at once: permission bits alone do not tell,
    e.g. for root or on a read-only mount). The chain is that of the folder ``path`` names
    (:func:`resolved`: ``a/../b`` is ``b``, whether ``a`` exists or not)."""
    import tempfile

    path = resolved(path)
    existing = next(p for p in (path, *path.parents) if p.exists())
    if not existing.is_dir():
        raise ValueError(f"{key} = {str(path)!r}: {existing} is a file, not a folder; give a "
                         "folder")
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as err:
        reason = err.strerror or type(err).__name__
        raise ValueError(f"{key} = {str(path)!r}: cannot write in {existing} ({reason}); "
                         "choose a folder you can write to") from None


def check_fresh(path: str | os.PathLike, key: str, patterns: tuple[str, ...], overwrite: bool,
                flag: str) -> None:
    """Refuse (ValueError, one line) an output folder ``path`` that already holds files of the
    kinds a run writes there (``patterns``, e.g. ``*.csv``): an earlier run's or the user's
    own, which the run would replace unasked; ``overwrite`` (the user's ``flag``) lets it.
    The folder looked in is the one the writes reach (:func:`resolved`): ``new/../out`` is
    ``out``, although ``new/`` does not exist."""
    folder = resolved(path)
    if overwrite or not folder.is_dir():
        return
    found = sorted(p.name for pattern in patterns for p in folder.glob(pattern) if p.is_file())
    if found:
        raise ValueError(f"{key} = {str(path)!r}{_spelled(path, folder)} already holds "
                         f"{first_and_more(found)}, which this run would replace; choose a new "
                         f"folder, or {flag} to replace them")


def first_and_more(names: list[str]) -> str:
    """``a`` or ``a and 3 more``: the first of ``names`` and how many follow."""
    return names[0] + (f" and {len(names) - 1} more" if len(names) > 1 else "")


def check_inside(path: str | os.PathLike, root: str | os.PathLike, key: str) -> None:
    """Refuse (ValueError, one line) a ``path`` that resolves outside ``root`` (e.g. a run
    folder made from ``task_name=../../x``): ``..`` and links are resolved first."""
    p, r = Path(path).resolve(), Path(root).resolve()
    if p != r and r not in p.parents:
        raise ValueError(f"{key} puts {str(path)!r} at {p}, outside {r}; use a plain name "
                         "(letters, digits, '_', '-', '.'; no '..' or '/')")


def resolved(path: str | os.PathLike) -> Path:
    """The absolute path the system reaches by ``path``: links followed and each ``..`` taken
    after the part before it (``os.path.realpath``). A part that does not exist yet is kept as
    spelled, so ``new/../out`` is ``out`` (a writer that makes its parents makes ``new/`` and
    then writes into ``out``)."""
    return Path(os.path.realpath(Path(path).expanduser()))


def _spelled(path: str | os.PathLike, real: Path) -> str:
    """`` (that is REAL)`` where ``path`` is spelled otherwise than the folder it reaches."""
    return "" if Path(path).absolute() == real else f" (that is {real})"


def same_path(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether ``a`` and ``b`` name one file or folder: the same :func:`resolved` path, or,
    both existing, the same file by device and inode (a hard link, a bind mount)."""
    ra, rb = resolved(a), resolved(b)
    if ra == rb:
        return True
    try:
        return os.path.samefile(ra, rb)
    except OSError:
        return False


def check_not_input(outputs: Iterable[str | os.PathLike], key: str,
                    source: str | os.PathLike, source_key: str) -> None:
    """Refuse (ValueError, one line) an output folder ``key`` one of whose files ``outputs``
    is the input file ``source`` (the user's ``source_key``; :func:`same_path`): the run
    would replace what it reads, whatever ``overwrite`` says."""
    for out in outputs:
        if same_path(out, source):
            raise ValueError(f"{key}: the output {resolved(out)} would replace the input "
                             f"{source_key} {source}, which this run reads; give {key} another "
                             f"folder (or the {source_key} file another name)")


def check_outside(out: str | os.PathLike, key: str, inputs: dict[str, str | os.PathLike]
                  ) -> None:
    """Refuse (ValueError, one line) an output folder ``out`` (the user's ``key``) that is an
    input folder of ``inputs`` (``{its key: path}``), lies inside it, or directly holds an
    input file (a link's target counts): its files would go among the inputs, or replace them,
    whatever ``overwrite`` says. Paths are compared as :func:`resolved`."""
    real = resolved(out)
    for name, path in inputs.items():
        source = resolved(path)
        if source.is_dir():
            clash = same_path(real, source) or source in real.parents
            where = "is" if same_path(real, source) else "lies inside"
            what = f"{where} the folder of {name} = {str(path)!r}"
        else:
            clash = same_path(source.parent, real)
            what = f"holds {name} {source}"
        if clash:
            raise ValueError(f"{key} = {str(out)!r}{_spelled(out, real)} {what}, which this "
                             f"run reads: its files would go among (or replace) what it "
                             f"reads, whatever overwrite says; give {key} a folder apart "
                             f"from {name}")


def read_csv_table(path: str | os.PathLike, key: str, fix: str, columns: Iterable[str] = (),
                   numeric: Iterable[str] = ()) -> pd.DataFrame:
    """The CSV file ``path`` as a DataFrame, or a refusal (ValueError, one line naming ``key``,
    the file, what is wrong and ``fix``): a path that is not a regular file, an empty file, a
    file that is not UTF-8 text (binary, another encoding) or not read as CSV, a table without
    the ``columns`` it needs, or a cell of the ``numeric`` columns that is not a finite number
    (named by its row, counted from 1 after the header)."""
    import numpy as np
    import pandas as pd

    path = Path(path)
    what = file_problem(path)
    if what is None:
        try:
            table = pd.read_csv(path, encoding="utf-8")
        except pd.errors.EmptyDataError:
            what = "is empty (no header, no rows)"
        except UnicodeDecodeError as err:
            what = f"is not UTF-8 text (byte {err.start}: binary, or another encoding)"
        except pd.errors.ParserError as err:
            what = f"is not read as CSV ({' '.join(str(err).split())})"
        except OSError as err:
            what = f"cannot be read ({err.strerror or type(err).__name__})"
    if what is not None:
        raise ValueError(f"{key} {path} {what}; {fix}")
    columns, numeric = list(columns), list(numeric)
    missing = [c for c in dict.fromkeys([*columns, *numeric]) if c not in table.columns]
    if missing:
        raise ValueError(f"{key} {path}: columns {missing} are missing; it needs "
                         f"{list(dict.fromkeys([*columns, *numeric]))}; {fix}")
    if table.empty:
        raise ValueError(f"{key} {path} holds a header and no rows; {fix}")
    for col in numeric:
        values = pd.to_numeric(table[col], errors="coerce").to_numpy(dtype=float)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise ValueError(f"{key} {path}: column {col} row {bad[0] + 1} is "
                             f"{table[col].iloc[bad[0]]!r}, not a finite number; {fix}")
    return table


def existing_file(value: object, key: str, fix: str) -> Path:
    """``value`` as the path of an existing regular file, else a refusal (ValueError, one line
    naming ``key``, the value and what is wrong; ``fix`` says what to give instead): not a
    path at all (None, a number, a mapping: from the Python API or a config), a path that does
    not exist, a folder, or a file of another kind (a FIFO, or a device such as /dev/zero:
    reading it waits or never ends)."""
    if isinstance(value, bool) or not isinstance(value, str | os.PathLike) or value == "":
        raise ValueError(f"{key} = {value!r} is not a file name; {fix}")
    path = Path(value)
    what = file_problem(path)
    if what is None:
        return path
    raise ValueError(f"{key} = {str(path)!r} {what}; {fix}")


def file_problem(path: Path, missing: str = "does not exist") -> str | None:
    """What keeps ``path`` from being read as a regular file (``missing`` where it does not
    exist; a folder; a FIFO, device or socket, whose reading waits or never ends), or None."""
    if not path.exists():
        return missing
    if path.is_dir():
        return "is a folder, not a file"
    if not path.is_file():
        return "is not a regular file (a FIFO, a device or a socket)"
    return None


def repeated_header(path: str | Path) -> list[str]:
    """The column names a table file (``.csv``: its header line as written; ``.parquet``: its
    schema) holds more than once, which pandas would read as ``a``, ``a.1``, ... or refuse
    with pyarrow's own text; none for other files or a file whose header cannot be read (its
    reader then says why)."""
    path = Path(path)
    if path.suffix == ".csv":
        with open(path, newline="", encoding="utf-8", errors="replace") as f:
            names = [h.strip() for h in next(csv.reader(f), [])]
    elif path.suffix == ".parquet":
        import pyarrow.lib
        import pyarrow.parquet

        try:
            names = pyarrow.parquet.read_schema(path).names
        except (OSError, pyarrow.lib.ArrowException):
            return []
    else:
        return []
    return repeated(names)


def repeated(names: Iterable) -> list:
    """The names that stand more than once in ``names`` (column labels), sorted."""
    names = list(names)
    return sorted({n for n in names if names.count(n) > 1})


def check_unrepeated(path: str | Path, where: str) -> None:
    """Refuse (ValueError, one line starting with ``where``) a table file whose header names a
    column more than once (:func:`repeated_header`)."""
    twice = repeated_header(path)
    if twice:
        raise ValueError(f"{where} has column(s) {twice} more than once; keep one of each")
