"""The reproduction app writes every table named and shaped like the thesis reference."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from physics.reference import THESIS_TABLES
from tests.acceptance.readme import REPRODUCE
from tests.acceptance.refusal import refusal, tree

REF = THESIS_TABLES
FAST = ["solver.n_points=101", "stiffness.fem_refine=1", "stiffness.fem_refines=[1]",
        "stiffness.positions=50", "evolution.cases=[3]", "evolution.points=11"]
TABLES = ["table02_speed", "table03_torque", "table04_roughness", "table05_lubricant",
          "table06_center_distance", "table07_tvms_energy_vs_fem", "table08_wear_vs_stiffness",
          "table09_dynamics_vs_wear", "table10_dynamic_vs_quasistatic",
          "table12_evolution_fits_case3", "table14_dte_features_case3"]


#: the README command whose run these tests read (:func:`tests.conftest._group` keeps them on
#: the worker that runs it)
README_KEY = REPRODUCE


@pytest.fixture
def out(readme_folder):
    """The tables and figures of the README's ``python -m physics.reproduce``, run once per
    session at the acceptance tests' size (``tests/acceptance/readme.py``, ``FAST_REPRO``)."""
    folder, _ = readme_folder(README_KEY)
    return next(folder.glob("outputs/*/*"))


@pytest.mark.parametrize("name", TABLES)
def test_table_shape_matches_reference(out, name):
    ours = pd.read_csv(out / f"{name}.csv")
    ref = pd.read_csv(REF / f"{name}.csv")
    assert list(ours.columns) == list(ref.columns)
    a, b = ours.iloc[:, 0], ref.iloc[:, 0]
    if name == "table14_dte_features_case3":  # its rows: evolution.table14_cycles, a subset here
        assert np.isin(a.astype(float), b.astype(float)).all() and len(a) >= 2
    elif pd.api.types.is_numeric_dtype(b):
        assert np.allclose(a.astype(float), b.astype(float))
    else:
        assert a.str.lower().tolist() == b.str.lower().tolist()
    assert ours.select_dtypes("number").notna().all().all()


def test_dynamics_outputs(out):
    dte = pd.read_csv(out / "dte.csv")
    assert list(dte.columns) == ["cycles", "time_s", "dte_m", "force_N"]
    for _, rec in dte.groupby("cycles"):
        assert rec.time_s.max() >= 0.1 - 1 / 40960 and len(rec) >= 4096
    evo = pd.read_csv(out / "wear_evolution.csv")
    assert list(evo.columns) == ["case", "cycles", "root_wear_mm"]
    assert evo.cycles.max() == pytest.approx(1.5e7)
    for name in ("dte_spectrum.png", "wear_evolution.png", "feature_trends.png", "tvms.png"):
        assert (out / name).stat().st_size > 10_000


def test_wear_profile_outputs(out):
    df = pd.read_csv(out / "wear_profile.csv")
    assert list(df.columns) == ["side", "roll_mm", "radius_mm", "zone", "wear_um"]
    assert set(df.side) == {"pinion", "gear"} and set(df.zone) == {"single", "double"}
    assert (df.wear_um >= 0).all()
    assert (out / "wear_profile.png").stat().st_size > 10_000
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporaries


def test_overrides_reach_the_physics(tmp_path, config_store):
    """Gear overrides on the command line reach the scenario the reproduction runs, and its
    geometry: the gear's tip radius m z2 / 2 + m of a module-3 pair."""
    from physics.gear.stiffness import mesh_stiffness
    from tests.acceptance.refusal import APPS, composed

    spec = APPS["reproduce"]
    prepare = spec.prepare()
    plan = prepare(composed(spec, [f"out_dir={tmp_path / 'out'}", *FAST, "gear.module_mm=3",
                                   "gear.bore_radius1_mm=12", "gear.bore_radius2_mm=20"],
                            tmp_path / "run"))
    g = plan.scenario.gear
    assert (g.module_mm, g.bore_radius1_mm, g.bore_radius2_mm) == (3.0, 12.0, 20.0)
    ra2 = mesh_stiffness(g, plan.scenario.material).geometry.ra2
    assert ra2 == pytest.approx((3 * 27 / 2 + 3) * 1e-3, rel=1e-9)
    assert not (tmp_path / "out").exists()  # prepare writes nothing


def test_bad_override_fails_before_writing(tmp_path, config_store):
    err = refusal("reproduce", [f"out_dir={tmp_path / 'x'}", "operating.torque_Nm=-5"],
                  tmp_path)
    assert "operating.torque_Nm = -5.0 must lie in" in str(err)
    assert not tree(tmp_path)


def test_contact_state_has_the_solver_film_and_the_regression_beside_it(out):
    df = pd.read_csv(out / "contact_state.csv")
    for col in ("h_min_nm", "h_central_nm", "pressure_peak_MPa", "asperity_load_ratio_pct",
                "h_min_regression_nm", "asperity_load_ratio_regression_pct"):
        assert col in df.columns and df[col].notna().all()
    assert (df.h_central_nm > df.h_min_nm).all() and (df.h_min_nm > 0).all()
    # the pressure peak is of the order of the Hertz pressure (the outlet spike may exceed it)
    assert (df.pressure_peak_MPa > 0.8 * df.p_max_MPa).all()
    assert (df.pressure_peak_MPa < 1.5 * df.p_max_MPa).all()
    # the solver's share is largest at the pinion root, where the film is thinnest
    assert df.asperity_load_ratio_pct.idxmax() == df.film_ratio.idxmin() == 0
    assert (out / "ehl_pressure_film.png").stat().st_size > 10_000


def test_lubricated_wear_moves_the_dynamics_and_features(out):
    """With the default (lubricated) model the case-3 root wear reaches micrometres by 1.5e7
    cycles, and Tables 9 and 14 change with it, without the dry law: the combined error grows
    by a tenth of the root wear or more (the wear is a profile error of both flanks), the DTE's
    peak-to-peak and kurtosis move by more than 1 %, its RMS less (thesis 4.2: insensitive)."""
    evo = pd.read_csv(out / "wear_evolution.csv")
    root = evo[(evo.case == 3) & (evo.cycles == evo.cycles.max())].root_wear_mm.iloc[0]
    assert 1e-3 < root < 30e-3
    t9 = pd.read_csv(out / "table09_dynamics_vs_wear.csv")
    rise = t9.combined_error_amplitude_um.iloc[-1] - t9.combined_error_amplitude_um.iloc[0]
    assert rise > 0.1 * root * 1e3
    t14 = pd.read_csv(out / "table14_dte_features_case3.csv")
    change = {col: abs(t14[col].iloc[-1] / t14[col].iloc[0] - 1)
              for col in ("peak_to_peak_1e-5_m", "kurtosis", "rms_1e-5_m")}
    assert change["peak_to_peak_1e-5_m"] > 0.01 and change["kurtosis"] > 0.005
    assert 0 < change["rms_1e-5_m"] < change["peak_to_peak_1e-5_m"]
