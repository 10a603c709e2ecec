"""The source files a computation is made from, found by reading its imports (no module is imported).

A cache entry's key digests the code that made it (:func:`precompute.cache.entries.source_digest`).  Which
files that is follows from the code itself: a stage names the modules it runs (its *entry
modules*), and :func:`stage_sources` adds every module of the project they import, transitively,
plus the OSL shaders they compile.  A module imported by a new file is picked up by the next key
without anyone keeping a list.

What counts as an import, read with :mod:`ast` from each file (anywhere in it, function bodies
included, so a lazy import counts too):

* ``import a.b`` and ``from a.b import c`` (``c`` too when it is a module), absolute or relative;
  importing ``a.b`` runs ``a/__init__.py`` as well, so that counts;
* ``importlib.import_module("a.b")`` with a literal name.

Only modules of the project count: a dotted name whose top-level package is a folder with an
``__init__.py`` in ``root`` (``clothlight``, ``precompute``) and that resolves to a file there;
everything else (NumPy, bpy, the standard library) is left out.

OSL: a string literal in one of those modules that names a shader of ``root/osl`` (``"cloth_yarn"``
or ``"cloth_yarn.osl"``) adds that shader, and every header it ``#include``\\ s from ``osl/``, as
:func:`clothlight.blender.osl_shaders.inline_includes` inlines them.  So a shader must be named by a
literal in the module that builds it, as every ClothLight material does.
"""

from __future__ import annotations

import ast
import functools
import pathlib
import re
from collections.abc import Iterable

from precompute.cache.entries import source_digest

#: The folder of the shaders, relative to the project root.
OSL_FOLDER = "osl"
#: Calls whose one literal argument names a module to import: (function name, prefix of the module).
_IMPORT_CALLS = {"import_module": ""}
_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$', re.MULTILINE)


def module_file(root: pathlib.Path, name: str) -> pathlib.Path | None:
    """The file of the project module ``name`` (a package's ``__init__.py``), or None when it is not one."""
    parts = name.split(".")
    if not parts[0] or not (root / parts[0] / "__init__.py").is_file():
        return None
    base = root.joinpath(*parts)
    for candidate in (base / "__init__.py", base.with_name(base.name + ".py")):
        if candidate.is_file():
            return candidate
    return None


def _module_name(root: pathlib.Path, path: pathlib.Path) -> tuple[str, bool]:
    """The dotted name of the module at ``path`` and whether it is a package."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    is_package = parts[-1] == "__init__"
    return ".".join(parts[:-1] if is_package else parts), is_package


def _absolute(module: str | None, level: int, package: str) -> str | None:
    """The absolute name of ``from <level dots><module> import …`` in ``package``."""
    if level == 0:
        return module
    base = package.split(".") if package else []
    if level - 1 > len(base) or (level - 1 == len(base) and not module):
        return None  # above the top-level package
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([module] if module else [])) or None


@functools.lru_cache(maxsize=1024)
def _scan(source: str) -> tuple[tuple[tuple[str | None, int, tuple[str, ...]], ...], frozenset[str]]:
    """What one parse of a module's source gives: its imports as ``(module, level, names)`` (``import
    a.b`` is ``("a.b", 0, ())``, an import call ``(name, 0, ())``) and its string literals.  Memoised
    on the text, so a module is parsed again only when it changed."""
    imports, strings = [], set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            imports.extend((alias.name, 0, ()) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            imports.append((node.module, node.level, tuple(alias.name for alias in node.names if alias.name != "*")))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            strings.add(node.value)
        elif isinstance(node, ast.Call) and len(node.args) == 1 and isinstance(node.args[0], ast.Constant):
            function = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", None)
            argument = node.args[0].value
            if function in _IMPORT_CALLS and isinstance(argument, str):
                prefix = _IMPORT_CALLS[function]
                imports.append((".".join(part for part in (prefix, argument) if part), 0, ()))
    return tuple(imports), frozenset(strings)


def imported_names(source: str, name: str, is_package: bool) -> set[str]:
    """Dotted names of every module the source of module ``name`` may import (see the module docstring)."""
    package = name if is_package else name.rpartition(".")[0]
    names: set[str] = set()
    for module, level, members in _scan(source)[0]:
        target = _absolute(module, level, package)
        if target:
            names.add(target)
            names.update(f"{target}.{member}" for member in members)
    return names


def _with_parents(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[: i + 1]) for i in range(len(parts))]


def python_sources(root: str | pathlib.Path, entries: Iterable[str]) -> list[pathlib.Path]:
    """The project's module files that the modules ``entries`` are made of: theirs and those they
    import, transitively (with the packages' ``__init__.py`` on the way).  Sorted."""
    root = pathlib.Path(root).resolve()
    found: set[pathlib.Path] = set()
    resolved: set[str] = set()  # names already looked up: most modules import the same few
    pending = []
    for entry in entries:
        if module_file(root, entry) is None:
            raise ValueError(f"{entry!r} is not a module of the project in {root}")
        pending.append(entry)
    while pending:
        for name in _with_parents(pending.pop()):
            if name in resolved:
                continue
            resolved.add(name)
            path = module_file(root, name)
            if path is None:
                continue
            found.add(path)
            module, is_package = _module_name(root, path)
            pending.extend(imported_names(path.read_text(encoding="utf-8"), module, is_package))
    return sorted(found)


def osl_sources(root: str | pathlib.Path, python_files: Iterable[pathlib.Path]) -> list[pathlib.Path]:
    """The shaders of ``root/osl`` named by a string literal in ``python_files``, with the headers they
    include (transitively).  Sorted."""
    folder = pathlib.Path(root).resolve() / OSL_FOLDER
    shaders = {path.stem: path for path in folder.glob("*.osl")} if folder.is_dir() else {}
    found: set[pathlib.Path] = set()
    for path in python_files:
        for text in _scan(path.read_text(encoding="utf-8"))[1]:
            shader = shaders.get(text.removesuffix(".osl"))
            if shader is not None:
                found.add(shader)
    pending = list(found)
    while pending:
        for include in _INCLUDE.findall(pending.pop().read_text(encoding="utf-8")):
            header = folder / include
            if header.is_file() and header not in found:
                found.add(header)
                pending.append(header)
    return sorted(found)


def stage_sources(root: str | pathlib.Path, entries: Iterable[str], files: Iterable[str] = ()) -> tuple[str, ...]:
    """Paths (relative to ``root``, with ``/``) of the source files of a stage that runs the modules
    ``entries`` and, as written, the project files ``files`` (code a stage runs from a module whose
    other imports it does not need).  Python first, then OSL, each sorted."""
    root = pathlib.Path(root).resolve()
    python = python_sources(root, entries)
    for relative in files:
        path = root / relative
        if not path.is_file():
            raise ValueError(f"{relative!r} is not a file of the project in {root}")
        if path not in python:
            python.append(path)
    python.sort()
    return tuple(path.relative_to(root).as_posix() for path in (*python, *osl_sources(root, python)))


def stage_digest(root: str | pathlib.Path, entries: Iterable[str], files: Iterable[str] = ()) -> str:
    """SHA-256 (hex) of :func:`stage_sources` (names and contents): what a stage's cache key holds of its code."""
    return source_digest(root, stage_sources(root, entries, files))
