"""The default reproduction is deterministic: its tables hash as recorded (``table_hashes.sha256``,
written by ``python -m physics.reproduce record_hashes=true``). A change of the physics changes
them on purpose: record the new hashes with the change and say why in its commit.

The comparison itself is checked fast on small files: an empty or missing record, an edited
digest and a table missing on either side each fail it."""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys
from pathlib import Path

import pytest
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from physics.command import register_schema
from physics.reproduce import thesis
from physics.reproduce.thesis import (
    HASH_RECORD,
    UNRECORDED,
    ReproduceConfig,
    prepare,
    run,
    table_hashes,
    write_hash_record,
)
from tests.acceptance.refusal import APPS, composed, refusal

ROOT = Path(__file__).resolve().parents[2]
RECORD_IT = "python -m physics.reproduce record_hashes=true"
#: a small run (few grid points, one case)
FAST = ["solver.n_points=101", "stiffness.fem_refine=1", "stiffness.fem_refines=[1]",
        "stiffness.positions=40", "evolution.cases=[3]", "evolution.points=9",
        "evolution.table14_cycles=[0,1.5e7]"]
_LINE = re.compile(r"([0-9a-f]{64})  (\S+)")


def read_record(record: Path) -> dict[str, str]:
    """The digests of ``record`` by table name; an empty, missing or malformed record fails."""
    text = record.read_text() if record.is_file() else ""
    if not text.strip():
        raise AssertionError(f"{record} is empty or missing: nothing to compare the tables "
                             f"with; record them with {RECORD_IT} in the checkout")
    recorded = {}
    for line in text.splitlines():
        m = _LINE.fullmatch(line)
        if m is None:
            raise AssertionError(f"{record}: the line {line!r} is not '<sha256>  <name>'; "
                                 f"record it again with {RECORD_IT}")
        recorded[m.group(2)] = m.group(1)
    return recorded


def check_tables(record: Path, out: Path) -> None:
    """Fail unless the tables (CSV files) in ``out`` are exactly those of ``record``, byte for
    byte: every recorded table is there with its digest, and every table of the run (but the
    unrecorded ones) is recorded (:func:`read_record`: an empty or missing record fails)."""
    recorded = read_record(record)
    ours = table_hashes(out, sorted(p.name for p in out.glob("*.csv")))
    changed = sorted(n for n in recorded if n in ours and ours[n] != recorded[n])
    gone = sorted(set(recorded) - set(ours))
    new = sorted(set(ours) - set(recorded))
    if changed or gone or new:
        raise AssertionError(f"the tables differ from {record.name}: changed {changed}, "
                             f"recorded but not written {gone}, written but not recorded "
                             f"{new}; where the physics changed on purpose, record them again "
                             f"with {RECORD_IT}")


@pytest.mark.slow
def test_default_tables_are_byte_identical_to_the_recorded_ones(tmp_path):
    read_record(HASH_RECORD)  # an empty record fails before the long run
    subprocess.run([sys.executable, "-m", "physics.reproduce", f"out_dir={tmp_path / 'out'}",
                    f"hydra.run.dir={tmp_path / 'run'}"], check=True, cwd=tmp_path,
                   capture_output=True)
    check_tables(HASH_RECORD, tmp_path / "out")


@pytest.fixture
def tables(tmp_path) -> Path:
    """A run's folder of three small tables (one of them unrecorded) and its record."""
    out = tmp_path / "out"
    out.mkdir()
    for name, text in [("table02_speed.csv", "a,b\n1,2\n"), ("tvms.csv", "k\n3\n"),
                       (*UNRECORDED, "x\n1\n")]:
        (out / name).write_text(text)
    names = sorted(p.name for p in out.iterdir())
    write_hash_record(tmp_path / "table_hashes.sha256", table_hashes(out, names))
    return out


def test_the_record_is_sha256sum_sorted_without_the_unrecorded_tables(tables):
    record = tables.parent / "table_hashes.sha256"
    lines = record.read_text().splitlines()
    assert [line.split("  ")[1] for line in lines] == ["table02_speed.csv", "tvms.csv"]
    assert all(_LINE.fullmatch(line) for line in lines)
    check_tables(record, tables)  # a matching record passes
    (tables / "table02_speed.csv").write_text("a,b\n1,2\n")  # the same bytes again
    check_tables(record, tables)
    assert not list(tables.parent.glob(".*.tmp"))  # written atomically, no temporary left


@pytest.mark.parametrize("empty", ["", "\n"])
def test_an_empty_or_missing_record_fails(tables, empty):
    record = tables.parent / "table_hashes.sha256"
    record.write_text(empty)
    with pytest.raises(AssertionError, match=f"empty or missing.*{re.escape(RECORD_IT)}"):
        check_tables(record, tables)
    record.unlink()
    with pytest.raises(AssertionError, match="empty or missing"):
        check_tables(record, tables)


def test_an_edited_digest_or_table_fails(tables):
    record = tables.parent / "table_hashes.sha256"
    text = record.read_text()
    record.write_text(text.replace(text[0], "f" if text[0] != "f" else "0", 1))
    with pytest.raises(AssertionError, match=r"changed \['table02_speed.csv'\]"):
        check_tables(record, tables)
    record.write_text(text)
    (tables / "tvms.csv").write_text("k\n4\n")
    with pytest.raises(AssertionError, match=r"changed \['tvms.csv'\]"):
        check_tables(record, tables)


def test_a_table_missing_from_the_record_or_the_run_fails(tables):
    record = tables.parent / "table_hashes.sha256"
    (tables / "table15_new.csv").write_text("y\n1\n")
    with pytest.raises(AssertionError, match=r"written but not recorded \['table15_new.csv'\]"):
        check_tables(record, tables)
    (tables / "table15_new.csv").unlink()
    (tables / "tvms.csv").unlink()
    with pytest.raises(AssertionError, match=r"recorded but not written \['tvms.csv'\]"):
        check_tables(record, tables)


def test_a_malformed_line_fails(tables):
    record = tables.parent / "table_hashes.sha256"
    record.write_text(record.read_text() + "abc tvms.csv\n")
    with pytest.raises(AssertionError, match=r"'abc tvms\.csv' is not"):
        check_tables(record, tables)


def _composed(overrides: list[str], out: Path) -> DictConfig:
    """The reproduce app's config as Hydra gives it to the app, with its overrides recorded."""
    register_schema("reproduce_schema", ReproduceConfig)  # as the app does
    return composed(APPS["reproduce"], overrides, out)


def test_recording_outside_a_checkout_is_refused_first(tmp_path, monkeypatch):
    installed = tmp_path / "site-packages" / "tests" / "reproduce" / "table_hashes.sha256"
    monkeypatch.setattr(thesis, "HASH_RECORD", installed)
    cfg = _composed(["record_hashes=true", "case=9"], tmp_path / "run")  # case: refused later
    with pytest.raises(ValueError, match=r"record_hashes = true: .* installed without it \("
                                         rf"{installed.parents[2]} holds no pyproject.toml .*"
                                         r"run the command in a checkout") as err:
        prepare(cfg)
    assert "\n" not in str(err.value)
    assert not any(tmp_path.iterdir())


def test_a_checkout_without_its_tests_is_refused_too(tmp_path, monkeypatch):
    """A tests/reproduce folder alone is not a checkout (another package's, say)."""
    installed = tmp_path / "site-packages" / "tests" / "reproduce" / "table_hashes.sha256"
    installed.parent.mkdir(parents=True)
    monkeypatch.setattr(thesis, "HASH_RECORD", installed)
    with pytest.raises(ValueError, match="installed without it"):
        prepare(_composed(["record_hashes=true"], tmp_path / "run"))


def test_recording_from_python_is_refused(tmp_path, monkeypatch):
    """Outside the command (no Hydra run) the run's overrides are unknown: refused."""
    cfg = _composed(["record_hashes=true"], tmp_path / "run")
    monkeypatch.setattr(HydraConfig.instance(), "cfg", None)
    with pytest.raises(ValueError, match=r"^record_hashes = true: the hashes are recorded by "
                                         r"the command python -m physics.reproduce "
                                         r"record_hashes=true only; call it so, or set "
                                         r"record_hashes to false$"):
        prepare(cfg)


def test_recording_a_changed_run_is_refused(tmp_path):
    cfg = _composed(["record_hashes=true", "case=4", f"out_dir={tmp_path}"], tmp_path / "run")
    with pytest.raises(ValueError, match=r"record_hashes = true with case=4: .* drop case=4"):
        prepare(cfg)
    assert not any(tmp_path.iterdir())


def test_the_default_run_records_the_checkout_s_record(tmp_path):
    cfg = _composed(["record_hashes=true", f"out_dir={tmp_path / 'out'}"], tmp_path / "run")
    assert prepare(cfg).record == HASH_RECORD == ROOT / "tests" / "reproduce" / HASH_RECORD.name
    cfg = _composed([f"out_dir={tmp_path / 'out'}"], tmp_path / "run")
    assert prepare(cfg).record is None


def test_a_refused_recording_leaves_the_record(tmp_path, config_store):
    before = HASH_RECORD.read_bytes()
    err = refusal("reproduce", ["record_hashes=true", "case=4"], tmp_path)
    assert str(err) == (
        "record_hashes = true with case=4: the record holds the default run's tables, "
        "which the test compares with a default run; drop case=4 (only out_dir, overwrite, "
        "record_hashes may be given with it)")
    assert not any(tmp_path.iterdir()) and HASH_RECORD.read_bytes() == before


@pytest.mark.slow
def test_a_run_writes_the_record_of_its_tables(tmp_path):
    """The run's own record of a small run (written where the plan says) matches its tables."""
    plan = prepare(_composed([*FAST, f"out_dir={tmp_path / 'out'}"], tmp_path / "run"))
    record = tmp_path / "table_hashes.sha256"
    written = run(dataclasses.replace(plan, record=record))
    check_tables(record, tmp_path / "out")
    names = [line.split("  ")[1] for line in record.read_text().splitlines()]
    assert names == sorted(f"{name}.csv" for name in written if f"{name}.csv" not in UNRECORDED)
