"""Measured-data bundles (``shared/specs/measured-bundle.md``): read, validate, write.

A bundle is a folder with ``manifest.csv`` (one row per record), ``signals/<record>.npy`` and
optionally ``gear.yaml`` (overrides of ``conf/gear``). :func:`read_bundle` refuses a bundle that
breaks a rule with one message naming the record and the rule, before anything is computed;
:func:`write_bundle` writes a complete bundle or nothing (a temporary folder renamed into place).
A feature table (a CSV with ``wear_mm`` and feature columns, like thesis Table 15) is the other
accepted form (:func:`read_feature_table`).
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

REQUIRED = ("record", "quantity", "fs_hz", "n1_rpm", "torque_Nm", "wear_mm", "cycles", "split")
QUANTITIES = ("dte_m", "accel_m_s2")
_NAME = re.compile(r"^[A-Za-z0-9_-]+$")


@dataclass(frozen=True)
class Bundle:
    path: Path
    manifest: pd.DataFrame
    signals: dict[str, np.ndarray]
    gear: dict

    @property
    def records(self) -> list[str]:
        return self.manifest.record.tolist()


def _fail(path: Path, record: str | None, rule: str) -> ValueError:
    where = f"record {record!r}" if record is not None else "manifest.csv"
    return ValueError(f"bundle {path}: {where}: {rule}")


def read_bundle(path: str | Path, z1: int = 18) -> Bundle:
    """Read and validate a bundle; ``z1`` (pinion teeth, from the gear config) sets the
    sampling-rate rule fs >= 4 x the third mesh harmonic."""
    path = Path(path)
    if not (path / "manifest.csv").is_file():
        raise ValueError(f"bundle {path}: manifest.csv is missing (see "
                         "shared/specs/measured-bundle.md)")
    man = pd.read_csv(path / "manifest.csv", dtype={"record": str, "quantity": str,
                                                    "split": str})
    missing = [c for c in REQUIRED if c not in man.columns]
    if missing:
        raise _fail(path, None, f"column(s) {missing} missing; required: {list(REQUIRED)}")
    if man.empty:
        raise _fail(path, None, "no records")
    dup = man.record[man.record.duplicated()].tolist()
    if dup:
        raise _fail(path, dup[0], "record names must be unique")
    gear = {}
    if (path / "gear.yaml").is_file():
        gear = yaml.safe_load((path / "gear.yaml").read_text()) or {}
        z1 = int(gear.get("z1", z1))
    signals = {}
    for row in man.itertuples(index=False):
        rec = str(row.record)
        if not _NAME.match(rec):
            raise _fail(path, rec, "names use letters, digits, '_' and '-' only")
        if row.quantity not in QUANTITIES:
            raise _fail(path, rec, f"quantity {row.quantity!r} is not one of {QUANTITIES}")
        for col in ("fs_hz", "n1_rpm", "torque_Nm"):
            v = getattr(row, col)
            if not (isinstance(v, int | float) and np.isfinite(v) and v > 0):
                raise _fail(path, rec, f"{col} = {v!r} must be a positive number")
        for col in ("wear_mm", "cycles"):
            v = getattr(row, col)
            if not pd.isna(v) and not (isinstance(v, int | float) and v >= 0):
                raise _fail(path, rec, f"{col} = {v!r} must be empty or >= 0")
        if not pd.isna(row.split) and row.split not in ("train", "test"):
            raise _fail(path, rec, f"split {row.split!r} must be train, test or empty")
        f = path / "signals" / f"{rec}.npy"
        if not f.is_file():
            raise _fail(path, rec, f"signals/{rec}.npy is missing")
        x = np.load(f, allow_pickle=False)
        if x.ndim != 1:
            raise _fail(path, rec, f"the signal must be 1-D, not of shape {x.shape}")
        if not np.all(np.isfinite(x)):
            raise _fail(path, rec, f"non-finite sample at index {int(np.argmin(np.isfinite(x)))}")
        revs = x.size / row.fs_hz * row.n1_rpm / 60
        if revs < 10:
            raise _fail(path, rec, f"{revs:.1f} pinion revolutions; at least 10 are needed")
        f_need = 4 * 3 * z1 * row.n1_rpm / 60
        if row.fs_hz < f_need:
            raise _fail(path, rec, f"fs_hz = {row.fs_hz:g} is below 4 x the third mesh "
                                   f"harmonic ({f_need:g} Hz)")
        signals[rec] = x.astype(float)
    return Bundle(path, man, signals, gear)


def write_bundle(path: str | Path, manifest: pd.DataFrame, signals: dict[str, np.ndarray],
                 gear: dict | None = None) -> Path:
    """Write a complete bundle at ``path`` (replacing one there) or nothing."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    try:
        (tmp / "signals").mkdir()
        manifest.to_csv(tmp / "manifest.csv", index=False)
        for name, x in signals.items():
            np.save(tmp / "signals" / f"{name}.npy", np.asarray(x, float))
        if gear:
            (tmp / "gear.yaml").write_text(yaml.safe_dump(gear))
        if path.exists():
            shutil.rmtree(path)
        os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return path


def read_feature_table(path: str | Path) -> pd.DataFrame:
    """A feature table: ``wear_mm`` plus feature columns (units in the names, as Table 15)."""
    path = Path(path)
    df = pd.read_csv(path)
    if "wear_mm" not in df.columns or df.shape[1] < 2:
        raise ValueError(f"feature table {path}: needs a wear_mm column and feature columns")
    if not np.all(np.isfinite(df.select_dtypes("number").to_numpy())):
        raise ValueError(f"feature table {path}: every value must be finite")
    return df
