"""The meshing sequence (physics.gear.mesh_sequence): the hunting period, which teeth meet, and
the factors that turn wear over a repeat into wear per pinion cycle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from physics.gear.mesh_sequence import hunting_period, meshing_sequence

teeth = st.integers(5, 60)


@given(z1=teeth, z2=teeth)
def test_every_pair_that_can_meet_meets_once_a_hunting_period(z1, z2):
    seq = meshing_sequence(z1, z2)
    assert len(seq) == hunting_period(z1, z2) == z1 * z2 // math.gcd(z1, z2)
    pairs = set(zip(seq.pinion.tolist(), seq.gear.tolist(), strict=True))
    assert len(pairs) == len(seq)  # each pair once
    g = math.gcd(z1, z2)
    # the hunting-tooth rule: tooth i meets tooth j exactly when i = j mod gcd
    assert pairs == {(i, j) for i in range(z1) for j in range(z2) if (i - j) % g == 0}
    assert np.all(np.bincount(seq.pinion, minlength=z1) == z2 // g)
    assert np.all(np.bincount(seq.gear, minlength=z2) == z1 // g)
    # consecutive meshes bring consecutive teeth of both wheels
    assert np.all(np.diff(seq.pinion) % z1 == 1) and np.all(np.diff(seq.gear) % z2 == 1)


@given(z1=teeth, z2=teeth, n1=st.sampled_from(["one", "all"]), n2=st.sampled_from(["one", "all"]))
def test_wear_over_a_repeat_becomes_each_real_teeths_wear_per_pinion_cycle(z1, z2, n1, n2):
    """Every pair of a repeat wearing its teeth by the same ``d`` wears each real pinion tooth
    by ``d`` and each real gear tooth by ``d z1 / z2`` per pinion cycle (a gear tooth meshes
    ``z1 / z2`` times per pinion revolution), whatever teeth the state carries."""
    n1, n2 = (1 if n == "one" else z for n, z in ((n1, z1), (n2, z2)))
    seq = meshing_sequence(z1, z2, n1, n2)
    (a, b), (c, d) = seq.per_pinion_cycle()
    summed1 = np.bincount(seq.pinion, minlength=n1)  # d = 1 on every mesh
    summed2 = np.bincount(seq.gear, minlength=n2)
    np.testing.assert_allclose(summed1 * a / b, 1.0, rtol=1e-12)
    np.testing.assert_allclose(summed2 * c / d, z1 / z2, rtol=1e-12)


def test_teeth_alike_carry_one_flank():
    assert len(meshing_sequence(18, 27, 18, 1)) == 18
    assert len(meshing_sequence(18, 27, 1, 27)) == 27
    seq = meshing_sequence(18, 27, 1, 1)
    assert len(seq) == 1 and seq.per_pinion_cycle() == ((1, 1), (18, 27))


@pytest.mark.parametrize(("args", "message"), [
    ((18, 27, 9), "n1 = 9: a state carries one flank per tooth"),
    ((18, 27, 18, 3), "n2 = 3"),
    ((0, 27), "z1 = 0 must be a whole number"),
    ((18, 27.5), "z2 = 27.5 must be a whole number"),
    ((True, 27), "z1 = True"),
    ((18, 27, 18.0), "n1 = 18.0"),
])
def test_bad_sequences_are_refused(args, message):
    with pytest.raises(ValueError, match=message):
        meshing_sequence(*args)


def test_pairs_of_the_same_two_flanks_are_computed_once():
    seq = meshing_sequence(18, 27)
    alike = seq.distinct_pairs(np.zeros((18, 5)), np.zeros((27, 5)))
    assert alike[0] == [(0, 0)] and np.all(alike[1] == 0)
    one = np.zeros((18, 5))
    one[4] = 1.0  # pinion tooth 4 worn: its 3 meshes differ from the rest's
    pairs, index = seq.distinct_pairs(one, np.zeros((27, 5)))
    assert len(pairs) == 2 and np.sum(index == index[4]) == 3
    for m in range(len(seq)):  # each mesh's representative has the mesh's two flanks
        i, j = pairs[index[m]]
        assert np.array_equal(one[i], one[seq.pinion[m]]) and j in range(27)
    own = seq.distinct_pairs(np.arange(18.0)[:, None], np.arange(27.0)[:, None])
    assert len(own[0]) == len(seq) == 54
