"""The calibration and every candidate's fit: the search (:func:`search`) of the model's
parameters on the train records.

The declared nuisance (:mod:`physics.loop.model.declared`) is calibrated on the train records of all
groups at once, before any effect is considered (:func:`calibrate`): the physical parameters
are one value for the whole bundle, the measurement chain's belong to the acceleration records
only, and the groups' standardised residuals are concatenated into one cost. A parameter that
does not move the residuals is held at its declared value and reported as not identifiable
(:func:`identifiable`). The search: a scrambled Sobol sample around the declared values
(:func:`explore`), ``m_h`` levelled at each point (:func:`with_level`), the best refined by
bounded least squares on the standardised signature residuals (:func:`least_squares`). A
candidate effect is screened at a grid of sizes (:func:`screen_effect`) and then gets the same
search, its parameters jointly with the identifiable nuisance. Fits weigh the residuals by the
noise alone (the discrepancy is for the judgement, :mod:`physics.loop.model.discrepancy`).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from physics.loop.config import LoopSettings
from physics.loop.effects import Effect
from physics.loop.measured.records import Records
from physics.loop.model.comparison import residuals, residuals_db, rms
from physics.loop.model.declared import (
    BOUNDS,
    DYNAMIC_NUISANCE,
    EXPLORED,
    MODEL_FORM,
    NUISANCE,
    RUNOUT_MODULATION,
    SCENARIO_DYNAMIC,
    SUPPORT,
    TORQUE,
    completed,
    declared_modes,
    declared_nuisance,
    from_unit,
    to_unit,
)
from physics.loop.model.simulation import accel_in, is_accel, model_signals
from physics.loop.threads import each

#: signature entries that do not scale with the record's gain
SCALE_FREE = ("kurtosis", "crest", "tsa_kurtosis")
#: RMS change of the standardised train residuals below which a parameter is not identifiable
MIN_SENSITIVITY = 0.02
#: half-width of the nuisance's search around its declared values (unit coordinates: a factor
#: of 2.3 in damping ratio, of 4 in profile error)
EXPLORE_SPAN = 0.25
#: the calibration explores this many times ``loop.explore`` points: every candidate starts from
#: it, and an effect in every record drags it into a basin of its own (an independent bundle
#: with a pit: damping ratio 0.010 and run-out modulation 0.125 from 32 points, and a transfer
#: path named; 0.126 and 0.2 from 128, and the pit named, 14.4 -> 8.5); with the model form
#: over its whole range the resonance's residual surface has a basin per mesh harmonic as well
CALIBRATION_EXPLORE = 4
#: ... and refines this many of its best points by least squares, keeping the best fit: from
#: one start the fit ends in the basin of whichever point the exploration ranks first, which the
#: last digits of the signatures decide (one independent bundle, a rounding change: train
#: chi-square 43,394 -> 47,860, stiffness factor 0.83 -> 0.64)
CALIBRATION_STARTS = 3
#: least-squares evaluations that polish a screened candidate's best grid point
SCREEN_NFEV = 6
#: relative cut of the train chi-square by which a refit of the declared model from an
#: adopted candidate's nuisance replaces the calibration (:func:`recalibrated`): least squares
#: restarted at the minimum it reached gains 3e-7 of the chi-square, from another start in
#: the same basin it ends within 0.2 % (a clean bundle of the project's model), in another
#: basin it was 28 % lower (a clean independent bundle, seed 104)
RECALIBRATION_GAIN = 0.01
#: refitted calibrations a bundle's first round may be rerun from (:func:`recalibrated`):
#: each rerun costs a first round (36-48 s on the independent bench's bundles) and no bundle
#: of the benches needed a second
MAX_RECALIBRATIONS = 2


def with_level(rec: Records, nuisance: dict, eff: Effect | None, values: dict) -> dict:
    """``m_h`` moved so that the model's level matches the train acceleration records'.

    ``m_h`` divides every amplitude, so in dB it is an offset of the entries that scale with the
    record (all but kurtosis and crest factors): one step of their mean residual, weighted by the
    inverse variance of each entry (:attr:`~physics.loop.measured.records.Group.sd`). The noise does
    not scale with it, so this is a starting value, not the fit. DTE records do not see ``m_h``, nor
    do records of a unit whose calibration is held (:func:`held`).
    """
    acc = is_accel(rec, rec.train)
    if rec.held or not acc.any():
        return nuisance
    res = residuals_db(rec, rec.train, model_signals(rec, rec.train, nuisance, eff, values))
    num = den = 0.0
    for r, i, a in zip(res, rec.train, acc, strict=True):
        if a:
            g = rec.group(i)
            w = np.where([n not in SCALE_FREE for n in g.names], g.sd**-2.0, 0.0)
            num, den = num + float(np.sum(r * w)), den + float(np.sum(w))
    lo, hi, _ = NUISANCE["housing_mass_kg"]
    return nuisance | {"housing_mass_kg": float(np.clip(
        nuisance["housing_mass_kg"] * 10 ** (-num / den / 20), lo, hi))}


def train_cost(rec: Records, nuisance: dict, eff: Effect | None, values: dict) -> float:
    return float(np.sum(residuals(rec, rec.train, model_signals(rec, rec.train, nuisance, eff,
                                                                values)) ** 2))


def identifiable(rec: Records, nuisance: dict, names: tuple[str, ...]) -> list[str]:
    """Those of ``names`` that change the train residuals: each is moved by a tenth of its
    (log) range; one that moves the standardised residuals by less than ``MIN_SENSITIVITY``
    RMS is not identifiable from these records and stays at its declared value."""
    nuisance = completed(nuisance, rec.scenarios[0])
    r0 = residuals(rec, rec.train, model_signals(rec, rec.train, nuisance, None, {}))
    out = []
    for n in names:
        u = to_unit(nuisance[n], *BOUNDS[n])
        moved = nuisance | {n: from_unit(u + (0.1 if u < 0.5 else -0.1), *BOUNDS[n])}
        r1 = residuals(rec, rec.train, model_signals(rec, rec.train, moved, None, {}))
        if rms(r1 - r0) >= MIN_SENSITIVITY:
            out.append(n)
    return out


def split_fitted(fitted: dict) -> tuple[dict, dict]:
    """(effect values with option, nuisance) of a fitted parameter set."""
    return ({k: v for k, v in fitted.items() if k not in BOUNDS},
            {n: fitted[n] for n in BOUNDS if n in fitted})


def least_squares(rec: Records, eff: Effect | None, fixed: dict, start: dict,
                  free: list[tuple[str, float, float, bool]], max_nfev: int) -> tuple[dict,
                                                                                      float]:
    """Bounded least squares of the train residuals over ``free`` parameters (name, bounds,
    log), in unit-scaled coordinates; ``fixed | start`` holds all values, the nuisance's and
    the effect's. Returns the fitted values and the train chi-square."""
    def values(u):
        return fixed | start | {n: from_unit(float(x), lo, hi, lg)
                                for (n, lo, hi, lg), x in zip(free, u, strict=True)}

    def fun(u):
        vals, nui = split_fitted(values(u))
        return residuals(rec, rec.train, model_signals(rec, rec.train, nui, eff, vals))

    if not free:
        return fixed | start, float(np.sum(fun(np.empty(0)) ** 2))
    u0 = np.array([np.clip(to_unit(start[n], lo, hi, lg), 0.001, 0.999)
                   for n, lo, hi, lg in free])
    sol = optimize.least_squares(fun, u0, bounds=(0, 1), diff_step=0.01, max_nfev=max_nfev,
                                 workers=columns)
    return values(sol.x), float(np.sum(sol.fun**2))


def columns(fn: Callable, points: Iterable) -> list:
    """The finite-difference Jacobian's evaluations on parallel threads (:func:`each`; within
    a candidate already on its own thread, one after another): scipy's ``workers`` map."""
    return each(fn, list(points), "jacobian")


@dataclass
class Candidate:
    name: str
    option: dict
    values: dict  # the effect's parameters (with its option)
    nuisance: dict  # refitted with the effect
    train_rss: float
    n_params: int
    refined: bool = False
    heldout: float = math.nan
    bic: float = 0.0
    # per group: see :func:`~physics.loop.search.attribution.signature_gain`
    explained: dict = field(default_factory=dict)
    own_before: float = math.nan  # held-out error in its own entries, declared model ...
    own_after: float = math.nan  # ... and with the candidate
    whole_cut: float = math.nan  # the least group's whole-signature cut (whole_cut)
    separable: float = math.nan  # share of its change no free parameter mimics (separable_share)


def screen_effect(rec: Records, eff: Effect, option: dict, nuisance: dict) -> Candidate:
    """The effect at a grid of sizes over its parameters' ranges (nuisance at the calibration,
    ``m_h`` levelled at each), the best grid point polished by a short least squares of the
    effect's parameters and ``m_h`` (a grid step is a seventh of the range, a factor of 1.4
    even for a sensor gain, too coarse for a signature as sharp as a gain on the DTE mean)."""
    per = {1: 7, 2: 5}.get(len(eff.params), 4)
    best = None
    for u in itertools.product(*[np.linspace(0.05, 0.95, per)] * len(eff.params)):
        vals = option | {p.name: from_unit(x, p.low, p.high, p.log)
                         for p, x in zip(eff.params, u, strict=True)}
        nui = with_level(rec, nuisance, eff, vals)
        cost = train_cost(rec, nui, eff, vals)
        if best is None or cost < best.train_rss:
            best = Candidate(eff.name, option, vals, nui, cost, len(eff.params))
    free = eff.bounds()
    free += ([("housing_mass_kg", *NUISANCE["housing_mass_kg"])]
             if accel_in(rec) and not rec.held else [])
    fitted, rss = least_squares(rec, eff, option, best.values | best.nuisance, free, SCREEN_NFEV)
    vals, nui = split_fitted(fitted)
    return dataclasses.replace(best, values=vals, nuisance=nui, train_rss=rss)


def wide(rec: Records, eff: Effect | None) -> bool:
    """Whether a search is the calibration with the model form over its whole range."""
    return eff is None and rec.settings.model_form


def explore(rec: Records, eff: Effect | None, c: Candidate, free_nuisance: list[str]
            ) -> list[Candidate]:
    """``c`` and a scrambled Sobol sample (``settings.explore`` points, twice as many for each
    effect parameter beyond the first; a measurement stage's extra points share the dynamic
    nuisance, and so the simulation, of the ``settings.explore`` others) over the effect's
    whole range and the dynamic nuisance within ``EXPLORE_SPAN`` (unit coordinates) of its
    declared values (the model form: of ``c``'s; in the calibration ``CALIBRATION_EXPLORE``
    times as many points, with ``loop.model_form``, :func:`wide`, the model form over its whole
    range; the default loop's run-out modulation around its declared value, none), ``m_h``
    levelled at each; best first.
    A missing effect drags the calibration (to the bounds, at worst), and least squares from a
    single start stays in its basin; the declared values are the prior that does not depend on
    the fit."""
    from scipy.stats import qmc  # imported on first use: a refusal need not wait for it
    params = eff.params if eff is not None else ()
    dyn = [n for n in free_nuisance if n in EXPLORED]
    # the scenario's nuisance (and support mode) around its declared values; the model form
    # over its whole range in the model-form calibration (its neutral value is no prior worth
    # holding to), around the calibration with an effect
    scn = rec.scenarios[0]
    prior = completed(c.nuisance, scn) | declared_nuisance(scn) | declared_modes(scn)
    # an unknown torque's wide prior: its whole range, around the configured torque
    span = {n: (0.5 if (wide(rec, eff) and n in MODEL_FORM) or n in TORQUE else EXPLORE_SPAN)
            for n in dyn}
    centres = {n: (0.5 if span[n] == 0.5 else to_unit(prior[n], *BOUNDS[n])) for n in dyn}
    dim = len(params) + len(dyn)
    # as many points per dimension of the effect whatever its parameter count: twice as many
    # for each parameter beyond the first (a pit's depth, face share and length from 32
    # points: 0.5 um, 0.74, 2.8 mm, held-out error 3.2; from 128: 22 um, 0.43, 1.18 mm, 1.25,
    # the true pit's 26 um, 0.41, 1.18 mm giving 1.24)
    per_dynamics = 2 ** max(len(params) - 1, 0)
    n_points = rec.settings.explore * (CALIBRATION_EXPLORE if eff is None else per_dynamics)
    pts = (qmc.Sobol(dim, seed=rec.settings.seed).random(n_points) if dim and n_points
           else np.empty((0, 0)))
    # a measurement stage leaves the dynamics alone: its extra points share the dynamic
    # nuisance of the first of each block (one simulation per block, :func:`responses`' cache),
    # the dynamics as widely explored as for any one-parameter effect
    block = per_dynamics if eff is not None and eff.model is None and dyn else 1
    pts[:, len(params):] = np.repeat(pts[::block, len(params):], block, axis=0)

    def point(u: np.ndarray) -> Candidate:
        vals = c.option | {p.name: from_unit(float(x), p.low, p.high, p.log)
                           for p, x in zip(params, u, strict=False)}
        nui = dict(c.nuisance)
        for n, x in zip(dyn, u[len(params):], strict=True):
            nui[n] = from_unit(float(np.clip(centres[n] + span[n] * (2 * x - 1), 0, 1)),
                               *BOUNDS[n])
        nui = with_level(rec, nui, eff, vals)
        return dataclasses.replace(c, values=vals, nuisance=nui,
                                   train_rss=train_cost(rec, nui, eff, vals))

    # a block on one thread: its points after the first find the simulation kept
    blocks = each(lambda b: [point(u) for u in b],
                  [pts[i:i + block] for i in range(0, len(pts), block)], "exploring")
    found = [c, *itertools.chain.from_iterable(blocks)]
    return sorted(found, key=lambda x: x.train_rss)  # stable: the first of equals leads


def search(rec: Records, eff: Effect | None, c: Candidate, free_nuisance: list[str]
           ) -> Candidate:
    """The model's (the declared one's, ``eff`` None, or with an effect) parameters fitted on
    the train records: the best explored start refined by least squares (a candidate: the best
    ``loop.starts``; the calibration with the model form: the best ``CALIBRATION_STARTS``; the
    lowest fit kept), the effect's parameters jointly with the identifiable nuisance. The
    declared model and every refined candidate get the same search."""
    if eff is None:
        n_starts = CALIBRATION_STARTS if wide(rec, eff) else 1
    else:
        n_starts = rec.settings.starts
    starts = explore(rec, eff, c, free_nuisance)[:n_starts]
    free = eff.bounds() if eff is not None else []
    free += [(n, *BOUNDS[n]) for n in free_nuisance]
    fits = [least_squares(rec, eff, s.option, s.values | s.nuisance, free,
                          rec.settings.max_nfev) for s in starts]
    k = min(range(len(fits)), key=lambda i: fits[i][1])
    vals, nui = split_fitted(fits[k][0])
    return dataclasses.replace(starts[k], values=vals, nuisance=nui, train_rss=fits[k][1],
                               refined=True)


def screened(settings: LoopSettings) -> tuple[str, ...]:
    """The dynamic parameters the calibration may free: the scenario's nuisance and the mesh
    modulation of the pinion's run-out (:data:`~physics.loop.model.declared.RUNOUT_MODULATION`); the
    rest of the model form with ``loop.model_form`` only."""
    return DYNAMIC_NUISANCE if settings.model_form else (*SCENARIO_DYNAMIC, *RUNOUT_MODULATION)


def calibrate(rec: Records, start: dict) -> tuple[dict, list[str]]:
    """Fit the declared nuisance parameters on the train records (from their declared
    values); returns the calibrated nuisance and the names of the free ones. ``m_h`` (and a
    declared support mode) scales and shapes every acceleration amplitude and is always free
    for acceleration records; a dynamic parameter that is not identifiable stays at its
    declared value. Records of unknown torque add its factor
    (:data:`~physics.loop.model.declared.TORQUE`, from 1)."""
    names = screened(rec.settings)
    if rec.torque_unknown is not None and rec.torque_unknown.any():
        start, names = {"torque_factor": 1.0} | start, (*names, *TORQUE)
    start = with_level(rec, completed(start, rec.scenarios[0]), None, {})
    free = identifiable(rec, start, names)
    if accel_in(rec):
        free += ["housing_mass_kg", *[n for n in SUPPORT if n in start]]
    c = Candidate("declared", {}, {}, start, train_cost(rec, start, None, {}), 0)
    return search(rec, None, c, free).nuisance, free


def recalibrated(rec: Records, calibration: dict, start: dict, free: list[str]
                 ) -> dict | None:
    """The declared model refitted on the train records by least squares from ``start`` (an
    adopted candidate's refitted nuisance), the same ``free`` parameters as the calibration;
    returned where it fits them better than ``calibration`` by more than
    :data:`RECALIBRATION_GAIN`, else None.

    The null test weighs a candidate against the declared model's best fit. A candidate is
    fitted jointly with the nuisance, so it may carry the nuisance into a basin the
    calibration's search did not reach; its gain is then the basin's, not the effect's,
    and the declared model refitted from there shows it (an independent clean bundle: a
    tip relief adopted, 5.71 -> 4.35, where the declared model from the tip relief's nuisance
    gives 4.67 and a train chi-square of 65,898 against the calibration's 91,529)."""
    if not free:
        return None
    fitted, rss = least_squares(rec, None, {}, start, [(n, *BOUNDS[n]) for n in free],
                                rec.settings.max_nfev)
    before = train_cost(rec, calibration, None, {})
    return split_fitted(fitted)[1] if rss < (1.0 - RECALIBRATION_GAIN) * before else None


def held(rec: Records, calibration: dict) -> tuple[Records, dict, list[str]]:
    """The unit's own calibration on its earliest records (``calibration``, of
    :func:`calibrate` there: ``reference=first:N`` or ``before:X``) held for its later records
    ``rec``: its damping, run-out, profile error, run-out modulation and measurement chain are
    the same unit's, so nothing recalibrated can absorb what changed since (a DTE gain, a
    friction the damping would take, a level the housing's ``m_h`` would). Returns ``rec``
    marked held (``m_h`` levelled by no candidate either), the nuisance and its free names:
    none, or the torque factor alone where the manifest leaves the torque unknown (an
    operating condition, not the unit's)."""
    rec = dataclasses.replace(rec, held=True)
    if rec.torque_unknown is None or not rec.torque_unknown.any():
        return rec, dict(calibration), []
    start = {"torque_factor": 1.0} | calibration
    c = Candidate("declared", {}, {}, start, train_cost(rec, start, None, {}), 0)
    return rec, search(rec, None, c, list(TORQUE)).nuisance, list(TORQUE)
