"""The docstring examples of ``physics`` and ``surrogate`` run as doctests in the default test run
and the main entry points keep theirs.

A module takes part when its source contains ``>>>``: the files are read as text, so a module
without examples is not imported here (``surrogate`` would import torch). ``__main__`` modules
are left out (importing one starts its app). Examples are compared with ``ELLIPSIS`` and
``NORMALIZE_WHITESPACE``; a failing example fails its module's test with the doctest report.
"""

from __future__ import annotations

import doctest
import importlib
import inspect
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("physics", "surrogate")
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE

#: the public functions and classes whose docstrings must carry a numpydoc ``Examples`` section
#: with at least one example; each must also be found by the doctest finder,
#: so that its examples run
ENTRY_POINTS = (
    "physics.gear.geometry.mesh_geometry",
    "physics.gear.contact.hertz_half_width",
    "physics.gear.contact.hertz_max_pressure",
    "physics.gear.kinematics.sliding_velocity",
    "physics.gear.stiffness.MeshStiffness",
    "physics.tribology.wear.simulate_wear",
    "physics.signals.features.features",
    "physics.signals.indicators.time_synchronous_average",
    "physics.signals.indicators.na4",
    "physics.signals.indicators.indicators",
    "physics.signals.measurement.housing_acceleration",
    "physics.estimators.empirical_inverse.EmpiricalInverse.from_config",
    "physics.estimators.empirical_inverse.EmpiricalInverse.predict",
    "physics.params.Scenario",
)


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules_with_examples() -> list[str]:
    """The modules of :data:`PACKAGES` whose source holds ``>>>``, by dotted name."""
    return [_module_name(path)
            for package in PACKAGES
            for path in sorted((ROOT / package).rglob("*.py"))
            if path.name != "__main__.py" and ">>>" in path.read_text(encoding="utf-8")]


MODULES = modules_with_examples()


def _doctests(module_name: str) -> list[doctest.DocTest]:
    module = importlib.import_module(module_name)
    tests = doctest.DocTestFinder(exclude_empty=True).find(module)
    return sorted((t for t in tests if t.examples), key=lambda t: t.name)


def _resolve(dotted: str) -> tuple[str, object]:
    """The module of ``dotted`` (the longest importable prefix) and the object it names."""
    parts = dotted.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        candidate = ".".join(parts[:cut])
        try:
            obj = importlib.import_module(candidate)
        except ModuleNotFoundError as err:
            if err.name != candidate:  # a module that exists but fails to import
                raise
            continue
        for attr in parts[cut:]:
            obj = getattr(obj, attr)
        return ".".join(parts[:cut]), obj
    raise AssertionError(f"{dotted} names no module")


def test_modules_with_examples_are_found():
    assert MODULES, "no module of physics/ or surrogate/ holds a '>>>' example"
    missing = {_resolve(name)[0] for name in ENTRY_POINTS} - set(MODULES)
    assert not missing, f"modules of the entry points without examples: {sorted(missing)}"


@pytest.mark.parametrize("module_name", MODULES)
def test_examples_run(module_name: str):
    tests = _doctests(module_name)
    assert tests, (f"{module_name} contains '>>>' but doctest finds no example in it: put the "
                   "examples in the docstring of the module or of one of its own functions, "
                   "classes or methods")
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    report: list[str] = []
    failed = attempted = 0
    for test in tests:
        result = runner.run(test, out=report.append)
        failed, attempted = failed + result.failed, attempted + result.attempted
    if failed:
        pytest.fail(f"{failed} of {attempted} doctest examples of {module_name} failed:\n"
                    + "".join(report), pytrace=False)


#: a numpydoc section header: a title line underlined by dashes
SECTION = re.compile(r"^(\S[^\n]*)\n-{3,}[ \t]*$", re.MULTILINE)


def examples_section(doc: str) -> str | None:
    """The body of the numpydoc ``Examples`` section of ``doc`` (``None`` without one)."""
    headers = list(SECTION.finditer(doc))
    for i, header in enumerate(headers):
        if header.group(1).strip() == "Examples":
            end = headers[i + 1].start() if i + 1 < len(headers) else len(doc)
            return doc[header.end():end]
    return None


def test_examples_section_parser():
    doc = "Summary.\n\nParameters\n----------\nx : int\n\nExamples\n--------\n>>> 1 + 1\n2\n"
    assert examples_section(doc) == "\n>>> 1 + 1\n2\n"
    assert examples_section("Summary.\n\n>>> 1 + 1\n2\n") is None


@pytest.mark.parametrize("dotted", ENTRY_POINTS)
def test_entry_point_has_examples(dotted: str):
    module_name, obj = _resolve(dotted)
    doc = inspect.getdoc(obj) or ""
    body = examples_section(doc)
    assert body is not None, f"{dotted}: its docstring has no numpydoc 'Examples' section"
    assert any(line.lstrip().startswith(">>>") for line in body.splitlines()), (
        f"{dotted}: its 'Examples' section holds no '>>>' example")
    found = {t.name for t in _doctests(module_name)}
    assert dotted in found, (f"{dotted}: the doctest finder of {module_name} does not reach it, "
                             "so its examples would not run")
