"""The wear reading: a model-based wear estimate of each record (the wear state whose simulated
signature is nearest, relative to the group's train records of known wear,
:func:`wear_estimates`), its error and skill against the train records' mean wear
(:func:`wear_score`, :func:`wear_skill`), and which model reads the wear once an effect is
adopted (:func:`reads_wear`: the adopted one unless it lowers the estimate's leave-one-out
skill on the train records by more than ``loop.max_wear_loss``, :func:`wear_check`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from physics.loop.effects import Effect
from physics.loop.measured.records import Group, Records, by_group
from physics.loop.model.comparison import residuals_db, rms
from physics.loop.model.simulation import model_signals


def train_wear_residuals(rec: Records, nuisance: dict, eff: Effect | None, values: dict
                         ) -> dict[int, dict[int, np.ndarray]]:
    """The dB residual of each train record of known wear at its own worn model, keyed by
    group index, then by record (bundle index); groups without such records left out."""
    wear = rec.bundle.manifest.wear_mm.to_numpy(float)
    known = np.array([i for i in rec.train if not np.isnan(wear[i])], int)
    if not known.size:
        return {}
    res = residuals_db(rec, known, model_signals(rec, known, nuisance, eff, values))
    return {g: {int(known[j]): res[j] for j in pos} for g, pos in by_group(rec, known).items()}


def reference_moments(group: Group, rows: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Per entry, the mean of the residual ``rows`` [dB] and their spread beyond the group's
    noise [dB^2] (method of moments, ``var - entry_sd^2`` clipped at 0; zero with one row)."""
    r = np.array(rows)
    spread = (np.maximum(r.var(axis=0, ddof=1) - group.entry_sd**2, 0.0) if len(rows) > 1
              else np.zeros(r.shape[1]))
    return r.mean(axis=0), spread


def wear_reference(rec: Records, nuisance: dict, eff: Effect | None, values: dict
                   ) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """What the model misses of each group's records whatever their wear, read from the
    group's train records of known wear at their own worn models
    (:func:`train_wear_residuals`): per entry, their mean residual [dB] and its spread beyond
    the noise [dB^2] (:func:`reference_moments`). Keyed by group index; groups without such
    records left out.

    The residual of a record is read as ``r = mu + delta + eps``: ``mu`` what the model misses
    in every record of the group (its form error there, an undeclared effect), ``delta`` the
    part that changes from record to record, chiefly with wear (where the model's wear
    signature is not the gearbox's), ``eps`` the noise (Kennedy & O'Hagan's discrepancy with a
    mean, J. R. Stat. Soc. B 63 (2001) 425, estimated where the wear is known)."""
    return {g: reference_moments(rec.groups[g], list(rows.values()))
            for g, rows in train_wear_residuals(rec, nuisance, eff, values).items()}


def wear_estimates(rec: Records, idx: np.ndarray, nuisance: dict, eff: Effect | None,
                   values: dict, leave_one_out: bool = False) -> np.ndarray:
    """Model-based wear estimate of each record [mm]: the wear state whose simulated signature
    is nearest, the residuals taken relative to the group's train records of known wear
    (:func:`wear_reference`: their mean residual removed, each entry weighed by the noise and
    the residual's spread between them). A record is so read by how it differs from records
    of its own gearbox, operating point and sensor, with the entries where the model's wear
    signature tracks the gearbox's weighed most: what the model misses in all of them (its
    form error, an undeclared effect) does not move the estimate. ``leave_one_out``: each
    record read against the others (for train records of known wear). Measured on the
    independent simulator's bundles: docs/loop.md."""
    train = train_wear_residuals(rec, nuisance, eff, values)
    out = []
    for i in idx:
        states = rec.wear_states[i]
        if not states:
            out.append(np.nan)
            continue
        wear = np.array([w for w, _ in states])
        sig = model_signals(rec, np.array([i] * len(states)), nuisance, eff, values,
                            models=[m for _, m in states])
        group = rec.group(i)
        rows = [r for j, r in train.get(int(rec.group_of[i]), {}).items()
                if not (leave_one_out and j == i)]
        mean, spread = reference_moments(group, rows) if rows else (0.0, 0.0)
        sd = np.sqrt(group.sd**2 + spread)
        res = residuals_db(rec, np.array([i] * len(states)), sig)
        cost = np.array([rms((r - mean) / sd) for r in res])
        j = int(np.argmin(cost))
        if 0 < j < len(cost) - 1:  # parabolic refinement between grid states
            c0, c1, c2 = cost[j - 1:j + 2]
            d = c0 - 2 * c1 + c2
            shift = 0.5 * (c0 - c2) / d if d > 0 else 0.0
            out.append(float(np.interp(j + np.clip(shift, -1, 1), np.arange(len(wear)), wear)))
        else:
            out.append(float(wear[j]))
    return np.array(out)


class WearScore(NamedTuple):
    """How well the model-based wear estimate (:func:`wear_estimates`) reads the held-out
    records whose wear is known."""

    #: mean relative error over the worn ones [%] (mean absolute error [mm] if none is worn)
    error: float
    #: ``1 - MAE / MAE of the constant guess`` (the train records' mean known wear): <= 0 says
    #: the estimate carries no wear information on these records; None without such a guess
    skill: float | None
    #: the records scored (bundle indices), their known wear and its estimate [mm]
    records: tuple[int, ...] = ()
    true_mm: tuple[float, ...] = ()
    estimate_mm: tuple[float, ...] = ()


def wear_score(rec: Records, nuisance: dict, eff: Effect | None, values: dict,
               on_train: bool = False) -> WearScore | None:
    """Error and skill of the model-based wear estimate over the held-out records whose wear is
    known, or (``on_train``) over the train records whose wear is known, each read against the
    others of its group (leave one out); None if there is no such record."""
    wear = rec.bundle.manifest.wear_mm.to_numpy(float)

    def known(idx: np.ndarray) -> np.ndarray:
        return np.array([i for i in idx if not np.isnan(wear[i]) and rec.wear_states[i]], int)

    test, train = known(rec.test), known(rec.train)
    if on_train:
        test = train if train.size > 1 else np.empty(0, int)
    if not test.size:
        return None
    true = wear[test]
    est = wear_estimates(rec, test, nuisance, eff, values, leave_one_out=on_train)
    ok = true > 0
    error = (float(np.mean(np.abs(est[ok] - true[ok]) / true[ok]) * 100) if ok.any()
             else float(np.mean(np.abs(est - true))))
    return WearScore(error, wear_skill(est, true, wear[train]), tuple(int(i) for i in test),
                     tuple(map(float, true)), tuple(map(float, est)))


def wear_skill(est: np.ndarray, true: np.ndarray, train_wear: np.ndarray) -> float | None:
    """Skill of wear estimates ``est`` of records of wear ``true`` against the constant guess,
    the mean of ``train_wear`` (Murphy 1988's skill score on the mean absolute error): 1 exact,
    <= 0 no better than the guess; None without train wear or if the guess is exact."""
    guess = float(np.mean(np.abs(np.mean(train_wear) - true))) if train_wear.size else 0.0
    return 1 - float(np.mean(np.abs(est - true))) / guess if guess > 0 else None


def wear_check(before: WearScore | None, after: WearScore | None, max_loss: float
               ) -> dict | None:
    """Whether an adopted effect reads the wear (``before``, ``after``: the leave-one-out scores on
    the train records): it may lower the wear estimate's skill by at most ``max_loss``, i.e. raise
    its mean absolute error by at most that share of the constant guess's (the spread of the wear
    it reads), not of its own error, which on a good estimate is finer than the estimate's
    resolution (a rule on the error itself refuses a torque ripple of our own records at 3.9 ->
    5.3 % of error, skill 0.85 -> 0.79). Where the skill is undefined (the guess exact: every
    such record of one wear) the mean relative error may grow by at most ``max_loss`` of its
    value. None without such scores: the adopted effect reads the wear. Both scores carry the
    same guess, so their skills are both defined or both not."""
    if before is None or after is None:
        return None
    if before.skill is not None and after.skill is not None:
        bound = before.skill - max_loss
        return {"measure": "skill", "before": before.skill, "value": after.skill,
                "bound": bound, "holds": after.skill >= bound}
    bound = (1 + max_loss) * before.error
    return {"measure": "error", "before": before.error, "value": after.error, "bound": bound,
            "holds": after.error <= bound}


@dataclass(frozen=True)
class Reader:
    """The model that reads the wear (:func:`wear_estimates`): its nuisance, effect, values."""

    name: str
    nuisance: dict
    effect: Effect | None = None
    values: dict = field(default_factory=dict)


def reads_wear(rec: Records, reader: Reader, adopted: Reader, max_loss: float
               ) -> tuple[Reader, dict | None]:
    """Which model reads the wear once ``adopted`` is adopted over the model ``reader`` that
    read it so far: ``adopted`` unless :func:`wear_check` on the two models' leave-one-out
    scores on the train records of known wear refuses it; the check with
    ``reads_with`` (None without such records: ``adopted`` reads it)."""
    loo = [wear_score(rec, r.nuisance, r.effect, r.values, on_train=True)
           for r in (reader, adopted)]
    check = wear_check(*loo, max_loss)
    if check is None:
        return adopted, None
    chosen = adopted if check["holds"] else reader
    return chosen, check | {"reads_with": chosen.name, "before_model": reader.name,
                            "after_model": adopted.name}
