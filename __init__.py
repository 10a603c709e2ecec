"""Blender extension entry point: the add-on lives in the ``clothlight`` package.

Blender imports this folder as ``bl_ext.<repo>.clothlight``; everything inside
is imported relatively from there.
"""

# pytest imports this file as a top-level module when the checkout's folder name is no Python
# identifier (a `mktemp -d` clone): there is no package to import relatively from, and nothing to register.
if __package__:
    from .clothlight import register, unregister  # noqa: F401
