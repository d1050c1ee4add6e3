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

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.testbeds.synthetic": ("make_bundle",),
    "physics.testbeds.independent_simulator": (
        "IndependentPair", "SISTER_UNIT", "EFFECT_NAMES", "make_independent_bundle",
        "simulate_record", "wear_depths", "effect_values"),
    "physics.testbeds.loop_bench": (
        "BOTH", "SISTER_SEED", "base_scenario", "sister_reference", "report_label",
        "residual_cells", "visibility", "attainable", "best_candidate"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
