"""Sun-mode materials follow their sun: moving, rotating, dimming or animating it updates the shader.

A sun-mode yarn material evaluates the BRDF for one parallel beam whose direction and irradiance
are shader inputs (:func:`clothlight.blender.materials.sync_sun`).  Apply Material records the sun object
in the material's ``clothlight_sun`` custom property (an ID pointer, so renaming the lamp keeps
the link); these handlers copy the lamp's state into every such material whenever the scene
changes or the frame moves.
"""

from __future__ import annotations

import bpy
from bpy.app.handlers import persistent

from .materials import shader_node, sync_sun

SUN_PROPERTY = "clothlight_sun"


def sync_linked_suns() -> int:
    """Copy each linked sun's state into its materials; returns how many materials were synced.

    The writes change only materials, never lights, so the depsgraph handler below (which reacts
    to light changes) does not call itself again."""
    synced = 0
    for material in bpy.data.materials:
        sun = material.get(SUN_PROPERTY)
        if isinstance(sun, bpy.types.Object) and sun.type == "LIGHT" and sun.data.type == "SUN" \
                and shader_node(material) is not None:
            sync_sun(material, sun)
            synced += 1
    return synced


@persistent
def _on_depsgraph_update(_scene, depsgraph) -> None:
    for update in depsgraph.updates:
        block = update.id
        if isinstance(block, bpy.types.Light) or (isinstance(block, bpy.types.Object) and block.type == "LIGHT"):
            sync_linked_suns()
            return


@persistent
def _on_frame_change(_scene, _depsgraph=None) -> None:
    sync_linked_suns()


def add_handlers() -> None:
    bpy.app.handlers.depsgraph_update_post.append(_on_depsgraph_update)
    bpy.app.handlers.frame_change_post.append(_on_frame_change)


def remove_handlers() -> None:
    for handlers, function in ((bpy.app.handlers.depsgraph_update_post, _on_depsgraph_update),
                               (bpy.app.handlers.frame_change_post, _on_frame_change)):
        if function in handlers:
            handlers.remove(function)
