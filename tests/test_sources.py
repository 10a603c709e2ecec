"""Cache keys digest the code that really made an entry: each stage's entry modules, every project
module they import (transitively) and the OSL shaders they compile (precompute/cache/sources.py)."""

import ast
import shutil

import pytest

from precompute import bake as bake_module
from precompute.cache import entries as cache
from precompute.cache.sources import _absolute, imported_names, module_file, python_sources, stage_digest, stage_sources

REPO = bake_module.PROJECT_ROOT
#: The hand-typed lists the stages had before their sources were derived: each missed code.
OLD_TABLE_SOURCES = {"precompute/tables/color.py", "precompute/tables/exr.py", "precompute/tables/layout.py",
                     "precompute/tables/closure_fit.py", "precompute/bake.py"}
OLD_MEASUREMENT_SOURCES = {
    "clothlight/garment/goniometry.py", "clothlight/blender/garment/measure.py",
    "clothlight/blender/materials.py", "clothlight/blender/measurement_render.py", "clothlight/weave/geometry.py",
    "osl/cloth_yarn.osl", "osl/clothlight.h",
}
#: Files no stage of the yarn bake runs: editing them must not cost a bake.
NOT_IN_THE_BAKE = ("precompute/tables/plots.py", "precompute/cli/bake.py", "precompute/__main__.py",
                   "clothlight/blender/ui.py", "osl/cloth_garment.osl")


@pytest.fixture
def tree(tmp_path):
    """A copy of the project's packages and shaders, to edit."""
    for name in ("clothlight", "precompute", "osl"):
        shutil.copytree(REPO / name, tmp_path / name, ignore=shutil.ignore_patterns("__pycache__"))
    return tmp_path


@pytest.fixture
def bake_keys(tree, monkeypatch):
    """The yarn bake's two cache keys, for the default red cotton, of the code in ``tree``."""
    monkeypatch.setattr(bake_module, "PROJECT_ROOT", tree)
    configuration = bake_module.bake_configuration("paper_2008")

    def keys() -> dict:
        spectral = cache.cache_key(bake_module.spectral_inputs(configuration))
        return {"spectral": spectral, "tables": cache.cache_key(bake_module.table_inputs(spectral, configuration))}

    return keys


def modules_called_from(relative: str, functions) -> set[str]:
    """The project modules whose names ``functions`` of file ``relative`` use (and the functions of
    that file they call, transitively): what a stage that runs them without the file's other imports
    must hold."""
    tree = ast.parse((REPO / relative).read_text())
    package = relative.removesuffix(".py").replace("/", ".").rpartition(".")[0]
    imported = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            target = _absolute(node.module, node.level, package)
            for alias in node.names:
                member = f"{target}.{alias.name}"
                imported[alias.asname or alias.name] = member if module_file(REPO, member) else target
        elif isinstance(node, ast.Import):
            imported.update({alias.asname or alias.name.partition(".")[0]: alias.name for alias in node.names})
    # The functions asked for may be nested (their bodies are walked whole); calls are followed to the
    # file's top-level functions.
    nested = [node for node in ast.walk(tree) if isinstance(node, ast.FunctionDef) and node.name in functions]
    assert sorted(node.name for node in nested) == sorted(functions), "each function named once in the file"
    top_level = {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}
    pending, seen, modules = nested, set(), set()
    while pending:
        function = pending.pop()
        if function in seen:
            continue
        seen.add(function)
        for node in ast.walk(function):
            if isinstance(node, ast.Name) and node.id in imported:
                modules.add(imported[node.id])
            elif isinstance(node, ast.Name) and node.id in top_level:
                pending.append(top_level[node.id])
    return {module for module in modules if module_file(REPO, module) is not None}


def _touch(path):
    path.write_bytes(path.read_bytes() + b"\n# edited\n" if path.suffix == ".py" else path.read_bytes() + b"\n")


def test_the_table_stage_covers_the_closure_twins_the_old_list_missed():
    table = set(stage_sources(REPO, **bake_module.TABLE_SOURCES))
    assert "precompute/tables/cycles_closures.py" in table  # closure_fit.py imports it to fit lobes.exr
    assert "precompute/tables/cycles_closures.py" not in OLD_TABLE_SOURCES
    assert OLD_TABLE_SOURCES < table


def test_the_spectral_stage_is_the_physics_without_the_colour_and_the_fit():
    spectral = set(stage_sources(REPO, **bake_module.SPECTRAL_SOURCES))
    assert {"precompute/optics/coefficients.py", "precompute/optics/mie.py", "precompute/optics/dye.py",
            "precompute/optics/phase.py",
            "precompute/tables/grids.py", "precompute/transport/_kernels.py", "precompute/bake.py"} <= spectral
    assert not {"precompute/tables/color.py", "precompute/tables/closure_fit.py", "precompute/tables/exr.py"} & spectral


def test_what_the_spectral_stage_runs_of_bake_py_comes_from_the_spectral_modules():
    spectral = set(stage_sources(REPO, **bake_module.SPECTRAL_SOURCES))
    used = modules_called_from("precompute/bake.py", ["_simulate", "_simulate_series", "_reweighted_spectral"])
    assert {"precompute.optics.coefficients", "precompute.transport", "precompute.transport.absorption"} <= used
    assert {module_file(REPO, m).relative_to(REPO).as_posix() for m in used} <= spectral


def test_every_file_of_a_stage_changes_its_key(tree, bake_keys):
    before = bake_keys()
    for definition in (bake_module.SPECTRAL_SOURCES, bake_module.TABLE_SOURCES):
        digest = stage_digest(tree, **definition)  # what the stage's key holds of its code
        for relative in stage_sources(tree, **definition):
            original = (tree / relative).read_bytes()
            _touch(tree / relative)
            assert stage_digest(tree, **definition) != digest, relative
            (tree / relative).write_bytes(original)
    assert bake_keys() == before
    # The keys themselves: the closure twins are the tables' code, the transport the simulation's too.
    _touch(tree / "precompute" / "tables" / "cycles_closures.py")
    twins = bake_keys()
    assert twins["spectral"] == before["spectral"] and twins["tables"] != before["tables"]
    _touch(tree / "precompute" / "transport" / "__init__.py")
    assert bake_keys()["spectral"] != twins["spectral"] and bake_keys()["tables"] != twins["tables"]


def test_files_no_stage_imports_leave_the_keys_alone(tree, bake_keys):
    before = bake_keys()
    for relative in NOT_IN_THE_BAKE:
        _touch(tree / relative)
    (tree / "precompute" / "unused_new_module.py").write_text("import numpy\n")
    assert bake_keys() == before


def test_a_new_module_joins_the_key_of_the_stage_that_imports_it(tree, bake_keys):
    before = bake_keys()
    (tree / "precompute" / "ballistic_twin.py").write_text("SPEED = 1.0\n")
    assert bake_keys() == before  # not imported yet
    beam = tree / "precompute" / "transport" / "beam.py"
    beam.write_text(beam.read_text() + "\nfrom precompute import ballistic_twin  # noqa: E402,F401\n")
    assert "precompute/ballistic_twin.py" in stage_sources(tree, **bake_module.SPECTRAL_SOURCES)
    edited = bake_keys()
    assert edited["spectral"] != before["spectral"]
    (tree / "precompute" / "ballistic_twin.py").write_text("SPEED = 2.0\n")
    assert bake_keys()["spectral"] != edited["spectral"]


def test_imports_are_read_as_python_resolves_them():
    source = "\n".join([
        "import numpy as np",
        "from . import sibling, CONSTANT",
        "from ..weave import params",
        "from .pkg.sub import name",
        "def lazy():",
        "    import clothlight.validation.rig",
        "    from precompute.tables import grids",
        "    return grids, importlib.import_module('precompute.tables.color')",
    ])
    names = imported_names(source, "clothlight.garment.bake", is_package=False)
    assert {"numpy", "clothlight.garment", "clothlight.garment.sibling", "clothlight.weave",
            "clothlight.weave.params", "clothlight.garment.pkg.sub", "clothlight.validation.rig",
            "precompute.tables.grids", "precompute.tables.color"} <= names
    assert "precompute.transport" in imported_names("from . import transport", "precompute", is_package=True)
    assert module_file(REPO, "numpy") is None and module_file(REPO, "precompute.bake.CONSTANT") is None
    assert module_file(REPO, "precompute.transport").name == "__init__.py"
    files = {path.relative_to(REPO).as_posix() for path in python_sources(REPO, ["precompute.transport.beam"])}
    assert {"precompute/__init__.py", "precompute/transport/__init__.py", "precompute/transport/beam.py"} <= files
    with pytest.raises(ValueError, match="not a module"):
        stage_sources(REPO, ["precompute.no_such_module"])


def test_the_garment_measurement_covers_the_rig_and_the_shaders_the_old_list_missed(bpy):
    from clothlight.blender.garment import bake as garment_bake

    measurement = set(stage_sources(REPO, **garment_bake.MEASUREMENT_SOURCES))
    rig = {"clothlight/blender/sample_object.py", "clothlight/blender/validation/rig.py",
           "clothlight/weave/centerline.py", "clothlight/weave/params.py", "clothlight/blender/osl_shaders.py"}
    assert rig <= measurement and not rig & OLD_MEASUREMENT_SOURCES
    assert OLD_MEASUREMENT_SOURCES < measurement
    assert {"osl/cloth_yarn.osl", "osl/clothlight.h"} <= measurement and "osl/cloth_garment.osl" not in measurement
    assert "clothlight/garment/tables.py" not in measurement  # a new fit re-renders nothing
    tables = set(stage_sources(REPO, **garment_bake.TABLE_SOURCES))
    assert {"clothlight/garment/tables.py", "clothlight/blender/garment/detail.py",
            "precompute/tables/cycles_closures.py"} <= tables


def test_what_the_measurement_runs_of_the_garment_bake_comes_from_its_modules(bpy):
    from clothlight.blender.garment import bake as garment_bake

    measurement = set(stage_sources(REPO, **garment_bake.MEASUREMENT_SOURCES))
    used = modules_called_from("clothlight/blender/garment/bake.py", ["measure", "save_measurement"])
    assert "clothlight.blender.garment.measure" in used
    assert {module_file(REPO, m).relative_to(REPO).as_posix() for m in used} <= measurement


def test_every_file_of_the_garment_measurement_changes_its_digest(bpy, tree):
    from clothlight.blender.garment import bake as garment_bake

    definition = garment_bake.MEASUREMENT_SOURCES
    before = stage_digest(tree, **definition)
    for relative in stage_sources(tree, **definition):
        original = (tree / relative).read_bytes()
        _touch(tree / relative)
        assert stage_digest(tree, **definition) != before, relative
        (tree / relative).write_bytes(original)
    _touch(tree / "osl" / "cloth_garment.osl")
    _touch(tree / "clothlight" / "blender" / "ui.py")
    assert stage_digest(tree, **definition) == before
