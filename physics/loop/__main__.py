"""``python -m physics.loop data=BUNDLE|TABLE.csv``: close the loop with measured data (schema
:class:`~physics.loop.config.LoopConfig`, choices ``conf/loop/loop.yaml``; method in
:mod:`physics.loop.bundle_loop` and :mod:`physics.loop.table_loop`)."""

# ruff: noqa: E402 (the imports after the handlers: see install_at_start)
from __future__ import annotations

from physics.interrupt import install_at_start

install_at_start(__name__)  # Ctrl-C and SIGTERM handled from here on, during the slow imports

import logging
import sys
from dataclasses import dataclass
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from physics.command import check_run_folder as command_check_run_folder
from physics.command import entry, register_schema, run_command
from physics.loop.bundle_loop import run_loop
from physics.loop.config import LoopConfig, LoopSettings
from physics.loop.measured.bundle import (
    Bundle,
    FeatureTable,
    check_not_own_reference,
    read_measurements,
)
from physics.loop.measured.records import group_keys
from physics.loop.measured.usable import (
    check_reference_folder,
    check_stated_once,
    check_usable,
    shown_candidates,
)
from physics.loop.report import write_report
from physics.loop.search.attribution import candidates_for
from physics.loop.search.form_error import check_reference, form_reference
from physics.loop.search.own_history import parse_history, split_history
from physics.loop.search.own_history import source as history_source
from physics.loop.table_loop import (
    check_table,
    check_table_settings,
    parse_columns,
    run_feature_table,
    table_candidates,
)
from physics.params import (
    Scenario,
    scenario_from_config,
)

log = logging.getLogger(__name__)


register_schema("loop_schema", LoopConfig)


@dataclass(frozen=True)
class LoopJob:
    data: Bundle | FeatureTable
    scenario: Scenario
    settings: LoopSettings
    progress: bool
    out: Path
    reference: Bundle | None  # a sister gearbox's bundle, or this one's earliest records
    history: str | None = None  # ``reference=first:N`` or ``before:X``: the unit's own


def prepare(cfg: DictConfig) -> LoopJob:
    opts = OmegaConf.to_container(cfg.loop, resolve=True)
    settings = LoopSettings(**opts)
    for key in ("data", "reference"):
        if isinstance(cfg[key], str) and not cfg[key].strip():
            raise ValueError(f"{key}= is empty (it was read as the working folder); "
                             + ("give a bundle folder or a feature-table .csv file "
                                "(docs/own-data.md)" if key == "data" else
                                "give first:N, before:X or a sister gearbox's bundle folder, "
                                "or leave out reference="))
    base = scenario_from_config(cfg)
    if base.dynamics.flank_contact != "path" and Path(cfg.data).suffix != ".csv":
        raise ValueError(f"dynamics.flank_contact = {base.dynamics.flank_contact!r}: the loop's "
                         "effects modify the contact on the path of a bundle's records (the "
                         "off-path pairs of the exact contact are not in them yet); leave it at "
                         "'path' (a feature table takes either: docs/loop.md)")
    data, scn = read_measurements(cfg.data, base)
    check_stated_once(cfg, data, base, _given())
    if isinstance(data, FeatureTable):  # what the loop cannot follow: refused before work
        check_table_settings(_given())
        check_table(data, scn, _given())
        table_candidates(parse_columns(data.frame)[0], scn, settings)
    history = parse_history(cfg.reference)
    reference = None
    if history is not None:  # the unit's own earliest records: left out of the analysis
        if not isinstance(data, Bundle):
            raise ValueError(f"reference={cfg.reference}: a reference serves bundles of "
                             f"records; data={cfg.data} is a feature table; leave out "
                             "reference=")
        reference, data = split_history(data, history)
    if isinstance(data, Bundle):  # what the loop cannot use: refused before work
        check_usable(data, scn, settings)
        shown_candidates(candidates_for(set(data.manifest.quantity), settings), data, scn,
                         settings)
    if history is not None:
        try:
            check_usable(reference, scn, settings)
        except ValueError as err:
            rule = str(err).removeprefix(f"bundle {reference.path}: ")
            if "train and one test record" in rule:
                rule = ("the reference is calibrated as the loop calibrates, on a train and a "
                        "test record of each group")
            raise ValueError(f"reference={cfg.reference} takes {len(reference.records)} "
                             f"record(s) {reference.records} as the reference: {rule}; take "
                             "more records as the reference (first:2 or more), or give a "
                             "sister gearbox's bundle") from None
        check_reference(data, reference.gear, group_keys(reference.manifest)[0])
    elif cfg.reference is not None:
        check_reference_folder(cfg.reference)
        check_not_own_reference(cfg.data, cfg.reference)
        if not isinstance(data, Bundle):
            raise ValueError(f"reference={cfg.reference}: a reference serves bundles of "
                             f"records; data={cfg.data} is a feature table; leave out "
                             "reference=")
        reference, _ = read_measurements(cfg.reference, base)
        if not isinstance(reference, Bundle):
            raise ValueError(f"reference={cfg.reference}: must be a bundle folder "
                             "(docs/own-data.md), not a feature table")
        check_usable(reference, scn, settings)
        check_reference(data, reference.gear, group_keys(reference.manifest)[0])
    return LoopJob(data, scn, settings, bool(cfg.progress),
                   Path(HydraConfig.get().runtime.output_dir), reference,
                   history.spec if history is not None else None)


def _given() -> set[str]:
    """The keys given on the command line (``hydra.overrides.task``; none where unknown)."""
    try:
        task = HydraConfig.get().overrides.task
    except (ValueError, AttributeError):
        return set()
    return {str(o).split("=", 1)[0].lstrip("+~") for o in task}


def execute(job: LoopJob) -> None:
    """Run the loop and write its report. Ctrl-C or SIGTERM (a batch system's time limit;
    :mod:`physics.interrupt` raises both as KeyboardInterrupt) keeps what was computed by then
    (:func:`~physics.loop.bundle_loop.run_loop`), marked partial."""
    if isinstance(job.data, Bundle):
        reference = None
        if job.reference is not None:
            log.info("calibrating the declared model on the reference's %d records",
                     len(job.reference.records))
            reference = form_reference(
                job.reference, job.scenario, job.settings,
                **({"source": history_source(job.history)} if job.history else {}))
        report = run_loop(job.data, job.scenario, job.settings, progress=job.progress,
                          reference=reference)
    else:
        report = run_feature_table(job.data, job.scenario, job.settings)
    write_report(report, job.out)
    if report.partial and report.partial["interrupted"]:
        raise KeyboardInterrupt  # after the partial report: run_command ends the run
    if report.error_before is None:  # stopped by loop.time_limit_s in the first round
        log.warning("the time limit of %g s passed in the first round: %s; the partial report "
                    "is in %s", job.settings.time_limit_s, report.partial["missing"], job.out)
        return
    log.info("chosen effect: %s; held-out error %.3f -> %.3f; report in %s",
             report.chosen_effect, report.error_before, report.error_after, job.out)


@hydra.main(version_base="1.3", config_path="pkg://gearwear_conf.loop", config_name="loop")
def task(cfg: DictConfig) -> None:
    run_command(cfg, prepare, execute,
                kept=lambda job: (f"a partial report is kept in {job.out} (report.json: "
                                  "partial: what was computed before the stop)"
                                  if (job.out / "report.json").is_file() else
                                  "nothing is kept (the loop writes its report after its first "
                                  "round); run the command again"))


_main = entry(task, check=prepare)


def check_run_folder(argv: list[str]) -> None:
    """Refuse (one line, exit 2) a run whose run folder (``hydra.run.dir``, or
    ``hydra.sweep.dir`` with ``-m``; ``logs/loop/...`` of the working folder by default) cannot
    be made, before Hydra tries: from a read-only working folder Hydra raised a
    PermissionError traceback. Help and config printing (``--help``, ``--cfg``, ...) make no
    folder and are left alone."""
    if any(a.split("=")[0] in ("--help", "-h", "--hydra-help", "--cfg", "-c", "--info", "-i",
                               "--shell-completion", "-sc", "--resolve") for a in argv):
        return
    sweep = any(a in ("-m", "--multirun") for a in argv)
    key = "hydra.sweep.dir" if sweep else "hydra.run.dir"
    given = [a.split("=", 1)[1] for a in argv if a.split("=", 1)[0].lstrip("+") == key]
    spec = given[-1].strip("'\"") if given else (
        "logs/loop/multiruns/${now:}" if sweep else "logs/loop/runs/${now:}")
    parts = Path(spec).parts
    fixed = Path(*parts[:next((i for i, p in enumerate(parts) if "${" in p), len(parts))] or ".")
    command_check_run_folder(fixed, key)


def main():
    check_run_folder(sys.argv[1:])
    return _main()


main.__doc__ = task.__doc__


if __name__ == "__main__":
    main()
