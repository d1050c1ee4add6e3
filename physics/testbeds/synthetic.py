"""Measured-like bundles with an undeclared effect from the project's own model, to try the loop
(:mod:`physics.loop`) without measurements.

:func:`make_bundle` simulates records of the full model with one effect of the library switched
on at a realistic size (its ``typical`` value times a seeded factor in [0.7, 1.4], within its
bounds: the transfer path's residue 0.7-1), with the declared nuisance parameters (and the
declared chain modes) moved off their defaults (each times a seeded factor in [0.6, 1.6]) and
white measurement noise at ``snr_db``. Records span the wear life of one operating case (wear
and cycles known), so the loop also has a wear estimate to judge.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd

from physics.dynamics.model import simulate
from physics.loop.effects import effect
from physics.loop.measured.bundle import check_bundle_target, write_bundle
from physics.loop.measured.records import shaft_rates
from physics.loop.measured.worn_states import mesh_stiffness, worn_models
from physics.loop.model.declared import declared_modes, declared_nuisance, modes_of, with_nuisance
from physics.params import Scenario
from physics.signals.measurement import add_noise, declared_chain, sensed


def make_bundle(path: str | Path, base: Scenario, effect_name: str | None, seed: int,
                quantity: str = "accel_m_s2", records: int = 10, duration_s: float = 1.0,
                cycles_max: float = 1.5e7, snr_db: float = 30.0,
                values: dict | None = None, onset: float | None = None) -> tuple[Path, dict]:
    """Write a bundle; return its path and the truth (effect, its values, the nuisance).
    ``values`` set some of the effect's values and options beyond the library's: e.g.
    ``{"order": 2.6}`` makes a torque ripple at a non-integer shaft order, which no candidate
    of the library has. ``onset`` (a share of the records' life, 0-1): the effect appears
    during the bundle's life, in the records of at least ``onset * cycles_max`` cycles only
    (the earlier ones are clean; the truth's ``with_effect`` lists which carry it). A ``path``
    that holds anything but an earlier bundle is refused before any work
    (:func:`~physics.loop.measured.bundle.check_bundle_target`); an earlier bundle there is
    replaced."""
    path = check_bundle_target(path)
    if onset is not None and not 0.0 < onset <= 1.0:
        raise ValueError(f"onset = {onset!r} must be a share of the life in (0, 1]; e.g. 0.3 "
                         "leaves the first 30 % of the records' cycles clean")
    given = dict(values or {})
    rng = np.random.default_rng([seed, 7])
    dyn = base.dynamics
    nuisance = {k: v * rng.uniform(0.6, 1.6)
                for k, v in (declared_nuisance(base) | declared_modes(base)).items()}
    eff = effect(effect_name) if effect_name else None
    values = {}
    if eff is not None:
        if quantity not in eff.quantities:
            raise ValueError(f"effect {effect_name} does not show in {quantity} records; use "
                             f"one of {eff.quantities}")
        option = eff.options[int(rng.integers(len(eff.options)))]
        values = dict(option) | {p.name: float(np.clip(p.typical * rng.uniform(0.7, 1.4),
                                                       p.low, p.high)) for p in eff.params}
        values |= given
    cycles = np.linspace(0.0, cycles_max, records)
    ms = mesh_stiffness(base.gear, base.material)
    by_cycles, root = worn_models(base, ms, list(cycles))
    declared = [with_nuisance(by_cycles[float(c)], nuisance, dyn.damping_ratio) for c in cycles]
    carries = (cycles >= onset * cycles_max if onset is not None
               else np.ones(records, bool)) if eff is not None else np.zeros(records, bool)
    models = declared
    if eff is not None and eff.model is not None:
        models = [eff.model(m, values) if on else m
                  for m, on in zip(declared, carries, strict=True)]
    run = dataclasses.replace(dyn, duration_s=duration_s, transient_s=0.1, phase_bins=16)
    def chain(ms):
        rows: list[np.ndarray] = [np.empty(0)] * len(ms)
        for periods in {m.periods for m in ms}:  # a pit's tables span a revolution: apart
            ks = [k for k, m in enumerate(ms) if m.periods == periods]
            for k, x in zip(ks, sensed(simulate([ms[k] for k in ks], run), quantity),
                            strict=True):
                rows[k] = x
        return declared_chain(np.stack(rows), quantity, nuisance["housing_mass_kg"],
                              fs=dyn.sample_rate_hz, **modes_of(nuisance))

    clean = chain(models)
    plain = chain(declared) if models is not declared else clean
    if eff is not None and eff.record is not None:
        clean = np.where(carries[:, None], eff.record(clean, dyn.sample_rate_hz, values), clean)
    x = add_noise(clean, snr_db, np.random.default_rng([seed, 8]))
    # the power the effect adds to the records against the noise's (-inf: it adds nothing)
    with np.errstate(divide="ignore"):
        effect_db = float(10 * np.log10(np.mean((clean - plain) ** 2) / np.mean((x - clean) ** 2)))
    names = [f"r{k:02d}" for k in range(records)]
    manifest = pd.DataFrame({
        "record": names, "quantity": quantity, "fs_hz": dyn.sample_rate_hz,
        "n1_rpm": base.operating.n1_rpm, "torque_Nm": base.operating.torque_Nm,
        "wear_mm": [root[float(c)] for c in cycles], "cycles": cycles, "split": "",
    })
    truth = {"effect": effect_name, "values": values, "nuisance": nuisance, "seed": seed,
             "f1_hz": shaft_rates(base)[0], "effect_to_noise_db": effect_db,
             "with_effect": [n for n, on in zip(names, carries, strict=True) if on]}
    return write_bundle(path, manifest, dict(zip(names, x, strict=True))), truth
