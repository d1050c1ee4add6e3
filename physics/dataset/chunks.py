"""The stored chunks of a dataset build: where they live, the manifest that vouches for them,
and the lock that makes one build the writer of a dataset.

A chunk folder ``<out>/<name>_chunks/`` holds ``chunk_<i>.parquet`` (and ``chunk_<i>.npy``,
the records, where kept) and ``manifest.json``: per finished chunk the hash of the config that
determines it and the sha256 of its files' bytes. The manifest lives outside the chunks, so a
damaged chunk cannot vouch for itself; it is replaced atomically under an exclusive ``flock`` of
the folder, so the parallel jobs of a multirun keep each other's entries.

A build holds ``<out>/<name>.lock`` (a whole build) or ``<out>/<name>.chunk_<i>.lock`` (one
chunk's job), created with ``O_CREAT | O_EXCL`` (:func:`physics.files.take_lock`): a whole build
shares its dataset with no other build, a chunk job only with the chunk jobs of its own config.
"""

from __future__ import annotations

import glob
import json
import logging
import os
from pathlib import Path

from physics.files import (
    lock_is_live,
    lock_message,
    read_lock,
    release_lock,
    set_aside,
    sha256_file,
    take_lock,
    write_text,
)

log = logging.getLogger(__name__)


def chunk_folder(out: Path, name: str) -> Path:
    """Where the chunks of dataset ``name`` live (one folder per dataset name)."""
    return out / f"{name}_chunks"


def chunk_path(folder: Path, chunk: int) -> Path:
    return folder / f"chunk_{chunk:03d}.parquet"


MANIFEST = "manifest.json"


def read_manifest(folder: Path, repair: bool = False) -> dict[str, dict]:
    """The manifest of a chunk folder: ``{chunk file name: {"hash": config hash, "sha256": of
    the file's bytes, "signals_sha256": of its records or None}}`` ({} where there is none).
    It lives outside the chunks, so a chunk's damage cannot vouch for itself. An unreadable
    manifest counts as empty; with ``repair`` (a build, not its planning) it is set aside
    (``*.damaged``) with a warning."""
    path = folder / MANIFEST
    try:
        data = json.loads(path.read_text())
        chunks = data["chunks"]
        if not isinstance(chunks, dict):
            raise TypeError("chunks is not a mapping")
        return chunks
    except FileNotFoundError:
        return {}
    except (OSError, ValueError, KeyError, TypeError) as err:
        if not repair:
            return {}
        aside = set_aside(path)
        log.warning("the chunk manifest %s is unreadable (%s); set aside as %s, its chunks are "
                    "computed again", path, err, aside.name)
        return {}


def record_chunk(folder: Path, name: str, entry: dict) -> None:
    """Put one finished chunk's entry into the manifest (read-modify-write under an exclusive
    ``flock`` of the folder, so parallel chunk jobs do not lose each other's entries; the file
    itself is replaced atomically)."""
    import fcntl

    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        chunks = read_manifest(folder, repair=True)
        chunks[name] = entry
        write_text(folder / MANIFEST, json.dumps({"chunks": chunks}, indent=1, sort_keys=True)
                   + "\n")
    finally:
        os.close(fd)  # also releases the flock


def chunk_state(folder: Path, chunk: int, digest: str, keep_signals: bool = False,
                manifest: dict[str, dict] | None = None) -> str:
    """``"done"`` (in the manifest with this config's hash and the file's sha256 matches it),
    ``"missing"`` (no file), ``"damaged"`` (recorded for this config, but its bytes, or its
    records', no longer match) or ``"stale"`` (not recorded for this config: another config's,
    or a killed job's)."""
    path = chunk_path(folder, chunk)
    if not path.is_file():
        return "missing"
    entry = (read_manifest(folder) if manifest is None else manifest).get(path.name)
    if not isinstance(entry, dict) or entry.get("hash") != digest:
        return "stale"
    try:
        if sha256_file(path) != entry.get("sha256"):
            return "damaged"
        if keep_signals:
            npy = path.with_suffix(".npy")
            if not entry.get("signals_sha256") or not npy.is_file():
                return "stale"  # computed without its records
            if sha256_file(npy) != entry["signals_sha256"]:
                return "damaged"
    except OSError:
        return "damaged"
    return "done"


def chunk_is_done(folder: Path, chunk: int, digest: str, keep_signals: bool = False) -> bool:
    return chunk_state(folder, chunk, digest, keep_signals) == "done"


def set_aside_damaged(folder: Path, chunks, digest: str, keep_signals: bool = False
                      ) -> list[int]:
    """Rename every damaged chunk of ``chunks`` (and its records) to ``*.damaged`` with a
    one-line warning naming it; returns those chunks (to be computed again)."""
    manifest = read_manifest(folder, repair=folder.is_dir())
    damaged = []
    for c in chunks:
        if chunk_state(folder, c, digest, keep_signals, manifest) != "damaged":
            continue
        path = chunk_path(folder, c)
        aside = [set_aside(p).name for p in (path, path.with_suffix(".npy")) if p.is_file()]
        log.warning("chunk %s does not match the sha256 the manifest %s holds for it (damaged "
                    "on disk); set aside as %s and computed again", path,
                    folder / MANIFEST, ", ".join(aside))
        damaged.append(c)
    return damaged


def lock_file(out: Path, name: str, chunk: int | None) -> Path:
    """The lock of a build: ``<out>/<name>.lock`` for a whole build, ``<out>/<name>.chunk_<i>
    .lock`` for one chunk's job (the jobs of one multirun run side by side)."""
    if chunk is None:
        return out / f"{name}.lock"
    return out / f"{name}.chunk_{chunk:03d}.lock"


def take_dataset_lock(out: Path, name: str, chunk: int | None, digest: str) -> Path:
    """Make this process the one writer of dataset ``<out>/<name>.parquet`` (of config hash
    ``digest``; ``chunk``: one chunk's job, None: the whole build), before any work.

    A conflict raises ValueError naming the other run's pid and its lock file; a lock left by
    a dead process is taken over with a warning (:func:`physics.files.take_lock`)."""
    what = f"the dataset {out / name}.parquet"
    own = take_lock(lock_file(out, name, chunk), what, {"digest": digest})
    stem = glob.escape(name)
    for other in sorted([*out.glob(f"{stem}.lock"), *out.glob(f"{stem}.chunk_*.lock")]):
        if other == own:
            continue
        holder = read_lock(other)
        if holder is None or not lock_is_live(holder):
            continue
        whole = other.name == f"{name}.lock"
        if chunk is None or whole or holder.get("digest") != digest:
            release_lock(own)
            raise ValueError(lock_message(other, holder, what))
    return own
