"""Tooth-root bending stress of a tooth as it is, new or worn, and its fatigue strength.

The tooth is the generated form of :mod:`physics.gear.tooth` with its drive flank worn along
the normal (:meth:`physics.gear.stiffness.MeshStiffness.drive_half_width`). The normal load
``F_n`` acts at a point of the drive flank (by default the highest point of single-tooth
contact, ISO 6336-3:2006 method B) along the flank's inward normal, at ``alpha_F`` to the
perpendicular of the tooth's centre line. Each cross-section at height ``y`` below the load
point, of thickness ``s(y)`` (the worn drive half-width plus the coast one) and centre ``c(y)``,
carries the bending moment ``M = F_n cos(alpha_F) h(y)``, ``h = (y_L - y) - tan(alpha_F) (x_L -
c)`` the height of the load line's crossing with the section's centre above it (ISO's lever
``h_Fe``). Its nominal bending stress on the loaded side is ``6 M / (b s^2)``; the critical
section is where that is largest (Lewis 1892: the section where the inscribed parabola of
uniform strength touches the profile; ISO approximates it by the 30-degree tangent), which for
a new tooth lies in the fillet and moves up the flank as the wear thins it. The radial
component's compression is left out, as in ISO's form factor

    Y_F = 6 (h / m) cos(alpha_F) / ((s / m)^2 cos(alpha_n)),  sigma_F0 = F_t / (b m) Y_F Y_S,

with ``F_t = F_n cos(alpha_n)`` and the stress correction of the notch at the critical section
(ISO 6336-3:2006, 6.3, after Dolan & Broghamer 1942)

    Y_S = (1.2 + 0.13 L) q_s^(1 / (1.21 + 2.3 / L)),  L = s / h,  q_s = s / (2 rho_F),

``rho_F`` the profile's radius of curvature there (fitted over :data:`NOTCH_REACH`; ``q_s``
held to the formula's range 1-8).

The strength it is judged against, :data:`physics.scope.ROOT_STRENGTH`, is the tooth-root
fatigue strength of case-carburised steel (``Y_ST sigma_Flim``, ISO 6336-5:2016); the load is
the quasi-static one (application and dynamic factors 1), as in the contact-driven wear.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from physics.gear.geometry import MeshGeometry
from physics.gear.stiffness import MeshStiffness
from physics.gear.tooth import involute_angle
from physics.params import OutOfScope

#: range of the notch parameter ``q_s`` over which ISO 6336-3's stress correction holds
NOTCH_RANGE = (1.0, 8.0)
#: arc length on either side of the critical point, in modules, over which the profile's
#: curvature is fitted: a third of the standard rack's tip round (0.38 m), which the fillet's
#: curvature follows
NOTCH_REACH = 0.125


@dataclass(frozen=True)
class RootStress:
    """The critical section of one tooth under one load (module text)."""

    stress: float  # sigma_F = nominal * Y_S [Pa]
    nominal: float  # sigma_F0 / Y_S: the section's bending stress [Pa]
    form_factor: float  # Y_F
    stress_correction: float  # Y_S
    radius: float  # the critical section's loaded-side point from the wheel centre [m]
    thickness: float  # s_Fn [m]
    lever: float  # h_Fe [m]


def single_contact_radius(geometry: MeshGeometry, wheel: int) -> float:
    """Flank radius [m] of the highest point of single-tooth contact of the pinion (1) or the
    gear (2): the pinion's at ``s_start + p_b``, the gear's at ``s_end - p_b`` (the end of the
    single-tooth zone nearer each wheel's tip)."""
    lo, hi = geometry.single_zone
    r1, r2 = geometry.flank_radii(np.array([hi if wheel == 1 else lo]))
    return float((r1 if wheel == 1 else r2)[0])


def root_stress(ms: MeshStiffness, wheel: int, force: float, radius: float | None = None,
                s_grid: np.ndarray | None = None, wear: np.ndarray | None = None
                ) -> RootStress:
    """Root stress of the pinion (1) or gear (2) tooth loaded by the normal force ``force``
    [N] at the drive-flank radius ``radius`` [m] (default: :func:`single_contact_radius`), its
    drive flank worn by ``wear`` [m] on ``s_grid`` (new without)."""
    if wheel not in (1, 2):
        raise ValueError(f"wheel = {wheel!r} must be 1 (pinion) or 2 (gear)")
    if not (math.isfinite(force) and force > 0):
        raise ValueError(f"force = {force!r} must be a finite normal load > 0 (N)")
    form, gear = ms.forms[wheel - 1], ms.gear
    if radius is None:
        radius = single_contact_radius(ms.geometry, wheel)
    if not form.rb <= radius <= form.ra:
        raise ValueError(f"radius = {radius!r} m must lie on the involute, in [{form.rb:.6g}, "
                         f"{form.ra:.6g}] m")
    drive = ms.drive_half_width(wheel, s_grid, wear)
    theta, a_r = involute_angle(form.z, gear.alpha, form.rb, radius)
    alpha_f = float(a_r - theta)  # the load's angle to the centre line's perpendicular
    y_l = radius * math.cos(float(theta))
    x_l = float(np.interp(y_l, form.y, drive))
    below = form.y < y_l
    y, s = form.y[below], drive[below] + form.x[below]
    centre = 0.5 * (drive[below] - form.x[below])
    lever = (y_l - y) - math.tan(alpha_f) * (x_l - centre)
    bending = 6 * force * math.cos(alpha_f) * lever / (gear.face_width * s**2)
    at = int(np.argmax(bending))
    rho = _curvature_radius(drive[below], y, at, NOTCH_REACH * gear.m)
    length = s[at] / lever[at]
    q_s = min(max(s[at] / (2 * rho), NOTCH_RANGE[0]), NOTCH_RANGE[1])
    y_s = (1.2 + 0.13 * length) * q_s ** (1 / (1.21 + 2.3 / length))
    f_t = force * math.cos(gear.alpha)
    nominal = float(bending[at])
    return RootStress(nominal * y_s, nominal, nominal * gear.face_width * gear.m / f_t, y_s,
                      float(math.hypot(drive[below][at], y[at])), float(s[at]),
                      float(lever[at]))


def _curvature_radius(x: np.ndarray, y: np.ndarray, at: int, reach: float) -> float:
    """Radius of curvature [m] of the profile curve ``(x, y)`` at point ``at``: the circle
    fitted by least squares (Kasa 1976) to the points within ``reach`` [m] of arc length on
    either side (a wear cut interpolated on its own grid makes point-wise derivatives noisy);
    infinite where they lie on a line."""
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    near = np.abs(arc - arc[at]) <= reach
    if near.sum() < 3:
        return math.inf
    px, py = x[near] - x[at], y[near] - y[at]
    # x^2 + y^2 = 2 a x + 2 b y + c: the centre (a, b), the radius sqrt(c + a^2 + b^2)
    design = np.column_stack([2 * px, 2 * py, np.ones_like(px)])
    (a, b, c), *_ = np.linalg.lstsq(design, px**2 + py**2, rcond=None)
    radius2 = c + a * a + b * b
    return math.sqrt(radius2) if radius2 > 0 and math.isfinite(radius2) else math.inf


def check_root_strength(ms: MeshStiffness, s_grid: np.ndarray, pinion: np.ndarray,
                        gear: np.ndarray, force: float, limit: float, cycles: float) -> None:
    """Raise :class:`OutOfScope` when a tooth of either wheel, worn by its row of ``pinion``
    or ``gear`` ``(teeth, grid)`` [m] on ``s_grid``, carries a root stress under ``force`` at
    its highest point of single-tooth contact above ``limit`` [Pa], naming the tooth, where and
    when: it would break by tooth-root fatigue; one worn to its centre line is named so."""
    for wheel, rows, name in ((1, pinion, "pinion"), (2, gear, "gear")):
        for tooth, wear in enumerate(rows):
            which = f"{name} tooth {tooth}" if len(rows) > 1 else f"every {name} tooth"
            try:
                r = root_stress(ms, wheel, force, s_grid=s_grid, wear=wear)
            except OutOfScope as err:  # worn to its centre line: said with the tooth and when
                raise OutOfScope(f"after {cycles:.3g} cycles {which}: {err}") from None
            if r.stress > limit:
                raise OutOfScope(
                    f"after {cycles:.3g} cycles {which} (deepest wear {wear.max() * 1e6:.0f} "
                    f"um) carries a tooth-root stress of {r.stress / 1e6:.0f} MPa at radius "
                    f"{r.radius * 1e3:.2f} mm (a section {r.thickness * 1e3:.2f} mm thick), "
                    f"above its {limit / 1e6:.0f} MPa root fatigue strength: the tooth would "
                    "break; the wear model is outside its scope")
