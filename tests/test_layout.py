"""The wings of navcore and orchestrator: every module in a wing, imports running one way.

Read from the source (the AST, function-level imports included), not by importing: a late
import inside a function counts like one at the top.  The order is the one the README's
layout section and each wing's docstring state.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"navcore": ROOT / "fmus" / "navcore", "orchestrator": ROOT / "orchestrator"}
# lowest first; a wing may import the wings before it, never one after it
WING_ORDER = {
    "navcore": ["core", "ins", "sensors", "filters", "vehicles", "components"],
    "orchestrator": ["results", "building", "model", "cosim", "running", "campaigns",
                     "reporting", "verification", "packaging", "cli"],
}
# the only modules outside a wing: the package face and the one error module
OUTSIDE = {"__init__", "errors"}


def _modules():
    """(dotted name, path, is package) of every module of both packages."""
    for pkg, folder in PACKAGES.items():
        for path in sorted(folder.rglob("*.py")):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            is_pkg = parts[-1] == "__init__"
            if is_pkg:
                parts = parts[:-1]
            yield ".".join([pkg, *parts]), path, is_pkg


MODULES = {name: (path, is_pkg) for name, path, is_pkg in _modules()}


def _imported(name: str, path: Path, is_pkg: bool):
    """The navcore/orchestrator modules ``name`` imports (absolute dotted names)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_pkg else name.split(".")[:-1]
                base = base[:len(base) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            subs = [f"{module}.{a.name}" for a in node.names]
            targets = [t for t in subs if t in MODULES] or [module]
        else:
            continue
        for target in targets:
            while target and target not in MODULES:
                target = target.rpartition(".")[0]
            if target and target.split(".")[0] in PACKAGES and target != name:
                found.add(target)
    return found


def _wing(name: str):
    parts = name.split(".")
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and MODULES[name][1]) else None


def _rank(name: str):
    pkg = name.split(".")[0]
    wing = _wing(name)
    return -1 if wing is None else WING_ORDER[pkg].index(wing)


def test_every_module_is_in_a_known_wing():
    loose = []
    for name, (path, is_pkg) in MODULES.items():
        parts = name.split(".")
        if len(parts) == 1:
            continue
        if len(parts) == 2 and not is_pkg:
            if parts[1] not in OUTSIDE:
                loose.append(name)
        elif parts[1] not in WING_ORDER[parts[0]]:
            loose.append(name)
    assert loose == []


def back_imports():
    """(importer, imported) pairs where a lower wing imports a higher one (or the package
    face or error module imports a wing, except the faces' lazy exports)."""
    bad = []
    for name, (path, is_pkg) in MODULES.items():
        for target in _imported(name, path, is_pkg):
            if target.split(".")[0] != name.split(".")[0]:
                if name.startswith("navcore"):  # navcore never imports the master
                    bad.append((name, target))
                continue
            if _rank(target) > _rank(name) and not (is_pkg and _wing(name) == _wing(target)):
                bad.append((name, target))
    return bad


def test_no_import_runs_from_a_lower_wing_to_a_higher_one():
    assert back_imports() == []


def test_no_import_cycle_between_modules():
    graph = {name: _imported(name, *MODULES[name]) for name in MODULES}
    state = {}
    cycles = []

    def visit(node, stack):
        state[node] = "open"
        for nxt in sorted(graph[node]):
            if state.get(nxt) == "open":
                cycles.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = "done"

    for name in sorted(graph):
        if name not in state:
            visit(name, [name])
    assert cycles == []


@pytest.mark.parametrize("pkg", sorted(WING_ORDER))
def test_each_wing_docstring_states_its_place(pkg):
    for wing in WING_ORDER[pkg]:
        doc = ast.get_docstring(ast.parse((PACKAGES[pkg] / wing / "__init__.py").read_text()))
        assert doc and "Wing order" in doc, f"{pkg}.{wing}"


def test_the_check_sees_a_back_import(tmp_path, monkeypatch):
    """The checker itself: a made-up module of the lowest wing importing the highest."""
    fake = tmp_path / "fake.py"
    fake.write_text("def f():\n    from ..cli import commands\n")
    monkeypatch.setitem(MODULES, "orchestrator.results.fake", (fake, False))
    assert ("orchestrator.results.fake", "orchestrator.cli.commands") in back_imports()


def test_no_source_line_is_longer_than_100_characters():
    roots = [ROOT / "orchestrator", ROOT / "fmus", ROOT / "tests", ROOT / "benchmarks"]
    long = [f"{path.relative_to(ROOT)}:{i}"
            for root in roots for path in sorted(root.rglob("*.py"))
            if "dist" not in path.relative_to(ROOT).parts
            for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
            if len(line) > 100]
    assert long == []
