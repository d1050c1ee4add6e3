"""The asperity wear coefficient: its calibration, and the wear magnitude and bound it gives.

The default ``Tribology.wear_coeff`` is the result of ``python -m physics.tribology.calibration``
(one figure: 2.7 um quasi-static pinion root wear after 1.5e7 cycles at the baseline, thesis
Table 8); these tests check that the stored default is what that computation gives, that the
lubricated law never exceeds the dry one, and that the wear it implies is plausible elsewhere.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from physics.params import Lubricant, Operating, Scenario, Tribology
from physics.tribology import calibration
from physics.tribology.wear import simulate_wear, wear_coefficient


def test_stored_default_gives_the_calibration_target():
    """One wear run at the stored default lands on the target within 0.5 % (the default is
    rounded to three significant digits)."""
    wear = calibration.root_wear(Scenario(), Tribology().wear_coeff, calibration.DEFAULT_CYCLES)
    assert wear * 1e6 == pytest.approx(calibration.DEFAULT_TARGET_UM, rel=5e-3)


@pytest.mark.slow
def test_calibration_script_reproduces_the_stored_default(capsys):
    k = calibration.calibrate_wear_coeff()
    assert k == pytest.approx(Tribology().wear_coeff, rel=5e-3)
    assert calibration.main([]) == 0
    assert "Archard coefficient on the total load" in capsys.readouterr().out


def test_calibration_is_proportional_while_the_wear_is_small():
    """While no point wears by more than one profile update (1 um) and no point meets the dry
    bound the wear is proportional to k_a."""
    k0 = 1e-3
    small = calibration.root_wear(Scenario(), k0, 1e6)
    k = calibration.calibrate_wear_coeff(0.01, 1e6)
    assert k == pytest.approx(k0 * 0.01e-6 / small, rel=1e-4)
    assert calibration.root_wear(Scenario(), k, 1e6) * 1e6 == pytest.approx(0.01, rel=1e-5)


def test_calibration_refuses_bad_input():
    with pytest.raises(ValueError, match="must be positive"):
        calibration.calibrate_wear_coeff(-1.0)
    with pytest.raises(ValueError, match="regime must be 'mixed'"):
        calibration.calibrate_wear_coeff(scn=Scenario(tribology=Tribology(regime="dry")))


def test_implied_total_load_coefficient_lies_below_the_dry_one():
    """The coefficient is an Archard coefficient: k_a below 1, and the total-load coefficient
    it implies on the baseline path between 1e-10 and the dry 2e-8."""
    assert 0 < Tribology().wear_coeff < 1
    mean_k, top_k = calibration.total_load_coefficient(simulate_wear(Scenario(), 0.0))
    assert 1e-10 < mean_k < top_k <= Tribology().dry_wear_coeff


def test_wear_coefficient_is_bounded_by_the_dry_law():
    """At every share and deficiency the lubricated coefficient is at most the dry one, and at
    full unprotected asperity contact it is the dry law; a boundary share blends towards it."""
    tri = Tribology()
    share = np.array([0.0, 1e-6, 1e-4, 1e-2, 1.0])
    psi = np.array([1.0, 1e-3, 1.0, 1e-5, 1.0])
    k = wear_coefficient(tri, share, psi)
    assert np.all(k <= tri.dry_wear_coeff) and k[-1] == tri.dry_wear_coeff and k[0] == 0.0
    half = wear_coefficient(dataclasses.replace(tri, boundary_share=0.5), share, psi)
    assert np.all((half >= k) & (half <= tri.dry_wear_coeff))


@pytest.mark.parametrize("lub", [Lubricant(), Lubricant(eta0_Pa_s=0.1, alpha_m2_per_N=1.8e-8),
                                 Lubricant(eta0_Pa_s=0.25, alpha_m2_per_N=2.2e-8)])
def test_lubricated_wear_stays_below_the_dry_wear_at_every_point(lub):
    """Thesis 2.7.5: the dry law wears the most. The lubricated rate of the unworn flanks lies
    at or below the dry rate at every flank point, for the baseline oil and two thinner ones."""
    scn = dataclasses.replace(Scenario(), lubricant=lub)
    wet = simulate_wear(scn, 0.0).first_rate
    dry = simulate_wear(dataclasses.replace(scn, tribology=Tribology(regime="dry")),
                        0.0).first_rate
    assert np.all(wet.flank1 <= dry.flank1 * (1 + 1e-12))
    assert np.all(wet.flank2 <= dry.flank2 * (1 + 1e-12))


def test_lubricated_wear_magnitude_is_plausible():
    """Baseline after 1e6 cycles: a mean below the dry law's; the peak near the pinion root;
    nothing negative; the gear wears less than the pinion (it meshes z1/z2 times as often)."""
    res = simulate_wear(Scenario(), 1e6)
    dry = simulate_wear(Scenario(tribology=Tribology(regime="dry")), 1e6)
    assert 0.01e-6 < res.mean_depth() < dry.mean_depth()
    assert 0.1e-6 < res.pinion.max() < 10e-6
    assert np.argmax(res.pinion) < len(res.s) // 10  # at the pinion root
    assert res.pinion.min() >= 0 and res.gear.min() >= 0
    assert res.worn_area("gear") < res.worn_area("pinion")


@pytest.mark.parametrize("n1", [1000.0, 3000.0])
def test_wear_per_cycle_falls_with_speed(n1):
    """Thesis Table 2's trend: the film thickens with speed and the asperity share falls
    faster than the oil-film deficiency coefficient rises with the flash temperature."""
    base = simulate_wear(Scenario(), 1e6).mean_depth()
    other = simulate_wear(dataclasses.replace(Scenario(), operating=Operating(n1_rpm=n1)),
                          1e6).mean_depth()
    assert (other < base) == (n1 > 2000.0)
