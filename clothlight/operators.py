"""Operators of the ClothLight add-on.  Each reports errors through Blender's report system."""

from __future__ import annotations

import bpy

from .render_setup import use_cycles_osl_on_cpu


class CLOTHLIGHT_OT_setup_render(bpy.types.Operator):
    """Switch the scene to Cycles with Open Shading Language on the CPU, as ClothLight materials need"""

    bl_idname = "clothlight.setup_render"
    bl_label = "Set Up Cycles for ClothLight"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        self.report({"INFO"}, use_cycles_osl_on_cpu(context.scene))
        return {"FINISHED"}


CLASSES = (CLOTHLIGHT_OT_setup_render,)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister() -> None:
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
