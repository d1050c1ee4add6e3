"""Measured-data bundles (``docs/own-data.md``): read, validate, write.

A bundle is a folder with ``manifest.csv`` (one row per record), ``signals/<record>.npy`` and
optionally ``gear.yaml`` (overrides of ``conf/physics/gear``). :func:`read_bundle` refuses a
bundle that breaks a rule with one message naming the record and the rule, before anything is
computed;
:func:`write_bundle` writes a complete bundle or nothing (a temporary folder renamed into place).
A feature table (a CSV with ``wear_mm`` and feature columns, like thesis Table 15) is the other
accepted form (:func:`read_feature_table`), with an optional ``gear.yaml`` and ``operating.yaml``
beside it (:class:`FeatureTable`).
"""

from __future__ import annotations

import dataclasses
import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from omegaconf import OmegaConf
from omegaconf.errors import OmegaConfBaseException

from physics.params import GearPair, Operating, Scenario
from physics.scope import check_scope
from physics.tribology.asperity_table import check_scenario

REQUIRED = ("record", "quantity", "fs_hz", "n1_rpm", "torque_Nm", "wear_mm", "cycles", "split")
QUANTITIES = ("dte_m", "accel_m_s2")
#: optional columns that set a record's lubricant or roughness
OPTIONAL_NUMERIC = ("eta0_Pa_s", "sigma_um")
_NAME = re.compile(r"^[A-Za-z0-9_-]+$")
#: what a manifest's torque_Nm cell or a gear.yaml value may say where it is not known
UNKNOWN = ("", "unknown", "null", "none", "nan", "na")
#: the gear data the signature needs (its orders): never unknown
SIGNATURE_GEAR = ("z1", "z2")
#: the largest gear.yaml read (a gear pair's overrides are a few hundred bytes)
MAX_YAML_BYTES = 64 * 1024
#: the most the records of one bundle may take in memory together, as float64
MAX_RECORDS_BYTES = 2 * 1024**3


@dataclass(frozen=True)
class Bundle:
    path: Path
    manifest: pd.DataFrame
    signals: dict[str, np.ndarray]
    gear: dict
    #: gear.yaml keys stated as unknown: the configured pair's values are used
    unknown_gear: tuple[str, ...] = ()

    @property
    def records(self) -> list[str]:
        return self.manifest.record.tolist()


@dataclass(frozen=True)
class FeatureTable:
    """A feature table (:func:`read_feature_table`) and what the ``gear.yaml`` and
    ``operating.yaml`` beside it state: their overrides of the configured pair and operating
    point, and the keys they state as unknown (a gear key: the configured value stands in;
    ``torque_Nm``: calibrated as a nuisance, docs/loop.md)."""

    path: Path | None  # None: a data frame given in Python
    frame: pd.DataFrame
    stated: dict
    unknown: tuple[str, ...] = ()

    @property
    def torque_unknown(self) -> bool:
        return "torque_Nm" in self.unknown


def _fail(path: Path, record: str | None, rule: str) -> ValueError:
    where = f"record {record!r}" if record is not None else "manifest.csv"
    return ValueError(f"bundle {path}: {where}: {rule}")


def read_bundle(path: str | Path, gear: GearPair | None = None) -> Bundle:
    """Read and validate a bundle; ``gear`` is the configured pair, to which the bundle's
    ``gear.yaml`` applies its overrides (its ``z1`` sets the sampling-rate rule fs >= 4 x the
    third mesh harmonic). ``Bundle.gear`` holds the overrides."""
    path = Path(path)
    gear = gear if gear is not None else GearPair()
    if not path.is_dir():
        raise ValueError(f"bundle {path}: no such folder (see docs/own-data.md)")
    man = _read_manifest(path)
    overrides, unknown = _read_gear(path, gear, f"bundle {path}")
    z1 = dataclasses.replace(gear, **overrides).z1
    sizes = {rec: _signal_size(path, rec) for rec in man.record}
    total = sum(sizes.values()) * 8
    if total > MAX_RECORDS_BYTES:
        raise _fail(path, None, f"the records hold {sum(sizes.values()):,} samples together, "
                                f"{total / 1e9:.3g} GB as float64, above the limit of "
                                f"{MAX_RECORDS_BYTES / 1e9:.3g} GB; split the bundle or "
                                "shorten its records")
    signals = {}
    for row in man.itertuples(index=False):
        rec = row.record
        x = _read_signal(path, rec)
        revs = x.size / row.fs_hz * row.n1_rpm / 60
        if revs < 10:
            raise _fail(path, rec, f"{revs:.1f} pinion revolutions; at least 10 are needed")
        f_need = 4 * 3 * z1 * row.n1_rpm / 60
        if row.fs_hz < f_need:
            raise _fail(path, rec, f"fs_hz = {row.fs_hz:g} is below 4 x the third mesh "
                                   f"harmonic ({f_need:g} Hz)")
        signals[rec] = x
    return Bundle(path, man, signals, overrides, unknown)


def _read_manifest(path: Path) -> pd.DataFrame:
    """manifest.csv with every cell checked; a bad cell is reported against its own record."""
    f = path / "manifest.csv"
    if not f.is_file():
        raise ValueError(f"bundle {path}: manifest.csv is missing (see "
                         "docs/own-data.md)")
    try:
        man = pd.read_csv(f, dtype=str, keep_default_na=False)
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as err:
        raise _fail(path, None, f"not a readable CSV table ({err}); one header line and one "
                                "row per record are needed") from None
    missing = [c for c in REQUIRED if c not in man.columns]
    if missing:
        raise _fail(path, None, f"column(s) {missing} missing; required: {list(REQUIRED)}")
    if man.empty:
        raise _fail(path, None, "no records; add one row per record")
    man["record"] = man.record.str.strip()
    dup = man.record[man.record.duplicated()].tolist()
    if dup:
        raise _fail(path, dup[0], "record names must be unique")
    for rec in man.record:
        if not _NAME.match(rec):
            raise _fail(path, rec, "names use letters, digits, '_' and '-' only")
    numeric = {"fs_hz": False, "n1_rpm": False, "torque_Nm": None, "wear_mm": True,
               "cycles": True} | {c: True for c in OPTIONAL_NUMERIC if c in man.columns}
    for col, may_be_empty in numeric.items():
        text = man[col].str.strip()
        if may_be_empty is None:  # the torque: a positive number or unknown
            text = text.where(~text.str.lower().isin(UNKNOWN), "")
        values = pd.to_numeric(text.where(text != ""), errors="coerce")
        for rec, s, v in zip(man.record, text, values, strict=True):
            if s == "" and may_be_empty is not False:
                continue
            shown = repr(float(v)) if np.isfinite(v) else repr(s)
            if may_be_empty is None:
                if not (np.isfinite(v) and v > 0):
                    raise _fail(path, rec, f"{col} = {shown} must be a positive number, or "
                                           "empty or 'unknown' where it is not known (then "
                                           "calibrated: docs/loop.md)")
            elif may_be_empty:
                if not (np.isfinite(v) and v >= 0):
                    raise _fail(path, rec, f"{col} = {shown} must be empty or a number >= 0")
            elif not (np.isfinite(v) and v > 0):
                raise _fail(path, rec, f"{col} = {shown} must be a positive number")
        man[col] = values
    for rec, q, s in zip(man.record, man.quantity.str.strip(), man.split.str.strip(),
                         strict=True):
        if q not in QUANTITIES:
            raise _fail(path, rec, f"quantity {q!r} is not one of {QUANTITIES}")
        if s not in ("train", "test", ""):
            raise _fail(path, rec, f"split {s!r} must be train, test or empty")
    man["quantity"] = man.quantity.str.strip()
    man["split"] = man.split.str.strip().replace("", np.nan)
    return man


def _read_gear(path: Path, gear: GearPair, where: str) -> tuple[dict, tuple[str, ...]]:
    """The overrides of ``gear.yaml`` in the folder ``path``, checked by building the pair they
    give, and the keys it states as unknown (null or ``unknown``: the configured pair's values
    stand in; not the signature's :data:`SIGNATURE_GEAR`)."""
    return _read_sidecar(path / "gear.yaml", gear, where, {
        k: f"the tooth numbers {SIGNATURE_GEAR} set the orders of the signature and cannot be "
           "unknown; count them, or leave the key out to use the configured pair's"
        for k in SIGNATURE_GEAR})


def _read_operating(path: Path, operating: Operating, where: str) -> tuple[dict, tuple[str, ...]]:
    """The overrides of ``operating.yaml`` beside a feature table, checked by building the
    operating point they give, and whether it states the torque unknown (calibrated then:
    ``torque_factor`` of :data:`physics.loop.model.declared.TORQUE`, around the configured
    torque); the speed and the bulk temperature must be stated or left out."""
    return _read_sidecar(path / "operating.yaml", operating, where, {
        k: "only torque_Nm may be unknown (the loop calibrates it); state this one, or leave "
           "the key out to use the configured value" for k in ("n1_rpm", "bulk_temperature_K")})


def _read_sidecar(f: Path, current, where: str, stated: dict[str, str]
                  ) -> tuple[dict, tuple[str, ...]]:
    """The overrides of the YAML file ``f`` of the dataclass ``current``'s keys (none if there
    is no such file), checked by building the value they give, and the keys it states as
    unknown (``stated``: the keys that may not be unknown, each with the reason)."""
    if not f.is_file():
        return {}, ()
    name = f.name
    size = f.stat().st_size
    if size > MAX_YAML_BYTES:
        raise ValueError(f"{where}: {name} holds {size:,} bytes, above the limit of "
                         f"{MAX_YAML_BYTES:,}; it maps a few keys to values")
    try:
        text = f.read_text()
        _plain_yaml(text, name)  # raises ValueError
        # OmegaConf's YAML reads 4.9e4 as a number (PyYAML's YAML 1.1 reads a string)
        overrides = OmegaConf.to_container(OmegaConf.create(text or "{}"))
    except (yaml.YAMLError, UnicodeDecodeError, OmegaConfBaseException) as err:
        text = " ".join(str(err).split())
        raise ValueError(f"{where}: {name} is not readable YAML ({text})") from None
    except ValueError as err:  # an anchor, alias or tag
        raise ValueError(f"{where}: {err}") from None
    known = {f.name for f in dataclasses.fields(current)}
    if not isinstance(overrides, dict):
        raise ValueError(f"{where}: {name} must map keys ({sorted(known)}) to values")
    unknown = sorted(set(overrides) - known)
    if unknown:
        raise ValueError(f"{where}: {name}: unknown key(s) {unknown}; allowed: "
                         f"{sorted(known)}")
    missing = tuple(k for k, v in overrides.items()
                    if v is None or (isinstance(v, str) and v.strip().lower() in UNKNOWN))
    for k in missing:
        if k in stated:
            raise ValueError(f"{where}: {name}: {k} = {overrides[k]!r}: {stated[k]}")
        del overrides[k]
    try:
        dataclasses.replace(current, **overrides)
    except ValueError as err:
        raise ValueError(f"{where}: {name}: {err}") from None
    return overrides, missing


def _plain_yaml(text: str, name: str) -> None:
    """Refuse YAML anchors, aliases and tags (an alias bomb expands a few lines into billions
    of nodes; a tag builds objects): scanned token by token, nothing is expanded."""
    for token in yaml.scan(text, Loader=yaml.SafeLoader):
        if isinstance(token, (yaml.AnchorToken, yaml.AliasToken, yaml.TagToken)):
            kind = {yaml.AnchorToken: "anchors (&)", yaml.AliasToken: "aliases (*)",
                    yaml.TagToken: "tags (!)"}[type(token)]
            line = token.start_mark.line + 1
            raise ValueError(f"{name} line {line}: YAML {kind} are not accepted; write "
                             "each value out")


def _npy_header(f: Path) -> tuple[tuple[int, ...], np.dtype, int]:
    """Shape, dtype and data offset of a .npy file, read from its header alone."""
    fmt = np.lib.format
    with f.open("rb") as fp:
        version = fmt.read_magic(fp)
        if version == (1, 0):
            shape, _, dtype = fmt.read_array_header_1_0(fp)
        elif version == (2, 0):
            shape, _, dtype = fmt.read_array_header_2_0(fp)
        else:
            raise ValueError(f"npy format version {version} is not supported; save it with "
                             "numpy.save")
        return shape, dtype, fp.tell()


def _signal_size(path: Path, rec: str) -> int:
    """The samples of record ``rec`` by its header, checked against the file's size before
    anything is loaded."""
    f = path / "signals" / f"{rec}.npy"
    if not f.is_file():
        raise _fail(path, rec, f"signals/{rec}.npy is missing")
    try:
        shape, dtype, offset = _npy_header(f)
    except (ValueError, OSError, EOFError) as err:
        raise _fail(path, rec, f"signals/{rec}.npy is not a numpy .npy array of numbers "
                               f"({err}); save it with numpy.save") from None
    if dtype.kind not in "iuf":
        raise _fail(path, rec, f"signals/{rec}.npy holds {dtype} values; numbers are needed")
    count = int(np.prod(shape, dtype=object))
    claimed, held = count * dtype.itemsize, f.stat().st_size - offset
    if claimed != held:
        raise _fail(path, rec, f"signals/{rec}.npy: its header claims shape {shape} of {dtype} "
                               f"({claimed:,} bytes) but the file holds {held:,} bytes of data; "
                               "it is damaged or truncated: save it again with numpy.save")
    return count


def _read_signal(path: Path, rec: str) -> np.ndarray:
    f = path / "signals" / f"{rec}.npy"
    if not f.is_file():
        raise _fail(path, rec, f"signals/{rec}.npy is missing")
    try:
        x = np.load(f, allow_pickle=False)
    except (ValueError, OSError, EOFError) as err:
        raise _fail(path, rec, f"signals/{rec}.npy is not a numpy .npy array of numbers "
                               f"({err}); save it with numpy.save") from None
    if x.dtype.kind not in "iuf":
        raise _fail(path, rec, f"signals/{rec}.npy holds {x.dtype} values; numbers are needed")
    if x.ndim != 1:
        raise _fail(path, rec, f"the signal must be 1-D, not of shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise _fail(path, rec, f"non-finite sample at index {int(np.argmin(np.isfinite(x)))}")
    return x.astype(float)


def record_scenario(base: Scenario, row) -> Scenario:
    """The scenario of one manifest row: its speed, torque (the configured one where the
    manifest leaves it unknown) and, where given, lubricant viscosity and roughness."""
    torque = float(row.torque_Nm)
    op = dataclasses.replace(base.operating, n1_rpm=float(row.n1_rpm),
                             torque_Nm=torque if np.isfinite(torque) else
                             base.operating.torque_Nm)
    lub, tri = base.lubricant, base.tribology
    if "eta0_Pa_s" in row._fields and not pd.isna(row.eta0_Pa_s):
        lub = dataclasses.replace(lub, eta0_Pa_s=float(row.eta0_Pa_s))
    if "sigma_um" in row._fields and not pd.isna(row.sigma_um):
        tri = dataclasses.replace(tri, sigma_um=float(row.sigma_um))
    return dataclasses.replace(base, operating=op, lubricant=lub, tribology=tri)


def read_measurements(path: str | Path, base: Scenario
                      ) -> tuple[Bundle | FeatureTable, Scenario]:
    """The bundle (a folder) or feature table (a .csv file) at ``path`` and the scenario with
    the bundle's gear overrides (a table's: those of the ``gear.yaml`` and ``operating.yaml``
    beside it); every record's scenario is checked against the model's scope. Refuses a bad
    input before any work."""
    path = Path(path)
    if path.is_dir():
        bundle = read_bundle(path, base.gear)
        scn = dataclasses.replace(base, gear=dataclasses.replace(base.gear, **bundle.gear))
        for row in bundle.manifest.itertuples(index=False):
            try:
                check_scenario(check_scope(record_scenario(scn, row)))
            except ValueError as err:
                raise _fail(path, row.record, str(err)) from None
        return bundle, scn
    if path.is_file() and path.suffix == ".csv":
        where = f"feature table {path}"
        gear, unknown_gear = _read_gear(path.parent, base.gear, where)
        op, unknown_op = _read_operating(path.parent, base.operating, where)
        scn = dataclasses.replace(base, gear=dataclasses.replace(base.gear, **gear),
                                  operating=dataclasses.replace(base.operating, **op))
        table = FeatureTable(path, read_feature_table(path), gear | op,
                             unknown_gear + unknown_op)
        return table, check_scenario(check_scope(scn))
    raise ValueError(f"data = {str(path)!r} is neither a bundle folder nor a feature-table .csv "
                     "file; see docs/own-data.md")


def write_bundle(path: str | Path, manifest: pd.DataFrame, signals: dict[str, np.ndarray],
                 gear: dict | None = None) -> Path:
    """Write a complete bundle at ``path`` (replacing one there) or nothing. Its folders and
    files get the usual permissions (0o755 / 0o644 under the usual umask), not the temporary
    folder's 0o700: a bundle is shared with the group that reads it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    umask = os.umask(0)
    os.umask(umask)
    try:
        (tmp / "signals").mkdir()
        manifest.to_csv(tmp / "manifest.csv", index=False)
        for name, x in signals.items():
            np.save(tmp / "signals" / f"{name}.npy", np.asarray(x, float))
        if gear:
            (tmp / "gear.yaml").write_text(yaml.safe_dump(gear))
        for p in (tmp, *tmp.rglob("*")):
            os.chmod(p, (0o777 if p.is_dir() else 0o666) & ~umask)
        if path.exists():
            shutil.rmtree(path)
        os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return path


def check_not_own_reference(data: str | Path, reference: str | Path) -> None:
    """Refuse a bundle given as its own reference (``reference=`` the same folder as ``data=``,
    after resolving links and relative paths): a reference is a sister gearbox's bundle."""
    if Path(data).resolve() == Path(reference).resolve():
        raise ValueError(f"reference={reference} is the bundle data={data} itself (same folder "
                         f"{Path(data).resolve()}); a reference is another gearbox's bundle: "
                         "give that one, or leave out reference=")


def read_feature_table(path: str | Path) -> pd.DataFrame:
    """A feature table: ``wear_mm`` plus feature columns (units in the names, as Table 15);
    a bad cell is reported with its row and column."""
    path = Path(path)
    try:
        df = pd.read_csv(path)
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as err:
        raise ValueError(f"feature table {path}: not a readable CSV table ({err})") from None
    if "wear_mm" not in df.columns or df.shape[1] < 2 or df.empty:
        raise ValueError(f"feature table {path}: needs a wear_mm column, feature columns and "
                         "at least one row")
    for col in df.columns:
        values = pd.to_numeric(df[col], errors="coerce")
        bad = ~np.isfinite(values.to_numpy(float))
        if bad.any():
            row = int(np.argmax(bad))
            raise ValueError(f"feature table {path}: row {row + 1}, column {col!r}: "
                             f"{df[col].iloc[row]!r} is not a finite number")
        df[col] = values
    wear = df["wear_mm"].to_numpy(float)
    out = (wear < 0) | (wear > 10)
    if out.any():
        row = int(np.argmax(out))
        raise ValueError(f"feature table {path}: row {row + 1}, column 'wear_mm' = "
                         f"{wear[row]:g} lies outside [0, 10] mm, what a wear depth can be; give "
                         "it in mm")
    return df
