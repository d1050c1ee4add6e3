"""The torsional model's form uncertainty: the mesh's stiffness level, double/single ratio and
resonance, and the backlash, as factors on a built :class:`~physics.dynamics.model.PairModel`;
and the once-per-revolution mesh modulation of the pinion's run-out (:func:`with_modulation`),
an edit of the model's stiffness tables.

Two reasonable models of one gear pair differ by more than measurement noise: the
potential-energy stiffness of :mod:`physics.gear.stiffness` against ISO 6336-1 or a finite-element
model, the gear blanks' inertias against the shafts, hubs and couplings that turn with them. The
factors below are that uncertainty, neutral at 1 (the declared model bit for bit). The
scenario states them (``dynamics.stiffness_factor`` ... , :class:`physics.params.Dynamics`), so
the wear evolution and the records of a dataset trajectory see the same model; the measured-data
loop calibrates them (:mod:`physics.loop.search.fit`, ``loop.model_form``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

#: the factors' names (each neutral at 1)
FACTORS = ("stiffness_factor", "double_contact_factor", "resonance_factor")


def with_model_form(m, v: dict):
    """The :class:`~physics.dynamics.model.PairModel` ``m`` with the form factors and backlash
    of ``v`` (missing names are neutral; at the neutral values ``m`` itself; this module
    imports nothing of the model, which builds with it).

    - ``stiffness_factor`` ``s_k`` multiplies both pairs' stiffness. The declared stiffness
      is the potential-energy method's (:mod:`physics.gear.stiffness`); ISO 6336-1 (2006, cl.
      9) gives ``c' = 14 N/(mm um)`` times correction factors for the same pair, finite-element
      and measured values scatter by some 10-30 % about both, and a real mount puts shaft
      and bearing compliance in series with the mesh.
    - ``double_contact_factor`` ``r`` multiplies the pairs' stiffness in the double-contact
      zone (where pair B is on the path) and so the double/single stiffness ratio: ISO
      6336-1's lumped mean ``c_gamma = c' (0.75 eps_alpha + 0.25)`` implies one ratio, the
      potential-energy method another, and a loaded tooth touches early (extended contact),
      which lengthens the double zone's effect; the ratio sets the mesh harmonics' level.
    - ``resonance_factor`` ``f_r`` multiplies the mesh resonance ``sqrt(k_mean / m_e)``
      (thesis 3.3) through the inertias: both are scaled by ``s_m = (k_mean' / k_mean) /
      f_r^2`` (``k_mean'`` the mean stiffness after the two factors above), so ``m_e`` by
      ``s_m``. The declared inertias are the gear blanks alone, while shafts, hubs and
      couplings turn with them, and shaft and bearing compliance couple the torsional mode
      with lateral ones: the mesh resonance is the least certain frequency of the model.
      It is a factor on the resonance rather than on the mass so that the stiffness level
      (quasi-static amplitudes) and the resonance (dynamic amplification) are near-orthogonal
      directions for a fit.
    - the damping ``c`` is rescaled by ``sqrt(k_mean' m_e' / (k_mean m_e))`` so that the
      damping ratio keeps its meaning, ``c = 2 zeta sqrt(k_mean m_e)``.
    - ``half_backlash_um`` replaces the half backlash: it opens the dead zone where flanks
      separate and, in the declared DTE (measured from the centre of the backlash), sets the
      DTE's mean; measured DTE is referred to flank contact or to an arbitrary encoder zero,
      so the DTE's datum is as uncertain as the backlash itself.
    """
    s_k = float(v.get("stiffness_factor", 1.0))
    f_r = float(v.get("resonance_factor", 1.0))
    r = float(v.get("double_contact_factor", 1.0))
    backlash = v.get("half_backlash_um")
    if backlash is not None and float(backlash) * 1e-6 == m.half_backlash:
        backlash = None  # the declared value: nothing to change
    if s_k == 1.0 and f_r == 1.0 and r == 1.0 and backlash is None:
        return m
    double = m.k_b > 0
    k_a = m.k_a * np.where(double, r, 1.0) * s_k
    k_b = m.k_b * r * s_k
    stiffer = float(np.mean(k_a + k_b)) / float(np.mean(m.k_a + m.k_b))
    s_m = stiffer / f_r**2
    j1, j2 = m.inertias
    k_off = None if m.k_off is None else m.k_off * r * s_k  # off-path: where two pairs touch
    return dataclasses.replace(
        m, k_a=k_a, k_b=k_b, k_off=k_off, mass=m.mass * s_m, inertias=(j1 * s_m, j2 * s_m),
        damping=m.damping * math.sqrt(stiffer * s_m),
        half_backlash=m.half_backlash if backlash is None else float(backlash) * 1e-6)


def revolution_tables(m):
    """``m`` with its per-cell tables (stiffness, gaps, friction factors) tiled over one pinion
    revolution, ``z1`` mesh periods: the form a model needs for a feature that differs from
    tooth to tooth. ``m`` itself if it spans a revolution already."""
    z1 = round(m.omega_mesh / m.omega1)
    if m.periods == z1:
        return m
    if m.periods != 1:
        raise ValueError(f"tables of {m.periods} mesh periods: one period or one pinion "
                         f"revolution ({z1} periods) expected")
    names = [k for k in ("k_a", "k_b", "g_a", "g_b", "lam_a", "lam_b", "k_off", "g_off")
             if getattr(m, k) is not None]
    return dataclasses.replace(m, periods=z1, **{k: np.tile(getattr(m, k), (1,) * (getattr(
        m, k).ndim - 1) + (z1,)) for k in names})


def with_modulation(m, v: dict):
    """A once-per-pinion-revolution modulation of the mesh stiffness, ``k_i(t) (1 + mu
    cos(w1 t + phi))`` (``mesh_modulation`` ``mu``, ``modulation_phase_rad`` ``phi``; ``mu`` = 0
    or missing: ``m`` itself).

    Radial run-out of the pinion (ISO 1328-2:2020, ``F_r``) and its wobble change the centre
    distance and the load distribution across the face once per revolution, and with them
    the length of the contact lines that carry the load, so the mesh stiffness; the declared
    model holds the run-out only as a line-of-action error (thesis 3.3), which is inert in
    the torsional model. Lumped models of such errors modulate the mesh once per revolution
    in amplitude (Inalpolat & Kahraman, J. Sound Vib. 329 (2010) 371; the sidebands ``k f_m
    +- f_1`` of Randall, J. Mech. Des. 104 (1982) 259). The depth is not predictable from a
    tolerance class (the face-load factor's variation is unknown), so it is calibrated. The
    factor is a time term of the kernel (``m.pinion_modulation``, its phase), pairs A and B by
    the same instantaneous factor; the tables keep their length.

    A gear that runs out (the loop's effect ``gear_runout``: ``m.centre_runout``, its
    eccentricity ``e2``) changes the centre distance in the same way once per gear revolution,
    so it modulates the mesh by the same mechanism: depth ``mu e2 / e1`` (the depth per unit
    eccentricity of the pinion's, ``e1`` = ``v["eccentricity1_um"]``) in the same phase
    relation to its own centre-distance change (``k (1 + mu2 cos(w2 t + phi))``, a time term of
    the kernel as well). Without it a gear run-out would make its sidebands by the kinematic
    error and the moving path of contact alone, while the pinion's, declared, makes them by
    all three.
    """
    mu = float(v.get("mesh_modulation", 0.0))
    if mu == 0.0:
        return m
    phase = float(v.get("modulation_phase_rad", 0.0))
    depth2 = mu * m.centre_runout / (v["eccentricity1_um"] * 1e-6) if m.centre_runout else 0.0
    return dataclasses.replace(m, pinion_modulation=mu, pinion_modulation_phase=phase,
                               gear_modulation=depth2, gear_modulation_phase=phase)
