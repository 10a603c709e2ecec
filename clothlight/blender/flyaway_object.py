"""A woven sample's flyaway fibres in Blender: hair curves shaded with Cycles' hair BSDF of the dye.

The fibres (:mod:`clothlight.weave.flyaways`) go in as one hair-curves object, a child of the sample
so that it follows the sample's transform (the sample's millimetres), every fibre a curve with its
points and the fibre's radius.  Its material is Cycles' Principled Hair BSDF (Chiang) parametrised
by absorption coefficient, σ derived from the medium's dye and fibre material
(:func:`clothlight.weave.fibre_optics.hair_absorption_coefficient`), with the fibre material's
index.  The roughness is an appearance setting, not a measurement: a cotton fibre's surface is
convoluted and waxy, rougher than a hair's cuticle.

The fibres of a sample are rebuilt in place: their object is named after the sample
(``<sample> Flyaways``) and records what it was built from (``clothlight_flyaways``).
"""

from __future__ import annotations

import bpy
import numpy as np

from precompute.optics.medium import load_preset

from ..weave import WeaveParameterError
from ..weave.closeup import CloseupSettings
from ..weave.fibre_optics import fibre_radius_mm, fibre_refractive_index, hair_absorption_coefficient
from ..weave.flyaways import flyaway_fibres

#: Custom property of a fibres object: the settings and medium it was built from.
FLYAWAY_PROPERTY = "clothlight_flyaways"
#: Longitudinal and azimuthal roughness of the hair BSDF (module docstring).
FIBRE_ROUGHNESS = 0.4
FIBRE_RADIAL_ROUGHNESS = 0.6


def flyaway_name(sample: bpy.types.Object) -> str:
    return f"{sample.name} Flyaways"


def flyaway_material(preset: str) -> bpy.types.Material:
    """The material ``ClothLight Fibres <preset>``: Principled Hair (Chiang, absorption coefficient)
    of the preset's fibres; rebuilt from scratch if it exists."""
    medium = load_preset(preset)
    name = f"ClothLight Fibres {preset}"
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    tree = material.node_tree
    tree.nodes.clear()
    hair = tree.nodes.new("ShaderNodeBsdfHairPrincipled")
    hair.model, hair.parametrization = "CHIANG", "ABSORPTION"
    hair.inputs["Absorption Coefficient"].default_value = hair_absorption_coefficient(medium).tolist()
    hair.inputs["IOR"].default_value = fibre_refractive_index(medium)
    hair.inputs["Roughness"].default_value = FIBRE_ROUGHNESS
    hair.inputs["Radial Roughness"].default_value = FIBRE_RADIAL_ROUGHNESS
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.location = (300, 0)
    tree.links.new(hair.outputs["BSDF"], output.inputs["Surface"])
    return material


def build_flyaway_object(sample: bpy.types.Object, params, settings: CloseupSettings, preset: str,
                         collection=None) -> bpy.types.Object:
    """The flyaway fibres of the sample object ``sample`` built from ``params`` (its
    WeaveParameters) with the close-up ``settings`` and the fibres of the medium ``preset``, as a
    hair-curves child of ``sample`` in ``collection`` (default: the sample's first), replacing the
    fibres built for it before.  A sample that grows no fibre gets none (and loses its old ones);
    returns the fibres object or None."""
    medium = load_preset(preset)
    fibres = flyaway_fibres(params, settings, fibre_radius_mm(medium))
    name = flyaway_name(sample)
    old = bpy.data.objects.get(name)
    if old is not None:
        if old.type != "CURVES" or FLYAWAY_PROPERTY not in old:
            raise WeaveParameterError("name", name, "a free object name or that of a sample's flyaway fibres")
        data = old.data
        bpy.data.objects.remove(old)
        if data.users == 0:
            bpy.data.hair_curves.remove(data)
    if not len(fibres.counts):
        return None
    curves = bpy.data.hair_curves.new(name)
    curves.add_curves(fibres.counts.tolist())
    curves.attributes["position"].data.foreach_set("vector", fibres.points.astype(np.float32).ravel())
    radius = curves.attributes.new("radius", "FLOAT", "POINT")
    radius.data.foreach_set("value", np.full(len(fibres.points), fibres.radius_mm, dtype=np.float32))
    curves.materials.append(flyaway_material(preset))
    obj = bpy.data.objects.new(name, curves)
    (collection or (sample.users_collection[0] if sample.users_collection
                    else bpy.context.scene.collection)).objects.link(obj)
    obj.parent = sample
    obj[FLYAWAY_PROPERTY] = {"preset": preset, "fibres": len(fibres.counts),
                             "density_per_mm": settings.flyaway_density_per_mm,
                             "length_mm": settings.flyaway_length_mm, "curl_per_mm": settings.flyaway_curl_per_mm,
                             "seed": settings.seed, "radius_mm": fibres.radius_mm}
    return obj
