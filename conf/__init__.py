"""Hydra configs of gearwear, shipped as the package ``gearwear_conf`` (``pyproject.toml`` maps
it to this folder). One folder per app, each its own config namespace; ``physics/`` holds the
physics parameter groups that the physics apps share through their search path."""
