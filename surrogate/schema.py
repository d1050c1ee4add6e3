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

    @classmethod
    def fit(cls, train: pd.DataFrame, inputs: list[str], units: dict[str, str],
            target: str) -> FeatureSchema:
        x = train[inputs].to_numpy(float)
        std = x.std(axis=0)
        std = np.where(std > 0, std, 1.0)  # a constant input (one case's lubricant) stays 0
        return cls(tuple(inputs), tuple(units[c] for c in inputs), target, units[target],
                   tuple(x.mean(axis=0).tolist()), tuple(std.tolist()),
                   tuple(x.min(axis=0).tolist()), tuple(x.max(axis=0).tolist()),
                   float(train[target].std()) or 1.0)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> FeatureSchema:
        if d.get("version") != SCHEMA_VERSION:
            raise ValueError(f"checkpoint schema version {d.get('version')!r} is not "
                             f"{SCHEMA_VERSION}: retrain the model with this package version")
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()})

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
            if scale > 0 and typical > 0 and not (scale / UNIT_FACTOR**2 < typical
                                                  < scale * UNIT_FACTOR):
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


#: identifying columns a prediction input may carry besides the features (passed through)
KEEP_COLUMNS = frozenset({"case", "replicate", "cycles", "record", "root_wear_mm",
                          "max_wear_mm", "mean_wear_mm", "eta0_Pa_s", "sigma_um", "n1_rpm",
                          "torque_Nm", *NUISANCE_COLUMNS})
#: columns an input may carry and the model ignores: the identifying ones and every other
#: column of the physics dataset (features of sensors or kinds the model does not use)
IGNORED_COLUMNS = KEEP_COLUMNS | frozenset(units())
