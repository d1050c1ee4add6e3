"""Gear geometry and elasticity (thesis 2.1-2.3, 3.1-3.2): line of action, kinematics, the
rack-generated tooth, Hertz line contact, potential-energy mesh stiffness of worn teeth, its
finite-element check, and double-tooth load sharing. Imports numpy/scipy and ``physics.params``."""
