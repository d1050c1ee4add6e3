"""Torsional gear-pair dynamics (thesis 3.3-3.5, 4.1): the model with backlash and worn teeth, its
compiled kernels and two-DOF reference, and the dynamic-load/wear coupling (evolution). Imports
``physics.params``, ``physics.gear`` and ``physics.tribology``."""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.dynamics.model": (
        "PairModel", "Response", "EXACT_PHASES", "build_model", "simulate", "simulate_two_dof",
        "force_per_position", "blank_inertia", "kernel_parameters", "time_step", "output_samples",
        "anti_aliasing_filter", "anti_aliased"),
    "physics.dynamics.teeth": ("per_tooth_model", "sequence_model", "with_tooth_positions"),
    "physics.dynamics.model_form": (
        "FACTORS", "with_model_form", "revolution_tables", "with_modulation"),
    "physics.dynamics.evolution": (
        "CANDIDATES", "EvolutionModel", "feedback_dynamics", "dynamic_mesh_force",
        "simulate_dynamic_wear", "root_wear_evolution", "largest_phase_gap", "fit_evolution_model",
        "fit_evolution_models"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
