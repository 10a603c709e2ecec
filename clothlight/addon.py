"""Where this add-on sits among Python packages, inside Blender and out.

Inside Blender the extension is the package ``bl_ext.<repo>.clothlight`` and this
add-on is its ``clothlight`` sub-package; in development both ``clothlight`` and
``precompute`` are top-level packages of the repository.  This module is the
one place that knows the difference, so nothing ever edits ``sys.path``.
"""

from __future__ import annotations

import importlib
from types import ModuleType

#: The extension's package (``bl_ext.<repo>.clothlight``), or "" in development.
EXTENSION_PACKAGE = __package__.rpartition(".")[0]


def import_precompute(submodule: str = "") -> ModuleType:
    """Import ``precompute`` (or ``precompute.<submodule>``) wherever this add-on runs."""
    name = "precompute" + (f".{submodule}" if submodule else "")
    if EXTENSION_PACKAGE:
        name = f"{EXTENSION_PACKAGE}.{name}"
    return importlib.import_module(name)
