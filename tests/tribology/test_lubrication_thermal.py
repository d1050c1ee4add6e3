"""Rheology, Masjedi-Khonsari regressions and flash temperature (thesis 2.4-2.5)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.tribology import lubrication, thermal

VISC = {"eta0": 0.35, "alpha": 2.5e-8, "beta0": 0.03, "t0": 315.0}


def test_roelands_reference_state_and_coefficients():
    assert lubrication.viscosity(0.0, 315.0, **VISC) == pytest.approx(0.35)
    dp, dT = 1e3, 1e-3
    dlnp = (math.log(lubrication.viscosity(dp, 315.0, **VISC)) - math.log(0.35)) / dp
    assert dlnp == pytest.approx(2.5e-8, rel=1e-4)  # alpha = d ln(eta)/dp at p = 0
    dlnt = (math.log(lubrication.viscosity(0.0, 315.0 + dT, **VISC)) - math.log(0.35)) / dT
    assert dlnt == pytest.approx(-0.03, rel=1e-3)  # -beta0 at T0


@settings(max_examples=40)
@given(p=st.floats(0, 3e9), T=st.floats(300, 500))
def test_viscosity_rises_with_pressure_and_falls_with_temperature(p, T):
    eta = lubrication.viscosity(p, T, **VISC)
    assert lubrication.viscosity(p * 1.1 + 1e6, T, **VISC) > eta
    assert lubrication.viscosity(p, T + 5, **VISC) < eta


def test_dowson_higginson_limits():
    assert lubrication.density(0.0, 315.0, 870.0, 315.0) == pytest.approx(870.0)
    assert lubrication.density(1e13, 315.0, 870.0, 315.0) == pytest.approx(
        870.0 * (1 + 0.6 / 1.7), rel=1e-3)
    assert lubrication.density(0.0, 335.0, 870.0, 315.0) < 870.0


def _groups(w=3.94e5, R=3.694e-3, u=1.289, eta=0.35, sigma=0.5e-6):
    e_prime = 2 * 206e9 / (2 * (1 - 0.09))
    return lubrication.dimensionless_groups(w, R, u, eta, 2.5e-8, e_prime, 7e9, sigma)


def test_masjedi_khonsari_hand_calculation_at_the_thesis_pitch_point():
    g = _groups()
    # W = w/(E'R), U = eta u/(E'R), G = alpha E': E' = 226.4 GPa
    assert float(g["W"]) == pytest.approx(4.71e-4, rel=2e-3)
    assert float(g["U"]) == pytest.approx(5.39e-10, rel=2e-3)
    assert float(g["G"]) == pytest.approx(5659, rel=1e-3)
    H = lubrication.min_film_thickness(g["W"], g["U"], g["G"], g["sigma_bar"])
    h = float(H) * 3.694e-3
    # 1.652 * 1.803 * 2.318e-7 * 406.6 * R ~ 1.03 um
    assert h == pytest.approx(1.03e-6, rel=0.02)


def test_film_grows_with_speed_and_asperity_share_falls():
    lo, hi = _groups(u=0.6), _groups(u=1.9)
    h_lo = lubrication.min_film_thickness(lo["W"], lo["U"], lo["G"], lo["sigma_bar"])
    h_hi = lubrication.min_film_thickness(hi["W"], hi["U"], hi["G"], hi["sigma_bar"])
    assert h_hi > h_lo
    la = [lubrication.asperity_load_ratio_pct(g["W"], g["U"], g["G"], g["V"], g["sigma_bar"])
          for g in (lo, hi)]
    assert la[1] < la[0]


def test_asperity_share_rises_with_roughness_and_vanishes_for_smooth_surfaces():
    shares = [lubrication.asperity_load_ratio_pct(**{k: v for k, v in _groups(sigma=s).items()})
              for s in (1e-12, 0.3e-6, 0.5e-6, 1e-6)]
    assert shares[0] == pytest.approx(0.0, abs=1e-6)
    assert shares[1] < shares[2] < shares[3]


@pytest.mark.parametrize("pe", [200.0, 1000.0])
def test_band_source_tends_to_the_high_peclet_form(pe):
    assert thermal.band_source_max_rise(pe) == pytest.approx(2 / math.sqrt(math.pi * pe),
                                                             rel=5e-3)


@pytest.mark.parametrize("pe", [0.3, 1.0, 4.0])
def test_band_source_against_direct_integration_of_jaeger_kernel(pe):
    """theta(xi) = (1/pi) int_{-1}^{1} exp(-Pe (xi - x)) K0(Pe |xi - x|) dx, maximised."""
    from scipy.integrate import quad
    from scipy.optimize import minimize_scalar
    from scipy.special import k0

    def theta(xi):
        f = lambda x: math.exp(-pe * (xi - x)) * k0(pe * abs(xi - x))  # noqa: E731
        return quad(f, -1, xi, limit=200)[0] + quad(f, xi, 1, limit=200)[0]

    best = minimize_scalar(lambda xi: -theta(xi), bounds=(-1, 1), method="bounded")
    assert thermal.band_source_max_rise(pe) == pytest.approx(-best.fun / math.pi,
                                                             rel=2e-3)


@given(st.floats(1e-7, 1e4))
@settings(max_examples=60, deadline=None)
def test_tabulated_rise_matches_the_band_scan(pe):
    # the log-log table of the maximum against scanning the band at this Peclet number
    direct = thermal._exact_max_rise(np.array([pe]))[0]
    assert thermal.band_source_max_rise(np.array([pe]))[0] == pytest.approx(direct, rel=3e-5)


def test_flash_temperature_is_blok_partition_of_two_single_body_rises():
    q, b, v1, v2, k, kappa = 1e8, 1e-4, 1.0, 3.0, 46.0, 1.25e-5
    single = [q * b / k * thermal.band_source_max_rise(thermal.peclet(v, b, kappa))
              for v in (v1, v2)]
    combined = 1 / (1 / single[0] + 1 / single[1])
    assert thermal.flash_temperature(q, b, v1, v2, k, kappa) == pytest.approx(combined)


@settings(max_examples=40)
@given(q=st.floats(1e6, 1e9), scale=st.floats(1.01, 5))
def test_flash_temperature_linear_in_heat_and_falls_with_speed(q, scale):
    base = thermal.flash_temperature(q, 1e-4, 1.0, 1.5, 46.0, 1.25e-5)
    assert thermal.flash_temperature(q * scale, 1e-4, 1.0, 1.5, 46.0, 1.25e-5) == pytest.approx(
        base * scale)
    assert thermal.flash_temperature(q, 1e-4, scale, 1.5 * scale, 46.0, 1.25e-5) < base


def test_heat_flux_vanishes_without_sliding():
    assert thermal.heat_flux(np.zeros(3), 1e8, 1e7, 0.1).tolist() == [0.0, 0.0, 0.0]


def test_fixed_point_solver_hits_the_root_of_a_decreasing_map():
    from physics.tribology.contact_state import _fixed_point

    scale = np.array([0.01, 1.0, 10.0, 100.0, 1e6])
    x, iterations = _fixed_point(lambda x: 100 * np.exp(-x / scale), np.zeros(5), 1e-9, 100)
    assert np.allclose(x, 100 * np.exp(-x / scale), atol=1e-8)
    assert iterations < 60
    with pytest.raises(RuntimeError, match="did not converge in 2 iterations"):
        _fixed_point(lambda x: 100 * np.exp(-x / scale), np.zeros(5), 1e-9, 2)
