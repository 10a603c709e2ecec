"""The import graph runs one way: the physics at the bottom, the add-on above it, Blender above that.

The graph is read from the source with :mod:`ast` (every import statement, those inside functions
included), never by importing: a lazy import is an edge like any other.  Three properties:

* no module of ``precompute`` names ``clothlight`` or a Blender module;
* no import circle between modules;
* no module imports from a layer above its own (:data:`LAYERS`, the layers docs/architecture.md
  draws), and every package of the project is named in docs/architecture.md.
"""

from __future__ import annotations

import re

import pytest

from tests.helpers import BLENDER_ONLY, REPO
from tests.test_bpy_boundary import imported_modules, module_name

ROOTS = ("precompute", "clothlight")
#: The layers, bottom first: each a name and the module prefixes in it (a module belongs to the layer
#: of its longest matching prefix).  A module may import from its own layer and those below.
LAYERS = (
    ("common ground: errors, exit codes, bounds, caches, the execution layer",
     ("precompute", "precompute.errors", "precompute.exit_codes", "precompute.outputs", "precompute.bounds",
      "precompute.cache", "precompute.distributed")),
    ("medium optics", ("precompute.optics",)),
    ("table format, slab layout", ("precompute.tables", "precompute.slab")),
    ("Monte-Carlo transport", ("precompute.transport",)),
    ("bake", ("precompute.bake",)),
    ("fit's optimiser, brute-force reference", ("precompute.fit", "precompute.reference")),
    ("physics command line", ("precompute.cli", "precompute.__main__")),
    ("add-on without Blender", ("clothlight",)),
    ("add-on in Blender", ("clothlight.blender",)),
    ("jobs that render: the fit, the command lines of the sweep and the garment, the cloth bake's worker",
     ("clothlight.fit", "clothlight.validate", "clothlight.garment.__main__", "clothlight.cloth_bake_worker")),
)


def project_modules() -> dict[str, object]:
    """Every module of the project by name, with its path."""
    return {module_name(path): path for root in ROOTS for path in sorted((REPO / root).rglob("*.py"))}


def layer_of(module: str, layers=LAYERS) -> int:
    """Index of the layer of ``module``: that of its longest matching prefix."""
    best, best_length = None, -1
    for index, (_, prefixes) in enumerate(layers):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best_length:
                best, best_length = index, len(prefix)
    if best is None:
        raise KeyError(f"{module} is in no layer")
    return best


def import_graph(modules: dict) -> dict[str, set[str]]:
    """module → the project modules it imports (a name resolves to the longest module it starts with;
    a module's own packages, which Python runs before it, are no edge)."""

    def resolve(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for module, path in modules.items():
        targets = set()
        for name, _ in imported_modules(path, module):
            target = resolve(name)
            if target is not None and target != module and not module.startswith(target + "."):
                targets.add(target)
        graph[module] = targets
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(graph.get(node, ())):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def upward_imports(graph: dict[str, set[str]], layers=LAYERS) -> list[tuple[str, str]]:
    return sorted((module, target) for module, targets in graph.items() for target in targets
                  if layer_of(target, layers) > layer_of(module, layers))


@pytest.fixture(scope="module")
def graph():
    return import_graph(project_modules())


def test_precompute_names_neither_the_add_on_nor_blender():
    offenders = [(module, name) for module, path in project_modules().items() if module.startswith("precompute")
                 for name, _ in imported_modules(path, module)
                 if name.partition(".")[0] in ("clothlight", *BLENDER_ONLY)]
    assert offenders == []


def test_there_is_no_import_circle(graph):
    assert circles(graph) == []


def test_no_module_imports_from_a_layer_above_its_own(graph):
    assert upward_imports(graph) == []


def test_the_checks_find_a_circle_and_an_upward_import():
    graph = {"precompute.bake": {"precompute.optics.medium"}, "precompute.optics.medium": {"precompute.bake"},
             "clothlight.blender.ui": {"clothlight.fit.run"}, "clothlight.fit.run": set()}
    assert circles(graph) == [["precompute.bake", "precompute.optics.medium"]]
    assert upward_imports(graph) == [("clothlight.blender.ui", "clothlight.fit.run"),
                                     ("precompute.optics.medium", "precompute.bake")]
    assert layer_of("clothlight.garment.__main__") > layer_of("clothlight.blender.garment.measure")
    assert layer_of("clothlight.garment.tables") < layer_of("clothlight.blender.garment.measure")


def test_the_graph_sees_lazy_and_relative_imports(graph):
    # the fit's forward model renders the cloth response only on a cache miss: a lazy import, still an edge
    assert "clothlight.blender.validation.response_render" in graph["clothlight.fit.forward"]
    assert "precompute.transport._kernels" in graph["precompute.transport.cylinder"]
    assert "clothlight.medium_settings" in graph["clothlight.blender.properties"]


def test_every_package_is_named_in_the_architecture_page():
    """By its path from the repository's root (``precompute/optics/``), so that a new package, or a
    moved one, shows where the page is out of date."""
    text = (REPO / "docs" / "architecture.md").read_text(encoding="utf-8")
    packages = sorted(path.parent.relative_to(REPO).as_posix() + "/" for root in ROOTS
                      for path in (REPO / root).rglob("__init__.py"))
    missing = [package for package in packages if not re.search(r"(?<![\w/])" + re.escape(package), text)]
    assert missing == []
