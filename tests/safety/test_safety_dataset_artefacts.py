"""Item 1: every stored dataset artefact is verifiable: each chunk's sha256 lives outside it,
in the chunk folder's manifest; a damaged or unreadable chunk is named, set aside and computed
again (on resume and before the merge); the dataset's sidecar holds the dataset's sha256."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pandas as pd
import pytest

from physics.dataset.chunks import MANIFEST
from physics.dataset.generation import (
    build_dataset,
    chunk_folder,
    chunk_path,
    merge,
    plan_dataset,
    spec_from_config,
)
from physics.files import sha256_file
from physics.params import Dynamics, Scenario, WearSolver

BASE = Scenario(solver=WearSolver(n_points=51),
                dynamics=Dynamics(duration_s=0.02, transient_s=0.005, phase_bins=64))
SMALL = {"cases": [3], "wear_states": 3, "replicates": 2, "cycles_max": 1e6, "chunks": 2}


def generate(out: Path, chunk: int | None = None, store_signals: bool = False):
    job = plan_dataset(BASE, spec_from_config(SMALL), out, chunk=chunk, jobs=1,
                       store_signals=store_signals, progress=False)
    return job, build_dataset(job)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return generate(tmp_path_factory.mktemp("ref"))[1]


def _flip(path: Path, at: int) -> None:
    data = bytearray(path.read_bytes())
    data[at] ^= 0x10
    path.write_bytes(bytes(data))


def test_manifest_holds_each_chunks_sha256_and_sidecar_the_datasets(reference):
    folder = chunk_folder(reference.parent, "dataset")
    chunks = json.loads((folder / MANIFEST).read_text())["chunks"]
    for c in range(2):
        path = chunk_path(folder, c)
        assert chunks[path.name]["sha256"] == sha256_file(path)
    side = json.loads(reference.with_suffix(".json").read_text())
    assert side["sha256"] == sha256_file(reference)


@pytest.mark.parametrize("where", ["data", "header"])
def test_a_damaged_chunk_is_named_set_aside_and_computed_again(tmp_path, reference, caplog,
                                                               where):
    out = tmp_path / "run"
    generate(out, chunk=0)  # a finished multirun job
    path = chunk_path(chunk_folder(out, "dataset"), 0)
    # a flipped bit in the middle of the data pages, or in the first page header
    _flip(path, path.stat().st_size // 2 if where == "data" else 8)
    with caplog.at_level(logging.WARNING):
        job, merged = generate(out)
    assert 0 in job.todo  # resume does not trust it
    warned = [r.getMessage() for r in caplog.records if "chunk_000.parquet" in r.getMessage()]
    assert warned and "set aside" in warned[0] and "\n" not in warned[0]
    assert (path.parent / "chunk_000.parquet.damaged").is_file()
    pd.testing.assert_frame_equal(pd.read_parquet(merged), pd.read_parquet(reference))
    assert merged.read_bytes() == reference.read_bytes()


def test_a_chunk_damaged_after_planning_is_caught_at_the_merge(tmp_path, reference, caplog):
    out = tmp_path / "merge"
    generate(out, chunk=0)
    generate(out, chunk=1)
    job = plan_dataset(BASE, spec_from_config(SMALL), out, jobs=1, progress=False)
    assert job.todo == ()
    _flip(chunk_path(job.folder, 1), 200)
    with caplog.at_level(logging.WARNING):
        merged = build_dataset(job)
    assert any("chunk_001.parquet" in r.getMessage() for r in caplog.records)
    assert merged.read_bytes() == reference.read_bytes()


def test_merge_alone_refuses_a_chunk_that_does_not_match(tmp_path):
    out = tmp_path / "direct"
    job, _ = generate(out)
    _flip(chunk_path(job.folder, 0), 100)
    with pytest.raises(ValueError, match=r"chunks \[0\] .*damaged"):
        merge(job.spec, out, "dataset", job.digest, {})


def test_damaged_records_are_set_aside_too(tmp_path, caplog):
    out = tmp_path / "sig"
    job, _ = generate(out, chunk=0, store_signals=True)
    npy = chunk_path(job.folder, 0).with_suffix(".npy")
    _flip(npy, npy.stat().st_size - 3)
    with caplog.at_level(logging.WARNING):
        generate(out, store_signals=True)
    assert (npy.parent / "chunk_000.npy.damaged").is_file()
    side = json.loads((out / "dataset.json").read_text())
    assert side["signals_sha256"] == sha256_file(out / "dataset_signals.npy")


def test_acceptance_flipped_bit_is_not_merged_through_the_app(tmp_path, reference):
    """The user's probe: one flipped bit in a finished chunk, then the app resumes."""
    import subprocess
    import sys

    out = tmp_path / "app"
    generate(out, chunk=0)
    path = chunk_path(chunk_folder(out, "dataset"), 0)
    _flip(path, path.stat().st_size // 2)
    sizes = [f"data.{k}={v}".replace(" ", "") for k, v in SMALL.items()]
    small = ["solver.n_points=51", "dynamics.duration_s=0.02", "dynamics.transient_s=0.005",
             "dynamics.phase_bins=64"]
    run = subprocess.run([sys.executable, "-m", "physics.dataset", f"out_dir={out}",
                          "progress=false", "jobs=1", *sizes, *small,
                          f"hydra.run.dir={tmp_path / 'hydra'}"],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "chunk_000.parquet" in run.stderr + run.stdout
    assert (path.parent / "chunk_000.parquet.damaged").is_file()
    assert (out / "dataset.parquet").read_bytes() == reference.read_bytes()


def test_a_damaged_manifest_is_set_aside_and_its_chunks_computed_again(tmp_path, reference,
                                                                      caplog):
    out = tmp_path / "man"
    job, _ = generate(out, chunk=0)
    (job.folder / MANIFEST).write_text("{not json")
    planned = plan_dataset(BASE, spec_from_config(SMALL), out, jobs=1, progress=False)
    assert planned.todo == (0, 1) and (job.folder / MANIFEST).is_file()  # planning writes not
    with caplog.at_level(logging.WARNING):
        merged = build_dataset(planned)
    assert (job.folder / "manifest.json.damaged").is_file()
    assert any("manifest" in r.getMessage() for r in caplog.records)
    assert merged.read_bytes() == reference.read_bytes()
