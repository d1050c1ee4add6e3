"""Item 3: a user's table (data.table=) is checked before any training: finite values, values
within what their units allow, one unit per column across groups, wear not negative and not
falling in time, every row in a group. A run that fails after training started exports
nothing (no wear_surrogate.pt; its checkpoints set aside)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hydra import compose, initialize_config_module

import surrogate.training as training
from surrogate import settings
from surrogate.inputs import DEFAULT_INPUTS
from surrogate.tables import user_table

ROOT = Path(__file__).resolve().parents[2]
NEEDED = [*DEFAULT_INPUTS, "n1_rpm", "torque_Nm", "root_wear_mm"]


def table(groups: int = 6, rows: int = 5, seed: int = 0) -> pd.DataFrame:
    """A plausible labelled table of ``groups`` rigs, their rows in time order."""
    rng = np.random.default_rng(seed)
    n = groups * rows
    cycles = np.tile(np.linspace(0, 4e6, rows), groups)
    wear = cycles * 4e-9 * rng.uniform(0.8, 1.2, n).reshape(groups, rows).mean(1).repeat(rows)
    return pd.DataFrame({
        "rig": np.repeat([f"rig{i}" for i in range(groups)], rows), "cycles": cycles,
        "dte_peak_to_peak": 2e-5 + 1e-6 * wear * 100 + rng.normal(0, 1e-7, n),
        "dte_kurtosis": 2.5 + rng.normal(0, 0.1, n), "acc_kurtosis": 3 + rng.normal(0, 0.1, n),
        "acc_crest": 4 + rng.normal(0, 0.1, n), "acc_margin": 6 + rng.normal(0, 0.1, n),
        "acc_impulse": 5 + rng.normal(0, 0.1, n), "acc_shape": 1.3 + rng.normal(0, 0.01, n),
        **{f"dte_mesh{k}_db": -10 * k + 1e3 * wear + rng.normal(0, 0.1, n)
           for k in range(2, 7)},
        "n1_rpm": 2000.0, "torque_Nm": 300.0, "root_wear_mm": wear})


def read(tmp_path: Path, df: pd.DataFrame, group: str = "rig") -> pd.DataFrame:
    path = tmp_path / "mine.csv"
    df.to_csv(path, index=False)
    return user_table(path, {}, group, NEEDED, "root_wear_mm")


def test_a_plausible_table_is_read(tmp_path):
    out = read(tmp_path, table())
    assert len(out) == 30 and out.replicate.nunique() == 6
    assert out.cycles.max() == 4e6  # the table's own time axis is kept


def _at(df, row, col, value):
    df = df.copy()
    df[col] = df[col].astype(object) if isinstance(value, str) else df[col]
    df.loc[row, col] = value
    return df


@pytest.mark.parametrize(("change", "message"), [
    (lambda d: _at(d, 7, "acc_crest", 1e300),
     r"row 8, column 'acc_crest' = 1e\+300 lies outside \[-1e\+06, 1e\+06\]"),
    (lambda d: _at(d, 3, "dte_kurtosis", np.nan),
     r"row 4, column 'dte_kurtosis' = nan is not a finite number"),
    (lambda d: _at(d, 2, "dte_peak_to_peak", 1e-2),
     r"row 3, column 'dte_peak_to_peak' = 0.01 lies outside \[0, 0.001\], what its unit m "
     r"allows"),
    (lambda d: d.assign(dte_peak_to_peak=np.where(d.rig == "rig2", d.dte_peak_to_peak * 1e-3,
                                                  d.dte_peak_to_peak)),
     r"column 'dte_peak_to_peak' has a median of .* in group 'rig\d' but .* in group "
     r"'rig\d', more than 100 times apart: mixed units"),
    (lambda d: _at(d, 4, "root_wear_mm", -0.001),
     r"row 5, column 'root_wear_mm' = -0.001 is negative"),
    (lambda d: _at(d, 3, "root_wear_mm", 0.0),
     r"group 'rig0': root_wear_mm falls from .* \(row 3, cycles 2e\+06\) to 0 \(row 4, "
     r"cycles 3e\+06\)"),
    (lambda d: _at(d, 11, "rig", np.nan), r"row 12 has no value in the group column 'rig'"),
    (lambda d: _at(d, 11, "rig", " "), r"row 12 has no value in the group column 'rig'"),
    (lambda d: _at(d, 0, "root_wear_mm", 50.0),
     r"row 1, column 'root_wear_mm' = 50 lies outside \[0, 10\]"),
])
def test_a_bad_table_is_refused_in_one_line(tmp_path, change, message):
    with pytest.raises(ValueError, match=message) as err:
        read(tmp_path, change(table()))
    assert "\n" not in str(err.value) and "mine.csv" in str(err.value)


def test_wear_order_follows_the_time_column_not_the_row_order(tmp_path):
    shuffled = table().sample(frac=1.0, random_state=3)  # rows in any order: time says
    assert len(read(tmp_path, shuffled)) == 30


def train_cfg(tmp: Path, *overrides: str, table: str = "mine.csv", val_replicates: int = 1,
              max_epochs: int = 2):
    """The train app's config for a small run on the user table ``tmp / table`` (rig groups)."""
    settings.register()
    with initialize_config_module("gearwear_conf.train", version_base="1.3"):
        return compose("train", overrides=[
            f"paths.root_dir={tmp}", f"paths.output_dir={tmp / 'run'}",
            f"data.dataset={tmp / 'unused.parquet'}", f"data.table={tmp / table}",
            "data.group=rig", f"data.val_replicates={val_replicates}", "data.test_replicates=1",
            "trainer.enable_progress_bar=false", f"trainer.max_epochs={max_epochs}",
            "model.members=2", "logger=csv", *overrides])


def test_a_run_that_fails_after_starting_exports_nothing(tmp_path, monkeypatch):
    table().to_csv(tmp_path / "mine.csv", index=False)

    def fails(*args, **kwargs):
        raise RuntimeError("a failure after training")

    monkeypatch.setattr(training, "report_test", fails)
    with pytest.raises(RuntimeError, match="after training"):
        training.train(train_cfg(tmp_path))
    run = tmp_path / "run"
    assert not (run / "wear_surrogate.pt").exists()
    assert not list(run.glob("*.staged")) and not (run / "metrics.json").exists()
    assert not list(run.rglob("checkpoints/*.ckpt"))  # no best.ckpt under its usual name
    monkeypatch.undo()
    assert np.isfinite(training.train(train_cfg(tmp_path)))  # the same run, then, succeeds
    assert (run / "wear_surrogate.pt").is_file()


@pytest.mark.slow  # its check: test_a_bad_table_is_refused_in_one_line; a train.py refusal
# after Lightning's import, as typed: the fine-tune's in test_safety_unhonoured_settings.py
def test_acceptance_train_refuses_a_table_of_1e300_before_training(tmp_path):
    """The user's probe through the command line: exit 2, one line, nothing trained."""
    df = _at(table(), 7, "acc_crest", 1e300)
    df.to_csv(tmp_path / "mine.csv", index=False)
    run = subprocess.run([sys.executable, "train.py", f"data.table={tmp_path / 'mine.csv'}",
                          "data.group=rig", f"paths.output_dir={tmp_path / 'run'}",
                          f"hydra.run.dir={tmp_path / 'run'}", "trainer.max_epochs=2"],
                         capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert run.returncode == 2, run.stderr[-2000:]
    # (Lightning's notices of the trainer made in prepare come before it)
    lines = [ln for ln in run.stderr.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1 and "'acc_crest' = 1e+300" in lines[0]
    assert "Traceback" not in run.stderr
    assert not (tmp_path / "run" / "wear_surrogate.pt").exists()


def test_a_csv_header_that_repeats_a_column_is_refused(tmp_path):
    """pandas reads a repeated CSV column as ``a`` and ``a.1``: the repetition is read from the
    header itself, for a training table and for a prediction input alike."""
    from surrogate.predict import read_table
    from surrogate.tables import read_user_table

    bad = tmp_path / "twice.csv"
    bad.write_text("rig,dte_rms,dte_rms,wear_mm\nA,1.0,2.0,0.1\n")
    with pytest.raises(ValueError, match=r"has column\(s\) \['dte_rms'\] more than once"):
        read_user_table(bad, {})
    with pytest.raises(ValueError, match=r"input = .* has column\(s\) \['dte_rms'\] more than"):
        read_table(bad)
    good = tmp_path / "once.csv"
    good.write_text("rig,dte_rms,wear_mm\nA,1.0,0.1\n")
    assert list(read_table(good).columns) == ["rig", "dte_rms", "wear_mm"]


def test_a_parquet_schema_that_repeats_a_column_is_refused(tmp_path):
    """A Parquet table may hold one name twice (pyarrow writes it): refused by name for a
    training table and a prediction input, not with pyarrow's FieldRef text."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from surrogate.predict import read_table
    from surrogate.tables import read_user_table

    bad = tmp_path / "twice.parquet"
    pq.write_table(pa.table([["A"], [1.0], [2.0], [0.1]],
                            names=["rig", "dte_rms", "dte_rms", "wear_mm"]), bad)
    with pytest.raises(ValueError, match=r"has column\(s\) \['dte_rms'\] more than once"):
        read_user_table(bad, {})
    with pytest.raises(ValueError, match=r"input = .* has column\(s\) \['dte_rms'\] more than"):
        read_table(bad)
    good = tmp_path / "once.parquet"
    pq.write_table(pa.table([["A"], [1.0], [0.1]], names=["rig", "dte_rms", "wear_mm"]), good)
    assert list(read_table(good).columns) == ["rig", "dte_rms", "wear_mm"]
