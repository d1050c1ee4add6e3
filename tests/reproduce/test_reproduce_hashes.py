"""The default reproduction is deterministic: its tables hash as recorded (``table_hashes.sha256``,
written by the default ``python -m physics.reproduce``). A change of the physics changes them on
purpose: record the new hashes with the change and say why in its commit."""

from __future__ import annotations

import hashlib
import subprocess
import sys
from pathlib import Path

import pytest

HASHES = Path(__file__).with_name("table_hashes.sha256")
#: depends on whether the thesis's own tables are given (thesis_tables=)
OPTIONAL = {"estimator_accuracy.csv"}


@pytest.mark.slow
def test_default_tables_are_byte_identical_to_the_recorded_ones(tmp_path):
    subprocess.run([sys.executable, "-m", "physics.reproduce", f"out_dir={tmp_path / 'out'}",
                    f"hydra.run.dir={tmp_path / 'run'}"], check=True, cwd=tmp_path,
                   capture_output=True)
    recorded = dict(line.split()[::-1] for line in HASHES.read_text().splitlines())
    changed = [name for name, digest in recorded.items() if name not in OPTIONAL and
               hashlib.sha256((tmp_path / "out" / name).read_bytes()).hexdigest() != digest]
    assert not changed, f"tables that differ from the recorded run: {changed}"
