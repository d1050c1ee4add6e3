"""The surrogate's network in plain torch: a deep ensemble of Gaussian MLPs with stacked weights,
its Gaussian mixture, and the trained network as inference loads it (without Lightning, whose
import takes two seconds of every ``surrogate.predict``).

Each of ``members`` networks maps the scaled features to a mean and a log-variance of the scaled
target (Lakshminarayanan, Pritzel & Blundell, "Simple and scalable predictive uncertainty
estimation using deep ensembles", NeurIPS 2017). The prediction is the mixture: mean of the
members' means, and variance ``mean(var_m + mu_m^2) - mu^2``.
"""

from __future__ import annotations

import itertools
import math

import torch
from torch import nn

from surrogate.settings import ModelConfig

#: the hyperparameters of the network's shape and training that a saved file holds
MODEL_KEYS = ("width", "depth", "members", "lr", "weight_decay", "interval", "trainable")


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
        # read as its transpose (no copy): faster than rows first on the CPU
        # (``bench/bench_surrogate.py``).
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


class Network(nn.Module):
    """A trained ensemble as a saved file holds it: its hyperparameters (with the schema) and
    the network under the same state-dict keys as the training module
    (:class:`surrogate.model.WearRegressor`), so either can be loaded into the other."""

    def __init__(self, hparams: dict) -> None:
        super().__init__()
        ModelConfig(**{k: hparams[k] for k in MODEL_KEYS}).check()
        self.hparams = dict(hparams)
        self.net = EnsembleMLP(int(hparams["n_inputs"]), [int(hparams["width"])]
                               * int(hparams["depth"]), int(hparams["members"]))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x)
