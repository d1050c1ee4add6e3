"""Time-varying mesh stiffness of worn spur teeth by the potential energy method (thesis 3.1-3.2).

Each tooth is a cantilever of variable section standing on the gear body. A load ``F`` along the
line of action at the flank point of height ``y_L`` (tooth frame of :mod:`physics.tooth`) makes
the angle ``alpha_1 = alpha_R - theta_R`` with the normal to the tooth centre line; its
components ``F cos(alpha_1)`` (bending and shear) and ``F sin(alpha_1)`` (compression) store the
energies (Yang & Lin, ASME J. Mech. Trans. Autom. Des. 109 (1987); Tian, 2004; Chen & Shao,
Mech. Mach. Theory 46 (2011) 440-455):

    1/k_b = int [cos(a1) (y_L - y) - sin(a1) e(y)]^2 / (E I(y)) dy
    1/k_s = int 1.2 cos^2(a1) / (G A(y)) dy
    1/k_a = int sin^2(a1) / (E A(y)) dy

from the root circle to the load, over the real section: the generated fillet and involute, with
the drive flank moved in by the wear depth. ``w(y) = x_drive + x_coast`` is the section width,
``I = w^3 B / 12``, ``A = w B``, and ``e(y)`` the lever arm of the radial component about the
section's centroid (which shifts by half the local wear). The thesis's bending integrand is the
same with ``e = h_w``.

The gear body adds the fillet-foundation compliance of Sainsot, Velex & Duverger (ASME J. Mech.
Des. 126 (2004) 748-752), and the pair the Hertz contact stiffness ``k_h = pi E B / (4 (1 -
nu^2))`` (Yang & Sun, 1985; thesis 3.1). One pair:

    1/k = 1/k_h + sum over pinion and gear of (1/k_b + 1/k_s + 1/k_a + 1/k_f)

Teeth wider than five modules are in plane strain: ``E`` above is ``E / (1 - nu^2)`` then
(``plane="strain"``), and ``G = E / (2 (1 + nu))`` in both cases.

The integrals up to every load height come from one cumulative quadrature per tooth and state of
wear, so a whole mesh cycle costs a few interpolations (no quadrature per mesh position).
"""

from __future__ import annotations

import functools
import logging
import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_simpson

from physics.gear.geometry import MeshGeometry, mesh_geometry
from physics.gear.tooth import ToothForm, checked_wear, generate_tooth, involute_angle
from physics.gear.tooth_contact import flank_coordinate
from physics.params import GearPair, Material, OutOfScope

log = logging.getLogger(__name__)

# Sainsot, Velex & Duverger (2004), Table 1: X*(h_f, theta_f) = A/theta_f^2 + B h_f^2
# + C h_f/theta_f + D/theta_f + E h_f + F, for L*, M*, P*, Q*.
SAINSOT = {
    "L": (-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045),
    "M": (60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086),
    "P": (-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236),
    "Q": (-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904),
}
#: ranges of h_f = r_f / r_bore and theta_f [rad] over which Sainsot et al. fitted the
#: polynomials; outside them the polynomials are extrapolated (see :class:`MeshStiffness`: an
#: h_f outside warns, a theta_f outside is logged at debug level).
SAINSOT_HF_RANGE = (1.4, 7.0)
SAINSOT_THETA_RANGE = (0.01, 0.12)


class SainsotRangeWarning(UserWarning):
    """The gear-body formula is used outside the range of r_f/r_bore it was fitted on (a bore
    the user chose: worth a look at the gear's parameters)."""


def sainsot_coefficients(h_f: float, theta_f: float) -> dict[str, float]:
    """L*, M*, P*, Q* of Sainsot et al. (2004) for ``h_f = r_f / r_bore`` and ``theta_f`` [rad]."""
    return {k: a / theta_f**2 + b * h_f**2 + c * h_f / theta_f + d / theta_f + e * h_f + f
            for k, (a, b, c, d, e, f) in SAINSOT.items()}


def iso6336_single_pair_stiffness(gear: GearPair) -> float:
    """Single-pair stiffness ``c' b`` [N/m] of ISO 6336-1:2019 method B (clause 9), a check.

    ``q' = C1 + C2/z1 + C3/z2`` (unshifted spur teeth) with C1 = 0.04723, C2 = 0.15551,
    C3 = 0.25791 mm um/N; ``c'_th = 1/q'``; ``c' = c'_th C_M C_R C_B`` with C_M = 0.8 (solid
    discs), C_R = 1 and ``C_B = [1 + 0.5 (1.2 - h_fP/m)] [1 - 0.02 (20 deg - alpha)]``.
    """
    q = 0.04723 + 0.15551 / gear.z1 + 0.25791 / gear.z2  # mm um / N
    h_fp = gear.ha_star + gear.c_star
    c_b = (1 + 0.5 * (1.2 - h_fp)) * (1 - 0.02 * (20.0 - gear.pressure_angle_deg))
    c_prime = (1 / q) * 0.8 * 1.0 * c_b  # N/(mm um)
    return c_prime * 1e9 * gear.face_width  # N/(mm um) = 1e9 N/m^2, times face width [m]


@dataclass(frozen=True)
class _Cumulative:
    """Cumulative integrals of one tooth, from the root circle up to each grid height."""

    y: np.ndarray  # heights [m]
    x_drive: np.ndarray  # worn half-width on the drive side [m]
    j0: np.ndarray  # int 1/I
    j1: np.ndarray  # int u/I, u = y - y_root
    j2: np.ndarray  # int u^2/I
    k0: np.ndarray  # int d/I, d = wear reduction of the drive half-width
    k1: np.ndarray  # int u d/I
    k2: np.ndarray  # int d^2/I
    a0: np.ndarray  # int 1/A


def _worn_half_width(form: ToothForm, cut: np.ndarray) -> np.ndarray:
    """The drive half-width of ``form`` at each profile height reduced by ``cut`` [m];
    :class:`OutOfScope` where the wear reaches the tooth's centre line."""
    x_drive = form.x - cut
    if np.any(x_drive <= 0):
        worst = int(np.argmin(x_drive))
        raise OutOfScope(
            f"wear of {cut[worst] * 1e6:.1f} um at radius {form.radius[worst] * 1e3:.3f} mm "
            f"reaches the tooth centre line (half-thickness {form.x[worst] * 1e6:.1f} um there): "
            "the tooth would be worn through; the wear model is outside its scope"
        )
    return x_drive


def _cumulative(form: ToothForm, cut: np.ndarray, width: float) -> _Cumulative:
    """Cumulative section integrals of ``form`` with the drive half-width reduced by ``cut``."""
    x_drive = _worn_half_width(form, cut)
    w = x_drive + form.x
    inv_i = 12.0 / (w**3 * width)
    u = form.y - form.y[0]
    integrands = np.stack([inv_i, u * inv_i, u * u * inv_i, cut * inv_i, u * cut * inv_i,
                           cut * cut * inv_i, 1.0 / (w * width)])
    cum = cumulative_simpson(integrands, x=form.y, initial=0.0, axis=-1)
    return _Cumulative(form.y, x_drive, *cum)


@dataclass(frozen=True)
class ToothCompliances:
    """Compliances [m/N] of one tooth at each load position: bending, shear, axial, foundation."""

    bending: np.ndarray
    shear: np.ndarray
    axial: np.ndarray
    foundation: np.ndarray

    @property
    def total(self) -> np.ndarray:
        return self.bending + self.shear + self.axial + self.foundation


class MeshStiffness:
    """Potential-energy mesh stiffness of a gear pair, healthy or worn.

    One pair's stiffness ``1/k = 1/k_h + sum (1/k_b + 1/k_s + 1/k_a + 1/k_f)`` over pinion and
    gear (module docstring: Yang & Lin 1987; Chen & Shao 2011; Sainsot et al. 2004; thesis
    3.1-3.2), for the drive flanks worn by given profiles.

    Parameters
    ----------
    gear : GearPair
        The pair.
    material : Material
        Both wheels' material.
    plane : {"strain", "stress"} or None
        Plane strain (``E / (1 - nu^2)`` in place of ``E``) or plane stress; ``None`` takes
        strain for a face width above 5 modules, stress otherwise.
    n_fillet, n_involute : int
        Profile points of each tooth on its fillet and involute (the quadrature nodes).

    Raises
    ------
    ValueError
        For a ``plane`` other than ``"strain"`` or ``"stress"``, or a pair outside the model's
        scope (:func:`physics.gear.geometry.mesh_geometry`).

    Warns
    -----
    SainsotRangeWarning
        For an r_f/r_bore outside the range the gear-body polynomials were fitted on (Notes).

    Notes
    -----
    Limits: the gear-body (foundation) compliance extrapolates the Sainsot et al. (2004)
    polynomials, fitted for theta_f in (0.01, 0.12) rad, to the thesis pinion's theta_f = 0.167
    rad (z = 18; with the thesis's tooth proportions every wheel of 25 teeth or fewer lies beyond
    the fitted range); the 2-D FE check of thesis Table 7
    (:func:`physics.gear.tooth_fem.fe_pair_stiffness`) covers that pinion. The extrapolation
    follows from the tooth count, not from a choice the user can change: it is logged at debug
    level, not warned. An r_f/r_bore outside (1.4, 7.0) (a bore radius far from the thesis's
    proportions) issues a :class:`SainsotRangeWarning`.

    Examples
    --------
    >>> from physics.params import GearPair, Material
    >>> ms = MeshStiffness(GearPair(), Material())
    >>> ms.plane  # face width 30 mm > 5 modules of 2 mm
    'strain'
    >>> k = ms.pair(np.array([0.0]))  # one pair at the pitch point [N/m]
    >>> 3e8 < float(k[0]) < 6e8
    True

    Over one mesh period two pairs share the load for the share ``epsilon - 1`` of it (thesis
    2.2), and the mesh is stiffer there than anywhere in the single-tooth zone:

    >>> c = ms.mesh_cycle(200)
    >>> two = c["k_pair2"] > 0
    >>> round(float(two.mean()), 2), round(ms.geometry.contact_ratio - 1, 2)
    (0.58, 0.58)
    >>> bool(c["k_total"][two].min() > c["k_total"][~two].max())
    True
    """

    def __init__(self, gear: GearPair, material: Material, plane: str | None = None,
                 n_fillet: int = 300, n_involute: int = 500):
        if plane is None:
            plane = "strain" if gear.face_width_mm > 5 * gear.module_mm else "stress"
        if plane not in ("strain", "stress"):
            raise ValueError(f"plane = {plane!r} must be 'strain' or 'stress'")
        self.gear, self.material, self.plane = gear, material, plane
        self.geometry: MeshGeometry = mesh_geometry(gear)
        self.forms = (generate_tooth(gear, 1, n_fillet, n_involute),
                      generate_tooth(gear, 2, n_fillet, n_involute))
        nu = material.poisson
        self.E = material.E / (1 - nu**2) if plane == "strain" else material.E
        self.G = material.E / (2 * (1 + nu))
        self.k_hertz = math.pi * material.E * gear.face_width / (4 * (1 - nu**2))
        for form, name in zip(self.forms, ("pinion", "gear"), strict=True):
            h_f, th = form.rf / form.bore, form.theta_f
            text = (f"{name}: r_f/r_bore = {h_f:.2f} and theta_f = {th:.3f} rad; the Sainsot "
                    f"gear-body polynomials were fitted for r_f/r_bore in {SAINSOT_HF_RANGE} and "
                    f"theta_f in {SAINSOT_THETA_RANGE} and are extrapolated here")
            if not SAINSOT_HF_RANGE[0] <= h_f <= SAINSOT_HF_RANGE[1]:
                warnings.warn(f"{text}; check the bore radius", SainsotRangeWarning,
                              stacklevel=2)
            elif not SAINSOT_THETA_RANGE[0] <= th <= SAINSOT_THETA_RANGE[1]:
                log.debug(text)  # the tooth count's: stated in the class's Limits
        self._healthy = tuple(_cumulative(f, np.zeros_like(f.x), gear.face_width)
                              for f in self.forms)

    # -- one tooth ---------------------------------------------------------------------------
    def _cut(self, form: ToothForm, s: np.ndarray, wear: np.ndarray, wheel: int) -> np.ndarray:
        """Reduction of the drive half-width at each profile height for wear on the grid s."""
        s, wear = checked_wear(s, wear)
        # each profile point's depth at its flank coordinate: on the involute the roll that
        # brings it onto the line of action, on the fillet its arc below the involute
        order = np.argsort(s)
        depth = np.interp(flank_coordinate(form, self.geometry, wheel), s[order], wear[order],
                          left=0.0, right=0.0)
        return depth / form.nx

    def drive_half_width(self, wheel: int, s_grid: np.ndarray | None = None,
                         wear: np.ndarray | None = None) -> np.ndarray:
        """Half-width [m] of the drive side of the pinion (1) or gear (2) tooth at each height
        of its form (``forms[wheel - 1].y``), its drive flank worn along the normal by ``wear``
        on ``s_grid`` (unworn without); :class:`OutOfScope` where the wear reaches the centre
        line."""
        form = self.forms[wheel - 1]
        if wear is None:
            return form.x.copy()
        return _worn_half_width(form, self._cut(form, s_grid, wear, wheel))

    def tooth(self, wheel: int, radius: np.ndarray, cumulative: _Cumulative | None = None
              ) -> ToothCompliances:
        """Compliances of the pinion (1) or gear (2) tooth loaded at flank radii ``radius``."""
        form = self.forms[wheel - 1]
        c = cumulative or self._healthy[wheel - 1]
        radius = np.asarray(radius, dtype=float)
        theta, a_r = involute_angle(form.z, self.gear.alpha, form.rb, radius)
        a1 = a_r - theta
        y_l = radius * np.cos(theta)
        x_l = np.interp(y_l, c.y, c.x_drive)  # worn load point on the drive flank
        u_l = y_l - c.y[0]

        def at(arr: np.ndarray) -> np.ndarray:
            return np.interp(y_l, c.y, arr)

        j0, j1, j2, k0, k1, k2 = (at(a) for a in (c.j0, c.j1, c.j2, c.k0, c.k1, c.k2))
        cos, sin = np.cos(a1), np.sin(a1)
        # [cos (u_L - u) - sin (x_L + d/2)]^2 / I, integrated term by term
        lever2 = u_l**2 * j0 - 2 * u_l * j1 + j2
        cross = x_l * (u_l * j0 - j1) + 0.5 * (u_l * k0 - k1)
        arm2 = x_l**2 * j0 + x_l * k0 + 0.25 * k2
        bending = (cos**2 * lever2 - 2 * cos * sin * cross + sin**2 * arm2) / self.E
        a0 = at(c.a0)
        shear = 1.2 * cos**2 * a0 / self.G
        axial = sin**2 * a0 / self.E
        coef = sainsot_coefficients(form.rf / form.bore, form.theta_f)
        u_f = y_l - x_l * np.tan(a1) - form.root_height
        s_f = 2 * form.rf * form.theta_f
        ratio = u_f / s_f
        foundation = cos**2 / (self.E * self.gear.face_width) * (
            coef["L"] * ratio**2 + coef["M"] * ratio + coef["P"] * (1 + coef["Q"] * np.tan(a1)**2))
        return ToothCompliances(bending, shear, axial, foundation)

    # -- pairs and the mesh --------------------------------------------------------------------
    def pair_function(self, s_grid: np.ndarray | None = None, wear1: np.ndarray | None = None,
                      wear2: np.ndarray | None = None):
        """``k(s)`` [N/m] of one tooth pair for the wear profiles given on ``s_grid``."""
        if wear1 is None and wear2 is None:
            cums = self._healthy
        else:
            s_grid = np.asarray(s_grid, dtype=float)
            w1 = np.zeros_like(s_grid) if wear1 is None else wear1
            w2 = np.zeros_like(s_grid) if wear2 is None else wear2
            cums = tuple(
                _cumulative(f, self._cut(f, s_grid, w, i + 1), self.gear.face_width)
                for i, (f, w) in enumerate(zip(self.forms, (w1, w2), strict=True)))

        def k(s: np.ndarray) -> np.ndarray:
            r1, r2 = self.geometry.flank_radii(np.asarray(s, dtype=float))
            total = (self.tooth(1, r1, cums[0]).total + self.tooth(2, r2, cums[1]).total
                     + 1.0 / self.k_hertz)
            return 1.0 / total

        return k

    def pair(self, s: np.ndarray, s_grid: np.ndarray | None = None,
             wear1: np.ndarray | None = None, wear2: np.ndarray | None = None) -> np.ndarray:
        """Stiffness [N/m] of the tooth pair in contact at roll coordinates ``s``."""
        return self.pair_function(s_grid, wear1, wear2)(s)

    def mesh_cycle(self, n: int = 200, s_grid: np.ndarray | None = None,
                   wear1: np.ndarray | None = None, wear2: np.ndarray | None = None
                   ) -> dict[str, np.ndarray]:
        """Mesh stiffness over one mesh period (one base pitch of roll).

        Returns ``roll`` (roll coordinate of pair 1, from the start of contact) and the
        stiffnesses ``k_pair1``, ``k_pair2`` (the pair one base pitch ahead, 0 when out of
        contact) and ``k_total`` [N/m], at ``n`` positions.
        """
        if n < 10:
            raise ValueError(f"n = {n} mesh positions is too few; use at least 10 (200 default)")
        g = self.geometry
        k = self.pair_function(s_grid, wear1, wear2)
        roll, ahead, in_contact = g.mesh_period(n)
        k1 = k(roll)
        k2 = np.where(in_contact, k(ahead), 0.0)
        return {"roll": roll, "k_pair1": k1, "k_pair2": k2, "k_total": k1 + k2}


@functools.lru_cache(maxsize=16)
def mesh_stiffness(gear: GearPair, material: Material) -> MeshStiffness:
    """The potential-energy mesh stiffness of a pair, built once per (frozen, hashable) gear
    pair and material and shared by every wear run, dynamic model and table of it (it holds no
    state that they change)."""
    return MeshStiffness(gear, material)
