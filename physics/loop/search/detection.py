"""Detection limits: for the bundle at hand, the smallest size of each library effect that the
loop's rule would name (:func:`detection_limits`).

A candidate that is not named is not shown to be absent: it may be there below what these
records can show. Its detection limit is found by injection (the recovery test of signal
detection): the effect at size ``s`` is added to the calibrated declared model, and the change
it makes to each record's signature [dB] is added to the *measured* signature of that record,
so the records keep their own noise and the declared model's own discrepancy. The null test
(:func:`physics.loop.judge.adoption.null_test`, with the bundle's discrepancy, its allowance for the
round's number of candidates and the same BIC and gain bounds) then judges the candidate at
the injected values against the calibrated model. A size is *named* where every condition
holds.

The size is the effect's first parameter (the transfer path's residue, the sensor's gain
departure from 1), moved from its neutral value towards its typical size by factors of 2: the
typical size first, then down by factors of 4 while named (to a 64th) or up by factors of 2
while not (to 4 times; within the parameter's bounds), and two bisections (in the log) between
the largest size not named and the smallest named; the others at their typical values (the
option: the candidate's). Cost: at most six simulations of the records per candidate, no
fit.

What it is: the limit for a fit that finds the injected values; a fit from the loop's search
starts elsewhere and may stop short (a higher limit), or absorb some noise and discrepancy as
well (a slightly lower one). It holds for the other parameters at their typical values (a
transfer path's mode at another frequency, a pit of another width have other limits) and for
the records at hand (their noise, their number, the model's discrepancy on them).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from physics.loop.effects import Effect
from physics.loop.judge.adoption import holds, null_test
from physics.loop.measured.records import Records
from physics.loop.model.comparison import residuals, residuals_db
from physics.loop.model.discrepancy import discrepancy_allowance
from physics.loop.model.simulation import model_signals
from physics.loop.search.attribution import bic, signature_gain
from physics.loop.threads import each

#: the parameter that sizes each effect, where it is not its first
SIZE = {"transfer_path": "residue"}
#: a size parameter's value without the effect, where it is not 0
NEUTRAL = {"gain": 1.0}
#: the ladder: the typical size times 2^k, k = 0 first, then down by factors of 4 while named
#: (to 2^-6, a 64th) or up by factors of 2 while not (to 4 times), within the bounds; then
#: BISECTIONS halvings (in the log) of the bracket
LADDER_DOWN = (-2, -4, -6)
LADDER_UP = (1, 2)
BISECTIONS = 2


def size_param(eff: Effect):
    """The parameter that sizes ``eff`` (:data:`SIZE`, else its first)."""
    name = SIZE.get(eff.name, eff.params[0].name)
    return next(p for p in eff.params if p.name == name)


def _injected(rec: Records, idx: np.ndarray, base: list[np.ndarray], with_eff: list[np.ndarray]
              ) -> list[np.ndarray]:
    """The measured signatures of records ``idx`` plus the change [dB] the effect makes to the
    model's (its signals ``with_eff`` against ``base``)."""
    before, after = residuals_db(rec, idx, base), residuals_db(rec, idx, with_eff)
    measured = list(rec.measured)
    for k, i in enumerate(idx):
        measured[i] = rec.measured[i] + (before[k] - after[k])
    return measured


def judged_at(rec: Records, judged: Records, nuisance: dict, eff: Effect, values: dict,
              base_train: list[np.ndarray], base_test: list[np.ndarray], n_candidates: int
              ) -> dict:
    """The null test's conditions on ``eff`` at ``values`` injected into the records (see the
    module text), the candidate taken at the injected values."""
    s = rec.settings
    train = model_signals(rec, rec.train, nuisance, eff, values)
    test = model_signals(rec, rec.test, nuisance, eff, values)
    measured = _injected(rec, rec.train, base_train, train)
    measured = _injected(dataclasses.replace(rec, measured=measured), rec.test, base_test, test)
    fit, judge = (dataclasses.replace(r, measured=measured) for r in (rec, judged))
    null = residuals(fit, rec.train, base_train)
    chi2 = float(np.sum(residuals(fit, rec.train, train) ** 2))
    k = len(eff.params)
    delta_bic = bic(chi2, null.size, k) - bic(float(np.sum(null**2)), null.size, 0)
    explained, own_before, own_after, whole = signature_gain(judge, rec.test, base_test, test,
                                                             eff.judged_in())
    allowed = discrepancy_allowance(k, n_candidates, s.false_add_rate)
    if not explained:  # the effect moves none of its entries by their noise: not seen
        return {"seen": {"value": 0.0, "bound": 1.0, "holds": False}}
    return null_test(own_after, own_before, delta_bic, s.min_gain, s.min_delta_bic,
                     min(explained.values()), allowed, whole)


def detection_limit(rec: Records, judged: Records, nuisance: dict, eff: Effect, option: dict,
                    base_train: list[np.ndarray], base_test: list[np.ndarray],
                    n_candidates: int) -> dict:
    """The smallest size of ``eff`` (with ``option``) that the rule would name on these records
    (the module text): ``limit`` (None if none up to the ladder's top is named),
    ``not_named_at`` (the largest size tried that is not; None if the smallest is named), the
    parameter, its unit, its typical size and the sizes tried."""
    p = size_param(eff)
    neutral = NEUTRAL.get(p.name, 0.0)

    def value(k: float) -> float:
        return float(np.clip(neutral + (p.typical - neutral) * 2.0**k, p.low, p.high))

    cache: dict[float, bool] = {}

    def named(k: float) -> bool:
        if k not in cache:
            values = eff.defaults() | dict(option) | {p.name: value(k)}
            cache[k] = holds(judged_at(rec, judged, nuisance, eff, values, base_train,
                                       base_test, n_candidates))
        return cache[k]

    k_named = k_not = None
    if named(0):
        k_named = 0
        for k in LADDER_DOWN:
            if not named(k):
                k_not = k
                break
            k_named = k
    else:
        k_not = 0
        for k in LADDER_UP:
            if named(k):
                k_named = k
                break
            k_not = k
    for _ in range(BISECTIONS if k_named is not None and k_not is not None else 0):
        mid = 0.5 * (k_named + k_not)  # bisection in the log
        if value(mid) in (value(k_named), value(k_not)):
            break
        if named(mid):
            k_named = mid
        else:
            k_not = mid
    return {"parameter": p.name, "unit": p.unit, "typical": p.typical,
            "limit": value(k_named) if k_named is not None else None,
            "not_named_at": value(k_not) if k_not is not None else None,
            "sizes_tried": len(cache)}


def detection_limits(rec: Records, judged: Records, nuisance: dict,
                     candidates: list[tuple[Effect, dict]], base_train: list[np.ndarray],
                     base_test: list[np.ndarray]) -> list[dict]:
    """:func:`detection_limit` of every candidate (effect, option) of the first round, in its
    order, each with its ``effect`` and ``option``."""
    return each(lambda c: {"effect": c[0].name, "option": dict(c[1]),
                           **detection_limit(rec, judged, nuisance, *c, base_train, base_test,
                                             len(candidates))},
                candidates, "detection limits")

