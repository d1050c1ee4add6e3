"""The house: import graph without cycles, layers in their order, apps imported by nothing,
physics/ free of torch, and the installed package list in step with the tree."""

from __future__ import annotations

import ast
import tomllib
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: physics layers, each importing only from those before it (README, Architecture)
LAYERS = ["params", "files", "command", "gear", "scope", "tribology", "dynamics", "signals",
          "estimators", "dataset", "reproduce", "loop"]


def modules() -> dict[str, Path]:
    out = {}
    for pkg in ("physics", "surrogate"):
        for path in (ROOT / pkg).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = path
    return out


def imports(path: Path) -> set[str]:
    """Modules ``path`` imports (absolute names; ``from a import b`` gives a.b if that is a
    module, else a)."""
    known = modules()
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            subs = {f"{node.module}.{a.name}" for a in node.names}
            found |= (subs & set(known)) or {node.module}
    return found


def graph() -> dict[str, set[str]]:
    known = modules()
    return {m: {i for i in imports(p) if i in known} for m, p in known.items()}


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
        assert "train" not in imports(path), path
        assert not any(i.endswith("__main__") for i in imports(path)), path


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
