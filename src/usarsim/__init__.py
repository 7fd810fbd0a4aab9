"""usarsim: a USARSim-compatible robot simulator on MuJoCo."""

import os as _os
import sys as _sys

__version__ = "0.1.0"

# Cameras are rendered offscreen: on a Linux machine without a display, through EGL (Mesa's
# software renderer where there is no GPU).  MUJOCO_GL set by the user wins.
if _sys.platform.startswith("linux") and not _os.environ.get("DISPLAY"):
    _os.environ.setdefault("MUJOCO_GL", "egl")
