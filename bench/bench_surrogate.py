"""CPU inference of the wear surrogate: ``python bench/bench_surrogate.py``.

Prints the batch throughput [rows/s] (median of 7 runs) of the main job's network (width 16,
depth 2, 5 members, 8 inputs: the magnitudes of the DTE mesh lines' vector changes and the
operating point) on 1e6 rows through ``Surrogate.predict_array`` served by ONNX Runtime
(``Surrogate.serve``) on two threads and on one, its single-row latency and the one-off cost
of ``serve()`` (the import and the export, the first in the process), the public
``Surrogate.predict`` as a loaded model runs it, in torch (the schema checks, the gearbox checks
and each gearbox's vector changes since its first record, gearboxes of 8 records; one reading:
a gearbox's baseline record and one record); as references measured in the same run, the same
computation in torch (:func:`surrogate.inference.torch_predict`) and the analytic
empirical-inverse estimator (target: >= 1e6 rows/s and >= 100 times the estimator). Timing
does not depend on the weights' values, so the network is built with its initial weights; the
schema is fitted to random rows. ``--out FILE.json`` also writes the figures
(``docs/figures/bench_surrogate.json`` is the run the README quotes).
"""

from __future__ import annotations

import argparse
import json
import time
import timeit
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd
import torch

from physics.estimators.empirical_inverse import EmpiricalInverse
from surrogate.inference import ScaledEnsemble, Surrogate, torch_predict
from surrogate.inputs import BASELINE_INPUTS, input_columns
from surrogate.model import WearRegressor
from surrogate.schema import FeatureSchema, vector_columns


def rate(fn, n_rows: int, repeat: int = 7) -> float:
    """Rows per second of ``fn()`` over ``n_rows`` (median of ``repeat``: this machine's
    timings scatter by a factor of 2 from run to run)."""
    return n_rows / float(np.median(timeit.repeat(fn, number=1, repeat=repeat)))


def latency_us(fn, repeat: int = 300) -> float:
    """Median time of one call [us]."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times)) * 1e6


def records(rng: np.random.Generator, n: int, per_gearbox: int) -> pd.DataFrame:
    """``n`` records of gearboxes of ``per_gearbox`` records each, as a user's table gives
    them: the lines' parts [m], a gearbox's one operating point, its id."""
    parts = vector_columns(BASELINE_INPUTS)
    frame = pd.DataFrame(rng.normal(0.0, 1e-6, (n, len(parts))), columns=parts)
    gearbox = np.arange(n) // per_gearbox
    point = rng.uniform(1.0, 2.0, (gearbox[-1] + 1, 2))[gearbox]
    return frame.assign(n1_rpm=point[:, 0], torque_Nm=point[:, 1], gearbox=gearbox)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, help="also write the figures to this JSON file")
    args = ap.parse_args()
    if args.out is not None and args.out.suffix != ".json":
        ap.error(f"--out = {str(args.out)!r} is not a .json file name; give e.g. "
                 "docs/figures/bench_surrogate.json")
    torch.manual_seed(0)
    cols = input_columns(["dte", "acc"], True, baseline=True)
    lines = tuple(BASELINE_INPUTS)
    rng = np.random.default_rng(0)
    train = pd.DataFrame(rng.uniform(1.0, 2.0, (512, len(cols))), columns=cols)
    train[list(lines)] = rng.uniform(0.0, 3e-6, (512, len(lines)))  # changes [m]
    train["mean_wear_mm"] = rng.uniform(0, 0.03, 512)
    schema = FeatureSchema.fit(train, cols, dict.fromkeys([*cols, "mean_wear_mm"], "1"),
                               "mean_wear_mm", baseline=lines, vectors=lines)
    model = WearRegressor(len(cols), schema.to_dict(), width=16, depth=2, members=5)
    n, per_gearbox = 1_000_000, 8
    x = rng.uniform(1.0, 2.0, (n, len(cols)))
    frame = records(rng, n, per_gearbox)
    threads = torch.get_num_threads()
    graph = ScaledEnsemble(model, schema)
    measured, serve_s = {}, None
    for t in (threads, 1):  # the session takes torch's thread count when it is built
        torch.set_num_threads(t)
        start = time.perf_counter()
        served = Surrogate(model, interval_scale=1.645).serve()
        serve_s = time.perf_counter() - start if serve_s is None else serve_s
        served.predict_array(x[:1000])
        measured[t] = (rate(partial(served.predict_array, x), n),
                       rate(partial(torch_predict, graph, x), n))
    torch.set_num_threads(threads)
    (batch, ref), (serial, ref_serial) = measured[threads], measured[1]
    served = Surrogate(model, interval_scale=1.645).serve()
    one = latency_us(lambda: served.predict_array(x[:1]))
    one_ref = latency_us(lambda: torch_predict(graph, x[:1]))
    s = Surrogate(model, interval_scale=1.645)  # as loaded: torch
    checked = rate(lambda: s.predict(frame, gearbox=["gearbox"]), n, repeat=2)
    one_checked = latency_us(lambda: s.predict(frame.iloc[:2], gearbox=["gearbox"]),
                             repeat=100)

    est = EmpiricalInverse.from_config("thesis")
    cycles = rng.uniform(0, est.cycles_max, 200_000)
    k = cycles / est.cycles_unit
    p2p, kurt = np.polyval(est.p2p_cubic, k), np.polyval(est.kurtosis_cubic, k)
    est.predict(p2p[:10], kurt[:10])
    est_rate = rate(lambda: est.predict(p2p, kurt), p2p.size)
    est_one = latency_us(lambda: est.predict(p2p[:1], kurt[:1]), repeat=100)

    print(f"torch threads                       : {threads}")
    print(f"serve() once (import and export)    : {serve_s:.2f} s")
    print(f"served, batch of {n:,} rows     : {batch:,.0f} rows/s (target >= 1e6)")
    print(f"served, same, one thread            : {serial:,.0f} rows/s")
    print(f"same in torch (reference)           : {ref:,.0f} rows/s, one thread "
          f"{ref_serial:,.0f} (ONNX Runtime / torch: {batch / ref:.2f}, {serial / ref_serial:.2f})")
    print(f"surrogate.predict (checks, changes) : {checked:,.0f} rows/s (torch)")
    print(f"served, one row                     : {one:.0f} us (torch {one_ref:.0f} us; "
          f"{one_checked:.0f} us for one reading through predict)")
    print(f"empirical inverse, batch            : {est_rate:,.0f} rows/s, one row {est_one:.0f} us")
    print(f"surrogate / estimator (batch)       : {batch / est_rate:.0f} x (target >= 100)")
    if args.out is not None:
        figures = {"torch_threads": threads, "serve_s": serve_s, "batch_rows_per_s": batch,
                   "one_thread_rows_per_s": serial, "torch_rows_per_s": ref,
                   "torch_one_thread_rows_per_s": ref_serial, "predict_rows_per_s": checked,
                   "one_row_us": one, "one_reading_through_predict_us": one_checked,
                   "torch_one_row_us": one_ref, "estimator_rows_per_s": est_rate,
                   "estimator_one_row_us": est_one, "over_estimator": batch / est_rate}
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
