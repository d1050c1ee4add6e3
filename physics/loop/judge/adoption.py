"""The adoption rule of the measured-data loops: the null test a candidate effect must pass to be
adopted (:func:`null_test`), whether all its conditions hold (:func:`holds`) and which
candidate of a ranked round is judged (:func:`first_passing`). The bundle loop, the feature-table
loop, the attribution and the detection limits decide with it; the report only writes what it
decided (:mod:`physics.loop.report`)."""

from __future__ import annotations

import math


def null_test(heldout: float, null_heldout: float, delta_bic: float, min_gain: float,
              min_delta_bic: float, explained: float | None = None, allowed: float = 0.0,
              whole: float | None = None) -> dict[str, dict]:
    """The conditions of the null test, each with the candidate's value, the bound it must
    pass and whether it does: ``gain``, the held-out error's relative cut, at least
    ``min_gain``; ``delta_bic``, at most ``-min_delta_bic``; and, where the loop measures them,
    ``explained``, more than ``allowed``, and ``whole``, the whole signature's cut in every
    group where the candidate shows, at least one standard error
    (:func:`physics.loop.search.attribution.whole_cut`).

    The bundle loop passes the held-out errors in the candidate's own signature entries (in units of
    the noise), as ``explained`` the smallest over the groups (operating points and quantities; of
    the quantities the candidate can act on) of the sum of squares (standardised by noise and model
    discrepancy) it removes per held-out record there, and as ``allowed`` what the discrepancy lets
    a candidate of its size absorb by chance
    (:func:`physics.loop.bundle_loop.discrepancy_allowance`). The feature-table loop judges the
    features as a whole and leaves the last two conditions out."""
    gain = 1.0 - heldout / null_heldout if null_heldout > 0 else math.nan
    checks = {"gain": {"value": gain, "bound": min_gain,
                       "holds": bool(heldout <= (1 - min_gain) * null_heldout)},
              "delta_bic": {"value": delta_bic, "bound": -min_delta_bic,
                            "holds": bool(delta_bic <= -min_delta_bic)}}
    if explained is not None:
        checks["explained"] = {"value": explained, "bound": allowed,
                               "holds": bool(explained > allowed)}
    if whole is not None:
        checks["whole"] = {"value": whole, "bound": 1.0, "holds": bool(whole >= 1.0)}
    return checks


def holds(checks: dict[str, dict]) -> bool:
    """Whether every condition of a :func:`null_test` holds."""
    return all(c["holds"] for c in checks.values())


def first_passing(verdicts: list[dict[str, dict]]) -> int:
    """The place of the candidate a round judges, from the :func:`null_test` conditions of its
    candidates in ranking order: the first whose conditions all hold (the best that passes),
    else the first."""
    return next((k for k, checks in enumerate(verdicts) if holds(checks)), 0)
