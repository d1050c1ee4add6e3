"""Reproduction of the thesis tables 2-14 (``python -m physics.reproduce``): tables
(``physics.reproduce.thesis``) and figures (``physics.reproduce.plots``); the model beside a real
rig's vibration over wear (``python -m physics.reproduce.rig``); wear tooth by tooth
(``python -m physics.reproduce.teeth``); both pairs from new to worn out and their teeth's root
stress (``python -m physics.reproduce.worn_out``). Imports every physics
subpackage above it; nothing imports the app."""

from __future__ import annotations

from physics.exports import lazy_exports

#: the public names, by the module that defines each (imported on first use: physics.exports)
_SOURCES = {
    "physics.reproduce.thesis": ("ReproduceConfig", "reproduce"),
    "physics.reproduce.rig": ("rig_comparison", "read_rig_table"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _SOURCES)
