"""Lightning data module over the physics dataset (:mod:`physics.dataset`).

Rows are split by *trajectory* (one replicate of one case, all its wear states), never by rows
of one trajectory: neighbouring wear states are nearly the same sample. Per case, a seeded
permutation of the replicates gives ``test_replicates`` for the test set, ``val_replicates`` for
validation (by default :func:`validation_count`) and the rest for training; ``holdout_case``
instead puts a whole case in the test set (leave-one-case-out). Of 16 or more validation
trajectories, half choose the epoch kept and the other half calibrate the interval
(:func:`calibration_split`). The input scaling is fitted on the training rows only and travels
with the model in its :class:`~surrogate.schema.FeatureSchema`.

A dataset built here simulates :func:`replicates_per_case` gearboxes per trained case: what a
network learns about gearboxes it was not trained on is set by how many it was trained on
(docs/surrogate.md, Alternatives considered).
"""

from __future__ import annotations

import copy
import dataclasses
import json
import logging
import math
from pathlib import Path

import lightning as L
import numpy as np
import pandas as pd
import torch
from torch.utils.data import BatchSampler, DataLoader, RandomSampler, TensorDataset

from physics.dataset.generation import (
    DatasetJob,
    build_dataset,
    dataset_digest,
    plan_dataset,
    spec_from_config,
)
from physics.dataset.generation import units as dataset_units
from physics.files import existing_file
from physics.params import Scenario, operating_cases
from physics.signals.order_analysis import LINE_ORDERS, MESH_ORDERS
from surrogate.schema import (
    FeatureSchema,
    first_rows,
    network_frame,
    repeated_header,
    source_columns,
    vector_columns,
    vector_inputs,
    vector_parts,
)

log = logging.getLogger(__name__)
#: the sensors a user may have: DTE (``dte_*`` features) and housing acceleration (``acc_*``)
SENSORS = ("dte", "acc")
#: the features of each sensor that a gearbox's unknown offsets and scales leave alone. A DTE
#: record's mean is the half backlash plus the static deflection (tens of um, set by tolerances
#: the user does not know; an encoder pair measures the DTE only up to a constant), so of the
#: DTE the mean-free peak-to-peak value, the kurtosis and the levels of mesh harmonics 2-6
#: relative to the first (ratios of the record's own lines, which wear moves by several dB:
#: :func:`physics.signals.order_analysis.mesh_harmonic_levels`) are used; the housing
#: acceleration's level scales with the housing's effective mass and the transfer path, so of it
#: only the dimensionless shape features are used (Table 13 definitions in
#: :mod:`physics.signals.features`; docs/surrogate.md measures the gain on gearboxes away from
#: the training ones, and the harmonics' phases, dataset columns too, as an alternative)
INVARIANT = {"dte": ("peak_to_peak", "kurtosis", *(f"mesh{k}_db" for k in MESH_ORDERS)),
             "acc": ("kurtosis", "crest", "margin", "impulse", "shape")}
#: the absolute reading's default inputs (``data.baseline=false``): the invariant features of
#: both sensors
DEFAULT_INPUTS = [f"{q}_{f}" for q in SENSORS for f in INVARIANT[q]]
CONDITIONS = ["n1_rpm", "torque_Nm"]


#: the baseline reading's default inputs: the DTE's mesh lines 1-6, each a complex amplitude
#: against a once-per-revolution mark (dataset columns ``dte_line<k>_re``, ``_im``), read as
#: their vector change since the baseline record (docs/surrogate.md, Method, Baseline mode)
BASELINE_INPUTS = [f"dte_line{k}" for k in LINE_ORDERS]


def input_columns(sensors: list[str], operating_point: bool, baseline: bool = False
                  ) -> list[str]:
    """The network's default inputs, with or without the operating point: read against the
    baseline record, the DTE's mesh lines (:data:`BASELINE_INPUTS`); read absolutely, the
    :data:`INVARIANT` features of the sensors a user has."""
    unknown = sorted(set(sensors) - set(SENSORS))
    if unknown or not sensors or len(set(sensors)) != len(sensors):
        raise ValueError(f"data.sensors = {list(sensors)} must name one or both of {SENSORS}")
    if baseline and "dte" not in sensors:
        raise ValueError(f"data.sensors = {list(sensors)}: the reading against the baseline "
                         "record takes the DTE's mesh lines; without a DTE read absolutely "
                         "(data.baseline=false) or name the inputs (data.inputs=[...])")
    cols = (BASELINE_INPUTS if baseline else
            [f"{q}_{f}" for q in SENSORS if q in sensors for f in INVARIANT[q]])
    return cols + (CONDITIONS if operating_point else [])


def cases_of(case: str | int) -> list[int]:
    """``case`` of the train config: one operating case of Table 11 (1-5) or ``all``."""
    valid = sorted(operating_cases())
    if str(case).strip() == "all":
        return valid
    if str(case).strip() in {str(c) for c in valid}:
        return [int(case)]
    raise ValueError(f"case = {case!r} is not an operating case; use one of {valid} (thesis "
                     "Table 11) or all")


#: the fewest gearboxes per case a built dataset simulates: the all-case network's error on
#: shifted gearboxes scatters over training seeds with fewer (docs/surrogate.md, Alternatives
#: considered)
MIN_REPLICATES = 128
#: the fewest validation trajectories per case: they choose the epoch and calibrate the
#: interval
MIN_VALIDATION = 8
#: validation trajectories (all cases together) from which on half of each case's calibrate the
#: interval apart from those that choose the epoch (:func:`calibration_split`)
MIN_APART = 2 * MIN_VALIDATION
#: chunks of a dataset built here (fewer where it has fewer trajectories): the build's
#: processes take chunks as they finish, so many small ones keep both cores busy to the end
#: (with the dataset API's 5, one of 2 processes idles through the last fifth of a build)
BUILD_CHUNKS = 32


def replicates_per_case(gearboxes: int, cases: int) -> int:
    """Gearboxes per case for a dataset of ``gearboxes`` shared by ``cases`` operating cases,
    at least :data:`MIN_REPLICATES` (so ``case=all`` has 128 per case)."""
    return max(MIN_REPLICATES, math.ceil(gearboxes / cases))


def validation_count(trajectories: int) -> int:
    """Validation trajectories of a case with ``trajectories``: a sixth, at least
    :data:`MIN_VALIDATION`. The conformal interval's quantile is read from half of them
    (:func:`calibration_split`): the fewer, the more its coverage scatters over seeds, and
    below 19 calibrating gearboxes no quantile reaches the 95 % level (the largest score is
    taken; :func:`surrogate.conformal.attainable`). A sixth of the main job's 256 gives 43: 21
    calibrate."""
    return max(MIN_VALIDATION, round(trajectories / 6))


def stale_dataset(path: Path, job: DatasetJob) -> str | None:
    """What differs between the dataset at ``path`` and the one ``job`` would build (its
    sidecar's settings against the job's), or None when it is that dataset or has no sidecar
    of ours to compare."""
    sidecar = path.with_suffix(".json")
    side = json.loads(sidecar.read_text()) if sidecar.is_file() else {}
    # the chunks split the work, not the rows: the same dataset cut otherwise is not stale
    built = side.get("config", {}).get("data", {}).get("chunks")
    spec = job.spec
    if isinstance(built, int) and 1 <= built <= spec.units:
        spec = dataclasses.replace(spec, chunks=built)
    if side.get("hash") in (None, dataset_digest(job.base, spec)):
        return None
    have = side.get("config", {})
    want = json.loads(json.dumps({"scenario": dataclasses.asdict(job.base),
                                  "data": dataclasses.asdict(spec)}, default=str))
    diff = [f"{part}.{k}: {have.get(part, {}).get(k)!r} -> {v!r}"
            for part in ("data", "scenario") for k, v in want[part].items()
            if have.get(part, {}).get(k) != v]
    return "; ".join(diff) or "the physics it was built with"


def dataset_job(path: str | Path, spec: dict | None = None, jobs: int = 2) -> DatasetJob:
    """The checked build of the dataset at ``path`` (``spec``: DatasetSpec values other than the
    defaults), as ``python -m physics.dataset out_dir=<folder> name=<stem>`` would run it."""
    path = Path(path)
    if path.suffix != ".parquet":
        raise ValueError(f"data.dataset = {str(path)!r} must name a .parquet file")
    return plan_dataset(Scenario(), spec_from_config(spec or {}), path.parent, path.stem,
                        jobs=jobs, out_key="the folder of data.dataset (paths.data_dir unless "
                                           "data.dataset is set)")


def load_dataset(path: str | Path, spec: dict | None = None, jobs: int = 2) -> pd.DataFrame:
    """Read the dataset at ``path``, building it with the dataset API if it is missing."""
    path = Path(path)
    job = dataset_job(path, spec, jobs)
    if not path.is_file():
        log.info("dataset %s missing: generating it (physics.dataset, %d jobs)", path, jobs)
        build_dataset(job)
    elif (diff := stale_dataset(path, job)) is not None:
        log.warning("dataset %s was built with other settings than this run asks for (%s); "
                    "training on it as it is: delete it (or name another data.dataset) to "
                    "build the one this run describes", path, diff)
    return pd.read_parquet(path)


#: the range (low, high) each unit allows a user's column: a value outside is a unit error or
#: a broken reading. DTE features: 1 mm of transmission error is far beyond any running spur
#: pair (a worn one shows tens of um); housing acceleration: 1e5 m/s^2 (10^4 g); wear depth: a
#: tooth of module 2 is 4.5 mm high, so 10 mm is no wear depth; dimensionless shape features
#: (kurtosis, crest, ...) of a finite record stay far below 1e6
PLAUSIBLE = {"m": (0.0, 1e-3), "m/s^2": (0.0, 1e5), "1": (-1e6, 1e6), "mm": (0.0, 10.0),
             "r/min": (0.0, 1e5), "N m": (-1e6, 1e6), "Pa s": (0.0, 1e3), "um": (0.0, 1e4),
             "kg": (0.0, 1e5), "Hz": (0.0, 1e6), "dB": (-300.0, 300.0), "g": (0.0, 1e4),
             "m/s": (0.0, 1e3), "rev/s": (0.0, 2e3), "s": (0.0, 1e10), "h": (0.0, 1e7)}
#: other spellings of the units of :data:`PLAUSIBLE` (``^`` cannot stand unquoted in a Hydra
#: override: ``data.units={fme15: m/s2}``)
UNIT_ALIASES = {"m/s2": "m/s^2", "m s^-2": "m/s^2", "m/s**2": "m/s^2", "rpm": "r/min",
                "1/min": "r/min", "Nm": "N m", "N*m": "N m", "Hz_rev": "rev/s", "rps": "rev/s",
                "-": "1", "": "1", "µm": "um", "μm": "um"}
#: the units a wear depth (the target) may be given in: it is not negative and does not fall
LENGTH_UNITS = ("m", "mm", "um")


def normalise_unit(unit) -> str:
    """A user's unit as the checks know it (:data:`UNIT_ALIASES`); others are kept as given."""
    text = str(unit).strip()
    return UNIT_ALIASES.get(text, text)


#: per-group medians of one dimensional feature further apart than this: mixed units
MIXED_UNITS_RATIO = 100.0
#: the columns of a user table that order a trajectory's rows in time (after data.columns)
ORDER_COLUMNS = ("cycles", "time_s", "time_h", "time")


def _plain(value):
    """A numpy scalar as the Python value it holds (messages show ``3``, not ``np.int64(3)``)."""
    return value.item() if isinstance(value, np.generic) else value


def _shown(value) -> str:
    """A cell as a message shows it: numbers plainly, text quoted."""
    try:
        return f"{float(value):.6g}"
    except (TypeError, ValueError):
        return repr(value)


def check_user_table(df: pd.DataFrame, path: Path | str, needed: list[str], group: str,
                     target: str | None = None, units: dict[str, str] | None = None,
                     line_parts: tuple[str, ...] = ()) -> None:
    """A user's table checked before any training, one refusal per rule naming the column,
    the row (1-based, as the file's data rows) or the group, and the fix:

    - every group key present (no empty or NaN ``group`` value);
    - every needed value a finite number;
    - every value within the range its unit allows (:data:`PLAUSIBLE`, by ``units``: the
      dataset's units of our column names and the user's of his own, :func:`table_units`): a
      DTE in m of 1e-2 is a unit error; a unit the table does not know is checked for finite
      values and one unit per column only;
    - one unit per column: a dimensional feature whose per-group median differs more than
      :data:`MIXED_UNITS_RATIO` times between two groups mixes units;
    - the ``line_parts`` (the real and imaginary parts of complex-line inputs,
      :func:`~surrogate.schema.vector_inputs`) take either sign within their unit's range, and
      their per-group medians, set by each gearbox's phase against its mark, are not compared;
    - wear (``target``, in a unit of :data:`LENGTH_UNITS`) not negative and, where an
      :data:`ORDER_COLUMNS` column is given (with a value in every row; a column left wholly
      empty counts as not given), not falling within a group in its order.
    """
    keys = df[group]
    empty = keys.isna() | (keys.astype(str).str.strip() == "")
    if empty.any():
        r = int(np.argmax(empty.to_numpy()))
        raise ValueError(f"{path}: row {r + 1} has no value in the group column {group!r} "
                         f"({keys.iloc[r]!r}); every row needs its trajectory (gearbox, run): "
                         "fill it in or drop the row")
    values = df[needed].apply(pd.to_numeric, errors="coerce").to_numpy(float)
    bad = ~np.isfinite(values)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise ValueError(f"{path}: row {r + 1}, column {needed[c]!r} = "
                         f"{_shown(df[needed[c]].iloc[r])} is not a finite number; repair or "
                         "drop the row")
    unit_of = {**dataset_units(), **(units or {})}
    for c, name in enumerate(needed):
        unit = unit_of.get(name)
        if name == target and unit in LENGTH_UNITS and (values[:, c] < 0).any():
            r = int(np.argmax(values[:, c] < 0))
            raise ValueError(f"{path}: row {r + 1}, column {name!r} = {values[r, c]:.6g} is "
                             f"negative; wear is a depth (>= 0, in {unit}): repair the reading")
        if unit not in PLAUSIBLE:
            continue
        lo, hi = PLAUSIBLE[unit]
        if name in line_parts:
            lo = -hi
        out = (values[:, c] < lo) | (values[:, c] > hi)
        if out.any():
            r = int(np.argmax(out))
            fix = ("it is dimensionless: repair the reading" if unit == "1" else
                   f"convert the column to {unit} (data.columns maps names, not units) or "
                   "state its unit (data.units)")
            raise ValueError(f"{path}: row {r + 1}, column {name!r} = {values[r, c]:.6g} lies "
                             f"outside [{lo:g}, {hi:g}], what its unit {unit} allows; {fix}")
    codes, names = pd.factorize(keys, sort=True)
    for c, name in enumerate(needed):
        if (name == target or name in CONDITIONS or unit_of.get(name) in (None, "1")
                or name in line_parts):
            continue
        med = pd.Series(np.abs(values[:, c])).groupby(codes).median()
        med = med[med > 0]
        if len(med) > 1 and med.max() > MIXED_UNITS_RATIO * med.min():
            hi_g, lo_g = (_plain(names[i]) for i in (med.idxmax(), med.idxmin()))
            raise ValueError(f"{path}: column {name!r} has a median of {med.max():.3g} in group "
                             f"{hi_g!r} but {med.min():.3g} in group {lo_g!r}, more than "
                             f"{MIXED_UNITS_RATIO:g} times apart: mixed units; give every "
                             f"group in {unit_of[name]}")
    if target is None or target not in needed or unit_of.get(target) not in LENGTH_UNITS:
        return  # the order rule is wear's
    wear = values[:, needed.index(target)]
    # an order column without a single value is not given (the bundle spec lets cycles be
    # unknown); one with some values must have them all
    order = next((c for c in ORDER_COLUMNS if c in df.columns
                  and pd.to_numeric(df[c], errors="coerce").notna().any()), None)
    if order is None:
        return
    t = pd.to_numeric(df[order], errors="coerce").to_numpy(float)
    if not np.isfinite(t).all():
        r = int(np.argmax(~np.isfinite(t)))
        raise ValueError(f"{path}: row {r + 1}, column {order!r} = {_shown(df[order].iloc[r])} "
                         "is not a finite number; repair or drop the row")
    frame = pd.DataFrame({"g": codes, "t": t, "w": wear, "row": np.arange(len(df))})
    frame = frame.sort_values(["g", "t"], kind="stable")
    same = frame.g.to_numpy()[1:] == frame.g.to_numpy()[:-1]
    falls = same & (np.diff(frame.w.to_numpy()) < 0)
    if falls.any():
        i = int(np.argmax(falls))
        a, b = frame.iloc[i], frame.iloc[i + 1]
        raise ValueError(f"{path}: group {_plain(names[int(b.g)])!r}: {target} falls from "
                         f"{a.w:.6g} "
                         f"(row {int(a.row) + 1}, {order} {a.t:g}) to {b.w:.6g} (row "
                         f"{int(b.row) + 1}, {order} {b.t:g}); wear does not heal: repair the "
                         f"readings or the {order} column")


def with_vector_units(units: dict[str, str], vectors) -> dict[str, str]:
    """``units`` with each complex-line input's unit, its parts' (one unit for both)."""
    out = dict(units)
    for v in vectors:
        given = {units[c] for c in vector_parts(v)}
        if len(given) != 1:
            raise ValueError(f"the parts {vector_parts(v)} of the line input {v} have units "
                             f"{sorted(given)}; give both parts in one unit")
        out[v] = given.pop()
    return out


def read_user_table(path: str | Path, columns: dict[str, str]) -> pd.DataFrame:
    """A user's table as read from ``path`` (CSV or parquet), its columns renamed by
    ``columns`` (the table's name -> ours)."""
    path = existing_file(path, "data.table", "give your .csv or .parquet table")
    if path.suffix not in (".csv", ".parquet"):
        raise ValueError(f"data.table = {str(path)!r} must be an existing .csv or .parquet file")
    twice = repeated_header(path)
    if twice:
        raise ValueError(f"data.table = {path} has column(s) {twice} more than once; keep one "
                         "of each")
    try:
        df = pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError,
            OSError) as err:
        raise ValueError(f"data.table = {path} is not a readable table ({err})") from None
    unknown = sorted(set(columns) - set(df.columns))
    if unknown:
        raise ValueError(f"data.columns names {unknown}, which {path} does not have")
    df = df.rename(columns=columns)
    twice = sorted(set(df.columns[df.columns.duplicated()]))
    if twice:
        raise ValueError(f"{path} has column(s) {twice} more than once (after data.columns); "
                         "keep one of each")
    return df


def sidecar_path(path: str | Path) -> Path:
    """The units sidecar of a user's table: ``mine.units.yaml`` beside ``mine.csv``."""
    path = Path(path)
    return path.with_name(f"{path.stem}.units.yaml")


def table_units(path: str | Path, columns: dict[str, str], given: dict | None,
                needed: list[str]) -> dict[str, str]:
    """The units of a user's table: the dataset's for our column names, then those of its
    sidecar (:func:`sidecar_path`, ``column: unit`` per line), then ``given``
    (``data.units``), each later one winning; names as the table's or as mapped by
    ``columns``. Raises naming every ``needed`` column without a unit."""
    own: dict[str, str] = {}
    side = sidecar_path(path)
    if side.is_file():
        import yaml

        try:
            read = yaml.safe_load(side.read_text())
        except yaml.YAMLError as err:
            raise ValueError(f"{side} is not readable YAML ({str(err).splitlines()[0]})") from None
        if read is not None and not (isinstance(read, dict) and all(
                isinstance(k, str) and isinstance(v, str | int | float) for k, v in read.items())):
            raise ValueError(f"{side} must map column names to units, one per line "
                             "(fme15: m/s^2); it holds something else")
        own.update(read or {})
    own.update({str(k): v for k, v in dict(given or {}).items()})
    bad = [k for k, v in own.items() if not isinstance(v, str | int | float) or isinstance(v, bool)]
    if bad:
        raise ValueError(f"data.units gives {bad[0]!r} no unit ({own[bad[0]]!r}); give a unit "
                         "per column: data.units={fme15: m/s2}")
    own = {columns.get(k, k): normalise_unit(v) for k, v in own.items()}
    units = {**dataset_units(), **own}
    missing = [c for c in needed if c not in units]
    if missing:
        hint = ", ".join(f"{c}: UNIT" for c in missing)
        raise ValueError(f"{path}: column(s) {missing} have no unit; give them with "
                         f"data.units={{{hint}}} or in {side.name} beside the table "
                         "(1 for a dimensionless feature)")
    return {c: units[c] for c in dict.fromkeys([*own, *needed])}


def user_table(path: str | Path, columns: dict[str, str], group: str | None,
               needed: list[str], target: str | None = None, units: dict | None = None,
               group_by: str | None = None) -> pd.DataFrame:
    """A user's labelled feature table as the data module's rows (:func:`user_rows` of
    :func:`read_user_table`); ``units`` as :func:`table_units` takes them."""
    df = read_user_table(path, columns)
    return user_rows(df, path, group, needed, target,
                     table_units(path, columns, units, needed), group_by)


#: columns a user's table may carry for the thesis's estimator beside the network (its
#: features and the cycle count), kept in the rows where the table gives them
ESTIMATOR_COLUMNS = ("dte_peak_to_peak", "dte_kurtosis")


def user_rows(df: pd.DataFrame, path: str | Path, group: str | None, needed: list[str],
              target: str | None = None, units: dict[str, str] | None = None,
              group_by: str | None = None, line_parts: tuple[str, ...] = ()) -> pd.DataFrame:
    """A user's table (renamed) as the data module's rows: the ``needed`` columns as numbers,
    ``case`` 0, ``replicate`` the index of each trajectory in sorted order (a value of
    ``group``, or with ``group_by`` another column, a pair of the two), ``split_group`` the
    index of the row's ``group_by`` value in sorted order (of ``group`` without one), ``row``
    the row of the table, ``cycles`` where given (else NaN) and the estimator's features where
    given (:data:`ESTIMATOR_COLUMNS`). Checked by :func:`check_user_table` first (``line_parts``
    as it takes them); the rows of each trajectory are read in the table's order."""
    path = Path(path)
    for option, col in (("data.group", group), ("data.group_by", group_by)):
        if col is not None and col not in df.columns:
            raise ValueError(f"{option} = {col!r} is not a column of {path}; it has {list(df)}")
    if group is None:
        raise ValueError(f"data.group = None must name the column of {path} that tells "
                         f"the trajectories (gearboxes, test runs) apart; it has {list(df)}")
    missing = [c for c in needed if c not in df.columns]
    if missing:
        raise ValueError(f"{path} lacks column(s) {missing}; map yours with data.columns "
                         "(units as in the dataset: docs/dataset.md)")
    if df.empty:
        raise ValueError(f"data.table = {path} has no rows")
    if target is None:
        target = next((c for c in needed if dataset_units().get(c) == "mm"), None)
    check_user_table(df, path, needed, group, target, units, line_parts)
    by = group_by or group
    if by != group:
        check_user_table(df, path, [], by)  # every row in a group of group_by, too
    out = df[needed].astype(float)
    out["case"] = 0
    keys = [group] if by == group else [by, group]
    out["replicate"] = df.groupby(keys, sort=True).ngroup().to_numpy()
    out["split_group"] = pd.factorize(df[by], sort=True)[0]
    out["row"] = np.arange(len(df))
    out["cycles"] = (df["cycles"].astype(float) if "cycles" in df.columns and "cycles"
                     not in needed else np.nan)
    for name in ESTIMATOR_COLUMNS:
        if name in df.columns and name not in needed:
            out[name] = pd.to_numeric(df[name], errors="coerce").to_numpy(float)
    return out


def check_split(case: int, trajectories: int, val_replicates: int | None,
                test_replicates: int, holdout_case: int | None) -> tuple[int, int]:
    """The (test, validation) trajectory counts of ``case``; ValueError when it has too few
    trajectories for them and one to train on."""
    n_test = 0 if holdout_case is not None else test_replicates
    n_val = validation_count(trajectories) if val_replicates is None else val_replicates
    if trajectories < n_test + n_val + 1:
        raise ValueError(
            f"case {case} has {trajectories} trajectories; a split with {n_val} "
            f"validation and {n_test} test trajectories needs at least "
            f"{n_test + n_val + 1}: lower data.val_replicates and "
            "data.test_replicates, or add trajectories (data.generate.replicates)")
    return n_test, n_val


def match_groups(values, uniques: pd.Index, option: str, column: str, source) -> list[int]:
    """The indices in ``uniques`` (a column's sorted distinct values) of the user's ``values``
    (``data.test_groups``, ``data.val_groups``): numbers matched as numbers (45 is 45.0),
    others as text. Raises naming a value the column does not have."""
    codes = []
    numeric = pd.api.types.is_numeric_dtype(uniques.dtype)
    for v in list(values or []):
        if numeric:
            try:
                hit = np.flatnonzero(np.isclose(uniques.to_numpy(float), float(v),
                                                rtol=1e-12, atol=0))
            except (TypeError, ValueError):
                hit = np.array([], int)
        else:
            hit = np.flatnonzero(uniques.astype(str) == str(v))
        if hit.size == 0:
            shown = [u.item() if isinstance(u, np.generic) else u for u in uniques[:20]]
            raise ValueError(f"{option} = {list(values)}: column {column!r} of {source} has no "
                             f"value {v!r}; its values: {shown}"
                             + (" ..." if len(uniques) > 20 else ""))
        codes.append(int(hit[0]))
    return list(dict.fromkeys(codes))


def split_table(rows: pd.DataFrame, test_codes: list[int] | None, val_codes: list[int] | None,
                val_replicates: int | None, test_replicates: int, seed: int,
                describe) -> dict[str, pd.DataFrame]:
    """Train/val/test rows of a user's table (:func:`user_rows`): the rows whose
    ``split_group`` is one of ``test_codes`` (``val_codes``) test (validate); where none are
    named, ``test_replicates`` (``val_replicates``; None: :func:`validation_count`)
    trajectories are drawn from the others with ``seed``, in the order of
    :func:`split_trajectories` (which this is, without named groups). ``describe(n)`` says
    in the user's terms what the table's ``n`` trajectories are, for messages."""
    reps = np.sort(rows.replicate.unique())
    of_rep = rows.groupby("replicate").split_group.first().reindex(reps).to_numpy()
    perm = np.random.default_rng([seed, 0]).permutation(reps)
    test = (reps[np.isin(of_rep, test_codes)] if test_codes else None)
    val = (reps[np.isin(of_rep, val_codes)] if val_codes else None)
    n_test = 0 if test is not None else test_replicates
    n_val = (0 if val is not None else
             validation_count(len(reps)) if val_replicates is None else val_replicates)
    available = len(reps) - sum(len(x) for x in (test, val) if x is not None)
    if available < n_test + n_val + 1:
        named = "".join(f", {len(x)} named by data.{k}_groups" for k, x in
                        (("test", test), ("val", val)) if x is not None)
        raise ValueError(
            f"{describe(len(reps))}{named}; {n_val} more to validate and {n_test} more to test, "
            f"drawn, and one to train need {n_test + n_val + 1} besides the named ones, "
            f"{available} remain: lower data.val_replicates and data.test_replicates, name "
            "the groups by value (data.val_groups, data.test_groups), or split by a finer "
            "column (data.group)")
    if test is None:
        free = perm[~np.isin(perm, val if val is not None else [])]
        test = free[:n_test]
    if val is None:
        free = perm[~np.isin(perm, test)]
        val = free[:n_val]
    parts = {"test": rows[rows.replicate.isin(test)], "val": rows[rows.replicate.isin(val)]}
    parts["train"] = rows[~rows.replicate.isin(np.concatenate([test, val]))]
    return {k: parts[k].reset_index(drop=True) for k in ("train", "val", "test")}


def gearboxes(rows: pd.DataFrame) -> np.ndarray:
    """Each row's gearbox (trajectory: case and replicate) as an integer label."""
    return rows.groupby(["case", "replicate"], sort=False).ngroup().to_numpy()


def calibration_split(frames: dict[str, pd.DataFrame], seed: int) -> dict[str, pd.DataFrame]:
    """``frames`` with its validation trajectories cut in two: ``val``, which choose the epoch
    kept (early stopping, the checkpoint), and ``cal``, which calibrate the interval. A
    split-conformal interval covers its level only on data that chose nothing of the model
    (Angelopoulos & Bates, "A gentle introduction to conformal prediction", 2021, sec. 2.3):
    validation rows that also chose the epoch have smaller errors than a new gearbox's, and
    the interval under-covers (docs/surrogate.md, Where it does not know). Of each case's
    validation trajectories half (rounded down, drawn with ``seed`` in a stream of their own)
    calibrate; with fewer than :data:`MIN_APART` validation trajectories in all, both are the
    same rows."""
    val = frames["val"]
    if len(np.unique(gearboxes(val))) < MIN_APART:
        return {**frames, "cal": val}
    chosen = []
    for case, rows in val.groupby("case", sort=True):
        reps = np.sort(rows.replicate.unique())
        perm = np.random.default_rng([seed, int(case), 1]).permutation(reps)
        chosen.append(rows[rows.replicate.isin(perm[:len(reps) // 2])].index)
    is_cal = val.index.isin(np.concatenate(chosen))
    return {**frames, "val": val[~is_cal].reset_index(drop=True),
            "cal": val[is_cal].reset_index(drop=True)}


def split_trajectories(df: pd.DataFrame, val_replicates: int | None, test_replicates: int,
                       seed: int, holdout_case: int | None = None) -> dict[str, pd.DataFrame]:
    """Train/val/test rows, split by (case, replicate) trajectory; see the module text.
    ``val_replicates`` None: :func:`validation_count` of each case."""
    parts: dict[str, list[pd.DataFrame]] = {"train": [], "val": [], "test": []}
    for case, rows in df.groupby("case", sort=True):
        reps = np.sort(rows.replicate.unique())
        if case == holdout_case:
            parts["test"].append(rows)
            continue
        n_test, n_val = check_split(case, len(reps), val_replicates, test_replicates,
                                    holdout_case)
        perm = np.random.default_rng([seed, int(case)]).permutation(reps)
        groups = {"test": perm[:n_test], "val": perm[n_test:n_test + n_val],
                  "train": perm[n_test + n_val:]}
        for name, chosen in groups.items():
            parts[name].append(rows[rows.replicate.isin(chosen)])
    return {k: pd.concat(v, ignore_index=True) if v else df.iloc[:0] for k, v in parts.items()}


class WearDataModule(L.LightningDataModule):
    """Features -> wear (the mean depth read against each gearbox's first record, or the root
    wear read absolutely), from the dataset of the given cases or a user's table."""

    def __init__(self, dataset: str, case: str | int = 3,
                 sensors: tuple[str, ...] = SENSORS, operating_point: bool = True,
                 inputs: list[str] | None = None, target: str | None = None,
                 baseline: bool | None = None, val_replicates: int | None = None,
                 test_replicates: int = 8,
                 holdout_case: int | None = None, batch_size: int = 64, seed: int = 0,
                 generate: dict | None = None, jobs: int = 2, table: str | None = None,
                 columns: dict[str, str] | None = None, group: str | None = None,
                 gearboxes: int = 256, units: dict[str, str] | None = None,
                 group_by: str | None = None, test_groups: list | None = None,
                 val_groups: list | None = None, cv: str | None = None) -> None:
        super().__init__()
        self.dataset = str(dataset)
        self.cases = cases_of(case)
        if table is None and holdout_case is not None and int(holdout_case) not in self.cases:
            raise ValueError(f"data.holdout_case = {holdout_case} must be one of the cases "
                             f"{self.cases}")
        # the main job reads against each gearbox's first record; a user's table absolutely
        # unless it says its first rows are baselines
        baseline = table is None if baseline is None else bool(baseline)
        if inputs is not None and not len(inputs):
            raise ValueError("data.inputs = [] names no input; give the feature columns "
                             "(data.inputs=[fme15,acc_rms]) or leave data.inputs unset (null) "
                             "for the default inputs of data.sensors")
        self.inputs = (list(inputs) if inputs is not None else
                       input_columns(list(sensors), operating_point, baseline))
        self.target = target or ("mean_wear_mm" if baseline else "root_wear_mm")
        if self.target in self.inputs:
            raise ValueError(f"data.target = {self.target!r} is also among data.inputs: a model "
                             "given its own answer learns nothing; remove it from data.inputs")
        # the features, not the operating point, are read against the baseline record
        self.baseline = tuple(c for c in self.inputs if c not in CONDITIONS) if baseline else ()
        self.vectors: tuple[str, ...] = ()  # the complex-line inputs, found among the columns
        self.val_replicates = None if val_replicates is None else int(val_replicates)
        self.test_replicates = int(test_replicates)
        self.holdout_case = None if holdout_case is None else int(holdout_case)
        self.batch_size, self.seed = int(batch_size), int(seed)
        self.jobs = int(jobs)
        for name, v, lo in (("batch_size", self.batch_size, 1), ("jobs", self.jobs, 1),
                            ("val_replicates", self.val_replicates, 1),
                            ("test_replicates", self.test_replicates, 0),
                            ("gearboxes", int(gearboxes), 1)):
            if v is not None and v < lo:
                raise ValueError(f"data.{name} = {v} must be >= {lo}")
        # a dataset built here holds the trained cases only (the main job stays short)
        spec = {"cases": self.cases,
                "replicates": replicates_per_case(int(gearboxes), len(self.cases)),
                **dict(generate or {})}
        if "chunks" not in spec:  # a user's count wins; the spec's checks come first
            work = spec_from_config(spec | {"chunks": 1}).units
            spec["chunks"] = min(BUILD_CHUNKS, work)
        self.generate = spec
        self.table = None
        self.labels: pd.DataFrame | None = None  # a user table's columns besides the network's
        self.source = self.dataset if table is None else str(table)  # named in errors
        self.units = dataset_units()
        self.group = self.group_by = None
        self.test_codes = self.val_codes = None
        self.cv, self.fold_label = cv, None
        self.folds: list[int] = []
        if cv not in (None, "logo"):
            raise ValueError(f"data.cv = {cv!r} must be logo (leave one group out: one fold per "
                             "value of data.group_by) or null")
        if table is not None:  # a user's own data: read and checked now, before any work
            self._read_table(table, dict(columns or {}), group, group_by, units, test_groups,
                             val_groups, holdout_case)
        else:
            given = [f"data.{k}" for k, v in (("group_by", group_by), ("test_groups", test_groups),
                                              ("val_groups", val_groups), ("cv", cv),
                                              ("units", units)) if v]
            if given:
                raise ValueError(f"{', '.join(given)} apply to a table of your own "
                                 "(data.table=...); the physics dataset is split by "
                                 "data.test_replicates, data.val_replicates and "
                                 "data.holdout_case")
            if not Path(self.dataset).is_file():
                dataset_job(self.dataset, self.generate, self.jobs)  # checks the build
            self.check_dataset_columns_and_split()
        self.schema: FeatureSchema | None = None
        self.frames: dict[str, pd.DataFrame] = {}

    def check_dataset_columns_and_split(self) -> None:
        """Before any work on the physics dataset: the inputs and the target are its columns,
        and each case has the trajectories the split asks for. Read from the file's header and
        its case and replicate columns or, for a dataset still to be built, from the columns
        and replicates the build will give."""
        if Path(self.dataset).is_file():
            import pyarrow.parquet as pq

            try:
                columns = pq.read_schema(self.dataset).names
                keys = pd.read_parquet(self.dataset, columns=["case", "replicate"])
            except Exception as err:  # any unreadable file: one line
                raise ValueError(f"data.dataset = {self.dataset} is not a readable dataset "
                                 f"({type(err).__name__}: {err}); delete it to build it "
                                 "again") from None
            counts = keys.groupby("case").replicate.nunique().to_dict()
        else:
            columns = list(dataset_units())
            counts = dict.fromkeys(self.cases, int(self.generate["replicates"]))
        # the dataset's line inputs, also where a file of an older layout lacks their parts
        self.set_vectors([*columns, *dataset_units()])
        self.units = with_vector_units(dataset_units(), self.vectors)
        missing = [c for c in [*self.sources, self.target] if c not in columns]
        if missing and set(missing) <= set(dataset_units()):  # a file of an older layout
            raise ValueError(f"data.inputs/data.target: columns {missing} are not in "
                             f"{self.source}, built by an older version of the dataset "
                             "API that did not write them; delete it to build it again")
        if missing:
            raise ValueError(f"data.inputs/data.target: columns {missing} are not in "
                             f"{self.source}; choose from {sorted(columns)}")
        for case in self.cases:
            if case in counts and case != self.holdout_case:
                check_split(case, counts[case], self.val_replicates, self.test_replicates,
                            self.holdout_case)

    def _read_table(self, table: str, columns: dict[str, str], group: str | None,
                    group_by: str | None, units: dict | None, test_groups: list | None,
                    val_groups: list | None, holdout_case: int | None) -> None:
        """Read, check and plan the split of a user's table (``data.table``): every refusal
        before any work."""
        if holdout_case is not None:
            raise ValueError("data.holdout_case applies to the physics dataset; in a table of "
                             "your own name the test groups by value: data.group_by=COLUMN "
                             "data.test_groups=[...]")
        raw = read_user_table(table, columns)
        # the dataset's line inputs too, so that a table without their parts is told to add them
        self.set_vectors([*raw.columns, *dataset_units()])
        needed = [*self.sources, self.target]
        self.units = with_vector_units(table_units(table, columns, units, needed), self.vectors)
        self.group, self.group_by = group, group_by or group
        self.table = user_rows(raw, table, group, needed, self.target, self.units, group_by,
                               tuple(vector_columns(self.vectors)))
        self.cases = [0]
        self.labels = raw[[c for c in raw.columns if c not in needed]]
        if self.baseline:  # before the split: its refusal names the rule, not the counts
            self.check_baselines(self.table)
        by = self.group_by
        uniques = pd.Index(pd.factorize(raw[by], sort=True)[1])
        self.group_values = [u.item() if isinstance(u, np.generic) else u for u in uniques]
        self.test_codes = match_groups(test_groups, uniques, "data.test_groups", by,
                                       self.source) or None
        self.val_codes = match_groups(val_groups, uniques, "data.val_groups", by,
                                      self.source) or None
        both = sorted(set(self.test_codes or []) & set(self.val_codes or []))
        if both:
            raise ValueError(f"data.test_groups and data.val_groups both name {by} = "
                             f"{[self.group_values[k] for k in both]}; a group tests or "
                             "validates, not both")
        if self.cv:
            if self.test_codes:
                raise ValueError("data.cv=logo tests on every group in turn; leave "
                                 "data.test_groups empty (data.val_groups stay fixed)")
            self.folds = [k for k in range(len(uniques)) if k not in (self.val_codes or [])]
            if len(self.folds) < 2:
                raise ValueError(f"data.cv=logo needs two or more values of {by!r} to leave "
                                 f"out in turn; {self.source} has {self.group_values}"
                                 + (" besides data.val_groups" if self.val_codes else ""))
            for k in self.folds:  # every fold's split refused now, not after some trained
                self.fold(k).split()
        else:
            self.split()

    def describe(self, n: int) -> str:
        """A user table's ``n`` trajectories in its own terms (for messages)."""
        if self.group_by == self.group:
            return f"{self.source} has {n} groups of {self.group!r}"
        return f"{self.source} has {n} trajectories (pairs of {self.group_by!r} and {self.group!r})"

    def split(self) -> dict[str, pd.DataFrame]:
        """The train/val/test rows of a user's table (:func:`split_table`)."""
        return split_table(self.table, self.test_codes, self.val_codes, self.val_replicates,
                           self.test_replicates, self.seed, self.describe)

    def fold(self, k: int) -> WearDataModule:
        """The data module of fold ``k`` of ``data.cv=logo``: the table's rows of the
        ``k``-th value of ``data.group_by`` (sorted) test, the rest train and validate."""
        dm = copy.copy(self)
        dm.test_codes, dm.cv, dm.folds = [k], None, []
        dm.fold_label = self.group_values[k]
        dm.schema, dm.frames = None, {}
        return dm

    @property
    def calibration_apart(self) -> bool:
        """Whether the interval is calibrated on validation trajectories that chose nothing
        (:func:`calibration_split`), not on those that also chose the epoch."""
        return self.frames["cal"] is not self.frames["val"]

    def split_summary(self) -> str:
        """Rows and trajectories of each part of the split, in the table's terms (``cal``: the
        validation trajectories that calibrate the interval, where they are apart)."""
        parts = {k: f for k, f in self.frames.items() if k != "cal" or self.calibration_apart}
        if self.table is None:
            return ", ".join(f"{k} {len(f)} rows ({f.groupby(['case', 'replicate']).ngroups} "
                             "trajectories)" for k, f in parts.items())
        by = self.group_by

        def values(f: pd.DataFrame) -> str:
            codes = np.sort(f.split_group.unique())
            shown = [self.group_values[c] for c in codes[:8]]
            return f"{by} {shown}{' ...' if len(codes) > 8 else ''}"

        return ", ".join(f"{k} {len(f)} rows ({values(f)})" for k, f in parts.items())

    def setup(self, stage: str | None = None) -> None:
        """Read (building it if missing) and split the data, once: Lightning calls this at
        every stage, and a single process needs no separate ``prepare_data``."""
        if self.schema is not None:
            return
        parts = self.split() if self.table is not None else self.split_dataset()
        self.frames = calibration_split(parts, self.seed)
        self.schema = FeatureSchema.fit(self.network_rows("train"), self.inputs, self.units,
                                        self.target, self.baseline, self.vectors)

    def split_dataset(self) -> dict[str, pd.DataFrame]:
        """The train/val/test rows of the physics dataset (built if missing) of the trained
        cases (:func:`split_trajectories`), its columns and baselines checked."""
        df = load_dataset(self.dataset, self.generate, self.jobs)
        unknown = sorted(set(self.cases) - set(df.case.unique().tolist()))
        if unknown:
            raise ValueError(f"cases {unknown} are not in {self.dataset} (it holds "
                             f"{sorted(df.case.unique().tolist())}); regenerate it with them")
        missing = [c for c in [*self.sources, self.target] if c not in df.columns]
        if missing:
            raise ValueError(f"columns {missing} are not in {self.dataset}; choose from "
                             f"{list(df.columns)}")
        df = df[df.case.isin(self.cases)]
        if self.baseline:
            self.check_baselines(df)
        return split_trajectories(df, self.val_replicates, self.test_replicates, self.seed,
                                  self.holdout_case)

    def check_baselines(self, df: pd.DataFrame) -> None:
        """Each trajectory's first row must be its baseline record, its least worn (the
        unworn one in the physics dataset); raise naming the first that is not."""
        keys = ["case", "replicate"]
        wear = df[self.target].to_numpy(float)
        least = df.groupby(keys, sort=False)[self.target].transform("min").to_numpy(float)
        bad = first_rows(df, keys) & (wear > least)
        if bad.any():
            r = int(np.argmax(bad))
            raise ValueError(
                f"{self.source}: trajectory {self.trajectory(df, r)} starts at "
                f"{self.target} = {wear[r]:.4g}, above its least ({least[r]:.4g}); "
                "data.baseline reads each trajectory against its first row, so that must be "
                "its baseline record (unworn, or its least worn): put it first")
        from surrogate.inference import check_gearboxes  # single rows, rows out of time order

        if self.labels is None:
            check_gearboxes(df, keys, None, f"{self.source} (a gearbox is a trajectory)")
            return
        ids = list(dict.fromkeys([self.group_by, self.group]))
        named = self.labels[ids].iloc[df.row.to_numpy()].reset_index(drop=True)
        cycles = df[["cycles"]].reset_index(drop=True) if df.cycles.notna().any() else None
        check_gearboxes(pd.concat([named, cycles], axis=1) if cycles is not None else named,
                        ids, None, f"{self.source} (a gearbox is a trajectory)")

    def trajectory(self, df: pd.DataFrame, r: int) -> dict:
        """The trajectory of row ``r`` of ``df`` (rows of this module), in the table's own
        columns where it is a user's table."""
        if self.labels is None:
            return df[["case", "replicate"]].iloc[[r]].to_dict("records")[0]
        ids = list(dict.fromkeys([self.group_by, self.group]))
        row = self.labels[ids].iloc[int(df.row.iloc[r])]
        return {k: v.item() if isinstance(v, np.generic) else v for k, v in row.items()}

    def set_vectors(self, columns: list[str]) -> None:
        """Find the complex-line inputs among ``columns`` (:func:`vector_inputs`)."""
        self.vectors = vector_inputs(self.inputs, columns)

    @property
    def sources(self) -> list[str]:
        """The columns the inputs are read from (a line input from its two parts)."""
        return source_columns(self.inputs, self.vectors)

    def network_rows(self, split: str) -> pd.DataFrame:
        """The rows of ``split`` as the network reads them: line inputs as magnitudes
        (:func:`vector_magnitudes`) and, with ``baseline``, the features as changes since each
        trajectory's first row (:func:`baseline_changes`; a line's as its vector change)."""
        return network_frame(self.frames[split], self.inputs, self.baseline, self.vectors,
                             ["case", "replicate"])

    def tensors(self, split: str) -> TensorDataset:
        rows = self.network_rows(split)
        x = self.schema.scale(rows[self.inputs].to_numpy(float))
        y = rows[self.target].to_numpy(float) / self.schema.target_scale
        return TensorDataset(torch.as_tensor(x, dtype=torch.float32),
                             torch.as_tensor(y, dtype=torch.float32))

    def train_dataloader(self) -> DataLoader:
        # the batches of ``shuffle=True`` (same permutation), each taken as one slice of the
        # tensors instead of row by row and stacked
        data, g = self.tensors("train"), torch.Generator().manual_seed(self.seed)
        order = BatchSampler(RandomSampler(data, generator=g), self.batch_size, drop_last=False)
        return DataLoader(data, sampler=order, batch_size=None, generator=g)

    def val_dataloader(self) -> DataLoader:
        return DataLoader(self.tensors("val"), batch_size=4096)

    def test_dataloader(self) -> DataLoader:
        return DataLoader(self.tensors("test"), batch_size=4096)
