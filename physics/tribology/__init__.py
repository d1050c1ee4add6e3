"""Tribology of the tooth contact: Hertz contact, lubrication (regressions and the numerical
mixed-EHL solver), flash temperature, contact state, wear (on the path, and driven by the tooth
contact of the flanks as they are). Imports numpy/scipy and
physics.params/physics.gear only."""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.tribology.asperity_table": (
        "MixedEHLTable", "shipped_table", "lookup", "check_scenario"),
    "physics.tribology.calibration": (
        "THESIS_WEAR_COEFF", "calibrate_wear_coeff", "root_wear", "total_load_coefficient"),
    "physics.tribology.contact_state": ("ContactState", "solve_contact_state"),
    "physics.tribology.contact_wear": (
        "ContactWear", "simulate_contact_wear", "tooth_wear_per_cycle", "wear_per_cycle",
        "whole_flank_grid"),
    "physics.tribology.lubrication": (
        "viscosity", "density", "roelands_exponents", "dimensionless_groups", "min_film_thickness",
        "asperity_load_ratio_pct"),
    "physics.tribology.mixed_ehl": (
        "EHLSolution", "solve_line_contact", "log_gt_integral",
        "greenwood_tripp_integral", "asperity_pressure", "pressure_flow_factor", "average_gap",
        "pan_hamrock_film"),
    "physics.tribology.thermal": (
        "flash_temperature", "band_source_max_rise", "peclet", "heat_flux"),
    "physics.tribology.wear": (
        "MeshForce", "WearRate", "WearResult", "simulate_wear", "wear_rate", "film_deficiency",
        "wear_coefficient", "Flank", "flank_grid", "check_shakedown", "quasi_static_force"),
    "physics.tribology.worn_contact": (
        "WornContact", "solve_worn_contact", "solve_gap_contact", "worn_gap", "flank_profile",
        "band_reach", "levelling_length"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
