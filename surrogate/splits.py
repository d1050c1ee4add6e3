"""The splits of the rows into training, validation and test, always by whole trajectory.

Rows are split by *trajectory* (one replicate of one case, all its wear states), never by rows
of one trajectory: neighbouring wear states are nearly the same sample. Per case, a seeded
permutation of the replicates gives ``test_replicates`` for the test set, ``val_replicates`` for
validation (by default :func:`validation_count`) and the rest for training; ``holdout_case``
instead puts a whole case in the test set (leave-one-case-out): :func:`split_trajectories`. A
user's table is split the same way by its own groups, or by groups named by value
(:func:`split_table`, :func:`match_groups`). Of 16 or more validation trajectories, half
choose the epoch kept and the other half calibrate the interval (:func:`calibration_split`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: the fewest validation trajectories per case: they choose the epoch and calibrate the
#: interval
MIN_VALIDATION = 8
#: validation trajectories (all cases together) from which on half of each case's calibrate the
#: interval apart from those that choose the epoch (:func:`calibration_split`)
MIN_APART = 2 * MIN_VALIDATION


def validation_count(trajectories: int) -> int:
    """Validation trajectories of a case with ``trajectories``: a sixth, at least
    :data:`MIN_VALIDATION`. The conformal interval's quantile is read from half of them
    (:func:`calibration_split`): the fewer, the more its coverage scatters over seeds, and
    below 19 calibrating gearboxes no quantile reaches the 95 % level (the largest score is
    taken; :func:`surrogate.conformal.attainable`). A sixth of the main job's 256 gives 43: 21
    calibrate."""
    return max(MIN_VALIDATION, round(trajectories / 6))


def check_split(case: int, trajectories: int, val_replicates: int | None,
                test_replicates: int, holdout_case: int | None) -> tuple[int, int]:
    """The (test, validation) trajectory counts of ``case``; ValueError when it has too few
    trajectories for them and one to train on."""
    n_test = 0 if holdout_case is not None else test_replicates
    n_val = validation_count(trajectories) if val_replicates is None else val_replicates
    if trajectories < n_test + n_val + 1:
        raise ValueError(
            f"case {case} has {trajectories} trajectories; a split with {n_val} "
            f"validation and {n_test} test trajectories needs at least "
            f"{n_test + n_val + 1}: lower data.val_replicates and "
            "data.test_replicates, or add trajectories (data.generate.replicates)")
    return n_test, n_val


def match_groups(values, uniques: pd.Index, option: str, column: str, source) -> list[int]:
    """The indices in ``uniques`` (a column's sorted distinct values) of the user's ``values``
    (``data.test_groups``, ``data.val_groups``): numbers matched as numbers (45 is 45.0),
    others as text. Raises naming a value the column does not have."""
    codes = []
    numeric = pd.api.types.is_numeric_dtype(uniques.dtype)
    for v in list(values or []):
        if numeric:
            try:
                hit = np.flatnonzero(np.isclose(uniques.to_numpy(float), float(v),
                                                rtol=1e-12, atol=0))
            except (TypeError, ValueError):
                hit = np.array([], int)
        else:
            hit = np.flatnonzero(uniques.astype(str) == str(v))
        if hit.size == 0:
            shown = [u.item() if isinstance(u, np.generic) else u for u in uniques[:20]]
            raise ValueError(f"{option} = {list(values)}: column {column!r} of {source} has no "
                             f"value {v!r}; its values: {shown}"
                             + (" ..." if len(uniques) > 20 else ""))
        codes.append(int(hit[0]))
    return list(dict.fromkeys(codes))


def split_table(rows: pd.DataFrame, test_codes: list[int] | None, val_codes: list[int] | None,
                val_replicates: int | None, test_replicates: int, seed: int,
                describe) -> dict[str, pd.DataFrame]:
    """Train/val/test rows of a user's table (:func:`~surrogate.tables.user_rows`): the rows whose
    ``split_group`` is one of ``test_codes`` (``val_codes``) test (validate); where none are
    named, ``test_replicates`` (``val_replicates``; None: :func:`validation_count`)
    trajectories are drawn from the others with ``seed``, in the order of
    :func:`split_trajectories` (which this is, without named groups). ``describe(n)`` says
    in the user's terms what the table's ``n`` trajectories are, for messages."""
    reps = np.sort(rows.replicate.unique())
    of_rep = rows.groupby("replicate").split_group.first().reindex(reps).to_numpy()
    perm = np.random.default_rng([seed, 0]).permutation(reps)
    test = (reps[np.isin(of_rep, test_codes)] if test_codes else None)
    val = (reps[np.isin(of_rep, val_codes)] if val_codes else None)
    n_test = 0 if test is not None else test_replicates
    n_val = (0 if val is not None else
             validation_count(len(reps)) if val_replicates is None else val_replicates)
    available = len(reps) - sum(len(x) for x in (test, val) if x is not None)
    if available < n_test + n_val + 1:
        named = "".join(f", {len(x)} named by data.{k}_groups" for k, x in
                        (("test", test), ("val", val)) if x is not None)
        raise ValueError(
            f"{describe(len(reps))}{named}; {n_val} more to validate and {n_test} more to test, "
            f"drawn, and one to train need {n_test + n_val + 1} besides the named ones, "
            f"{available} remain: lower data.val_replicates and data.test_replicates, name "
            "the groups by value (data.val_groups, data.test_groups), or split by a finer "
            "column (data.group)")
    if test is None:
        free = perm[~np.isin(perm, val if val is not None else [])]
        test = free[:n_test]
    if val is None:
        free = perm[~np.isin(perm, test)]
        val = free[:n_val]
    parts = {"test": rows[rows.replicate.isin(test)], "val": rows[rows.replicate.isin(val)]}
    parts["train"] = rows[~rows.replicate.isin(np.concatenate([test, val]))]
    return {k: parts[k].reset_index(drop=True) for k in ("train", "val", "test")}


def gearboxes(rows: pd.DataFrame) -> np.ndarray:
    """Each row's gearbox (trajectory: case and replicate) as an integer label."""
    return rows.groupby(["case", "replicate"], sort=False).ngroup().to_numpy()


def calibration_split(frames: dict[str, pd.DataFrame], seed: int) -> dict[str, pd.DataFrame]:
    """``frames`` with its validation trajectories cut in two: ``val``, which choose the epoch
    kept (early stopping, the checkpoint), and ``cal``, which calibrate the interval. A
    split-conformal interval covers its level only on data that chose nothing of the model
    (Angelopoulos & Bates, "A gentle introduction to conformal prediction", 2021, sec. 2.3):
    validation rows that also chose the epoch have smaller errors than a new gearbox's, and
    the interval under-covers (docs/surrogate.md, Where it does not know). Of each case's
    validation trajectories half (rounded down, drawn with ``seed`` in a stream of their own)
    calibrate; with fewer than :data:`MIN_APART` validation trajectories in all, both are the
    same rows."""
    val = frames["val"]
    if len(np.unique(gearboxes(val))) < MIN_APART:
        return {**frames, "cal": val}
    chosen = []
    for case, rows in val.groupby("case", sort=True):
        reps = np.sort(rows.replicate.unique())
        perm = np.random.default_rng([seed, int(case), 1]).permutation(reps)
        chosen.append(rows[rows.replicate.isin(perm[:len(reps) // 2])].index)
    is_cal = val.index.isin(np.concatenate(chosen))
    return {**frames, "val": val[~is_cal].reset_index(drop=True),
            "cal": val[is_cal].reset_index(drop=True)}


def split_trajectories(df: pd.DataFrame, val_replicates: int | None, test_replicates: int,
                       seed: int, holdout_case: int | None = None) -> dict[str, pd.DataFrame]:
    """Train/val/test rows, split by (case, replicate) trajectory; see the module text.
    ``val_replicates`` None: :func:`validation_count` of each case."""
    parts: dict[str, list[pd.DataFrame]] = {"train": [], "val": [], "test": []}
    for case, rows in df.groupby("case", sort=True):
        reps = np.sort(rows.replicate.unique())
        if case == holdout_case:
            parts["test"].append(rows)
            continue
        n_test, n_val = check_split(case, len(reps), val_replicates, test_replicates,
                                    holdout_case)
        perm = np.random.default_rng([seed, int(case)]).permutation(reps)
        groups = {"test": perm[:n_test], "val": perm[n_test:n_test + n_val],
                  "train": perm[n_test + n_val:]}
        for name, chosen in groups.items():
            parts[name].append(rows[rows.replicate.isin(chosen)])
    return {k: pd.concat(v, ignore_index=True) if v else df.iloc[:0] for k, v in parts.items()}
