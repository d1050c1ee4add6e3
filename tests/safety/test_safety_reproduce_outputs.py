"""The reproduction and the rig comparison never replace files they did not make: an output
folder that already holds tables or figures (an earlier run's, or the user's own) is refused
before work, unless the user says overwrite."""

from __future__ import annotations

from pathlib import Path

import pytest

from physics.files import check_fresh
from physics.reproduce.rig import main as rig_main
from tests.acceptance.refusal import refusal

ROOT = Path(__file__).resolve().parents[2]


def test_a_folder_with_a_table_of_the_users_is_refused_and_kept(tmp_path, config_store):
    out = tmp_path / "res"
    out.mkdir()
    (out / "table02_speed.csv").write_text("mine\n")
    err = refusal("reproduce", [f"out_dir={out}"], tmp_path)
    assert str(err) == (
        f"out_dir = '{out}' already holds table02_speed.csv, which this run would "
        "replace; choose a new folder, or overwrite=true to replace them")
    assert (out / "table02_speed.csv").read_text() == "mine\n"
    assert sorted(p.name for p in out.iterdir()) == ["table02_speed.csv"]


def test_the_rig_comparison_refuses_its_own_earlier_files_without_overwrite(tmp_path, capsys):
    (tmp_path / "rig_summary.csv").write_text("earlier\n")
    assert rig_main(["--out", str(tmp_path)]) == 2
    assert "already holds rig_summary.csv" in capsys.readouterr().err
    assert (tmp_path / "rig_summary.csv").read_text() == "earlier\n"


def test_overwrite_and_an_empty_or_new_folder_pass(tmp_path):
    (tmp_path / "a.csv").write_text("x")
    with pytest.raises(ValueError, match=r"already holds a\.csv, which this run would replace"):
        check_fresh(tmp_path, "out_dir", ("*.csv",), False, "overwrite=true")
    check_fresh(tmp_path, "out_dir", ("*.csv",), True, "overwrite=true")
    check_fresh(tmp_path, "out_dir", ("*.png",), False, "overwrite=true")
    check_fresh(tmp_path / "new", "out_dir", ("*.csv",), False, "overwrite=true")


def test_the_dataset_app_keeps_a_dataset_file_it_did_not_make(tmp_path):
    """A dataset.parquet without the app's dataset.json beside it is the user's: refused
    before work, and kept."""
    from physics.dataset.generation import DatasetSpec, check_not_users, plan_dataset
    from physics.params import Scenario

    (tmp_path / "dataset.parquet").write_text("mine")
    spec = DatasetSpec(cases=[3], replicates=2, wear_states=2, chunks=2)
    job = plan_dataset(Scenario(), spec, tmp_path)  # a user's table given to read stays fine
    with pytest.raises(ValueError, match=r"already holds dataset\.parquet, which this build "
                                         r"would replace: no build of this app made it"):
        check_not_users(job)
    assert (tmp_path / "dataset.parquet").read_text() == "mine"


def test_a_dataset_record_the_app_did_not_write_is_kept(tmp_path):
    """A dataset.json that is not the app's record (a user's file of that name, no parquet
    beside it) is refused before work, and kept; the app's own record lets the build go on."""
    from physics.dataset.generation import DatasetSpec, check_not_users, plan_dataset
    from physics.params import Scenario

    spec = DatasetSpec(cases=[3], replicates=2, wear_states=2, chunks=2)
    job = plan_dataset(Scenario(), spec, tmp_path)
    (tmp_path / "dataset.json").write_text('{"my": "notes"}')
    with pytest.raises(ValueError, match=r"already holds dataset\.json, which this build would "
                                         r"replace: no build of this app made it"):
        check_not_users(job)
    assert (tmp_path / "dataset.json").read_text() == '{"my": "notes"}'
    (tmp_path / "dataset.json").write_text('{"hash": "abc", "schema_version": 1}')
    check_not_users(job)


def test_train_refuses_to_build_over_a_users_dataset_record(tmp_path):
    """The training run's own build of a missing dataset refuses, before work, a folder whose
    dataset.json is the user's."""
    from surrogate.data import WearDataModule

    (tmp_path / "dataset.json").write_text("my notes")
    with pytest.raises(ValueError, match=r"the folder of data\.dataset = .* already holds "
                                         r"dataset\.json"):
        WearDataModule(str(tmp_path / "dataset.parquet"))
    assert (tmp_path / "dataset.json").read_text() == "my notes"
