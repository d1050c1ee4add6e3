"""Every command and snippet of README.md, and those of the docs pages beyond the README's one
example each, run as a subprocess in a fresh folder, as typed (``tests/acceptance/readme.py``
says how, and which size overrides each gets).

A command that others start from runs once per session (``readme_folder``) and is tested in
the folder it left. ``test_every_readme_command_has_an_acceptance_test`` fails when the README
documents a command that the tables do not cover, or when the README table names one the README
no longer has.
"""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

import pytest

from physics.loop import LoopConfig
from physics.reproduce.thesis import ReproduceConfig
from tests.acceptance.readme import (
    ALL,
    BY_CI,
    COMMANDS,
    DOCS,
    DOCS_SNIPPETS,
    ROOT,
    SNIPPETS,
    STARTS,
    TRAIN_CASE3,
    commands,
    copy_start,
    run_step,
    snippets,
)

#: top-level keys each --help must show: the fields of the app's schema
HELP_KEYS = {
    "python -m physics.reproduce --help": [f.name for f in fields(ReproduceConfig)],
    "python -m physics.loop --help": [f.name for f in fields(LoopConfig)],
    "python train.py --help": ["case", "seed", "data", "model", "trainer", "callbacks",
                               "logger", "paths"],
}


def test_every_readme_command_has_an_acceptance_test():
    documented = set(commands())
    missing = documented - set(COMMANDS) - set(BY_CI)
    stale = set(COMMANDS) - documented
    assert not missing, f"README commands without an acceptance test: {sorted(missing)}"
    assert not stale, f"acceptance tests of commands the README no longer has: {sorted(stale)}"
    assert set(snippets()) == set(SNIPPETS)


def test_every_benchmark_script_has_an_acceptance_test():
    scripts = {f"python bench/{p.name}" for p in (ROOT / "bench").glob("bench_*.py")}
    assert scripts <= set(ALL), sorted(scripts - set(ALL))


def _params(*tables: dict) -> list:
    return [pytest.param(k, marks=[pytest.mark.slow] if c.slow else [], id=k[:60])
            for table in tables for k, c in table.items()]


def _ran(key: str, tmp_path: Path, readme_folder):
    """The folder ``key`` ran in and its process: the session's, if others start from it or
    read it, else a run in ``tmp_path`` from a copy of its start."""
    if key in STARTS:
        return readme_folder(key)
    case = ALL[key]
    if case.start is not None:
        copy_start(readme_folder(case.start)[0], tmp_path, case.only)
    return tmp_path, run_step(key, tmp_path)


@pytest.mark.parametrize("key", _params(COMMANDS, DOCS))
def test_command(key, tmp_path, readme_folder):
    case = ALL[key]
    folder, proc = _ran(key, tmp_path, readme_folder)
    if key.endswith("--help"):  # the help shows the config, generated from the app's schema
        assert "Powered by Hydra" in proc.stdout and "== Config ==" in proc.stdout
        for name in HELP_KEYS[key]:
            assert f"\n{name}:" in proc.stdout, f"{name} missing from {key}"
    if key == TRAIN_CASE3:  # each log line once, in the app's format; no advertisement
        out = proc.stdout + proc.stderr
        assert out.count("GPU available") == 1, out[-3000:]
        assert "litlogger" not in out and "INFO: " not in out, out[-3000:]
    if case.check is not None:
        case.check(folder)


@pytest.mark.parametrize("key", _params(SNIPPETS, DOCS_SNIPPETS))
def test_snippet(key, tmp_path, readme_folder):
    folder, _ = _ran(key, tmp_path, readme_folder)
    if ALL[key].check is not None:
        ALL[key].check(folder)
