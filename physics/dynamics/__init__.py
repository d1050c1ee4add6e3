"""Torsional gear-pair dynamics (thesis 3.3-3.5, 4.1): the model with backlash and worn teeth, its
compiled kernels and two-DOF reference, and the dynamic-load/wear coupling (evolution). Imports
``physics.params``, ``physics.gear`` and ``physics.tribology``."""
