"""The feature schema a surrogate is trained on, stored with it, and checked against its input."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from physics.dataset.generation import NUISANCE_COLUMNS, units

SCHEMA_VERSION = 1
#: a value this many times outside the training envelope (or its inverse) means a wrong unit
UNIT_FACTOR = 30.0


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

    @classmethod
    def fit(cls, train: pd.DataFrame, inputs: list[str], units: dict[str, str],
            target: str, baseline: tuple[str, ...] = ()) -> FeatureSchema:
        """The schema of a network trained on ``train`` (with ``baseline``: the rows as
        :func:`baseline_changes` gives them, so the scaling and envelope are of the changes)."""
        x = train[inputs].to_numpy(float)
        std = x.std(axis=0)
        std = np.where(std > 0, std, 1.0)  # a constant input (one case's lubricant) stays 0
        return cls(tuple(inputs), tuple(units[c] for c in inputs), target, units[target],
                   tuple(x.mean(axis=0).tolist()), tuple(std.tolist()),
                   tuple(x.min(axis=0).tolist()), tuple(x.max(axis=0).tolist()),
                   float(train[target].std()) or 1.0, baseline=tuple(baseline))

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> FeatureSchema:
        if d.get("version") != SCHEMA_VERSION:
            raise ValueError(f"checkpoint schema version {d.get('version')!r} is not "
                             f"{SCHEMA_VERSION}: retrain the model with this package version")
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()})

    def network_rows(self, df: pd.DataFrame, gearbox: list[str] | None = None) -> pd.DataFrame:
        """``df`` as the network reads it: for a baseline model its :attr:`baseline` columns
        as changes since the first row of each gearbox (the rows sharing the values of the
        ``gearbox`` columns); gearbox columns that are neither inputs nor identifying columns
        (:data:`KEEP_COLUMNS`) are dropped."""
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
            cols = [c for c in self.baseline if c in df.columns]  # check() names missing ones
            df = baseline_changes(df, cols, keys)
        return df.drop(columns=[c for c in keys if c not in self.inputs
                                and c not in KEEP_COLUMNS])

    def check(self, df: pd.DataFrame) -> np.ndarray:
        """The input matrix of ``df``, after checking its columns, values and units.

        Raises ``ValueError`` for a missing or unknown column, a non-numeric, NaN or infinite
        value, or a column whose values lie orders of magnitude outside the training envelope
        (a unit error, e.g. micrometres given for metres).
        """
        missing = [c for c in self.inputs if c not in df.columns]
        if missing:
            units = dict(zip(self.inputs, self.units, strict=True))
            raise ValueError(f"input lacks column(s) {missing}; the model needs {units} "
                             "(column: unit)")
        extra = [c for c in df.columns if c not in self.inputs and c not in IGNORED_COLUMNS]
        if extra:
            raise ValueError(f"input has column(s) {extra} the model was not trained on; drop "
                             f"them (allowed besides the inputs: {sorted(KEEP_COLUMNS)} and "
                             "the dataset's other features)")
        if len(df) == 0:
            raise ValueError("input has no rows")
        try:
            x = df[list(self.inputs)].to_numpy(float)
        except ValueError as err:
            raise ValueError(f"input columns must be numeric: {err}") from None
        bad = ~np.isfinite(x)
        if bad.any():
            r, c = np.argwhere(bad)[0]
            raise ValueError(f"row {r} column {self.inputs[c]} is {x[r, c]}: every input must "
                             "be finite; drop or repair such rows")
        for j, name in enumerate(self.inputs):
            lo, hi = self.low[j], self.high[j]
            typical = float(np.median(np.abs(x[:, j])))
            scale = max(abs(lo), abs(hi))
            # a change since the baseline may be near zero in any unit: only too large a value
            # is a unit error there
            floor = 0.0 if name in self.baseline else scale / UNIT_FACTOR**2
            if scale > 0 and typical > 0 and not (floor < typical < scale * UNIT_FACTOR):
                raise ValueError(
                    f"column {name}: typical value {typical:.3g} is far outside the training "
                    f"range [{lo:.3g}, {hi:.3g}] {self.units[j]}; is it in another unit? "
                    f"The model expects {self.units[j]}")
        scale = np.maximum(np.abs(self.low), np.abs(self.high))
        far = (np.abs(x) > scale * UNIT_FACTOR) & (scale > 0)
        if far.any():
            r, j = np.argwhere(far)[0]
            raise ValueError(
                f"row {r} column {self.inputs[j]} is {x[r, j]:.4g}, more than {UNIT_FACTOR:g} "
                f"times the training range [{self.low[j]:.3g}, {self.high[j]:.3g}] "
                f"{self.units[j]}: a unit or transcription error; repair or drop the row")
        return x

    def in_envelope(self, x: np.ndarray, margin: float = 0.05) -> np.ndarray:
        """True for rows whose every input lies in the training range widened by ``margin``."""
        lo, hi = np.asarray(self.low), np.asarray(self.high)
        pad = margin * (hi - lo)
        return np.all((x >= lo - pad) & (x <= hi + pad), axis=1)

    def scale(self, x: np.ndarray) -> np.ndarray:
        return (x - np.asarray(self.mean)) / np.asarray(self.std)


def baseline_changes(df: pd.DataFrame, columns: list[str], gearbox: list[str]) -> pd.DataFrame:
    """``df`` with each of ``columns`` replaced by its change since the first row (in the
    table's order) of the row's gearbox, the rows sharing the values of the ``gearbox`` columns.

    Condition monitoring reads vibration against a reference value taken on the machine
    itself (ISO 20816-1:2016, evaluation criterion II: the change of vibration magnitude from
    a reference value). A gearbox's own run-out, profile error and stiffness set the level of
    every feature before any wear; the change is what wear adds. The first row of a gearbox is
    its baseline: its changes are zero."""
    idx = df.groupby(gearbox, sort=False, dropna=False).ngroup().to_numpy()
    first = np.unique(idx, return_index=True)[1]
    values = df[columns].to_numpy(float)
    out = df.copy()
    out[columns] = values - values[first][idx]
    return out


#: identifying columns a prediction input may carry besides the features (passed through)
KEEP_COLUMNS = frozenset({"case", "replicate", "cycles", "record", "root_wear_mm",
                          "max_wear_mm", "mean_wear_mm", "eta0_Pa_s", "sigma_um", "n1_rpm",
                          "torque_Nm", *NUISANCE_COLUMNS})
#: columns an input may carry and the model ignores: the identifying ones and every other
#: column of the physics dataset (features of sensors or kinds the model does not use)
IGNORED_COLUMNS = KEEP_COLUMNS | frozenset(units())
