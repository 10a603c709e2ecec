"""ClothLight's OSL shaders as Cycles script nodes.

Shaders live in the extension's ``osl/`` folder.  They are embedded as internal
text blocks (so a saved .blend renders anywhere, with the bytecode stored in the
node) and, because ``#include`` of a relative header fails for in-memory text,
the shared header is inlined when the text block is made.
"""

from __future__ import annotations

import pathlib
import re

OSL_DIR = pathlib.Path(__file__).resolve().parents[2] / "osl"
_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$', re.MULTILINE)


def inline_includes(source: str) -> str:
    """``source`` with its ``#include "…"`` of headers in ``osl/`` replaced by their text."""

    def inline(match: re.Match) -> str:
        header = OSL_DIR / match.group(1)
        if not header.is_file():
            return match.group(0)  # a system header such as stdosl.h
        return _INCLUDE.sub(inline, header.read_text())

    return _INCLUDE.sub(inline, source)


def shader_source(name: str) -> str:
    """Source of ``osl/<name>.osl`` with its local headers inlined."""
    path = OSL_DIR / f"{name}.osl"
    if not path.is_file():
        raise FileNotFoundError(f"no OSL shader named {name!r} in {OSL_DIR}")
    return inline_includes(path.read_text())


def add_script_node(node_tree, name: str, source: str | None = None):
    """Add a Cycles script node running shader ``name`` from ``osl/`` (or the given source).

    The shader is embedded as the internal text block ``clothlight_<name>.osl``.
    Raises RuntimeError when it does not compile: Cycles would otherwise render
    the material black.
    """
    import bpy

    text_name = f"clothlight_{name}.osl"
    text = bpy.data.texts.get(text_name) or bpy.data.texts.new(text_name)
    text.from_string(inline_includes(source) if source is not None else shader_source(name))
    node = node_tree.nodes.new("ShaderNodeScript")
    node.mode = "INTERNAL"
    node.script = text
    if not node.outputs:
        raise RuntimeError(
            f"OSL shader {name!r} did not compile (no outputs on the script node); "
            "see the console for OSL's messages"
        )
    return node
