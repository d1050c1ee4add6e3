"""The declared measurement chain: what a sensor sees of the gear pair's response.

- DTE: the relative displacement on the line of action, ``x(t)`` of :mod:`physics.dynamics`.
- Housing acceleration: a rigid housing of effective mass ``m_h`` driven by the fluctuating mesh
  force, ``a(t) = (F_d(t) - mean F_d) / m_h`` (``dynamics.housing_mass_kg``). Structural
  resonances of the transfer path are not part of the declared chain; they are an effect of
  :mod:`physics.effects`.
- Measurement noise: white Gaussian at a signal-to-noise ratio relative to the AC power.
"""

from __future__ import annotations

import numpy as np


def housing_acceleration(force: np.ndarray, housing_mass_kg: float) -> np.ndarray:
    """Rigid-housing acceleration [m/s^2] of a dynamic mesh force record ``(..., n)`` [N]."""
    if not housing_mass_kg > 0:
        raise ValueError(f"housing_mass_kg = {housing_mass_kg!r} must be > 0 (kg)")
    return (force - force.mean(axis=-1, keepdims=True)) / housing_mass_kg


def add_noise(x: np.ndarray, snr_db: float, rng: np.random.Generator) -> np.ndarray:
    """White Gaussian noise at ``snr_db`` relative to each signal's AC power (mean kept).

    ``snr_db = inf`` returns ``x`` unchanged.
    """
    if not np.isfinite(snr_db):
        return x
    ac = x - x.mean(axis=-1, keepdims=True)
    power = np.mean(ac**2, axis=-1, keepdims=True)
    return x + rng.standard_normal(x.shape) * np.sqrt(power / 10 ** (snr_db / 10))
