"""Parameter sets: YAML groups match the dataclass defaults; bad values fail early and clearly."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st
from omegaconf import OmegaConf

from physics.params import (
    Dynamics,
    GearPair,
    Lubricant,
    Material,
    Operating,
    Scenario,
    Tribology,
    WearSolver,
    scenario_from_config,
)

CONF = Path(__file__).resolve().parent.parent / "conf" / "physics"
DEFAULT_GROUPS = {
    "gear/thesis": GearPair, "material/steel": Material, "lubricant/thesis": Lubricant,
    "tribology/thesis": Tribology, "operating/baseline": Operating, "solver/default": WearSolver,
    "dynamics/default": Dynamics,
}


@pytest.mark.parametrize("group", sorted(DEFAULT_GROUPS))
def test_default_yaml_equals_dataclass_defaults(group):
    part = group.split("/")[0]
    built = getattr(scenario_from_config({part: OmegaConf.load(CONF / f"{group}.yaml")}), part)
    assert built == DEFAULT_GROUPS[group]()


@pytest.mark.parametrize("case", [1, 2, 3, 4, 5, "2"])
def test_cases_build(case):
    scn = scenario_from_config({"case": case})
    assert scn.operating.n1_rpm in (1800.0, 2000.0, 2200.0)
    assert 280 < scn.operating.torque_Nm < 320


def test_case_3_is_the_baseline_operating_point():
    scn = scenario_from_config({"case": 3})
    assert scn.operating == Operating() and scn.lubricant == Lubricant()


@pytest.mark.parametrize("bad", [0, 6, "three", 2.5, True])
def test_unknown_case_lists_the_valid_ones(bad):
    with pytest.raises(ValueError, match=r"not an operating case; valid cases: \[1, 2, 3, 4, 5\]"):
        scenario_from_config({"case": bad})


def test_published_lubricants_keep_the_thesis_ordering():
    """Thesis 2.7.5: SAE30 has the higher eta0 and pressure-viscosity coefficient than PAO."""
    sae = scenario_from_config({"lubricant": OmegaConf.load(CONF / "lubricant/sae30.yaml")})
    pao = scenario_from_config({"lubricant": OmegaConf.load(CONF / "lubricant/pao.yaml")})
    assert sae.lubricant.eta0_Pa_s > pao.lubricant.eta0_Pa_s
    assert sae.lubricant.alpha_m2_per_N > pao.lubricant.alpha_m2_per_N


def test_unknown_key_is_named():
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['modul_mm'\]"):
        scenario_from_config({"gear": {"modul_mm": 2}})


@pytest.mark.parametrize(
    ("part", "field", "value"),
    [
        ("operating", "n1_rpm", 0.0), ("operating", "n1_rpm", -100.0),
        ("operating", "torque_Nm", 0.0), ("lubricant", "eta0_Pa_s", 0.0),
        ("tribology", "sigma_um", -0.5), ("material", "hardness_GPa", 0.0),
        ("operating", "torque_Nm", float("nan")), ("gear", "face_width_mm", float("inf")),
    ],
)
def test_bad_value_names_field_value_and_range(part, field, value):
    cls = type(getattr(Scenario(), part))
    with pytest.raises(ValueError, match=rf"{part}\.{field} = .* must (lie in|be a finite number)"):
        cls(**{field: value})


def test_bore_outside_root_circle_is_refused():
    with pytest.raises(ValueError, match=r"bore_radius1_mm = 16.*root radius 15.5 mm"):
        GearPair(bore_radius1_mm=16.0)


def test_pinion_must_be_the_smaller_wheel():
    with pytest.raises(ValueError, match="z1 = 30 exceeds z2 = 27"):
        GearPair(z1=30)


@given(st.floats(max_value=0.0, allow_nan=False))
def test_non_positive_speed_always_refused(n1):
    with pytest.raises(ValueError, match=r"operating\.n1_rpm"):
        Operating(n1_rpm=n1)


def test_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        Operating().n1_rpm = 1.0  # type: ignore[misc]


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Tribology(regime="wet"), r"tribology\.regime = 'wet' must be one of"),
        (lambda: Tribology(asperity_model="greenwood"),
         r"tribology\.asperity_model = 'greenwood' must be one of \['solver', 'regression'\]"),
        (lambda: Tribology(wear_coeff=0.0), r"tribology\.wear_coeff = 0\.0 must lie in"),
        (lambda: WearSolver(n_points=10), r"solver\.n_points = 10 must be a whole number"),
        (lambda: WearSolver(max_iterations=0), r"solver\.max_iterations = 0"),
        (lambda: Operating(torque_Nm=True), r"operating\.torque_Nm = True must be a finite number"),
        (lambda: GearPair(center_distance_mm=60.0), r"center_distance_mm = 60.0 must lie in"),
        (lambda: GearPair(z1=18.5), r"gear\.z1 = 18\.5 must be a whole number"),
    ],
)
def test_more_bad_values(make, message):
    with pytest.raises(ValueError, match=message):
        make()
