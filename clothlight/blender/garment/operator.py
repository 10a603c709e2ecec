"""The garment material in the interface: put a cloth bake on the selected meshes.

The cloth bake itself runs from the command line (``python -m clothlight.garment bake``, minutes
of renders); the panel shows the command.  The material module (the cloth-table reader: OpenEXR,
SciPy, numba's grids) is imported when the operator runs, not when the add-on is enabled.
"""

from __future__ import annotations

import bpy

from ..materials import GENERAL_MODE

BAKE_COMMAND = "python -m clothlight.garment bake --tables YARN_BAKE --out DIR"


def _meshes(context):
    return [obj for obj in context.selected_objects if obj.type == "MESH"]


class CLOTHLIGHT_OT_apply_garment_material(bpy.types.Operator):
    """Give the selected meshes the garment material of a cloth bake (general lighting; the warp
    follows the UV map's u, the front the normals)"""

    bl_idname = "clothlight.apply_garment_material"
    bl_label = "Apply Garment Material"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not _meshes(context):
            cls.poll_message_set("Select the garment's mesh objects")
            return False
        return True

    def execute(self, context):
        from .material import apply_garment_material, cloth_tables_from_bake

        settings = context.scene.clothlight
        folder = bpy.path.abspath(settings.cloth_tables_dir)
        try:
            tables = cloth_tables_from_bake(folder)
        except (FileNotFoundError, ValueError, KeyError) as error:
            self.report({"ERROR"}, f"Cloth bake: {error}")
            return {"CANCELLED"}
        done, skipped = [], []
        for obj in _meshes(context):
            try:
                apply_garment_material(obj, tables, mode=GENERAL_MODE, open_weave=settings.garment_open_weave,
                                       transmission=settings.garment_transmission,
                                       weave_repeats_per_uv=settings.garment_weave_repeats or None)
                done.append(obj.name)
            except ValueError as error:
                skipped.append(str(error))
        for message in skipped:
            self.report({"WARNING"}, message)
        if not done:
            return {"CANCELLED"}
        self.report({"INFO"}, f"Garment material on {', '.join(done)}")
        return {"FINISHED"}


CLASSES = (CLOTHLIGHT_OT_apply_garment_material,)
