"""Torsional gear-pair dynamics (thesis 3.3-3.5, 4.1): the model with backlash and worn teeth, its
compiled kernels and two-DOF reference, and the dynamic-load/wear coupling (evolution). Imports
``physics.params``, ``physics.gear`` and ``physics.tribology``."""

from __future__ import annotations

import importlib

#: the public names, by the module that defines each; a name is imported on first use, so that
#: importing the package (or one of its modules) stays light and free of import cycles
_SOURCES = {
    "physics.dynamics.model": (
        "PairModel", "Response", "build_model", "simulate", "simulate_two_dof",
        "force_per_position", "blank_inertia", "kernel_parameters", "time_step", "output_samples",
        "anti_aliasing_filter", "anti_aliased"),
    "physics.dynamics.model_form": (
        "FACTORS", "with_model_form", "revolution_tables", "with_modulation"),
    "physics.dynamics.evolution": (
        "CANDIDATES", "EvolutionModel", "feedback_dynamics", "dynamic_mesh_force",
        "simulate_dynamic_wear", "root_wear_evolution", "largest_phase_gap", "fit_evolution_model",
        "fit_evolution_models"),
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
