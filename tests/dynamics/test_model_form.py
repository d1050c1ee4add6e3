"""The model's form factors (physics.dynamics.model_form): what each moves, and that a scenario
that states them gets them in every model it builds."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.dynamics.model import build_model, simulate
from physics.dynamics.model_form import FACTORS, with_model_form
from physics.params import scenario_from_config


@pytest.fixture(scope="module")
def scn():
    return scenario_from_config({"case": 3})


def _dte(models, scn, seconds=0.25):
    dyn = dataclasses.replace(scn.dynamics, duration_s=seconds, transient_s=0.05, phase_bins=16)
    return simulate(models, dyn).dte


def _stated(scn, **factors):
    return dataclasses.replace(scn, dynamics=dataclasses.replace(scn.dynamics, **factors))


def test_factors_move_stiffness_mass_and_keep_the_damping_ratio(scn):
    m = build_model(scn)
    out = with_model_form(m, {"stiffness_factor": 1.5, "resonance_factor": 0.8,
                              "double_contact_factor": 1.2, "half_backlash_um": 10.0})
    double = m.k_b > 0
    np.testing.assert_allclose(out.k_a[~double], 1.5 * m.k_a[~double])  # single contact
    np.testing.assert_allclose((out.k_a + out.k_b)[double], 1.8 * (m.k_a + m.k_b)[double])
    # the mesh resonance sqrt(k_mean / m_e) moves by the resonance factor alone
    assert np.sqrt(np.mean(out.k_a + out.k_b) / out.mass) == pytest.approx(
        0.8 * np.sqrt(np.mean(m.k_a + m.k_b) / m.mass))
    # m_e = J1 J2 / (J1 rb2^2 + J2 rb1^2) of the scaled inertias is the scaled mass
    (j1, j2), g = out.inertias, m.geometry
    assert j1 * j2 / (j1 * g.rb2**2 + j2 * g.rb1**2) == pytest.approx(out.mass)

    def ratio(x):
        return x.damping / (2 * np.sqrt(np.mean(x.k_a + x.k_b) * x.mass))

    assert ratio(out) == pytest.approx(ratio(m))
    assert out.half_backlash == pytest.approx(10e-6)
    # the declared DTE is measured from the centre of the backlash: the datum moves its mean
    base, moved = _dte([m, dataclasses.replace(m, half_backlash=10e-6)], scn)
    assert np.mean(base) - np.mean(moved) == pytest.approx(m.half_backlash - 10e-6, rel=1e-3)


def test_the_neutral_scenario_builds_the_declared_model(scn):
    m = build_model(scn)
    assert all(getattr(scn.dynamics, f) == 1.0 for f in FACTORS)
    assert with_model_form(m, {f: 1.0 for f in FACTORS}) is m


@settings(max_examples=8, deadline=None)
@given(s_k=st.floats(0.5, 2.0), r=st.floats(0.6, 1.6), f_r=st.floats(0.5, 2.0))
def test_a_scenarios_factors_are_those_of_every_model_it_builds(scn, s_k, r, f_r):
    factors = {"stiffness_factor": s_k, "double_contact_factor": r, "resonance_factor": f_r}
    stated = build_model(_stated(scn, **factors))
    by_hand = with_model_form(build_model(scn), factors)
    for name in ("k_a", "k_b", "mass", "damping", "inertias"):
        np.testing.assert_allclose(np.asarray(getattr(stated, name)),
                                   np.asarray(getattr(by_hand, name)), rtol=1e-12, err_msg=name)


def test_a_stiffer_mesh_deflects_less_under_the_same_load(scn):
    """The static deflection on the line of action is ``W / k(t)`` (thesis 3.3): at twice the
    stiffness level, half the mean elastic deflection (the DTE mean less the half backlash, its
    datum), and that mean is the static one, the period mean of ``W / k``."""
    m = build_model(scn)
    stiff = build_model(_stated(scn, stiffness_factor=2.0))
    soft, hard = (np.mean(x) - m.half_backlash for x in _dte([m, stiff], scn))
    assert hard / soft == pytest.approx(0.5, rel=0.02)
    assert soft == pytest.approx(m.static_force * np.mean(1 / (m.k_a + m.k_b)), rel=0.02)
