"""The declared measurement chain: what a sensor sees of the gear pair's response.

- DTE: the relative displacement on the line of action, ``x(t)`` of :mod:`physics.dynamics`.
- Housing acceleration: a rigid housing of effective mass ``m_h`` driven by the fluctuating mesh
  force, ``a(t) = (F_d(t) - mean F_d) / m_h`` (``dynamics.housing_mass_kg``). Structural
  resonances of the transfer path are not part of the declared chain; they are an effect of
  :mod:`physics.effects`.
- Measurement noise: white Gaussian at a signal-to-noise ratio relative to the AC power.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from physics.dynamics.model import Response


def housing_acceleration(force: np.ndarray, housing_mass_kg: float) -> np.ndarray:
    """Rigid-housing acceleration [m/s^2] of a dynamic mesh force record ``(..., n)`` [N]."""
    if not housing_mass_kg > 0:
        raise ValueError(f"housing_mass_kg = {housing_mass_kg!r} must be > 0 (kg)")
    return (force - force.mean(axis=-1, keepdims=True)) / housing_mass_kg


def sensed(resp: Response, quantity: str) -> np.ndarray:
    """The response a record of ``quantity`` is made from: DTE for ``dte_m``, the dynamic mesh
    force for housing acceleration (``accel_m_s2``), one row per simulated model."""
    return resp.dte if quantity == "dte_m" else resp.force


def declared_chain(x: np.ndarray, quantity: str, housing_mass_kg: float) -> np.ndarray:
    """The declared chain applied to :func:`sensed`: DTE as it is, the force through the rigid
    housing."""
    return x if quantity == "dte_m" else housing_acceleration(x, housing_mass_kg)


def add_noise(x: np.ndarray, snr_db: float, rng: np.random.Generator) -> np.ndarray:
    """White Gaussian noise at ``snr_db`` relative to each signal's AC power (mean kept).

    ``snr_db = inf`` returns ``x`` unchanged.
    """
    if not np.isfinite(snr_db):
        return x
    ac = x - x.mean(axis=-1, keepdims=True)
    power = np.mean(ac**2, axis=-1, keepdims=True)
    return x + rng.standard_normal(x.shape) * np.sqrt(power / 10 ** (snr_db / 10))
