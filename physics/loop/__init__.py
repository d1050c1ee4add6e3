"""The measured-data loop: compare the declared model with measured records, find what it
misses, add that effect, report the error before and after; the app ``python -m physics.loop``.

Modules in the order of the data: ``bundle`` (the measured bundle's format), ``effects`` (the
library of effects the declared model leaves out), ``config`` (the loop's settings),
``declared`` (the declared model's nuisance and form parameters), ``worn_states`` (worn models
per operating point), ``records`` (records, groups, split), ``simulation`` (the model's
records), ``comparison`` (residuals and errors), ``fit`` (calibration and search),
``discrepancy`` (the model discrepancy), ``wear_reading`` (the model-based wear estimate),
``attribution`` (candidates, null test, second round), ``form_error`` (a sister gearbox's
form reference), ``own_history`` (this unit's earliest records as the reference), ``lines``
(spectral lines no declared order explains), ``verdict`` (an effect, an unexplained residual
or nothing), ``usable`` (what a bundle lets the loop do, decided before work), ``report``;
``threads`` (candidates on parallel threads, the time limit) serves them;
``bundle_loop.run_loop`` orchestrates them, ``table_loop`` runs the loop on a feature table.
Imports every physics subpackage above it except the apps; the test rigs that make bundles to
try it on are in :mod:`physics.testbeds`."""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.loop.bundle": (
        "Bundle", "read_bundle", "write_bundle", "read_feature_table", "read_measurements",
        "record_scenario"),
    "physics.loop.effects": ("EFFECTS", "Effect", "Param", "effect"),
    "physics.loop.config": ("LoopConfig", "LoopSettings"),
    "physics.loop.declared": (
        "NUISANCE", "MODEL_FORM", "SUPPORT", "MOUNT", "CHAIN_MODES", "CHAIN", "BOUNDS", "TORQUE",
        "SCENARIO_DYNAMIC", "DYNAMIC_NUISANCE", "RUNOUT_MODULATION", "declared_nuisance",
        "declared_model_form", "declared_modes", "modes_of", "completed", "to_unit", "from_unit",
        "with_nuisance"),
    "physics.loop.worn_states": (
        "WearHistory", "wear_history", "records_history", "worn_models", "cycles_for_wear",
        "wear_grid_cycles", "records_cycles"),
    "physics.loop.records": (
        "Group", "Records", "prepare", "group_label", "group_keys", "split_records",
        "entry_scatter", "shaft_rates", "by_group"),
    "physics.loop.simulation": ("responses", "model_signals"),
    "physics.loop.comparison": (
        "residuals_db", "standardised", "residuals", "noise_only", "rms", "feature_error",
        "residual_table", "group_errors"),
    "physics.loop.fit": (
        "Candidate", "calibrate", "search", "explore", "screen_effect", "least_squares",
        "identifiable", "with_level", "train_cost", "screened"),
    "physics.loop.discrepancy": (
        "entry_family", "discrepancy_sd", "with_discrepancy", "discrepancy_allowance"),
    "physics.loop.wear_reading": (
        "WearScore", "Reader", "wear_estimates", "wear_reference", "wear_score", "wear_skill",
        "wear_check", "reads_wear"),
    "physics.loop.attribution": (
        "Round", "attribute", "candidates_for", "stacked", "second_candidates",
        "signature_gain", "whole_cut", "free_directions", "separable_share", "bic"),
    "physics.loop.form_error": ("FormReference", "form_reference", "check_reference"),
    "physics.loop.own_history": (
        "History", "parse_history", "split_history", "own_reference", "life_order"),
    "physics.loop.report": (
        "LoopReport", "STABLE_KEYS", "write_report", "null_test", "holds", "first_passing",
        "verdict_line"),
    "physics.loop.lines": (
        "unexplained_lines", "declared_lines", "record_spectrum", "crossing_probability"),
    "physics.loop.verdict": (
        "VERDICTS", "judge", "unexplained_entries", "group_lines", "entry_kind"),
    "physics.loop.usable": ("check_usable", "shown_candidates"),
    "physics.loop.threads": ("TimeLimit", "one_blas_thread", "each", "in_time"),
    "physics.loop.bundle_loop": ("run_loop",),
    "physics.loop.table_loop": ("run_feature_table", "parse_columns"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
