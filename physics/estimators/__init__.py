"""Wear estimators from vibration features (thesis 4.4): the analytic empirical inverse. Imports the
physics subpackages above it (``gear`` ... ``signals``)."""
