"""Configs: loop (see ../__init__.py)."""
