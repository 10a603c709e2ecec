"""ClothLight panels: the 3D View sidebar's "Cloth" tab."""

from __future__ import annotations

import bpy


class CLOTHLIGHT_PT_main(bpy.types.Panel):
    bl_label = "ClothLight"
    bl_idname = "CLOTHLIGHT_PT_main"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Cloth"

    def draw(self, context):
        layout = self.layout
        layout.operator("clothlight.setup_render", icon="SHADING_RENDERED")


CLASSES = (CLOTHLIGHT_PT_main,)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister() -> None:
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
