"""The layering docs/architecture.md describes holds: modules import only sideways or downwards.

The layers, top to bottom, are listed once here and in the document's diagram; a new package
(``keyshape/``, ``proxy3d/``, ``scene/``, ``web/``) must be given a place in both before it can be imported.
"""

import ast
from pathlib import Path

import toonmotion

PACKAGE = Path(toonmotion.__file__).parent

# Top to bottom. Each set is one layer; a module may import its own layer and any below it.
LAYERS = (
    {"cli", "web"},
    {"batch"},
    {"api"},
    {"io", "render", "testing", "samples", "sample_animation", "sample_cartoons"},
    {"scene"},
    {"capture", "keyshape", "proxy3d"},
    {"animate"},
    {"deform"},
    {"rig"},
    {"shape"},
    {"geometry"},
    {"errors", "progress", "limits"},
)


def _layer(name):
    found = [i for i, names in enumerate(LAYERS) if name in names]
    return found[0] if found else None


def _imports(path):
    """``(line, first package below toonmotion)`` of every toonmotion import in a module."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            parts = node.module.split(".")
            if parts[0] != "toonmotion":
                continue
            if len(parts) > 1:
                yield node.lineno, parts[1]
            else:  # `from toonmotion import api` names a module; `__version__` is the package's
                yield from ((node.lineno, a.name) for a in node.names if _layer(a.name) is not None)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "toonmotion" and len(parts) > 1:
                    yield node.lineno, parts[1]


def test_every_module_belongs_to_a_layer():
    tops = {p.relative_to(PACKAGE).with_suffix("").parts[0] for p in PACKAGE.rglob("*.py")}
    assert {t for t in tops - {"__init__"} if _layer(t) is None} == set()


def test_no_module_imports_a_layer_above_its_own():
    upward = []
    for path in sorted(PACKAGE.rglob("*.py")):
        top = path.relative_to(PACKAGE).with_suffix("").parts[0]
        if top == "__init__":  # the package re-exports the API lazily
            continue
        for line, name in _imports(path):
            if _layer(name) is None or _layer(name) < _layer(top):
                upward.append(f"{path.relative_to(PACKAGE)}:{line} imports toonmotion.{name}")
    assert upward == []


def test_library_code_never_prints():
    """Only the CLI writes to the terminal; the library reports through progress callbacks."""
    printing = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.relative_to(PACKAGE).parts[0] == "cli":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "print":
                printing.append(f"{path.relative_to(PACKAGE)}:{node.lineno}")
    assert printing == []


def _dotted(path):
    """A module's dotted name (a package's is its folder's)."""
    parts = path.relative_to(PACKAGE).with_suffix("").parts
    return ".".join(("toonmotion", *parts)).removesuffix(".__init__")


def _module_imports(path):
    """Every toonmotion module ``path`` imports, by its dotted name (a name imported from a package
    that is itself a module counts as that module), wherever the import stands: at the top, in a
    function or under ``TYPE_CHECKING``."""
    modules = {_dotted(p) for p in PACKAGE.rglob("*.py")}
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] != "toonmotion":
                continue
            named = [f"{node.module}.{a.name}" for a in node.names if f"{node.module}.{a.name}" in modules]
            yield from named or ([node.module] if node.module in modules else [])
        elif isinstance(node, ast.Import):
            yield from (a.name for a in node.names if a.name in modules)


def test_no_import_cycle():
    """No module imports, even only for type checking, one that imports it back (directly or round
    a loop): each idea sits below what uses it. A package's __init__ re-exporting its modules is
    not a loop."""
    graph = {}
    for path in PACKAGE.rglob("*.py"):
        name = _dotted(path)
        if path.name != "__init__.py":
            graph[name] = {m for m in _module_imports(path) if not name.startswith(m + ".")}
    cycles, state = [], {}

    def visit(node, trail):  # depth first: an edge back to a module still open closes a loop
        state[node] = "open"
        for nxt in sorted(graph[node] & graph.keys()):
            if state.get(nxt) == "open":
                cycles.append(" -> ".join([*trail[trail.index(nxt):], nxt]))
            elif nxt not in state:
                visit(nxt, [*trail, nxt])
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])
    assert cycles == []
