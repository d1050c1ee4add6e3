"""The deep ensemble of Gaussian MLPs (:mod:`surrogate.network`) as one Lightning module.

Each of ``members`` networks is trained on the Gaussian negative log-likelihood from its own
random start (Lakshminarayanan, Pritzel & Blundell, NeurIPS 2017). The members' weights are
stacked, so the whole ensemble runs as batched matrix products. The prediction is the mixture
(:func:`~surrogate.network.mixture`); the interval is the Gaussian one of that variance at the
configured level, and its empirical coverage on held-out data is logged as ``test/coverage``.
"""

from __future__ import annotations

from statistics import NormalDist

import lightning as L
import torch
from torch import nn

from surrogate.network import EnsembleMLP, mixture
from surrogate.settings import ModelConfig


class WearRegressor(L.LightningModule):
    """Scaled features -> scaled wear, with the schema that undoes the scaling."""

    def __init__(self, n_inputs: int, schema: dict, width: int = 64, depth: int = 2,
                 members: int = 5, lr: float = 3e-3, weight_decay: float = 1e-5,
                 interval: float = 0.95, trainable: str = "all", kind: str = "auto",
                 folds: int = 5) -> None:
        super().__init__()
        # kind and folds choose the model a run keeps (surrogate.training.select), checked here
        # with the rest of the config and not kept among the network's hyperparameters
        ModelConfig(width=width, depth=depth, members=members, lr=lr, weight_decay=weight_decay,
                    interval=interval, trainable=trainable, kind=kind, folds=folds).check()
        self.save_hyperparameters(ignore=["kind", "folds"])
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
        # step of these small networks
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
