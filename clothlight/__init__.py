"""ClothLight add-on: woven cloth samples, yarn-BRDF materials and a virtual gonioreflectometer.

Core logic (weave geometry, table reading, background bake jobs) is importable
without Blender; the Blender-facing modules are registered here, in order, and
unregistered in reverse.
"""

from __future__ import annotations

import importlib

# Modules holding Blender classes, in registration order.
_BLENDER_MODULES = ("preferences", "properties", "preset_menus", "operators", "validation.operator",
                   "garment.operator", "ui", "sun_link")


def _modules():
    return [importlib.import_module(f".{name}", __package__) for name in _BLENDER_MODULES]


def register() -> None:
    for module in _modules():
        module.register()


def unregister() -> None:
    for module in reversed(_modules()):
        module.unregister()
