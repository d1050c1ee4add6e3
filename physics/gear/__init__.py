"""Gear geometry and elasticity (thesis 2.1-2.3, 3.1-3.2): line of action, kinematics, the
rack-generated tooth, Hertz line contact, potential-energy mesh stiffness of worn teeth, its
finite-element check, and double-tooth load sharing. Imports numpy/scipy and ``physics.params``."""

from __future__ import annotations

import importlib

#: the public names, by the module that defines each; a name is imported on first use, so that
#: importing the package (or one of its modules) stays light and free of import cycles
_SOURCES = {
    "physics.gear.contact": (
        "reduced_modulus", "equivalent_radius", "hertz_half_width", "hertz_max_pressure",
        "hertz_mean_pressure"),
    "physics.gear.geometry": ("MeshGeometry", "mesh_geometry", "working_pressure_angle"),
    "physics.gear.kinematics": (
        "surface_velocities", "sliding_velocity", "entraining_velocity", "sliding_distances"),
    "physics.gear.load_sharing": ("PairStiffness", "pair_loads"),
    "physics.gear.stiffness": (
        "MeshStiffness", "SainsotRangeWarning", "ToothCompliances", "sainsot_coefficients",
        "iso6336_single_pair_stiffness", "mesh_stiffness"),
    "physics.gear.tooth": ("ToothForm", "generate_tooth"),
    "physics.gear.tooth_fem": ("FEResult", "fe_pair_stiffness"),
}
_SOURCE = {name: module for module, names in _SOURCES.items() for name in names}
__all__ = sorted(_SOURCE)


def __getattr__(name: str):
    if name in _SOURCE:
        value = getattr(importlib.import_module(_SOURCE[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
