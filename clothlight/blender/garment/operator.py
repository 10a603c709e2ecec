"""The garment material in the interface: put a cloth bake on the selected meshes.

Apply Garment Material finds its cloth tables by itself: the Cloth Bake folder when one is set
(Bake Cloth sets it), else the cloth tables shipped with the extension for an unchanged shipped
preset at the default Thread Count (:func:`clothlight.prebaked.prebaked_cloth_tables`, through their
copy in the cache), else it starts Bake Cloth, which puts the material on the same meshes when it is
done.  The yarns' scale comes from each mesh: weave repeats per UV unit from its size in the scene's units
(:mod:`clothlight.garment.uv_scale`).  The material module (the cloth-table reader: OpenEXR,
SciPy, numba's grids) is imported when the operator runs, not when the add-on is enabled.
"""

from __future__ import annotations

import pathlib

import bpy
import numpy as np

from .. import preferences
from ..materials import GENERAL_MODE

BAKE_COMMAND = "python -m clothlight.garment bake --tables YARN_BAKE --out DIR"
#: Separates object names in Bake Cloth's ``apply_to``.
NAME_SEPARATOR = "\n"


def _meshes(context):
    return [obj for obj in context.selected_objects if obj.type == "MESH"]


def shipped_cloth_tables(scene) -> pathlib.Path | None:
    """The copy in the cache of the cloth tables shipped for the panel's medium, when it is an
    unchanged shipped preset read from its shipped yarn tables (no Tables folder set) at the
    validation weave's thread count (the one they were measured at); else None."""
    from ...prebaked import prebaked_cloth_tables, user_copy
    from .density import DEFAULT_THREADS_PER_CM

    medium = scene.clothlight.medium
    if medium.tables_dir or scene.clothlight.garment_threads_per_cm != DEFAULT_THREADS_PER_CM:
        return None
    try:
        shipped = prebaked_cloth_tables(medium.request())
    except ValueError:  # settings the panel refuses: no shipped preset either
        return None
    return None if shipped is None else user_copy(shipped, preferences.cache_directory(), cloth=True)


def mesh_triangles_mm(obj, scene) -> tuple[np.ndarray, np.ndarray]:
    """(corners in mm (n, 3, 3), their UVs (n, 3, 2)) of ``obj``'s evaluated mesh, in the world
    (object transform and the scene's unit scale applied), on its active UV map."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        mesh.calc_loop_triangles()
        loops = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
        mesh.loop_triangles.foreach_get("loops", loops)
        vertex_of_loop = np.empty(len(mesh.loops), dtype=np.int32)
        mesh.loops.foreach_get("vertex_index", vertex_of_loop)
        positions = np.empty(len(mesh.vertices) * 3, dtype=np.float64)
        mesh.vertices.foreach_get("co", positions)
        uvs = np.empty(len(mesh.loops) * 2, dtype=np.float64)
        mesh.uv_layers.active.data.foreach_get("uv", uvs)
    finally:
        evaluated.to_mesh_clear()
    matrix = np.array(obj.matrix_world)
    positions = positions.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    millimetres_per_unit = 1000.0 * scene.unit_settings.scale_length
    corners = positions[vertex_of_loop[loops]].reshape(-1, 3, 3) * millimetres_per_unit
    return corners, uvs.reshape(-1, 2)[loops].reshape(-1, 3, 2)


def apply_to_meshes(context, objects, folder) -> tuple[list[str], list[str]]:
    """Put the garment material of the cloth tables in ``folder`` on ``objects`` with the Garment
    panel's settings: (names done, warnings for those skipped).  ValueError (a TableError among
    them) when the folder is not a cloth bake."""
    from .material import apply_garment_material, cloth_tables_from_bake
    from ...garment.uv_scale import weave_repeats_per_uv

    settings = context.scene.clothlight
    tables = cloth_tables_from_bake(folder)
    done, skipped = [], []
    for obj in objects:
        try:
            repeats = None
            if settings.garment_yarn_detail:
                if tables.detail_repeat_mm is None:
                    raise ValueError(f"{obj.name!r}: this cloth bake has no weave detail texture, bake the cloth "
                                     "again for Yarn Detail")
                repeats = settings.garment_weave_repeats or None
                if repeats is None and obj.data.uv_layers:  # without one, the material names what is missing
                    try:
                        repeats = weave_repeats_per_uv(*mesh_triangles_mm(obj, context.scene),
                                                       tables.detail_repeat_mm)
                    except ValueError as error:
                        raise ValueError(f"{obj.name!r}: {error}") from None
            apply_garment_material(obj, tables, mode=GENERAL_MODE, open_weave=settings.garment_open_weave,
                                   transmission=settings.garment_transmission, weave_repeats_per_uv=repeats)
            done.append(obj.name)
        except ValueError as error:  # each message names its object
            skipped.append(str(error))
    return done, skipped


def report_applied(operator, done: list[str], skipped: list[str]) -> set[str]:
    for message in skipped:
        operator.report({"WARNING"}, message)
    if not done:
        return {"CANCELLED"}
    operator.report({"INFO"}, f"Garment material on {', '.join(done)}")
    return {"FINISHED"}


class CLOTHLIGHT_OT_apply_garment_material(bpy.types.Operator):
    """Give the selected meshes the garment material (general lighting; the warp follows the UV map's u,
    the front the normals): the Cloth Bake folder's, the shipped cloth of an unchanged preset, or a new
    Bake Cloth that applies it when done"""

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
        settings = context.scene.clothlight
        meshes = _meshes(context)
        if settings.cloth_tables_dir:
            folder = bpy.path.abspath(settings.cloth_tables_dir)
        else:
            try:
                folder = shipped_cloth_tables(context.scene)
            except (OSError, ValueError) as error:
                self.report({"ERROR"}, f"Shipped cloth tables: {error}")
                return {"CANCELLED"}
            if folder is None:
                if not bpy.ops.clothlight.bake_cloth.poll():  # a bake running, or none possible here
                    self.report({"ERROR"}, "No cloth tables for this medium yet, and Bake Cloth cannot start: "
                                           "see the Garment panel")
                    return {"CANCELLED"}
                self.report({"INFO"}, "No cloth tables for this medium yet: baking them (Garment panel), then "
                                      "applying the material")
                return bpy.ops.clothlight.bake_cloth(
                    "INVOKE_DEFAULT", apply_to=NAME_SEPARATOR.join(obj.name for obj in meshes))
            settings.cloth_tables_dir = str(folder)
        try:
            done, skipped = apply_to_meshes(context, meshes, folder)
        except (FileNotFoundError, ValueError, KeyError) as error:
            self.report({"ERROR"}, f"Cloth bake: {error}")
            return {"CANCELLED"}
        return report_applied(self, done, skipped)


CLASSES = (CLOTHLIGHT_OT_apply_garment_material,)
