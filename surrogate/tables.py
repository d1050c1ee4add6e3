"""A user's own labelled table (``data.table``): reading it (CSV or parquet, columns renamed by
``data.columns``), the units of its columns (the dataset's for our names, a sidecar
``<table>.units.yaml``, ``data.units``) and the checks it passes before any training (group
keys, finite numbers, plausible values for each unit, one unit per column, wear that does not
fall), and its rows as the data module reads them (:func:`user_rows`). Every refusal names
the column, the row or the group, and the fix (docs/own-data.md).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from physics.dataset.generation import units as dataset_units
from physics.files import check_unrepeated, repeated
from surrogate.inputs import CONDITIONS
from surrogate.schema import vector_parts
from surrogate.settings import table_file

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
    path = table_file(path)
    check_unrepeated(path, f"data.table = {path}")
    try:
        df = pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError,
            OSError) as err:
        raise ValueError(f"data.table = {path} is not a readable table ({err})") from None
    unknown = sorted(set(columns) - set(df.columns))
    if unknown:
        raise ValueError(f"data.columns names {unknown}, which {path} does not have")
    df = df.rename(columns=columns)
    twice = repeated(df.columns)
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
    if side.exists() and not side.is_file():
        kind = "a folder" if side.is_dir() else "not a regular file (a FIFO or a device)"
        raise ValueError(f"{side}, the units sidecar of the table, is {kind}; make it a text "
                         "file of column: unit lines, or move it away and give data.units")
    if side.is_file():
        import yaml

        try:
            read = yaml.safe_load(side.read_text(encoding="utf-8"))
        except UnicodeDecodeError as err:
            raise ValueError(f"{side} is not UTF-8 text (byte {err.object[err.start]:#04x} at "
                             f"offset {err.start}); write the units sidecar as text, "
                             "column: unit per line") from None
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


def check_columns(df: pd.DataFrame, path: str | Path, needed: list[str], group: str | None,
                  group_by: str | None = None) -> None:
    """Refuse (ValueError, one line) a table that lacks its ``group`` or ``group_by`` column or
    a ``needed`` one (after ``data.columns``), naming them: before their units are asked for."""
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


def user_rows(df: pd.DataFrame, path: str | Path, group: str | None, needed: list[str],
              target: str | None = None, units: dict[str, str] | None = None,
              group_by: str | None = None, line_parts: tuple[str, ...] = (),
              operating: tuple[str, ...] = ()) -> pd.DataFrame:
    """A user's table (renamed) as the data module's rows: the ``needed`` columns as numbers,
    ``case`` 0, ``replicate`` the index of each trajectory in sorted order (a value of
    ``group``, or with ``group_by`` another column, a pair of the two), ``split_group`` the
    index of the row's ``group_by`` value in sorted order (of ``group`` without one), ``row``
    the row of the table, ``cycles`` where given (else NaN) and the estimator's features where
    given (:data:`ESTIMATOR_COLUMNS`) and the ``operating`` columns (the operating point, as
    numbers: :func:`~surrogate.inputs.operating_columns`). Checked by
    :func:`check_user_table` first (``line_parts`` as it takes them); the rows of each
    trajectory are read in the table's order."""
    path = Path(path)
    check_columns(df, path, needed, group, group_by)
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
    for name in (*ESTIMATOR_COLUMNS, *operating):
        if name in df.columns and name not in out.columns:
            out[name] = pd.to_numeric(df[name], errors="coerce").to_numpy(float)
    return out
