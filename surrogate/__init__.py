"""Torch/Lightning surrogate mapping vibration features to pinion wear depth, at the root (thesis
4) or the flank's mean (``data.target``).

- :mod:`surrogate.schema`: the feature schema (names, units, scaling, training envelope) a model
  carries and checks its input against, and how a network reads its rows (complex lines as
  magnitudes, changes since each gearbox's baseline record);
- :mod:`surrogate.data`: the Lightning data module over the physics dataset, split by trajectory;
- :mod:`surrogate.network`: the deep ensemble of Gaussian MLPs in plain torch, and a trained
  network as inference loads it;
- :mod:`surrogate.model`: that ensemble as one Lightning module, for training;
- :mod:`surrogate.training`: ``train(cfg)``, called by ``train.py``;
- :mod:`surrogate.inference`: export, safe loading, CPU prediction with intervals and flags;
- :mod:`surrogate.novelty`: the novelty score against the training rows, the flag's threshold
  and the interval's difficulty;
- :mod:`surrogate.conformal`: the conformal quantile of held-out scores, by row or by
  gearbox, that sets the interval's scale and the flag's threshold;
- :mod:`surrogate.predict`, :mod:`surrogate.summarise`, :mod:`surrogate.benchmark`: commands.
"""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "surrogate.schema": ("FeatureSchema", "baseline_changes", "vector_magnitudes",
                         "network_frame"),
    "surrogate.settings": ("DataConfig", "ModelConfig", "TrainerConfig"),
    "surrogate.data": (
        "WearDataModule", "DEFAULT_INPUTS", "BUILD_CHUNKS", "load_dataset", "input_columns",
        "split_trajectories", "replicates_per_case", "validation_count", "stale_dataset"),
    "surrogate.network": ("EnsembleMLP", "Network", "mixture"),
    "surrogate.model": ("WearRegressor",),
    "surrogate.training": ("TrainJob", "train", "fit", "kept"),
    "surrogate.inference": (
        "Surrogate", "ScaledEnsemble", "export", "conformal_scale", "torch_predict",
        "gearbox_columns"),
    "surrogate.predict": ("predict_file",),
    "surrogate.novelty": ("Novelty", "difficulty", "envelope_report"),
    "surrogate.conformal": ("exchangeable_quantile",),
    "surrogate.benchmark": (
        "DRY_LAW", "MODEL_FORM_OFF", "one_rig_table", "one_rig", "INDEPENDENT_WEAR_MM",
        "fit_estimator", "fit_fleet_estimator", "independent_fleet", "referenced",
        "seed_summary", "typical_wear"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
