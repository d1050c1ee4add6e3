"""Item 5: bundles parsed safely: YAML without anchors/aliases/tags and below a size limit,
.npy headers checked against the file size before loading, a memory budget for the records,
a bundle refused as its own reference, bundles readable by the group."""

from __future__ import annotations

import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import physics.loop.measured.bundle as bundle_mod
from physics.loop.measured.bundle import check_not_own_reference, read_bundle, write_bundle

FS = 50_000.0


def manifest(n=2):
    return pd.DataFrame({"record": [f"r{i}" for i in range(n)], "quantity": "accel_m_s2",
                         "fs_hz": FS, "n1_rpm": 2000.0, "torque_Nm": 300.0, "wear_mm": 0.0,
                         "cycles": 0.0, "split": ""})


def signals(n=2):
    rng = np.random.default_rng(0)
    return {f"r{i}": rng.standard_normal(int(0.5 * FS)) for i in range(n)}


@pytest.fixture
def bundle(tmp_path):
    return write_bundle(tmp_path / "b", manifest(), signals())


LAUGHS = textwrap.dedent("""\
    a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]
    b: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a]
    c: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b]
    d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c]
    e: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d]
    f: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e]
    g: &g [*f,*f,*f,*f,*f,*f,*f,*f,*f]
    """)


def test_acceptance_billion_laughs_is_refused_at_once(bundle):
    """The user's probe: a 7-line gear.yaml of aliases, through the app's reader, in a child
    process with a timeout (it hung before)."""
    (bundle / "gear.yaml").write_text(LAUGHS)
    code = ("from physics.loop.measured.bundle import read_bundle\n"
            f"try:\n    read_bundle({str(bundle)!r})\n"
            "except ValueError as e:\n    print(e)\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60)
    assert run.returncode == 0, run.stderr
    assert "gear.yaml line 1: YAML anchors (&) are not accepted" in run.stdout
    assert len(run.stdout.strip().splitlines()) == 1


@pytest.mark.parametrize("text, word", [("z1: !!python/object:os.system 1\n", "tags"),
                                        ("z1: *x\n", "aliases")])
def test_tags_and_aliases_are_refused(bundle, text, word):
    (bundle / "gear.yaml").write_text(text)
    with pytest.raises(ValueError, match=f"gear.yaml line 1: YAML {word}"):
        read_bundle(bundle)


def test_a_large_gear_yaml_is_refused(bundle):
    (bundle / "gear.yaml").write_text("# padding\n" * 10_000 + "z1: 19\n")
    with pytest.raises(ValueError, match=r"gear.yaml holds 100,007 bytes, above the limit"):
        read_bundle(bundle)


def test_plain_gear_yaml_still_reads(bundle):
    (bundle / "gear.yaml").write_text("z1: 18\n")
    assert read_bundle(bundle).gear == {"z1": 18}


def _lying_header(f: Path, n: int) -> None:
    x = np.zeros(10)
    header = {"descr": "<f8", "fortran_order": False, "shape": (n,)}
    with f.open("wb") as fp:
        np.lib.format.write_array_header_1_0(fp, header)
        fp.write(x.tobytes())


def test_a_header_claiming_1e12_samples_is_refused_before_loading(bundle):
    _lying_header(bundle / "signals" / "r1.npy", 10**12)
    with pytest.raises(ValueError) as err:
        read_bundle(bundle)
    text = str(err.value)
    assert "record 'r1'" in text and "(1000000000000,)" in text and "80 bytes" in text
    assert "\n" not in text


def test_a_truncated_signal_is_refused(bundle):
    f = bundle / "signals" / "r0.npy"
    f.write_bytes(f.read_bytes()[:-8])
    with pytest.raises(ValueError, match=r"record 'r0'.*damaged or truncated"):
        read_bundle(bundle)


def test_records_above_the_memory_budget_are_refused(bundle, monkeypatch):
    monkeypatch.setattr(bundle_mod, "MAX_RECORDS_BYTES", 100_000)
    with pytest.raises(ValueError, match=r"50,000 samples together, 0.0004 GB as float64, "
                                         r"above the limit of 0.0001 GB"):
        read_bundle(bundle)


def test_a_bundle_is_not_its_own_reference(bundle, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match=r"reference=b/ is the bundle data=.* itself"):
        check_not_own_reference(bundle, "b/")
    (tmp_path / "link").symlink_to(bundle)
    with pytest.raises(ValueError, match="itself"):
        check_not_own_reference("link", bundle)
    other = write_bundle(tmp_path / "c", manifest(), signals())
    check_not_own_reference(bundle, other)


def test_written_bundles_are_readable_by_the_group(tmp_path):
    import os

    old = os.umask(0o022)
    try:
        path = write_bundle(tmp_path / "shared", manifest(), signals(), gear={"z1": 18})
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o755
    assert stat.S_IMODE((path / "signals").stat().st_mode) == 0o755
    for f in (path / "manifest.csv", path / "gear.yaml", path / "signals" / "r0.npy"):
        assert stat.S_IMODE(f.stat().st_mode) == 0o644


def test_a_feature_table_with_wear_outside_its_unit_is_refused(tmp_path):
    from physics.loop.measured.bundle import read_feature_table

    path = tmp_path / "t.csv"
    pd.DataFrame({"wear_mm": [0.0, 24.0], "rms_m_s2": [1.0, 2.0]}).to_csv(path, index=False)
    with pytest.raises(ValueError, match=r"row 2, column 'wear_mm' = 24 lies outside \[0, 10\]"):
        read_feature_table(path)
