"""Wear from features on the CPU: ``python -m surrogate.predict ckpt=PATH input=FILE``.

``input`` is a CSV or parquet table with the feature columns the model was trained on (their
names and units are in the checkpoint; a missing one is refused, naming it). Every other column
(labels, ids, the true wear, features the model does not read) passes through: ``output``
(default: ``wear.csv`` in the run folder; never the input itself, and an existing file only with
``overwrite=true``) gets them and ``<target>_pred`` (the
model's wear: ``root_wear_mm`` or ``mean_wear_mm``), its standard deviation, the interval
bounds, the ``novelty`` score and the ``out_of_range`` flag (:mod:`surrogate.novelty`); where
more rows are flagged than of the training distribution, or the table's true wear (a column
of the model's target) lies beyond the trained range, one line in the log says so. A model
read against each gearbox's first record (``data.baseline``: the main job's) reads it so:
``gearbox=COLUMN`` (or ``gearbox=[A,B]``) names the column(s) that tell the gearboxes apart,
which the output keeps.
Each gearbox needs its baseline record first and at least one record after it; where a
``cycles`` column is given each gearbox's rows must be sorted by it, and without one the
table's row order is taken as the time order (the first row of a gearbox is its baseline).
From Python::

    from surrogate import Surrogate
    wear = Surrogate.load("wear_surrogate.pt").predict(features_df, gearbox=["rig"])
"""

# ruff: noqa: E402 (the imports after the handlers: see install_at_start)
from __future__ import annotations

from physics.interrupt import deferred, install_at_start

install_at_start(__name__)  # Ctrl-C and SIGTERM handled from here on, during the slow imports

import logging
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import hydra
import pandas as pd
from omegaconf import DictConfig

from physics.command import entry, run_command
from physics.files import atomic_write, check_unrepeated, check_writable, existing_file
from surrogate.settings import model_file

if TYPE_CHECKING:
    from surrogate.inference import Surrogate

log = logging.getLogger(__name__)


def read_table(path: str | Path) -> pd.DataFrame:
    path = existing_file(path, "input", "pass a CSV or parquet feature table")
    if path.suffix not in (".parquet", ".csv"):
        raise ValueError(f"input = {path}: use a .csv or .parquet file")
    check_unrepeated(path, f"input = {path}")
    try:
        return pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError,
            OSError) as err:
        raise ValueError(f"input = {path} is not a readable table ({err})") from None


@dataclass(frozen=True)
class PredictJob:
    surrogate: Surrogate
    table: pd.DataFrame
    output: Path
    gearbox: tuple[str, ...] = ()  # the columns that tell the gearboxes apart (baseline models)


def check_output(value: object, source: Path, overwrite: object, model: Path | None = None
                 ) -> Path:
    """The output file ``value``; refused (ValueError, one line) where it is no file name, or
    would replace a file: the input table ``source`` or the model file ``model`` (existing
    files) itself, also through a link, always; another existing file unless ``overwrite`` is
    true; a folder; a device or a FIFO (/dev/full); a folder that cannot be written."""
    if isinstance(value, bool) or not isinstance(value, str | os.PathLike) or value == "":
        raise ValueError(f"output = {value!r} is not a file name; give a .csv file name")
    output = Path(value)
    if not isinstance(overwrite, bool):
        raise ValueError(f"overwrite = {overwrite!r} is not a switch; give overwrite=true or "
                         "overwrite=false")
    if output.is_dir():
        raise ValueError(f"output = {str(output)!r} is a folder; give a .csv file name")
    if output.exists() and not output.is_file():
        raise ValueError(f"output = {str(output)!r} is not a regular file (a FIFO, a device or "
                         "a socket); give a .csv file name")
    if output.exists():
        for option, given in (("input", source), ("ckpt", model)):
            if given is not None and given.is_file() and os.path.samefile(output, given):
                raise ValueError(f"output = {str(output)!r} is the {option} file itself "
                                 f"({option} = {str(given)!r}): the predictions never replace "
                                 "what the run reads; give another output file name")
        if not overwrite:
            raise ValueError(f"output = {str(output)!r} already exists: a file this run did "
                             "not write is replaced only when asked; give another output file "
                             "name, or pass overwrite=true to replace it")
    check_writable(output.parent, "output")
    return output


def prepare(cfg: DictConfig) -> PredictJob:
    """Load and check the checkpoint and the table, and the output (:func:`check_output`),
    before any work."""
    return checked_job(cfg.ckpt, cfg.input, cfg.output, cfg.get("gearbox"), cfg.overwrite)


def checked_job(ckpt: object, source: object, target: object, gearbox: object,
                overwrite: object) -> PredictJob:
    """The model, the table and the output checked (:func:`check_output`) before any work,
    each refusal naming the option (``ckpt``, ``input``, ``output``, ``gearbox``). The files
    are judged before the model's reader (torch, about 2 s) is imported."""
    model = model_file(ckpt, "ckpt")
    table = read_table(source)
    output = check_output(target, Path(source), overwrite, model)
    with deferred():  # a signal during the import is raised after it
        from surrogate.inference import Surrogate, check_gearboxes, gearbox_columns
    surrogate = Surrogate.load(model, key="ckpt")
    columns = gearbox_columns(gearbox)
    if surrogate.schema.baseline:
        check_gearboxes(table, list(columns), surrogate.schema.target, f"input = {source}")
    surrogate.schema.check(surrogate.schema.network_rows(table, list(columns)))
    return PredictJob(surrogate, table, output, columns)


def predict_file(ckpt: str | Path, source: str | Path, target: str | Path,
                 gearbox: str | Sequence[str] | None = (), overwrite: bool = False
                 ) -> pd.DataFrame:
    """Predict wear for every row of ``source`` with ``ckpt`` (``gearbox``: the column or
    columns that tell the gearboxes apart, for a model read against each one's first record);
    write ``target`` (never ``source`` itself; an existing file only with ``overwrite``);
    return it. Every argument is checked before any work, as the command checks it."""
    return execute(checked_job(ckpt, source, target, gearbox or None, overwrite))


def execute(job: PredictJob) -> pd.DataFrame:
    from surrogate.novelty import envelope_report  # imported with the model's reader

    df = job.table
    pred = job.surrogate.predict(df, list(job.gearbox))
    keep = [c for c in df.columns if c not in job.surrogate.schema.columns
            and c not in pred.columns]  # labels, ids, other features: passed through
    result = pd.concat([df[keep], pred], axis=1)
    atomic_write(job.output, lambda p: result.to_csv(p, index=False))
    schema, novelty = job.surrogate.schema, job.surrogate.novelty
    true = (pd.to_numeric(df[schema.target], errors="coerce").to_numpy(float)
            if schema.target in df.columns else None)
    _, line = envelope_report(result.out_of_range.to_numpy(), novelty, true, "rows",
                              schema.target_unit)
    if line:
        log.warning(line)
    log.info("%d rows -> %s", len(result), job.output)
    return result


@hydra.main(version_base="1.3", config_path="pkg://gearwear_conf.predict",
            config_name="predict")
def task(cfg: DictConfig) -> None:
    run_command(cfg, prepare, execute,
                kept=lambda job: f"nothing is kept ({job.output} is written at the end, "
                                 "whole or not at all); run the command again")


main = entry(task, check=prepare)


if __name__ == "__main__":
    main()
