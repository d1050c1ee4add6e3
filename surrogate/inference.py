"""CPU inference: export a trained ensemble to a pickle-free file, load it, predict wear.

The exported file (``wear_surrogate.pt``) holds only tensors and plain values: the weights, the
hyperparameters and the :class:`~surrogate.schema.FeatureSchema`; it is read with
``torch.load(weights_only=True)``, so loading it runs no code.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import torch
from omegaconf import OmegaConf

from physics.files import atomic_write
from surrogate.model import WearRegressor, mixture
from surrogate.schema import FeatureSchema

FORMAT = "gearwear-wear-surrogate-2"  # 2: with the conformal interval scale


def export(model: WearRegressor, path: str | Path, interval_scale: float) -> Path:
    """Write the model's weights, hyperparameters, schema and the calibrated interval scale
    (:func:`conformal_scale`) to ``path`` (atomically)."""
    if not (math.isfinite(interval_scale) and interval_scale > 0):
        raise ValueError(f"interval_scale = {interval_scale!r} must be a finite number > 0")
    hparams = OmegaConf.to_container(OmegaConf.create(dict(model.hparams)))  # plain values only
    payload = {"format": FORMAT, "hparams": hparams, "interval_scale": float(interval_scale),
               "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()}}
    return atomic_write(path, lambda p: torch.save(payload, p))


def conformal_scale(mean: np.ndarray, std: np.ndarray, true: np.ndarray, level: float) -> float:
    """Split-conformal interval scale: the ``ceil((n + 1) level) / n`` empirical quantile of the
    normalised residuals ``|y - mu| / sigma`` on data the network did not train on (the
    validation trajectories), so that ``mu +- scale sigma`` covers a share ``level`` of new rows
    (Papadopoulos et al. 2002; Angelopoulos & Bates, "A gentle introduction to conformal
    prediction", 2021, sec. 2.3)."""
    scores = np.sort(np.abs(true - mean) / np.maximum(std, 1e-300))
    n = scores.size
    if n == 0:
        raise ValueError("no validation rows to calibrate the interval on")
    return float(scores[min(math.ceil((n + 1) * level), n) - 1])


class Surrogate:
    """A loaded ensemble: ``predict(df)`` returns wear with its interval and flags."""

    def __init__(self, model: WearRegressor, interval_scale: float) -> None:
        self.model = model.eval()
        self.schema = FeatureSchema.from_dict(model.hparams["schema"])
        self.interval_scale = interval_scale  # conformal: mu +- scale sigma at the trained level

    @classmethod
    def load(cls, path: str | Path) -> Surrogate:
        path = Path(path)
        if not path.is_file():
            raise ValueError(f"checkpoint {path} does not exist; train one with "
                             "`python train.py` (it writes wear_surrogate.pt in its run folder)")
        try:
            payload = torch.load(path, map_location="cpu", weights_only=True)
        except Exception as err:
            raise ValueError(f"{path} is not a safe wear-surrogate file ({err}); pass the "
                             "wear_surrogate.pt a training run exported") from None
        if not isinstance(payload, dict) or payload.get("format") != FORMAT:
            raise ValueError(f"{path} is not a {FORMAT} file; pass the wear_surrogate.pt a "
                             "training run exported")
        try:
            FeatureSchema.from_dict(payload["hparams"]["schema"])  # version check first
            model = WearRegressor(**payload["hparams"])
            model.load_state_dict(payload["state_dict"])
            scale = float(payload["interval_scale"])
        except (KeyError, TypeError, RuntimeError, ValueError) as err:
            raise ValueError(f"{path} is incomplete or from another model ({err}); pass the "
                             "wear_surrogate.pt a training run exported") from None
        bad = [k for k, v in payload["state_dict"].items() if not torch.isfinite(v).all()]
        if bad:
            raise ValueError(f"{path} has non-finite weights ({bad[0]}, ...): the training "
                             "diverged; retrain (e.g. with a smaller model.lr)")
        return cls(model, scale)

    def predict_array(self, x: np.ndarray, batch: int = 4096) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of wear for an unscaled input matrix (no checks).

        Batches of 4096 rows keep the members' activations in the cache: on one thread of this
        machine 3.3e6 rows/s against 1.6e6 with batches of 16384 (measured with the forward
        pass rows-first); the rates now and what else was tried: docs/surrogate.md,
        Throughput."""
        xs = torch.as_tensor(np.asarray(x, np.float32))
        shift = torch.as_tensor(self.schema.mean, dtype=torch.float32)
        inv = 1.0 / torch.as_tensor(self.schema.std, dtype=torch.float32)
        mean = torch.empty(len(xs))
        std = torch.empty(len(xs))
        with torch.inference_mode():
            for lo in range(0, len(xs), batch):
                m, v = mixture(self.model((xs[lo:lo + batch] - shift) * inv))
                mean[lo:lo + batch] = m
                std[lo:lo + batch] = v.clamp_min(0).sqrt()
        s = self.schema.target_scale
        return mean.numpy() * s, std.numpy() * s

    def predict(self, df: pd.DataFrame) -> pd.DataFrame:
        """Wear for every row of ``df`` (checked against the schema; see FeatureSchema.check).

        Columns: ``<target>_pred`` (clipped at 0: wear depth is not negative), ``<target>_std``,
        ``<target>_lower`` / ``_upper`` (the conformal interval of the trained level, clipped at
        0) and
        ``out_of_range`` (an input outside the training envelope: extrapolation).
        """
        x = self.schema.check(df)
        mean, std = self.predict_array(x)
        bad = ~(np.isfinite(mean) & np.isfinite(std))
        if bad.any():
            raise ValueError(f"the model gives a non-finite wear for row {int(np.argmax(bad))} "
                             f"({int(bad.sum())} of {len(bad)} rows); nothing is written")
        half = self.interval_scale * std
        t = self.schema.target
        return pd.DataFrame({f"{t}_pred": np.maximum(mean, 0.0), f"{t}_std": std,
                             f"{t}_lower": np.maximum(mean - half, 0.0),
                             f"{t}_upper": np.maximum(mean + half, 0.0),
                             "out_of_range": ~self.schema.in_envelope(x)}, index=df.index)
