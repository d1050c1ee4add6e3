"""Gear geometry and elasticity (thesis 2.1-2.3, 3.1-3.2): line of action, kinematics, the
rack-generated tooth, Hertz line contact, potential-energy mesh stiffness of worn teeth, its
finite-element check, double-tooth load sharing, the tooth contact of flanks of any shape on and
off the path, the root bending stress of a tooth new or worn, the meshing sequence of the teeth,
and the manufacturing tolerances of an accuracy grade. Imports numpy/scipy and
``physics.params``."""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.gear.accuracy": (
        "runout_tolerance_um", "profile_form_tolerance_um", "cumulative_pitch_tolerance_um",
        "minimum_backlash_um", "maximum_backlash_um", "tooth_thickness_tolerance_um",
        "it_tolerance_um", "single_pitch_tolerance_um", "tooth_positions_um", "position_bound_m",
        "POSITION_BOUND_FP"),
    "physics.gear.contact": (
        "reduced_modulus", "equivalent_radius", "hertz_half_width", "hertz_max_pressure",
        "hertz_mean_pressure"),
    "physics.gear.geometry": ("MeshGeometry", "mesh_geometry", "working_pressure_angle"),
    "physics.gear.kinematics": (
        "surface_velocities", "sliding_velocity", "entraining_velocity", "sliding_distances"),
    "physics.gear.load_sharing": ("PairStiffness", "pair_loads"),
    "physics.gear.mesh_sequence": ("MeshSequence", "meshing_sequence", "hunting_period"),
    "physics.gear.stiffness": (
        "MeshStiffness", "SainsotRangeWarning", "ToothCompliances", "sainsot_coefficients",
        "iso6336_single_pair_stiffness", "mesh_stiffness"),
    "physics.gear.tooth": ("ToothForm", "generate_tooth", "checked_wear", "involute_angle"),
    "physics.gear.tooth_bending": (
        "RootStress", "root_stress", "single_contact_radius", "check_root_strength"),
    "physics.gear.tooth_contact": (
        "PairGaps", "WornFlank", "worn_flank", "flank_coordinate", "LoadedContact",
        "loaded_contact", "share_load", "pair_slots", "clamped", "NO_CONTACT"),
    "physics.gear.tooth_fem": ("FEResult", "fe_pair_stiffness"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
