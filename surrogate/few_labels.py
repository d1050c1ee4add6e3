"""Wear read from a few labelled stages of one rig, with and without the physics as a prior.

A user who has measured a rig's housing acceleration over its life but labelled only a few
stages (an inspection now and then) reads the others from the RMS over the healthy stage's,
``r``, by one of three readers, each calibrated on the healthy stage and the labelled ones:

- **physics**: the project's model of the user's pair (``python -m physics.reproduce.rig``:
  the contact-driven wear of the rig's geometry and its housing acceleration, one curve
  ``g_T(w)`` of RMS over new per torque ``T`` of the swept range, the rig's load being
  unknown) calibrated as ``log r = a + log g_T(w)``: the torque ``T`` of the curve and the level
  ``a`` of least squares over the labelled stages (the calibration of the physics model's
  scale, two numbers). The curve is read through its monotone envelope (scikit-learn's
  ``IsotonicRegression`` of ``log g_T`` over wear: a reading needs one wear per level), the
  wear of a record the envelope's inverse at ``log r - a``, clipped to the curve's range;
- **exponential** (the same calibration without physics): ``log r = a + b w``, level and rate
  of least squares, the exponential degradation model of a vibration feature (Gebraeel,
  Lawley, Li & Ryan, IIE Trans. 37 (2005) 543), inverted; a rate that is not positive reads no
  wear;
- **line**: wear a straight line of ``r`` through the labelled stages (least squares).

:func:`few_label_study` draws ``labelled`` worn stages with a seed, ``draws`` times, and scores
each reader on the records of every other worn stage: the mean over the stages of each stage's
mean relative error, as the real rig's benchmark scores (docs/benchmark.md, Few labels).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.isotonic import IsotonicRegression

#: the columns of the rig's record table the study reads
RECORD_COLUMNS = ("stage", "wear_mm", "acc_rms_g")
#: how far the curves' deepest stage may lie from the records' [factor]: the same rig's stages
#: in the same unit (a table in um, or of a few stages, lies far outside)
REACH_FACTOR = 1.5


def check_comparison(comparison: pd.DataFrame, records: pd.DataFrame, where: str) -> None:
    """Refuse (ValueError, one line starting with ``where``) model curves that cannot be the
    rig's: a wear column that is not finite, non-negative and non-decreasing down the stages
    (as ``python -m physics.reproduce.rig`` writes it), a deepest stage more than
    :data:`REACH_FACTOR` times off the records' (another unit, a part of the stages) or a
    curve value that is not a finite positive ratio."""
    wear = pd.to_numeric(comparison.wear_mm, errors="coerce").to_numpy(float)
    if not (np.isfinite(wear).all() and (wear >= 0).all() and (np.diff(wear) >= 0).all()):
        raise ValueError(f"{where}: wear_mm must be finite, >= 0 and non-decreasing down the "
                         "stages, one row per stage as python -m physics.reproduce.rig "
                         "writes it")
    deepest, measured = float(wear.max(initial=0.0)), float(records.wear_mm.max())
    if not measured / REACH_FACTOR <= deepest <= measured * REACH_FACTOR:
        raise ValueError(f"{where}: its deepest stage is {deepest:g} mm and the records' "
                         f"{measured:g} mm: the curves must cover the same rig's stages in mm "
                         "(within a factor 1.5); give the rig_comparison.csv of those records")
    for c in map(str, comparison.columns):
        if c.startswith("rms_") and c.endswith("Nm"):
            g = pd.to_numeric(comparison[c], errors="coerce").to_numpy(float)
            if not (np.isfinite(g).all() and (g > 0).all()):
                raise ValueError(f"{where}: column {c} must hold finite positive ratios of "
                                 "RMS over new; one is not")


def physics_curves(comparison: pd.DataFrame, contact: str = "model") -> dict[float, np.ndarray]:
    """The model's RMS-over-new curves of ``comparison`` (``rig_comparison.csv`` of ``python -m
    physics.reproduce.rig``: one row per stage, ``wear_mm`` and ``rms_<contact>_<T>Nm`` columns,
    ``model`` the exact tooth contact, ``path`` the contact on the theoretical path) by torque
    [N m], each on the stages' wear."""
    prefix = f"rms_{contact}_"
    curves = {float(c[len(prefix):-2]): comparison[c].to_numpy(float)
              for c in comparison.columns if c.startswith(prefix) and c.endswith("Nm")}
    if not curves:
        raise ValueError(f"the rig comparison has no column {prefix}<torque>Nm; give the "
                         "rig_comparison.csv of python -m physics.reproduce.rig")
    return curves


def monotone_envelopes(wear_mm: np.ndarray, curves: dict[float, np.ndarray]
                       ) -> tuple[np.ndarray, dict[float, np.ndarray]]:
    """The wear sorted and each curve's monotone envelope of its logarithm over it (module
    text): made once, read by every :class:`PhysicsReader`."""
    order = np.argsort(wear_mm)
    wear = np.asarray(wear_mm, float)[order]
    return wear, {t: IsotonicRegression(increasing=True).fit(
        wear, np.log(np.asarray(g, float)[order])).predict(wear) for t, g in curves.items()}


class PhysicsReader:
    """The model's curve calibrated on labelled stages (module text), from the curves'
    envelopes over the sorted ``wear`` (:func:`monotone_envelopes`)."""

    def __init__(self, wear: np.ndarray, envelopes: dict[float, np.ndarray],
                 labelled_mm: np.ndarray, labelled_ratio: np.ndarray) -> None:
        self.wear = wear
        best = None
        for torque, env in envelopes.items():
            at = np.interp(labelled_mm, wear, env)
            level = float(np.mean(np.log(labelled_ratio) - at))
            cost = float(np.sum((np.log(labelled_ratio) - level - at) ** 2))
            if best is None or cost < best[0]:
                best = (cost, torque, level, env)
        _, self.torque, self.level, self.envelope = best

    def read(self, ratio: np.ndarray) -> np.ndarray:
        """Wear [mm] of RMS ratios ``ratio``: the envelope's inverse (its first wear of each
        level), clipped to the curve's wear range."""
        levels, first = np.unique(self.envelope, return_index=True)
        return np.interp(np.log(np.asarray(ratio, float)) - self.level, levels,
                         self.wear[first])


def exponential_read(labelled_mm: np.ndarray, labelled_ratio: np.ndarray,
                     ratio: np.ndarray) -> np.ndarray:
    """Wear [mm] of ``ratio`` by ``log r = a + b w`` fitted on the labelled stages (module
    text); zero where the fitted rate is not positive."""
    b, a = np.polyfit(labelled_mm, np.log(labelled_ratio), 1)
    if b <= 0:
        return np.zeros(len(np.atleast_1d(ratio)))
    return np.maximum((np.log(np.asarray(ratio, float)) - a) / b, 0.0)


def line_read(labelled_mm: np.ndarray, labelled_ratio: np.ndarray,
              ratio: np.ndarray) -> np.ndarray:
    """Wear [mm] of ``ratio`` by a straight line of the ratio through the labelled stages."""
    slope, intercept = np.polyfit(labelled_ratio, labelled_mm, 1)
    return np.maximum(slope * np.asarray(ratio, float) + intercept, 0.0)


def stage_error(read: np.ndarray, true: np.ndarray, stage: np.ndarray) -> float:
    """The mean over the stages of each stage's mean relative error [%]."""
    rel = pd.Series(np.abs(read - true) / true)
    return float(rel.groupby(np.asarray(stage)).mean().mean() * 100)


#: the physics readers of the study, by the contact of the model's curves they calibrate
#: (rig_comparison.csv's ``model``: the exact tooth contact; ``path``: on the theoretical path,
#: the dynamics' default ``flank_contact``)
CONTACTS = {"physics_exact": "model", "physics_path": "path"}


def few_label_study(records: pd.DataFrame, comparison: pd.DataFrame, labelled: int = 3,
                    draws: int = 200, seed: int = 0) -> pd.DataFrame:
    """One row per draw of ``labelled`` worn stages of the rig's ``records`` (``stage``,
    ``wear_mm``, ``acc_rms_g``; the healthy stage, ``wear_mm`` 0, labelled always): the
    stages drawn, each physics reader's torque (``<reader>_torque_Nm``, :data:`CONTACTS`),
    and each reader's error over the other worn stages' records (``<reader>_mre_pct``: the
    physics readers, ``exponential`` and ``line``; module text)."""
    if labelled < 2:
        raise ValueError(f"labelled = {labelled}: the readers fit two numbers; give at least 2 "
                         "labelled worn stages (the healthy one is labelled besides)")
    if not (records.wear_mm == 0).any():
        raise ValueError(f"the rig's records hold no healthy stage (wear_mm 0) among their "
                         f"{len(records)} rows: every reading is over the healthy stage's RMS; "
                         "give the rig's whole record table")
    healthy = records.loc[records.wear_mm == 0, "acc_rms_g"].mean()
    worn = records[records.wear_mm > 0]
    means = worn.groupby("stage", sort=False).agg(wear_mm=("wear_mm", "first"),
                                                  rms=("acc_rms_g", "mean"))
    if len(means) <= labelled:
        raise ValueError(f"labelled = {labelled}: the rig has {len(means)} worn stages; "
                         "label fewer, so that some are read")
    wear = comparison.wear_mm.to_numpy(float)
    models = {name: monotone_envelopes(wear, physics_curves(comparison, contact))
              for name, contact in CONTACTS.items()}
    rng = np.random.default_rng(seed)
    rows = []
    for k in range(draws):
        chosen = means.iloc[np.sort(rng.choice(len(means), labelled, replace=False))]
        lab_w = np.r_[0.0, chosen.wear_mm.to_numpy(float)]
        lab_r = np.r_[1.0, chosen.rms.to_numpy(float) / healthy]
        test = worn[~worn.stage.isin(chosen.index)]
        ratio, true = test.acc_rms_g.to_numpy(float) / healthy, test.wear_mm.to_numpy(float)
        row = {"draw": k, "stages": " ".join(chosen.index)}
        for name, (grid, envelopes) in models.items():
            reader = PhysicsReader(grid, envelopes, lab_w[1:], lab_r[1:])
            row[f"{name}_torque_Nm"] = reader.torque
            row[f"{name}_mre_pct"] = stage_error(reader.read(ratio), true, test.stage)
        for name, read in (("exponential", exponential_read), ("line", line_read)):
            row[f"{name}_mre_pct"] = stage_error(read(lab_w, lab_r, ratio), true, test.stage)
        rows.append(row)
    return pd.DataFrame(rows)


def summary(study: pd.DataFrame) -> pd.DataFrame:
    """One row per reader of :func:`few_label_study`: the mean and median over the draws of
    its error, and the share of the draws it reads best."""
    names = [*CONTACTS, "exponential", "line"]
    errors = study[[f"{r}_mre_pct" for r in names]].to_numpy()
    best = np.argmin(errors, axis=1)
    return pd.DataFrame({"reader": names, "mean_mre_pct": errors.mean(axis=0),
                         "median_mre_pct": np.median(errors, axis=0),
                         "best_share": [float(np.mean(best == i)) for i in range(len(names))],
                         "draws": len(study)})
