"""The lubricated wear coefficient: its calibration, and the wear magnitude it gives.

The default ``Tribology.wear_coeff`` is the result of ``python -m physics.tribology.calibration``
(one figure: 0.245 um average pinion wear after 1e6 cycles at the baseline, thesis Table 2);
these tests check that the stored default is what that computation gives and that the wear it
implies is plausible elsewhere.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from physics.params import Operating, Scenario, Tribology
from physics.tribology import calibration
from physics.tribology.wear import simulate_wear


def test_stored_default_gives_the_calibration_target():
    """One wear run at the stored default lands on the target within 0.5 % (the default is
    rounded to three significant digits)."""
    wear = calibration.mean_wear(Scenario(), Tribology().wear_coeff, 1e6)
    assert wear * 1e6 == pytest.approx(calibration.DEFAULT_TARGET_UM, rel=5e-3)


@pytest.mark.slow
def test_calibration_script_reproduces_the_stored_default(capsys):
    k = calibration.calibrate_wear_coeff()
    assert k == pytest.approx(Tribology().wear_coeff, rel=5e-3)
    assert calibration.main([]) == 0
    assert "calibrated wear_coeff" in capsys.readouterr().out


def test_calibration_is_proportional_while_the_wear_is_small():
    """While no point wears by more than one profile update (1 um) the wear is proportional to
    k; at the calibrated 0.245 um average (4 um at the root, 5 updates) it is sub-linear: the
    worn root sheds load to the partner pair."""
    k_thesis = calibration.THESIS_WEAR_COEFF
    small = calibration.mean_wear(Scenario(), k_thesis, 1e6)
    k = calibration.calibrate_wear_coeff(0.01, 1e6)
    assert k == pytest.approx(k_thesis * 0.01e-6 / small, rel=1e-4)
    assert calibration.mean_wear(Scenario(), k, 1e6) * 1e6 == pytest.approx(0.01, rel=1e-5)
    assert Tribology().wear_coeff > k_thesis * 0.245e-6 / small


def test_calibration_refuses_bad_input():
    with pytest.raises(ValueError, match="must be positive"):
        calibration.calibrate_wear_coeff(-1.0)
    with pytest.raises(ValueError, match="regime must be 'mixed'"):
        calibration.calibrate_wear_coeff(scn=Scenario(tribology=Tribology(regime="dry")))


def test_lubricated_wear_magnitude_is_plausible():
    """Baseline after 1e6 cycles: the calibrated average, below the dry law's; a peak at the
    pinion root of a few micrometres (the thin, hot film there concentrates the asperity
    load: 17 times the average, where the dry law has 5); nothing negative; the gear wears
    less than the pinion (it meshes z1/z2 times as often)."""
    res = simulate_wear(Scenario(), 1e6)
    dry = simulate_wear(Scenario(tribology=Tribology(regime="dry")), 1e6)
    assert 0.2e-6 < res.mean_depth() < 0.3e-6 < dry.mean_depth()
    assert 1e-6 < res.pinion.max() < 10e-6
    assert np.argmax(res.pinion) < len(res.s) // 10  # at the pinion root
    assert res.pinion.min() >= 0 and res.gear.min() >= 0
    assert res.worn_area("gear") < res.worn_area("pinion")


def test_thesis_coefficient_gives_the_uncalibrated_magnitude():
    """With the thesis's k = 5e-4 and the solver's share the wear is about 1e-4 um: the gap
    the calibration closes (docs/reproduction.md)."""
    wear = calibration.mean_wear(Scenario(), calibration.THESIS_WEAR_COEFF, 1e6)
    assert 1e-5 < wear * 1e6 < 1e-3


@pytest.mark.parametrize("n1", [1000.0, 3000.0])
def test_wear_per_cycle_falls_with_speed(n1):
    """Thesis Table 2's trend: the film thickens with speed and the asperity share falls
    faster than the oil-film deficiency coefficient rises with the flash temperature."""
    base = simulate_wear(Scenario(), 1e6).mean_depth()
    other = simulate_wear(dataclasses.replace(Scenario(), operating=Operating(n1_rpm=n1)),
                          1e6).mean_depth()
    assert (other < base) == (n1 > 2000.0)
