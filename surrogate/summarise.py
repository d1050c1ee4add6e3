"""One table of a sweep's runs: ``python -m surrogate.summarise SWEEP_DIR [--out FILE]``.

Each run folder of a Hydra multirun (``logs/train/multiruns/<time>/<n>``) that holds a
``metrics.json`` gives one row: the run, its overrides (``.hydra/overrides.yaml``) and its
metrics; failed runs (no metrics) are listed with ``status=failed``, runs whose records cannot
be read with ``status=unreadable`` and the reason. Rows are sorted by the sweep's optimised
metric. The table goes to ``SWEEP_DIR/summary.csv`` unless ``--out`` says
otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

import pandas as pd
import yaml

from physics.files import WriteFailed, atomic_write, check_writable, resolved

#: what to pass instead of a bad folder
FIX = "pass the folder of a multirun, e.g. logs/train/multiruns/<time>"


def run_folders(sweep: object) -> list[Path]:
    """The run folders (``<n>/.hydra``) of the multirun folder ``sweep``, in their order;
    ValueError (one line, naming the folder and what is wrong) for anything else: no folder
    name, a path that does not exist, a file, a folder that cannot be read, a folder without
    run folders."""
    if isinstance(sweep, bool) or not isinstance(sweep, str | os.PathLike) or sweep == "":
        raise ValueError(f"sweep = {sweep!r} is not a folder name; {FIX}")
    sweep = Path(sweep)
    if not sweep.exists():
        raise ValueError(f"{sweep} does not exist; {FIX}")
    if not sweep.is_dir():
        what = "a file" if sweep.is_file() else "a device, a FIFO or a socket"
        raise ValueError(f"{sweep} is {what}, not a folder; {FIX}")
    try:
        runs = [p for p in sweep.iterdir() if (p / ".hydra").is_dir()]
    except OSError as err:
        raise ValueError(f"{sweep} cannot be read ({err.strerror or err}); {FIX}") from None
    if not runs:
        what = "is empty" if not any(sweep.iterdir()) else "holds no Hydra run folders (<n>/.hydra)"
        raise ValueError(f"{sweep} {what}: it is not the folder of a multirun; {FIX}")
    return sorted(runs, key=lambda p: (len(p.name), p.name))


def run_row(run: Path) -> tuple[dict, str | None]:
    """One run's row (its overrides, status and metrics) and its optimised metric's name: a
    run whose records cannot be read is a row with ``status=unreadable`` and the reason."""
    row: dict = {"run": run.name}
    try:
        overrides = yaml.safe_load((run / ".hydra" / "overrides.yaml").read_text()) or []
        cfg = yaml.safe_load((run / ".hydra" / "config.yaml").read_text()) or {}
        metrics = run / "metrics.json"
        values = json.loads(metrics.read_text()) if metrics.is_file() else None
        if not isinstance(overrides, list) or not isinstance(cfg, dict) or not isinstance(
                values, dict | None):
            raise ValueError("its records hold something else than a run's")
    except (OSError, ValueError, yaml.YAMLError) as err:
        reason = " ".join(str(err).split())
        return {**row, "status": "unreadable", "error": reason}, None
    row["overrides"] = " ".join(map(str, overrides))
    if values is None:
        row["status"] = "failed"
    else:
        row.update(status="ok", **values)
    return row, cfg.get("optimized_metric")


def summarise(sweep: str | Path) -> pd.DataFrame:
    """One row per run of the multirun folder ``sweep`` (:func:`run_folders`, :func:`run_row`),
    sorted by the sweep's optimised metric."""
    rows, metric = [], None
    for run in run_folders(sweep):
        row, optimised = run_row(run)
        rows.append(row)
        metric = metric or optimised
    df = pd.DataFrame(rows)
    if metric in df.columns:
        df = df.sort_values(metric, na_position="last").reset_index(drop=True)
    return df


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m surrogate.summarise",
                                     description=__doc__.split("\n\n")[1])
    parser.add_argument("sweep", help="the multirun folder (logs/train/multiruns/<time>)")
    parser.add_argument("--out", help="output CSV (default: SWEEP/summary.csv, which a run "
                                      "of this command replaces)")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace an existing --out file (never one of the sweep's own)")
    args = parser.parse_args(argv)
    default = Path(args.sweep) / "summary.csv"
    out = Path(args.out or default)
    try:
        df = summarise(args.sweep)
        if out.is_dir() or (out.exists() and not out.is_file()):
            raise ValueError(f"--out = {str(out)!r} is not a regular file; give a .csv file "
                                 "name")
        mine = resolved(out) == resolved(default)
        if not mine and resolved(args.sweep) in resolved(out).parents:
            raise ValueError(f"--out = {str(out)!r} lies in the sweep's folder, whose files "
                             "this command reads; give a file outside it (or leave --out out: "
                             f"{default})")
        if not mine and out.exists() and not args.overwrite:
            raise ValueError(f"--out = {str(out)!r} already exists: a file this command did "
                             "not write is replaced only when asked; give another file name, "
                             "or add --overwrite")
        check_writable(out.parent, "--out")
        atomic_write(out, lambda p: df.to_csv(p, index=False))
    except ValueError as err:
        parser.exit(2, f"error: {err}\n")
    except WriteFailed as err:
        parser.exit(1, f"error: {err.strerror}; make room (or choose another --out) and run "
                       "the command again\n")
    print(df.to_string(max_colwidth=40))
    print(f"\n-> {out}")


if __name__ == "__main__":
    main()
