"""Add-on preferences: cache folder and thread count for bakes."""

from __future__ import annotations

import os

import bpy

from .addon import EXTENSION_PACKAGE, import_precompute


class ClothLightPreferences(bpy.types.AddonPreferences):
    # Blender looks preferences up by the extension's package name.
    bl_idname = EXTENSION_PACKAGE or "clothlight"

    cache_dir: bpy.props.StringProperty(
        name="Cache Folder",
        description="Folder for baked BRDF tables (a content-addressed cache: equal settings reuse a bake). "
                    "Empty: the extension's user folder",
        subtype="DIR_PATH",
        default="",
    )
    threads: bpy.props.IntProperty(
        name="Bake Threads",
        description="CPU threads used by Monte-Carlo bakes. 0: all cores",
        default=0,
        min=0,
        soft_max=os.cpu_count() or 1,
    )

    def draw(self, context):
        from .operators import bake_unavailable_reason

        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "cache_dir")
        layout.label(text=f"In use: {cache_directory(context)}", icon="FILE_FOLDER")
        layout.prop(self, "threads")
        reason = bake_unavailable_reason()
        if reason:
            layout.label(text=reason, icon="ERROR")


def preferences(context=None) -> ClothLightPreferences | None:
    """This add-on's preferences, or None when it is not enabled as an extension."""
    context = context or bpy.context
    addon = context.preferences.addons.get(ClothLightPreferences.bl_idname)
    return addon.preferences if addon else None


def cache_directory(context=None) -> str:
    """Folder for baked tables: the preference if set, else the extension's user cache folder
    (in development, outside an extension, the bake's own default cache)."""
    prefs = preferences(context)
    if prefs and prefs.cache_dir:
        return bpy.path.abspath(prefs.cache_dir)
    if not EXTENSION_PACKAGE:
        return str(import_precompute("cache").default_cache_dir())
    return bpy.utils.extension_path_user(EXTENSION_PACKAGE, path="cache", create=True)


def numba_cache_directory() -> str | None:
    """Where bakes keep numba's compiled kernels: the extension's user folder, since an extension must
    not write into its own folder.  None in development (numba's default, next to the sources)."""
    if not EXTENSION_PACKAGE:
        return None
    return bpy.utils.extension_path_user(EXTENSION_PACKAGE, path="numba", create=True)


def register() -> None:
    bpy.utils.register_class(ClothLightPreferences)


def unregister() -> None:
    bpy.utils.unregister_class(ClothLightPreferences)
