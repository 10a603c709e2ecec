"""Blender extension entry point: the add-on lives in the ``clothlight`` package.

Blender imports this folder as ``bl_ext.<repo>.clothlight``; everything inside
is imported relatively from there.
"""

from .clothlight import register, unregister  # noqa: F401
