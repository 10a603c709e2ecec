"""Add-on preferences: cache folder and thread count for bakes and fits; the user folders the add-on writes into.

An extension must not write into its own folder (Blender may replace it on update, or install it
read-only): whatever the add-on keeps goes under the extension's user folder
(``bpy.utils.extension_path_user``) — the bake cache (:func:`cache_directory`, with the user copies
of the pre-baked tables and the fit's cloth responses), numba's compiled kernels
(:func:`numba_cache_directory`), the bake and fit children's Python bytecode
(:func:`bytecode_cache_directory`) and the fits written without a folder of their own
(:func:`fit_directory`).
"""

from __future__ import annotations

import os

import bpy

from ..fit_job import fit_unavailable_reason
from ..jobs import bake_unavailable_reason


#: The extension's package (``bl_ext.<repo>.clothlight``), or "" in development, where ``clothlight`` is
#: a top-level package: this module is ``<extension>.clothlight.blender.preferences``.
EXTENSION_PACKAGE = __package__.rpartition(".")[0].rpartition(".")[0]


class ClothLightPreferences(bpy.types.AddonPreferences):
    # Blender looks preferences up by the extension's package name.
    bl_idname = EXTENSION_PACKAGE or "clothlight"

    cache_dir: bpy.props.StringProperty(
        name="Cache Folder",
        description="Folder for baked BRDF tables (a content-addressed cache: equal settings reuse a bake). "
                    "Empty: the extension's user folder",
        subtype="DIR_PATH",
        default="",
    )
    threads: bpy.props.IntProperty(
        name="Bake Threads",
        description="CPU threads used by Monte-Carlo bakes and fits (a count). 0: all cores",
        default=0,
        min=0,
        soft_max=os.cpu_count() or 1,
    )

    scheduler: bpy.props.StringProperty(
        name="Dask Scheduler",
        description="Address of a dask cluster (tcp://HOST:PORT, started with `dask scheduler` and `dask worker` "
                    "from the same ClothLight) whose workers run the bakes' transport; the bake's Python needs "
                    "dask and distributed. Blank: this machine's cores",
        default="",
    )

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "cache_dir")
        layout.label(text=f"In use: {cache_directory(context)}", icon="FILE_FOLDER")
        layout.prop(self, "threads")
        layout.prop(self, "scheduler")
        for reason in (bake_unavailable_reason(), fit_unavailable_reason()):
            if reason:
                layout.label(text=reason, icon="ERROR")


def preferences(context=None) -> ClothLightPreferences | None:
    """This add-on's preferences, or None when it is not enabled as an extension."""
    context = context or bpy.context
    addon = context.preferences.addons.get(ClothLightPreferences.bl_idname)
    return addon.preferences if addon else None


def cache_directory(context=None) -> str:
    """Folder for baked tables: the preference if set, else the extension's user cache folder
    (in development, outside an extension, the bake's own default cache)."""
    from precompute.cache import entries as cache
    prefs = preferences(context)
    if prefs and prefs.cache_dir:
        return bpy.path.abspath(prefs.cache_dir)
    if not EXTENSION_PACKAGE:
        return str(cache.default_cache_dir())
    return bpy.utils.extension_path_user(EXTENSION_PACKAGE, path="cache", create=True)


def fit_directory() -> str:
    """Where a fit writes when the panel names no folder: ``fits/`` in the extension's user folder
    (in development, in the user cache folder)."""
    from precompute.cache import entries as cache
    folder = _user_folder("fits")
    if folder is None:
        return str(cache.default_cache_dir() / "fits")
    return folder


def _user_folder(name: str) -> str | None:
    """The folder ``name`` of the extension's user folder (created), or None in development."""
    if not EXTENSION_PACKAGE:
        return None
    return bpy.utils.extension_path_user(EXTENSION_PACKAGE, path=name, create=True)


def numba_cache_directory(in_blender: bool = False) -> str | None:
    """Where numba keeps ClothLight's compiled kernels: the extension's user folder, since an extension
    must not write into its own folder.  None in development (numba's default, next to the sources).

    The bake child and Blender's own process (``in_blender``) each have their own folder, so that
    neither loads a kernel while the other writes it.  Both import the kernels as ``precompute.…``
    (the extension's root ``__init__.py``), the name a cached kernel records."""
    return _user_folder("numba_blender" if in_blender else "numba")


def bytecode_cache_directory() -> str | None:
    """Where the bake child keeps Python bytecode (its ``PYTHONPYCACHEPREFIX``): the extension's user
    folder.  None in development (Python's default, ``__pycache__`` next to the sources)."""
    return _user_folder("pycache")


class _NumbaCache:
    """The folder :func:`use_user_numba_cache` gave numba (None: it changed nothing)."""

    folder: str | None = None


def use_user_numba_cache() -> None:
    """Point numba's cache at :func:`numba_cache_directory` in Blender's own process.

    The add-on imports no numba when it is enabled, but a validation sweep or a garment job run in
    Blender's process imports precompute's ``cache=True`` kernels, and numba would write its index
    files — at the least an empty ``__pycache__`` — next to their sources, inside the extension.
    numba reads ``NUMBA_CACHE_DIR`` when it is imported (and again before each compilation), and a
    kernel picks its cache folder when it is defined, so the folder is set here, at enable time,
    before anything of the add-on can import numba; where another add-on imported numba already,
    its configuration is set too.  A folder the user (or another add-on) chose is kept.  In
    development nothing changes (numba caches next to the sources, as in every other process).
    """
    import sys

    folder = numba_cache_directory(in_blender=True)
    numba = sys.modules.get("numba")
    if folder is None or os.environ.get("NUMBA_CACHE_DIR") or (numba is not None and numba.config.CACHE_DIR):
        return
    os.environ["NUMBA_CACHE_DIR"] = folder
    if numba is not None:
        numba.config.CACHE_DIR = folder
    _NumbaCache.folder = folder


def restore_numba_cache() -> None:
    """Undo :func:`use_user_numba_cache` (kernels defined meanwhile keep the folder they picked)."""
    import sys

    folder, _NumbaCache.folder = _NumbaCache.folder, None
    if folder is None:
        return
    if os.environ.get("NUMBA_CACHE_DIR") == folder:
        del os.environ["NUMBA_CACHE_DIR"]
    numba = sys.modules.get("numba")
    if numba is not None and numba.config.CACHE_DIR == folder:
        numba.config.CACHE_DIR = ""
