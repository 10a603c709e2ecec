"""The reference a user would otherwise render cloth with: a Principled BSDF with full sheen.

One definition for the examples' side-by-side copies (``scripts/make_example_blends.py``,
``scripts/make_garment_example.py``) and the render-cost benchmarks (``benchmarks/render_cost.py``),
so that every comparison is against the same material.
"""

from __future__ import annotations

import bpy

#: Sheen weight and roughness of the reference: full sheen on a rough dielectric, as for cloth.
SHEEN_WEIGHT = 1.0
ROUGHNESS = 0.8


def principled_sheen(name: str, base_color) -> bpy.types.Material:
    """A new material ``name``: Principled BSDF of base colour ``base_color`` (linear RGB) with
    full sheen, roughness 0.8."""
    material = bpy.data.materials.new(name)
    node = material.node_tree.nodes["Principled BSDF"]
    node.inputs["Base Color"].default_value = (*base_color, 1.0)
    node.inputs["Sheen Weight"].default_value = SHEEN_WEIGHT
    node.inputs["Roughness"].default_value = ROUGHNESS
    return material
