"""A draped cloth to wear the garment material: a square of fabric dropped over a sphere with
Blender's cloth simulation, frozen into a plain mesh.

The grid's UV map runs u along its x edge, the warp; the simulation keeps UVs, so the warp
follows the fabric through the folds.  Sizes are in metres (a garment-scale scene).
"""

from __future__ import annotations

import bmesh
import bpy

#: Grid cuts along each side of the fabric (a 48 × 48 grid drapes smoothly in seconds).
DEFAULT_CUTS = 48
DEFAULT_FRAMES = 45


def _bmesh_object(name: str, build, collection):
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    try:
        build(bm)
        bm.to_mesh(mesh)
    finally:
        bm.free()
    for polygon in mesh.polygons:
        polygon.use_smooth = True
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    return obj


def draped_cloth(scene, *, size_m: float = 1.2, cuts: int = DEFAULT_CUTS, frames: int = DEFAULT_FRAMES,
                 obstacle_radius_m: float = 0.35, name: str = "Draped Cloth"):
    """Drop a ``size_m`` square of cloth (``cuts`` × ``cuts`` grid) over a sphere of radius
    ``obstacle_radius_m`` at the origin, simulate ``frames`` frames and freeze the result.

    Returns (cloth, sphere): two mesh objects in ``scene``'s collection, the cloth without
    modifiers (its simulated shape applied), UV map ``UVMap`` with u along the warp."""
    if not (isinstance(cuts, int) and cuts >= 4 and isinstance(frames, int) and frames >= 1):
        raise ValueError(f"cuts ≥ 4 and frames ≥ 1 (integers), not {cuts!r}, {frames!r}")
    if not (size_m > 0 and obstacle_radius_m > 0):
        raise ValueError("size_m and obstacle_radius_m are lengths > 0 (m)")
    collection = scene.collection
    sphere = _bmesh_object(f"{name} Form", lambda bm: bmesh.ops.create_uvsphere(
        bm, u_segments=48, v_segments=24, radius=obstacle_radius_m), collection)
    collision = sphere.modifiers.new("Collision", "COLLISION")
    sphere.collision.thickness_outer = 0.01
    del collision

    def grid(bm):
        bm.loops.layers.uv.new("UVMap")
        bmesh.ops.create_grid(bm, x_segments=cuts, y_segments=cuts, size=size_m / 2.0, calc_uvs=True)

    cloth = _bmesh_object(name, grid, collection)
    cloth.location = (0.0, 0.0, obstacle_radius_m + 0.05)
    # Rotate a little so the folds do not line up with the warp.
    cloth.rotation_euler = (0.0, 0.0, 0.3)
    simulation = cloth.modifiers.new("Cloth", "CLOTH")
    simulation.settings.quality = 6
    simulation.settings.mass = 0.15
    simulation.collision_settings.distance_min = 0.008
    simulation.point_cache.frame_start = 1
    simulation.point_cache.frame_end = frames
    previous = scene.frame_current
    for frame in range(1, frames + 1):
        scene.frame_set(frame)
    evaluated = cloth.evaluated_get(bpy.context.evaluated_depsgraph_get())
    frozen = bpy.data.meshes.new_from_object(evaluated)
    old = cloth.data
    cloth.modifiers.clear()
    cloth.data = frozen
    frozen.name = name
    bpy.data.meshes.remove(old)
    scene.frame_set(previous)
    sphere.modifiers.clear()
    return cloth, sphere
