"""Add-on preferences: cache folder and thread count for bakes."""

from __future__ import annotations

import os

import bpy

from .addon import EXTENSION_PACKAGE


class ClothLightPreferences(bpy.types.AddonPreferences):
    # Blender looks preferences up by the extension's package name.
    bl_idname = EXTENSION_PACKAGE or "clothlight"

    cache_dir: bpy.props.StringProperty(
        name="Cache Folder",
        description="Folder for baked BRDF tables. Empty: the extension's user folder",
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
        layout = self.layout
        layout.prop(self, "cache_dir")
        layout.prop(self, "threads")


def preferences(context=None) -> ClothLightPreferences | None:
    """This add-on's preferences, or None when it is not enabled as an extension."""
    context = context or bpy.context
    addon = context.preferences.addons.get(ClothLightPreferences.bl_idname)
    return addon.preferences if addon else None


def cache_directory(context=None) -> str:
    """Folder for baked tables: the preference if set, else the extension's user cache folder."""
    prefs = preferences(context)
    if prefs and prefs.cache_dir:
        return bpy.path.abspath(prefs.cache_dir)
    return bpy.utils.extension_path_user(EXTENSION_PACKAGE, path="cache", create=True)


def register() -> None:
    bpy.utils.register_class(ClothLightPreferences)


def unregister() -> None:
    bpy.utils.unregister_class(ClothLightPreferences)
