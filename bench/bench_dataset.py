"""Dataset and estimator benchmark: ``python bench/bench_dataset.py``.

Prints:
- wall time and peak memory (this process and its workers) of the default dataset of
  ``python -m physics.dataset`` (5 cases x 64 replicates x 8 wear states; memory target <= 2 GB
  on this 2-core machine; the time is dominated by the wear evolution of each trajectory, about
  0.6 s each), written to a temporary folder, with 2 worker processes and, as the
  reference measured in the same run, one chunk of it with one process;
- the analytic empirical-inverse estimator's throughput in rows per second, vectorised over a
  batch against one call per row (the surrogate is compared with these figures).
"""

from __future__ import annotations

import resource
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from physics.dataset.generation import (
    DatasetSpec,
    build_dataset,
    plan_dataset,
)
from physics.estimators.empirical_inverse import EmpiricalInverse
from physics.params import Scenario


def peak_mb() -> float:
    """Largest resident set of this process and of its largest finished child [MB]."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return max(own, children) / 1024


def timed_generation(out: Path, chunk: int | None = None, jobs: int = 2
                     ) -> tuple[float, Path | None]:
    """The default dataset (``python -m physics.dataset``) into ``out``, timed."""
    job = plan_dataset(Scenario(), DatasetSpec(), out, chunk=chunk,
                       jobs=jobs, progress=False)
    t = time.perf_counter()
    path = build_dataset(job)
    return time.perf_counter() - t, path


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        t_full, path = timed_generation(Path(tmp) / "full")
        df = pd.read_parquet(path)
        trajectories = len(df.groupby(["case", "replicate"]))
        t_one, _ = timed_generation(Path(tmp) / "one", chunk=0, jobs=1)
    print(f"default dataset: {len(df)} rows ({df.case.nunique()} cases, "
          f"{df.groupby('case').replicate.nunique().min()} replicates, "
          f"{df.groupby(['case', 'replicate']).size().min()} wear states) "
          f"in {t_full:.1f} s with 2 processes ({2 * t_full / trajectories:.2f} s per "
          f"trajectory and process); peak memory {peak_mb():.0f} MB (target <= 2048 MB)")
    print(f"reference, 1 process: one chunk of 5 in {t_one:.1f} s -> {5 * t_one:.1f} s for all; "
          f"speed-up of the parallel run {5 * t_one / t_full:.2f}x")

    est = EmpiricalInverse.from_config("thesis")
    rng = np.random.default_rng(0)
    cycles = rng.uniform(0, est.cycles_max, 200_000)
    n = cycles / est.cycles_unit
    p2p, kurt = np.polyval(est.p2p_cubic, n), np.polyval(est.kurtosis_cubic, n)
    est.predict(p2p[:10], kurt[:10])
    t = time.perf_counter()
    est.predict(p2p, kurt)
    batch = p2p.size / (time.perf_counter() - t)
    t = time.perf_counter()
    for i in range(500):
        est.predict(p2p[i], kurt[i])
    single = 500 / (time.perf_counter() - t)
    print(f"empirical-inverse estimator: {batch:,.0f} rows/s in a batch of {p2p.size:,}; "
          f"{single:,.0f} rows/s one row per call ({1e6 / single:.0f} us latency); "
          f"batch/single {batch / single:.0f}x")


if __name__ == "__main__":
    main()
