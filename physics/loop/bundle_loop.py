"""Close the loop with measured data: calibrate, find the residual, attribute it, extend, report.

``python -m physics.loop data=BUNDLE`` (Hydra app, ``conf/loop.yaml``) runs the steps below on a
measured bundle (:mod:`physics.loop.measured.bundle`) and writes ``report.json``, ``report.md`` and
figures into its run folder.

1. **Records** (:mod:`physics.loop.measured.records`, :mod:`physics.loop.measured.worn_states`):
   each record becomes a scenario (its speed, torque, lubricant and gear overrides) with its worn
   teeth: the dynamically coupled wear evolution (:mod:`physics.dynamics.evolution`) is run once per
   operating point to the records' cycle counts (or, where only the wear depth is known, to the
   cycle count of that depth). A bundle may mix operating points, quantities, sampling rates and
   record lengths: records of one (speed, torque, quantity, sampling rate) form a **group**
   (:class:`~physics.loop.measured.records.Group`) with its own signature definition and entry
   scatter. Records are split into train and test by record within each group (the manifest's
   ``split`` column where given, else seeded), never by windows of one record.
2. **Calibration** (:mod:`physics.loop.search.fit`; the parameters in
   :mod:`physics.loop.model.declared`) of the declared nuisance parameters on the train records of
   all groups at once, before any effect is considered: the physical ones (mesh damping ratio,
   pinion run-out and profile error amplitudes, the once-per-revolution mesh modulation that the
   run-out makes, with its phase,
   :data:`~physics.loop.model.declared.RUNOUT_MODULATION` and
   :func:`physics.dynamics.model_form.with_modulation`, and with ``loop.model_form`` the rest of
   the model's own form uncertainty, :data:`~physics.loop.model.declared.MODEL_FORM`: mesh-stiffness
   level, double/single stiffness ratio, effective mass and backlash,
   :func:`physics.dynamics.model_form.with_model_form`) are one value for the whole bundle; the
   measurement chain's (the housing's effective mass ``m_h`` and, where the scenario declares them,
   the bearing support's mode and the housing mounting's, each with its damping,
   :data:`~physics.loop.model.declared.CHAIN_MODES`) belong to the acceleration records only; the
   groups' standardised residuals are concatenated into one cost. With a **reference**
   (``reference=``,
   :mod:`physics.loop.search.form_error`: a sister gearbox's clean records at the same operating
   points and sensors), the declared model is first calibrated on those, and its mean residual per
   group and entry there, the model's own form error, is removed from the measured signatures
   before this calibration. Where the reference is this unit's own earliest records
   (``reference=first:N``), their calibration is held instead
   (:func:`physics.loop.search.fit.held`): the same unit's nuisance and measurement chain, which
   nothing may recalibrate to absorb what changed since. A parameter that does not move the
   residuals (the pinion run-out on the line of action: a shaft-rate error is dynamically inert in
   the torsional model; the modulation's phase, which no amplitude of the signature sees unless
   another once-per-revolution feature is in the model; the backlash in acceleration records whose
   flanks never part) is held at its declared value and reported as not identifiable. Every
   candidate effect is then fitted jointly with the free parameters, model form included. The search
   (:func:`physics.loop.search.fit.search`): a scrambled Sobol sample around the declared values,
   ``m_h`` levelled at each point, the best refined by bounded least squares on the standardised
   signature residuals. Measurement noise is not fitted: its level is read off each record's
   spectral floor (:func:`physics.signals.order_analysis.white_noise_std`) and white noise of that
   level (seeded per record) is added to the model's record.
3. **Residual and model discrepancy** (:mod:`physics.loop.model.comparison`,
   :mod:`physics.loop.model.discrepancy`): the signature of :mod:`physics.signals.order_analysis`
   (mesh harmonics with pinion and gear sidebands up to 0.45 fs, half-octave bands, statistics,
   synchronous-average kurtosis, all in dB) of measurement minus calibrated model, per entry,
   divided by the entry's scatter between the measured records' segments (pooled over the group's
   train records, plus a floor ``floor_db``) and a model discrepancy in quadrature. The discrepancy
   (:func:`~physics.loop.model.discrepancy.discrepancy_sd`) is estimated on the train residuals of
   the calibrated declared model, per entry family and group: with it the RMS standardised residual
   is about 1 where model and measurement agree up to noise and the model's known form error. It
   enters the judgement (held-out errors, the null test), not the fits: the calibration and every
   candidate's fit weigh the residuals by the noise alone, because a discrepancy estimated on
   records where an effect is missing is large exactly in that effect's entries and would
   down-weight them in its fit (a tip relief of 16 um in the project's own records was fitted at 11
   um with it). The report's headline error stays in units of the noise alone.
4. **Attribution** (:mod:`physics.loop.search.attribution`): every effect of
   :mod:`physics.loop.effects` that can show in the bundle's quantities is added in turn (a
   measurement-chain effect acts only on its own quantities). Screening: the effect at a grid of
   sizes, nuisance at the calibration, the best size polished by a short least squares. Every
   candidate (or the best ``refine`` by train chi-square) then gets the same search as the
   calibration, their parameters jointly with the identifiable nuisance (a missing effect biases the
   calibration, at worst to its bounds, so the nuisance must move with the effect). Candidates are
   ranked by held-out error (RMS standardised residual, with discrepancy, over the test records)
   with the Bayesian information criterion on the train records beside it (chi-square plus k ln n,
   the scatter being known, k the effect's parameters).
   The **null test** (:func:`physics.loop.judge.adoption.null_test`), judged where each candidate's
   own signature lives (the entries its model moves by more than their noise,
   :func:`~physics.loop.search.attribution.signature_gain`): the best by held-out error of those
   that pass it is adopted (a candidate that soaks up form error across the spectrum can rank first
   and fail it while the effect in the data passes); a candidate passes only if it lowers the
   held-out error there (in units of the noise) by at least ``min_gain`` (20 %), its BIC by at least
   ``min_delta_bic`` (10, "very strong" on Kass & Raftery's scale), and, in every group where it
   shows (of the quantities it can act on), removes more standardised sum of squares per held-out
   record than the discrepancy lets a candidate of its size absorb by chance
   (:func:`~physics.loop.model.discrepancy.discrepancy_allowance`) and cuts the group's held-out
   error over all its entries by at least one standard error
   (:func:`~physics.loop.search.attribution.whole_cut`). The records' wear takes no part in
   this decision: an adopted effect **reads the wear** (:mod:`physics.loop.search.wear_reading`)
   only if, where the train records' wear is known, it does not lower the model-based wear
   estimate's leave-one-out skill on them by more than ``max_wear_loss`` (0.1: its mean absolute
   error may grow by a tenth of the constant guess's;
   :func:`~physics.loop.search.wear_reading.wear_check`); else the model before it keeps reading it.
   The held-out records' wear is only scored, before and after, never used to decide (a decision on
   it would leave the held-out score no longer held out). The rule is designed for a false-add rate
   of ``false_add_rate`` (1 %) per bundle when the declared model's form error is unstructured (no
   effect of the library resembles it); a form error that looks like an effect is not separable from
   it by any rule on these data. Each candidate's **separability** is reported beside it
   (:func:`~physics.loop.search.attribution.separable_share`): the share of its change of the train
   residuals that no linear combination of the free nuisance's directions reproduces (near 0: the
   declared model's own freedom makes the same change; a DTE sensor gain against a free stiffness
   level, whose lengths scale out of the equation of motion, is the exact case).
   The null is the declared model's best fit (:func:`best_null_round`): after an adoption the
   declared model is refitted from the adopted candidate's nuisance
   (:func:`~physics.loop.search.fit.recalibrated`); where that fits the train records better by more
   than 1 % of the chi-square, it becomes the calibration and the round is judged again, each
   candidate keeping its lowest fit, at most twice (a candidate's gain can be a better basin
   of the nuisance that its joint fit reached).
   **Greedy second round** (:func:`~physics.loop.search.attribution.attribute` again): once an
   effect is adopted, every other effect is tried on the model that carries it
   (:func:`~physics.loop.search.attribution.stacked`, the first's parameters held at their fit, the
   nuisance refitted), judged by the same rule against that model.
5. **Report** (:func:`run_loop`, :mod:`physics.loop.report`): error before and after on the
   held-out records, overall and per group, as the standardised signature residual (noise alone:
   the figure the report leads with; noise and discrepancy) and in dB, as the mean relative error
   of the Table 13 features [%], and, where the wear is known, as the error of a model-based wear
   estimate (the wear state whose simulated signature is nearest, relative to the group's train
   records of known wear: :func:`~physics.loop.search.wear_reading.wear_estimates`) [%] and as its
   skill against the train records' mean wear (:func:`~physics.loop.search.wear_reading.wear_skill`;
   at or below 0 the estimate reads no wear on these records, and the choice of the model that reads
   it above then compares noise).
"""

from __future__ import annotations

import logging
import time

import numpy as np

from physics.arguments import argument
from physics.loop.config import LoopSettings
from physics.loop.effects import Effect
from physics.loop.judge.verdict import closest, group_lines, judge, unexplained_entries
from physics.loop.measured.bundle import Bundle
from physics.loop.measured.records import Records, prepare
from physics.loop.measured.usable import check_usable, shown_candidates
from physics.loop.model.comparison import (
    feature_error,
    group_errors,
    noise_only,
    residual_table,
    residuals,
    residuals_db,
    rms,
)
from physics.loop.model.declared import (
    BOUNDS,
    TORQUE,
    at_bounds,
    declared_modes,
    declared_nuisance,
)
from physics.loop.model.discrepancy import entry_family, with_discrepancy
from physics.loop.model.simulation import model_signals
from physics.loop.report import LoopReport, stop_entries
from physics.loop.search.attribution import Round, attribute, candidates_for, second_candidates
from physics.loop.search.detection import detection_limits
from physics.loop.search.fit import (
    MAX_RECALIBRATIONS,
    Candidate,
    calibrate,
    held,
    recalibrated,
    screened,
)
from physics.loop.search.form_error import FormReference
from physics.loop.search.wear_reading import Reader, wear_score
from physics.loop.threads import TimeLimit, one_blas_thread
from physics.params import Scenario

log = logging.getLogger(__name__)


def group_summary(rec: Records, before: list[np.ndarray], after: list[np.ndarray]
                  ) -> dict[str, dict]:
    """Per group: its key, records, discrepancy per entry family [dB] and held-out errors before
    and after (``before``/``after``: model signals of the test records)."""
    err = {key: group_errors(rec, rec.test, sig, disc)
           for key, sig, disc in (("before", before, True), ("after", after, True),
                                  ("before_noise_only", before, False),
                                  ("after_noise_only", after, False))}
    out = {}
    for g in rec.groups:
        n1, torque, quantity, fs = g.key
        fam = {entry_family(n): float(d) for n, d in zip(g.names, g.discrepancy_sd,
                                                          strict=True)}
        out[g.label] = {"n1_rpm": n1, "torque_Nm": torque, "quantity": quantity, "fs_hz": fs,
                        "records": [rec.bundle.records[i] for i in g.records],
                        "entries": len(g.names), "discrepancy_db": fam,
                        **{f"error_{k}": v.get(g.label) for k, v in err.items()}}
    return out


def assumed(bundle: Bundle, base: Scenario, nuisance: dict) -> dict:
    """What the bundle left unknown and what stood in: the torque of records without one
    (the configured torque times the calibrated factor, its prior), the speed of records
    without one (each one's reading off its spectrum, the height of its mesh comb over the
    floor, the operating point's speed used), gear data stated unknown (the configured pair's
    values)."""
    out = {}
    unknown = ~np.isfinite(bundle.manifest.torque_Nm.to_numpy(float))
    if unknown.any():
        t0 = base.operating.torque_Nm
        lo, hi, _ = TORQUE["torque_factor"]
        out["torque_Nm"] = {"records": [r for r, u in zip(bundle.records, unknown, strict=True)
                                        if u],
                            "configured": t0, "prior": [lo * t0, hi * t0],
                            "calibrated": t0 * nuisance.get("torque_factor", 1.0),
                            "worn_teeth_at": t0}
    if bundle.speeds:
        man = bundle.manifest.set_index("record")
        out["n1_rpm"] = {"records": list(bundle.speeds),
                         "read_rpm": {r: e.rpm for r, e in bundle.speeds.items()},
                         "comb_db": {r: e.comb_db for r, e in bundle.speeds.items()},
                         "used_rpm": {r: float(man.n1_rpm[r]) for r in bundle.speeds}}
    if bundle.unknown_gear:
        out["gear"] = {k: getattr(base.gear, k) for k in bundle.unknown_gear}
    return out


def best_null_round(rec: Records, nuisance: dict, free_nuisance: list[str],
                    candidates: list[tuple[Effect, dict]], progress: bool = False,
                    deadline: float | None = None
                    ) -> tuple[Round, dict, Records, list[str], bool]:
    """The first round judged against the declared model's best fit: where the declared model
    refitted from an adopted candidate's nuisance (:func:`~physics.loop.search.fit.recalibrated`)
    fits the train records better than ``nuisance``, the refit becomes the calibration and the round
    is run again, each candidate keeping the lower of its fits
    (:func:`~physics.loop.search.attribution.lowest_fits`), at most
    :data:`~physics.loop.search.fit.MAX_RECALIBRATIONS` times. Returns the round, the calibration it
    was judged against, the records with that calibration's discrepancy, the candidates whose
    nuisance moved the calibration, and whether the cap left a better fit unused. Past
    ``deadline`` the next candidate raises :class:`TimeLimit` (:func:`first_round_partial`)."""
    refits: list[str] = []
    earlier: list[Candidate] = []
    while True:
        judged = with_discrepancy(rec, nuisance)
        first = attribute(rec, judged, None, {}, nuisance, free_nuisance, candidates,
                          Reader("the declared model", nuisance), progress, deadline,
                          earlier=earlier)
        better = (recalibrated(rec, nuisance, first.best.nuisance, free_nuisance)
                  if first.adopted else None)
        if better is None or len(refits) == MAX_RECALIBRATIONS:
            if better is not None:
                log.warning("the declared model refitted from %s's nuisance fits better still; "
                            "the cap of %d refits is reached: the adoption is judged against "
                            "the last", first.best.name, MAX_RECALIBRATIONS)
            return first, nuisance, judged, refits, better is not None
        log.info("the declared model refitted from %s's nuisance fits the train records "
                 "better than the calibration: the first round again from there",
                 first.best.name)
        refits.append(first.best.name)
        nuisance, earlier = better, first.ranking


def calibrated_on(held: bool, refits: list[str], capped: bool) -> str:
    """What the report's calibration was fitted on (:func:`best_null_round`'s refits)."""
    text = ("this unit's earliest records, held for the later ones" if held
            else "the train records")
    if refits:
        text += (", then refitted from the nuisance of " + ", then of ".join(refits)
                 + " (a better fit of the declared model; every candidate judged again)")
    if capped:
        text += (f"; after {MAX_RECALIBRATIONS} refits a further one would fit better still "
                 "(not made: the adoption is judged against the last)")
    return text


def first_round_partial(bundle: Bundle, rec: Records, settings: LoopSettings,
                        stop: BaseException, nuisance: dict | None, left_out: dict
                        ) -> LoopReport:
    """The report of a run stopped in its first round (``stop``: the time limit or an
    interrupt): what was computed by then, nothing more (no simulation runs after a stop).
    The calibration where it was finished (else none), and the candidates screened or
    refined by then with their train residual sums (``stop.candidates``, from
    :func:`~physics.loop.search.attribution.attribute`); no candidate was judged, so no
    effect is named and no held-out error is given: ``verdict`` is ``not_judged``."""
    done = [{"effect": c.name, "option": c.option,
             "parameters": {k: v for k, v in c.values.items() if k not in c.option},
             "nuisance": c.nuisance, "refined": c.refined, "train_rss": c.train_rss}
            for c in sorted(getattr(stop, "candidates", []), key=lambda c: c.train_rss)]
    missing = ("the calibration was not finished: no candidate was searched" if nuisance is None
               else f"{len(done)} candidates were fitted on the train records and none judged"
               " on the held-out ones: no effect is named")
    return LoopReport.stopped(
        "bundle", stop, settings.time_limit_s, missing, nuisance, "the train records", None,
        "not computed: the run stopped before any held-out comparison", None, done,
        {"min_gain": settings.min_gain, "min_delta_bic": settings.min_delta_bic,
         "false_add_rate": settings.false_add_rate, "max_wear_loss": settings.max_wear_loss},
        {"not_searched": left_out, "train_records": [bundle.records[i] for i in rec.train],
         "test_records": [bundle.records[i] for i in rec.test]})


@one_blas_thread
def run_loop(bundle: Bundle, base: Scenario, settings: LoopSettings | None = None,
             progress: bool = False, reference: FormReference | None = None) -> LoopReport:
    """The whole loop on one bundle; returns its report (see the module text). With a
    ``reference`` (:func:`physics.loop.search.form_error.form_reference`, a sister gearbox's
    records) the declared model's mean form error measured there is removed from the
    measured signatures first."""
    argument(bundle, "run_loop(bundle)", Bundle, "a Bundle (physics.loop.read_bundle)")
    argument(base, "run_loop(base)", Scenario, "a physics.params.Scenario")
    settings = argument(settings, "run_loop(settings)", (LoopSettings, type(None)),
                        "a LoopSettings or None (the defaults)") or LoopSettings()
    argument(reference, "run_loop(reference)", (FormReference, type(None)),
             "a FormReference (physics.loop.search.form_error.form_reference) or None")
    started = time.monotonic()
    check_usable(bundle, base, settings)  # refusals before work
    candidates, left_out = shown_candidates(
        candidates_for(set(bundle.manifest.quantity), settings), bundle, base, settings)
    start = declared_nuisance(base) | declared_modes(base)  # a bad chain mode: before work
    if reference is not None:
        reference.check(bundle)
    rec = prepare(bundle, base, settings)
    if reference is not None:
        rec = reference.subtracted(rec)
    deadline = started + settings.time_limit_s if settings.time_limit_s else None
    nuisance = None
    try:
        if reference is not None and reference.same_unit:
            rec, nuisance, free_nuisance = held(rec, reference.calibration)
        else:
            nuisance, free_nuisance = calibrate(rec, start)
        first, nuisance, judged, refits, capped = best_null_round(
            rec, nuisance, free_nuisance, candidates, progress, deadline)
    except (TimeLimit, KeyboardInterrupt) as stop:  # what the first round computed, kept
        return first_round_partial(bundle, rec, settings, stop, nuisance, left_out)
    declared = Reader("the declared model", nuisance)
    base_test = first.base_test  # the calibrated declared model's
    rounds = [first]
    eff = first.effects[first.best.name]
    more = second_candidates(eff, first.best.values, candidates) if first.adopted else []
    partial = None
    try:
        if more and deadline is not None and time.monotonic() > deadline:
            raise TimeLimit
        if more:  # greedy: a second effect on the residual of the first, the same rule
            rounds.append(attribute(rec, judged, eff, first.best.values, first.best.nuisance,
                                    free_nuisance, more, first.reader, progress, deadline))
    except (TimeLimit, KeyboardInterrupt) as stop:
        partial = {**stop_entries(stop, settings.time_limit_s), "after_round": 1,
                   "missing": f"the greedy second round on {first.best.name} was not "
                              "finished: a second effect was not searched"}
    last = next((r for r in reversed(rounds) if r.adopted), None)
    best = last.best if last else None
    chosen = last.effects[best.name] if last else None
    after_nui = best.nuisance if last else nuisance
    after_vals = best.values if last else {}
    after_test = (model_signals(rec, rec.test, after_nui, chosen, after_vals) if last
                  else base_test)
    adopted = [r.best for r in rounds if r.adopted]
    # each adopted round has scored its reader before and after on the held-out records
    wear_before = first.wear[0] if first.adopted else wear_score(rec, nuisance, None, {})
    wear_after = last.wear[1] if last else wear_before
    entries = ({} if last else
               unexplained_entries(reference.judging(judged) if reference is not None
                                   else judged, rec.test, base_test, settings.false_add_rate))
    lines = {} if last else group_lines(rec, settings.false_add_rate)
    said, unexplained = judge(last is not None, entries, lines,
                                closest(first.ranking, first.all_checks))
    limits = (detection_limits(rec, judged, nuisance, candidates,
                               model_signals(rec, rec.train, nuisance, None, {}), base_test)
              if said != "effect" and settings.detection_limits else None)
    ranking = first.table()
    for row in ranking:
        row["detection_limit"] = next(
            (d for d in limits or () if (d["effect"], d["option"]) == (row["effect"],
                                                                      row["option"])), None)
    rec.cache.clear()  # the report keeps the records, not the simulations
    ranges = {n: BOUNDS[n] for n in nuisance if n in BOUNDS}  # the calibration's search ranges
    return LoopReport(
        verdict=said, unexplained=unexplained, partial=partial,
        mode="bundle",
        chosen_effect=chosen.name if chosen else None,
        chosen_option=({k: v for c in adopted for k, v in c.option.items()} if last
                       else None),
        chosen_parameters=({k: v for c in adopted for k, v in c.values.items()
                            if k not in c.option} if last else None),
        error_before=noise_only(rec, rec.test, base_test),
        error_after=noise_only(rec, rec.test, after_test),
        error_unit="RMS of the held-out records' signature residuals, each in units of its "
                   "own scatter between segments (1: at the noise); with the model "
                   "discrepancy in quadrature: error_before_with_discrepancy",
        feature_error_before_pct=feature_error(rec, rec.test, base_test),
        feature_error_after_pct=feature_error(rec, rec.test, after_test),
        wear_error_before_pct=wear_before.error if wear_before else None,
        wear_error_after_pct=wear_after.error if wear_after else None,
        calibration=nuisance,
        calibrated_on=calibrated_on(rec.held, refits, capped),
        nuisance_after=after_nui,
        null_bic=first.null_bic,
        ranking=ranking,
        decision_rule={"min_gain": settings.min_gain, "min_delta_bic": settings.min_delta_bic,
                       "false_add_rate": settings.false_add_rate, "allowed": first.allowed,
                       "max_wear_loss": settings.max_wear_loss},
        details={
            "error_before_db": rms(np.concatenate(residuals_db(rec, rec.test, base_test))),
            "error_after_db": rms(np.concatenate(residuals_db(rec, rec.test, after_test))),
            "error_before_with_discrepancy": rms(residuals(judged, rec.test, base_test)),
            "error_after_with_discrepancy": rms(residuals(judged, rec.test, after_test)),
            "not_identifiable": [] if rec.held else [
                n for n in (*screened(settings), *TORQUE)
                if n in nuisance and n not in free_nuisance],
            "not_searched": left_out,
            "nuisance_ranges": ranges,
            "at_bound": {"calibration": at_bounds(nuisance, ranges),
                         "after": at_bounds(after_nui, ranges)},
            "detection_limits": limits,
            "assumed": assumed(bundle, base, nuisance),
            "form_reference": reference.summary() if reference is not None else None,
            "train_records": [bundle.records[i] for i in rec.train],
            "test_records": [bundle.records[i] for i in rec.test],
            "groups": group_summary(judged, base_test, after_test),
            "residual_before": residual_table(rec, rec.test, base_test),
            "residual_after": residual_table(rec, rec.test, after_test),
            "wear_skill_before": wear_before.skill if wear_before else None,
            "wear_skill_after": wear_after.skill if wear_after else None,
            "wear_estimates": ({"records": [bundle.records[i] for i in wear_before.records],
                                "true_mm": list(wear_before.true_mm),
                                "before_mm": list(wear_before.estimate_mm),
                                "after_mm": list(wear_after.estimate_mm)}
                               if wear_before and wear_after else None),
            "verdicts": [{"effect": r.best.name, "rank": r.pick, "adopted": r.adopted,
                          "checks": r.checks, "wear_reading": r.wear_reading,
                          "also_passing": [{"effect": c.name, "option": c.option,
                                            "heldout_error": c.heldout}
                                           for c in r.also_passing]}
                         for r in rounds],
            "wear_read_by": (last.reader if last else declared).name,
            "second_round": ({"on": first.best.name, "rank": rounds[1].pick,
                              "adopted": rounds[1].adopted,
                              "allowed": rounds[1].allowed, "ranking": rounds[1].table()}
                             if len(rounds) > 1 else None),
        },
        signals={"test": rec.test, "before": base_test, "after": after_test, "rec": rec},
    )
