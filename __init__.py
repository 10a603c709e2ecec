"""Blender extension entry point: the add-on lives in the ``clothlight`` package.

Blender imports this folder as ``bl_ext.<repo>.clothlight``: the add-on's modules import each other
relatively from there, and import the physics, which needs no Blender, as the top-level package
``precompute`` — as they do in development and in the bake's child process, where this folder is on
the import path.  In Blender's own process :func:`_import_precompute_from` gives that name to this
folder's copy, the one place that knows the difference.
"""

import importlib.machinery


class _SourceFileLoaderWithoutBytecode(importlib.machinery.SourceFileLoader):
    """A source loader that stores no bytecode (``set_data`` is how a source loader stores it, and all
    it stores)."""

    def set_data(self, path, data, *, _mode=0o666):
        pass


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

    def finder_without_bytecode(path: str):
        if not path or not inside(path):
            raise ImportError("not a folder of the ClothLight extension")
        return importlib.machinery.FileFinder(
            path, (_SourceFileLoaderWithoutBytecode, importlib.machinery.SOURCE_SUFFIXES))

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


def _import_precompute_from(root: str) -> None:
    """Make ``import precompute`` import the package in the extension's folder ``root``.

    The add-on imports ``precompute`` by its own name, so that its imports are plain ones a reader
    (and the import-graph test) can follow, and run one way: the add-on on the physics, never back.
    Outside Blender that name is found on the import path; inside, the extension's folder is not on
    it, and an extension must not put it there (Blender's extension rules: ``sys.path`` is every
    add-on's).  So a finder, asked first, answers for that one name only, with this folder's
    ``precompute/``; its submodules follow from the package's own path, through the loader without
    bytecode (:func:`_load_without_bytecode`).  Modules of an earlier copy of this folder (an
    update installed while Blender runs) are dropped first, so that the new code is what runs.
    """
    import importlib.abc
    import importlib.util
    import os
    import sys

    package = os.path.join(os.path.realpath(root), "precompute")

    class PrecomputeFinder(importlib.abc.MetaPathFinder):
        clothlight_root = root

        def find_spec(self, name, path=None, target=None):
            if name != "precompute":
                return None
            init = os.path.join(package, "__init__.py")
            return importlib.util.spec_from_file_location(name, init, submodule_search_locations=[package],
                                                          loader=_SourceFileLoaderWithoutBytecode(name, init))

    sys.meta_path[:] = [finder for finder in sys.meta_path if getattr(finder, "clothlight_root", None) != root]
    sys.meta_path.insert(0, PrecomputeFinder())
    for name in [name for name in sys.modules if name == "precompute" or name.startswith("precompute.")]:
        file = getattr(sys.modules[name], "__file__", None) or ""
        if os.path.realpath(file).startswith(package + os.sep):
            del sys.modules[name]


def register() -> None:
    from .clothlight.blender import registration

    registration.register()


def unregister() -> None:
    from .clothlight.blender import registration

    registration.unregister()


# pytest imports this file as a top-level module when the checkout's folder name is no Python
# identifier (a `mktemp -d` clone): there is no package to import relatively from, and nothing to register.
if __package__:
    if __package__.startswith("bl_ext."):
        _load_without_bytecode(__path__[0], globals().get("__cached__"))
        _import_precompute_from(__path__[0])
