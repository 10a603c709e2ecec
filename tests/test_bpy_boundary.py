"""Where the bpy line falls: everything that imports Blender is in ``clothlight/blender/``.

The rest of the project (``precompute``, the bpy-free part of ``clothlight``, the extension's entry
point) must import without Blender, so that it runs in a plain Python and its tests need no bpy.
Two checks: the source of every module outside the Blender folder names no Blender module and
reaches the Blender folder only from inside a function (the command lines, ``register``); and
importing every one of those modules with Blender's modules made unimportable works and loads no
Blender-side module.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys

from tests.helpers import BLENDER_ONLY, REPO

BLENDER_FOLDER = REPO / "clothlight" / "blender"
#: The packages whose modules must import without Blender (the extension's entry point included).
BPY_FREE_ROOTS = ("clothlight", "precompute")


def bpy_free_files() -> list:
    files = [REPO / "__init__.py"]
    for root in BPY_FREE_ROOTS:
        files += [path for path in sorted((REPO / root).rglob("*.py")) if BLENDER_FOLDER not in path.parents]
    return files


def module_name(path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_modules(path, module: str | None = None):
    """(absolute module name, whether the import runs when the module is imported) of every import
    statement in ``path`` (the module ``module``, by default the repository's name for it);
    relative imports resolved against the module's package."""
    module = module or module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    at_import = {id(node) for node in tree.body}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            prefix = node.module
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                prefix = ".".join(base + ([node.module] if node.module else []))
            names = [prefix] + [f"{prefix}.{alias.name}" for alias in node.names]
        else:
            continue
        for name in names:
            yield name, id(node) in at_import


def test_no_module_outside_the_blender_folder_names_a_blender_module():
    offenders = [(path.relative_to(REPO).as_posix(), name) for path in bpy_free_files()
                 for name, _ in imported_modules(path) if name.partition(".")[0] in BLENDER_ONLY]
    assert offenders == []


def test_the_blender_folder_is_reached_only_from_inside_functions():
    offenders = [(path.relative_to(REPO).as_posix(), name) for path in bpy_free_files()
                 for name, at_import in imported_modules(path)
                 if at_import and (name == "clothlight.blender" or name.startswith("clothlight.blender."))]
    assert offenders == []


def test_the_import_walk_resolves_relative_imports_and_tells_nested_ones(tmp_path):
    cli = tmp_path / "cli.py"
    cli.write_text("from ..blender.garment import bake\nimport bpy.props\n"
                   "def run():\n    from ..blender import scene_files\n")
    found = set(imported_modules(cli, "clothlight.garment.cli"))
    assert {("clothlight.blender.garment", True), ("clothlight.blender.garment.bake", True), ("bpy.props", True),
            ("clothlight.blender.scene_files", False)} <= found
    assert ("clothlight.blender.validation.run", False) in set(imported_modules(REPO / "clothlight" / "validate.py"))


def test_every_bpy_free_module_imports_without_blender():
    modules = [module_name(path) for path in bpy_free_files()
               if path.name != "__main__.py" and path != REPO / "__init__.py"]
    script = f"""
import importlib.abc, json, sys
class WithoutBlender(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in {BLENDER_ONLY!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
sys.meta_path.insert(0, WithoutBlender())
failed = {{}}
for name in {modules!r}:
    try:
        importlib.import_module(name)
    except Exception as error:
        failed[name] = f"{{type(error).__name__}}: {{error}}"
loaded = sorted(name for name in sys.modules
                if name.startswith("clothlight.blender") or name.partition(".")[0] in {BLENDER_ONLY!r})
print(json.dumps({{"failed": failed, "loaded": loaded, "count": len({modules!r})}}))
"""
    result = subprocess.run([sys.executable, "-c", script], cwd=REPO, capture_output=True, text=True, check=True)
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert report["failed"] == {}
    assert report["loaded"] == []
    assert report["count"] > 60
