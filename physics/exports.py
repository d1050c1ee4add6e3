"""A subpackage's public names, each imported on first use (PEP 562), so that importing a package
or one of its modules stays light and free of import cycles. Every ``__init__.py`` of the
project states its names by the module that defines each and calls :func:`lazy_exports`."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable


def lazy_exports(package: str, sources: dict[str, tuple[str, ...]]
                 ) -> tuple[list[str], Callable[[str], object], Callable[[], list[str]]]:
    """``__all__``, ``__getattr__`` and ``__dir__`` of ``package`` for the public names
    ``sources`` (``{module: names}``); a name, once imported, is kept in the package."""
    source = {name: module for module, names in sources.items() for name in names}
    public = sorted(source)

    def __getattr__(name: str) -> object:
        if name in source:
            value = getattr(importlib.import_module(source[name]), name)
            setattr(sys.modules[package], name, value)
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted({*vars(sys.modules[package]), *public})

    return public, __getattr__, __dir__
