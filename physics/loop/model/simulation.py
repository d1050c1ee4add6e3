"""The model's records: the declared model (with the calibrated nuisance, an effect, the
run-out's mesh modulation) simulated for records of the bundle, one analysis segment each,
through the measurement chain with each record's noise level (read off its spectral floor,
:func:`physics.signals.order_analysis.white_noise_std`; seeded per record)."""

from __future__ import annotations

import dataclasses
import functools
import threading

import numpy as np

from physics.dynamics.model import PairModel, simulate
from physics.dynamics.model_form import with_modulation
from physics.loop.effects import Effect
from physics.loop.measured.records import Records
from physics.loop.model.declared import (
    DYNAMIC_NUISANCE,
    TORQUE,
    modes_of,
    with_nuisance,
    with_torque,
)
from physics.signals.measurement import declared_chain, sensed

#: simulations kept by :func:`responses` (candidates fitted on parallel threads share them)
CACHE_SIZE = 256
_CACHE_LOCK = threading.Lock()
#: the model's records are integrated from this many decay times of the mesh mode before the
#: record's start (:func:`physics.dynamics.model.simulate`'s ``settle``), not from t = 0: the
#: start's free vibration has fallen to e^-30 (1e-13) there, the record's start phase is kept,
#: and at the declared damping (7 %) the integration is a fifth to a third shorter
SETTLE_DECAYS = 30.0


def responses(rec: Records, idx: np.ndarray, nuisance: dict, eff: Effect | None,
              values: dict, models: list[PairModel] | None = None) -> list[np.ndarray]:
    """Simulated DTE or mesh force (by each record's quantity) of records ``idx``, one analysis
    segment each.

    Memoised on the parameters the dynamics see (``rec.cache``): a change of the measurement
    chain's parameters (``m_h``, a transfer path, a sensor) reuses the simulation.
    """
    dynamic = eff is not None and eff.model is not None
    key = None
    if models is None:
        key = (tuple(int(i) for i in idx),
               tuple(nuisance.get(n) for n in (*DYNAMIC_NUISANCE, *TORQUE)),
               (eff.name, tuple(sorted(values.items()))) if dynamic else None)
        with _CACHE_LOCK:
            hit = rec.cache.get(key)
        if hit is not None:
            return hit
    man = rec.bundle.manifest
    base_ratio = rec.scenarios[0].dynamics.damping_ratio
    ms = [with_nuisance(m, nuisance, base_ratio)
          for m in (models if models is not None else [rec.models[i] for i in idx])]
    unknown = rec.torque_unknown
    if unknown is not None:  # before an effect: a ripple's share is of this torque
        ms = [with_torque(m, nuisance) if unknown[i] else m for m, i in zip(ms, idx,
                                                                            strict=True)]
    if dynamic:
        ms = [eff.model(m, values) for m in ms]
    ms = [with_modulation(m, nuisance) for m in ms]
    out: list[np.ndarray] = [np.empty(0)] * len(idx)
    fs_all = man.fs_hz.to_numpy(float)[idx]
    quantity = man.quantity.to_numpy()[idx]
    for fs in np.unique(fs_all):
        sel = np.flatnonzero(fs_all == fs)
        dyn = dataclasses.replace(rec.scenarios[0].dynamics, sample_rate_hz=float(fs),
                                  duration_s=rec.settings.segment_s,
                                  transient_s=rec.settings.transient_s, phase_bins=16,
                                  step_factor=rec.settings.step_factor)
        resp = simulate([ms[k] for k in sel], dyn, settle=SETTLE_DECAYS)
        for j, k in enumerate(sel):
            out[k] = sensed(resp, quantity[k])[j]
    if key is not None:
        for x in out:
            x.flags.writeable = False  # shared by every later call with this key
        with _CACHE_LOCK:
            if len(rec.cache) >= CACHE_SIZE:
                rec.cache.pop(next(iter(rec.cache)))  # the oldest entry
            rec.cache[key] = out
    return out


def model_signals(rec: Records, idx: np.ndarray, nuisance: dict, eff: Effect | None,
                  values: dict, models: list[PairModel] | None = None) -> list[np.ndarray]:
    """Simulated records (one analysis segment each) of records ``idx`` through the chain:
    rigid-housing acceleration (or DTE), the effect's measurement stage on the quantities it
    acts on, the record's noise."""
    man = rec.bundle.manifest
    raw = responses(rec, idx, nuisance, eff, values, models)
    quantity = man.quantity.to_numpy()[idx]
    fs_all = man.fs_hz.to_numpy(float)[idx]
    out: list[np.ndarray] = [np.empty(0)] * len(idx)
    # the chain along the last axis: records of one quantity, rate and length at once
    kinds = [(q, f, x.size) for q, f, x in zip(quantity, fs_all, raw, strict=True)]
    for kind in dict.fromkeys(kinds):
        q, fs, _ = kind
        sel = [k for k, other in enumerate(kinds) if other == kind]
        x = declared_chain(np.stack([raw[k] for k in sel]), q, nuisance["housing_mass_kg"],
                           fs=fs, **modes_of(nuisance))
        if eff is not None and eff.record is not None and q in eff.quantities:
            x = eff.record(x, fs, values)
        for row, k in zip(x, sel, strict=True):
            i = int(idx[k])
            out[k] = row + rec.noise_std[i] * record_noise(rec.settings.seed, i, row.size)
    return out


@functools.lru_cache(maxsize=1024)
def record_noise(seed: int, i: int, n: int) -> np.ndarray:
    """Standard white noise of record ``i``'s model records (common numbers: the same in every
    evaluation), read-only."""
    x = np.random.default_rng([seed, i]).standard_normal(n)
    x.flags.writeable = False
    return x


def is_accel(rec: Records, idx: np.ndarray) -> np.ndarray:
    """Which of records ``idx`` are housing acceleration (the quantity ``m_h`` acts on)."""
    return rec.bundle.manifest.quantity.to_numpy()[idx] == "accel_m_s2"


def accel_in(rec: Records) -> bool:
    return bool(is_accel(rec, np.arange(len(rec.models))).any())
