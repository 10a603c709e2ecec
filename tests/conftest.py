"""Shared test set-up.

Blender keeps user state (preferences, installed extensions) in its user
resource folder; tests point it at a throw-away folder before anything imports
bpy, so they never touch a real Blender installation's settings.
"""

import atexit
import os
import shutil
import tempfile

if "BLENDER_USER_RESOURCES" not in os.environ:
    _user_resources = tempfile.mkdtemp(prefix="clothlight-blender-user-")
    os.environ["BLENDER_USER_RESOURCES"] = _user_resources
    atexit.register(shutil.rmtree, _user_resources, ignore_errors=True)
