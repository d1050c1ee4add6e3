"""Configs: predict (see ../__init__.py)."""
