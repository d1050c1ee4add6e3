"""Each pinion tooth its own flank (physics.dynamics.teeth): a uniform set of teeth is the
one-period model, one worn tooth repeats once per revolution, a state worn tooth by tooth is the
model of its meshing sequence, and Table 15 by the model."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from physics import reference
from physics.dynamics.model import build_model, simulate
from physics.dynamics.teeth import per_tooth_model, sequence_model, with_tooth_positions
from physics.gear.accuracy import tooth_positions_um
from physics.gear.stiffness import mesh_stiffness
from physics.params import Scenario
from physics.reproduce.localised import FEATURES, INDICATOR_ROWS, table15_model
from physics.tribology.wear import simulate_wear

THESIS_TABLES = reference.THESIS_TABLES


def _scn(contact: str, revolutions: float = 2.0, eccentricity_um: float = 7.5) -> Scenario:
    base = Scenario()
    return dataclasses.replace(base, dynamics=dataclasses.replace(
        base.dynamics, flank_contact=contact, duration_s=revolutions * 60 / 2000,
        eccentricity1_um=eccentricity_um))


@pytest.fixture(scope="module")
def worn_state():
    scn = Scenario()
    res = simulate_wear(scn, 1e6)
    return res.s, res.pinion / res.pinion.max() * 10e-6


@pytest.mark.parametrize("contact", ["path", "exact"])
def test_a_uniform_set_of_teeth_is_the_one_period_model(contact, worn_state):
    scn = _scn(contact)
    ms = mesh_stiffness(scn.gear, scn.material)
    s, w1 = worn_state
    one = build_model(scn, ms, s, w1, np.zeros_like(w1))
    tiled = per_tooth_model([one] * scn.gear.z1)
    assert tiled.periods == scn.gear.z1 and len(tiled.k_a) == scn.gear.z1 * len(one.k_a)
    a, b = simulate([one], scn.dynamics), simulate([tiled], scn.dynamics)
    np.testing.assert_allclose(b.force, a.force, rtol=1e-9, atol=1e-9 * one.static_force)


def test_one_worn_tooth_repeats_once_per_revolution(worn_state):
    """All teeth worn alike excite the mesh orders only; one worn tooth adds the shaft orders
    around them (its sidebands), what a synchronous average reads (no run-out here: it makes
    shaft orders of its own)."""
    scn = _scn("exact", revolutions=5, eccentricity_um=0.0)  # 6144 samples: whole revolutions
    ms = mesh_stiffness(scn.gear, scn.material)
    s, w1 = worn_state
    new = build_model(scn, ms)
    worn = build_model(scn, ms, s, w1, np.zeros_like(w1))
    z1 = scn.gear.z1
    models = [per_tooth_model([worn] * z1), per_tooth_model([worn] + [new] * (z1 - 1))]
    force = simulate(models, scn.dynamics, every_phase=False).force
    force -= force.mean(axis=1, keepdims=True)
    spectrum = np.abs(np.fft.rfft(force, axis=1))  # 5 revolutions: shaft order k at bin 5 k
    shaft = spectrum[:, 5 * np.arange(1, 3 * z1)]
    mesh_orders = np.arange(1, 3 * z1) % z1 == 0
    energy = (shaft[:, ~mesh_orders] ** 2).sum(axis=1) / (shaft[:, mesh_orders] ** 2).sum(axis=1)
    assert energy[0] < 1e-5  # the tables' grid leaves a trace
    assert energy[1] > 1e-4


def test_a_tooth_count_that_is_not_the_pinions_is_refused():
    scn = _scn("path")
    m = build_model(scn, mesh_stiffness(scn.gear, scn.material))
    with pytest.raises(ValueError, match=r"17 tooth models for a 18/27 pair; give one per "
                                         r"pinion tooth \(18\) or one per mesh of the hunting "
                                         r"period \(54"):
        per_tooth_model([m] * 17)


def test_a_state_worn_tooth_by_tooth_becomes_the_model_of_its_meshing_sequence(worn_state):
    """sequence_model: teeth alike on both wheels are the one-period model tiled; every tooth
    of both wheels carried alike spans the hunting period (54 meshes) and moves the same; one
    pinion tooth's own wear is pair A's tables in the meshes it enters, and each tooth's
    position closes its pairs' gaps as with_tooth_positions does."""
    scn = _scn("path")
    ms = mesh_stiffness(scn.gear, scn.material)
    s, w1 = worn_state
    w2 = np.zeros_like(w1)
    z1, z2 = scn.gear.z1, scn.gear.z2
    one = build_model(scn, ms, s, w1, w2)
    tiled = per_tooth_model([one] * z1)
    uniform = sequence_model(scn, ms, s, w1[None], w2[None], n_phase=len(one.k_a))
    for name in ("k_a", "k_b", "g_a", "g_b"):
        np.testing.assert_array_equal(getattr(uniform, name), getattr(tiled, name))
    hunting = sequence_model(scn, ms, s, np.tile(w1, (z1, 1)), np.tile(w2, (z2, 1)),
                             n_phase=len(one.k_a))
    assert hunting.periods == 54
    a, b = simulate([tiled], scn.dynamics), simulate([hunting], scn.dynamics)
    np.testing.assert_allclose(b.force, a.force, rtol=1e-9, atol=1e-9 * one.static_force)
    rows = np.zeros((z1, s.size))
    rows[4] = w1
    own = sequence_model(scn, ms, s, rows, w2[None], n_phase=len(one.k_a))
    n = len(one.k_a)
    np.testing.assert_array_equal(own.g_a[4 * n:5 * n], one.g_a)
    assert np.all(own.g_a[:4 * n] == 0) and np.all(own.g_a[5 * n:] == 0)
    pos = 1e-6 * np.arange(z1)
    placed = sequence_model(scn, ms, s, rows, w2[None], (pos, np.zeros(1)), n_phase=n)
    new = build_model(scn, ms, n_phase=n)
    expected = per_tooth_model(with_tooth_positions([one if i == 4 else new for i in range(z1)],
                                                    pos))
    np.testing.assert_array_equal(placed.g_a, expected.g_a)
    np.testing.assert_array_equal(
        sequence_model(scn, ms, s, rows, w2[None], (pos, None), n_phase=n).g_a, placed.g_a)
    with pytest.raises(ValueError, match="give a row per tooth"):
        sequence_model(scn, ms, s, w1, w2)
    with pytest.raises(ValueError, match=r"positions of the gear of shape \(27,\): give one per "
                                         r"row of its wear \(1\)"):
        sequence_model(scn, ms, s, rows, w2[None], (pos, np.zeros(z2)), n_phase=n)


def test_table15_by_the_model(worn_state):
    """Root wear on every tooth raises the housing RMS with its depth; on one tooth less; the
    measured rises come from the thesis's table when it is given, NaN otherwise."""
    scn = Scenario()
    base = simulate_wear(scn, 1e6)
    table = table15_model(scn, base, THESIS_TABLES)
    assert list(table.columns) == ["wear_mm", "feature", "rise_measured", "rise_one_tooth",
                                   "rise_all_teeth", "rise_one_tooth_mode_least",
                                   "rise_one_tooth_mode_largest"]
    modes = table[table["feature"].isin(list(FEATURES))]
    assert (modes.rise_one_tooth_mode_least <= modes.rise_one_tooth_mode_largest).all()
    assert len(table) == 3 * (len(FEATURES) + len(INDICATOR_ROWS))
    fm4 = table[table["feature"] == "fm4"]
    assert np.all(fm4["rise_one_tooth"] > 5 * fm4["rise_all_teeth"])  # a local fault's mark
    rms = table[table["feature"] == "rms"]
    assert np.all(np.diff(rms["rise_all_teeth"]) > 0)
    assert np.all(rms["rise_one_tooth"] < rms["rise_all_teeth"])
    assert np.all(table["rise_one_tooth"] > 1.0)
    assert table.loc[table["feature"].isin(INDICATOR_ROWS), "rise_measured"].isna().all()
    assert rms["rise_measured"].iloc[-1] == pytest.approx(2.278 / 1.066)
    assert table15_model(scn, base, None)["rise_measured"].isna().all()


def test_every_tooth_ahead_alike_shifts_the_transmission_error_and_nothing_else():
    """All pinion teeth ahead by the same ``d``: the flanks meet ``d`` earlier, so the DTE is
    the one of the theoretical teeth less ``d`` at every instant, and the mesh force the same."""
    scn = _scn("path")
    ms = mesh_stiffness(scn.gear, scn.material)
    one = build_model(scn, ms)
    z1, d = scn.gear.z1, 3e-6
    models = [per_tooth_model([one] * z1),
              per_tooth_model(with_tooth_positions([one] * z1, [d] * z1))]
    a, b = simulate(models, scn.dynamics).dte, simulate(models, scn.dynamics).force
    np.testing.assert_allclose(a[1], a[0] - d, rtol=0, atol=1e-6 * np.ptp(a[0]))
    np.testing.assert_allclose(b[1], b[0], rtol=1e-6, atol=1e-6 * one.static_force)
    with pytest.raises(ValueError, match="17 tooth positions for 18 tooth models"):
        with_tooth_positions([one] * z1, [0.0] * 17)


def test_pitch_deviations_of_a_grade_make_shaft_orders_that_grow_with_the_grade():
    """Teeth off their places by the single pitch deviations ISO 1328 allows: the synchronous
    average sees shaft orders between the mesh orders, more for a coarser grade (the same seed,
    so the same pattern scaled by sqrt(2) per grade)."""
    scn = _scn("exact", revolutions=5, eccentricity_um=0.0)
    ms = mesh_stiffness(scn.gear, scn.material)
    one = build_model(scn, ms)
    z1, g = scn.gear.z1, scn.gear
    d1 = g.module_mm * g.z1
    models = [per_tooth_model(with_tooth_positions(
        [one] * z1, 1e-6 * tooth_positions_um(z1, grade, g.module_mm, d1, seed=4)))
        for grade in (4, 6, 8)]
    force = simulate(models, scn.dynamics, every_phase=False).force
    force -= force.mean(axis=1, keepdims=True)
    spectrum = np.abs(np.fft.rfft(force, axis=1))
    shaft = spectrum[:, 5 * np.arange(1, 3 * z1)]
    between = np.arange(1, 3 * z1) % z1 != 0
    level = np.sqrt((shaft[:, between] ** 2).sum(axis=1))
    assert np.all(np.diff(level) > 0)
