"""Wear from features on the CPU: ``python -m surrogate.predict ckpt=PATH input=FILE``.

``input`` is a CSV or parquet table with the feature columns the model was trained on (their
names and units are in the checkpoint; identifying columns such as ``case``, ``cycles`` or
``record`` are passed through). ``output`` (default: ``wear.csv`` in the run folder) gets the
input's identifying columns (true wear included, where given) and ``root_wear_mm_pred``, its
standard deviation, the interval bounds and the ``out_of_range`` flag. From Python::

    from surrogate.inference import Surrogate
    wear = Surrogate.load("wear_surrogate.pt").predict(features_df)
"""

from __future__ import annotations

import logging
from pathlib import Path

import hydra
import pandas as pd
from omegaconf import DictConfig

from physics.files import atomic_write
from surrogate.inference import Surrogate
from surrogate.schema import KEEP_COLUMNS

log = logging.getLogger(__name__)


def read_table(path: str | Path) -> pd.DataFrame:
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"input = {path} does not exist; pass a CSV or parquet feature table")
    if path.suffix == ".parquet":
        return pd.read_parquet(path)
    if path.suffix == ".csv":
        return pd.read_csv(path)
    raise ValueError(f"input = {path}: use a .csv or .parquet file")


def predict_file(ckpt: str | Path, source: str | Path, target: str | Path) -> pd.DataFrame:
    """Predict wear for every row of ``source`` with ``ckpt``; write ``target``; return it."""
    surrogate = Surrogate.load(ckpt)
    df = read_table(source)
    pred = surrogate.predict(df)
    keep = [c for c in df.columns if c in KEEP_COLUMNS and c not in pred.columns]
    result = pd.concat([df[keep], pred], axis=1)
    atomic_write(target, lambda p: result.to_csv(p, index=False))
    n_out = int(result.out_of_range.sum())
    if n_out:
        log.warning("%d of %d rows lie outside the training envelope (out_of_range): their "
                    "wear is an extrapolation", n_out, len(result))
    return result


@hydra.main(version_base="1.3", config_path="../conf", config_name="predict")
def main(cfg: DictConfig) -> None:
    out = predict_file(cfg.ckpt, cfg.input, cfg.output)
    log.info("%d rows -> %s", len(out), cfg.output)


if __name__ == "__main__":
    main()
