"""The loop bench's bundle sets and readings (``bench/bench_loop.py``): the scenario each
generator's bundles are analysed with, the sister unit's form reference, and what the bench
reads off the reports (where a bundle's residual stands out from the model-form error, whether
halving the error is attainable at all, the first round's judged candidate)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd

from physics.loop import LoopSettings, read_bundle
from physics.loop.model.discrepancy import entry_family
from physics.loop.search.form_error import FormReference, form_reference
from physics.params import scenario_from_config
from physics.testbeds.independent_simulator import (
    SISTER_UNIT,
    IndependentPair,
    make_independent_bundle,
)
from physics.testbeds.synthetic import make_bundle


def base_scenario(generator: str = "own"):
    """Case 3; for the independent simulator's gearbox with its bearing-support mode declared
    as a user would estimate it from the drawings: ``sqrt(k_b / m_b)`` of the shaft in bending
    in series with the bearings' stated stiffness and the pinion body's mass (2.5 kHz; the
    simulator's mode, coupled with the mesh, lies near 2.2 kHz), and the housing's mode on its
    mounting as the mounts' data sheet and the housing's mass give it (150 Hz)."""
    if generator == "own":
        return scenario_from_config({"case": 3})
    pair = IndependentPair()
    support = math.sqrt(pair.bearing_stiffness / pair.body_mass) / (2 * math.pi)
    return scenario_from_config({"case": 3, "dynamics": {
        "support_hz": support, "mount_hz": pair.mount_frequency_hz}})


#: the seed of the sister unit of ``--reference`` (the independent simulator's is
#: :data:`~physics.testbeds.independent_simulator.SISTER_UNIT`; the own generator draws a
#: unit's nuisance from its seed)
SISTER_SEED = 300


#: the quantities of a bundle with both sensors (``--both``), and its label
BOTH = ("dte_m", "accel_m_s2")


def sister_reference(generator: str, quantities: tuple[str, ...], records: int, tmp: Path
                     ) -> FormReference:
    """The declared model's form error on the sister unit's clean records of ``quantities``
    (:data:`~physics.testbeds.independent_simulator.SISTER_UNIT`), calibrated as the loop
    calibrates."""
    base = base_scenario(generator)
    folder = tmp / f"sister_{'_'.join(quantities)}"
    if generator == "independent":
        path, _ = make_independent_bundle(folder, None, quantities=quantities, seed=SISTER_SEED,
                                          pair=IndependentPair(**SISTER_UNIT))
    else:
        path, _ = make_bundle(folder, base, None, SISTER_SEED, quantity=quantities[0],
                              records=records)
    return form_reference(read_bundle(path), base, LoopSettings(seed=SISTER_SEED))


def report_label(generator: str, name: str | None, seed: int, quantity: str) -> str:
    """The folder of one bundle's report under ``<out>/reports``."""
    return f"{generator}_{name or 'none'}_{seed}_{quantity}"


def residual_cells(report: Path) -> dict[tuple[str, str], float]:
    """A bundle's residual before any effect (measured minus calibrated declared model, the
    mean over the held-out records, ``residual_before`` of report.json), RMS [dB] per group
    and cell: each entry family (:func:`physics.loop.model.discrepancy.entry_family`: one kind of
    line at every mesh harmonic) and each mesh harmonic with its sidebands (every kind of line
    at one harmonic: where a structural mode shows)."""
    out = {}
    for group, res in json.loads(report.read_text())["residual_before"].items():
        cells: dict[str, list[float]] = {}
        for name, value in res.items():
            cells.setdefault(f"family {entry_family(name)}", []).append(value)
            harmonic = re.match(r"line_mesh(\d+)", name)
            if harmonic:
                cells.setdefault(f"mesh harmonic {harmonic.group(1)}", []).append(value)
        out |= {(group, c): float(np.sqrt(np.mean(np.square(v)))) for c, v in cells.items()}
    return out


def visibility(runs: pd.DataFrame, out: Path) -> pd.DataFrame:
    """Where each bundle's residual stands out from the model-form error: per group and cell
    (:func:`residual_cells`), its RMS residual less the largest of the other clean bundles of
    its quantity; the cell with the largest excess and that excess [dB]. The clean bundles'
    own rows give the chance level (one clean bundle against the others). An effect whose
    bundle stands out no more than a clean one leaves its residual where the declared model's
    form error already is: no rule on these residuals can name it and not name the form error
    of a clean bundle too."""
    cells = {i: residual_cells(out / "reports" / report_label(
        r.generator, None if r.truth == "none" else r.truth, r.seed, r.quantity) / "report.json")
        for i, r in runs.iterrows()}
    clean = runs.truth == "none"
    rows = []
    for i, r in runs.iterrows():
        others = [cells[j] for j in runs.index[clean & (runs.quantity == r.quantity)] if j != i]
        if not others:
            continue
        ref = pd.DataFrame(others).max()
        excess = (pd.Series(cells[i]) - ref).dropna()
        group, cell = excess.idxmax()
        rows.append({"truth": r.truth, "seed": r.seed, "quantity": r.quantity, "group": group,
                     "cell": cell, "excess_db": round(float(excess.max()), 1)})
    return pd.DataFrame(rows)


def attainable(runs: pd.DataFrame) -> pd.DataFrame:
    """Whether halving the held-out error is within reach on each bundle: ``clean_floor``, the
    smallest held-out error of the clean bundles of its quantity (what the declared model
    misses on records without any effect: the form error and noise a perfect fit of the effect
    leaves, at best), and ``halving_attainable``, its error before at least twice that. Where
    the effect adds less than the form error already is, no fit of it can halve the error.
    ``beyond_chance``: its error before exceeds every clean bundle's of its quantity (the clean
    floor's chance level: the largest form error of the clean draws); a bundle below it cannot
    be told from a clean one by its error alone."""
    clean = runs[runs.truth == "none"].groupby("quantity").error_before
    floor = runs.quantity.map(clean.min())
    return runs.assign(clean_floor=floor, halving_attainable=runs.error_before >= 2 * floor,
                       beyond_chance=runs.error_before > runs.quantity.map(clean.max()))


def best_candidate(r) -> dict:
    """The first round's judged candidate (the adopted one, else the best by held-out error)
    and the null test's figures on it: why it was or was not adopted (own-entry error
    before/after, the least sum of squares it explains per held-out record over the groups
    against what the discrepancy allows, its BIC change, the share of its change the free
    nuisance cannot mimic); the other candidates that pass as well (``;``-separated)."""
    best = r["ranking"][r["verdicts"][0]["rank"]]
    return {"best": best["effect"], "own_before": best["own_entries_error"][0],
            "own_after": best["own_entries_error"][1],
            "explained": min(best["explained"].values(), default=0.0),
            "allowed": r["decision_rule"]["allowed"], "delta_bic": best["delta_bic"],
            "separable": best["separable"],
            "also_passing": ";".join(c["effect"] for c in r["verdicts"][0]["also_passing"])}
