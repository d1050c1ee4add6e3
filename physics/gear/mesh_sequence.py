"""The meshing sequence of a spur pair: which pinion tooth meets which gear tooth, and when.

Teeth are numbered in the order they enter the mesh. Mesh ``m`` (the ``m``-th tooth pair to
enter contact, counted from a pair ``(0, 0)``) brings pinion tooth ``m mod z1`` onto gear tooth
``m mod z2``: each mesh advances both wheels by one pitch. The pattern repeats after the
hunting period ``lcm(z1, z2)`` meshes, in which every pinion tooth meets ``z2 / gcd(z1, z2)``
gear teeth and every gear tooth ``z1 / gcd(z1, z2)`` pinion teeth, each pair once: pinion
tooth ``i`` meets gear tooth ``j`` only where ``i = j mod gcd(z1, z2)`` (why gear designers
choose "hunting" tooth numbers with no common factor; e.g. Dudley, *Handbook of Practical Gear
Design*, 1984). With a
common factor the teeth fall into ``gcd`` families that never touch one another, so a
difference between teeth persists.

A state may also hold *one* tooth for a wheel whose teeth are alike: its one flank stands for
all of them. :func:`meshing_sequence` covers both: with ``n1`` and ``n2`` teeth carried (each 1 or
the wheel's count) the pattern repeats after ``lcm(n1, n2)`` meshes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def hunting_period(z1: int, z2: int) -> int:
    """Meshes after which the same pinion tooth meets the same gear tooth again:
    ``lcm(z1, z2)``."""
    return math.lcm(int(z1), int(z2))


@dataclass(frozen=True)
class MeshSequence:
    """One repeat of the meshing sequence of a state with ``n1`` pinion and ``n2`` gear teeth
    carried (each 1, for teeth alike, or the wheel's count).

    ``pinion[m]`` and ``gear[m]`` are the teeth of mesh ``m``, ``m = 0 .. len - 1``; every pair
    of the repeat is distinct."""

    z1: int
    z2: int
    n1: int
    n2: int
    pinion: np.ndarray  # (meshes,) int
    gear: np.ndarray  # (meshes,) int

    def __len__(self) -> int:
        return len(self.pinion)

    def per_pinion_cycle(self) -> tuple[tuple[int, int], tuple[int, int]]:
        """``(numerator, denominator)`` of the factors, pinion and gear, that turn wear summed
        over one repeat of the sequence on a carried tooth into wear per pinion cycle of each
        real tooth: the repeat turns the pinion ``len / z1`` times, and a carried tooth stands
        for ``z / n`` real teeth, which share its sum. Pinion ``n1 / len``; gear ``z1 n2 /
        (len z2)`` (teeth alike: ``z1 / z2``, a gear tooth meshes that often per pinion
        cycle). Whole numbers, so that ``x * num / den`` rounds as the single-tooth model
        always has."""
        n = len(self)
        return (self.n1, n), (self.z1 * self.n2, n * self.z2)

    def distinct_pairs(self, wear1: np.ndarray, wear2: np.ndarray
                       ) -> tuple[list[tuple[int, int]], np.ndarray]:
        """The pairs of the repeat whose teeth differ, for teeth worn by ``wear1`` ``(n1, ...)``
        and ``wear2`` ``(n2, ...)``: one ``(pinion row, gear row)`` of each distinct pair of
        wear states, and for each mesh the index of its pair among them. Whatever depends on a
        pair's two flanks alone (its gaps, its compliance, its tables) is then computed once a
        distinct pair: teeth still alike (a start from new) share it."""
        rows1, rows2 = (np.unique(np.asarray(w).reshape(len(w), -1), axis=0,
                                  return_inverse=True)[1].ravel() for w in (wear1, wear2))
        kinds = rows1[self.pinion] * (rows2.max() + 1) + rows2[self.gear]
        _, first, index = np.unique(kinds, return_index=True, return_inverse=True)
        return ([(int(self.pinion[m]), int(self.gear[m])) for m in first], index.ravel())


def meshing_sequence(z1: int, z2: int, n1: int | None = None, n2: int | None = None
                     ) -> MeshSequence:
    """The meshing sequence of a ``z1``/``z2`` pair carrying ``n1`` pinion and ``n2`` gear
    teeth (each 1 or the wheel's count; by default every tooth: the hunting period).

    >>> seq = meshing_sequence(18, 27)
    >>> len(seq), sorted(set(seq.gear[seq.pinion == 0].tolist()))
    (54, [0, 9, 18])
    >>> len(meshing_sequence(18, 27, n2=1)), len(meshing_sequence(18, 27, 1, 1))
    (18, 1)
    """
    z1, z2 = _teeth("z1", z1), _teeth("z2", z2)
    n1 = z1 if n1 is None else n1
    n2 = z2 if n2 is None else n2
    for name, n, z in (("n1", n1, z1), ("n2", n2, z2)):
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n not in (1, z):
            raise ValueError(f"{name} = {n!r}: a state carries one flank per tooth ({z}) or one "
                             f"for teeth alike (1); give {z} or 1")
    n1, n2 = int(n1), int(n2)
    m = np.arange(math.lcm(n1, n2))
    return MeshSequence(z1, z2, n1, n2, m % n1, m % n2)


def _teeth(name: str, z: object) -> int:
    """A tooth count as an int; ``ValueError`` naming it unless it is a whole number >= 1."""
    if isinstance(z, bool) or not isinstance(z, int | np.integer) or z < 1:
        raise ValueError(f"{name} = {z!r} must be a whole number of teeth >= 1")
    return int(z)
