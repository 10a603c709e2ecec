"""Opening the file a command line job works in: an empty scene, a user's .blend, one of its objects."""

from __future__ import annotations

import pathlib

import bpy


def open_empty_file() -> None:
    """Start from Blender's empty file (no default cube, camera or light)."""
    bpy.ops.wm.read_homefile(use_empty=True)


def open_blend_file(path) -> str | None:
    """Open the .blend file ``path``: None when it opened, otherwise Blender's reason in one line."""
    try:
        bpy.ops.wm.open_mainfile(filepath=str(pathlib.Path(path).resolve()))
    except RuntimeError as error:
        return str(error).strip().splitlines()[-1] if str(error).strip() else "Blender cannot open it"
    return None


def object_named(name: str):
    """The open file's object ``name``, or None."""
    return bpy.data.objects.get(name)


def object_names() -> list[str]:
    """The names of the open file's objects, sorted."""
    return sorted(bpy.data.objects.keys())
