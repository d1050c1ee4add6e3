"""The declared measurement chain: what a sensor sees of the gear pair's response.

- DTE: the relative displacement on the line of action, ``x(t)`` of :mod:`physics.dynamics`.
- Housing acceleration: a rigid housing of effective mass ``m_h`` driven by the fluctuating mesh
  force, ``a(t) = (F_d(t) - mean F_d) / m_h`` (``dynamics.housing_mass_kg``), optionally through a
  declared bearing-support mode (:func:`support_path`, ``dynamics.support_hz``; 0, the default: a
  rigid support), and optionally on its mounting (:func:`housing_mount`, ``dynamics.mount_hz``; 0,
  the default: a free housing). Further structural resonances of the transfer path
  (:func:`transfer_path`) are not part of the declared chain of the loop (there they are an effect
  of :mod:`physics.loop.effects`); the dataset draws one per trajectory.
- Measurement noise: white Gaussian at a signal-to-noise ratio relative to the AC power.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from physics.dynamics.model import Response


def housing_acceleration(force: np.ndarray, housing_mass_kg: float) -> np.ndarray:
    """Rigid-housing acceleration [m/s^2] of a dynamic mesh force record ``(..., n)`` [N].

    Newton's second law for a rigid housing of effective mass ``m_h`` driven by the fluctuating
    part of the mesh force: ``a(t) = (F_d(t) - mean F_d) / m_h`` (module docstring; the mean
    force is a static load on the mounting).

    Parameters
    ----------
    force : numpy.ndarray
        Dynamic mesh force records along the last axis (..., n) [N].
    housing_mass_kg : float
        Effective housing mass ``m_h`` [kg], > 0 (``dynamics.housing_mass_kg``).

    Returns
    -------
    numpy.ndarray
        Housing acceleration (..., n) [m/s^2], zero mean along the last axis.

    Raises
    ------
    ValueError
        For a housing mass that is not positive.

    Examples
    --------
    A mesh force of 1000 N fluctuating by +-10 N on a housing of 20 kg: ``a = F / m = 10 / 20
    = 0.5 m/s^2`` about zero.

    >>> force = np.array([990.0, 1010.0, 990.0, 1010.0])  # [N]
    >>> housing_acceleration(force, 20.0).tolist()  # [m/s^2]
    [-0.5, 0.5, -0.5, 0.5]
    >>> housing_acceleration(force, 0.0)
    Traceback (most recent call last):
        ...
    ValueError: housing_mass_kg = 0.0 must be > 0 (kg)
    """
    if not housing_mass_kg > 0:
        raise ValueError(f"housing_mass_kg = {housing_mass_kg!r} must be > 0 (kg)")
    return (force - force.mean(axis=-1, keepdims=True)) / housing_mass_kg


def sensed(resp: Response, quantity: str) -> np.ndarray:
    """The response a record of ``quantity`` is made from: DTE for ``dte_m``, the dynamic mesh
    force for housing acceleration (``accel_m_s2``), one row per simulated model."""
    return resp.dte if quantity == "dte_m" else resp.force


def declared_chain(x: np.ndarray, quantity: str, housing_mass_kg: float, *,
                   fs: float | None = None, support_hz: float = 0.0,
                   support_damping: float = 0.05, mount_hz: float = 0.0,
                   mount_damping: float = 0.1) -> np.ndarray:
    """The declared chain applied to :func:`sensed`: DTE as it is, the force through the
    bearing support (``support_hz`` > 0, sampled at ``fs``; :func:`support_path`) and the rigid
    housing, on its mounting (``mount_hz`` > 0; :func:`housing_mount`)."""
    if quantity == "dte_m":
        return x
    if (support_hz > 0 or mount_hz > 0) and fs is None:
        raise ValueError("a declared support or mount mode needs the record's sampling rate fs")
    if support_hz > 0:
        x = support_path(x, fs, support_hz, support_damping)
    a = housing_acceleration(x, housing_mass_kg)
    return housing_mount(a, fs, mount_hz, mount_damping) if mount_hz > 0 else a


def transmissibility(f: np.ndarray, fn_hz: float, zeta: float) -> np.ndarray:
    """Complex force transmissibility of a single-degree-of-freedom support at frequencies
    ``f`` [Hz]: ``(1 + 2 i zeta r) / (1 - r^2 + 2 i zeta r)``, ``r = f / fn`` (Rao, Mechanical
    Vibrations, 5th ed., 3.6; the analog form of :func:`transfer_path`)."""
    r = np.asarray(f, float) / fn_hz
    return (1 + 2j * zeta * r) / (1 - r**2 + 2j * zeta * r)


def support_path(x: np.ndarray, fs: float, fn_hz: float, zeta: float) -> np.ndarray:
    """The mesh force as the housing feels it through the bearing support: the pinion body on
    its bearings is a single-degree-of-freedom mode (shaft bending in series with the rolling
    bearings' radial stiffness, the body's mass), so the bearing force is the mesh force times
    :func:`transmissibility`. Applied along the last axis in the frequency domain (one period
    of ``x`` assumed: accurate where the mode's decay time ``1 / (2 pi zeta fn)``, 2.6 ms at
    2 kHz and 0.03, is short against the record), so ``fn_hz`` may lie anywhere, also above
    ``fs / 2`` where the mode only raises the band below it; as ``fn_hz`` grows the support
    becomes rigid (identity)."""
    return _through_mode(x, fs, fn_hz, zeta, "support", lambda t: t)


def housing_mount(a: np.ndarray, fs: float, fn_hz: float, zeta: float) -> np.ndarray:
    """The free housing's acceleration ``a`` as the housing on its mounting moves: a mass on a
    spring and damper driven by a force, ``s^2 / (s^2 + 2 zeta wn s + wn^2)`` times the free
    mass's (Rao, Mechanical Vibrations, 5th ed., 3.4): the free mass's above the mounting mode
    ``fn_hz``, stiffness-controlled (lowered by ``(f / fn)^2``) below it, where the shaft
    orders and drive-line orders lie; it is ``1 -`` :func:`transmissibility`. Applied along the
    last axis in the frequency domain (one period of ``a`` assumed, as :func:`support_path`)."""
    return _through_mode(a, fs, fn_hz, zeta, "mount", lambda t: 1 - t)


def _through_mode(x: np.ndarray, fs: float, fn_hz: float, zeta: float, name: str,
                  response) -> np.ndarray:
    """``x`` through ``response`` of the single-degree-of-freedom :func:`transmissibility` at
    ``fn_hz``, ``zeta``, along its last axis in the frequency domain."""
    if not fn_hz > 0 or not 0 < zeta < 1:
        raise ValueError(f"{name} fn_hz = {fn_hz!r} must be > 0 and zeta = {zeta!r} in (0, 1)")
    n = x.shape[-1]
    t = transmissibility(np.fft.rfftfreq(n, 1 / fs), fn_hz, zeta)
    return np.fft.irfft(np.fft.rfft(x, axis=-1) * response(t), n, axis=-1)


def transfer_path(x: np.ndarray, fs: float, fn_hz: float, zeta: float,
                  residue: float = 1.0) -> np.ndarray:
    """A structural mode between the mesh and the sensor: the rigid path plus one mode of the
    accelerance, ``1 - g s^2 / (s^2 + 2 zeta wn s + wn^2)`` (Ewins, Modal Testing, 2nd ed.,
    2000, 2.3 and 2.7: a rigid body's accelerance plus one mode's, ``g = -m A_r`` the mode's
    modal constant over the rigid one), discretised by the bilinear transform pre-warped at
    ``fn_hz``, applied along the last axis of ``x``. ``residue`` g = 1 (the default) is the
    base-excited transmissibility ``(2 zeta wn s + wn^2) / (...)`` of a sensor on a
    sub-structure (Rao, Mechanical Vibrations, 5th ed., 3.6): it passes the band below the
    mode and cuts the band above it; g < 0 is a housing mode in parallel with the rigid path,
    whose level is ``1`` below the mode and ``1 - g`` above it. At the mode the gain is
    ``sqrt(1 + g^2 / (4 zeta^2))``, about ``|g| / (2 zeta)``."""
    if not 0 < fn_hz < fs / 2 or not 0 < zeta < 1:
        raise ValueError(f"transfer path fn_hz = {fn_hz!r} must lie in (0, fs/2 = {fs / 2:g}) and "
                         f"zeta = {zeta!r} in (0, 1)")
    from scipy import signal  # imported on first use: a refusal need not wait for it

    return signal.lfilter(*_resonance_filter(float(fs), float(fn_hz), float(zeta),
                                             float(residue)), x, axis=-1)


@lru_cache(maxsize=256)
def _resonance_filter(fs: float, fn_hz: float, zeta: float, residue: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """The digital filter of :func:`transfer_path` (``scipy.signal.bilinear`` takes a
    millisecond; the loop applies one path to every record of an evaluation)."""
    from scipy import signal

    wn = 2 * fs * math.tan(math.pi * fn_hz / fs)
    return signal.bilinear([1 - residue, 2 * zeta * wn, wn**2], [1.0, 2 * zeta * wn, wn**2], fs)


def add_noise(x: np.ndarray, snr_db: float, rng: np.random.Generator) -> np.ndarray:
    """White Gaussian noise at ``snr_db`` relative to each signal's AC power (mean kept).

    ``snr_db = inf`` returns ``x`` unchanged.
    """
    if not np.isfinite(snr_db):
        return x
    ac = x - x.mean(axis=-1, keepdims=True)
    power = np.mean(ac**2, axis=-1, keepdims=True)
    return x + rng.standard_normal(x.shape) * np.sqrt(power / 10 ** (snr_db / 10))
