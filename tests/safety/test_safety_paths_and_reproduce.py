"""Paths as the system reaches them, the reproduction's inputs checked before work, true
interrupt lines, and ``case=`` beside the values it sets:

- an output folder spelled ``new/../out`` (``new/`` absent) is ``out``: its files are seen, and
  a run without overwrite is refused (R12, G12);
- an output folder that is, or holds, what the run reads is refused even with overwrite: the
  reproduction's ``out_dir`` against ``thesis_tables`` (R07), the rig's ``--out`` against its
  ``--table`` (G08);
- every thesis table the reproduction reads is checked before work, one line naming the file
  (R01, R04, R05), and so is the evolution grid of Table 12's fits (R00);
- a run folder Hydra cannot make (a read-only working folder) ends every app in one line
  (R08c, RO1p, RO1t: ``physics.command.RunRecord``);
- the rig's table: empty or binary (G09, G09b), depths beyond the pair's tip (G07b), and rises
  at depths no stage stands for left empty (G08b);
- an interrupted reproduction says truly how to go on (I01-I03);
- ``case=`` with a value it sets (``operating.torque_Nm=``, a lubricant) is refused in every
  app that has ``case`` (L40, R13).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from omegaconf import OmegaConf

from physics.command import RunRecord, register_schema, run_command
from physics.files import check_fresh, check_writable, resolved
from physics.gear.stiffness import mesh_stiffness
from physics.params import check_case, scenario_for_case, scenario_from_config
from physics.reference import THESIS_TABLES
from physics.reproduce import rig
from physics.reproduce.thesis import (
    ReproduceConfig,
    ReproducePlan,
    interrupted_note,
    prepare,
)
from tests.acceptance.refusal import APPS, composed
from tests.safety.test_safety_run_folders import start_refused

ROOT = Path(__file__).resolve().parents[2]
TABLE14 = "table14_dte_features_case3.csv"
TABLE15 = "table15_measured_acceleration_features.csv"
#: a reproduction small enough to check (prepare only: nothing is computed here)
SMALL = ["evolution.cases=[3]"]


@pytest.fixture
def reproduce_cfg(config_store, tmp_path):
    """``reproduce_cfg(*overrides)``: the reproduction's config as its app gets it."""
    register_schema("reproduce_schema", ReproduceConfig)  # as the app does
    return lambda *overrides: composed(APPS["reproduce"], [*SMALL, *overrides], tmp_path / "run")


def thesis_copy(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name in (TABLE14, TABLE15):
        (folder / name).write_bytes((THESIS_TABLES / name).read_bytes())
    return folder


# --- (g) paths as the system reaches them ------------------------------------------------------

def test_a_folder_spelled_through_a_missing_one_is_the_folder_it_reaches(tmp_path):
    """R12: ``nope/../out`` is ``out``; its table is seen, and the run is refused unasked."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "table02_speed.csv").write_text("user\n")
    spelled = f"{tmp_path}/nope/../out"
    assert resolved(spelled) == out
    with pytest.raises(ValueError, match=r"nope/\.\./out' \(that is .*/out\) already holds "
                                         r"table02_speed\.csv, which this run would replace"):
        check_fresh(spelled, "out_dir", ("*.csv",), False, "overwrite=true")
    (tmp_path / "f").write_text("mine")  # a file reached so is no folder to write in
    with pytest.raises(ValueError, match="is a file, not a folder"):
        check_writable(f"{tmp_path}/nope/../f", "out_dir")
    assert not (tmp_path / "nope").exists()


def test_the_reproduction_sees_the_users_table_through_the_spelling(reproduce_cfg, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "table02_speed.csv").write_text("user\n")
    with pytest.raises(ValueError, match=r"already holds table02_speed\.csv") as err:
        prepare(reproduce_cfg(f"out_dir={tmp_path}/nope/../out"))
    assert "\n" not in str(err.value)
    plan = prepare(reproduce_cfg(f"out_dir={tmp_path}/nope/../out", "overwrite=true"))
    assert plan.out == out  # the writes go where the check looked, and make no nope/
    assert not (tmp_path / "nope").exists() and (out / "table02_speed.csv").read_text() == "user\n"


def test_the_rig_sees_the_users_summary_through_the_spelling(tmp_path, capsys):
    """G12."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "rig_summary.csv").write_text("mine\n")
    assert rig.main(["--out", f"{tmp_path}/nope/../out"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "already holds rig_summary.csv" in err[0], err
    assert (out / "rig_summary.csv").read_text() == "mine\n"
    assert not (tmp_path / "nope").exists()


@pytest.mark.parametrize("where", ["same", "inside", "spelled", "link"])
def test_out_dir_among_the_thesis_tables_is_refused_even_with_overwrite(reproduce_cfg, tmp_path,
                                                                       where):
    """R07: the thesis's tables are what the reproduction reads; out_dir the same folder, one
    inside it, or a folder that holds one of them (a link's target) would mix or replace
    them."""
    tables = thesis_copy(tmp_path / "tt")
    out = {"same": tables, "inside": tables / "sub", "spelled": f"{tmp_path}/x/../tt",
           "link": tmp_path / "out"}[where]
    if where == "link":  # the tables folder's Table 14 is a link into out
        out.mkdir()
        (out / TABLE14).write_bytes((tables / TABLE14).read_bytes())
        (tables / TABLE14).unlink()
        (tables / TABLE14).symlink_to(out / TABLE14)
    before = (THESIS_TABLES / TABLE14).read_bytes()
    with pytest.raises(ValueError, match=r"out_dir = .*(is|lies inside) the folder of "
                                         r"thesis_tables|out_dir = .* holds the thesis's Table "
                                         r"14") as err:
        prepare(reproduce_cfg(f"out_dir={out}", f"thesis_tables={tables}", "overwrite=true"))
    assert "whatever overwrite says" in str(err.value) and "\n" not in str(err.value)
    assert (tables / TABLE14).read_bytes() == before


def test_a_folder_apart_from_the_thesis_tables_passes(reproduce_cfg, tmp_path):
    tables = thesis_copy(tmp_path / "tt")
    plan = prepare(reproduce_cfg(f"out_dir={tmp_path / 'out'}", f"thesis_tables={tables}"))
    assert plan.thesis14 == tables / TABLE14 and plan.out == tmp_path / "out"


def test_the_rig_refuses_an_out_whose_files_would_replace_its_table(tmp_path, capsys):
    """G08: the table is named as an output (rig_comparison.csv in --out), also through a
    spelling or a link; a table of another name in --out stays fine."""
    x = tmp_path / "x"
    x.mkdir()
    records = pd.read_csv(rig.default_table())
    table = x / "rig_comparison.csv"
    records[records.stage_order <= 1].to_csv(table, index=False)
    before = table.read_bytes()
    for out in (str(x), f"{tmp_path}/nope/../x"):
        assert rig.main(["--table", str(table), "--out", out, "--overwrite"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error: --out: the output ") and (
            "would replace the input --table" in err[0]), err
    (tmp_path / "link.csv").symlink_to(table)
    assert rig.main(["--table", str(tmp_path / "link.csv"), "--out", str(x), "--overwrite"]) == 2
    assert "would replace the input --table" in capsys.readouterr().err
    assert table.read_bytes() == before
    from physics.files import check_not_input

    check_not_input([x / name for name in rig.OUTPUT_FILES], "--out", x / "records.csv",
                    "--table")


# --- (c) the reproduction's inputs, the rig's table, the run folder --------------------------

@pytest.mark.parametrize(("damage", "said"), [
    ("no15", rf"thesis_tables: Table 15 .*/tt/{TABLE15} does not exist; give thesis_tables"),
    ("nonew", rf"thesis_tables: Table 15 .*/tt/{TABLE15} has no new-gear row \(wear_mm = 0\)"),
    ("binary14", rf"thesis_tables: Table 14 .*/tt/{TABLE14} is not UTF-8 text"),
    ("empty15", rf"thesis_tables: Table 15 .*/tt/{TABLE15} is empty"),
    ("text14", rf"thesis_tables: Table 14 .*/tt/{TABLE14}: column kurtosis row 2 is 'high', "
               "not a finite number"),
])
def test_every_thesis_table_is_checked_before_work(reproduce_cfg, tmp_path, damage, said):
    """R01, R04, R05: Table 15 beside Table 14, each a UTF-8 CSV with its columns and rows,
    refused in one line naming the file (after the work they were a traceback)."""
    tables = thesis_copy(tmp_path / "tt")
    t14, t15 = tables / TABLE14, tables / TABLE15
    if damage == "no15":
        t15.unlink()
    elif damage == "nonew":
        t15.write_text("".join(t15.read_text().splitlines(keepends=True)[:1]
                               + t15.read_text().splitlines(keepends=True)[2:]))
    elif damage == "binary14":
        t14.write_bytes(b"cycles_1e6,wear_mm\n\xff\xfe\x00\x01" * 8)
    elif damage == "empty15":
        t15.write_text("")
    else:
        frame = pd.read_csv(t14).astype({"kurtosis": object})
        frame.loc[1, "kurtosis"] = "high"
        frame.to_csv(t14, index=False)
    with pytest.raises(ValueError, match=said) as err:
        prepare(reproduce_cfg(f"out_dir={tmp_path / 'out'}", f"thesis_tables={tables}"))
    assert "\n" not in str(err.value) and "thesis_tables=null" in str(err.value)
    assert not (tmp_path / "out").exists()


def test_an_evolution_grid_without_room_for_table12s_fits_is_refused(reproduce_cfg, tmp_path):
    """R00: 5 points from 0 to 2e6 with fit_until 1e6 give 3 and 2 (the fits need 5 and 2);
    the line names the points that would do."""
    grid = ["evolution.points=5", "evolution.table14_cycles=[0,1e6,2e6]",
            "evolution.cycles_max=2e6", "evolution.fit_until=1e6"]
    with pytest.raises(ValueError, match=r"evolution\.points = 5 .* puts 3 cycle counts at N "
                                         r"<= evolution\.fit_until = 1e\+06 and 2 beyond it; "
                                         r"Table 12's fits need >= 5 and >= 2: give "
                                         r"evolution\.points=9 or more"):
        prepare(reproduce_cfg(f"out_dir={tmp_path / 'out'}", *grid))
    prepare(reproduce_cfg(f"out_dir={tmp_path / 'out'}", *grid[1:], "evolution.points=9"))
    with pytest.raises(ValueError, match=r"lower evolution\.fit_until below"):
        prepare(reproduce_cfg(f"out_dir={tmp_path / 'out'}", "evolution.fit_until=1.5e7"))


def test_a_run_folder_that_cannot_be_made_ends_the_app_in_one_line(tmp_path, capsys):
    """R08c, RO1p, RO1t: Hydra made the run folder itself and raised a PermissionError
    traceback; every app's RunRecord (its ``hydra.callbacks``) refuses first, naming the
    folder and the fix. (/proc takes no folder, as a read-only working folder.)"""
    for key, node in (("hydra.run.dir", {"run": {"dir": "/proc/gearwear/logs/run"}}),
                      ("hydra.sweep.dir", {"sweep": {"dir": "/proc/gearwear/multi"}})):
        assert start_refused(key, node) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(
            f"error: {key} = '/proc/gearwear/") and "cannot write in /proc" in err[0] and (
            f"run from a folder you can write to, or give {key}=<such a folder>" in err[0]), err
    (tmp_path / "file").write_text("mine")
    with pytest.raises(SystemExit):
        RunRecord().on_run_start(OmegaConf.create(
            {"hydra": {"run": {"dir": str(tmp_path / "file" / "run")}}}))
    assert "is a file, not a folder" in capsys.readouterr().err
    apps = [ROOT / "conf" / app / f"{app}.yaml" for app in ("reproduce", "loop", "predict",
                                                            "dataset")]
    for path in [*apps, ROOT / "conf" / "train" / "hydra" / "default.yaml"]:
        text = yaml.safe_load(path.read_text())
        callbacks = (text.get("hydra", text) or {}).get("callbacks", {})
        assert callbacks["run_record"]["_target_"] == "physics.command.RunRecord", path


@pytest.mark.slow
@pytest.mark.parametrize("app", ["reproduce", "predict", "train"])
def test_each_app_from_a_folder_it_cannot_write_says_so_in_one_line(app):
    """The same through each app's command, from a working folder that takes no folder."""
    cmd = {"reproduce": ["-m", "physics.reproduce"],
           "predict": ["-m", "surrogate.predict", "ckpt=x.pt", "input=x.csv"],
           "train": [str(ROOT / "train.py")]}[app]
    run = subprocess.run([sys.executable, *cmd], cwd="/proc", capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "hydra.run.dir" in lines[0] and "Traceback" not in run.stderr


@pytest.mark.parametrize(("content", "said"), [
    (b"", "is empty (no header, no rows)"),
    (b"stage,wear_mm\n\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1\x00\x00", "is not UTF-8 text"),
])
def test_an_empty_or_binary_rig_table_is_named_with_its_option(tmp_path, capsys, content, said):
    """G09, G09b: pandas' own words named neither the option nor the file."""
    table = tmp_path / "t.csv"
    table.write_bytes(content)
    assert rig.main(["--table", str(table), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: --table {table} {said}" + err[0].split(said, 1)[1]], err
    assert "give the rig's records table" in err[0] and not (tmp_path / "o").exists()


def test_rig_depths_beyond_the_pairs_tip_are_refused_before_work(tmp_path, capsys):
    """G07b: a table in um read as mm ran 163 s into the wear model's OutOfScope; refused
    at once, naming the depth and the tip thickness; negative and NaN depths too."""
    records = pd.read_csv(rig.default_table())
    scn = rig.rig_scenario(100.0)
    tip = mesh_stiffness(scn.gear, scn.material).geometry.tip_thickness * 1e3
    assert 1.6 < tip < 1.8
    for wear, said in ((records.wear_um, f"wear_mm = 932 mm reaches the {tip:.3g} mm"),
                       (records.wear_mm.where(records.stage_order != 3, -0.1),
                        "wear_mm = -0.1 is negative"),
                       (records.wear_mm.where(records.stage_order != 3, np.nan),
                        "column wear_mm row")):
        table = tmp_path / "t.csv"
        records.assign(wear_mm=wear).to_csv(table, index=False)
        assert rig.main(["--table", str(table), "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and said in err[0] and f"--table {table}" in err[0], err
    rig.read_rig_table(rig.default_table())  # the rig's own, to 0.93 mm, passes


def test_rises_at_depths_no_stage_stands_for_are_left_empty_and_said(monkeypatch):
    """G08b: a table of stages 0 and 0.04 mm gave 'rises at 0.9 mm' from its 0.04 mm stage."""
    ones = {"exact": np.array([1.0, 2.0]), "path": np.array([1.0, 3.0])}
    monkeypatch.setattr(rig, "model_rms", lambda torque, depths, contacts=(): ones)
    records = pd.read_csv(rig.default_table())
    two = records[records.stage_order <= 1]
    _, summary, _, _ = rig.rig_comparison(two)
    for at in rig.RISE_AT_MM:
        for col in ("rise_measured", "rise_model", "model_over_measured"):
            assert summary[f"{col}_{at:g}mm"].isna().all()
    assert rig.unread_rises(np.array([0.0, 0.04])) == (
        "no stage of the table lies within 0.025 mm of 0.4 mm and 0.9 mm (its stages reach "
        "0-0.04 mm): the summary's rises there are left empty")
    depths = rig.stage_means(records)["wear_mm"].to_numpy()
    assert rig.unread_rises(depths) is None  # the rig's own: 0.4 and 0.89 mm
    assert [depths[rig.rise_stage(depths, at)] for at in rig.RISE_AT_MM] == [0.4, 0.89]


# --- (e) an interrupted reproduction says truly how to go on -----------------------------------

def _plan(out: Path, overwrite: bool = False, run_folder: Path | None = None) -> ReproducePlan:
    return ReproducePlan(OmegaConf.create({"overwrite": overwrite}), None, {}, None, out,
                         run_folder=run_folder)


def test_the_interrupt_line_names_only_a_folder_that_exists_and_the_rerun_that_works(tmp_path):
    """I01-I03: the line named an out folder that did not exist yet; I02: it said to run the
    command again, which check_fresh then refused without overwrite=true."""
    out = tmp_path / "out"
    assert interrupted_note(_plan(out)) == "no table was written yet; run the command again"
    out.mkdir()
    assert str(out) not in interrupted_note(_plan(out))
    (out / "table02_speed.csv").write_text("x")
    (out / "tvms.png").write_text("x")
    line = interrupted_note(_plan(out))
    assert line == (f"2 table(s) and figure(s) written so far are in {out}; run the command "
                    f"again with overwrite=true to compute them all (without it, out_dir={out} "
                    "is refused, as it holds these files)")
    with pytest.raises(ValueError, match="already holds"):  # what the line says, truly
        check_fresh(out, "out_dir", ("*.csv", "*.png"), False, "overwrite=true")
    check_fresh(out, "out_dir", ("*.csv", "*.png"), True, "overwrite=true")
    assert "run the same command again (with its overwrite=true)" in interrupted_note(
        _plan(out, overwrite=True))
    assert interrupted_note(_plan(out, run_folder=out)).endswith(
        "run the command again to compute them all (in a new run folder)")


# --- (d) case= beside a value it sets ----------------------------------------------------------

def test_case_with_a_value_it_sets_is_refused_where_case_is_applied():
    """L40, R13: ``case=1 operating.torque_Nm=100`` ran at case 1's 290 N m without a word."""
    with pytest.raises(ValueError, match=r"case = 1 sets operating\.torque_Nm = 290 \(thesis "
                                         r"Table 11\), and operating\.torque_Nm = 100 is given "
                                         r"too: .* give either case=1 or operating\.torque_Nm, "
                                         "not both"):
        scenario_from_config({"case": 1, "operating": {"torque_Nm": 100.0}})
    with pytest.raises(ValueError, match=r"lubricant\.eta0_Pa_s = 0\.078 is given too"):
        scenario_from_config({"case": 1, "lubricant": {"eta0_Pa_s": 0.078}})
    # the default's value given on the command line is a choice as well
    with pytest.raises(ValueError, match=r"operating\.torque_Nm = 300 is given too"):
        check_case({"case": 1, "operating": {"torque_Nm": 300.0}}, ["operating.torque_Nm=300"])
    # what the case sets itself, a value it does not set, and no case: all pass
    check_case({"case": 1, "operating": {"torque_Nm": 290.0}}, ["operating.torque_Nm=290"])
    check_case({"case": 1, "operating": {"torque_Nm": 300.0, "bulk_temperature_K": 330.0}},
               ["operating.bulk_temperature_K=330"])
    check_case({"case": None, "operating": {"torque_Nm": 100.0}}, ["operating.torque_Nm=100"])
    check_case({"case": "all"})  # train.py's case, without the groups it sets
    assert scenario_from_config({"case": 1}).operating.torque_Nm == 290.0


def test_a_study_over_the_cases_takes_each_cases_values(reproduce_cfg):
    """The reproduction's evolution runs each case of Table 11 in the configured scenario: an
    operating point given without case= is the base run's and no conflict there."""
    cfg = reproduce_cfg("operating.torque_Nm=250", "lubricant=pao")
    assert scenario_from_config(cfg).operating.torque_Nm == 250.0
    scn = scenario_for_case(cfg, 1)
    assert (scn.operating.n1_rpm, scn.operating.torque_Nm, scn.lubricant.eta0_Pa_s) == (
        1800.0, 290.0, 0.35)
    assert scn.lubricant.rho0_kg_m3 == 846.0  # the rest stays the configured lubricant's


def test_the_reproduction_refuses_case_with_an_operating_override(reproduce_cfg, tmp_path):
    """R13."""
    with pytest.raises(ValueError, match=r"case = 1 sets operating\.torque_Nm"):
        prepare(reproduce_cfg(f"out_dir={tmp_path / 'out'}", "case=1", "operating.torque_Nm=100"))
    prepare(reproduce_cfg(f"out_dir={tmp_path / 'out'}", "case=1"))


def test_every_app_with_case_refuses_it_before_its_own_checks(config_store, tmp_path, capsys):
    """L40 through the shared start of every app (physics.command.run_command): the loop's
    config with case=1 and operating.torque_Nm=300 (the default's value, given) is refused
    before its prepare runs, in one line, exit code 2."""
    from physics.loop.config import LoopConfig

    register_schema("loop_schema", LoopConfig)
    cfg = composed(APPS["loop"], ["data=table.csv", "case=1", "operating.torque_Nm=300"],
                   tmp_path / "run")

    def never(_):
        raise AssertionError("prepare ran")

    with pytest.raises(SystemExit) as end:
        run_command(cfg, never, never)
    assert end.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["error: case = 1 sets operating.torque_Nm = 290 (thesis Table 11), and "
                   "operating.torque_Nm = 300 is given too: the case's value would be used "
                   "without a word; give either case=1 or operating.torque_Nm, not both"], err
    assert not os.path.exists(tmp_path / "run")
