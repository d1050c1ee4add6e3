"""Reproduction of the thesis tables 2-14 (``python -m physics.reproduce``): tables
(``physics.reproduce.thesis``) and figures (``physics.reproduce.plots``). Imports every physics
subpackage above it; nothing imports the app."""
