"""One table of a sweep's runs: ``python -m surrogate.summarise SWEEP_DIR [--out FILE]``.

Each run folder of a Hydra multirun (``logs/train/multiruns/<time>/<n>``) that holds a
``metrics.json`` gives one row: the run, its overrides (``.hydra/overrides.yaml``) and its
metrics; failed runs (no metrics) are listed with ``status=failed``. Rows are sorted by the
sweep's optimised metric. The table goes to ``SWEEP_DIR/summary.csv`` unless ``--out`` says
otherwise.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd
import yaml

from physics.files import atomic_write


def summarise(sweep: str | Path) -> pd.DataFrame:
    sweep = Path(sweep)
    runs = sorted((p for p in sweep.iterdir() if (p / ".hydra").is_dir()),
                  key=lambda p: (len(p.name), p.name)) if sweep.is_dir() else []
    if not runs:
        raise ValueError(f"{sweep} holds no Hydra run folders (<n>/.hydra); pass the folder "
                         "of a multirun, e.g. logs/train/multiruns/<time>")
    rows, metric = [], None
    for run in runs:
        overrides = yaml.safe_load((run / ".hydra" / "overrides.yaml").read_text()) or []
        row = {"run": run.name, "overrides": " ".join(overrides)}
        cfg = yaml.safe_load((run / ".hydra" / "config.yaml").read_text())
        metric = metric or cfg.get("optimized_metric")
        m = run / "metrics.json"
        if m.is_file():
            row.update(status="ok", **json.loads(m.read_text()))
        else:
            row["status"] = "failed"
        rows.append(row)
    df = pd.DataFrame(rows)
    if metric in df.columns:
        df = df.sort_values(metric, na_position="last").reset_index(drop=True)
    return df


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m surrogate.summarise",
                                     description=__doc__.split("\n\n")[1])
    parser.add_argument("sweep", help="the multirun folder (logs/train/multiruns/<time>)")
    parser.add_argument("--out", help="output CSV (default: SWEEP/summary.csv)")
    args = parser.parse_args(argv)
    df = summarise(args.sweep)
    out = Path(args.out or Path(args.sweep) / "summary.csv")
    atomic_write(out, lambda p: df.to_csv(p, index=False))
    print(df.to_string(max_colwidth=40))
    print(f"\n-> {out}")


if __name__ == "__main__":
    main()
