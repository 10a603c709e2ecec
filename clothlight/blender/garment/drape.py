"""A draped cloth to wear the garment material: a square of fabric dropped over a sphere with
Blender's cloth simulation, frozen into a plain mesh.

The grid's UV map runs u along its x edge, the warp; the simulation keeps UVs, so the warp
follows the fabric through the folds.  Sizes are in metres (a garment-scale scene).
"""

from __future__ import annotations

import bmesh
import bpy

#: Grid cuts along each side of the fabric (2.5 cm cells on the 1.2 m square).
DEFAULT_CUTS = 48
#: Frames simulated: enough for the fabric to settle over the form.
DEFAULT_FRAMES = 80
#: The cloth's simulation settings: Blender's Cotton preset (mass 0.3 kg, stiffnesses 15), with the
#: bending stiffness raised to 50.  At the preset's 0.5 the fabric buckles at the grid's own scale
#: and folds flat onto itself (crumpled zig-zags: a quarter of the edges folded by more than 30°,
#: up to 177°); at 50 the folds are wider than a cell (2 % of the edges above 30°, none above 36°;
#: tests/test_drape.py).
CLOTH_SETTINGS = {"quality": 10, "mass": 0.3, "air_damping": 1.0, "tension_stiffness": 15.0,
                  "compression_stiffness": 15.0, "shear_stiffness": 15.0, "bending_stiffness": 50.0}


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
    for key, value in CLOTH_SETTINGS.items():
        setattr(simulation.settings, key, value)
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
