"""The data of a training run, without torch or Lightning: the physics dataset
(:mod:`physics.dataset`) or a user's table, every setting checked and the split planned when
:class:`WearData` is made, the rows read and split by :meth:`WearData.setup`.
:class:`surrogate.data.WearDataModule` serves them to Lightning; ``train.py`` makes a
:class:`WearData` of its settings before it imports Lightning, so that a setting of the data
is refused in a second or two, not after the imports.

The physics dataset is read from its file, built with the dataset API where it is missing
(:func:`load_dataset`); a user's table is read and checked by :mod:`surrogate.tables`. Rows
are split by trajectory (:mod:`surrogate.splits`); the network's inputs are those of
:mod:`surrogate.inputs` unless named. The input scaling is fitted on the training rows only
and travels with the model in its :class:`~surrogate.schema.FeatureSchema`.

A dataset built here simulates :func:`replicates_per_case` gearboxes per trained case: what a
network learns about gearboxes it was not trained on is set by how many it was trained on
(docs/surrogate.md, Alternatives considered).
"""

from __future__ import annotations

import copy
import dataclasses
import json
import logging
import math
from pathlib import Path

import numpy as np
import pandas as pd
from omegaconf import DictConfig

from physics.dataset.generation import (
    DatasetJob,
    build_dataset,
    check_not_users,
    dataset_digest,
    plan_dataset,
    spec_from_config,
)
from physics.dataset.generation import units as dataset_units
from physics.files import repeated
from physics.params import Scenario
from surrogate import settings
from surrogate.inputs import (
    CONDITIONS,
    SENSORS,
    input_columns,
    operating_columns,
    stating_operating,
)
from surrogate.schema import (
    FeatureSchema,
    first_rows,
    network_frame,
    source_columns,
    vector_columns,
    vector_inputs,
)
from surrogate.splits import (
    calibration_split,
    check_split,
    match_groups,
    split_table,
    split_trajectories,
)
from surrogate.tables import (
    check_columns,
    read_user_table,
    table_units,
    user_rows,
    with_vector_units,
)

log = logging.getLogger(__name__)


#: the fewest gearboxes per case a built dataset simulates: the all-case network's error on
#: shifted gearboxes scatters over training seeds with fewer (docs/surrogate.md, Alternatives
#: considered)
MIN_REPLICATES = 128
#: chunks of a dataset built here (fewer where it has fewer trajectories): the build's
#: processes take chunks as they finish, so many small ones keep both cores busy to the end
#: (with the dataset API's 5, one of 2 processes idles through the last fifth of a build)
BUILD_CHUNKS = 32


def replicates_per_case(gearboxes: int, cases: int) -> int:
    """Gearboxes per case for a dataset of ``gearboxes`` shared by ``cases`` operating cases,
    at least :data:`MIN_REPLICATES` (so ``case=all`` has 128 per case)."""
    return max(MIN_REPLICATES, math.ceil(gearboxes / cases))


def stale_dataset(path: Path, job: DatasetJob) -> str | None:
    """What differs between the dataset at ``path`` and the one ``job`` would build (its
    sidecar's settings against the job's), or None when it is that dataset or has no sidecar
    of ours to compare."""
    sidecar = path.with_suffix(".json")
    side = json.loads(sidecar.read_text()) if sidecar.is_file() else {}
    # the chunks split the work, not the rows: the same dataset cut otherwise is not stale
    built = side.get("config", {}).get("data", {}).get("chunks")
    spec = job.spec
    if isinstance(built, int) and 1 <= built <= spec.units:
        spec = dataclasses.replace(spec, chunks=built)
    if side.get("hash") in (None, dataset_digest(job.base, spec)):
        return None
    have = side.get("config", {})
    want = json.loads(json.dumps({"scenario": dataclasses.asdict(job.base),
                                  "data": dataclasses.asdict(spec)}, default=str))
    diff = [f"{part}.{k}: {have.get(part, {}).get(k)!r} -> {v!r}"
            for part in ("data", "scenario") for k, v in want[part].items()
            if have.get(part, {}).get(k) != v]
    return "; ".join(diff) or "the physics it was built with"


#: how a refusal names the folder a missing dataset is built into
BUILD_FOLDER = "the folder of data.dataset"


def dataset_job(path: str | Path, spec: dict | None = None, jobs: int = 2) -> DatasetJob:
    """The checked build of the dataset at ``path`` (``spec``: DatasetSpec values other than the
    defaults), as ``python -m physics.dataset out_dir=<folder> name=<stem>`` would run it."""
    path = Path(path)
    if path.suffix != ".parquet":
        raise ValueError(f"data.dataset = {str(path)!r} must name a .parquet file")
    return plan_dataset(Scenario(), spec_from_config(spec or {}), path.parent, path.stem,
                        jobs=jobs, out_key="the folder of data.dataset (paths.data_dir unless "
                                           "data.dataset is set)")


def load_dataset(path: str | Path, spec: dict | None = None, jobs: int = 2) -> pd.DataFrame:
    """Read the dataset at ``path``, building it with the dataset API if it is missing."""
    path = Path(path)
    job = dataset_job(path, spec, jobs)
    if not path.is_file():
        check_not_users(job, BUILD_FOLDER)
        log.info("dataset %s missing: generating it (physics.dataset, %d jobs)", path, jobs)
        build_dataset(job)
    elif (diff := stale_dataset(path, job)) is not None:
        log.warning("dataset %s was built with other settings than this run asks for (%s); "
                    "training on it as it is: delete it (or name another data.dataset) to "
                    "build the one this run describes", path, diff)
    return pd.read_parquet(path)


class WearData:
    """Features -> wear (the mean depth read against each gearbox's first record, or the root
    wear read absolutely), from the dataset of the given cases or a user's table: checked when
    made, read and split by :meth:`setup`."""

    def __init__(self, dataset: str, case: str | int = 3,
                 sensors: tuple[str, ...] = SENSORS, operating_point: bool = True,
                 inputs: list[str] | None = None, target: str | None = None,
                 baseline: bool | None = None, val_replicates: int | None = None,
                 test_replicates: int = 8,
                 holdout_case: int | None = None, batch_size: int = 64, seed: int = 0,
                 generate: dict | None = None, jobs: int = 2, table: str | None = None,
                 columns: dict[str, str] | None = None, group: str | None = None,
                 gearboxes: int = 256, units: dict[str, str] | None = None,
                 group_by: str | None = None, test_groups: list | None = None,
                 val_groups: list | None = None, cv: str | None = None) -> None:
        super().__init__()
        self.dataset = str(dataset)
        self.cases = settings.cases_of(case)
        if table is None and holdout_case is not None and int(holdout_case) not in self.cases:
            raise ValueError(f"data.holdout_case = {holdout_case} must be one of the cases "
                             f"{self.cases}")
        # the main job reads against each gearbox's first record; a user's table absolutely
        # unless it says its first rows are baselines
        baseline = table is None if baseline is None else bool(baseline)
        if inputs is not None and not len(inputs):
            raise ValueError("data.inputs = [] names no input; give the feature columns "
                             "(data.inputs=[fme15,acc_rms]) or leave data.inputs unset (null) "
                             "for the default inputs of data.sensors")
        self.inputs = (list(inputs) if inputs is not None else
                       input_columns(list(sensors), operating_point, baseline))
        twice = repeated(self.inputs)
        if twice:
            raise ValueError(f"data.inputs = {self.inputs} names {twice} more than once: each "
                             "input is one column of the network; name each column once")
        self.target = target or ("mean_wear_mm" if baseline else "root_wear_mm")
        if self.target in self.inputs:
            raise ValueError(f"data.target = {self.target!r} is also among data.inputs: a model "
                             "given its own answer learns nothing; remove it from data.inputs")
        # the features, not the operating point, are read against the baseline record
        self.baseline = tuple(c for c in self.inputs if c not in CONDITIONS) if baseline else ()
        self.vectors: tuple[str, ...] = ()  # the complex-line inputs, found among the columns
        self.val_replicates = None if val_replicates is None else int(val_replicates)
        self.test_replicates = int(test_replicates)
        self.holdout_case = None if holdout_case is None else int(holdout_case)
        self.batch_size, self.seed = int(batch_size), int(seed)
        self.jobs = int(jobs)
        for name, v, lo in (("batch_size", self.batch_size, 1), ("jobs", self.jobs, 1),
                            ("val_replicates", self.val_replicates, 1),
                            ("test_replicates", self.test_replicates, 0),
                            ("gearboxes", int(gearboxes), 1)):
            if v is not None and v < lo:
                raise ValueError(f"data.{name} = {v} must be >= {lo}")
        # a dataset built here holds the trained cases only (the main job stays short)
        per_case = replicates_per_case(int(gearboxes), len(self.cases))
        if int(gearboxes) < MIN_REPLICATES and "replicates" not in (generate or {}):
            log.warning("data.gearboxes = %d: a dataset built here simulates at least %d "
                        "gearboxes per trained case (fewer scatter a network's error on new "
                        "gearboxes over seeds), %d in all for %d case(s); "
                        "+data.generate.replicates=N sets the count per case itself",
                        int(gearboxes), MIN_REPLICATES, per_case * len(self.cases),
                        len(self.cases))
        spec = {"cases": self.cases, "replicates": per_case, **dict(generate or {})}
        if "chunks" not in spec:  # a user's count wins; the spec's checks come first
            work = spec_from_config(spec | {"chunks": 1}).units
            spec["chunks"] = min(BUILD_CHUNKS, work)
        self.generate = spec
        self.table = None
        self.labels: pd.DataFrame | None = None  # a user table's columns besides the network's
        self.source = self.dataset if table is None else str(table)  # named in errors
        self.units = dataset_units()
        self.group = self.group_by = None
        #: the columns that state the rows' operating point without being inputs
        #: (:func:`~surrogate.inputs.operating_columns`), whose training range the model keeps
        self.operating: list[str] = []
        self.test_codes = self.val_codes = None
        self.cv, self.fold_label = cv, None
        self.folds: list[int] = []
        if cv not in (None, "logo"):
            raise ValueError(f"data.cv = {cv!r} must be logo (leave one group out: one fold per "
                             "value of data.group_by) or null")
        if table is not None:  # a user's own data: read and checked now, before any work
            self._read_table(table, dict(columns or {}), group, group_by, units, test_groups,
                             val_groups, holdout_case)
        else:
            given = [f"data.{k}" for k, v in (("group_by", group_by), ("test_groups", test_groups),
                                              ("val_groups", val_groups), ("cv", cv),
                                              ("units", units)) if v]
            if given:
                raise ValueError(f"{', '.join(given)} apply to a table of your own "
                                 "(data.table=...); the physics dataset is split by "
                                 "data.test_replicates, data.val_replicates and "
                                 "data.holdout_case")
            if not Path(self.dataset).is_file():  # checks the build: its settings, its files
                check_not_users(dataset_job(self.dataset, self.generate, self.jobs),
                                BUILD_FOLDER)
            self.check_dataset_columns_and_split()
        self.schema: FeatureSchema | None = None
        self.frames: dict[str, pd.DataFrame] = {}

    def check_dataset_columns_and_split(self) -> None:
        """Before any work on the physics dataset: the inputs and the target are its columns,
        and each case has the trajectories the split asks for. Read from the file's header and
        its case and replicate columns or, for a dataset still to be built, from the columns
        and replicates the build will give."""
        if Path(self.dataset).is_file():
            import pyarrow.parquet as pq

            try:
                columns = pq.read_schema(self.dataset).names
                keys = pd.read_parquet(self.dataset, columns=["case", "replicate"])
            except Exception as err:  # any unreadable file: one line
                raise ValueError(f"data.dataset = {self.dataset} is not a readable dataset "
                                 f"({type(err).__name__}: {err}); delete it to build it "
                                 "again") from None
            counts = keys.groupby("case").replicate.nunique().to_dict()
        else:
            columns = list(dataset_units())
            counts = dict.fromkeys(self.cases, int(self.generate["replicates"]))
        # the dataset's line inputs, also where a file of an older layout lacks their parts
        self.set_vectors([*columns, *dataset_units()])
        self.units = with_vector_units(dataset_units(), self.vectors)
        missing = [c for c in [*self.sources, self.target] if c not in columns]
        if missing and set(missing) <= set(dataset_units()):  # a file of an older layout
            raise ValueError(f"data.inputs/data.target: columns {missing} are not in "
                             f"{self.source}, built by an older version of the dataset "
                             "API that did not write them; delete it to build it again")
        if missing:
            raise ValueError(f"data.inputs/data.target: columns {missing} are not in "
                             f"{self.source}; choose from {sorted(columns)}")
        for case in self.cases:
            if case in counts and case != self.holdout_case:
                check_split(case, counts[case], self.val_replicates, self.test_replicates,
                            self.holdout_case)

    def _read_table(self, table: str, columns: dict[str, str], group: str | None,
                    group_by: str | None, units: dict | None, test_groups: list | None,
                    val_groups: list | None, holdout_case: int | None) -> None:
        """Read, check and plan the split of a user's table (``data.table``): every refusal
        before any work."""
        if holdout_case is not None:
            raise ValueError("data.holdout_case applies to the physics dataset; in a table of "
                             "your own name the test groups by value: data.group_by=COLUMN "
                             "data.test_groups=[...]")
        raw = read_user_table(table, columns)
        # the dataset's line inputs too, so that a table without their parts is told to add them
        self.set_vectors([*raw.columns, *dataset_units()])
        needed = [*self.sources, self.target]
        check_columns(raw, table, needed, group, group_by)
        self.units = with_vector_units(table_units(table, columns, units, needed), self.vectors)
        self.group, self.group_by = group, group_by or group
        self.operating = operating_columns(raw, self.units, self.inputs, [self.target])
        unchecked = [c for c in stating_operating(raw, self.units, self.inputs, [self.target])
                     if c not in self.operating]
        if unchecked:
            log.warning("column(s) %s of %s state the operating point but are not a number in "
                        "every row: the model cannot check a reading's operating point against "
                        "them (give the speed or torque as numbers)", unchecked, table)
        self.table = user_rows(raw, table, group, needed, self.target, self.units, group_by,
                               tuple(vector_columns(self.vectors)), tuple(self.operating))
        self.cases = [0]
        self.labels = raw[[c for c in raw.columns if c not in needed]]
        if self.baseline:  # before the split: its refusal names the rule, not the counts
            self.check_baselines(self.table)
        by = self.group_by
        uniques = pd.Index(pd.factorize(raw[by], sort=True)[1])
        self.group_values = [u.item() if isinstance(u, np.generic) else u for u in uniques]
        self.test_codes = match_groups(test_groups, uniques, "data.test_groups", by,
                                       self.source) or None
        self.val_codes = match_groups(val_groups, uniques, "data.val_groups", by,
                                      self.source) or None
        both = sorted(set(self.test_codes or []) & set(self.val_codes or []))
        if both:
            raise ValueError(f"data.test_groups and data.val_groups both name {by} = "
                             f"{[self.group_values[k] for k in both]}; a group tests or "
                             "validates, not both")
        if self.cv:
            if self.test_codes:
                raise ValueError("data.cv=logo tests on every group in turn; leave "
                                 "data.test_groups empty (data.val_groups stay fixed)")
            self.folds = [k for k in range(len(uniques)) if k not in (self.val_codes or [])]
            if len(self.folds) < 2:
                raise ValueError(f"data.cv=logo needs two or more values of {by!r} to leave "
                                 f"out in turn; {self.source} has {self.group_values}"
                                 + (" besides data.val_groups" if self.val_codes else ""))
            for k in self.folds:  # every fold's split refused now, not after some trained
                self.fold(k).split()
        else:
            self.split()

    def describe(self, n: int) -> str:
        """A user table's ``n`` trajectories in its own terms (for messages)."""
        if self.group_by == self.group:
            return f"{self.source} has {n} groups of {self.group!r}"
        return f"{self.source} has {n} trajectories (pairs of {self.group_by!r} and {self.group!r})"

    def split(self) -> dict[str, pd.DataFrame]:
        """The train/val/test rows of a user's table (:func:`split_table`)."""
        return split_table(self.table, self.test_codes, self.val_codes, self.val_replicates,
                           self.test_replicates, self.seed, self.describe)

    def fold(self, k: int) -> WearData:
        """The data module of fold ``k`` of ``data.cv=logo``: the table's rows of the
        ``k``-th value of ``data.group_by`` (sorted) test, the rest train and validate."""
        dm = copy.copy(self)
        dm.test_codes, dm.cv, dm.folds = [k], None, []
        dm.fold_label = self.group_values[k]
        dm.schema, dm.frames = None, {}
        return dm

    @property
    def calibration_apart(self) -> bool:
        """Whether the interval is calibrated on validation trajectories that chose nothing
        (:func:`calibration_split`), not on those that also chose the epoch."""
        return self.frames["cal"] is not self.frames["val"]

    def split_summary(self) -> str:
        """Rows and trajectories of each part of the split, in the table's terms (``cal``: the
        validation trajectories that calibrate the interval, where they are apart)."""
        parts = {k: f for k, f in self.frames.items() if k != "cal" or self.calibration_apart}
        if self.table is None:
            return ", ".join(f"{k} {len(f)} rows ({f.groupby(['case', 'replicate']).ngroups} "
                             "trajectories)" for k, f in parts.items())
        by = self.group_by

        def values(f: pd.DataFrame) -> str:
            codes = np.sort(f.split_group.unique())
            shown = [self.group_values[c] for c in codes[:8]]
            return f"{by} {shown}{' ...' if len(codes) > 8 else ''}"

        return ", ".join(f"{k} {len(f)} rows ({values(f)})" for k, f in parts.items())

    def setup(self, stage: str | None = None) -> None:
        """Read (building it if missing) and split the data, once: Lightning calls this at
        every stage, and a single process needs no separate ``prepare_data``."""
        if self.schema is not None:
            return
        parts = self.split() if self.table is not None else self.split_dataset()
        self.frames = calibration_split(parts, self.seed)
        if self.table is None:  # the dataset's operating point, where it is not an input
            self.operating = [c for c in CONDITIONS if c not in self.inputs]
        self.schema = FeatureSchema.fit(self.network_rows("train"), self.inputs, self.units,
                                        self.target, self.baseline, self.vectors,
                                        tuple(self.operating))

    def split_dataset(self) -> dict[str, pd.DataFrame]:
        """The train/val/test rows of the physics dataset (built if missing) of the trained
        cases (:func:`split_trajectories`), its columns and baselines checked."""
        df = load_dataset(self.dataset, self.generate, self.jobs)
        unknown = sorted(set(self.cases) - set(df.case.unique().tolist()))
        if unknown:
            raise ValueError(f"cases {unknown} are not in {self.dataset} (it holds "
                             f"{sorted(df.case.unique().tolist())}); regenerate it with them")
        missing = [c for c in [*self.sources, self.target] if c not in df.columns]
        if missing:
            raise ValueError(f"columns {missing} are not in {self.dataset}; choose from "
                             f"{list(df.columns)}")
        df = df[df.case.isin(self.cases)]
        if self.baseline:
            self.check_baselines(df)
        return split_trajectories(df, self.val_replicates, self.test_replicates, self.seed,
                                  self.holdout_case)

    def check_baselines(self, df: pd.DataFrame) -> None:
        """Each trajectory's first row must be its baseline record, its least worn (the
        unworn one in the physics dataset); raise naming the first that is not."""
        keys = ["case", "replicate"]
        wear = df[self.target].to_numpy(float)
        least = df.groupby(keys, sort=False)[self.target].transform("min").to_numpy(float)
        bad = first_rows(df, keys) & (wear > least)
        if bad.any():
            r = int(np.argmax(bad))
            raise ValueError(
                f"{self.source}: trajectory {self.trajectory(df, r)} starts at "
                f"{self.target} = {wear[r]:.4g}, above its least ({least[r]:.4g}); "
                "data.baseline reads each trajectory against its first row, so that must be "
                "its baseline record (unworn, or its least worn): put it first")
        from surrogate.inference import check_gearboxes  # single rows, rows out of time order

        if self.labels is None:
            check_gearboxes(df, keys, None, f"{self.source} (a gearbox is a trajectory)")
            return
        ids = list(dict.fromkeys([self.group_by, self.group]))
        named = self.labels[ids].iloc[df.row.to_numpy()].reset_index(drop=True)
        cycles = df[["cycles"]].reset_index(drop=True) if df.cycles.notna().any() else None
        check_gearboxes(pd.concat([named, cycles], axis=1) if cycles is not None else named,
                        ids, None, f"{self.source} (a gearbox is a trajectory)")

    def trajectory(self, df: pd.DataFrame, r: int) -> dict:
        """The trajectory of row ``r`` of ``df`` (rows of this module), in the table's own
        columns where it is a user's table."""
        if self.labels is None:
            return df[["case", "replicate"]].iloc[[r]].to_dict("records")[0]
        ids = list(dict.fromkeys([self.group_by, self.group]))
        row = self.labels[ids].iloc[int(df.row.iloc[r])]
        return {k: v.item() if isinstance(v, np.generic) else v for k, v in row.items()}

    def set_vectors(self, columns: list[str]) -> None:
        """Find the complex-line inputs among ``columns`` (:func:`vector_inputs`)."""
        self.vectors = vector_inputs(self.inputs, columns)

    @property
    def sources(self) -> list[str]:
        """The columns the inputs are read from (a line input from its two parts)."""
        return source_columns(self.inputs, self.vectors)

    def network_rows(self, split: str) -> pd.DataFrame:
        """The rows of ``split`` as the network reads them: line inputs as magnitudes
        (:func:`~surrogate.schema.vector_magnitudes`) and, with ``baseline``, the features as
        changes since each trajectory's first row (:func:`~surrogate.schema.baseline_changes`;
        a line's as its vector change)."""
        return network_frame(self.frames[split], self.inputs, self.baseline, self.vectors,
                             ["case", "replicate"])


def check_data(node: DictConfig) -> WearData | None:
    """The data settings ``node`` (a run's ``cfg.data``, as a fine-tune reads it) made into
    :class:`WearData` as the run's data module will be made of them, without torch or
    Lightning: every refusal of a data setting (``ValueError``, ``data: ...``) comes before the
    slow imports. None where ``node`` names a data module other than this project's."""
    if node.get("_target_") != settings.DataConfig._target_:
        return None
    return settings.instantiated(node, "data", _target_=f"{__name__}.WearData")
