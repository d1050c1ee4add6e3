"""Wear and vibration datasets across the operating cases of thesis Table 11: spec, chunks, resume,
merge (``physics.dataset.generation``) and the app ``python -m physics.dataset``. Imports the
physics subpackages above it; nothing imports the app."""
