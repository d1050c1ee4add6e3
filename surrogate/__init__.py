"""Torch/Lightning surrogate mapping vibration features to pinion wear depth, at the root (thesis
4; issue 6) or the flank's mean (``data.target``).

- :mod:`surrogate.schema`: the feature schema (names, units, scaling, training envelope) a model
  carries and checks its input against;
- :mod:`surrogate.data`: the Lightning data module over the physics dataset, split by trajectory;
- :mod:`surrogate.model`: a deep ensemble of Gaussian MLPs as one Lightning module;
- :mod:`surrogate.training`: ``train(cfg)``, called by ``train.py``;
- :mod:`surrogate.inference`: export, safe loading, CPU prediction with intervals and flags;
- :mod:`surrogate.predict`, :mod:`surrogate.summarise`, :mod:`surrogate.benchmark`: commands.
"""
