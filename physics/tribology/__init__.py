"""Tribology of the tooth contact: Hertz contact, lubrication (regressions and the numerical
mixed-EHL solver), flash temperature, contact state, wear. Imports numpy/scipy and
physics.params/physics.gear only."""
