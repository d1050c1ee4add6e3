"""``surrogate.predict`` never replaces the user's own table: an output that is the input table
(the same file, by any name: a spelling with ``..``, a symbolic or a hard link) is refused, and
an output that already exists is refused unless ``overwrite=true``; before any work, in one line
naming the value, the rule and the fix (exit 2), leaving no file.

Checked in-process through the app's ``prepare`` on the composed config, then once as a user
types the command."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from surrogate.predict import execute
from tests.acceptance.refusal import APPS, composed

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(Path(__file__).parent))
from test_safety_user_tables import table  # noqa: E402

SAME = "is the input file itself"
EXISTS = "already exists: a file this run did not write is replaced only when asked"


@pytest.fixture(scope="module")
def model(small_model) -> Path:
    """A small model of the user-table kind (no gearbox baseline), trained for one epoch."""
    return small_model("auto")


@pytest.fixture
def mine(tmp_path) -> Path:
    """The user's own feature table."""
    path = tmp_path / "mine" / "T.csv"
    path.parent.mkdir()
    table().drop(columns="rig").to_csv(path, index=False)
    return path


def prepare(model: Path, source: Path, output: Path | str, *more: str, work: Path):
    spec = APPS["predict"]
    cfg = composed(spec, [f"ckpt={model}", f"input={source}", f"output={output}", *more],
                   work / "logs" / "run")
    return spec.prepare()(cfg)


def _same_file_spellings(mine: Path) -> dict[str, Path]:
    folder = mine.parent
    (folder / "link.csv").symlink_to(mine)
    os.link(mine, folder / "hard.csv")
    (folder / "sub").mkdir()
    return {"same path": mine, "with ..": folder / "sub" / ".." / mine.name,
            "symbolic link": folder / "link.csv", "hard link": folder / "hard.csv"}


def test_the_model_file_is_never_the_output_even_when_asked(model, mine, tmp_path,
                                                             config_store):
    """``output=`` the checkpoint the run reads (by a symbolic link too) is refused, with
    ``overwrite=true`` as well: the model file is an input."""
    (tmp_path / "m.pt").symlink_to(model)
    before = model.read_bytes()
    for output in (model, tmp_path / "m.pt"):
        with pytest.raises(ValueError) as err:
            prepare(model, mine, output, "overwrite=true", work=tmp_path / "work")
        text = str(err.value)
        assert text.startswith(f"output = {str(output)!r} is the ckpt file itself"), text
        assert "\n" not in text
    assert model.read_bytes() == before
    assert not (tmp_path / "work").exists()


@pytest.mark.parametrize("spelling", ["same path", "with ..", "symbolic link", "hard link"])
@pytest.mark.parametrize("overwrite", [[], ["overwrite=true"]])
def test_the_input_table_is_never_the_output(model, mine, tmp_path, config_store, spelling,
                                             overwrite):
    before = mine.read_bytes()
    output = _same_file_spellings(mine)[spelling]
    with pytest.raises(ValueError) as err:
        prepare(model, mine, output, *overwrite, work=tmp_path / "work")
    text = str(err.value)
    assert text.startswith(f"output = {str(output)!r} {SAME}"), text
    assert f"input = {str(mine)!r}" in text and "give another output file name" in text, text
    assert "\n" not in text
    assert mine.read_bytes() == before
    assert not (tmp_path / "work").exists()


def test_an_existing_file_is_replaced_only_with_overwrite(model, mine, tmp_path, config_store):
    other = tmp_path / "mine" / "wear.csv"
    other.write_text("my earlier results\n")
    with pytest.raises(ValueError) as err:
        prepare(model, mine, other, work=tmp_path / "work")
    assert str(err.value) == (f"output = {str(other)!r} {EXISTS}; give another output file "
                              "name, or pass overwrite=true to replace it")
    assert other.read_text() == "my earlier results\n"
    job = prepare(model, mine, other, "overwrite=true", work=tmp_path / "work")
    assert other.read_text() == "my earlier results\n"  # prepare writes nothing
    execute(job)
    wear = pd.read_csv(other)
    assert len(wear) == len(pd.read_csv(mine)) and "root_wear_mm_pred" in wear.columns
    assert not (tmp_path / "work").exists()


def test_a_new_output_needs_no_overwrite(model, mine, tmp_path, config_store):
    job = prepare(model, mine, tmp_path / "out" / "wear.csv", work=tmp_path / "work")
    assert job.output == tmp_path / "out" / "wear.csv" and not job.output.parent.exists()


@pytest.mark.parametrize(("value", "shown"), [("abc", "'abc'"), ("1", "1")])
def test_overwrite_is_a_switch(model, mine, tmp_path, config_store, value, shown):
    with pytest.raises(ValueError, match=rf"^overwrite = {shown} is not a switch; give "
                                         r"overwrite=true or overwrite=false$"):
        prepare(model, mine, tmp_path / "w.csv", f"overwrite={value}", work=tmp_path / "work")


def test_the_command_refuses_to_replace_its_input_in_one_line(model, mine, tmp_path):
    """As a user types it: ``input=T.csv output=T.csv`` ends with exit 2 and one line, the
    table unchanged and no file left (the run folder it made is gone)."""
    before = mine.read_bytes()
    work = tmp_path / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith("HYDRA_")}
    run = subprocess.run([sys.executable, "-m", "surrogate.predict", f"ckpt={model}",
                          f"input={mine}", f"output={mine}"], cwd=work, capture_output=True,
                         text=True, timeout=300, env=env)
    assert run.returncode == 2, run.stderr[-2000:]
    assert run.stderr.splitlines() == [
        f"error: output = {str(mine)!r} {SAME} (input = {str(mine)!r}): the predictions never "
        "replace what the run reads; give another output file name"], run.stderr[-2000:]
    assert mine.read_bytes() == before
    assert not any(work.iterdir()) and sorted(p.name for p in mine.parent.iterdir()) == ["T.csv"]
