"""``python -m physics.dataset``: the wear and vibration dataset (schema
:class:`physics.dataset.generation.DatasetConfig`, choices ``conf/dataset/dataset.yaml``).

See :mod:`physics.dataset.generation` for what a row holds and how chunks, resume and merge work.
"""

from __future__ import annotations

import logging

import hydra
from omegaconf import DictConfig, OmegaConf

from physics.command import register_schema, run_command
from physics.dataset.generation import (
    DatasetConfig,
    DatasetJob,
    base_scenario,
    build_dataset,
    chunks_kept,
    plan_dataset,
    spec_from_config,
)

log = logging.getLogger(__name__)
register_schema("dataset_schema", DatasetConfig)


def prepare(cfg: DictConfig) -> DatasetJob:
    container = OmegaConf.to_container(cfg, resolve=True)
    job = plan_dataset(base_scenario(container), spec_from_config(container["data"]),
                       cfg.out_dir, cfg.name, cfg.chunk, cfg.jobs, cfg.store_signals,
                       cfg.progress)
    if len(job.todo) < (job.spec.chunks if job.merge else 1):
        log.info("finished chunks of this config (hash %s) are kept in %s and skipped",
                 job.digest, job.folder)
    return job


def execute(job: DatasetJob) -> None:
    path = build_dataset(job)
    if path is None:
        log.info("chunk written into %s; run without chunk= to merge", job.folder)
    else:
        log.info("dataset: %s", path)


@hydra.main(version_base="1.3", config_path="pkg://gearwear_conf.dataset",
            config_name="dataset")
def main(cfg: DictConfig) -> None:
    run_command(cfg, prepare, execute, kept=chunks_kept)


if __name__ == "__main__":
    main()
