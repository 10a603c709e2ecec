"""Shared test set-up.

Blender keeps user state (preferences, installed extensions) in its user
resource folder; tests point it at a throw-away folder before anything imports
bpy, so they never touch a real Blender installation's settings.
"""

import os
import tempfile

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="clothlight-blender-user-"))
