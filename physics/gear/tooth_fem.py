"""Finite-element check of the potential-energy mesh stiffness (thesis 3.1, Table 7).

The thesis checked its energy method against a 3-D ABAQUS model. This is an open-source 2-D
equivalent: each wheel is meshed whole (all teeth, the rim and the bore; generated tooth form of
:mod:`physics.tooth`) with quadratic triangles (``triangle`` for the mesh, ``scikit-fem`` for
the assembly), clamped at the bore, in plane strain (or plane stress for comparison). The tooth
pair in contact at roll coordinate ``s`` is loaded on each wheel by the Hertz pressure of its
share of the load, ``p = p_max sqrt(1 - (xi/b)^2)`` over the half-width b around the contact
point, pressing along the flank normal. The work-conjugate displacement

    delta_i = int p (u . -n) dxi / w

is the approach of the contact band towards the bore of wheel i, so ``w / (delta_1 + delta_2)``
per unit face width is the FE pair stiffness. It contains everything the energy method splits
into bending, shear, axial, gear-body and Hertz terms, with the contact term computed from the
elasticity of the real bodies instead of the constant ``pi E B / (4 (1 - nu^2))``.

The element size is graded from ``h_contact`` at the contact bands to ``h_far`` far from the
loaded tooth; :func:`fe_pair_stiffness` reports the element count so that a convergence study is
a loop over ``refine``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import triangle
from scipy.sparse.linalg import factorized
from skfem import (
    Basis,
    ElementTriP2,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshTri,
)
from skfem.models.elasticity import lame_parameters, linear_elasticity

from physics.gear.contact import equivalent_radius, hertz_half_width, reduced_modulus
from physics.gear.geometry import MeshGeometry
from physics.gear.tooth import ToothForm, generate_tooth
from physics.params import GearPair, Material

# scikit-fem logs every assembly and solve at INFO: hundreds of lines in an app's console and
# log for one reproduction; its warnings still show
logging.getLogger("skfem").setLevel(logging.WARNING)


@dataclass(frozen=True)
class FEResult:
    """Compliances [m/N, for the whole face width] of each wheel at each requested position."""

    s: np.ndarray  # roll coordinates [m]
    load_per_width: np.ndarray  # w of the pair [N/m]
    pinion: np.ndarray  # delta_1 / (w B)
    gear: np.ndarray  # delta_2 / (w B)
    elements: tuple[int, int]  # triangles of the pinion and gear meshes

    @property
    def pair_stiffness(self) -> np.ndarray:
        """FE stiffness of one tooth pair at each position [N/m]."""
        return 1.0 / (self.pinion + self.gear)


def _outline(form: ToothForm, contacts: np.ndarray, h_contact: float, h_tooth: float,
             h_far: float, band: float) -> np.ndarray:
    """Closed outline (counter-clockwise) of the whole wheel, graded around the contacts.

    The loaded tooth stands on the +y axis; ``contacts`` are points on its drive (x > 0) flank.
    """
    z = form.z
    pitch_angle = 2 * math.pi / z
    # one tooth unit, clockwise from -pi/z to +pi/z (polar angle measured from +y towards +x)
    flank = np.stack([form.x, form.y], axis=1)  # drive flank, root -> tip
    theta_tip = math.atan2(form.x[-1], form.y[-1])
    tip = np.array([[form.ra * math.sin(a), form.ra * math.cos(a)]
                    for a in np.linspace(-theta_tip, theta_tip, 40)[1:-1]])

    def root_arc(a0: float, a1: float) -> np.ndarray:
        a = np.linspace(a0, a1, 40)[1:-1]
        return np.stack([form.rf * np.sin(a), form.rf * np.cos(a)], axis=1)

    half = math.pi / z
    unit = np.concatenate([
        root_arc(-half, -form.theta_f), (flank * [-1, 1]), tip, flank[::-1],
        root_arc(form.theta_f, half),
    ])
    teeth = []
    for k in range(z):
        c, s_ = math.cos(k * pitch_angle), math.sin(k * pitch_angle)
        rot = np.array([[c, s_], [-s_, c]])  # clockwise by k pitches
        teeth.append(unit @ rot.T)
    dense = np.concatenate(teeth)
    dense = dense[::-1]  # counter-clockwise
    # spacing: fine near the contacts, medium on the loaded tooth, coarse elsewhere
    dist_c = np.min(np.linalg.norm(dense[:, None, :] - contacts[None, :, :], axis=2), axis=1)
    dist_t = np.hypot(dense[:, 0], dense[:, 1] - form.r)
    h = np.minimum(h_contact + 0.5 * np.maximum(dist_c - band, 0.0),
                   h_tooth + 0.5 * np.maximum(dist_t - 2 * form.module, 0.0))
    h = np.clip(h, h_contact, h_far)
    closed = np.vstack([dense, dense[:1]])
    seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    h_seg = 0.5 * (h + np.roll(h, -1))
    level = np.concatenate([[0.0], np.cumsum(seg / h_seg)])
    n = max(int(np.rint(level[-1])), 3 * z)
    targets = np.linspace(0.0, level[-1], n, endpoint=False)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    t_arc = np.interp(targets, level, arc)
    return np.stack([np.interp(t_arc, arc, closed[:, 0]), np.interp(t_arc, arc, closed[:, 1])],
                    axis=1)


def _mesh(form: ToothForm, contacts: np.ndarray, refine: float) -> MeshTri:
    m = form.module
    h_contact = 0.02 * m / refine
    outer = _outline(form, contacts, h_contact, 0.08 * m / refine, 0.6 * m / refine,
                     band=0.15 * m)
    n_bore = max(24, int(2 * math.pi * form.bore / (0.6 * m / refine)))
    a = np.linspace(0, 2 * math.pi, n_bore, endpoint=False)
    bore = np.stack([form.bore * np.cos(a), form.bore * np.sin(a)], axis=1)
    pts = np.vstack([outer, bore])
    n_out = len(outer)
    seg = np.vstack([
        np.stack([np.arange(n_out), (np.arange(n_out) + 1) % n_out], axis=1),
        n_out + np.stack([np.arange(n_bore), (np.arange(n_bore) + 1) % n_bore], axis=1),
    ])
    max_area = (0.6 * m / refine) ** 2 / 2
    tri = triangle.triangulate({"vertices": pts, "segments": seg, "holes": [[0.0, 0.0]]},
                               f"pq30a{max_area:.6e}Q")
    return MeshTri(np.ascontiguousarray(tri["vertices"].T),
                   np.ascontiguousarray(tri["triangles"].T))


def _compliances(form: ToothForm, points: np.ndarray, normals: np.ndarray,
                 half_widths: np.ndarray, material: Material, plane: str, refine: float
                 ) -> tuple[np.ndarray, int]:
    """Work-conjugate compliance delta/w [m^2/N per unit width] at each contact point."""
    mesh = _mesh(form, points, refine)
    element = ElementVector(ElementTriP2())
    basis = Basis(mesh, element, intorder=4)
    lam, mu = lame_parameters(material.E, material.poisson)
    if plane == "stress":
        lam = 2 * lam * mu / (lam + 2 * mu)
    K = linear_elasticity(lam, mu).assemble(basis)
    clamped = basis.get_dofs(
        lambda x: np.hypot(x[0], x[1]) < form.bore * (1 + 1e-9) + 1e-12).all()
    interior = basis.complement_dofs(clamped)
    solve_interior = factorized(K[interior][:, interior].tocsc())
    out = []
    for p, n, b in zip(points, normals, half_widths, strict=True):
        facets = mesh.facets_satisfying(
            lambda x, p=p, b=b: np.hypot(x[0] - p[0], x[1] - p[1]) < 1.5 * b,
            boundaries_only=True)
        fb = FacetBasis(mesh, element, facets=facets, intorder=12)

        @LinearForm
        def traction(v, w, p=p, n=n, b=b):
            xi = np.hypot(w.x[0] - p[0], w.x[1] - p[1])
            pressure = np.sqrt(np.clip(1 - (xi / b) ** 2, 0.0, None))  # unit p_max
            return -pressure * (n[0] * v[0] + n[1] * v[1])

        f = traction.assemble(fb)
        line_load = -f @ _unit_field(basis, n)  # int p dxi for unit p_max
        u_interior = solve_interior(f[interior])
        out.append((f[interior] @ u_interior) / line_load**2)
    return np.array(out), mesh.t.shape[1]


def _unit_field(basis: Basis, n: np.ndarray) -> np.ndarray:
    """Nodal vector of the uniform displacement field ``n`` (to read resultants off a load)."""
    return basis.project(lambda x: np.stack([np.full(x.shape[1:], n[0]),
                                             np.full(x.shape[1:], n[1])]))


def _contact_points(form: ToothForm, radius: np.ndarray, alpha: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Drive-flank points at ``radius`` and their outward unit normals (tooth frame)."""
    a_r = np.arccos(form.rb / radius)
    theta = math.pi / (2 * form.z) + (math.tan(alpha) - alpha) - (np.tan(a_r) - a_r)
    pts = np.stack([radius * np.sin(theta), radius * np.cos(theta)], axis=1)
    normals = np.stack([np.cos(a_r - theta), np.sin(a_r - theta)], axis=1)
    return pts, normals


def fe_pair_stiffness(gear: GearPair, material: Material, geom: MeshGeometry, s: np.ndarray,
                      load: np.ndarray, plane: str = "strain", refine: float = 1.0) -> FEResult:
    """FE compliance of both wheels, and the pair stiffness, at roll coordinates ``s``.

    ``load`` is the normal load on the pair at each position [N] (its share of the mesh force),
    which sets the Hertz half-width of the applied pressure.
    """
    if plane not in ("strain", "stress"):
        raise ValueError(f"plane = {plane!r} must be 'strain' or 'stress'")
    if refine <= 0:
        raise ValueError(f"refine = {refine!r} must be > 0 (1 = default mesh, 2 = twice as fine)")
    s = np.asarray(s, dtype=float)
    w = np.asarray(load, dtype=float) / gear.face_width
    R1, R2 = geom.curvature_radii(s)
    b = hertz_half_width(w, equivalent_radius(R1, R2), reduced_modulus(material, material))
    r1, r2 = geom.flank_radii(s)
    comp, elements = [], []
    for wheel, radius in ((1, r1), (2, r2)):
        form = generate_tooth(gear, wheel)
        pts, normals = _contact_points(form, radius, gear.alpha)
        c, n_el = _compliances(form, pts, normals, b, material, plane, refine)
        comp.append(c / gear.face_width)
        elements.append(n_el)
    return FEResult(s, w, comp[0], comp[1], (elements[0], elements[1]))

