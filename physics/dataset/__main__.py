"""``python -m physics.dataset``: the wear and vibration dataset (schema
:class:`physics.dataset.generation.DatasetConfig`, choices ``conf/dataset/dataset.yaml``).

See :mod:`physics.dataset.generation` for what a row holds and how chunks, resume and merge work.
"""

# ruff: noqa: E402 (the imports after the handlers: see install_at_start)
from __future__ import annotations

from physics.interrupt import install_at_start

install_at_start(__name__)  # Ctrl-C and SIGTERM handled from here on, during the slow imports

import logging

import hydra
from omegaconf import DictConfig, OmegaConf

from physics.command import entry, register_schema, run_command
from physics.dataset.generation import (
    DatasetConfig,
    DatasetJob,
    acquire_output,
    base_scenario,
    build_dataset,
    check_not_users,
    chunk_is_done,
    chunks_kept,
    plan_dataset,
    spec_from_config,
)

log = logging.getLogger(__name__)
register_schema("dataset_schema", DatasetConfig)


def plan(cfg: DictConfig) -> DatasetJob:
    """Check the config and plan the build; nothing is written (a sweep's jobs are checked
    with this before any starts)."""
    container = OmegaConf.to_container(cfg, resolve=True)
    job = plan_dataset(base_scenario(container), spec_from_config(container["data"]),
                       cfg.out_dir, cfg.name, cfg.chunk, cfg.jobs, cfg.store_signals,
                       cfg.progress)
    if len(job.todo) < (job.spec.chunks if job.merge else 1):
        log.info("finished chunks of this config (hash %s) are kept in %s and skipped",
                 job.digest, job.folder)
    return job


def prepare(cfg: DictConfig) -> DatasetJob:
    job = plan(cfg)
    check_not_users(job)  # this app always writes the dataset it plans
    acquire_output(job)  # the last check: one writer per dataset (released by build_dataset)
    return job


def execute(job: DatasetJob) -> None:
    path = build_dataset(job)
    if path is None:
        done = sum(chunk_is_done(job.folder, c, job.digest, job.store_signals)
                   for c in range(job.spec.chunks))
        rest = ("run the same command without chunk= to merge them" if done == job.spec.chunks
                else "run the same command without chunk= to compute the others and merge")
        log.info("chunk %d is in %s (%d of %d chunks of this config finished); %s", job.chunk,
                 job.folder, done, job.spec.chunks, rest)
    else:
        log.info("dataset: %s", path)


@hydra.main(version_base="1.3", config_path="pkg://gearwear_conf.dataset",
            config_name="dataset")
def task(cfg: DictConfig) -> None:
    run_command(cfg, prepare, execute, kept=chunks_kept)


main = entry(task, check=plan)


if __name__ == "__main__":
    main()
