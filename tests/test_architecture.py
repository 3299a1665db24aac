"""The package's shape: imports point down only, no cycles, one concept per module.

Every import of every module under ``hybridtable/`` is read with ``ast``
(function-level and ``TYPE_CHECKING`` imports included) and checked against the
layers of ``docs/architecture.md``::

    cli -> commands -> reports -> (analysis, diagnosis, studies)
        -> (measurement, stewart) -> loop -> compensators -> (systems, laws)
        -> (errors, _validation, limits, _components, data)

A module may import its own layer or any layer below, never one above, and no
two modules nor two first-level packages may import each other, directly or
around a longer circle. ``importlib`` loads none of our own modules but the
lazy re-exports of the package ``__init__`` files (:mod:`hybridtable._lazy`),
whose arrows this test reads from their ``lazy_exports`` call, so no arrow
hides from it. The top-level ``hybridtable/__init__.py`` is
the users' facade: it may import anything, and nothing inside imports it.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "hybridtable"

#: First-level subpackage or module -> layer (higher imports lower).
LAYERS: dict[str, int] = {
    "errors": 0,
    "_lazy": 0,
    "_plugins": 0,
    "_validation": 0,
    "_files": 0,
    "_components": 0,
    "_nested": 0,
    "limits": 0,
    "data": 0,
    "laws": 1,
    "systems": 1,
    "compensators": 2,
    "loop": 3,
    "measurement": 4,
    "stewart": 4,
    "analysis": 5,
    "diagnosis": 5,
    "effects": 5,
    "studies": 5,
    "six_dof": 5,
    "explain": 5,
    "sweeps": 6,
    "reports": 7,
    "commands": 8,
    "cli": 9,
}

#: Longest module without a reason written at its top.
MAX_LINES = 500
#: How a longer module says why it stays whole (in its docstring).
LONG_MODULE_REASON = "Why one module:"


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _is_lazy_exports(node: ast.AST) -> bool:
    return (
        isinstance(node, ast.Call)
        and getattr(node.func, "id", "") == "lazy_exports"
        and len(node.args) == 2
        and isinstance(node.args[1], ast.Dict)
    )


def _imports(name: str, path: Path) -> set[str]:
    """Modules of the package that ``name`` imports (anywhere in its body)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            candidates = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            # Each imported name: a submodule if it is one, else a name of ``module``.
            candidates = [
                f"{module}.{a.name}" if f"{module}.{a.name}" in MODULES else module
                for a in node.names
            ]
        elif _is_lazy_exports(node):
            # ``lazy_exports(__name__, {"child": (...)})``: the package's arrows to its children
            found |= {f"{name}.{k.value}" for k in node.args[1].keys}
            continue
        else:
            continue
        for c in candidates:
            while c and c not in MODULES:
                c = c.rpartition(".")[0]
            if c and c != name:
                found.add(c)
    return found


GRAPH = {m: _imports(m, p) for m, p in MODULES.items()}


def _room(module: str) -> str:
    """The first-level subpackage or module: ``hybridtable.loop.builder`` -> ``loop``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _design_edges() -> dict[str, set[str]]:
    """Edges of the design: a package's ``__init__`` re-exporting its own
    children is not an arrow between concepts, and the facade is left out."""
    return {
        m: {d for d in deps if not d.startswith(m + ".")}
        for m, deps in GRAPH.items()
        if m != "hybridtable"
    }


def test_every_room_has_a_layer():
    rooms = {_room(m) for m in MODULES if m != "hybridtable"}
    assert rooms <= set(LAYERS), f"give these a layer in LAYERS: {sorted(rooms - set(LAYERS))}"


def test_no_module_imports_another_that_imports_it_back():
    assert _cycles(_design_edges()) == []


def test_no_cycle_between_first_level_packages():
    rooms: dict[str, set[str]] = {}
    for m, deps in _design_edges().items():
        for d in deps:
            if _room(m) != _room(d):
                rooms.setdefault(_room(m), set()).add(_room(d))
    assert _cycles(rooms) == []


def test_no_module_imports_its_own_package():
    # A package's __init__ imports its children; a child importing the package
    # back (``from hybridtable.diagnosis import X`` inside diagnosis/fit.py) closes
    # a circle that the design edges, which drop parent -> child, would not show.
    back = [
        f"{m} imports its package {d}"
        for m, deps in GRAPH.items()
        for d in deps
        if m.startswith(d + ".")
    ]
    assert back == []


def test_imports_point_down_only():
    upward = [
        f"{m} (layer {LAYERS[_room(m)]}) imports {d} (layer {LAYERS[_room(d)]})"
        for m, deps in _design_edges().items()
        for d in sorted(deps)
        if d == "hybridtable" or LAYERS[_room(d)] > LAYERS[_room(m)]
    ]
    assert upward == []


def test_the_core_loop_imports_no_plugin_and_no_command():
    core = [m for m in MODULES if _room(m) in ("systems", "loop")]
    core.append("hybridtable.compensators.paper")
    allowed = {"hybridtable.compensators", "hybridtable.compensators.paper"}
    allowed.add("hybridtable.compensators.registry")
    reach = [
        f"{m} -> {d}"
        for m in core
        for d in GRAPH[m]
        if (_room(d) == "compensators" and d not in allowed)
        or (m == "hybridtable.compensators.paper" and d != m and _room(d) == "compensators")
    ]
    assert reach == []


#: Modules that import a *user's* module by name: ``--plugin MODULE:ATTR``.
USER_MODULE_LOADERS = {"hybridtable.effects.registry"}


def test_no_hidden_imports_of_our_own_modules():
    # Only the lazy re-exports of package __init__ files import by name, and this
    # test reads their arrows from the ``lazy_exports`` call; the plug-in
    # loader imports the user's module that --plugin names, never one of ours.
    hidden = []
    for m, path in MODULES.items():
        if m == "hybridtable._lazy" or m in USER_MODULE_LOADERS:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call):
                f = node.func
                name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
                if name in ("import_module", "__import__"):
                    hidden.append(f"{m}:{node.lineno}")
    assert hidden == []


@pytest.mark.parametrize("module", sorted(MODULES))
def test_every_module_names_its_public_api(module):
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    assert ast.get_docstring(tree), f"{module} has no docstring"
    names = [
        n.id
        for node in tree.body
        if isinstance(node, ast.Assign | ast.AnnAssign)
        for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
        for n in (t.elts if isinstance(t, ast.Tuple) else [t])
        if isinstance(n, ast.Name)
    ]
    if MODULES[module].name != "__init__.py" or module.count(".") >= 1:
        assert "__all__" in names, f"{module} has no __all__"


@pytest.mark.parametrize("module", sorted(MODULES))
def test_module_size_or_a_reason_at_its_top(module):
    text = MODULES[module].read_text(encoding="utf-8")
    lines = text.count("\n")
    if lines > MAX_LINES:
        doc = ast.get_docstring(ast.parse(text)) or ""
        assert LONG_MODULE_REASON in doc, (
            f"{module} has {lines} lines: split it by concept, or say why it stays whole "
            f"in its docstring ('{LONG_MODULE_REASON} ...')"
        )


def test_this_test_sees_a_cycle_an_upward_import_and_a_function_level_import(tmp_path):
    """The graph reader itself: a planted function-level import is an edge, and
    so is a lazy re-export."""
    a = tmp_path / "a.py"
    a.write_text("def f():\n    from hybridtable.cli import main\n    return main\n")
    edges = _imports("hybridtable.loop.fake", a)
    assert edges == {"hybridtable.cli"}
    b = tmp_path / "b.py"
    b.write_text(
        "import hybridtable.errors, hybridtable.cli\nfrom hybridtable.commands import compare, margins\n"
    )
    assert _imports("hybridtable.systems.fake", b) == {
        "hybridtable.errors",
        "hybridtable.cli",
        "hybridtable.commands.compare",
        "hybridtable.commands.margins",
    }
    init = tmp_path / "__init__.py"
    init.write_text('x = lazy_exports(__name__, {"builder": ("a",), "params": ("b",)})\n')
    assert _imports("hybridtable.loop", init) == {
        "hybridtable.loop.builder",
        "hybridtable.loop.params",
    }
    assert LAYERS[_room("hybridtable.cli")] > LAYERS[_room("hybridtable.loop.fake")]
    assert _cycles({"x": {"y"}, "y": {"z"}, "z": {"x"}}) == [["x", "y", "z"]]


@pytest.mark.slow
def test_every_test_measured_slow_still_exists():
    """tests/slow_tests.txt names tests by node id: a renamed or removed test
    must leave the list too (else make check would run it again unmarked)."""
    import subprocess
    import sys

    from tests.conftest import MEASURED_SLOW

    files = sorted({node.split("::", 1)[0] for node in MEASURED_SLOW})
    missing = [f for f in files if not (PACKAGE.parent / f).is_file()]
    assert not missing, f"tests/slow_tests.txt names test files that do not exist: {missing}"
    collected = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "--collect-only",
            "-q",
            "-m",
            "",
            "-p",
            "no:cacheprovider",
            *files,  # only the files it names: collecting every test costs 15 s
        ],
        cwd=PACKAGE.parent,
        capture_output=True,
        text=True,
        timeout=600,
    ).stdout.splitlines()
    stale = sorted(MEASURED_SLOW - set(collected))
    assert not stale, f"tests/slow_tests.txt names tests that do not exist: {stale}"
