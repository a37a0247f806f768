"""The package's import graph: no cycle, and no module imports a layer above its own.

What this checks: every ``import`` / ``from ... import`` statement of every
module under ``kilnctl/``, read with :mod:`ast` from the source, *including*
imports inside functions (a lazy import is still a dependency: it only moves
the failure to run time).  Imports under ``if TYPE_CHECKING:`` are left out:
they never run (annotations only).

What it does not see: a dependency that is passed in rather than imported.
There are two on purpose, both wired by the package root
(``kilnctl/__init__.py``): designed PID gains (``gains = "design"``) are
computed by :mod:`kilnctl.design`, which sits above the simulator, so the root
plugs :func:`kilnctl.design.gains_for` into :func:`kilnctl.gains.use_designer`
and the simulator asks :func:`kilnctl.gains.resolve_gains`; and the parameter
declarations (``kilnctl.params.SPECS``) are read from the components that
import ``params``, so the root hands ``params`` a loader of the component
registry (``kilnctl.params._registry_loader``).  The root is the composition root: its own
imports wire the layers and are exempt from the layer order (not from the cycle
check); imports *of* the root add no dependency, because Python runs the root
before any kilnctl module anyway.

The truth tested against is the source text itself (the graph is built from the
files, not from a hand list of edges); the layer table below is the design
decision being checked, and a new top-level module must be placed in it.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "kilnctl"

#: layers, lowest first: a module may import its own layer or a lower one.  ``figures`` is the shared figure
#: style (colours, fonts, writing a figure whole; it imports only errors and files), used by the ``.plot()``
#: methods of the analysis objects of every layer, so it sits at the bottom; ``assumptions`` renders docs.
#: ``structure`` resolves catalogue effects (measure/effects.py), so it sits with the measurement tools; the
#: simulator and the linearization below it take a Structure through its methods only.  ``__main__`` is
#: ``python -m kilnctl``, the command line's second entry point.
LAYERS = (
    ("errors", "units", "params", "gains", "files", "budget", "figures"),
    ("model",),
    ("response", "simulate"),
    ("linear", "linearize"),
    ("design", "verify", "optimize", "measure", "sweep", "structure"),
    ("report", "pages", "assumptions", "close_loop"),
    ("cli", "__main__", "demo", "demo_ramp"),
)
LAYER = {unit: i for i, names in enumerate(LAYERS) for unit in names}


def _modules() -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package __init__)."""
    mods = {}
    for f in sorted(ROOT.rglob("*.py")):
        parts = list(f.relative_to(ROOT.parent).with_suffix("").parts)
        is_pkg = parts[-1] == "__init__"
        mods[".".join(parts[:-1] if is_pkg else parts)] = (f, is_pkg)
    return mods


def _runtime_nodes(tree):
    """Every node of ``tree`` except those under ``if TYPE_CHECKING:``."""
    stack = [tree]
    while stack:
        node = stack.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and getattr(child.test, "id", getattr(child.test, "attr", "")) == "TYPE_CHECKING":
                stack.extend(child.orelse)
                continue
            stack.append(child)


def _targets(name, is_pkg, node, mods):
    """kilnctl modules an import node refers to (the module itself, or the package a name comes from)."""
    found = []
    if isinstance(node, ast.Import):
        found = [a.name for a in node.names]
    elif isinstance(node, ast.ImportFrom):
        if node.level:
            base = name.split(".") if is_pkg else name.split(".")[:-1]
            base = base[:len(base) - (node.level - 1)]
            mod = ".".join(base + ([node.module] if node.module else []))
        else:
            mod = node.module or ""
        found = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in mods else mod for a in node.names]
    out = set()
    for t in found:
        if t.split(".")[0] != "kilnctl":
            continue
        while t not in mods and "." in t:
            t = t.rsplit(".", 1)[0]
        out.add(t)
    return out


def import_graph() -> dict[str, set[str]]:
    """Module -> kilnctl modules it imports anywhere (top level or inside functions)."""
    mods = _modules()
    graph = {}
    for name, (f, is_pkg) in mods.items():
        tree = ast.parse(f.read_text(encoding="utf-8"), filename=str(f))
        edges = set()
        for node in _runtime_nodes(tree):
            edges |= _targets(name, is_pkg, node, mods)
        graph[name] = edges - {name, "kilnctl"}  # the root runs first whoever imports it: no dependency
    return graph


def _cycles(graph):
    """Strongly connected components with more than one node (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
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
            visit(v)
    return out


def _unit(module):
    """Top-level module or package a module belongs to (``kilnctl.design.pid`` -> ``design``)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "kilnctl"


def test_the_graph_sees_lazy_imports():
    # hand-checked in the source: sweep/study.py imports the engine inside Study.run(), and
    # optimize/model.py imports the problem only under TYPE_CHECKING
    g = import_graph()
    assert "kilnctl.sweep.engine" in g["kilnctl.sweep.study"]
    assert "kilnctl.optimize.problem" not in g["kilnctl.optimize.model"]
    assert {"kilnctl.errors", "kilnctl.params"} <= g["kilnctl.gains"] | {"kilnctl.errors"}


def test_no_cycle_between_modules():
    assert _cycles(import_graph()) == []


def test_no_cycle_between_packages():
    g = import_graph()
    units = {}
    for a, targets in g.items():
        units.setdefault(_unit(a), set()).update(_unit(b) for b in targets if _unit(b) != _unit(a))
    assert _cycles(units) == []


def test_every_module_has_a_layer():
    missing = sorted({_unit(m) for m in _modules()} - set(LAYER) - {"kilnctl"})
    assert missing == [], f"place these in LAYERS of tests/test_imports.py: {missing}"


def test_no_upward_import():
    upward = []
    for a, targets in sorted(import_graph().items()):
        if a == "kilnctl":
            continue  # the composition root (see the module docstring)
        for b in sorted(targets):
            if LAYER[_unit(b)] > LAYER[_unit(a)]:
                upward.append(f"{a} -> {b}")
    assert upward == []


def test_simulate_does_not_import_the_design():
    # the two named arrows (design <- simulate, design <- linear), checked by name
    g = import_graph()
    for low in ("kilnctl.simulate", "kilnctl.linear", "kilnctl.linearize"):
        assert not any(t.startswith("kilnctl.design") for t in g[low]), low
