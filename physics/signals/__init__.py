"""Vibration signals (thesis 4.2): the Table 13 features, order analysis and the declared
measurement chain (DTE, housing acceleration, noise). Imports ``physics.params`` and
``physics.dynamics``."""
