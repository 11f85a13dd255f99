"""The package's shape, checked from its source (issue 12's acceptance checks).

* Imports run one way: no import cycle between gfuzzy's modules, counting the lazy
  imports inside functions (only ``if TYPE_CHECKING:`` blocks, which never run, are left
  out).
* Planning never imports the learning subpackage (rule learning, tracking simulation).
* No module over ``MAX_MODULE_LINES`` lines and no function over ``MAX_FUNCTION_LINES``,
  without exceptions.
"""

from __future__ import annotations

import ast
import re
from functools import cache
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "gfuzzy"
MAX_MODULE_LINES = 800
MAX_FUNCTION_LINES = 100

def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


@cache
def _parsed(path: Path) -> tuple[str, ast.Module]:
    """A module's text and syntax tree, parsed once per process (the package's 30,000
    lines took 1.2 s of CPU to parse, and five tests read them)."""
    text = path.read_text(encoding="utf-8")
    return text, ast.parse(text)


def _imports(name: str, path: Path, known: set[str]) -> set[str]:
    """Modules of the package that ``name`` imports anywhere (lazy imports included)."""
    tree = _parsed(path)[1]
    is_pkg = path.name == "__init__.py"
    base = name.split(".") if is_pkg else name.split(".")[:-1]
    found: set[str] = set()

    def add(target: str) -> None:
        if target in known and target != name:
            found.add(target)

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(alias.name)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = base[: len(base) - (node.level - 1)]
                mod = ".".join(anchor + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            for alias in node.names:  # `from . import x` / `from .pkg import submodule`
                if f"{mod}.{alias.name}" in known:
                    add(f"{mod}.{alias.name}")
                else:
                    add(mod)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


def _graph() -> dict[str, set[str]]:
    """Each module of the package -> the package's modules it imports (a fresh copy of
    the graph, found once per process: four tests read it)."""
    return {name: set(deps) for name, deps in _found_graph().items()}


@cache
def _found_graph() -> dict[str, frozenset[str]]:
    mods = _modules()
    known = set(mods)
    # importing a submodule runs its packages' __init__ first; a package importing its own
    # submodules is not a cycle, so edges into a package's own __init__ are not followed
    graph = {}
    for name, path in mods.items():
        graph[name] = frozenset(t for t in _imports(name, path, known) if not name.startswith(t + "."))
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def strong(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            strong(v)
    return out


def test_the_import_graph_has_no_cycle():
    graph = _graph()
    assert "gfuzzy.planner.planner" in graph and "gfuzzy.planner.stages" in graph["gfuzzy.planner.planner"]  # lazy one seen
    assert _cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_planning_never_imports_learning():
    graph = _graph()
    learning = {m for m in graph if m == "gfuzzy.learning" or m.startswith("gfuzzy.learning.")}
    assert learning, "the learning subpackage moved?"
    offenders = {m: sorted(graph[m] & learning) for m in graph if m not in learning and graph[m] & learning}
    assert offenders == {}


def _sizes():
    """(module, module lines, [(function, lines) over the limit])."""
    for name, path in _modules().items():
        text, tree = _parsed(path)
        long = []
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    long.append((node.name, n))
        yield name, len(text.splitlines()), long


def test_no_module_or_function_is_too_long():
    over = {}
    for name, lines, long in _sizes():
        problems = ([f"{lines} lines"] if lines > MAX_MODULE_LINES else []) + [f"{f}(): {n} lines" for f, n in long]
        if problems:
            over[name] = problems
    assert over == {}


#: The packages in pipeline order (docs/architecture.md): a module imports only from its own
#: package and the packages before it. "base" is the flat modules of gfuzzy/.
LAYERS = (
    "base", "scene", "collision", "roadmap", "timespace", "ga", "fuzzy", "check", "planner",
    "runs", "navigation", "render", "export", "learning", "cli",
)
#: At most this many modules stay flat in gfuzzy/ (issue 20).
MAX_FLAT_MODULES = 10


def _layer(module: str) -> str:
    parts = module.split(".")
    return "base" if len(parts) == 1 or (PACKAGE / f"{parts[1]}.py").exists() else parts[1]


def test_packages_follow_the_pipeline_and_few_modules_stay_flat():
    flat = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(flat) <= MAX_FLAT_MODULES, flat
    packages = {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists()}
    assert packages == set(LAYERS) - {"base"}, packages ^ (set(LAYERS) - {"base"})
    order = {name: i for i, name in enumerate(LAYERS)}
    upward = sorted(
        f"{m} -> {d}"
        for m, deps in _graph().items()
        if m not in ("gfuzzy", "gfuzzy.__main__")  # the public API and the entry point: the top
        for d in deps
        if order[_layer(d)] > order[_layer(m)]
    )
    assert upward == []


def test_the_layer_rule_sees_an_upward_import():
    assert _layer("gfuzzy.timespace.unicycle") == "timespace" and _layer("gfuzzy.poses") == "base"
    order = {name: i for i, name in enumerate(LAYERS)}
    assert order[_layer("gfuzzy.planner.stages")] > order[_layer("gfuzzy.timespace.drive")]


def _documented_packages() -> list[tuple[str, list[str]]]:
    """docs/architecture.md's package table: (layer, modules in the order listed) per row."""
    doc = (PACKAGE.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    rows = []
    for line in doc.splitlines():
        cells = line.split("|")
        name = re.fullmatch(r" `([a-z_]+)/`.*", cells[1]) if len(cells) > 3 else None
        if name:
            layer = "base" if name[1] == "gfuzzy" else name[1]
            rows.append((layer, re.findall(r"`([a-z_]+)`", cells[2])))
    return rows


def test_the_architecture_table_lists_every_module_in_import_order():
    # it had lost eight modules (reach, softcost, soft_kernel, __main__, depth, exact, join,
    # passage) and put planner before check, which planner imports
    rows = _documented_packages()
    assert [layer for layer, _ in rows] == list(LAYERS)
    graph = _graph()
    for layer, listed in rows:
        prefix = "gfuzzy" if layer == "base" else f"gfuzzy.{layer}"
        here = {m[len(prefix) + 1 :] for m in graph if m != prefix and m.rsplit(".", 1)[0] == prefix}
        here -= set(LAYERS) if layer == "base" else set()  # the packages are rows of their own
        assert sorted(listed) == sorted(here), (layer, set(listed) ^ here)
        before: set[str] = set()
        for name in listed:
            later = {d for d in graph[f"{prefix}.{name}"] if d.rsplit(".", 1)[0] == prefix} - before
            assert name == "__main__" or not later, f"{prefix}.{name} imports {sorted(later)}, listed after it"
            before.add(f"{prefix}.{name}")
