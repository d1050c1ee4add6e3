"""Configs: reproduce (see ../__init__.py)."""
