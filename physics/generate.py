"""Dataset generator: ``python -m physics.generate`` (a Hydra app, config ``conf/generate.yaml``).

See :mod:`physics.dataset` for what a row holds and how chunks, resume and merge work.
"""

from __future__ import annotations

import logging
from concurrent.futures import ProcessPoolExecutor, as_completed
from importlib.metadata import version
from multiprocessing import get_context
from pathlib import Path

import hydra
from omegaconf import DictConfig, OmegaConf
from tqdm import tqdm

from physics.dataset import (
    base_scenario,
    chunk_folder,
    chunk_is_done,
    chunk_path,
    config_hash,
    merge,
    run_chunk,
    spec_from_config,
)
from physics.stiffness import MeshStiffness

log = logging.getLogger(__name__)


def generate(cfg: DictConfig) -> Path | None:
    """Run the chunks ``cfg`` asks for; merge when every chunk is there. Returns the dataset."""
    container = OmegaConf.to_container(cfg, resolve=True)
    container.pop("hydra", None)
    base = base_scenario(container)
    spec = spec_from_config(container["data"])
    physics = {k: container.get(k) for k in ("gear", "material", "lubricant", "tribology",
                                             "operating", "solver", "dynamics", "data")}
    digest = config_hash(physics)
    out = Path(cfg.out_dir)
    chunks = range(spec.chunks) if cfg.chunk is None else [int(cfg.chunk)]
    if cfg.chunk is not None:
        spec.chunk_units(int(cfg.chunk))  # validates the index before any work
    folder = chunk_folder(out, str(cfg.name))
    todo = [c for c in chunks if not chunk_is_done(chunk_path(folder, c), digest)]
    if len(todo) < len(chunks):
        log.info("%d chunk(s) already done (hash %s): skipped", len(chunks) - len(todo), digest)
    if todo:
        MeshStiffness(base.gear, base.material)  # states a range warning of the gear body once
    jobs = max(1, min(int(cfg.jobs), len(todo)))
    with tqdm(total=len(todo), desc="chunks", unit="chunk", disable=not cfg.progress) as bar:
        if jobs == 1:
            for c in todo:
                run_chunk(base, spec, c, folder, digest, cfg.store_signals)
                bar.update(1)
        else:
            with ProcessPoolExecutor(jobs, mp_context=get_context("spawn")) as pool:
                futures = [pool.submit(run_chunk, base, spec, c, out, digest, cfg.store_signals)
                           for c in todo]
                for f in as_completed(futures):
                    f.result()
                    bar.update(1)
    if cfg.chunk is not None:
        log.info("chunk %s written; run without chunk= to merge", cfg.chunk)
        return None
    sidecar = {"config": physics, "seed": spec.seed, "package_version": version("gearwear"),
               "description": "one row per (case, replicate, cycles); features of the DTE and "
                              "the housing acceleration after noise"}
    path = merge(spec, out, str(cfg.name), digest, sidecar, cfg.store_signals)
    log.info("dataset: %s", path)
    return path


@hydra.main(version_base="1.3", config_path="../conf", config_name="generate")
def main(cfg: DictConfig) -> None:
    generate(cfg)


if __name__ == "__main__":
    main()
