"""Configs: dataset (see ../__init__.py)."""
