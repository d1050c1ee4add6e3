"""Configs: train (see ../__init__.py)."""
