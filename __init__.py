"""Blender extension entry point: the add-on lives in the ``clothlight`` package.

Blender imports this folder as ``bl_ext.<repo>.clothlight``; everything inside
is imported relatively from there.
"""


def _load_without_bytecode(root: str, cached: str | None) -> None:
    """Make Python write no bytecode into the extension's folder ``root``.

    An extension writes nothing into its own folder (Blender replaces it on update, removes it with
    the extension, and may install it read-only), and Python's bytecode is no exception: Blender
    imports with bytecode on, so every module imported from here would leave ``__pycache__/*.pyc``
    beside it.  The process-wide switches are not this extension's to turn: ``sys.dont_write_bytecode``
    would take bytecode from every add-on and library in Blender, ``sys.pycache_prefix`` would move
    all of it into one folder.  So the change stays inside ``root``: a path hook, asked first for any
    folder, gives those inside ``root`` a finder whose source loader writes no bytecode (``set_data``
    is how a source loader stores bytecode, and all it stores).  The add-on's modules then compile
    from source at every start (about 0.1 s for the ~55 modules enabling imports).  Everything else
    is untouched.

    This file itself was imported — and its bytecode ``cached`` written — before any line of it ran;
    that one file is removed again (with its ``__pycache__`` folder when nothing else is in it).
    Nothing here runs outside Blender (``bl_ext.`` packages only), nor in the bake's child process,
    which gets ``PYTHONPYCACHEPREFIX`` instead (``clothlight.jobs.BakeJob``).
    """
    import importlib.machinery
    import os
    import sys

    root = os.path.realpath(root)

    def inside(path: str) -> bool:
        real = os.path.realpath(path)
        return real == root or real.startswith(root + os.sep)

    class SourceFileLoaderWithoutBytecode(importlib.machinery.SourceFileLoader):
        def set_data(self, path, data, *, _mode=0o666):
            pass

    def finder_without_bytecode(path: str):
        if not path or not inside(path):
            raise ImportError("not a folder of the ClothLight extension")
        return importlib.machinery.FileFinder(
            path, (SourceFileLoaderWithoutBytecode, importlib.machinery.SOURCE_SUFFIXES))

    finder_without_bytecode.clothlight_root = root
    # Once per folder, also when Blender imports this file again (a reload after an update).
    sys.path_hooks[:] = [hook for hook in sys.path_hooks if getattr(hook, "clothlight_root", None) != root]
    sys.path_hooks.insert(0, finder_without_bytecode)
    for path in [path for path in sys.path_importer_cache if isinstance(path, str) and path and inside(path)]:
        del sys.path_importer_cache[path]
    if cached and inside(cached):
        try:
            os.remove(cached)
            os.rmdir(os.path.dirname(cached))
        except OSError:
            pass  # not written (bytecode off, a read-only folder), or other files beside it


# pytest imports this file as a top-level module when the checkout's folder name is no Python
# identifier (a `mktemp -d` clone): there is no package to import relatively from, and nothing to register.
if __package__:
    if __package__.startswith("bl_ext."):
        _load_without_bytecode(__path__[0], globals().get("__cached__"))
    from .clothlight import register, unregister  # noqa: F401
