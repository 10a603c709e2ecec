"""Everything of the add-on that imports Blender (``bpy``, ``mathutils``, ``bmesh``).

The rest of ``clothlight`` (``weave``, ``validation``, ``garment``, the bake jobs) decides what to
build and measure without Blender and is tested without it; the modules here turn those decisions
into scenes, materials, renders, properties, operators and panels.  Nothing outside this folder
imports Blender (``tests/test_bpy_boundary.py`` walks the imports).

Add-on glue: ``preferences``, ``properties``, ``preset_menus`` (with the shipped ``presets/``),
``operators``, ``ui``, ``sun_link``.  Scenes and renders: ``sample_object`` (the woven sample),
``materials`` and ``osl_shaders`` (the OSL materials), ``render_setup``, ``measurement_render``,
``scene_files`` (what a command line job opens).  The gonioreflectometer in Blender:
``validation`` (rig, sweep, cloth response, operator); the garment material: ``garment``
(goniometer measurement, detail renders, drape, material, operator).
"""
