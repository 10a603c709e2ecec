"""ClothLight add-on: woven cloth samples, yarn-BRDF materials and a virtual gonioreflectometer.

Core logic (weave geometry, table reading, background bake jobs, the gonioreflectometer's
framing and calibration, the garment's goniometry) is importable and tested without Blender;
everything that imports Blender is in ``clothlight.blender``, whose modules holding Blender
classes are registered here, in order, and unregistered in reverse.
"""

from __future__ import annotations

import importlib

# Modules of clothlight.blender holding Blender classes, in registration order.
_BLENDER_MODULES = ("preferences", "properties", "preset_menus", "operators", "validation.operator",
                   "garment.operator", "ui", "sun_link")


def _modules():
    return [importlib.import_module(f".blender.{name}", __package__) for name in _BLENDER_MODULES]


def register() -> None:
    for module in _modules():
        module.register()


def unregister() -> None:
    for module in reversed(_modules()):
        module.unregister()
