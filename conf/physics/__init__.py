"""Configs: physics (see ../__init__.py)."""
