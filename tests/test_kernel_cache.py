"""The kernels compiled ahead of a parallel run (tests/kernel_cache.py) are the package's."""

from __future__ import annotations

import importlib

import numba

from tests.kernel_cache import KERNELS


def test_every_kernel_compiled_ahead_is_a_kernel_of_its_module():
    """A kernel renamed or moved would leave the cache always stale (compiled ahead every
    run): each named one is a numba dispatcher of the module named, cached on disk."""
    for path, name in KERNELS:
        module = importlib.import_module(path.removesuffix(".py").replace("/", "."))
        kernel = getattr(module, name)
        assert isinstance(kernel, numba.core.registry.CPUDispatcher), (path, name)
        assert kernel._cache.__class__.__name__ == "FunctionCache", (path, name)
