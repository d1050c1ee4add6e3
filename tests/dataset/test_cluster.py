"""Dataset chunks and sweeps through Hydra's submitit launcher: the cluster configs compose, and
a chunked generation runs through submitit's local executor, then merges as on one machine."""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from hydra import compose, initialize_config_module
from omegaconf import DictConfig

from surrogate import settings

SMALL = ["data.replicates=1", "data.cases=[3,4]", "data.chunks=2", "data.wear_states=3"]


def _run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True,
                          timeout=600, check=True)


@pytest.mark.slow
def test_chunks_run_as_submitit_jobs_and_merge(tmp_path):
    _run(["-m", "physics.dataset", "-m", "chunk=0,1", "hydra/launcher=submitit_local", *SMALL],
         tmp_path)
    chunks = sorted((tmp_path / "data" / "dataset_chunks").glob("chunk_*.parquet"))
    assert [c.name for c in chunks] == ["chunk_000.parquet", "chunk_001.parquet"]
    merge = _run(["-m", "physics.dataset", *SMALL], tmp_path)
    assert "dataset:" in merge.stdout + merge.stderr
    df = pd.read_parquet(tmp_path / "data" / "dataset.parquet")
    assert sorted(df.case.unique()) == [3, 4] and len(df) == 2 * 3


def _launcher(config: str) -> DictConfig:
    """The launcher of app ``config`` (``gearwear_conf.<config>``) under
    ``hydra/launcher=cluster``, as ``--cfg hydra`` prints it."""
    with initialize_config_module(f"gearwear_conf.{config}", version_base="1.3"):
        return compose(config, overrides=["hydra/launcher=cluster"],
                       return_hydra_config=True).hydra.launcher


def test_cluster_launcher_configs_compose(config_store):
    importlib.import_module("physics.dataset.__main__")  # registers the dataset's schema
    settings.register()  # as train.py does
    for config in ("dataset", "train"):
        launcher = _launcher(config)
        assert "SlurmLauncher" in launcher._target_ and launcher.cpus_per_task == 2
