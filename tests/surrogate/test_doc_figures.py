"""The figures docs/benchmark.md quotes for the real rig and the one-rig table are those of the
tables the benchmark writes, stored in docs/figures/ (``python -m surrogate.benchmark
--real-rig-only --figures docs/figures``; ``--one-rig-only --figures docs/figures``): a table
of the doc is read cell by cell and each number compared with its file's value at the digits
shown, so that changing the file or the doc alone fails."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "benchmark.md"
FIGURES = ROOT / "docs" / "figures"
NUMBER = re.compile(r"^\**(-?\d+(?:\.\d+)?)\**$")


def section(title: str) -> str:
    """The text of the doc's ``## title`` section, up to the next heading."""
    text = DOC.read_text()
    start = text.index(f"## {title}\n")
    end = re.search(r"\n#{2,3} ", text[start + 3:])
    return text[start:start + 3 + end.start()] if end else text[start:]


def tables(text: str) -> list[list[list[str]]]:
    """Every markdown table of ``text``: its rows (header first, the rule left out) of cells."""
    found, rows = [], []
    for line in [*text.splitlines(), ""]:
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if not all(set(c) <= set("-: ") for c in cells):
                rows.append(cells)
        elif rows:
            found.append(rows)
            rows = []
    return found


def table_with(text: str, first: str) -> list[list[str]]:
    """The table of ``text`` whose first header cell is ``first``."""
    for t in tables(text):
        if t[0][0] == first:
            return t
    raise AssertionError(f"docs/benchmark.md: no table headed {first!r} in its section; "
                         f"regenerate it from {FIGURES}")


def same(cell: str, value: float, where: str) -> None:
    """The doc's ``cell`` is ``value`` at the digits it shows ('-' for a missing value)."""
    if cell in ("-", "") or value is None or (isinstance(value, float) and math.isnan(value)):
        assert cell in ("-", "") and (value is None or math.isnan(value)), (
            f"{where}: the doc shows {cell!r}, the file {value!r}")
        return
    m = NUMBER.match(cell)
    assert m, f"{where}: {cell!r} is not a number"
    digits = len(m.group(1).split(".")[1]) if "." in m.group(1) else 0
    assert abs(float(m.group(1)) - value) <= 0.5 * 10 ** -digits + 1e-9, (
        f"{where}: the doc shows {m.group(1)}, docs/figures/ holds {value:.6g}: regenerate "
        "the doc's table from the file (or the file with the benchmark)")


#: the real rig's summary table: doc column -> real_rig.csv column
RIG_COLUMNS = {"mean relative error, worn stages [%]": "mean_relative_error_pct",
               "95 % coverage, rows": "interval_coverage_rows",
               "95 % coverage, stages": "interval_coverage_stages",
               "folds kept": "folds_kept"}
#: the real rig's stage table: doc column -> real_rig_stages.csv column
STAGE_COLUMNS = {"kept": "test_mean_relative_error_pct",
                 "network": "test_network_mean_relative_error_pct",
                 "linear": "test_linear_mean_relative_error_pct",
                 "monotone": "test_monotone_mean_relative_error_pct",
                 "average": "test_average_mean_relative_error_pct",
                 "median": "test_median_mean_relative_error_pct"}


def test_the_real_rig_figures_are_those_of_its_table():
    summary = pd.read_csv(FIGURES / "real_rig.csv").set_index("model")
    text = section("The real rig")
    doc = table_with(text, "model")
    header, quoted = doc[0], {}
    for row in doc[1:]:
        model = row[0].strip("*` ").split(" ")[0]
        assert model in summary.index, f"real rig table: model {row[0]!r} not in real_rig.csv"
        quoted[model] = row
        for name, col in RIG_COLUMNS.items():
            same(row[header.index(name)], summary.loc[model, col], f"real rig, {model}, {name}")
    assert set(quoted) == set(summary.index), (
        f"real rig table lists {sorted(quoted)}, real_rig.csv {sorted(summary.index)}")


def test_the_real_rig_worst_stages_are_those_of_its_table():
    stages = pd.read_csv(FIGURES / "real_rig_stages.csv").set_index("stage")
    doc = table_with(section("The real rig"), "stage")
    header = doc[0]
    for row in doc[1:]:
        stage = row[0].strip("*` ")
        assert stage in stages.index, f"real rig stages: {stage!r} not in real_rig_stages.csv"
        assert row[header.index("model kept")] == stages.loc[stage, "model_kind"]
        for name, col in STAGE_COLUMNS.items():
            same(row[header.index(name)], float(stages.loc[stage, col]),
                 f"real rig stage {stage}, {name}")
    worn = stages.test_mean_relative_error_pct.dropna()
    worst = set(worn.sort_values(ascending=False).index[:len(doc) - 1])
    assert {r[0].strip("*` ") for r in doc[1:]} == worst, (
        f"the doc's worst stages are not the {len(doc) - 1} of the largest kept error in "
        f"real_rig_stages.csv ({sorted(worst)})")


def test_the_real_rig_text_names_the_stages_its_interval_misses():
    """The prose after the tables: the worn stages the kept model's interval misses, each
    with its records missed, and the share of the healthy records it misses."""
    stages = pd.read_csv(FIGURES / "real_rig_stages.csv").set_index("stage")
    text = " ".join(section("The real rig").split())
    worn = stages.drop(index="Healthy")
    missed = worn[worn.test_interval_coverage < 1]
    for stage, row in missed.iterrows():
        records = round((1 - row.test_interval_coverage) * row.test_rows)
        said = f"{records} of {stage}'s {row.test_rows} records"
        assert said in text, f"docs/benchmark.md's real-rig text does not say {said!r}"
    assert len(missed) == 1, (f"the kept model's interval misses {sorted(missed.index)} "
                              "(real_rig_stages.csv): name each in the real-rig text")
    healthy = 1 - stages.loc["Healthy", "test_interval_coverage"]
    assert f"{healthy:.2f} of the healthy records" in text, (
        f"the kept model's interval misses {healthy:.3f} of the healthy records")


def test_the_real_rig_text_splits_the_error_as_its_table_does():
    """The points the first worn stages and the stages whose RMS falls add to the kept
    model's error, the others' error, and the best model per stage, from the stage table."""
    stages = pd.read_csv(FIGURES / "real_rig_stages.csv").set_index("stage")
    worn = stages.drop(index="Healthy")
    kept = worn.test_mean_relative_error_pct
    early, falling = [f"W{k}" for k in range(1, 6)], [f"W{k}" for k in range(29, 33)]
    rest = kept.drop(index=early + falling)
    best = worn[[f"test_{m}_mean_relative_error_pct"
                 for m in ("network", "linear", "monotone", "average")]].min(axis=1)
    text = " ".join(section("The real rig").split())
    for said in (f"What holds the error at {kept.mean():.1f} %",
                 f"add {kept[early].sum() / len(kept):.1f} points",
                 f"add {kept[falling].sum() / len(kept):.1f} points",
                 f"the other {len(rest)} stages are read to {rest.mean():.1f} %",
                 f"picked knowing the answer, reads {best.mean():.1f} %"):
        assert said in text, f"docs/benchmark.md's real-rig text does not say {said!r}"


#: the one-rig table: doc column -> one_rig.csv column
ONE_RIG_COLUMNS = {"kept": "kept_mre_pct", "network": "network_mre_pct",
                   "linear": "linear_mre_pct", "monotone": "monotone_mre_pct",
                   "average": "average_mre_pct", "estimator": "estimator_mre_pct",
                   "median": "median_mre_pct",
                   "coverage": "interval_coverage", "flagged": "flag_rate",
                   "missed, not flagged": "missed_not_flagged"}


def test_the_one_rig_figures_are_those_of_its_table():
    rig = pd.read_csv(FIGURES / "one_rig.csv").set_index("scenario")
    doc = table_with(section("One rig"), "split")
    header = doc[0]
    assert len(doc) - 1 == len(rig), f"one-rig table: {len(doc) - 1} rows, one_rig.csv {len(rig)}"
    for row in doc[1:]:
        split = re.search(r"`one_rig/(\w+)`", row[0])
        assert split, f"one-rig table: {row[0]!r} names no `one_rig/<split>`"
        r = rig.loc[f"one_rig/{split.group(1)}"]
        assert row[header.index("model kept")] == r["kept"], f"one rig {split.group(1)}: kept"
        for name, col in ONE_RIG_COLUMNS.items():
            same(row[header.index(name)], float(r[col]), f"one rig {split.group(1)}, {name}")


def test_the_benchmark_copies_its_tables_into_figures(tmp_path, capsys):
    from surrogate.benchmark import copy_figures, main

    out, figures = tmp_path / "out", tmp_path / "figures"
    out.mkdir()
    (out / "real_rig.csv").write_text("model,mean_relative_error_pct\nkept,1.0\n")
    copy_figures(out, figures)
    assert (figures / "real_rig.csv").read_text() == (out / "real_rig.csv").read_text()
    assert not (figures / "real_rig_stages.csv").exists()  # absent in out: nothing copied
    with pytest.raises(SystemExit) as end:
        main(["--figures", str(figures)])
    assert end.value.code == 2
    assert "--figures" in capsys.readouterr().err


#: the few-label table: doc row -> few_labels.csv reader
FEW_LABEL_ROWS = {"physics, the exact tooth contact": "physics_exact",
                  "physics, the contact on the path": "physics_path",
                  "exponential (no physics)": "exponential", "straight line": "line"}


def test_the_few_label_figures_are_those_of_its_table():
    """docs/benchmark.md's few-label table and its rank correlations, from few_labels.csv
    (``--few-labels-only``) and rig_summary.csv (``python -m physics.reproduce.rig``)."""
    table = pd.read_csv(FIGURES / "few_labels.csv").set_index("reader")
    doc = {row[0]: row[1:] for row in table_with(section("Few labels: the physics as a prior"),
                                                 "reader")[1:]}
    assert set(doc) == set(FEW_LABEL_ROWS)
    for label, reader in FEW_LABEL_ROWS.items():
        r = table.loc[reader]
        assert doc[label] == [f"{r.mean_mre_pct:.1f}", f"{r.median_mre_pct:.1f}",
                              f"{r.best_share:.2f}"], label
    rig = pd.read_csv(FIGURES / "rig_summary.csv")
    text = " ".join(section("Few labels: the physics as a prior").split())
    for contact in ("exact", "path"):
        rank = rig[rig.contact == contact].rank_correlation
        assert f"{rank.min():.2f}-{rank.max():.2f}" in text, contact
    for reader in FEW_LABEL_ROWS.values():  # the prose's comparisons quote the same means
        assert f"{table.loc[reader, 'mean_mre_pct']:.1f} %" in text, reader
    assert table.loc["physics_exact", "mean_mre_pct"] > table.loc["exponential", "mean_mre_pct"]
    assert table.loc["physics_path", "mean_mre_pct"] <= table.loc["exponential", "mean_mre_pct"]
    # "slightly worse than the straight line on average, and reads the median draw best"
    assert table.loc["physics_path", "mean_mre_pct"] > table.loc["line", "mean_mre_pct"]
    assert table.median_mre_pct.idxmin() == "physics_path"
    assert (f"{table.loc['physics_path', 'median_mre_pct']:.1f} % against "
            f"{table.loc['line', 'median_mre_pct']:.1f} %") in text
