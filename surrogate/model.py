"""A deep ensemble of Gaussian MLPs as one Lightning module.

Each of ``members`` networks maps the scaled features to a mean and a log-variance of the scaled
target and is trained on the Gaussian negative log-likelihood from its own random start
(Lakshminarayanan, Pritzel & Blundell, "Simple and scalable predictive uncertainty estimation
using deep ensembles", NeurIPS 2017). The members' weights are stacked, so the whole ensemble
runs as batched matrix products. The prediction is the mixture: mean of the members' means, and
variance ``mean(var_m + mu_m^2) - mu^2``; the interval is the Gaussian one of that variance at the
configured level, and its empirical coverage on held-out data is logged as ``test/coverage``.
"""

from __future__ import annotations

import itertools
import math
from statistics import NormalDist

import lightning as L
import torch
from torch import nn

from surrogate.settings import ModelConfig


class EnsembleMLP(nn.Module):
    """``members`` MLPs with stacked weights: input ``(batch, n_in)`` -> ``(members, batch, 2)``."""

    def __init__(self, n_inputs: int, hidden: list[int], members: int) -> None:
        super().__init__()
        sizes = [n_inputs, *hidden, 2]
        self.weights = nn.ParameterList()
        self.biases = nn.ParameterList()
        for a, b in itertools.pairwise(sizes):
            w = torch.empty(members, a, b)
            for m in range(members):  # Kaiming-uniform start, independent per member
                nn.init.kaiming_uniform_(w[m].T, a=math.sqrt(5))
            self.weights.append(nn.Parameter(w))
            self.biases.append(nn.Parameter(torch.empty(members, 1, b).uniform_(
                -1 / math.sqrt(a), 1 / math.sqrt(a))))
        self.act = nn.SiLU()

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        # Rows last: every product is (units_out, units_in) @ (units_in, rows), one wide matrix
        # product per member, and the first layer of all members is one product with the input
        # read as its transpose (no copy). On one thread of this machine 5.2e6 rows/s against
        # 3.7e6 with rows first (batches of 4096, both timed in one process; docs/surrogate.md).
        w, b = self.weights[0], self.biases[0]
        members, n_in, n_out = w.shape
        h = torch.addmm(b.transpose(1, 2).reshape(-1, 1),
                        w.transpose(1, 2).reshape(-1, n_in), x.T).view(members, n_out, -1)
        for w, b in zip(self.weights[1:], self.biases[1:], strict=True):
            h = torch.baddbmm(b.transpose(1, 2), w.transpose(1, 2), self.act(h))
        return h.transpose(1, 2)


def mixture(out: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Mean and variance of the ensemble's Gaussian mixture from ``(members, batch, 2)``."""
    mu, var = out[..., 0], torch.exp(out[..., 1].clamp(-20, 10))
    mean = mu.mean(0)
    return mean, (var + mu**2).mean(0) - mean**2


class WearRegressor(L.LightningModule):
    """Scaled features -> scaled wear, with the schema that undoes the scaling."""

    def __init__(self, n_inputs: int, schema: dict, width: int = 64, depth: int = 2,
                 members: int = 5, lr: float = 3e-3, weight_decay: float = 1e-5,
                 interval: float = 0.9, trainable: str = "all") -> None:
        super().__init__()
        ModelConfig(width=width, depth=depth, members=members, lr=lr, weight_decay=weight_decay,
                    interval=interval, trainable=trainable).check()
        self.save_hyperparameters()
        self.net = EnsembleMLP(n_inputs, [width] * depth, members)
        self.z = NormalDist().inv_cdf(0.5 + interval / 2)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x)

    def _nll(self, x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
        out = self(x)
        mu, logvar = out[..., 0], out[..., 1].clamp(-20, 10)
        return 0.5 * (logvar + (y.unsqueeze(0) - mu) ** 2 / torch.exp(logvar)).mean()

    def on_train_epoch_start(self) -> None:
        self._epoch_loss = torch.zeros(2)  # sum of loss x rows, rows

    def training_step(self, batch, _):
        loss = self._nll(*batch)
        # summed here and logged once an epoch: a ``self.log`` per step costs more than the
        # step of these small networks (profile of the main job: docs/surrogate.md)
        rows = len(batch[1])
        self._epoch_loss += torch.stack([loss.detach() * rows, torch.tensor(float(rows))])
        return loss

    def on_train_epoch_end(self) -> None:
        total, rows = self._epoch_loss
        self.log("train/loss", total / rows)

    def _evaluate(self, batch, stage: str) -> None:
        x, y = batch
        mean, var = mixture(self(x))
        scale = self.hparams.schema["target_scale"]
        pred, true = mean.clamp_min(0) * scale, y * scale
        nz = true != 0
        rel = ((pred - true).abs()[nz] / true[nz]).mean() * 100
        half = self.z * var.clamp_min(0).sqrt() * scale
        self.log_dict({f"{stage}/loss": self._nll(x, y),
                       f"{stage}/rmse": ((pred - true) ** 2).mean().sqrt(),
                       f"{stage}/mre_pct": rel,
                       f"{stage}/coverage": ((true - pred).abs() <= half).float().mean()},
                      prog_bar=stage == "val")

    def validation_step(self, batch, _):
        self._evaluate(batch, "val")

    def test_step(self, batch, _):
        self._evaluate(batch, "test")

    def trained_parameters(self) -> list[nn.Parameter]:
        """The weights the optimiser moves (``trainable``): all, or each member's output
        layer (``head``: the hidden layers, the physics-trained features, stay as they are)."""
        if self.hparams.trainable == "all":
            return list(self.parameters())
        return [self.net.weights[-1], self.net.biases[-1]]

    def configure_optimizers(self):
        return torch.optim.AdamW(self.trained_parameters(), lr=self.hparams.lr,
                                 weight_decay=self.hparams.weight_decay)
