"""The check a public function makes of what it is given (:func:`argument`,
:func:`path_argument`): a function given None, a number or a mapping where it takes a path, a
table or a scenario fails at its door with one line naming the argument, not deep inside with
an AttributeError. Imports nothing of the physics, so that any module may use it."""

from __future__ import annotations

import os
from pathlib import Path


def _shown(value: object, most: int = 60) -> str:
    """``value``'s repr on one line, cut to ``most`` characters."""
    text = " ".join(repr(value).split())
    return text if len(text) <= most else text[:most - 3] + "..."


def argument(value: object, name: str, kinds: type | tuple[type, ...], allowed: str) -> object:
    """``value`` if it is one of ``kinds`` (a bool never passes for anything else), else a
    TypeError in one line naming the argument ``name`` (e.g. ``read_bundle(path)``), the
    value, its type and what is ``allowed``: a public function of the loop given None, a
    number or a mapping where it takes a path, a table or a scenario fails there, not deep
    inside with an AttributeError."""
    kinds = kinds if isinstance(kinds, tuple) else (kinds,)
    if isinstance(value, kinds) and (bool in kinds or not isinstance(value, bool)):
        return value
    raise TypeError(f"{name} = {_shown(value)} is of type {type(value).__name__}; it must be "
                    f"{allowed}")


def path_argument(value: object, name: str, what: str) -> Path:
    """``value`` as a :class:`~pathlib.Path` (:func:`argument`: a str or an os.PathLike that
    is not empty; an empty name would be the working folder), ``what`` saying what it
    names (e.g. "a bundle folder")."""
    allowed = f"the path of {what} (a str or pathlib.Path)"
    argument(value, name, (str, os.PathLike), allowed)
    if not str(os.fspath(value)).strip():
        raise ValueError(f"{name} = {_shown(value)} is empty (it would be the working "
                         f"folder); it must be {allowed}")
    return Path(value)
