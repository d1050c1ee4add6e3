"""The few-label study (``python -m surrogate.benchmark --few-labels-only``) refuses, before
work and in one line, model curves that cannot be the rig's (another unit, a part of the
stages, reversed, a gap, a repeated column), a record table without the study's columns, an
output that is one of its inputs or a file, and options it would not use."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from surrogate import benchmark

ROOT = Path(__file__).resolve().parents[2]
CURVES = ROOT / "docs" / "figures" / "rig_comparison.csv"


def _curves(tmp: Path, name: str) -> Path:
    rc = pd.read_csv(CURVES)
    path = tmp / f"{name}.csv"
    if name == "um":
        rc.assign(wear_mm=rc.wear_mm * 1000).to_csv(path, index=False)
    elif name == "reversed":
        rc.assign(wear_mm=rc.wear_mm.to_numpy()[::-1]).to_csv(path, index=False)
    elif name == "short":
        rc.head(3).to_csv(path, index=False)
    elif name == "gap":
        rc.loc[5, "rms_model_100Nm"] = float("nan")
        rc.to_csv(path, index=False)
    elif name == "twice":
        path.write_text(CURVES.read_text().replace("rms_model_100Nm", "rms_model_200Nm", 1))
    return path


@pytest.mark.parametrize("name, message", [
    ("um", "its deepest stage is 932 mm and the records' 0.932 mm"),
    ("short", "its deepest stage is 0.081 mm"),
    ("reversed", "wear_mm must be finite, >= 0 and non-decreasing"),
    ("gap", "column rms_model_100Nm must hold finite positive ratios"),
    ("twice", "has column(s) ['rms_model_200Nm'] more than once")])
def test_curves_that_cannot_be_the_rigs_are_refused(tmp_path, capsys, name, message):
    with pytest.raises(SystemExit) as end:
        benchmark.main(["--few-labels-only", "--rig-comparison", str(_curves(tmp_path, name)),
                        "--out", str(tmp_path / "out")])
    assert end.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert message in err, err
    assert not (tmp_path / "out").exists()


def test_outputs_and_options_it_cannot_honour_are_refused(tmp_path, capsys):
    io = tmp_path / "io"
    io.mkdir()
    (io / "few_labels.csv").write_bytes(CURVES.read_bytes())
    (tmp_path / "afile").write_text("mine")
    empty = tmp_path / "empty.csv"
    empty.write_text("stage,wear_mm,acc_rms_g\n")
    worn = tmp_path / "worn.csv"
    worn.write_text("stage,wear_mm,acc_rms_g\nW1,0.1,0.2\nW2,0.9,0.3\n")
    tries = {
        ("--few-labels-only", "--out", str(io), "--rig-comparison", str(io / "few_labels.csv"),
         "--overwrite"): "is a file this run writes",
        ("--few-labels-only", "--out", str(io), "--rig-comparison", str(CURVES)):
            "already holds few_labels.csv, which this run would replace; choose a new folder, "
            "or add --overwrite",
        ("--few-labels-only", "--out", str(tmp_path / "o"), "--figures", str(io)):
            "--figures = '" + str(io) + "' already holds few_labels.csv",
        ("--few-labels-only", "--out", str(tmp_path / "o"), "--figures", str(tmp_path / "afile")):
            "is a file, not a folder",
        ("--few-labels-only", "--out", str(tmp_path / "o"), "--real-rig", str(CURVES)):
            "columns ['acc_rms_g'] are missing",
        ("--few-labels-only", "--real-rig-only"): "give one of them",
        ("--few-labels-only", "--out", str(tmp_path / "o"), "--real-rig", str(empty)):
            "holds a header and no rows",
        ("--few-labels-only", "--out", str(tmp_path / "o"), "--real-rig", str(worn)):
            "hold no healthy stage (wear_mm 0) among their 2 rows",
        ("--rig-comparison", str(CURVES)): "is read by --few-labels-only alone"}
    for argv, message in tries.items():
        with pytest.raises(SystemExit) as end:
            benchmark.main(list(argv))
        assert end.value.code == 2, argv
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert message in err, (argv, err)
    assert (io / "few_labels.csv").read_bytes() == CURVES.read_bytes()
    assert (tmp_path / "afile").read_text() == "mine" and not (tmp_path / "o").exists()
