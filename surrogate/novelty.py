"""How far a row lies from a network's training data, and what that does to its interval.

- the **novelty score** (:class:`Novelty`): the mean distance of a row to its ``neighbours``
  (5) nearest training rows in the network's standardised inputs, whitened by the training
  rows' covariance (a Mahalanobis metric: a row that breaks the training rows' correlation of
  two features, a combination no training gearbox showed, lies far even where each feature
  alone is typical), divided by the radius: the conformal ``level`` (0.95) quantile of the
  same distance of the validation rows (gearboxes or groups of the training distribution the
  network did not train on), each validation gearbox one exchangeable unit
  (:func:`~surrogate.conformal.exchangeable_quantile`; a gearbox's rows lie near or far
  together, so a quantile of the rows alone flags more than ``1 - level`` of a new gearbox's
  rows). A row of a new gearbox drawn like the training ones scores above 1 with probability
  at most ``1 - level`` on average over the draw of the validation gearboxes (one network's
  rate scatters about it; with fewer than 19 of them the bound is ``1 / (K + 1)``); on
  inputs nobody trained on, nearly all do. k-nearest-neighbour
  distances as a test of whether a point lies in the support of the training data: Lei, G'Sell,
  Rinaldo, Tibshirani & Wasserman, "Distribution-free predictive inference for regression",
  JASA 113 (2018) 1094, sec. 4; a distance to the training rows as the difficulty of a
  conformal interval: Papadopoulos, Vovk & Gammerman, "Regression conformal prediction with
  nearest neighbours", JAIR 40 (2011) 815;
- the **flag** (``out_of_range`` of :meth:`surrogate.inference.Surrogate.predict`): a score
  above 1, or an input outside the training
  range widened by 5 % (:meth:`~surrogate.schema.FeatureSchema.in_envelope`: a network
  extrapolates beyond the range of any one input, however near the row lies to the others);
- the **difficulty** (:func:`difficulty`) of the normalised conformal interval: the
  ensemble's standard deviation times ``1 + gamma * score``; the interval's scale is the
  conformal quantile of the calibration gearboxes' ``|y - mu| / difficulty``
  (:func:`surrogate.inference.conformal_scale`), so an interval widens with the novelty of its
  row as well as with the members' disagreement;
- the **training target's range** (``target_low``, ``target_high``), against which a table
  with the true wear (a test set, a user's table to fine-tune on) is read: wear beyond it is
  wear the network never saw, whatever its inputs (:func:`envelope_report`).

Everything is stored in the model file as a tensor and plain numbers (:meth:`Novelty.payload`;
``torch.load(weights_only=True)`` reads it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import torch
from scipy import spatial

from surrogate.conformal import exchangeable_quantile

#: training rows whose distances are averaged
NEIGHBOURS = 5
#: the validation gearboxes' conformal quantile of the distance at which a row is flagged: at
#: most 5 % of the rows of a new gearbox of the training distribution score above it
LEVEL = 0.95
#: weight of the novelty in the interval's difficulty: at a score of 1 (the flag) the
#: interval is twice as wide as the ensemble's spread alone would make it
GAMMA = 1.0
#: a share of flagged rows above this many times the share expected of the training
#: distribution (``1 - level``) is reported as data outside the training envelope
NOTE_FACTOR = 2.0


@dataclass(frozen=True)
class Novelty:
    """The training rows (standardised), the flag's radius (the held-out gearboxes' conformal
    quantile of the distance at ``level``), and the training target's range; see the module
    text."""

    reference: np.ndarray  # (rows, inputs), standardised as the network reads them, whitened
    whiten: np.ndarray  # (inputs, inputs): standardised rows @ whiten -> the metric's space
    radius: float  # mean distance to ``neighbours`` training rows at which a row is flagged
    level: float = LEVEL
    neighbours: int = NEIGHBOURS
    gamma: float = GAMMA
    target_low: float = 0.0
    target_high: float = math.inf

    @classmethod
    def fit(cls, train: np.ndarray, val: np.ndarray, target: np.ndarray, *,
            groups: np.ndarray | None = None, level: float = LEVEL,
            neighbours: int = NEIGHBOURS, gamma: float = GAMMA) -> Novelty:
        """From the standardised inputs of the training rows and of the validation rows (with
        their gearboxes, ``groups``; None: each row its own), and the training rows'
        target."""
        train = np.asarray(train, float)
        if len(train) == 0 or len(val) == 0:
            raise ValueError("novelty needs training and validation rows")
        if not 0 < level < 1:
            raise ValueError(f"novelty level = {level!r} must lie in (0, 1)")
        k = max(1, min(int(neighbours), len(train)))
        whiten = whitening(train)
        probe = cls((train @ whiten).astype(np.float32), whiten, 1.0, level, k, gamma)
        radius = exchangeable_quantile(probe.distance(np.asarray(val, float)), level, groups)
        # validation rows on top of training rows (a table of repeated records): any distance
        # is then novel; the smallest nonzero spacing of the training rows keeps the score finite
        if not radius > 0:
            spacing = probe.distance(train)
            radius = float(spacing[spacing > 0].min()) if (spacing > 0).any() else 1.0
        t = np.asarray(target, float)
        return cls(probe.reference, whiten, radius, level, k, gamma, float(t.min()),
                   float(t.max()))

    @cached_property
    def tree(self) -> spatial.cKDTree:
        return spatial.cKDTree(self.reference)

    def distance(self, xs: np.ndarray) -> np.ndarray:
        """Mean distance of the standardised rows ``xs`` to their nearest training rows (in
        the whitened metric)."""
        d, _ = self.tree.query(np.asarray(xs, float) @ self.whiten, k=self.neighbours)
        return d if self.neighbours == 1 else d.mean(axis=1)

    def score(self, xs: np.ndarray) -> np.ndarray:
        """The novelty score of the standardised rows ``xs`` (1: the flag's threshold)."""
        return self.distance(xs) / self.radius

    def payload(self) -> dict:
        """The model file's entry: a tensor and plain numbers."""
        return {"reference": torch.as_tensor(self.reference, dtype=torch.float32),
                "whiten": torch.as_tensor(self.whiten, dtype=torch.float64),
                "radius": self.radius, "level": self.level, "neighbours": self.neighbours,
                "gamma": self.gamma, "target_low": self.target_low,
                "target_high": self.target_high}

    @classmethod
    def from_payload(cls, d: dict) -> Novelty:
        ref, whiten = d["reference"], d["whiten"]
        if not isinstance(ref, torch.Tensor) or ref.ndim != 2 or len(ref) == 0:
            raise ValueError("its novelty reference is not a table of training rows")
        if not isinstance(whiten, torch.Tensor) or tuple(whiten.shape) != (ref.shape[1],) * 2:
            raise ValueError("its novelty metric does not match its training rows")
        out = cls(ref.numpy().astype(np.float32), whiten.numpy().astype(float),
                  float(d["radius"]), float(d["level"]),
                  int(d["neighbours"]), float(d["gamma"]), float(d["target_low"]),
                  float(d["target_high"]))
        if not (out.radius > 0 and 0 < out.level < 1 and out.neighbours >= 1
                and out.gamma >= 0 and np.isfinite(out.reference).all()
                and np.isfinite(out.whiten).all()):
            raise ValueError("its novelty entry holds invalid values")
        return out


def whitening(x: np.ndarray) -> np.ndarray:
    """The matrix ``W`` with ``cov(x @ W) = I`` (the inverse square root of the rows'
    covariance, by eigendecomposition). A direction in which the training rows do not vary
    (a constant input) is given the variance of a millionth of the largest, so any step
    along it is far."""
    x = np.asarray(x, float)
    cov = np.atleast_2d(np.cov(x.T)) if len(x) > 1 else np.eye(x.shape[1])
    values, vectors = np.linalg.eigh(cov)
    floor = 1e-6 * max(float(values.max()), 1e-12)
    return vectors / np.sqrt(np.maximum(values, floor))


def difficulty(std: np.ndarray, score: np.ndarray, gamma: float = GAMMA) -> np.ndarray:
    """The normalised conformal interval's scale per row: the ensemble's deviation times
    ``1 + gamma * score`` (module text)."""
    return np.asarray(std, float) * (1.0 + gamma * np.asarray(score, float))


def envelope_report(flagged: np.ndarray, novelty: Novelty, true: np.ndarray | None = None,
                    what: str = "rows", unit: str = "") -> tuple[dict, str | None]:
    """Figures of ``flagged`` rows (``out_of_range``) and, where the true target is
    given, of the rows whose target lies beyond the training range; and the one line to log
    where the rows lie outside the network's training data: a share flagged above
    :data:`NOTE_FACTOR` times that of the training distribution, or a true target more than
    5 % of the training range beyond it (None otherwise)."""
    flagged = np.asarray(flagged, bool)
    n, f = len(flagged), int(flagged.sum())
    share = f / n if n else 0.0
    figures = {"flagged_rows": f, "flagged_share": share}
    parts = []
    if share > NOTE_FACTOR * (1 - novelty.level):
        parts.append(f"{f} of {n} {what} ({100 * share:.0f} %) lie outside the network's "
                     "training data (farther from its training rows than a new gearbox "
                     f"like its validation ones lies with {100 * novelty.level:.0f} % "
                     "probability, or an input beyond its training range): their readings "
                     "are extrapolations")
    if true is not None:
        t = np.asarray(true, float)
        lo, hi = novelty.target_low, novelty.target_high
        pad = 0.05 * (hi - lo)
        beyond = (t > hi + pad) | (t < lo - pad)
        figures["target_beyond_rows"] = int(beyond.sum())
        if beyond.any():
            top = float(np.max(np.abs(t)))
            times = f", up to {top / hi:.3g} times its top" if hi > 0 and top > hi else ""
            parts.append(f"the true wear of {int(beyond.sum())} of {n} {what} lies beyond the "
                         f"range the network was trained on ({lo:.3g}-{hi:.3g} {unit}{times}): "
                         "it never saw such wear")
    return figures, ("; ".join(parts) if parts else None)
