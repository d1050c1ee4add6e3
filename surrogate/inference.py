"""CPU inference: export a trained ensemble to a pickle-free file, load it, predict wear.

The exported file (``wear_surrogate.pt``) holds only tensors and plain values: the weights, the
hyperparameters, the :class:`~surrogate.schema.FeatureSchema`, the conformal interval's scale
and the :class:`~surrogate.novelty.Novelty` (training rows and threshold); it is read with
``torch.load(weights_only=True)``, so loading it runs no code.

Predictions run in torch (:func:`torch_predict`: the input scaling, the members and their
mixture as one module, :class:`ScaledEnsemble`). A caller that predicts many times from one
loaded model (a monitoring service) calls :meth:`Surrogate.serve`: the same graph exported to
ONNX Runtime (:func:`onnx_session`), faster per call, after a one-off export and import that
take longer than torch needs for a million rows (``bench/bench_surrogate.py`` measures both;
docs/benchmark.md, Training and inference time).
"""

from __future__ import annotations

import copy
import io
import logging
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
import torch
from omegaconf import OmegaConf

from physics.files import atomic_write
from surrogate.candidates import Candidate
from surrogate.conformal import cv_plus, exchangeable_quantile
from surrogate.network import Network, mixture
from surrogate.novelty import Novelty, difficulty
from surrogate.schema import FeatureSchema, real_columns
from surrogate.settings import model_file

if TYPE_CHECKING:  # the training module imports Lightning, which inference does without
    import onnxruntime as ort

    from surrogate.model import WearRegressor

log = logging.getLogger(__name__)


def _first_line(err: BaseException, most: int = 200) -> str:
    """The first line of ``err``'s text, cut at ``most`` characters: torch's refusal of a
    foreign file runs to a dozen lines of advice about its own settings."""
    text = (str(err).strip().splitlines() or [type(err).__name__])[0]
    return text if len(text) <= most else text[:most - 3] + "..."

# 2: with the conformal interval scale; 3: with the novelty (normalised conformal interval)
FORMAT = "gearwear-wear-surrogate-3"
#: a model other than the network chosen by cross-validation (surrogate.candidates), with the
#: fold models and out-of-fold residuals of its CV+ interval
CHOSEN_FORMAT = "gearwear-wear-chosen-1"


@dataclass
class Chosen:
    """A non-network model kept by cross-validation (:mod:`surrogate.candidates`) and its
    CV+ interval (:func:`~surrogate.conformal.cv_plus`): the model fitted on all training
    groups, the fold models, each training row's fold, out-of-fold residual and group."""

    schema: FeatureSchema
    model: Candidate
    folds: list[Candidate]
    fold_of: np.ndarray
    residuals: np.ndarray
    groups: np.ndarray
    level: float
    reason: str = ""

    def readings(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The model's reading of unscaled rows ``x`` and each fold model's (rows, folds)."""
        xs = self.schema.scale(np.asarray(x, float))
        return (self.model.predict(xs, x),
                np.column_stack([f.predict(xs, x) for f in self.folds]))

    def payload(self) -> dict:
        return {"format": CHOSEN_FORMAT, "schema": self.schema.to_dict(),
                "model": self.model.payload(), "folds": [f.payload() for f in self.folds],
                "fold_of": torch.tensor(np.array(self.fold_of), dtype=torch.int64),
                "residuals": torch.tensor(np.array(self.residuals), dtype=torch.float64),
                "groups": torch.tensor(np.array(self.groups), dtype=torch.int64),
                "level": float(self.level), "reason": self.reason}

    @classmethod
    def from_payload(cls, d: dict) -> Chosen:
        return cls(FeatureSchema.from_dict(d["schema"]), Candidate.from_payload(d["model"]),
                   [Candidate.from_payload(f) for f in d["folds"]], d["fold_of"].numpy(),
                   d["residuals"].numpy(), d["groups"].numpy(), float(d["level"]),
                   str(d.get("reason", "")))


def export_chosen(chosen: Chosen, path: str | Path, novelty: Novelty) -> Path:
    """Write a :class:`Chosen` model and the novelty reference to ``path`` (atomically)."""
    payload = {**chosen.payload(), "novelty": novelty.payload()}
    return atomic_write(path, lambda p: torch.save(payload, p))


def export(model: Network | WearRegressor, path: str | Path, interval_scale: float,
           novelty: Novelty) -> Path:
    """Write the model's weights, hyperparameters, schema, the calibrated interval scale
    (:func:`conformal_scale` of the :func:`~surrogate.novelty.difficulty`) and the novelty
    reference to ``path`` (atomically)."""
    if not (math.isfinite(interval_scale) and interval_scale > 0):
        raise ValueError(f"interval_scale = {interval_scale!r} must be a finite number > 0")
    hparams = OmegaConf.to_container(OmegaConf.create(dict(model.hparams)))  # plain values only
    payload = {"format": FORMAT, "hparams": hparams, "interval_scale": float(interval_scale),
               "novelty": novelty.payload(),
               "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()}}
    return atomic_write(path, lambda p: torch.save(payload, p))


def conformal_scale(mean: np.ndarray, std: np.ndarray, true: np.ndarray, level: float,
                    groups: np.ndarray | None = None) -> float:
    """Split-conformal interval scale from the normalised residuals ``|y - mu| / sigma`` on
    data the network did not train on (the calibration trajectories), so that
    ``mu +- scale sigma`` covers a share ``level`` of new rows (Papadopoulos et al. 2002):
    their :func:`~surrogate.conformal.exchangeable_quantile`, by gearbox where ``groups``
    labels the rows' gearboxes (a gearbox's readings err together). ``std`` is the rows'
    difficulty: the ensemble's deviation widened by the novelty
    (:func:`surrogate.novelty.difficulty`; normalised conformal prediction, Papadopoulos, Vovk
    & Gammerman 2011)."""
    scores = np.abs(np.asarray(true, float) - mean) / np.maximum(std, 1e-300)
    if scores.size == 0:
        raise ValueError("no calibration rows to calibrate the interval on")
    return exchangeable_quantile(scores, level, groups)


class ScaledEnsemble(torch.nn.Module):
    """Unscaled inputs -> mean and standard deviation of wear in the target's unit: the
    ensemble and its Gaussian mixture (:func:`mixture`) on a copy of the network whose first
    layer carries the schema's input scaling, ``((x - shift) / std) W + b = x W' + b'`` with
    ``W' = W / std`` and ``b' = b - (shift / std) W`` (one pass over the rows fewer)."""

    def __init__(self, model: Network | WearRegressor, schema: FeatureSchema) -> None:
        super().__init__()
        self.net = copy.deepcopy(model.net).eval()
        inv = 1.0 / torch.tensor(schema.std, dtype=torch.float64)
        shift = torch.tensor(schema.mean, dtype=torch.float64) * inv
        with torch.no_grad():  # in double: mean / std reaches 20 for the operating point
            w, b = self.net.weights[0], self.net.biases[0]
            w64 = w.double()
            b.copy_(b.double() - torch.einsum("i,mio->mo", shift, w64).unsqueeze(1))
            w.copy_(w64 * inv[None, :, None])
        self.target_scale = float(schema.target_scale)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        mean, var = mixture(self.net(x))
        return mean * self.target_scale, var.clamp_min(0).sqrt() * self.target_scale


def torch_predict(graph: ScaledEnsemble, x: np.ndarray, batch: int = 4096
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation of wear for unscaled rows ``x``, in torch (the reference of
    :meth:`Surrogate.predict_array`)."""
    xs = torch.as_tensor(np.asarray(x, np.float32))
    with torch.inference_mode():
        parts = [graph(xs[lo:lo + batch]) for lo in range(0, len(xs), batch)]
    return (torch.cat([m for m, _ in parts]).numpy(), torch.cat([s for _, s in parts]).numpy())


def onnx_session(model: Network | WearRegressor, schema: FeatureSchema, threads: int
                 ) -> ort.InferenceSession:
    """:class:`ScaledEnsemble` as an ONNX Runtime session on ``threads`` threads.

    ONNX and ONNX Runtime are imported here: about a second, which a single prediction does
    without.

    Exported in memory by torch's TorchScript-based exporter (the torch.export-based one is
    many times slower for the same graph); ONNX Runtime fuses each ``x sigmoid(x)`` into one
    kernel and the first layer's product with its bias."""
    import onnxruntime as ort

    n_in = len(schema.inputs)
    graph = ScaledEnsemble(model, schema).eval()
    buf = io.BytesIO()
    with warnings.catch_warnings():  # the exporter's notice that a newer one exists
        warnings.simplefilter("ignore", DeprecationWarning)
        torch.onnx.export(graph, (torch.zeros(2, n_in),), buf, dynamo=False,
                          input_names=["x"], output_names=["mean", "std"],
                          dynamic_axes={"x": {0: "rows"}, "mean": {0: "rows"},
                                        "std": {0: "rows"}})
    options = ort.SessionOptions()
    options.intra_op_num_threads = threads
    options.inter_op_num_threads = 1
    return ort.InferenceSession(buf.getvalue(), options, providers=["CPUExecutionProvider"])


def check_gearboxes(df: pd.DataFrame, gearbox: list[str], target: str | None = None,
                    source: str = "input") -> None:
    """What a baseline model needs of each gearbox (the rows sharing the ``gearbox`` columns'
    values), refused with one line naming the gearbox:

    - at least two rows: the first is its baseline record (read as no change), so a gearbox
      of one row has nothing to read against it;
    - its rows in time order: where a ``cycles`` column is given its values must not fall
      from row to row (the first row, the baseline record, is then the earliest). Without
      one, the table's row order is taken as the time order;
    - where the true wear (``target``) is given, the first row is the least worn.
    """
    from surrogate.schema import first_rows

    keys = list(gearbox)
    if not keys or any(k not in df.columns for k in keys) or df.empty:
        return  # network_rows names what is missing
    first = first_rows(df, keys)  # refuses a row without its gearbox
    groups = df.groupby(keys, sort=False, dropna=False)
    rows = np.arange(len(df))

    def name(g) -> str:
        values = g if isinstance(g, tuple) else (g,)
        return repr({k: v.item() if isinstance(v, np.generic) else v
                     for k, v in zip(keys, values, strict=True)})

    sizes = groups.size()
    if (sizes < 2).any():
        g = sizes.index[int(np.argmax((sizes < 2).to_numpy()))]
        raise ValueError(f"{source}: gearbox {name(g)} has a single row; this model reads "
                         "each row as its change since the gearbox's baseline record (its first "
                         "row), so each gearbox needs its baseline record and later records: "
                         "add them, or leave this gearbox out")
    for col, rule in (("cycles", "sort each gearbox's rows by cycles"),):
        if col not in df.columns:
            continue
        values = pd.to_numeric(df[col], errors="coerce").to_numpy(float)
        for g, idx in groups.indices.items():
            v = values[idx]
            ok = np.isfinite(v)
            falls = np.flatnonzero(np.diff(v[ok]) < 0)
            if falls.size:
                a, b = rows[idx][ok][falls[0]], rows[idx][ok][falls[0] + 1]
                raise ValueError(f"{source}: gearbox {name(g)}: rows {a} and {b} are out of "
                                 f"time order ({col} {values[a]:g} then {values[b]:g}); this "
                                 "model reads the first row as the baseline record "
                                 f"and the rest after it: {rule}")
    if target is not None and target in df.columns:
        wear = pd.to_numeric(df[target], errors="coerce").to_numpy(float)
        least = df.assign(_w=wear).groupby(keys, sort=False)["_w"].transform("min").to_numpy()
        bad = first & (wear > least)
        if bad.any():
            r = int(np.argmax(bad))
            g = tuple(df[keys].iloc[r]) if len(keys) > 1 else df[keys[0]].iloc[r]
            raise ValueError(f"{source}: gearbox {name(g)} has no baseline record: its first "
                             f"row (row {r}) has {target} = {wear[r]:.4g}, above its least "
                             f"({least[r]:.4g}); put the gearbox's earliest (least worn) "
                             "record first")


def gearbox_columns(value) -> tuple[str, ...]:
    """``gearbox`` of the config or of :meth:`Surrogate.predict`: none, one column name or a
    list of them."""
    if value is None:
        return ()
    names = [value] if isinstance(value, str) else value
    if not isinstance(names, Sequence) or not names or not all(
            isinstance(n, str) and n for n in names):
        raise ValueError(f"gearbox = {value!r} must be a column name or a list of them")
    return tuple(names)


class Surrogate:
    """A loaded ensemble: ``predict(df)`` returns wear with its interval and flags."""

    def __init__(self, model: Network | WearRegressor | None, interval_scale: float,
                 novelty: Novelty | None = None, chosen: Chosen | None = None) -> None:
        #: the network (None where another model was chosen: ``chosen``)
        self.model = None if model is None else model.eval()
        #: the model other than the network kept by cross-validation, with its CV+ interval
        self.chosen = chosen
        self.schema = (chosen.schema if chosen is not None
                       else FeatureSchema.from_dict(model.hparams["schema"]))
        # conformal: mu +- scale difficulty at the trained level
        self.interval_scale = interval_scale
        #: the training rows and the flag's threshold (None: a network not yet calibrated,
        #: whose rows get no novelty score and whose interval is of the ensemble's spread)
        self.novelty = novelty
        self._session: ort.InferenceSession | None = None  # serve()

    @classmethod
    def load(cls, path: str | Path, key: str = "checkpoint") -> Surrogate:
        """The model exported to ``path`` (checked whole; a refusal names it as ``key``: the
        option or argument that gave it)."""
        path = model_file(path, key)
        named, fix = f"{key} = {str(path)!r}", "pass the wear_surrogate.pt a training run exported"
        try:
            payload = torch.load(path, map_location="cpu", weights_only=True)
        except Exception as err:
            raise ValueError(f"{named} is not a safe wear-surrogate file ({_first_line(err)}); "
                             f"{fix}") from None
        if isinstance(payload, dict) and payload.get("format") == CHOSEN_FORMAT:
            try:
                chosen = Chosen.from_payload(payload)
                novelty = Novelty.from_payload(payload["novelty"])
            except (KeyError, TypeError, AttributeError, RuntimeError, ValueError) as err:
                raise ValueError(f"{named} is incomplete or from another model "
                                 f"({_first_line(err)}); {fix}") from None
            return cls(None, 1.0, novelty, chosen)
        if not isinstance(payload, dict) or payload.get("format") != FORMAT:
            raise ValueError(f"{named} is not a {FORMAT} file; {fix}")
        try:
            schema = FeatureSchema.from_dict(payload["hparams"]["schema"])  # version first
            model = Network(payload["hparams"])
            model.load_state_dict(payload["state_dict"])
            scale = float(payload["interval_scale"])
            if not (math.isfinite(scale) and scale > 0):
                raise ValueError(f"its interval scale {scale!r} is not a finite number above "
                                 "zero")
            if len(schema.inputs) != int(payload["hparams"]["n_inputs"]):
                raise ValueError(f"its schema names {len(schema.inputs)} inputs, its network "
                                 f"takes {payload['hparams']['n_inputs']}")
            novelty = Novelty.from_payload(payload["novelty"])
            if novelty.reference.shape[1] != len(model.hparams["schema"]["inputs"]):
                raise ValueError("its novelty reference has another number of inputs")
        except (KeyError, TypeError, RuntimeError, ValueError) as err:
            raise ValueError(f"{named} is incomplete or from another model "
                             f"({_first_line(err)}); {fix}") from None
        bad = [k for k, v in payload["state_dict"].items() if not torch.isfinite(v).all()]
        if bad:
            raise ValueError(f"{named} has non-finite weights ({bad[0]}, ...): the training "
                             "diverged; retrain (e.g. with a smaller model.lr)")
        return cls(model, scale, novelty)

    @property
    def kind(self) -> str:
        """The model's kind: ``network`` or one of :data:`surrogate.candidates.KINDS`."""
        return "network" if self.chosen is None else self.chosen.model.kind

    @cached_property
    def graph(self) -> ScaledEnsemble:
        """The network with its input scaling and mixture, in torch (:class:`ScaledEnsemble`),
        built on first use from the weights as they are then."""
        return ScaledEnsemble(self.model, self.schema).eval()

    def serve(self, threads: int | None = None) -> Surrogate:
        """Predict from now on in ONNX Runtime (:func:`onnx_session`, on ``threads`` threads;
        as many as torch uses in this process where not given) and return this model: for a
        caller that predicts many times from one loaded model. The export and the import cost
        about 2 s once; each call then takes about a seventh of torch's time for one row and
        less than half of it for many (docs/benchmark.md). A model other than the network has
        no graph to export and is returned as it is."""
        if threads is not None and (isinstance(threads, bool) or not isinstance(threads, int)
                                    or threads < 1):
            raise ValueError(f"serve(threads = {threads!r}): the threads must be a whole number "
                             "of at least 1 (or None: as many as torch uses)")
        if self.chosen is None and self._session is None:
            self._session = onnx_session(self.model, self.schema,
                                         torch.get_num_threads() if threads is None else threads)
        return self

    def predict_array(self, x: np.ndarray, batch: int = 16384) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of wear for an unscaled input matrix (no checks).

        Batches of 16384 rows keep the members' activations in the cache (faster than batches
        of 131072); the rates and what else was tried: docs/benchmark.md, Training and
        inference time."""
        xs = np.ascontiguousarray(x, np.float32)
        if xs.ndim != 2 or xs.shape[1] != len(self.schema.inputs):
            raise ValueError(f"x has shape {xs.shape}; the model takes (rows, "
                             f"{len(self.schema.inputs)}) in the order {list(self.schema.inputs)}")
        if self.chosen is not None:  # its reading, and the fold models' spread about it
            mean, folds = self.chosen.readings(np.asarray(x, float))
            return mean, folds.std(axis=1)
        if self._session is None:
            return torch_predict(self.graph, xs, batch)
        mean, std = np.empty(len(xs), np.float32), np.empty(len(xs), np.float32)
        for lo in range(0, len(xs), batch):
            mean[lo:lo + batch], std[lo:lo + batch] = self._session.run(
                None, {"x": xs[lo:lo + batch]})
        return mean, std

    def coverage(self, pred: pd.DataFrame, df: pd.DataFrame, gearbox: list[str]) -> float:
        """The share of the readings of ``df`` (:meth:`FeatureSchema.readings`) whose true wear
        (``df``'s target column) lies inside the interval of ``pred`` (:meth:`predict` of
        ``df``)."""
        t = self.schema.target
        true = df[t].to_numpy()
        inside = (true >= pred[f"{t}_lower"].to_numpy()) & (true <= pred[f"{t}_upper"].to_numpy())
        return float(inside[self.schema.readings(df, gearbox)].mean())

    def predict(self, df: pd.DataFrame, gearbox: list[str] | None = None) -> pd.DataFrame:
        """Wear for every row of ``df`` (checked against the schema; see FeatureSchema.check).

        A model trained with a baseline (``schema.baseline``) reads feature changes since
        each gearbox's first row: ``gearbox`` names the columns that tell the gearboxes apart
        (:meth:`FeatureSchema.network_rows`); other models ignore it.

        Columns: ``<target>_pred`` (clipped at 0: wear depth is not negative), ``<target>_std``
        (the ensemble's), ``<target>_lower`` / ``_upper`` (the normalised conformal interval of
        the trained level, its half width the interval scale times the row's
        :func:`~surrogate.novelty.difficulty`; clipped at 0), ``novelty`` (the row's score,
        :class:`~surrogate.novelty.Novelty`: above 1 farther from the training rows than a
        row of a new gearbox like the validation ones lies with 95 % probability) and
        ``out_of_range``, the flag: a novelty above 1, an
        input outside the training range widened by 5 % (:meth:`FeatureSchema.in_envelope`),
        or an operating point (a speed or torque column of the training table that is not an
        input) outside the training one (:meth:`FeatureSchema.operating_outside`; one line in
        the log says so, or that the input lacks such a column): the reading is an
        extrapolation.
        """
        if not isinstance(df, pd.DataFrame):
            raise TypeError(f"df = {type(df).__name__}: predict reads a pandas DataFrame with "
                            f"the columns {self.schema.columns} (pd.read_csv of your table)")
        gearbox = list(gearbox_columns(gearbox or None))
        df = real_columns(df, self.schema.columns)  # before the baseline changes are formed
        if self.schema.baseline:
            check_gearboxes(df, gearbox, self.schema.target)
        x = self.schema.check(self.schema.network_rows(df, gearbox))
        mean, std = self.predict_array(x)
        bad = ~(np.isfinite(mean) & np.isfinite(std))
        if bad.any():
            raise ValueError(f"the model gives a non-finite wear for row {int(np.argmax(bad))} "
                             f"({int(bad.sum())} of {len(bad)} rows); nothing is written")
        score, flagged = self.flags(x)
        off, line = self.schema.operating_check(df)
        flagged = flagged | off
        if line:
            log.warning(line)
        lower, upper = self.bounds(x, mean, std, score)
        t = self.schema.target
        return pd.DataFrame({f"{t}_pred": np.maximum(mean, 0.0), f"{t}_std": std,
                             f"{t}_lower": np.maximum(lower, 0.0),
                             f"{t}_upper": np.maximum(upper, 0.0),
                             "novelty": score,
                             "out_of_range": flagged}, index=df.index)

    def bounds(self, x: np.ndarray, mean: np.ndarray, std: np.ndarray, score: np.ndarray,
               batch: int = 2048) -> tuple[np.ndarray, np.ndarray]:
        """The interval of unscaled rows ``x``: the network's normalised split-conformal one
        (``mean +- scale difficulty``), or a chosen model's CV+ one over its training groups
        (:func:`~surrogate.conformal.cv_plus`)."""
        if self.chosen is None:
            half = self.interval_scale * self.difficulty(std, score)
            return mean - half, mean + half
        c, lo, hi = self.chosen, np.empty(len(x)), np.empty(len(x))
        for a in range(0, len(x), batch):
            _, folds = c.readings(np.asarray(x[a:a + batch], float))
            lo[a:a + batch], hi[a:a + batch] = cv_plus(folds, c.fold_of, c.residuals, c.level,
                                                       c.groups)
        return lo, hi

    def flags(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The novelty scores of the unscaled input rows ``x`` and the flag ``out_of_range``:
        a score above 1 or an input outside the training range widened by 5 %."""
        score = self.novelty_score(x)
        return score, (score > 1) | ~self.schema.in_envelope(x)

    def novelty_score(self, x: np.ndarray) -> np.ndarray:
        """The novelty scores of the unscaled input rows ``x`` (NaN without a novelty
        reference: a NaN is never above 1)."""
        if self.novelty is None:
            return np.full(len(x), np.nan)
        return self.novelty.score(self.schema.scale(np.asarray(x, float)))

    def difficulty(self, std: np.ndarray, score: np.ndarray) -> np.ndarray:
        """The rows' interval scale before the conformal factor
        (:func:`~surrogate.novelty.difficulty`; the ensemble's deviation alone without a
        novelty reference)."""
        if self.novelty is None:
            return np.asarray(std, float)
        return difficulty(std, score, self.novelty.gamma)
