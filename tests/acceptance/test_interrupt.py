"""Ctrl-C on a long run: one line saying what was kept and how to resume; nothing lost."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest


@pytest.mark.slow
def test_ctrl_c_keeps_finished_chunks_and_says_how_to_resume(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "physics.dataset", "data.replicates=2"],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    time.sleep(8)
    os.killpg(proc.pid, signal.SIGINT)  # as a terminal sends it: to the whole process group
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 130
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.startswith("interrupted:")]
    assert len(lines) == 1 and "the same command" in lines[0]
    kept = sorted((tmp_path / "data" / "dataset_chunks").glob("chunk_*.parquet"))
    assert (f"{len(kept)} of 5 chunks" in lines[0] if kept
            else "no chunk of the 5 was finished" in lines[0])
    assert not list(tmp_path.rglob("*.tmp"))
