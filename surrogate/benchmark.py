"""Surrogate against the analytic empirical-inverse estimator: ``python -m surrogate.benchmark``.

On the same held-out trajectories, for

- ``case<k>``: a model of one case (``case=k``), tested on that case's test replicates;
- ``all``: one model of the five cases with the operating point as input (``case=all``);
- ``loco<k>``: leave one case out, trained on the other four, tested on all of case k;
- ``noisy_case3``: the case-3 model and estimator on a second dataset of the same trajectories
  with 10 dB more measurement noise (``data.snr_db`` 20 instead of 30);

the estimator (thesis 4.4: cubics of DTE peak-to-peak and kurtosis in cycles and the empirical
wear law, :class:`physics.empirical_inverse.EmpiricalInverse`) is fitted on the same training
trajectories as the network. Columns: RMSE [mm], R2, mean and maximum relative error [%], the
interval coverage (surrogate), batch throughput [rows/s] and single-row latency [us] on the CPU.
Writes ``benchmark.csv``, ``parity.png`` and the trained models into ``--out`` (default
``logs/benchmark/<time>``).
"""

from __future__ import annotations

import argparse
import logging
import time
from datetime import datetime
from pathlib import Path

import numpy as np
import pandas as pd
from hydra import compose, initialize_config_module
from hydra.utils import instantiate

from physics.estimators.empirical_inverse import EmpiricalInverse, wear_errors
from physics.files import atomic_write, pyplot
from surrogate import settings
from surrogate.inference import Surrogate
from surrogate.training import parity_figure, train

TARGET = "root_wear_mm"
log = logging.getLogger(__name__)


def train_config(root: Path, out: Path, *overrides: str):
    settings.register()
    with initialize_config_module("gearwear_conf.train", version_base="1.3"):
        return compose("train", overrides=[
            f"paths.root_dir={root}", f"paths.output_dir={out}", "logger=csv",
            "trainer.enable_progress_bar=false", *overrides])


def fit_estimator(train: pd.DataFrame) -> EmpiricalInverse:
    return EmpiricalInverse.fit(train.cycles.to_numpy(), train.dte_peak_to_peak.to_numpy(),
                                train.dte_kurtosis.to_numpy(), train[TARGET].to_numpy())


def throughput(fn, x: np.ndarray) -> tuple[float, float]:
    """Rows per second on ``x`` as one batch, and the latency of one row [us] (median of 200)."""
    fn(x[:8])
    t = time.perf_counter()
    fn(x)
    rate = len(x) / (time.perf_counter() - t)
    times = []
    for i in range(200):
        t = time.perf_counter()
        fn(x[i:i + 1])
        times.append(time.perf_counter() - t)
    return rate, float(np.median(times)) * 1e6


def evaluate(name: str, surrogate: Surrogate, est: EmpiricalInverse, test: pd.DataFrame,
             speed: bool) -> tuple[list[dict], dict]:
    true = test[TARGET].to_numpy()
    pred = surrogate.predict(test[list(surrogate.schema.inputs)])
    e = est.predict(test.dte_peak_to_peak.to_numpy(), test.dte_kurtosis.to_numpy())
    inside = ((true >= pred[f"{TARGET}_lower"]) & (true <= pred[f"{TARGET}_upper"])).mean()
    rows = [{"scenario": name, "estimator": "surrogate", "test_rows": len(test),
             **wear_errors(pred[f"{TARGET}_pred"], true), "interval_coverage": float(inside),
             "flagged_rows": int(pred.out_of_range.sum())},
            {"scenario": name, "estimator": "empirical_inverse", "test_rows": len(test),
             **wear_errors(e.wear, true), "interval_coverage": np.nan,
             "flagged_rows": int(np.sum(~e.valid))}]
    if speed:
        x = np.repeat(test[list(surrogate.schema.inputs)].to_numpy(float),
                      -(-1_000_000 // len(test)), axis=0)[:1_000_000]
        rows[0]["rows_per_s"], rows[0]["latency_us"] = throughput(
            lambda a: surrogate.predict_array(a)[0], x)
        p, k = test.dte_peak_to_peak.to_numpy(), test.dte_kurtosis.to_numpy()
        pk = np.repeat(np.stack([p, k], 1), -(-200_000 // len(test)), axis=0)[:200_000]
        rows[1]["rows_per_s"], rows[1]["latency_us"] = throughput(
            lambda a: est.predict(a[:, 0], a[:, 1]).wear, pk)
    plot = {"true": true, "surrogate": pred[f"{TARGET}_pred"].to_numpy(), "estimator": e.wear}
    return rows, plot


def run(out: Path, root: Path, max_epochs: int | None = None) -> pd.DataFrame:
    extra = [f"trainer.max_epochs={max_epochs}"] if max_epochs else []
    scenarios = [(f"case{c}", [f"case={c}"]) for c in range(1, 6)]
    scenarios.append(("all", ["case=all"]))
    scenarios += [(f"loco{c}", ["case=all", f"data.holdout_case={c}"]) for c in range(1, 6)]
    rows, plots = [], {}
    for name, overrides in scenarios:
        cfg = train_config(root, out / "models" / name, *overrides, *extra)
        log.info("scenario %s: training", name)
        train(cfg)
        dm = instantiate(cfg.data)
        dm.setup()
        surrogate = Surrogate.load(out / "models" / name / "wear_surrogate.pt")
        est = fit_estimator(dm.frames["train"])
        r, plots[name] = evaluate(name, surrogate, est, dm.frames["test"], speed=name == "case3")
        rows += r
        if name == "case3":
            noisy_cfg = train_config(root, out / "models" / "noisy", "case=3",
                                     f"data.dataset={root}/data/dataset_snr20.parquet",
                                     "+data.generate.snr_db=20", *extra)
            noisy = instantiate(noisy_cfg.data)
            noisy.setup()
            r, plots["noisy_case3"] = evaluate("noisy_case3", surrogate, est,
                                               noisy.frames["test"], speed=False)
            rows += r
    table = pd.DataFrame(rows)
    atomic_write(out / "benchmark.csv", lambda p: table.to_csv(p, index=False))
    plt = pyplot()
    fig, axes = plt.subplots(1, 4, figsize=(18, 4.6))
    for ax, name in zip(axes, ["case3", "all", "loco3", "noisy_case3"], strict=True):
        d = plots[name]
        parity_figure(d["true"], d["estimator"], None, name, TARGET, ax)
        ax.lines[0].set_label("empirical inverse")
        parity_figure(d["true"], d["surrogate"], None, name, TARGET, ax)
        ax.legend(["empirical inverse", "identity", "surrogate"], fontsize=7)
    atomic_write(out / "parity.png", lambda p: fig.savefig(p, dpi=110, format="png"))
    plt.close(fig)
    return table


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m surrogate.benchmark",
                                     description=__doc__.split("\n\n")[0],
                                     epilog="Takes about 5 minutes on 2 cores (11 trainings; "
                                            "a second, noisier dataset is generated once).")
    parser.add_argument("--out", type=Path, default=None,
                        help="output folder (default: logs/benchmark/<time>)")
    parser.add_argument("--max-epochs", type=int, default=None,
                        help="cap the training epochs (quick looks; the default config's "
                             "early stopping otherwise)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    out = args.out or Path("logs/benchmark") / datetime.now().strftime("%Y-%m-%d_%H-%M-%S")
    table = run(out.resolve(), Path.cwd(), args.max_epochs)
    cols = ["scenario", "estimator", "rmse", "r2", "mean_relative_error_pct",
            "max_relative_error_pct", "interval_coverage", "rows_per_s", "latency_us"]
    with pd.option_context("display.width", 200, "display.float_format", "{:.4g}".format):
        print(table[[c for c in cols if c in table.columns]].to_string(index=False))
    print(f"\n-> {out / 'benchmark.csv'}, {out / 'parity.png'}")


if __name__ == "__main__":
    main()
