"""Test rigs, not the product: the tools for trying the measured-data loop and the surrogate
without measurements.

- :mod:`physics.testbeds.synthetic`: measured-like bundles from the project's own model with an
  undeclared effect switched on (:func:`make_bundle`);
- :mod:`physics.testbeds.independent_simulator`: an independent spur-pair simulator of another
  model form, written without the project's dynamics, stiffness, effect or measurement code
  (:class:`IndependentPair`, :func:`make_independent_bundle`, :func:`simulate_record`,
  :func:`wear_depths`; :data:`SISTER_UNIT`, a sister gearbox of the same type);
- :mod:`physics.testbeds.loop_bench`: the loop bench's bundle sets and what it reads off the
  reports (``bench/bench_loop.py``).

The product never imports this package; ``surrogate/benchmark.py``, ``bench/`` and the tests
may. It imports the loop (its bundle format, and for the bundle makers the declared model).
"""

from __future__ import annotations

import importlib

#: the public names, by the module that defines each; a name is imported on first use, so that
#: importing the package (or one of its modules) stays light and free of import cycles
_SOURCES = {
    "physics.testbeds.synthetic": ("make_bundle",),
    "physics.testbeds.independent_simulator": (
        "IndependentPair", "SISTER_UNIT", "EFFECT_NAMES", "make_independent_bundle",
        "simulate_record", "wear_depths", "effect_values"),
    "physics.testbeds.loop_bench": (
        "BOTH", "SISTER_SEED", "base_scenario", "sister_reference", "report_label",
        "residual_cells", "visibility", "attainable", "best_candidate"),
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
