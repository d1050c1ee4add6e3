"""The house: import graph without cycles, layers in their order, apps imported by nothing,
physics/ free of torch, the installed package list in step with the tree, a public surface
(``__all__``) for every subpackage, no private name imported across subpackages, and the test
rigs (``physics.testbeds``) kept apart from the product."""

from __future__ import annotations

import ast
import importlib
import re
import tomllib
from functools import cache
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: physics layers, each importing only from those before it (README, Architecture)
LAYERS = ["exports", "blas", "arguments", "reference", "interrupt", "params", "files", "command",
          "gear", "scope", "tribology", "dynamics", "signals", "estimators", "dataset", "reproduce",
          "loop", "testbeds"]
#: the subpackages that name a public surface in ``__init__.py``
SUBPACKAGES = sorted({".".join(p.parent.relative_to(ROOT).parts)
                      for p in (ROOT / "physics").glob("*/**/__init__.py")} | {"surrogate"})
#: the loop's stages in the order of its data, each importing only from those before it; the
#: modules that serve every stage come first, the report and the orchestrators last
LOOP_LAYERS = [("config", "effects", "threads"), ("measured",), ("model",), ("judge",),
               ("search",), ("report",), ("bundle_loop", "table_loop"), ("__main__",)]
#: product code that may import the test rigs (besides bench/ and tests/)
TESTBED_USERS = {"surrogate.benchmark"}


@cache  # the tree does not change during a run; every import graph reads it
def modules() -> dict[str, Path]:
    out = {}
    for pkg in ("physics", "surrogate"):
        for path in (ROOT / pkg).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = path
    assert {"physics.params", "surrogate.predict"} <= set(out), f"no package found in {ROOT}"
    return out


@cache  # each module's text is parsed once a run, whichever test asks
def imports(path: Path, at_import: bool = False) -> frozenset[str]:
    """Modules ``path`` imports (absolute names; ``from a import b`` gives a.b if that is a
    module, else a). ``at_import``: only those importing it runs, its module-level imports,
    not those inside functions (deferred) or under ``if TYPE_CHECKING``."""
    known = modules()
    found = set()
    tree = ast.parse(path.read_text())
    for node in tree.body if at_import else ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            subs = {f"{node.module}.{a.name}" for a in node.names}
            found |= (subs & set(known)) or {node.module}
    return frozenset(found)


@cache
def graph() -> dict[str, frozenset[str]]:
    known = modules()
    return {m: frozenset(i for i in imports(p) if i in known) for m, p in known.items()}


def layer(module: str) -> int:
    return LAYERS.index(module.split(".")[1])


def test_no_import_cycle():
    try:
        tuple(TopologicalSorter(graph()).static_order())
    except CycleError as err:
        pytest.fail(f"import cycle: {err.args[1]}")


def test_physics_layers_import_only_downwards():
    wrong = [(m, i) for m, deps in graph().items() if m.startswith("physics.")
             for i in deps if i.startswith("physics.") and layer(i) > layer(m)]
    assert not wrong, f"imports against the layer order {LAYERS}: {wrong}"


def test_apps_are_imported_by_nothing():
    users = [(m, i) for m, deps in graph().items() for i in deps if i.endswith("__main__")]
    assert not users
    for path in [*ROOT.glob("physics/**/*.py"), *ROOT.glob("surrogate/*.py"),
                 *ROOT.glob("tests/**/*.py"), *ROOT.glob("bench/*.py")]:
        found = imports(path)
        assert "train" not in found, path
        assert not any(i.endswith("__main__") for i in found), path


def test_physics_never_imports_torch_or_the_surrogate():
    for name, path in modules().items():
        if name.startswith("physics"):
            bad = {i for i in imports(path) if i.split(".")[0] in ("torch", "lightning",
                                                                     "surrogate")}
            assert not bad, f"{name} imports {bad}"


def test_installed_packages_are_the_tree():
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(cfg["packages"])
    tree = {".".join(p.parent.relative_to(ROOT).parts) for pkg in ("physics", "surrogate")
            for p in (ROOT / pkg).rglob("__init__.py")}
    tree |= {".".join(("gearwear_conf", *p.parent.relative_to(ROOT / "conf").parts))
             for p in (ROOT / "conf").rglob("__init__.py")}
    assert listed == tree
    assert cfg["package-dir"] == {"gearwear_conf": "conf"}


def owner(path: Path) -> str:
    """The subpackage (or top-level module, or ``bench``/``tests``) a source file belongs to."""
    parts = path.relative_to(ROOT).with_suffix("").parts
    if parts[0] == "physics" and len(parts) > 2:
        return ".".join(parts[:2])
    return ".".join(parts) if parts[0] == "physics" else parts[0]


def module_owner(module: str) -> str:
    """The subpackage (or top-level module) an imported module name belongs to."""
    parts = module.split(".")
    return ".".join(parts[:2]) if parts[0] == "physics" and len(parts) > 1 else parts[0]


def top_level_names(path: Path) -> set[str]:
    """Names a module defines or imports at its top level."""
    names = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.FunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            for target in node.targets if isinstance(node, ast.Assign) else [node.target]:
                names |= {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}
        elif isinstance(node, ast.Import | ast.ImportFrom):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names}
    return names


@pytest.mark.parametrize("package", SUBPACKAGES)
def test_every_subpackage_names_its_public_surface(package):
    """``__all__`` lists names its modules define (read without importing them: the package
    imports its names on first use), none of them a submodule's name (which would hide it)."""
    mod = importlib.import_module(package)
    public = getattr(mod, "__all__", None)
    assert public, f"{package}/__init__.py names no public API (__all__)"
    folder = ROOT.joinpath(*package.split("."))
    modules = {p.stem: p for p in folder.rglob("*.py") if p.stem not in ("__init__", "__main__")}
    defined = set().union(*(top_level_names(p) for p in modules.values()))
    assert not set(public) - defined, f"{package}.__all__ names nothing: {set(public) - defined}"
    assert not set(public) & set(modules), f"{package}.__all__ hides submodules"
    assert not [n for n in public if n.startswith("_")]


def test_no_private_name_is_imported_across_subpackages():
    """A ``_name`` stays inside its subpackage: what siblings share is public (in ``__all__``).
    Tests may reach into the module they test."""
    wrong = []
    for path in [*ROOT.glob("physics/**/*.py"), *ROOT.glob("surrogate/*.py"),
                 *ROOT.glob("bench/*.py"), ROOT / "train.py"]:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                private = [a.name for a in node.names
                           if a.name.startswith("_") and not a.name.startswith("__")]
                if private and module_owner(node.module) != owner(path):
                    wrong.append((str(path.relative_to(ROOT)), node.module, private))
    assert not wrong, f"private names imported from another subpackage: {wrong}"


def test_the_product_does_not_import_the_test_rigs():
    users = {m for m, deps in graph().items() if not m.startswith("physics.testbeds")
             for i in deps if i.startswith("physics.testbeds")}
    assert users <= TESTBED_USERS, f"imports of physics.testbeds: {users - TESTBED_USERS}"


def loop_layer(module: str) -> int:
    """The place of a loop module's stage in :data:`LOOP_LAYERS`."""
    stage = module.split(".")[2]
    return next(k for k, names in enumerate(LOOP_LAYERS) if stage in names)


def test_the_loops_stages_import_only_downwards():
    """Records, then the model, the decisions, the search, the report, the orchestrators: a
    stage's modules import from their own stage or those before it, never after (the adoption
    rule decides, the report only writes)."""
    loop = {m: deps for m, deps in graph().items()
            if m.startswith("physics.loop.") and m.count(".") >= 2}
    wrong = [(m, d) for m, deps in loop.items() for d in deps
             if d.startswith("physics.loop.") and loop_layer(d) > loop_layer(m)]
    assert not wrong, wrong
    assert {m.split(".")[2] for m in loop} == {n for names in LOOP_LAYERS for n in names}


def test_the_loops_orchestrator_is_imported_only_by_its_app():
    """The loop's data flow one way: its modules feed ``run_loop`` (physics.loop.bundle_loop),
    none imports it back."""
    users = {m for m, deps in graph().items() if "physics.loop.bundle_loop" in deps}
    assert users <= {"physics.loop.__main__"}, users


def _at_start(roots: list[str]) -> dict[str, set[str]]:
    """What each project module that ``roots`` reach at module level (transitively) imports at
    module level."""
    known, out, todo = modules(), {}, list(roots)
    while todo:
        name = todo.pop()
        if name in out:
            continue
        found = out[name] = imports(known[name], at_import=True)
        parents = {".".join(i.split(".")[:k]) for i in found for k in range(1, i.count(".") + 1)}
        todo += [i for i in found | parents if i in known]
    return out


def _importing(roots: list[str], packages: tuple[str, ...]) -> dict[str, set[str]]:
    """The modules ``roots`` reach that import one of ``packages`` at module level."""
    return {m: bad for m, found in _at_start(roots).items()
            if (bad := {i for i in found if i.split(".")[0] in packages})}


def test_prediction_starts_without_lightning():
    """``surrogate.predict`` and ``Surrogate.load`` import torch, not Lightning (two seconds of
    every prediction's start): nothing they import at module level reaches it."""
    reached = _importing(["surrogate.predict", "surrogate.inference"],
                         ("lightning", "pytorch_lightning"))
    assert not reached, f"these import Lightning: {reached}"


def test_a_runs_data_is_checked_without_torch():
    """``surrogate.wear_data`` (the data a run reads, checked when made: ``train.py`` makes it
    before Lightning's import) reaches neither torch nor Lightning at module level."""
    reached = _importing(["surrogate.wear_data"], ("torch", "lightning", "pytorch_lightning"))
    assert not reached, f"these import torch or Lightning: {reached}"


#: the longest a page of docs/ and the README may be (a reference, not a notebook)
DOC_LINES, README_LINES = 450, 150


def test_docs_are_reference_pages_of_bounded_length_whose_links_resolve():
    """Every page of docs/ at most 450 lines and the README at most 150; every relative link
    of theirs names a file of the repository."""
    pages = sorted((ROOT / "docs").glob("*.md"))
    assert pages
    long = {p.name: n for p in pages if (n := len(p.read_text().splitlines())) > DOC_LINES}
    assert not long, f"docs pages above {DOC_LINES} lines: {long}"
    readme = ROOT / "README.md"
    assert len(readme.read_text().splitlines()) <= README_LINES
    broken = []
    for page in [readme, *pages]:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text()):
            if "://" not in target and not (page.parent / target).exists():
                broken.append(f"{page.name}: {target}")
    assert not broken, f"links to files that do not exist: {broken}"
