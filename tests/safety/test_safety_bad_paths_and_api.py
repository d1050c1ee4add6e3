"""Bad input to the surrogate's commands and Python API, each answered in one line naming the
value, what is wrong and the fix:

- a checkpoint whose stored input deviations (or target scale) are zero: refused on loading
  (it would predict infinities, or zero wear with an interval of width zero);
- ``surrogate.summarise`` on a folder that does not exist, a file, an empty folder, a folder
  without run folders, a run whose records cannot be read;
- a full disk while ``surrogate.predict`` writes: one line, exit 1, no half-written file;
  an output that is a device (/dev/full) refused before work (with ``overwrite=true`` it
  would have been replaced by a file);
- ``hydra/launcher=cluster`` without SLURM: refused before the sweep's folder is made;
- the Python API given ``None`` or a dict instead of a path or a table;
- a folder as ``init_from``, ``/dev/zero`` or a FIFO as a file input: said so, not
  "does not exist";
- a read-only data folder named as the train command's setting, not the dataset API's
  ``out_dir``;
- an unquoted value beyond ASCII in an override: the way to quote it, not the lexer's error.
"""

from __future__ import annotations

import errno
import os
import re
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import torch

from physics.command import check_spelling
from physics.files import WriteFailed, existing_file
from surrogate.inference import Surrogate
from surrogate.predict import execute, predict_file
from surrogate.summarise import main as summarise_main
from tests.acceptance.refusal import APPS, composed

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(Path(__file__).parent))
from test_safety_user_tables import table, train_cfg  # noqa: E402

ENV = {k: v for k, v in os.environ.items() if not k.startswith("HYDRA_")}


@pytest.fixture(scope="module")
def model(small_model) -> Path:
    """A small network trained for one epoch on a user table; the table beside it."""
    return small_model("network")


# --- a checkpoint that cannot scale its rows ----------------------------------------------------

@pytest.mark.parametrize(("field", "value", "said"), [
    ("std", 0.0, "its input scaling of ['dte_peak_to_peak', "),
    ("mean", float("nan"), "its input scaling of ['dte_peak_to_peak', "),
    ("target_scale", 0.0, "its target scale 0.0 is not a finite number above zero"),
])
def test_a_checkpoint_with_zero_deviations_is_refused_on_loading(model, tmp_path, field, value,
                                                                 said):
    payload = torch.load(model, weights_only=True)
    schema = payload["hparams"]["schema"]
    schema[field] = [value] * len(schema[field]) if field != "target_scale" else value
    torch.save(payload, tmp_path / "bad.pt")
    with pytest.raises(ValueError) as err:
        Surrogate.load(tmp_path / "bad.pt")
    text = str(err.value)
    assert text.startswith(f"checkpoint = '{tmp_path / 'bad.pt'}' is incomplete or from another "
                           f"model ({said}"), text
    assert text.endswith("pass the wear_surrogate.pt a training run exported")


def test_a_checkpoint_whose_schema_repeats_an_input_is_blamed(model, tmp_path):
    payload = torch.load(model, weights_only=True)
    schema = payload["hparams"]["schema"]
    schema["inputs"] = [schema["inputs"][0]] * len(schema["inputs"])
    torch.save(payload, tmp_path / "bad.pt")
    with pytest.raises(ValueError, match=r"is incomplete or from another model \(its schema "
                                         r"names the input\(s\) \['dte_peak_to_peak'\] more than "
                                         r"once\)"):
        Surrogate.load(tmp_path / "bad.pt")


def test_a_foreign_torch_file_is_refused_in_one_line(tmp_path):
    """A pickle torch's safe loader refuses: its dozen lines of advice cut to the first."""
    torch.save({"x": __import__("types").SimpleNamespace(a=1)}, tmp_path / "foreign.pt")
    with pytest.raises(ValueError) as err:
        Surrogate.load(tmp_path / "foreign.pt")
    assert len(str(err.value).splitlines()) == 1 and "is not a safe wear-surrogate file (" in \
        str(err.value), err.value


# --- surrogate.summarise on a bad folder --------------------------------------------------------

def _summarise(capsys, *argv: str) -> tuple[int, str]:
    with pytest.raises(SystemExit) as end:
        summarise_main(list(argv))
    return end.value.code, capsys.readouterr().err


def test_summarise_refuses_each_bad_folder_in_one_line(tmp_path, capsys):
    (tmp_path / "a file").write_text("x")
    (tmp_path / "empty").mkdir()
    (tmp_path / "plain").mkdir()
    (tmp_path / "plain" / "notes.txt").write_text("x")
    for folder, said in [("missing", "does not exist"), ("a file", "is a file, not a folder"),
                         ("empty", "is empty: it is not the folder of a multirun"),
                         ("plain", "holds no Hydra run folders (<n>/.hydra): it is not the "
                                   "folder of a multirun")]:
        code, err = _summarise(capsys, str(tmp_path / folder))
        assert code == 2 and err == (f"error: {tmp_path / folder} {said}; pass the folder of "
                                     "a multirun, e.g. logs/train/multiruns/<time>\n"), err
    code, err = _summarise(capsys, "/dev/zero")
    assert code == 2 and "is a device, a FIFO or a socket, not a folder" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a file", "empty", "plain"]


def test_summarise_lists_a_run_whose_records_cannot_be_read(tmp_path, capsys):
    sweep = tmp_path / "sweep"
    for run, overrides in (("0", "- model.width=8\n"), ("1", "[unclosed\n")):
        (sweep / run / ".hydra").mkdir(parents=True)
        (sweep / run / ".hydra" / "overrides.yaml").write_text(overrides)
        (sweep / run / ".hydra" / "config.yaml").write_text("optimized_metric: m\n")
    (sweep / "0" / "metrics.json").write_text('{"m": 1.5}\n')
    summarise_main([str(sweep)])
    assert "Traceback" not in capsys.readouterr().err
    rows = pd.read_csv(sweep / "summary.csv")
    assert rows.status.tolist() == ["ok", "unreadable"] and rows.m.iloc[0] == 1.5
    assert "while parsing" in rows.error.iloc[1]
    code, err = _summarise(capsys, str(sweep), "--out", "/dev/full")
    assert code == 2 and err == ("error: --out = '/dev/full' is not a regular file; give a .csv "
                                 "file name\n")
    # the default summary.csv is the command's own; another existing file only when asked, and
    # never one of the sweep's files, which it reads
    summarise_main([str(sweep)])
    mine = tmp_path / "mine.csv"
    mine.write_text("my own table\n")
    code, err = _summarise(capsys, str(sweep), "--out", str(mine))
    assert code == 2 and "already exists: a file this command did not write" in err, err
    assert mine.read_text() == "my own table\n"
    summarise_main([str(sweep), "--out", str(mine), "--overwrite"])
    assert pd.read_csv(mine).status.tolist() == ["ok", "unreadable"]
    before = (sweep / "0" / "metrics.json").read_text()
    for inside in (sweep / "0" / "metrics.json", sweep / "1" / ".." / "0" / "new.csv"):
        code, err = _summarise(capsys, str(sweep), "--out", str(inside), "--overwrite")
        assert code == 2 and "lies in the sweep's folder" in err, err
    assert (sweep / "0" / "metrics.json").read_text() == before
    assert not (sweep / "0" / "new.csv").exists()


# --- a full disk while predict writes -------------------------------------------------------------

def _prepare(model: Path, *overrides: str, work: Path):
    spec = APPS["predict"]
    cfg = composed(spec, [f"ckpt={model}", f"input={model.parents[1] / 'features.csv'}",
                          *overrides], work / "logs" / "run")
    return spec.prepare()(cfg)


def test_a_full_disk_during_predict_leaves_no_half_written_file(model, tmp_path, monkeypatch,
                                                                config_store):
    job = _prepare(model, f"output={tmp_path / 'out' / 'wear.csv'}", work=tmp_path)

    def full(self, path, *args, **kwargs):
        Path(path).write_text("case,wear\n1,")  # part of the rows, then the disk is full
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(pd.DataFrame, "to_csv", full)
    with pytest.raises(WriteFailed) as err:
        execute(job)
    assert err.value.errno == errno.ENOSPC
    assert err.value.strerror == (f"{tmp_path / 'out' / 'wear.csv'} could not be written (No "
                                  "space left on device)")
    assert not any((tmp_path / "out").iterdir())  # neither the file nor its temporary


def test_a_device_as_the_predict_output_is_refused_before_work(model, tmp_path, config_store):
    """/dev/full as the output is refused by the command's checks, even with
    ``overwrite=true`` (which would have replaced it by a file)."""
    with pytest.raises(ValueError) as err:
        _prepare(model, "output=/dev/full", "overwrite=true", work=tmp_path)
    assert str(err.value) == ("output = '/dev/full' is not a regular file (a FIFO, a device or "
                              "a socket); give a .csv file name")


def test_the_predict_command_ends_a_full_disk_in_one_line(model, tmp_path):
    """A write that fails with ENOSPC (the output's folder on a full disk, simulated in a small
    driver) ends the command with exit 1 and one line."""
    features = model.parents[1] / "features.csv"
    driver = ("import errno, sys, pandas as pd\n"
              "def full(*a, **k): raise OSError(errno.ENOSPC, 'No space left on device')\n"
              "pd.DataFrame.to_csv = full\n"
              "sys.argv = ['surrogate.predict', *sys.argv[1:]]\n"
              "from surrogate.predict import main\nmain()\n")
    run = subprocess.run([sys.executable, "-c", driver, f"ckpt={model}", f"input={features}",
                          "output=out/wear.csv", "hydra.run.dir=h"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=300, env=ENV)
    assert run.returncode == 1 and "Traceback" not in run.stderr, run.stderr[-2000:]
    assert [ln for ln in run.stderr.splitlines() if ln.startswith("error:")] == [
        "error: out/wear.csv could not be written (No space left on device); that file is left "
        "as it was: make room (or choose another folder) and run the command again"], run.stderr
    assert not list((tmp_path / "out").iterdir())


# --- the SLURM launcher without SLURM -------------------------------------------------------------

def test_the_cluster_launcher_without_slurm_is_refused_before_the_sweep(tmp_path):
    if any((Path(d) / "srun").exists() for d in os.environ.get("PATH", "").split(os.pathsep)):
        pytest.skip("this machine has a SLURM client")
    run = subprocess.run([sys.executable, str(ROOT / "train.py"), "-m", "case=3",
                          "hydra/launcher=cluster"], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300, env=ENV)
    assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr[-2000:]
    assert run.stderr.splitlines() == [
        "error: hydra.launcher = hydra_plugins.hydra_submitit_launcher.submitit_launcher."
        "SlurmLauncher: the sweep's jobs go to SLURM, and this machine has no SLURM client (no "
        "srun on the PATH); run the sweep here with the default launcher (drop "
        "hydra/launcher=cluster) or on a SLURM login node"]
    assert not any(tmp_path.iterdir())


# --- the Python API given what is no path or table ------------------------------------------------

@pytest.mark.parametrize("value", [None, {"path": "m.pt"}, 3, ""])
def test_the_api_names_an_argument_that_is_no_path(model, tmp_path, value):
    with pytest.raises(ValueError, match=rf"^checkpoint = {value!r} is not a file name; pass "
                                         r"the wear_surrogate.pt of a training run"):
        Surrogate.load(value)
    features = model.parents[1] / "features.csv"
    for args, key in (((value, features, tmp_path / "w.csv"), "ckpt"),
                      ((model, value, tmp_path / "w.csv"), "input"),
                      ((model, features, value), "output")):
        with pytest.raises(ValueError, match=rf"^{key} = {value!r} is not a file name"):
            predict_file(*args)
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("value", [None, {"dte_kurtosis": [3.0]}, "features.csv"])
def test_predict_names_a_table_that_is_no_data_frame(model, value):
    s = Surrogate.load(model)
    with pytest.raises(TypeError, match=rf"^df = {type(value).__name__}: predict reads a pandas "
                                        r"DataFrame with the columns \['dte_peak_to_peak'"):
        s.predict(value)


@pytest.mark.parametrize(("cell", "said"), [
    (complex(0.02, 0.01), r"is \(0\.02\+0\.01j\): a complex number"),
    ("abc", r"is 'abc': not a real number"),
    (True, r"is True: a boolean"),
])
def test_predict_names_the_row_and_column_of_a_cell_that_is_no_real_number(model, cell, said):
    """A complex feature (whose real part alone a float conversion would keep, without a word),
    a text or a boolean cell: refused naming the row (counted from 1) and the column."""
    s = Surrogate.load(model)
    df = table().drop(columns="rig")
    col = s.schema.columns[0]
    bad = df.astype({col: object})
    bad.loc[2, col] = cell
    with pytest.raises(ValueError, match=rf"^row 3 column {col} {said}"):
        s.predict(bad)
    whole = df.astype({col: complex}).assign(**{col: df[col] + 1j})
    with pytest.raises(ValueError, match=rf"^row 1 column {col} is .*a complex number"):
        s.predict(whole)
    assert len(s.predict(df.astype({col: complex}))) == len(df)  # no imaginary part: its value


def test_predict_refuses_a_frame_repeating_an_input_column(model):
    """Through the Python API, before any cell is read (a repeated column read as one ended
    in an AttributeError)."""
    s = Surrogate.load(model)
    df = table().drop(columns="rig")
    col = s.schema.columns[0]
    twice = pd.concat([df, df[[col]].astype(str)], axis=1)
    with pytest.raises(ValueError, match=rf"input has column\(s\) \['{col}'\] more than once"):
        s.predict(twice)


def test_the_api_never_writes_over_its_input(model, tmp_path):
    """predict_file, like the command, never replaces its input table, and another existing
    file only with ``overwrite``."""
    mine = tmp_path / "T.csv"
    table().to_csv(mine, index=False)
    before = mine.read_bytes()
    with pytest.raises(ValueError, match="is the input file itself"):
        predict_file(model, mine, mine, overwrite=True)
    (tmp_path / "w.csv").write_text("mine\n")
    with pytest.raises(ValueError, match="already exists"):
        predict_file(model, mine, tmp_path / "w.csv")
    assert mine.read_bytes() == before and (tmp_path / "w.csv").read_text() == "mine\n"
    assert len(predict_file(model, mine, tmp_path / "w.csv", gearbox="rig", overwrite=True))


# --- a folder, a device or a FIFO given as a file -----------------------------------------------

def test_a_folder_a_device_and_a_fifo_are_said_to_be_so(tmp_path):
    os.mkfifo(tmp_path / "pipe.csv")
    fix = "pass it"
    for path, said in ((tmp_path, "is a folder, not a file"),
                       (Path("/dev/zero"), "is not a regular file (a FIFO, a device or a socket)"),
                       (tmp_path / "pipe.csv", "is not a regular file"),
                       (tmp_path / "none.csv", "does not exist")):
        with pytest.raises(ValueError, match=f"^{re.escape(f'input = {str(path)!r} {said}')}"):
            existing_file(path, "input", fix)


def test_the_train_command_names_a_folder_given_as_init_from(model, tmp_path, config_store):
    table().to_csv(tmp_path / "in.csv", index=False)
    from surrogate.training import prepare

    with pytest.raises(ValueError, match=rf"^init_from = '{model.parent}' is a folder, not a "
                                         r"file; pass the wear_surrogate.pt of a training run"):
        prepare(train_cfg(tmp_path, f"init_from={model.parent}", table="in.csv"))
    os.mkfifo(tmp_path / "pipe.csv")
    with pytest.raises(ValueError, match=r"^data.table = '.*pipe.csv' is not a regular "
                                         r"file \(a FIFO"):
        prepare(train_cfg(tmp_path, table="pipe.csv"))


def test_a_fifo_as_the_predict_input_is_refused_at_once(model, tmp_path, config_store):
    os.mkfifo(tmp_path / "pipe.csv")
    spec = APPS["predict"]
    cfg = composed(spec, [f"ckpt={model}", f"input={tmp_path / 'pipe.csv'}"],
                   tmp_path / "logs" / "run")
    with pytest.raises(ValueError, match=r"^input = '.*pipe.csv' is not a regular file"):
        spec.prepare()(cfg)  # (reading a FIFO would wait for ever)


# --- the train command's data folder ------------------------------------------------------------

def test_an_unwritable_data_dir_is_named_as_the_train_command_s_setting(tmp_path, config_store):
    spec = APPS["train"]
    prepare = spec.prepare()  # registers the train schemas, as train.py does
    cfg = composed(spec, ["paths.data_dir=/proc/gearwear_data"], tmp_path / "run")
    with pytest.raises(ValueError) as err:
        prepare(cfg)
    assert str(err.value).startswith(
        "data: the folder of data.dataset (paths.data_dir unless data.dataset is set) = "
        "'/proc/gearwear_data': cannot write in /proc"), str(err.value)
    assert "out_dir" not in str(err.value)


# --- values beyond ASCII on the command line ------------------------------------------------------

def test_an_unquoted_value_beyond_ascii_gets_the_way_to_quote_it(tmp_path):
    check_spelling(["data.table='/tmp/mé.csv'", "case=3", "-m", "--cfg", "job"])  # all readable
    with pytest.raises(ValueError) as err:
        check_spelling(["case=3", "data.table=/tmp/mé.csv"])
    assert str(err.value) == (
        "data.table=/tmp/mé.csv: the value holds 'é', which Hydra's override grammar reads as "
        "its own or cannot read unquoted; quote the value: data.table='/tmp/mé.csv' (in the "
        "shell: \"data.table='/tmp/mé.csv'\")")
    with pytest.raises(ValueError, match=r"^data\.inputs=\[a,é\]: an item holding a character "
                                         r"beyond ASCII must be quoted"):
        check_spelling(["data.inputs=[a,é]"])
    with pytest.raises(ValueError, match=r"the key 'data.columns.Weg_ü' holds a character "
                                         r"beyond ASCII"):
        check_spelling(["+data.columns.Weg_ü=dte_kurtosis"])
    run = subprocess.run([sys.executable, "-m", "surrogate.predict", "ckpt=/tmp/mé.pt",
                          "input=x.csv"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=300, env=ENV)
    assert run.returncode == 2 and run.stderr.splitlines() == [
        "error: ckpt=/tmp/mé.pt: the value holds 'é', which Hydra's override grammar reads as "
        "its own or cannot read unquoted; quote the value: ckpt='/tmp/mé.pt' (in the shell: "
        "\"ckpt='/tmp/mé.pt'\")"], run.stderr
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(("arg", "odd"), [("data.table=a(1).csv", "'(' ')'"),
                                          ("input=v{2}.csv", "'{' '}'"),
                                          ("ckpt=x=1.pt", "'='"),
                                          ("output=it's.csv", "\"'\"")])
def test_an_unquoted_value_with_the_grammar_s_own_characters_gets_the_way_to_quote_it(arg, odd):
    """ASCII characters Hydra's grammar reads as its own (parentheses, braces, '=', a quote)
    in a value: the way to quote it, not the lexer's text; the quoted form is read."""
    with pytest.raises(ValueError) as err:
        check_spelling([arg])
    key, _, value = arg.partition("=")
    q = '"' if "'" in value else "'"
    assert str(err.value).startswith(f"{arg}: the value holds {odd}, which Hydra's override "
                                     f"grammar reads as its own or cannot read unquoted; quote "
                                     f"the value: {key}={q}{value}{q} (in the shell: "), err.value
    check_spelling([f"{key}={q}{value}{q}", "data.inputs=[a,b]", "x=[1,2]", "+y={a: 1}"])
    with pytest.raises(ValueError) as err:  # both quotes: in ', each ' escaped
        check_spelling(["input=it's\"q.csv"])
    assert "quote the value: input='it\\'s\"q.csv' (in the shell: " in str(err.value), err.value


def test_a_binary_units_sidecar_is_named(tmp_path):
    """A units sidecar that is not text: one line naming the file and the byte, not a bare
    decoding error."""
    from surrogate.tables import table_units

    table = tmp_path / "mine.csv"
    table.write_text("a,wear_mm\n1,0.1\n")
    (tmp_path / "mine.units.yaml").write_bytes(b"\x80\x81 binary")
    with pytest.raises(ValueError, match=r"mine\.units\.yaml is not UTF-8 text \(byte 0x80"):
        table_units(table, {}, None, ["a"])


def test_a_units_sidecar_that_is_a_folder_is_said_to_be_one(tmp_path):
    """A folder named like the units sidecar was passed over, and the run asked for the units
    it holds: said to be a folder."""
    from surrogate.tables import table_units

    table = tmp_path / "mine.csv"
    table.write_text("a,wear_mm\n1,0.1\n")
    (tmp_path / "mine.units.yaml").mkdir()
    with pytest.raises(ValueError, match=r"mine\.units\.yaml, the units sidecar of the table, is "
                                         r"a folder"):
        table_units(table, {}, None, ["a"])


def test_cells_of_every_numeric_kind_are_read_as_their_value():
    """Text numbers, pandas' nullable floats and strings, a Decimal, and a complex cell
    without an imaginary part are their real value; empty cells stay NaN for the finiteness
    check (which names them)."""
    from decimal import Decimal

    from surrogate.schema import FeatureSchema

    train = pd.DataFrame({"a": [0.0, 1.0, 2.0, 3.0], "w": [0.0, 0.1, 0.2, 0.3]})
    schema = FeatureSchema.fit(train, ["a"], {"a": "1", "w": "mm"}, "w")
    for col in (["1", "2.5", "1e0"], pd.array([1, 2.5, 1], dtype="Float64"),
                pd.array(["1", "2.5", "1"], dtype="string"), [Decimal("1"), 2.5, 1],
                pd.Series([1 + 0j, "2.5", 1.0], dtype=object)):
        assert schema.check(pd.DataFrame({"a": col}))[:, 0].tolist() == [1.0, 2.5, 1.0], col
    with pytest.raises(ValueError, match=r"^row 2 column a is nan: every input must be finite"):
        schema.check(pd.DataFrame({"a": pd.array(["1", None, "1"], dtype="string")}))
