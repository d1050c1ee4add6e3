"""The measured-data loop: declared model, effects, bundles, the bundle and feature-table loops,
report type, synthetic and independent-simulator bundles; the app ``python -m physics.loop``.
Imports every physics subpackage above it except the apps."""
