"""Attribution: every candidate effect added to the model in turn, fitted, ranked by held-out
error and judged by the null test (:func:`attribute`); the greedy second round's candidates
stacked on an adopted effect (:func:`stacked`, :func:`second_candidates`).

Beside each candidate: where its own signature lives and what it explains there
(:func:`signature_gain`), its BIC on the train records (:func:`bic`), and its separability
from the free nuisance (:func:`separable_share` of :func:`free_directions`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from physics.dynamics.model import PairModel
from physics.loop.config import LoopSettings
from physics.loop.effects import EFFECTS, Effect
from physics.loop.judge.adoption import first_passing, holds, null_test
from physics.loop.measured.records import Records, by_group
from physics.loop.model.comparison import residuals, residuals_db, rms
from physics.loop.model.declared import BOUNDS, from_unit, to_unit
from physics.loop.model.discrepancy import discrepancy_allowance
from physics.loop.model.simulation import model_signals
from physics.loop.search.fit import Candidate, screen_effect, search
from physics.loop.search.wear_reading import Reader, WearScore, reads_wear, wear_score
from physics.loop.threads import TimeLimit, each

log = logging.getLogger(__name__)


#: unit-coordinate step of the free parameters' directions that judge a candidate's
#: separability (:func:`free_directions`)
SEPARABILITY_STEP = 0.02


def bic(chi2: float, n: int, k: int) -> float:
    """Bayesian information criterion of standardised residuals (known scatter)."""
    return chi2 + k * math.log(n)


def signature_gain(rec: Records, idx: np.ndarray, before: list[np.ndarray],
                   after: list[np.ndarray], quantities: tuple[str, ...]
                   ) -> tuple[dict[str, float], float, float, float]:
    """Where a candidate's own signature lives and what it explains there, on records ``idx``.

    Its entries in a group: those where the model's signature moves with the candidate by
    more than the entry's noise scatter (mean over the group's records; measured data do not
    enter this choice). Only groups of the ``quantities`` the candidate can show in count: in
    the others (the DTE records of a bundle, for a transfer path to the accelerometer) only
    the nuisance refitted with it moves the signature, and a measurement-chain effect would
    otherwise be judged where it cannot act. Returns, per group where it has entries, the mean
    over the records of the drop of the standardised sum of squares (noise and discrepancy)
    over those entries, and the RMS residual there in units of the noise alone, before and
    after (its groups pooled; the effect-size guard of the null test, in the unit of the
    report's headline), and the least over those groups of the whole signature's cut
    (:func:`whole_cut`).
    """
    res_b, res_a = residuals_db(rec, idx, before), residuals_db(rec, idx, after)
    explained, e_b, e_a, whole = {}, [], [], []
    for k, mine in by_group(rec, idx).items():
        g = rec.groups[k]
        if g.key[2] not in quantities:
            continue
        own = np.mean([np.abs(res_b[j] - res_a[j]) for j in mine], axis=0) > g.entry_sd
        if not own.any():
            continue
        rb = np.array([res_b[j][own] for j in mine])
        ra = np.array([res_a[j][own] for j in mine])
        explained[g.label] = float(np.mean(np.sum((rb**2 - ra**2) / g.sd[own] ** 2, axis=1)))
        e_b.append((rb / g.entry_sd[own]).ravel())
        e_a.append((ra / g.entry_sd[own]).ravel())
        whole.append(whole_cut(np.array([res_b[j] for j in mine]) / g.entry_sd,
                               np.array([res_a[j] for j in mine]) / g.entry_sd))
    if not explained:
        return {}, math.nan, math.nan, math.nan
    return explained, rms(np.concatenate(e_b)), rms(np.concatenate(e_a)), min(whole)


def whole_cut(before: np.ndarray, after: np.ndarray) -> float:
    """The relative cut of a group's held-out error over all its entries (RMS in units of the
    noise, records x entries ``before`` and ``after`` a candidate), in units of the relative
    standard error of an RMS of that many values, ``1 / sqrt(2 n)``: a candidate whose own
    entries improve while the group's whole signature does not (a line or two of form error
    that an effect of the library happens to fit) cuts it by less than one."""
    return (1.0 - rms(after) / rms(before)) * math.sqrt(2.0 * before.size)


def free_directions(rec: Records, nuisance: dict, eff: Effect | None, values: dict,
                    free_nuisance: list[str]) -> np.ndarray:
    """Columns: the change of the standardised train residuals per unit-coordinate step of
    each free nuisance parameter (forward differences of ``SEPARABILITY_STEP``, towards the
    inside of its range) at the model ``eff`` at ``values`` with ``nuisance``."""
    r0 = residuals(rec, rec.train, model_signals(rec, rec.train, nuisance, eff, values))
    cols = []
    for n in free_nuisance:
        u = to_unit(nuisance[n], *BOUNDS[n])
        step = SEPARABILITY_STEP if u < 0.5 else -SEPARABILITY_STEP
        moved = nuisance | {n: from_unit(u + step, *BOUNDS[n])}
        r1 = residuals(rec, rec.train, model_signals(rec, rec.train, moved, eff, values))
        cols.append((r1 - r0) / step)
    return np.column_stack(cols) if cols else np.empty((r0.size, 0))


def separable_share(directions: np.ndarray, change: np.ndarray) -> float:
    """Share of the sum of squares of ``change`` that no linear combination of the columns of
    ``directions`` reproduces: 1 for a change orthogonal to all of them, 0 for one in their
    span (the least-squares residual of ``change`` on ``directions``, relative)."""
    ss = float(change @ change)
    if ss == 0.0:
        return math.nan
    if directions.shape[1] == 0:
        return 1.0
    coef, *_ = np.linalg.lstsq(directions, change, rcond=None)
    rest = change - directions @ coef
    return float(rest @ rest) / ss


def lowest_fits(ranking: list[Candidate], earlier: Sequence[Candidate]) -> list[Candidate]:
    """Each candidate of ``ranking`` or, where it fits the train records better, a copy of the
    same effect and option's fit in ``earlier`` (the fits being of one model on the same
    records, the lower is the candidate's fit; its judgement is made afresh)."""
    def key(c: Candidate) -> tuple:
        return c.name, tuple(sorted(c.option.items()))

    kept = {key(c): c for c in earlier}
    return [dataclasses.replace(kept[key(c)]) if key(c) in kept
            and kept[key(c)].train_rss < c.train_rss else c for c in ranking]


def candidates_for(quantities: set[str], settings: LoopSettings) -> list[tuple[Effect, dict]]:
    """(effect, option) pairs to try: the library's (or ``settings.candidates``) effects that can
    show in the records' quantities (none given: only the names are checked). Refused: an
    unknown name, and candidates none of which acts on the records' quantities (named, each
    with the quantities it acts on)."""
    names = settings.candidates if settings.candidates is not None else tuple(EFFECTS)
    unknown = sorted(set(names) - set(EFFECTS))
    if unknown:
        raise ValueError(f"loop.candidates: {unknown} not in the effect library; choose from "
                         f"{sorted(EFFECTS)}")
    out = [(EFFECTS[n], o) for n in names if quantities & set(EFFECTS[n].quantities)
           for o in EFFECTS[n].options]
    if quantities and not out:
        acting = sorted(n for n, e in EFFECTS.items() if quantities & set(e.quantities))
        raise ValueError(f"loop.candidates = {list(names)}: none acts on the data's "
                         f"{sorted(quantities)} ("
                         + "; ".join(f"{n} acts on {list(EFFECTS[n].quantities)} only"
                                     for n in names)
                         + f"); choose from those that do: {acting}")
    return out


@dataclass
class Round:
    """One round of attribution: the candidates ranked by held-out error and the verdict of
    the null test on the judged one (:attr:`best`)."""

    ranking: list[Candidate]
    effects: dict[str, Effect]  # each candidate's effect, by name
    null_bic: float
    # what the discrepancy allows the judged
    # (:func:`~physics.loop.model.discrepancy.discrepancy_allowance`)
    allowed: float
    adopted: bool
    base_test: list[np.ndarray]  # the test signals of the model the candidates were added to
    # the null test's conditions on the judged (:func:`physics.loop.judge.adoption.null_test`)
    checks: dict
    # the model that reads the wear after this round
    # (:class:`~physics.loop.search.wear_reading.Reader`)
    reader: Reader
    # where the judged was adopted: which model reads the wear, from the leave-one-out scores on
    # the train records (:func:`~physics.loop.search.wear_reading.wear_check`, with ``reads_with``),
    # None without them
    wear_reading: dict | None = None
    # held-out wear-estimate scores of the reader before and after this round (adopted only)
    wear: tuple[WearScore | None, WearScore | None] = (None, None)
    # the judged candidate's place in the ranking: the first that passes the null test, else
    # the first
    pick: int = 0
    # the other candidates that pass the null test too, in ranking order: where there are
    # any, the records do not single out the adopted effect
    also_passing: list[Candidate] = field(default_factory=list)
    # the null test's conditions on every candidate, in ranking order
    all_checks: list[dict] = field(default_factory=list)

    @property
    def best(self) -> Candidate:
        """The judged candidate: the adopted one, or the first by held-out error if none
        passes."""
        return self.ranking[self.pick]

    def table(self) -> list[dict]:
        """The ranking as the report writes it."""
        return [{"effect": c.name, "option": c.option,
                 "parameters": {k: v for k, v in c.values.items() if k not in c.option},
                 "nuisance": c.nuisance, "refined": c.refined,
                 "heldout_error": c.heldout, "delta_bic": c.bic - self.null_bic,
                 "own_entries_error": [c.own_before, c.own_after],
                 "explained": c.explained, "n_params": c.n_params,
                 "separable": c.separable} for c in self.ranking]


def attribute(rec: Records, judged: Records, declared: Effect | None, declared_values: dict,
              nuisance: dict, free_nuisance: list[str], candidates: list[tuple[Effect, dict]],
              reader: Reader, progress: bool = False, deadline: float | None = None,
              earlier: Sequence[Candidate] = ()) -> Round:
    """Screen, refine and judge ``candidates`` against the model ``declared`` (None: the calibrated
    declared model; else it with an adopted effect at ``declared_values``) at ``nuisance``; the
    null test on each, the best that passes adopted (see the module text); if one is, which model
    reads the wear after it (:func:`~physics.loop.search.wear_reading.reads_wear`; ``reader`` reads
    it before). Fits weigh the residuals of ``rec`` (noise alone); the held-out judgement uses
    ``judged`` (the same records with the model discrepancy,
    :func:`~physics.loop.model.discrepancy.with_discrepancy`). Past ``deadline``
    (:func:`time.monotonic`) the next candidate raises :class:`TimeLimit`. ``earlier``: the
    candidates of a round judged against another calibration of the same model (a rerun from a
    refitted calibration, :func:`physics.loop.search.fit.recalibrated`); each candidate keeps the
    lower of its two fits on the train records, judged against this round's model."""
    settings = rec.settings
    base_train = model_signals(rec, rec.train, nuisance, declared, declared_values)
    base_test = model_signals(rec, rec.test, nuisance, declared, declared_values)
    null_res = residuals(rec, rec.train, base_train)
    n_train = null_res.size
    null_bic = bic(float(np.sum(null_res**2)), n_train, 0)
    before = rms(residuals(judged, rec.test, base_test))
    effects = {eff.name: eff for eff, _ in candidates}
    try:
        ranking = each(lambda c: screen_effect(rec, *c, nuisance), candidates, "screening",
                       progress, deadline)
    except (TimeLimit, KeyboardInterrupt) as stop:  # the candidates screened by then
        stop.candidates = [c for _, c in getattr(stop, "finished", [])]
        raise
    ranking.sort(key=lambda c: c.train_rss)
    top = settings.refine
    try:
        ranking[:top] = each(lambda c: search(rec, effects[c.name], c, free_nuisance),
                             ranking[:top], "refining", progress, deadline)
    except (TimeLimit, KeyboardInterrupt) as stop:  # the refined ones in place of their screens
        done = dict(getattr(stop, "finished", []))
        stop.candidates = [done.get(i, c) for i, c in enumerate(ranking)]
        raise
    ranking = lowest_fits(ranking, earlier)
    directions = free_directions(rec, nuisance, declared, declared_values, free_nuisance)

    def scored(c: Candidate) -> None:
        without = residuals(rec, rec.train, model_signals(rec, rec.train, c.nuisance, declared,
                                                          declared_values))
        with_c = residuals(rec, rec.train, model_signals(rec, rec.train, c.nuisance,
                                                         effects[c.name], c.values))
        c.separable = separable_share(directions, with_c - without)
        test = model_signals(rec, rec.test, c.nuisance, effects[c.name], c.values)
        c.heldout = rms(residuals(judged, rec.test, test))
        c.explained, c.own_before, c.own_after, c.whole_cut = signature_gain(
            judged, rec.test, base_test, test, effects[c.name].judged_in())
        c.bic = bic(c.train_rss, n_train, c.n_params)

    try:
        each(scored, ranking, "judging")
    except (TimeLimit, KeyboardInterrupt) as stop:  # fitted, not all judged
        stop.candidates = ranking
        raise
    for c in ranking:
        log.info("%s %s: held-out %.2f (baseline %.2f), own entries %.2f -> %.2f, explained "
                 "%s, dBIC %.1f, separable %.2f%s", c.name, c.option, c.heldout, before,
                 c.own_before, c.own_after, {k: round(v, 1) for k, v in c.explained.items()},
                 c.bic - null_bic, c.separable, "" if c.refined else " (screened)")
    ranking.sort(key=lambda c: c.heldout)

    def verdict(c: Candidate) -> tuple[float, dict]:
        allowed = discrepancy_allowance(c.n_params, len(ranking), settings.false_add_rate)
        return allowed, null_test(c.own_after, c.own_before, c.bic - null_bic,
                                  settings.min_gain, settings.min_delta_bic,
                                  min(c.explained.values(), default=0.0), allowed, c.whole_cut)

    verdicts = [verdict(c) for c in ranking]
    pick = first_passing([checks for _, checks in verdicts])
    best = ranking[pick]
    allowed, checks = verdicts[pick]
    adopted = holds(checks)
    every = [ch for _, ch in verdicts]
    if not adopted:
        return Round(ranking, effects, null_bic, allowed, adopted, base_test, checks, reader,
                     all_checks=every)
    # last: it costs a simulation per wear state and record
    adopted_reader = Reader(f"the model with {best.name}", best.nuisance, effects[best.name],
                            best.values)
    after, reading = reads_wear(rec, reader, adopted_reader, settings.max_wear_loss)
    before = wear_score(rec, reader.nuisance, reader.effect, reader.values)
    wear = (before, before if after is reader else
            wear_score(rec, after.nuisance, after.effect, after.values))
    log.info("%s adopted; the wear read by %s (train leave-one-out %s), held-out %s -> %s",
             best.name, after.name, reading, *wear)
    also = [c for k, (c, (_, ch)) in enumerate(zip(ranking, verdicts, strict=True))
            if k != pick and holds(ch)]
    return Round(ranking, effects, null_bic, allowed, adopted, base_test, checks, after,
                 reading, wear, pick, also, every)


def stacked(first: Effect, values: dict, second: Effect) -> Effect:
    """``second`` added to a model that carries ``first`` at its fitted ``values``: a candidate
    of the greedy second round. Its parameters and options are the second's; the dynamics
    take both effects' model stages; each measurement stage acts on the quantities of both
    that have one (a pair whose measurement stages share no quantity is not stacked)."""
    staged = [e for e in (first, second) if e.record is not None]
    quantities = tuple(q for q in first.quantities + second.quantities
                       if all(q in e.quantities for e in staged))
    if staged and not quantities:
        raise ValueError(f"{first.name} and {second.name} act on the measurement chains of "
                         "different quantities; they are not stacked")

    def model(m: PairModel, v: dict) -> PairModel:
        stages = [(e, ev) for e, ev in ((first, values), (second, v)) if e.model is not None]
        built = [e.model(m, ev) for e, ev in stages]
        # an effect that tiles the tables over a pinion revolution (a tooth defect) needs
        # one-period tables and does not tile the others' per-pair factors: it goes first
        order = sorted(range(len(stages)), key=lambda i: built[i].periods == m.periods)
        m = built[order[0]]
        for i in order[1:]:
            e, ev = stages[i]
            m = e.model(m, ev)
        return m

    def record(x: np.ndarray, fs: float, v: dict) -> np.ndarray:
        for e, ev in ((first, values), (second, v)):
            x = e.record(x, fs, ev) if e.record is not None else x
        return x

    dynamic = first.model is not None or second.model is not None
    return dataclasses.replace(second, name=f"{first.name}+{second.name}",
                               quantities=tuple(dict.fromkeys(quantities)),
                               shows_in=second.quantities,
                               model=model if dynamic else None,
                               record=record if staged else None)


def second_candidates(first: Effect, values: dict, candidates: list[tuple[Effect, dict]]
                      ) -> list[tuple[Effect, dict]]:
    """The candidates of the greedy second round: every other effect stacked on ``first``."""
    return [(stacked(first, values, e), o) for e, o in candidates if e.name != first.name
            and not (first.record is not None and e.record is not None
                     and not set(first.quantities) & set(e.quantities))]
