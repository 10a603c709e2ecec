"""What enabling the add-on adds to Blender, in one list, and how disabling takes it back.

Every Blender class of the add-on is registered from :data:`CLASSES`, in its order, and unregistered
in reverse; the few other things enabling adds (the scene's settings, the preset folders, the sun
handlers, the numba cache folder) are added after the classes and removed before them, in mirror
order, so that a disable after an enable leaves Blender as it found it.
"""

from __future__ import annotations

import bpy
from bpy.props import PointerProperty

from . import closeup_operator, operators, preferences, preset_menus, properties, running_jobs, sun_link, ui
from .garment import operator as garment_operator
from .validation import operator as validation_operator

#: Every class, in registration order: the preferences, the property groups (each after the groups it
#: points to), the operators, then the panels that draw them.
CLASSES = (
    preferences.ClothLightPreferences,
    *properties.CLASSES,
    *preset_menus.CLASSES,
    *operators.CLASSES,
    *closeup_operator.CLASSES,
    *validation_operator.CLASSES,
    *garment_operator.CLASSES,
    *ui.CLASSES,
)

_register_classes, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def register() -> None:
    _register_classes()
    preferences.use_user_numba_cache()
    bpy.types.Scene.clothlight = PointerProperty(type=properties.ClothLightSceneSettings, name="ClothLight")
    bpy.utils.register_preset_path(str(preset_menus.PRESET_ROOT))
    sun_link.add_handlers()


def unregister() -> None:
    sun_link.remove_handlers()
    bpy.utils.unregister_preset_path(str(preset_menus.PRESET_ROOT))
    running_jobs.stop_all()
    del bpy.types.Scene.clothlight
    preferences.restore_numba_cache()
    _unregister_classes()
