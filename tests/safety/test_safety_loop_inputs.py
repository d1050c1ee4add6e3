"""The measured-data loop's inputs and the bundle makers: a user's folder never deleted by
write_bundle or the makers (an earlier bundle still replaced), the public functions given None,
a number or a mapping refused in one line naming the argument, and feature tables the loop would
have judged wrongly or for days refused before any work: a dimensional feature without its
unit, fewer than three distinct wear states, a repeated column, a NaN or negative wear in a data
frame, a stated nuisance outside the calibration's range, rows beyond the cap, candidates that
cannot show; the rows taken in order of wear; an acceleration beyond any accelerometer's range;
a row beyond the contact-driven wear's reach named."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import physics.loop as L
import physics.loop.measured.worn_states as worn_states_mod
import physics.loop.table_loop as table_loop_mod
from physics.loop.config import LoopSettings
from physics.loop.measured.bundle import FeatureTable, check_bundle_target
from physics.loop.measured.usable import shown_candidates
from physics.loop.model.declared import physical_nuisance
from physics.loop.search.attribution import candidates_for
from physics.loop.table_loop import (
    MAX_TABLE_ROWS,
    check_stated_nuisance,
    check_table,
    parse_columns,
    prepare_table,
    table_candidates,
)
from physics.params import OutOfScope, Scenario

FS = 50_000.0
G = 9.80665


def manifest(n: int = 3, quantity: str = "accel_m_s2") -> pd.DataFrame:
    return pd.DataFrame({"record": [f"r{i}" for i in range(n)], "quantity": quantity,
                         "fs_hz": FS, "n1_rpm": 2000.0, "torque_Nm": 300.0, "wear_mm": "",
                         "cycles": "", "split": ""})


def signals(n: int = 3, scale: float = 1.0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(0)
    return {f"r{i}": scale * rng.standard_normal(int(0.5 * FS)) for i in range(n)}


def one_line(err: pytest.ExceptionInfo) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text


def table(**columns) -> pd.DataFrame:
    return pd.DataFrame({"wear_mm": [0.0, 0.01, 0.02], "rms_g": [0.14, 0.12, 0.15]} | columns)


# --- (g) write_bundle and the makers never delete a user's folder -----------------------------

def test_acceptance_a_users_folder_is_refused_and_kept(tmp_path):
    """A50: write_bundle wiped a folder holding a thesis; refused now, the file kept."""
    mine = tmp_path / "mydata"
    (mine / "thesis").mkdir(parents=True)
    (mine / "thesis" / "chapter1.tex").write_text("precious")
    with pytest.raises(ValueError) as err:
        L.write_bundle(mine, manifest(), signals())
    text = one_line(err)
    assert f"write_bundle: {mine} holds thesis/" in text and "give a new folder's path" in text
    assert (mine / "thesis" / "chapter1.tex").read_text() == "precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mydata"]  # no temporary left


def test_a_stray_file_among_an_earlier_bundles_signals_is_refused(tmp_path):
    path = L.write_bundle(tmp_path / "b", manifest(), signals())
    (path / "signals" / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match=r"holds signals/notes.txt, which no bundle has"):
        L.write_bundle(path, manifest(), signals())
    assert (path / "signals" / "notes.txt").exists()


@pytest.mark.parametrize("maker", ["make_bundle", "make_independent_bundle"])
def test_acceptance_the_makers_refuse_a_users_folder_before_work(tmp_path, maker):
    """A74: make_independent_bundle deleted src/main.py; both makers refuse before simulating."""
    import physics.testbeds as tb

    project = tmp_path / "my_project"
    (project / "src").mkdir(parents=True)
    (project / "src" / "main.py").write_text("code")
    args = (Scenario(), None, 1) if maker == "make_bundle" else ()
    with pytest.raises(ValueError, match=r"holds src/, which no bundle has"):
        getattr(tb, maker)(project, *args)
    assert (project / "src" / "main.py").read_text() == "code"


def test_an_earlier_bundle_is_replaced_and_nothing_is_left_beside_it(tmp_path):
    """The README's make_bundle examples rerun into the same folder."""
    first = L.write_bundle(tmp_path / "b", manifest(4), signals(4), gear={"z1": 18})
    again = L.write_bundle(first, manifest(3), signals(3, scale=2.0))
    assert again == first
    bundle = L.read_bundle(again)
    assert bundle.records == ["r0", "r1", "r2"] and bundle.gear == {}
    np.testing.assert_array_equal(bundle.signals["r1"], signals(3, scale=2.0)["r1"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b"]  # the old one removed
    assert sorted(p.name for p in (first / "signals").iterdir()) == ["r0.npy", "r1.npy",
                                                                      "r2.npy"]
    empty = tmp_path / "empty"
    empty.mkdir()
    assert check_bundle_target(empty) == empty  # an empty folder holds nothing to lose


def test_acceptance_a_file_as_the_folder_and_no_manifest_are_one_line(tmp_path):
    """A51, A53; a link and a record name that would leave signals/ too."""
    notes = tmp_path / "notes.txt"
    notes.write_text("precious")
    with pytest.raises(ValueError) as err:
        L.write_bundle(notes, manifest(), signals())
    assert f"write_bundle: {notes} is a file, not a folder" in one_line(err)
    assert notes.read_text() == "precious"
    with pytest.raises(ValueError, match=r"notes.txt is a file, not a folder; give a path"):
        L.write_bundle(notes / "b", manifest(), signals())
    with pytest.raises(TypeError) as err:
        L.write_bundle(tmp_path / "b53", None, {})
    assert "write_bundle(manifest) = None is of type NoneType; it must be a pandas DataFrame" in (
        one_line(err))
    (tmp_path / "link").symlink_to(tmp_path)
    with pytest.raises(ValueError, match=r"is a link"):
        L.write_bundle(tmp_path / "link", manifest(), signals())
    with pytest.raises(ValueError, match=r"record name '../x' must use letters"):
        L.write_bundle(tmp_path / "b", manifest(), {"../x": np.ones(10)})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "notes.txt"]


# --- (c) the public functions given what they do not take ---------------------------------------

SCN = Scenario()
FRAME = table()


@pytest.mark.parametrize("call, named, kind", [
    (lambda: L.read_feature_table(None), "read_feature_table(path)", "NoneType"),
    (lambda: L.read_feature_table(123), "read_feature_table(path)", "int"),
    (lambda: L.read_bundle(None), "read_bundle(path)", "NoneType"),
    (lambda: L.read_bundle({}), "read_bundle(path)", "dict"),
    (lambda: L.read_measurements(None, SCN), "read_measurements(path)", "NoneType"),
    (lambda: L.read_measurements("t.csv", None), "read_measurements(base)", "NoneType"),
    (lambda: L.write_bundle(None, manifest(), {}), "write_bundle(path)", "NoneType"),
    (lambda: L.write_bundle("x", manifest(), [1]), "write_bundle(signals)", "list"),
    (lambda: L.run_feature_table(FRAME, None), "run_feature_table(base)", "NoneType"),
    (lambda: L.run_feature_table(None, SCN), "run_feature_table(table)", "NoneType"),
    (lambda: L.run_feature_table(FRAME, SCN, {}), "run_feature_table(settings)", "dict"),
    (lambda: L.run_loop(None, SCN), "run_loop(bundle)", "NoneType"),
    (lambda: L.write_report(None, Path("x")), "write_report(report)", "NoneType"),
    (lambda: L.check_usable(None, SCN, LoopSettings()), "check_usable(bundle)", "NoneType"),
    (lambda: L.check_usable(None, None, None), "check_usable(bundle)", "NoneType"),
])
def test_acceptance_a_wrong_argument_is_named_with_its_type_and_what_is_allowed(
        tmp_path, monkeypatch, call, named, kind):
    """A52, A55-A60, A67, A68, A71-A73: pathlib's TypeError or an AttributeError before."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TypeError) as err:
        call()
    text = one_line(err)
    assert text.startswith(f"{named} = ") and f"is of type {kind}; it must be" in text
    assert list(tmp_path.iterdir()) == []


def test_an_empty_path_is_not_the_working_folder():
    with pytest.raises(ValueError, match=r"read_bundle\(path\) = '' is empty"):
        L.read_bundle("")


def test_acceptance_one_candidate_name_is_not_split_into_letters():
    """A65: candidates='tip_relief' was read as the letters t, i, p, ..."""
    assert LoopSettings(candidates="tip_relief").candidates == ("tip_relief",)
    with pytest.raises(ValueError, match=r"loop.candidates = 5 must be a list of effect names"):
        LoopSettings(candidates=5)


# --- (e) messages that name the cause --------------------------------------------------------

def test_acceptance_candidates_that_cannot_show_are_named_with_the_reason(tmp_path):
    """B00: 'none of the candidates [] can show in these records ()'."""
    with pytest.raises(ValueError) as err:
        candidates_for({"dte_m"}, LoopSettings(candidates=("transfer_path",)))
    text = one_line(err)
    assert "loop.candidates = ['transfer_path']: none acts on the data's ['dte_m']" in text
    assert "transfer_path acts on ['accel_m_s2'] only" in text and "'tip_relief'" in text
    bundle = L.read_bundle(L.write_bundle(tmp_path / "b", manifest(), signals()))
    with pytest.raises(ValueError, match=r"no candidate effects to search in its "
                                         r"\['accel_m_s2'\] records"):
        shown_candidates([], bundle, SCN, LoopSettings())


def test_with_the_exact_contact_candidates_it_leaves_out_are_refused_before_work():
    exact = dataclasses.replace(SCN, dynamics=dataclasses.replace(SCN.dynamics,
                                                                  flank_contact="exact"))
    with pytest.raises(ValueError) as err:
        table_candidates("accel_m_s2", exact, LoopSettings(candidates=("tip_relief",)))
    text = one_line(err)
    assert "none is searched on this table (tip_relief: with dynamics.flank_contact=exact" in text
    assert "set dynamics.flank_contact=path" in text and "sensor" not in text


def test_acceptance_a_repeated_column_is_said_to_be_repeated(tmp_path):
    """L27: 'column rms_g.1 is not a Table 13 feature' (pandas' renamed repeat)."""
    path = tmp_path / "t.csv"
    path.write_text("wear_mm,rms_g,rms_g\n0,0.1,0.1\n0.01,0.2,0.2\n0.02,0.3,0.3\n")
    with pytest.raises(ValueError) as err:
        L.read_feature_table(path)
    assert f"feature table {path}: repeated column 'rms_g'" in one_line(err)
    frame = pd.DataFrame([[0, 0.1, 0.1]], columns=["wear_mm", "rms_g", "rms_g"])
    with pytest.raises(ValueError, match=r"^feature table: repeated column 'rms_g'"):
        L.run_feature_table(frame, SCN)


@pytest.mark.parametrize("wear, said", [
    (np.nan, "row 2, column 'wear_mm': empty (NaN) is not a finite number"),
    (-0.01, "row 2, column 'wear_mm' = -0.01 lies outside [0, 10] mm"),
])
def test_acceptance_a_data_frames_bad_wear_is_named_before_work(wear, said):
    """A69, A70: from deep inside the wear run, naming neither row nor column."""
    with pytest.raises(ValueError) as err:
        L.run_feature_table(table(wear_mm=[0.0, wear, 0.02]), SCN)
    assert one_line(err) == f"feature table: {said}" + (
        ", what a wear depth can be; give it in mm" if wear < 0 else "")


def test_acceptance_a_row_beyond_the_contact_wears_reach_is_named(monkeypatch):
    """L33: 'out of the model's scope: wear of 1041.0 um ...' after minutes, no row named."""
    def leaves_scope(scn, wear_mm):
        raise OutOfScope("wear of 1041.0 um at radius 29.972 mm reaches the tooth centre "
                         "line\n(half-thickness 1038.8 um there)")

    monkeypatch.setattr(worn_states_mod, "contact_states", leaves_scope)
    with pytest.raises(OutOfScope) as err:
        worn_states_mod.table_models(SCN, np.array([0.0, 0.5, 1.7]), rows=np.array([2, 3, 1]))
    text = one_line(err)
    assert text.startswith("feature table: row 1 (wear_mm = 1.7 mm, the deepest) lies beyond")
    assert "reaches the tooth centre line (half-thickness" in text
    assert "leave out the deepest row(s); the next deepest row is at 0.5 mm" in text


# --- (d) tables the loop would judge wrongly ----------------------------------------------------

@pytest.mark.parametrize("column, said", [
    ("rms", "column 'rms': rms is dimensional and needs its unit as a suffix"),
    ("peak_to_peak", "column 'peak_to_peak': peak_to_peak is dimensional"),
    ("kurtosis_g", "column 'kurtosis_g': kurtosis is dimensionless and takes no unit"),
])
def test_acceptance_a_dimensional_feature_without_its_unit_is_refused(column, said):
    """L28: an 'rms' column was read as m/s^2 beside one in g."""
    with pytest.raises(ValueError) as err:
        parse_columns(table(**{column: [0.5, 0.5, 0.5]}))
    assert said in one_line(err)


def test_acceptance_the_rows_are_taken_in_order_of_wear(monkeypatch):
    """L30: the rise 'from the first to the last row' followed the file's order."""
    seen = {}

    def models(scn, wear_mm, rows=None):
        seen["wear"], seen["rows"] = list(wear_mm), list(rows)
        return [None] * len(wear_mm)

    monkeypatch.setattr(table_loop_mod, "table_models", models)
    monkeypatch.setattr(table_loop_mod, "check_table_depths", lambda scn, wear: None)
    frame = pd.DataFrame({"wear_mm": [0.02, 0.0, 0.01, 0.0], "rms_g": [0.15, 0.14, 0.12, 0.13]})
    td = prepare_table(FeatureTable(None, frame, {}), SCN, LoopSettings())
    assert td.wear.tolist() == [0.0, 0.0, 0.01, 0.02]
    assert (td.measured[:, 0] / G).tolist() == pytest.approx([0.14, 0.13, 0.12, 0.15])
    assert seen == {"wear": [0.0, 0.0, 0.01, 0.02], "rows": [2, 4, 3, 1]}  # stable, file rows


def test_acceptance_fewer_than_three_distinct_wear_states_are_refused():
    """L31: three rows of one wear state passed the 'three rows' rule."""
    with pytest.raises(ValueError) as err:
        check_table(FeatureTable(None, table(wear_mm=[0.0, 0.0, 0.0]), {}), SCN)
    assert ("3 row(s) of 1 distinct wear state(s) (wear_mm 0); the cross-validation over the "
            "rows needs at least 3 distinct wear states") in one_line(err)


def test_acceptance_a_stated_nuisance_outside_the_calibrations_range_is_refused():
    """L35: a stated 5 kg and 0.5 were replaced by the range's bounds without a word."""
    rig = dataclasses.replace(SCN, gear=dataclasses.replace(SCN.gear, module_mm=3.0, z1=18,
                                                            z2=35))
    lo, hi, _ = physical_nuisance(rig)["housing_mass_kg"]
    light = dataclasses.replace(rig, dynamics=dataclasses.replace(rig.dynamics,
                                                                  housing_mass_kg=5.0))
    with pytest.raises(ValueError) as err:
        check_stated_nuisance(light, "accel_m_s2")
    assert (f"dynamics.housing_mass_kg = 5 lies outside {lo:.3g}-{hi:.3g} kg, the range a "
            "feature table's calibration searches") in one_line(err)
    check_stated_nuisance(light, "dte_m")  # a DTE has no housing
    check_stated_nuisance(rig, "accel_m_s2")  # the default 20 kg: a start, not a statement
    with pytest.raises(ValueError, match=r"dynamics.housing_mass_kg = 20 lies outside"):
        check_stated_nuisance(rig, "accel_m_s2", {"dynamics.housing_mass_kg"})
    damped = dataclasses.replace(SCN, dynamics=dataclasses.replace(SCN.dynamics,
                                                                   damping_ratio=0.5))
    with pytest.raises(ValueError, match=r"dynamics.damping_ratio = 0.5 lies outside "
                                         r"0.03-0.17 of critical"):
        check_stated_nuisance(damped, "dte_m")


def test_acceptance_an_acceleration_beyond_any_accelerometers_range_is_refused(tmp_path):
    """B04: mm/s^2 given as m/s^2 (RMS 660 g) passed under 1e4 m/s^2."""
    path = L.write_bundle(tmp_path / "b", manifest(), signals(scale=600 * G))
    with pytest.raises(ValueError) as err:
        L.read_bundle(path)
    text = one_line(err)
    assert "record 'r0': accel_m_s2 of RMS 5.86e+03 m/s^2 lies above 4903 m/s^2 (500 g)" in text
    L.read_bundle(L.write_bundle(tmp_path / "ok", manifest(), signals(scale=400 * G)))
    with pytest.raises(ValueError, match=r"row 1, column 'rms_g' = 600 must be positive and at "
                                         r"most 4.9e\+03 m/s\^2"):
        check_table(FeatureTable(None, table(rms_g=[600.0, 0.1, 0.1]), {}), SCN)


# --- (f) tables that would run for days -------------------------------------------------------

def test_acceptance_a_table_of_thousands_of_rows_is_refused_before_work():
    """L37: 5000 rows ran without a word (the rig's 36 take 25 min)."""
    wear = np.linspace(0.0, 0.02, 5000)
    frame = pd.DataFrame({"wear_mm": wear, "rms_g": 0.1 + wear})
    with pytest.raises(ValueError) as err:
        L.run_feature_table(frame, SCN)
    assert (f"feature table: 5,000 rows, above the {MAX_TABLE_ROWS} the loop takes: each row is "
            "one dynamic simulation") in one_line(err)


def test_settings_a_feature_table_does_not_use_are_refused_not_ignored():
    """loop.time_limit_s, loop.refine, ... steer the bundle loop; given for a feature table
    they are named in one line (the table loop's own, loop.max_nfev or loop.seed, pass)."""
    from physics.loop.table_loop import BUNDLE_SETTINGS, check_table_settings

    check_table_settings({"loop.max_nfev", "loop.seed", "loop.candidates", "data"})
    with pytest.raises(ValueError, match=r"^loop.time_limit_s: a feature table's run does not "
                                         r"use this setting"):
        check_table_settings({"loop.time_limit_s", "loop.seed"})
    with pytest.raises(ValueError, match=r"loop.explore, loop.refine: .* these settings"):
        check_table_settings({"loop.refine", "loop.explore"})
    assert set(BUNDLE_SETTINGS) < {f.name for f in dataclasses.fields(LoopSettings)}


def test_the_docs_state_the_acceleration_bound_the_loop_applies():
    """docs/own-data.md quotes the bound of a record's acceleration RMS as the code holds it."""
    from physics.loop.measured.bundle import MAX_ACCEL_RMS

    text = " ".join((Path(__file__).parents[2] / "docs" / "own-data.md").read_text().split())
    assert text.count(f"{MAX_ACCEL_RMS:.0f} m/s^2") == 2 and "1e4 m/s^2" not in text
