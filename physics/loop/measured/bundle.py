"""Measured-data bundles (``docs/own-data.md``): read, validate, write.

A bundle is a folder with ``manifest.csv`` (one row per record), ``signals/<record>.npy`` and
optionally ``gear.yaml`` (overrides of ``conf/physics/gear``). :func:`read_bundle` refuses a
bundle that breaks a rule with one message naming the record and the rule, before anything is
computed;
:func:`write_bundle` writes a complete bundle or nothing (a temporary folder renamed into place)
and replaces an earlier bundle only, never a folder holding anything else
(:func:`check_bundle_target`).
A feature table (a CSV with ``wear_mm`` and feature columns, like thesis Table 15) is the other
accepted form (:func:`read_feature_table`), with an optional ``gear.yaml`` and ``operating.yaml``
beside it (:class:`FeatureTable`).
"""

from __future__ import annotations

import dataclasses
import logging
import os
import re
import shutil
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from omegaconf import OmegaConf
from omegaconf.errors import OmegaConfBaseException

from physics.arguments import argument, path_argument
from physics.files import file_problem, repeated_header
from physics.params import GearPair, Operating, Scenario
from physics.scope import check_scope
from physics.signals.shaft_speed import (
    MIN_COMB_DB,
    MIN_LINES,
    MIN_MARGIN_DB,
    SpeedEstimate,
    pinion_speed,
)
from physics.tribology.asperity_table import check_scenario

log = logging.getLogger(__name__)

REQUIRED = ("record", "quantity", "fs_hz", "n1_rpm", "torque_Nm", "wear_mm", "cycles", "split")
QUANTITIES = ("dte_m", "accel_m_s2")
#: optional columns that set a record's lubricant or roughness
OPTIONAL_NUMERIC = ("eta0_Pa_s", "sigma_um")
_NAME = re.compile(r"^[A-Za-z0-9_-]+$")
#: what a manifest's n1_rpm or torque_Nm cell or a sidecar's value may say where it is not known
UNKNOWN = ("", "unknown", "null", "none", "nan", "na")
#: relative spread within which the speeds read off records of one stated torque are one
#: operating point (their median): the loop's highest lines (0.45 fs) then
#: lie within a tenth of a bin of a 0.25 s segment (4 Hz) at 41 kHz; the readings of one
#: speed agree far closer (tests/signals/test_shaft_speed.py)
SAME_SPEED = 2e-5
#: the gear data the signature needs (its orders): never unknown
SIGNATURE_GEAR = ("z1", "z2")
#: the largest gear.yaml read (a gear pair's overrides are a few hundred bytes)
MAX_YAML_BYTES = 64 * 1024
#: the most the records of one bundle may take in memory together, as float64
MAX_RECORDS_BYTES = 2 * 1024**3
#: the most samples one record may hold. The loop analyses every segment of ``loop.segment_s``
#: of a record at once (:func:`physics.signals.order_analysis.signature_segments`) and its noise
#: floor over the whole record (``white_noise_std``): about 90 bytes of working memory a sample
#: beyond the record's own 8 (measured: 1.2 GB more for 1.6e7 samples; a record of 1e8 took
#: 8 GB). 2**24 samples keep one record's analysis near 1.5 GB and are 336 s at 50 kHz, 1342
#: segments of 0.25 s: the scatter between segments, the comparison's noise, is known to 2 %
#: long before (its relative standard error is 1 / sqrt(2 (n - 1))); the model simulates one
#: segment a record whatever its length
MAX_RECORD_SAMPLES = 2**24
#: standard gravity [m/s^2] (3rd CGPM, 1901; ISO 80000-3), the unit accelerometers are read in
STANDARD_GRAVITY = 9.80665
#: the largest RMS (about the mean) a housing acceleration [m/s^2] can have: 500 g. An IEPE
#: (ICP) accelerometer's output swings at most +-5 V about its bias (PCB Piezotronics, "ICP &
#: charge accelerometers" fundamentals: full-scale output +-5 V), so at the least sensitive
#: industrial grade, 10 mV/g (the usual 100 mV/g gives +-50 g), it saturates at +-500 g; a
#: record's RMS never exceeds its largest |sample|, so no record of such a sensor has an RMS
#: above 500 g. A running gearbox's housing is far below: vibration severity (ISO 20816-1 and
#: -3, formerly ISO 10816) stops a machine at tens of mm/s RMS of housing velocity over
#: 10-1000 Hz (zone D; 0.1 m/s at 1 kHz is 6e2 m/s^2). A record above is not in m/s^2
#: (mm/s^2 are 1e-3 m/s^2; raw ADC counts)
MAX_ACCEL_RMS = 500 * STANDARD_GRAVITY
#: the largest |DTE| [m], as a share of the module: the DTE along the line of action is the
#: tooth pair's elastic deflection (its mean: ~1e-5 m at rated load, a tooth that deflected a
#: good share of its module would break), its profile and pitch errors (ISO 1328-1's coarsest
#: grade allows total deviations of ~0.1 mm at module 2) and, where the flanks part, the
#: backlash (~0.04-0.1 module); a tenth of the module (0.2 mm at module 2) is beyond them
#: together: a DTE above is not in metres (um or mm given as m) or holds the encoders' offset
MAX_DTE_MODULES = 0.1


@dataclass(frozen=True)
class Bundle:
    path: Path
    manifest: pd.DataFrame
    signals: dict[str, np.ndarray]
    gear: dict
    #: gear.yaml keys stated as unknown: the configured pair's values are used
    unknown_gear: tuple[str, ...] = ()
    #: the records whose manifest left ``n1_rpm`` unknown: each one's speed as read off its
    #: spectrum (:func:`physics.signals.shaft_speed.pinion_speed`); the manifest holds the
    #: speed of its operating point (:func:`estimate_speeds`)
    speeds: dict[str, SpeedEstimate] = dataclasses.field(default_factory=dict)

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

    @property
    def speed_unknown(self) -> bool:
        return "n1_rpm" in self.unknown


def _fail(path: Path, record: str | None, rule: str) -> ValueError:
    where = f"record {record!r}" if record is not None else "manifest.csv"
    return ValueError(f"bundle {path}: {where}: {rule}")


def read_bundle(path: str | Path, gear: GearPair | None = None) -> Bundle:
    """Read and validate a bundle; ``gear`` is the configured pair, to which the bundle's
    ``gear.yaml`` applies its overrides (its ``z1`` sets the sampling-rate rule fs >= 4 x the
    third mesh harmonic). ``Bundle.gear`` holds the overrides."""
    path = path_argument(path, "read_bundle(path)", "a bundle folder")
    gear = argument(gear, "read_bundle(gear)", (GearPair, type(None)),
                    "a GearPair or None (the configured pair)")
    gear = gear if gear is not None else GearPair()
    if not path.is_dir():
        raise ValueError(f"bundle {path}: no such folder (see docs/own-data.md)")
    man = _read_manifest(path)
    overrides, unknown = _read_gear(path, gear, f"bundle {path}")
    pair = dataclasses.replace(gear, **overrides)
    z1 = pair.z1
    sizes = {rec: _signal_size(path, rec, fs)
             for rec, fs in zip(man.record, man.fs_hz, strict=True)}
    total = sum(sizes.values()) * 8
    if total > MAX_RECORDS_BYTES:
        raise _fail(path, None, f"the records hold {sum(sizes.values()):,} samples together, "
                                f"{total / 1e9:.3g} GB as float64, above the limit of "
                                f"{MAX_RECORDS_BYTES / 1e9:.3g} GB; split the bundle or "
                                "shorten its records")
    signals = {}
    for row in man.itertuples(index=False):
        signals[row.record] = _read_signal(path, row.record)
        check_values(path, row.record, row.quantity, signals[row.record], pair.module_mm)
    speeds = estimate_speeds(path, man, signals, pair)
    for row in man.itertuples(index=False):
        rec = row.record
        x = signals[rec]
        revs = x.size / row.fs_hz * row.n1_rpm / 60
        if revs < 10:
            raise _fail(path, rec, f"{revs:.1f} pinion revolutions; at least 10 are needed")
        f_need = 4 * 3 * z1 * row.n1_rpm / 60
        if row.fs_hz < f_need:
            raise _fail(path, rec, f"fs_hz = {row.fs_hz:g} is below 4 x the third mesh "
                                   f"harmonic ({f_need:g} Hz)")
    return Bundle(path, man, signals, overrides, unknown, speeds)


def estimate_speeds(path: Path, man: pd.DataFrame, signals: dict[str, np.ndarray],
                    pair: GearPair) -> dict[str, SpeedEstimate]:
    """Read the pinion speed of each record whose ``n1_rpm`` the manifest leaves unknown off
    its spectrum (:func:`physics.signals.shaft_speed.pinion_speed`), sought between the
    slowest speed its length holds 10 revolutions of and the fastest its sampling rate
    resolves (``fs >= 12 z1 n1 / 60``), the bundle's own rules. Records of one stated torque
    (or all of unknown torque) whose speeds agree within :data:`SAME_SPEED` form one
    operating point at their median, written into ``man.n1_rpm``; each record's own reading
    is returned. A record whose spectrum holds no clear mesh comb, or too short a record for
    any speed its rate resolves, is refused, naming what was found."""
    speeds: dict[str, SpeedEstimate] = {}
    unknown = ~np.isfinite(man.n1_rpm.to_numpy(float))
    for row in man[unknown].itertuples(index=False):
        x, fs = signals[row.record], float(row.fs_hz)
        f_low, f_high = 10 * fs / x.size, fs / (12 * pair.z1)
        if f_low >= f_high:
            raise _fail(path, row.record,
                        f"n1_rpm unknown: {x.size} samples at fs_hz = {fs:g} hold 10 pinion "
                        f"revolutions only above {60 * f_low:.4g} r/min, and the rate resolves "
                        f"the third mesh harmonic only below {60 * f_high:.4g} r/min; give "
                        "n1_rpm or a longer record")
        est = pinion_speed(x, fs, pair.z1, f_low, f_high)
        if not est.clear:
            raise _fail(path, row.record,
                        f"n1_rpm unknown and no clear mesh comb of z1 = {pair.z1} in its "
                        f"spectrum between {60 * f_low:.4g} and {60 * f_high:.4g} r/min: the "
                        f"best, at {est.rpm:.6g} r/min, has {est.lines} lines among its "
                        f"harmonics, {est.comb_db:.1f} dB over the floor, the next speed "
                        f"({est.runner_up_rpm:.6g} r/min) {est.runner_up_db:.1f} dB (needed: "
                        f"{MIN_LINES} lines, {MIN_COMB_DB:g} dB, a lead of {MIN_MARGIN_DB:g} "
                        "dB); give n1_rpm, or check z1 in gear.yaml")
        speeds[row.record] = est
    if speeds:
        torque = man.torque_Nm.astype(float).fillna(-1.0)  # -1: unknown
        for _, rows in man[unknown].groupby(torque[unknown], sort=False):
            read = pd.Series({r: speeds[r].rpm for r in rows.record}).sort_values()
            # a new operating point wherever the next reading lies beyond SAME_SPEED
            point = (read.pct_change().fillna(0.0) > SAME_SPEED).cumsum()
            for _, members in read.groupby(point):
                man.loc[man.record.isin(members.index), "n1_rpm"] = float(members.median())
    return speeds


def check_values(path: Path, rec: str, quantity: str, x: np.ndarray, module_mm: float) -> None:
    """Refuse a record whose samples its declared quantity cannot hold: constant throughout (a
    sensor stuck or not connected), a housing acceleration of RMS above :data:`MAX_ACCEL_RMS`
    or a DTE beyond :data:`MAX_DTE_MODULES` of the module (not in the declared unit); one line
    naming the record, the value, the rule and the likely mistake."""
    lo, hi = float(np.min(x)), float(np.max(x))
    if hi - lo <= 1e-12 * max(abs(lo), abs(hi), np.finfo(float).tiny):
        raise _fail(path, rec, f"every sample is {lo:g}: a constant record (a sensor stuck, "
                               "not connected or not recorded) has no vibration to compare; "
                               "leave it out or record it again")
    unit = "m/s^2" if quantity == "accel_m_s2" else "m"
    if np.all(x == np.round(x)):
        raise _fail(path, rec, f"every sample of this {quantity} record is a whole number "
                               f"(RMS {float(np.std(x)):.3g}): quantised at 1 {unit}, it is raw "
                               "ADC counts, not " + unit + ": scale them by the converter's "
                               "volts per count and the sensor's sensitivity")
    if quantity == "accel_m_s2":
        rms = float(np.std(x))
        if rms > MAX_ACCEL_RMS:
            raise _fail(path, rec, f"accel_m_s2 of RMS {rms:.3g} m/s^2 lies above "
                                   f"{MAX_ACCEL_RMS:.4g} m/s^2 (500 g), beyond any gearbox "
                                   "housing's vibration and any industrial accelerometer's "
                                   "range (IEPE sensors saturate at 50-500 g; ISO 20816 stops a "
                                   "machine at tens of mm/s): the signal is not in m/s^2 "
                                   "(mm/s^2 are 1e-3 m/s^2; raw ADC counts?)")
    else:
        peak, limit = max(abs(lo), abs(hi)), MAX_DTE_MODULES * module_mm * 1e-3
        if peak > limit:
            raise _fail(path, rec, f"dte_m reaches {peak:.3g} m, above {limit:.3g} m, a tenth "
                                   f"of the module ({module_mm:g} mm), beyond any tooth "
                                   "deflection, profile error and backlash together: the signal "
                                   "is not in metres (um are 1e-6 m, mm 1e-3 m), or it "
                                   "holds the encoders' angle offset (its mean is the static "
                                   "deflection, some um)")


def _regular(path: Path, rec: str | None, f: Path, fix: str) -> None:
    """Refuse ``f`` (a file of the bundle at ``path``) unless it is an existing regular file:
    missing, a folder, or a FIFO or device (reading it waits or never ends) is said so."""
    what = file_problem(f, missing="is missing")
    if what is None:
        return
    name = f.relative_to(path) if f.is_relative_to(path) else f
    if rec is None:
        raise ValueError(f"bundle {path}: {name} {what}; {fix}")
    raise _fail(path, rec, f"{name} {what}; {fix}")


def _read_manifest(path: Path) -> pd.DataFrame:
    """manifest.csv with every cell checked; a bad cell is reported against its own record."""
    f = path / "manifest.csv"
    _regular(path, None, f, "it lists the records (see docs/own-data.md)")
    try:
        man = pd.read_csv(f, dtype=str, keep_default_na=False)
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as err:
        raise _fail(path, None, f"not a readable CSV table ({err}); one header line and one "
                                "row per record are needed") from None
    twice = repeated_header(f)
    if twice:  # pandas reads a repeated name as name.1, and the first would be used unseen
        raise _fail(path, None, f"column(s) {twice} more than once; keep one of each")
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
    numeric = {"fs_hz": False, "n1_rpm": None, "torque_Nm": None, "wear_mm": True,
               "cycles": True} | {c: True for c in OPTIONAL_NUMERIC if c in man.columns}
    for col, may_be_empty in numeric.items():
        text = man[col].str.strip()
        if may_be_empty is None:  # the speed, the torque: a positive number or unknown
            text = text.where(~text.str.lower().isin(UNKNOWN), "")
        values = pd.to_numeric(text.where(text != ""), errors="coerce")
        for rec, s, v in zip(man.record, text, values, strict=True):
            if s == "" and may_be_empty is not False:
                continue
            shown = repr(float(v)) if np.isfinite(v) else repr(s)
            if may_be_empty is None:
                if not (np.isfinite(v) and v > 0):
                    then = ("read off the record's spectrum: docs/own-data.md"
                            if col == "n1_rpm" else "calibrated: docs/loop.md")
                    raise _fail(path, rec, f"{col} = {shown} must be a positive number, or "
                                           f"empty or 'unknown' where it is not known (then "
                                           f"{then})")
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
    operating point they give, and which of the torque and the speed it states unknown
    (calibrated then: ``torque_factor`` of :data:`physics.loop.model.declared.TORQUE` and
    ``speed_factor`` of :data:`~physics.loop.model.declared.SPEED`, around the configured
    values); the bulk temperature must be stated or left out."""
    return _read_sidecar(path / "operating.yaml", operating, where, {
        "bulk_temperature_K": "only torque_Nm and n1_rpm may be unknown (the loop calibrates "
                              "them); state this one, or leave the key out to use the "
                              "configured value"})


def _read_sidecar(f: Path, current, where: str, stated: dict[str, str]
                  ) -> tuple[dict, tuple[str, ...]]:
    """The overrides of the YAML file ``f`` of the dataclass ``current``'s keys (none if there
    is no such file), checked by building the value they give, and the keys it states as
    unknown (``stated``: the keys that may not be unknown, each with the reason)."""
    if not (f.exists() or f.is_symlink()):
        return {}, ()
    if not f.is_file():
        kind = "a folder" if f.is_dir() else ("not a regular file (a FIFO, a device, a socket "
                                              "or a broken link)")
        raise ValueError(f"{where}: {f} is {kind}; give a YAML file there, or remove it")
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
    except UnicodeDecodeError as err:
        raise ValueError(f"{where}: {f} is not UTF-8 text (byte {err.object[err.start]:#04x} "
                         f"at offset {err.start}): a binary file? it must be YAML text mapping "
                         "keys to values") from None
    except (yaml.YAMLError, OmegaConfBaseException) as err:
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


def _signal_size(path: Path, rec: str, fs_hz: float) -> int:
    """The samples of record ``rec`` by its header, checked against the file's size and
    :data:`MAX_RECORD_SAMPLES` before anything is loaded."""
    f = path / "signals" / f"{rec}.npy"
    _regular(path, rec, f, "save the record there with numpy.save")
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
    if count > MAX_RECORD_SAMPLES:
        most = MAX_RECORD_SAMPLES / fs_hz
        raise _fail(path, rec, f"{count:,} samples ({count / fs_hz:.4g} s at fs_hz = "
                               f"{fs_hz:g}), above the {MAX_RECORD_SAMPLES:,} a record may hold: "
                               "the loop analyses all of a record's segments at once, ~100 "
                               "bytes of memory a sample (1.7 GB at the limit), and their "
                               f"scatter is known long before; cut it into records of at most "
                               f"{most:.4g} s at this rate (each a row of the manifest) or give "
                               "an excerpt")
    return count


def _read_signal(path: Path, rec: str) -> np.ndarray:
    f = path / "signals" / f"{rec}.npy"
    _regular(path, rec, f, "save the record there with numpy.save")
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
    path = path_argument(path, "read_measurements(path)",
                         "a bundle folder or a feature-table .csv file")
    argument(base, "read_measurements(base)", Scenario, "a physics.params.Scenario")
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
    if path.exists() and not path.is_file():
        raise ValueError(f"data = {str(path)!r} is not a regular file (a FIFO, a device or a "
                         "socket) nor a folder; give a bundle folder or a feature-table .csv "
                         "file (docs/own-data.md)")
    why = " (no such file or folder)" if not path.exists() else ""
    raise ValueError(f"data = {str(path)!r} is neither a bundle folder nor a feature-table .csv "
                     f"file{why}; see docs/own-data.md")


#: what a bundle folder holds besides its ``signals/*.npy``, as :func:`write_bundle` and the
#: bundle makers (:mod:`physics.testbeds`: ``make_bundle``, ``make_independent_bundle``) write
#: it: a folder that holds these alone, or nothing, is an earlier bundle, which
#: :func:`write_bundle` replaces
BUNDLE_FILES = ("manifest.csv", "gear.yaml")


def _not_bundle(path: Path) -> list[str]:
    """The entries of the folder ``path`` that no bundle has (:data:`BUNDLE_FILES`,
    ``signals/*.npy``; a link is never a bundle's), as names relative to ``path``."""
    out = []
    for entry in sorted(path.iterdir()):
        if entry.is_symlink():
            out.append(entry.name)
        elif entry.name in BUNDLE_FILES and entry.is_file():
            continue
        elif entry.name == "signals" and entry.is_dir():
            out += [f"signals/{e.name}" for e in sorted(entry.iterdir())
                    if e.is_symlink() or not (e.is_file() and e.suffix == ".npy")]
        else:
            out.append(entry.name + ("/" if entry.is_dir() else ""))
    return out


def check_bundle_target(path: str | Path) -> Path:
    """``path`` as a bundle's folder that :func:`write_bundle` may write, else a refusal
    (ValueError, one line naming the folder and the fix): an existing file or link, a parent
    that is a file, or a folder that holds anything an earlier bundle does not
    (:data:`BUNDLE_FILES`, ``signals/*.npy``): a user's folder, whose files replacing it would
    delete. A new folder, an empty one or an earlier bundle passes. The bundle makers call it
    before their work."""
    path = path_argument(path, "write_bundle(path)", "a new folder or an earlier bundle")
    if path.is_symlink():
        raise ValueError(f"write_bundle: {path} is a link (to {os.readlink(path)}), which "
                         "replacing would remove; give a new folder's path, or the folder "
                         "it points to")
    if path.exists() and not path.is_dir():
        raise ValueError(f"write_bundle: {path} is a file, not a folder; give a new folder's "
                         "path for the bundle (the file is left as it is)")
    if not path.exists():
        above = next((p for p in path.absolute().parents if p.exists()), None)
        if above is not None and not above.is_dir():
            raise ValueError(f"write_bundle: {path}: {above} is a file, not a folder; give a "
                             "path in a folder")
        return path
    foreign = _not_bundle(path)
    if foreign:
        more = f" and {len(foreign) - 1} more" if len(foreign) > 1 else ""
        raise ValueError(f"write_bundle: {path} holds {foreign[0]}{more}, which no bundle has "
                         f"(a bundle holds {', '.join(BUNDLE_FILES)} and signals/*.npy): "
                         "replacing the folder would delete it; give a new folder's path, or "
                         f"move {foreign[0]} out of {path} first")
    return path


def _remove_bundle(folder: Path) -> None:
    """Remove an earlier bundle set aside by :func:`write_bundle`, its own files alone; a
    folder that something else came into since is kept (and said so)."""
    try:
        for name in BUNDLE_FILES:
            (folder / name).unlink(missing_ok=True)
        if (folder / "signals").is_dir():
            for f in (folder / "signals").glob("*.npy"):
                f.unlink()
            (folder / "signals").rmdir()
        folder.rmdir()
    except OSError as err:
        log.warning("the earlier bundle replaced by write_bundle is kept in %s (%s): remove it "
                    "once you have checked it", folder, err.strerror or err)


def write_bundle(path: str | Path, manifest: pd.DataFrame, signals: dict[str, np.ndarray],
                 gear: dict | None = None) -> Path:
    """Write a complete bundle at ``path`` or nothing, refused before anything is written
    where ``path`` is not a new folder, an empty one or an earlier bundle
    (:func:`check_bundle_target`: a user's folder is never deleted). An earlier bundle is
    replaced: set aside, the new one renamed into place, then its files removed (or put back
    if the rename fails). Its folders and files get the usual permissions (0o755 / 0o644
    under the usual umask), not the temporary folder's 0o700: a bundle is shared with the
    group that reads it."""
    path = check_bundle_target(path)
    argument(manifest, "write_bundle(manifest)", pd.DataFrame,
             "a pandas DataFrame, one row per record (docs/own-data.md)")
    argument(signals, "write_bundle(signals)", Mapping,
             "a mapping of record names to 1-D arrays of samples")
    argument(gear, "write_bundle(gear)", (Mapping, type(None)),
             "a mapping of gear.yaml keys to values, or None")
    arrays = {}
    for name, x in signals.items():
        if not isinstance(name, str) or not _NAME.match(name):
            raise ValueError(f"write_bundle: record name {name!r} must use letters, digits, "
                             "'_' and '-' only (it names the file signals/<record>.npy)")
        try:
            arrays[name] = np.asarray(x, float)
        except (TypeError, ValueError) as err:
            raise ValueError(f"write_bundle: record {name!r}: its signal is not an array of "
                             f"numbers ({err})") from None
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    umask = os.umask(0)
    os.umask(umask)
    aside = None
    try:
        (tmp / "signals").mkdir()
        manifest.to_csv(tmp / "manifest.csv", index=False)
        for name, x in arrays.items():
            np.save(tmp / "signals" / f"{name}.npy", x)
        if gear:
            (tmp / "gear.yaml").write_text(yaml.safe_dump(dict(gear)))
        for p in (tmp, *tmp.rglob("*")):
            os.chmod(p, (0o777 if p.is_dir() else 0o666) & ~umask)
        if path.exists():
            check_bundle_target(path)  # nothing of the user's came in while it was written
            aside = Path(tempfile.mkdtemp(prefix=f".{path.name}.old.", dir=path.parent))
            os.replace(path, aside)  # onto the empty folder made for it
        os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        if aside is not None:
            if not path.exists() and any(aside.iterdir()):
                os.replace(aside, path)  # the earlier bundle back in place
            else:
                aside.rmdir()
        raise
    if aside is not None:
        _remove_bundle(aside)
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
    a repeated column or a bad cell is reported with its row and column
    (:func:`check_feature_frame`)."""
    path = path_argument(path, "read_feature_table(path)", "a feature-table .csv file")
    what = file_problem(path)
    if what is not None:
        raise ValueError(f"feature table {path} {what}; give a .csv file (docs/own-data.md)")
    try:
        header = pd.read_csv(path, header=None, nrows=1, dtype=str, keep_default_na=False)
        df = pd.read_csv(path)
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as err:
        raise ValueError(f"feature table {path}: not a readable CSV table ({err})") from None
    names = [str(c).strip() for c in header.iloc[0]]  # as written: pandas renames repeats
    if len(names) == df.shape[1]:
        df.columns = names
    return check_feature_frame(df, f"feature table {path}")


def check_feature_frame(df: pd.DataFrame, where: str = "feature table") -> pd.DataFrame:
    """``df`` with every cell a number, checked (one line starting with ``where``, naming the
    row, counted from 1 as in the file, the column and the rule): a repeated column name, no
    ``wear_mm`` or no feature column or no row, a cell that is not a finite number, a wear
    outside [0, 10] mm. A table given as a data frame goes through the same checks as one
    read from a file."""
    argument(df, f"{where}", pd.DataFrame, "a pandas DataFrame of wear_mm and features")
    repeated = sorted({str(c) for c in df.columns[df.columns.duplicated()]})
    if repeated:
        raise ValueError(f"{where}: repeated column {repeated[0]!r}"
                         + (f" (and {repeated[1:]})" if len(repeated) > 1 else "")
                         + "; each feature takes one column: remove or rename the repeat")
    if "wear_mm" not in df.columns or df.shape[1] < 2 or df.empty:
        raise ValueError(f"{where}: needs a wear_mm column, feature columns and at least one "
                         "row")
    df = df.copy()
    for col in df.columns:
        values = pd.to_numeric(df[col], errors="coerce")
        bad = ~np.isfinite(values.to_numpy(float))
        if bad.any():
            row = int(np.argmax(bad))
            cell = df[col].iloc[row]
            shown = repr(cell) if isinstance(cell, str) else (
                "empty (NaN)" if pd.isna(cell) else str(cell))
            raise ValueError(f"{where}: row {row + 1}, column {col!r}: {shown} is not a "
                             "finite number")
        df[col] = values
    wear = df["wear_mm"].to_numpy(float)
    out = (wear < 0) | (wear > 10)
    if out.any():
        row = int(np.argmax(out))
        raise ValueError(f"{where}: row {row + 1}, column 'wear_mm' = {wear[row]:g} lies "
                         "outside [0, 10] mm, what a wear depth can be; give it in mm")
    return df.reset_index(drop=True)
