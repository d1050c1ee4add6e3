"""The model discrepancy: what the calibrated declared model misses beyond the noise, per
entry family and group (:func:`discrepancy_sd`), and what it lets a candidate explain by
chance (:func:`discrepancy_allowance`).

It is estimated on the train residuals of the calibrated declared model; with it the RMS
standardised residual is about 1 where model and measurement agree up to noise and the model's
known form error. It enters the judgement (held-out errors, the null test), not the fits: a
discrepancy estimated on records where an effect is missing is large exactly in that effect's
entries and would down-weight them in its fit (a tip relief of 16 um in the project's own
records was fitted at 11 um with it).
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np

from physics.loop.measured.records import Group, Records, by_group
from physics.loop.model.comparison import residuals_db
from physics.loop.model.simulation import model_signals


def entry_family(name: str) -> str:
    """The family of a signature entry: its name without its numbers (one kind of line at
    every mesh harmonic, e.g. ``line_mesh+p`` for all first and second upper pinion sidebands;
    all bands; each statistic alone)."""
    return re.sub(r"\d+", "", name)


def discrepancy_sd(groups: list[Group], res_db: list[np.ndarray], prior_count: float
                   ) -> list[np.ndarray]:
    """Model-discrepancy standard deviation [dB] of each entry of each group, from the train
    residuals of the calibrated declared model (``res_db[k]``: group k's records x entries,
    possibly none).

    The residual is read as ``r = delta + eps``: a model discrepancy ``delta`` (Kennedy &
    O'Hagan, J. R. Stat. Soc. B 63 (2001) 425), independent of the measurement noise ``eps``
    whose variance is the segment scatter ``entry_sd^2``, so ``E r^2 = entry_sd^2 + d^2``.
    Method of moments per entry family (:func:`entry_family`) of each group: ``v`` the mean of
    ``r^2 - entry_sd^2`` over its ``m`` residuals; shrunk towards the pooled value ``v0`` (the
    same mean over every train residual of the bundle) as the posterior scale of a normal
    variance under a scaled-inverse-chi^2 prior of ``prior_count`` degrees of freedom
    (Gelman et al., Bayesian Data Analysis, 3rd ed., 2013, 2.6): ``d^2 = max(0, (nu0 v0 +
    m v) / (nu0 + m))``, ``v0`` clipped at zero. A family of many entries is estimable from
    few records; a group without train records gets the pooled value.
    Without this term a calibration against data from a different model form is pulled by
    the discrepancy and any effect that soaks part of it looks significant (Brynjarsdottir &
    O'Hagan, Inverse Problems 30 (2014) 114007).
    """
    excess = [r**2 - g.entry_sd**2 for g, r in zip(groups, res_db, strict=True)]
    pooled = np.concatenate([e.ravel() for e in excess])
    v0 = max(float(pooled.mean()), 0.0) if pooled.size else 0.0
    out = []
    for g, e in zip(groups, excess, strict=True):
        fam = np.array([entry_family(n) for n in g.names])
        d2 = np.full(len(g.names), v0)
        for f in np.unique(fam) if e.size else ():
            cells = e[:, fam == f]
            d2[fam == f] = (prior_count * v0 + cells.sum()) / (prior_count + cells.size)
        out.append(np.sqrt(np.maximum(d2, 0.0)))
    return out


def with_discrepancy(rec: Records, nuisance: dict) -> Records:
    """``rec`` with the discrepancy of :func:`discrepancy_sd` estimated on its train records
    for the declared model at ``nuisance``."""
    res = residuals_db(rec, rec.train, model_signals(rec, rec.train, nuisance, None, {}))
    pos = by_group(rec, rec.train)
    per_group = [np.array([res[j] for j in pos.get(k, [])]).reshape(-1, len(g.names))
                 for k, g in enumerate(rec.groups)]
    sds = discrepancy_sd(rec.groups, per_group, rec.settings.discrepancy_prior)
    return dataclasses.replace(rec, groups=[dataclasses.replace(g, discrepancy_sd=d)
                                            for g, d in zip(rec.groups, sds, strict=True)])


def discrepancy_allowance(k: int, n_candidates: int, rate: float) -> float:
    """Standardised sum of squares per held-out record that the model discrepancy lets a
    candidate of ``k`` parameters explain by chance.

    Under the discrepancy model of :func:`discrepancy_sd` (Gaussian, independent between
    entries, shared by the records of a group, so that what a fit absorbs on the train records
    it also absorbs on the held-out ones), least squares of k parameters removes from a
    record's standardised sum of squares at most the projection of ``delta + eps`` on k
    directions: a chi-square of k degrees of freedom. Its upper ``rate / n_candidates``
    quantile, Bonferroni over the candidates, bounds the chance that any of them passes by
    ``rate``, the false-add rate per bundle (so each may be judged, the best passing one
    adopted).
    """
    from scipy.stats import chi2  # imported on first use: a refusal need not wait for it
    return float(chi2.isf(rate / max(n_candidates, 1), max(k, 1)))
