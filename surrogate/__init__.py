"""Torch/Lightning surrogate mapping vibration features to pinion wear depth, at the root (thesis
4) or the flank's mean (``data.target``).

What a user calls is listed in ``__all__``: ``train(cfg)`` (a composed train config, as
``train.py`` runs it), :class:`Surrogate` (load a trained model and predict, on the CPU),
``predict_file`` (a table in, a table of readings out), the settings a train config is composed
of (:class:`DataConfig`, :class:`ModelConfig`, :class:`TrainerConfig`) and the Lightning data
module :class:`WearDataModule`. The rest is reached through its module:

- :mod:`surrogate.inputs`: the network's default inputs, by sensor and reading;
- :mod:`surrogate.schema`: the feature schema (names, units, scaling, training envelope and
  operating point) a model carries and checks its input against, and how a network reads its
  rows (complex lines as magnitudes, changes since each gearbox's baseline record);
- :mod:`surrogate.tables`: a user's own table: reading it, its units and its checks;
- :mod:`surrogate.splits`: the splits by trajectory, by a table's groups or by groups named by
  value, and the validation half that calibrates the interval;
- :mod:`surrogate.wear_data`: a run's data without torch or Lightning, the physics dataset
  (built where missing) or a user's table, checked when made; :mod:`surrogate.data`: it as
  Lightning's data module;
- :mod:`surrogate.network`: the deep ensemble of Gaussian MLPs in plain torch, and a trained
  network as inference loads it;
- :mod:`surrogate.model`: that ensemble as one Lightning module, for training;
- :mod:`surrogate.candidates`, :mod:`surrogate.baselines`: the linear, monotone, average and
  estimator models and the choice among them; the models scored beside the one kept;
- :mod:`surrogate.training`: ``train(cfg)``, its two phases ``prepare`` and ``fit`` (called by
  ``train.py``);
- :mod:`surrogate.inference`: export, safe loading, CPU prediction with intervals and flags;
- :mod:`surrogate.novelty`: the novelty score against the training rows, the flag's threshold
  and the interval's difficulty;
- :mod:`surrogate.conformal`: the conformal quantile of held-out scores, by row or by
  gearbox, that sets the interval's scale and the flag's threshold;
- :mod:`surrogate.few_labels`: a rig read from a few labelled stages, with and without the
  physics model's curve as a prior;
- :mod:`surrogate.figures`: the parity plot of a run and the benchmark's figures;
- :mod:`surrogate.predict`, :mod:`surrogate.summarise`, :mod:`surrogate.benchmark`: commands.
"""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "surrogate.settings": ("DataConfig", "ModelConfig", "TrainerConfig"),
    "surrogate.data": ("WearDataModule",),
    "surrogate.training": ("train",),
    "surrogate.inference": ("Surrogate",),
    "surrogate.predict": ("predict_file",),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
