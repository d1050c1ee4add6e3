"""The feature schema a surrogate is trained on, stored with it, and checked against its input."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from physics.dataset.generation import NUISANCE_COLUMNS
from physics.files import repeated
from physics.signals.order_analysis import VECTOR_PARTS

SCHEMA_VERSION = 2
#: a value this many times outside the training envelope (or its inverse) means a wrong unit
UNIT_FACTOR = 30.0
#: an operating point within this share of the training one (of its range, or of its value
#: where it did not vary) counts as the training one: a shaft speed held to 5 %
OPERATING_MARGIN = 0.05


@dataclass(frozen=True)
class FeatureSchema:
    """Input columns with units, the target, the input scaling and the training envelope."""

    inputs: tuple[str, ...]
    units: tuple[str, ...]
    target: str
    target_unit: str
    mean: tuple[float, ...]  # input scaling fitted on the training rows only
    std: tuple[float, ...]
    low: tuple[float, ...]  # training envelope per input
    high: tuple[float, ...]
    target_scale: float  # training target std
    version: int = SCHEMA_VERSION
    #: the inputs read as changes since the gearbox's baseline record (:func:`baseline_changes`,
    #: ``data.baseline``); empty: every input as measured
    baseline: tuple[str, ...] = ()
    #: the inputs that are complex lines, given as two columns ``<name>_re`` and ``<name>_im``
    #: and read as their magnitude (:func:`vector_magnitudes`)
    vectors: tuple[str, ...] = ()
    #: the training table's columns that state its operating point without being inputs (a
    #: shaft speed, a torque: :func:`surrogate.inputs.operating_columns`) and their range over
    #: the training rows; a row read outside it is flagged (:meth:`operating_outside`)
    operating: tuple[str, ...] = ()
    operating_low: tuple[float, ...] = ()
    operating_high: tuple[float, ...] = ()

    @property
    def columns(self) -> list[str]:
        """The columns an input table must hold: the inputs, each vector as its two parts."""
        return source_columns(self.inputs, self.vectors)

    @property
    def checked_columns(self) -> list[str]:
        """The columns a reading uses: :attr:`columns`, and the operating point's
        (:attr:`operating`: checked against the training one, not read by the model)."""
        return list(dict.fromkeys([*self.columns, *self.operating]))

    @classmethod
    def fit(cls, train: pd.DataFrame, inputs: list[str], units: dict[str, str],
            target: str, baseline: tuple[str, ...] = (),
            vectors: tuple[str, ...] = (), operating: tuple[str, ...] = ()) -> FeatureSchema:
        """The schema of a network trained on ``train`` (with ``baseline``: the rows as
        :func:`baseline_changes` gives them, so the scaling and envelope are of the changes);
        ``operating``: the columns of ``train`` that state its operating point (those it
        holds are recorded with their range)."""
        x = train[inputs].to_numpy(float)
        std = x.std(axis=0)
        std = np.where(std > 0, std, 1.0)  # a constant input (one case's lubricant) stays 0
        operating = tuple(c for c in operating if c in train.columns and c not in inputs)
        op = train[list(operating)].to_numpy(float)
        return cls(tuple(inputs), tuple(units[c] for c in inputs), target, units[target],
                   tuple(x.mean(axis=0).tolist()), tuple(std.tolist()),
                   tuple(x.min(axis=0).tolist()), tuple(x.max(axis=0).tolist()),
                   float(train[target].std()) or 1.0, baseline=tuple(baseline),
                   vectors=tuple(vectors), operating=operating,
                   operating_low=tuple(op.min(axis=0).tolist()) if operating else (),
                   operating_high=tuple(op.max(axis=0).tolist()) if operating else ())

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> FeatureSchema:
        if d.get("version") != SCHEMA_VERSION:
            raise ValueError(f"checkpoint schema version {d.get('version')!r} is not "
                             f"{SCHEMA_VERSION}: retrain the model with this package version")
        schema = cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()})
        schema.check_scaling()
        return schema

    def check_scaling(self) -> None:
        """Refuse (ValueError) a stored schema that cannot scale rows: one entry of each of
        the units, mean, std, low and high per input, finite, every deviation above zero (a
        training run stores 1 for an input that did not vary: :meth:`fit`) and the target's
        scale too. Dividing by a zero deviation gave every row an infinite input, and a zero
        target scale every row a wear of zero and an interval of width zero."""
        n = len(self.inputs)
        twice = repeated(self.inputs)
        if twice:
            raise ValueError(f"its schema names the input(s) {twice} more than once")
        for name in ("units", "mean", "std", "low", "high"):
            if len(getattr(self, name)) != n:
                raise ValueError(f"its schema has {len(getattr(self, name))} values of {name} "
                                 f"for {n} inputs")
        values = np.array([self.mean, self.std, self.low, self.high], float)
        bad = [c for c, ok in zip(self.inputs, np.isfinite(values).all(axis=0) & (values[1] > 0),
                                  strict=True) if not ok]
        if bad:
            raise ValueError(f"its input scaling of {bad} is not finite or has a deviation of "
                             "zero (std)")
        n_op = len(self.operating)
        try:
            ends = np.array([self.operating_low, self.operating_high], float).reshape(2, -1)
        except (TypeError, ValueError):  # not numbers, or of two lengths
            ends = np.full((2, n_op + 1), np.nan)
        if not all(isinstance(c, str) for c in self.operating) or ends.shape[1] != n_op or not (
                np.isfinite(ends).all() and (ends[0] <= ends[1]).all()):
            raise ValueError(f"its operating range of {list(self.operating)} is not one finite "
                             "low <= high pair per column")
        if not (math.isfinite(self.target_scale) and self.target_scale > 0):
            raise ValueError(f"its target scale {self.target_scale!r} is not a finite number "
                             "above zero")

    def network_rows(self, df: pd.DataFrame, gearbox: list[str] | None = None) -> pd.DataFrame:
        """``df`` as the network reads it: its :attr:`vectors` as magnitudes and, for a
        baseline model, its :attr:`baseline` columns as changes since the first row of each
        gearbox (:func:`baseline_changes`, a line's as its vector change,
        :func:`vector_magnitudes`; the rows sharing the values of the ``gearbox`` columns, its
        other inputs, the operating point, fixed); gearbox columns that are neither inputs nor
        identifying columns (:data:`KEEP_COLUMNS`) are dropped."""
        keys = list(gearbox or [])
        missing = [c for c in keys if c not in df.columns]
        if missing:
            raise ValueError(f"gearbox column(s) {missing} are not in the input; it has "
                             f"{list(df.columns)}")
        if self.baseline:
            if not keys:
                raise ValueError(
                    f"this model reads {list(self.baseline)} as changes since each gearbox's "
                    "baseline record: name the column(s) that tell the gearboxes apart "
                    "(gearbox=... on the command line, predict(df, gearbox=[...]) in Python), "
                    "with the rows of each gearbox in time order and the first its baseline "
                    "record (when new)")
        df = network_frame(df, self.inputs, self.baseline, self.vectors, keys)
        return df.drop(columns=[c for c in keys if c not in self.inputs
                                and c not in KEEP_COLUMNS])

    def readings(self, df: pd.DataFrame, gearbox: list[str]) -> np.ndarray:
        """True for the rows that are readings of wear: every row, or for a baseline model
        every row but each gearbox's baseline record (the reference, its change zero by
        construction and its interval clipped at zero wear: it cannot miss). Intervals are
        calibrated and their coverage scored on these rows."""
        return ~first_rows(df, gearbox) if self.baseline else np.ones(len(df), bool)

    def check(self, df: pd.DataFrame) -> np.ndarray:
        """The input matrix of ``df``, after checking its columns, values and units.

        Raises ``ValueError`` for a missing or repeated column, a value that is not a real
        number (:func:`check_numbers`), a NaN or infinite one, or a column whose values lie
        orders of magnitude outside the training envelope (a unit error, e.g. micrometres given
        for metres).
        """
        check_unrepeated_columns(df)
        missing = [c for c in self.inputs if c not in df.columns]
        if missing:
            units = dict(zip(self.inputs, self.units, strict=True))
            raise ValueError(f"input lacks column(s) {missing}; the model needs {units} "
                             "(column: unit)")
        if len(df) == 0:
            raise ValueError("input has no rows")
        x = real_columns(df, self.inputs)[list(self.inputs)].to_numpy(float)
        bad = ~np.isfinite(x)
        if bad.any():
            r, c = np.argwhere(bad)[0]
            name = self.inputs[c]
            shown = (f"{name} (its parts {vector_parts(name)})" if name in self.vectors
                     else name)
            raise ValueError(f"row {r + 1} column {shown} is {x[r, c]}: every input must "
                             "be finite; drop or repair such rows" + (
                                 " (read against the first record: the change since the "
                                 "gearbox's "
                                 "baseline record, so a NaN in that record spoils every row "
                                 "of the gearbox; repair it, do not drop it)"
                                 if self.inputs[c] in self.baseline else ""))
        # a change since the baseline may be near zero in any unit, and a gearbox of another
        # kind may change more than the training gearboxes did: only a far larger value (a
        # factor of a unit's size: 1e3, 1e6) is a unit error there
        factor = np.array([UNIT_FACTOR**2 if n in self.baseline else UNIT_FACTOR
                           for n in self.inputs])
        for j, name in enumerate(self.inputs):
            lo, hi = self.low[j], self.high[j]
            typical = float(np.median(np.abs(x[:, j])))
            scale = max(abs(lo), abs(hi))
            floor = 0.0 if name in self.baseline else scale / UNIT_FACTOR**2
            if scale > 0 and typical > 0 and not (floor < typical < scale * factor[j]):
                raise ValueError(
                    f"column {name}: typical value {typical:.3g} is far outside the training "
                    f"range [{lo:.3g}, {hi:.3g}] {self.units[j]}; is it in another unit? "
                    f"The model expects {self.units[j]}")
        scale = np.maximum(np.abs(self.low), np.abs(self.high))
        far = (np.abs(x) > scale * factor) & (scale > 0)
        if far.any():
            r, j = np.argwhere(far)[0]
            raise ValueError(
                f"row {r + 1} column {self.inputs[j]} is {x[r, j]:.4g}, more than {factor[j]:g} "
                f"times the training range [{self.low[j]:.3g}, {self.high[j]:.3g}] "
                f"{self.units[j]}: a unit or transcription error; repair or drop the row")
        return x

    def operating_values(self, df: pd.DataFrame) -> dict[str, np.ndarray]:
        """The values of the :attr:`operating` columns ``df`` holds, as numbers (NaN where a
        cell is not one)."""
        return {c: pd.to_numeric(df[c], errors="coerce").to_numpy(float)
                for c in self.operating if c in df.columns}

    def operating_outside(self, df: pd.DataFrame, margin: float = OPERATING_MARGIN,
                          values: dict[str, np.ndarray] | None = None
                          ) -> tuple[np.ndarray, list[str], list[str]]:
        """The rows of ``df`` read at an operating point the model was not trained at: a value
        of one of :attr:`operating` outside its training range widened by ``margin`` of the
        range or of the value's size, whichever is larger (a rig trained at 15 rev/s alone
        reads 15 +- 0.75). Returns that mask, the operating columns named in it (flagged rows'
        columns first), and the operating columns ``df`` lacks (its rows are read unchecked:
        the caller says so). A value that is not a finite number counts as outside.
        ``values``: :meth:`operating_values` of ``df``, where the caller has them."""
        values = self.operating_values(df) if values is None else values
        outside = np.zeros(len(df), bool)
        missing = [c for c in self.operating if c not in values]
        named = []
        for c, lo, hi in zip(self.operating, self.operating_low, self.operating_high,
                             strict=True):
            if c in missing:
                continue
            pad = margin * max(hi - lo, abs(lo), abs(hi))
            off = ~((values[c] >= lo - pad) & (values[c] <= hi + pad))
            if off.any():
                named.append(c)
            outside |= off
        return outside, named, missing

    def operating_check(self, df: pd.DataFrame) -> tuple[np.ndarray, str | None]:
        """The rows of ``df`` to flag for their operating point (:meth:`operating_outside`)
        and one line on it where a user must hear of it: rows without a number there, rows
        read outside the training one, or operating columns ``df`` lacks; None where none."""
        values = self.operating_values(df)
        flagged, named, missing = self.operating_outside(df, values=values)
        blank = np.zeros(len(df), bool)
        for v in values.values():
            blank |= ~np.isfinite(v)
        outside = flagged & ~blank
        parts = []
        if blank.any():
            parts.append(f"{int(blank.sum())} of {len(df)} rows give no number for "
                         f"{', '.join(values)}: flagged (out_of_range), their operating point "
                         "unknown")
        trained = {c: (lo, hi) for c, lo, hi in zip(self.operating, self.operating_low,
                                                     self.operating_high, strict=True)}

        def span(c: str) -> str:
            lo, hi = trained[c]
            return f"{c} {lo:.4g}" if lo == hi else f"{c} {lo:.4g}-{hi:.4g}"

        if outside.any():
            parts.append(f"{int(outside.sum())} of {len(df)} rows were measured at an "
                         f"operating point the model was not trained at "
                         f"({', '.join(span(c) for c in named)} in training): they are "
                         "flagged (out_of_range), their readings are not to be trusted")
        if missing:
            parts.append(f"the model was trained at {', '.join(span(c) for c in missing)}, "
                         f"and the input has no column {', '.join(missing)}: its rows' "
                         "operating point is not checked (add the column to have rows at "
                         "another one flagged)")
        return flagged, ("; ".join(parts) if parts else None)

    def operating_line(self, df: pd.DataFrame) -> str | None:
        """The line of :meth:`operating_check` alone."""
        return self.operating_check(df)[1]

    def in_envelope(self, x: np.ndarray, margin: float = 0.05) -> np.ndarray:
        """True for rows whose every input lies in the training range widened by ``margin``."""
        lo, hi = np.asarray(self.low), np.asarray(self.high)
        pad = margin * (hi - lo)
        return np.all((x >= lo - pad) & (x <= hi + pad), axis=1)

    def scale(self, x: np.ndarray) -> np.ndarray:
        return (x - np.asarray(self.mean)) / np.asarray(self.std)


def network_frame(df: pd.DataFrame, inputs, baseline, vectors, gearbox: list[str]
                  ) -> pd.DataFrame:
    """``df`` with its ``vectors`` as magnitudes and its ``baseline`` inputs as changes since
    each gearbox's first row (a line's as its vector change; the other inputs, the operating
    point, fixed within a gearbox): what a network of these inputs reads. Inputs ``df`` lacks
    are left for :meth:`FeatureSchema.check` to name."""
    if vectors:
        df = vector_magnitudes(df, vectors, gearbox if baseline else None)
    if not baseline:
        return df
    present = [c for c in inputs if c in df.columns]
    return baseline_changes(df, [c for c in present if c in baseline and c not in vectors],
                            gearbox, fixed=[c for c in present if c not in baseline])


def vector_inputs(inputs: list[str], columns: list[str]) -> tuple[str, ...]:
    """The ``inputs`` that are complex lines: not columns themselves, but their parts
    ``<name>_re`` and ``<name>_im`` are (the dataset's ``dte_line<k>``,
    :func:`physics.signals.order_analysis.mesh_lines`)."""
    have = set(columns)
    return tuple(c for c in inputs if c not in have and set(vector_parts(c)) <= have)


def check_unrepeated_columns(df: pd.DataFrame) -> None:
    """Refuse (ValueError) an input frame naming a column more than once."""
    twice = repeated(df.columns)
    if twice:
        raise ValueError(f"input has column(s) {twice} more than once; keep one of each")


def real_columns(df: pd.DataFrame, columns) -> pd.DataFrame:
    """``df`` with its ``columns`` checked (:func:`check_numbers`) and those not stored as
    numbers (text numbers, Decimals, nullable strings, complex cells without an imaginary
    part) as floats, so that later reads of them are plain numeric ones."""
    check_unrepeated_columns(df)
    check_numbers(df, columns)
    odd = [c for c in columns if c in df.columns and df[c].dtype.kind not in "iuf"]
    return df.assign(**{c: _as_real(df[c]) for c in odd}) if odd else df


def check_numbers(df: pd.DataFrame, columns) -> None:
    """Refuse (ValueError naming the row, counted from 1 without the header, the column and the
    cell) a cell of ``columns`` of ``df`` that is not a real number: text (``'abc'``), a
    complex number with an imaginary part (read as a float it would keep its real part alone)
    or a boolean (read as 0 or 1). Empty cells (NaN) are left to the finiteness check."""
    for c in columns:
        if c not in df.columns or df[c].dtype.kind in "iuf":
            continue
        col = df[c].to_numpy(object)
        why = [_not_real(v) for v in col]
        bad = [i for i, w in enumerate(why) if w]
        if bad:
            r = bad[0]
            raise ValueError(f"row {r + 1} column {c} is {col[r]!r}: {why[r]}; every input "
                             "must be a real number: repair the cell or drop the row")


def _as_real(col: pd.Series) -> np.ndarray:
    """A column of cells :func:`check_numbers` passed, as floats (a complex cell's imaginary
    part is zero there; an empty cell is NaN)."""
    return np.array([np.nan if _empty(v) else np.real(v) for v in col.to_numpy(object)], float)


def _empty(v: object) -> bool:
    """Whether a table cell ``v`` is empty (None, NaN, pandas' NA)."""
    return v is None or v is pd.NA or (isinstance(v, float) and np.isnan(v))


def _not_real(v: object) -> str:
    """Why a table cell ``v`` is neither empty nor a real number ('' where it is one)."""
    if isinstance(v, (bool, np.bool_)):
        return "a boolean (it would be read as 0 or 1), not a number"
    if isinstance(v, (complex, np.complexfloating)):
        return ("" if v.imag == 0 else "a complex number: give its magnitude (or the part "
                "the model was trained on)")
    if _empty(v):
        return ""
    try:
        float(v)
    except (TypeError, ValueError):
        return "not a real number"
    return ""


def vector_parts(name: str) -> list[str]:
    """The two columns of the complex line ``name``: ``<name>_re``, ``<name>_im``."""
    return [f"{name}_{p}" for p in VECTOR_PARTS]


def vector_columns(vectors) -> list[str]:
    """The parts of every complex line of ``vectors``, line by line."""
    return [part for v in vectors for part in vector_parts(v)]


def source_columns(inputs, vectors) -> list[str]:
    """``inputs`` with each of ``vectors`` replaced by its two parts."""
    return [part for c in inputs for part in (vector_parts(c) if c in vectors else [c])]


def vector_magnitudes(df: pd.DataFrame, vectors, gearbox: list[str] | None = None
                      ) -> pd.DataFrame:
    """``df`` with a column per name of ``vectors``: the magnitude of the complex line whose
    parts are ``<name>_re`` and ``<name>_im`` or, with ``gearbox``, of its change since the
    gearbox's first row (:func:`first_rows`): the vector change of a synchronous component
    against its reference record (ISO 10816-1:1995, Annex D), which for a line referenced to
    a once-per-revolution mark is free of the offset of that mark and, the transmission error
    being linear in the flanks' deviations, of the flank form the gearbox was made with
    (:func:`physics.signals.order_analysis.mesh_lines`)."""
    parts = vector_columns(vectors)
    missing = [c for c in parts if c not in df.columns]
    if missing:
        raise ValueError(f"input lacks column(s) {missing}: a line input (e.g. dte_line1) is "
                         "given as its real and imaginary parts, <name>_re and <name>_im, "
                         "against a once-per-revolution mark")
    z = df[parts].to_numpy(float).reshape(len(df), len(vectors), 2)
    if gearbox:
        z = z - z[baseline_of_rows(df, gearbox)]
    out = df.copy()
    out[list(vectors)] = np.hypot(z[..., 0], z[..., 1])
    return out


def baseline_of_rows(df: pd.DataFrame, gearbox: list[str]) -> np.ndarray:
    """The position of each row's baseline record, its gearbox's first row."""
    first = first_rows(df, gearbox)
    # groups numbered in order of first appearance: the first rows are groups 0, 1, 2, ...
    return np.flatnonzero(first)[df.groupby(gearbox, sort=False).ngroup().to_numpy()]


def first_rows(df: pd.DataFrame, gearbox: list[str]) -> np.ndarray:
    """True for the first row (in the table's order) of each gearbox, the rows sharing the
    values of the ``gearbox`` columns: its baseline record. Raises for a missing key."""
    nan = df[gearbox].isna().any(axis=1)
    if nan.any():
        raise ValueError(f"{int(nan.sum())} row(s) have no value in the gearbox column(s) "
                         f"{gearbox} (first: row {int(np.argmax(nan.to_numpy()))}); give every "
                         "row its gearbox")
    return ~df.duplicated(gearbox, keep="first").to_numpy()


def baseline_changes(df: pd.DataFrame, columns: list[str], gearbox: list[str],
                     fixed: list[str] = ()) -> pd.DataFrame:
    """``df`` with each of ``columns`` replaced by its change since the gearbox's baseline
    record, its first row (:func:`first_rows`): zero there. The ``fixed`` columns (the
    operating point) must not vary within a gearbox, and a ``cycles`` column, where given,
    must not fall: a record is compared with a baseline at its own operating point and from
    before it.

    A gearbox's own run-out, profile error and stiffness set the level of every feature
    before any wear; the change since the baseline is free of that level (not of how these
    shape the change). Condition monitoring reads a machine against its own reference value
    in the same way (ISO 20816-1:2016, evaluation criterion II: the change of broadband
    vibration magnitude from a reference value; used here for every feature by analogy)."""
    of_row = baseline_of_rows(df, gearbox)
    for name in [*fixed, *(["cycles"] if "cycles" in df.columns else [])]:
        values = df[name].to_numpy(float)
        base = values[of_row]
        # NaN is check()'s to name; cycles: the baseline is the gearbox's earliest record
        bad = values < base if name == "cycles" else ~np.isnan(values) & (values != base)
        if bad.any():
            r = int(np.argmax(bad))
            rule = ("the baseline record first (the earliest): sort each gearbox's rows by "
                    "cycles" if name == "cycles" else "one operating point per gearbox: add "
                    "the operating-point column(s) to the gearbox columns and give each "
                    "operating point its own baseline record")
            which = df[gearbox].iloc[[r]].to_dict("records")[0]
            raise ValueError(f"row {r}, gearbox {which}: {name} = "
                             f"{values[r]:g} against {base[r]:g} in its baseline record (its "
                             f"first row); a model read against it needs {rule}")
    out = df.copy()
    values = df[columns].to_numpy(float)
    out[columns] = values - values[of_row]
    return out


#: identifying columns a prediction input may carry besides the features (passed through)
KEEP_COLUMNS = frozenset({"case", "replicate", "cycles", "record", "root_wear_mm",
                          "max_wear_mm", "mean_wear_mm", "eta0_Pa_s", "sigma_um", "n1_rpm",
                          "torque_Nm", *NUISANCE_COLUMNS})
