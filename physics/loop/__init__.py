"""The measured-data loop: compare the declared model with measured records, find what it
misses, add that effect, report the error before and after; the app ``python -m physics.loop``.

Stages in the order of the data, each a package importing only those before it:
``measured`` (the bundle format, the records and their groups, the declared model's worn states,
what a bundle lets the loop do), ``model`` (the declared model's parameters, its records, the
residuals and the model discrepancy), ``judge`` (the adoption rule, unexplained lines, the
verdict) and ``search`` (calibration and fits, form references, the wear reading, attribution,
detection limits); ``report`` writes what they decided; ``bundle_loop.run_loop`` and
``table_loop.run_feature_table`` orchestrate them. ``effects`` (the library of effects the
declared model leaves out), ``config`` (the settings) and ``threads`` (candidates on parallel
threads, the time limit) serve every stage. Imports every physics subpackage above it except the
apps; the test rigs that make bundles to try it on are in :mod:`physics.testbeds`.

The public names below are what a user calls: the two loops, bundle I/O, the effect library,
the settings and the report; everything else is reached through its stage's module."""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.loop.bundle_loop": ("run_loop",),
    "physics.loop.table_loop": ("run_feature_table",),
    "physics.loop.measured.bundle": (
        "Bundle", "read_bundle", "write_bundle", "read_feature_table", "read_measurements"),
    "physics.loop.measured.usable": ("check_usable",),
    "physics.loop.effects": ("EFFECTS", "Effect", "Param", "effect"),
    "physics.loop.config": ("LoopConfig", "LoopSettings"),
    "physics.loop.report": ("LoopReport", "STABLE_KEYS", "write_report"),
    "physics.loop.judge.verdict": ("VERDICTS",),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
