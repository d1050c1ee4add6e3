"""Dataset chunks and sweeps through Hydra's submitit launcher: the cluster configs compose, and
a chunked generation runs through submitit's local executor, then merges as on one machine."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[2]
SMALL = ["data.replicates=1", "data.cases=[3,4]", "data.chunks=2", "data.wear_states=3"]


def _run(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True,
                          timeout=600, check=True)


def test_chunks_run_as_submitit_jobs_and_merge(tmp_path):
    _run(["-m", "physics.dataset", "-m", "chunk=0,1", "hydra/launcher=submitit_local", *SMALL],
         tmp_path)
    chunks = sorted((tmp_path / "data" / "dataset_chunks").glob("chunk_*.parquet"))
    assert [c.name for c in chunks] == ["chunk_000.parquet", "chunk_001.parquet"]
    merge = _run(["-m", "physics.dataset", *SMALL], tmp_path)
    assert "dataset:" in merge.stdout + merge.stderr
    df = pd.read_parquet(tmp_path / "data" / "dataset.parquet")
    assert sorted(df.case.unique()) == [3, 4] and len(df) == 2 * 3


def test_cluster_launcher_configs_compose(tmp_path):
    for app in (["-m", "physics.dataset"], [str(ROOT / "train.py")]):
        out = _run([*app, "hydra/launcher=cluster", "--cfg", "hydra"], tmp_path).stdout
        assert "SlurmLauncher" in out and "cpus_per_task: 2" in out
