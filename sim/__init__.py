"""MuJoCo simulation: models built from example-robot-data URDFs, scenes, the MuJoCo device.

Offscreen rendering needs an OpenGL platform chosen before ``mujoco`` is imported; headless
machines have EGL (Mesa llvmpipe), so ``MUJOCO_GL`` defaults to ``egl`` here (set it before
importing ``sim`` to choose ``osmesa`` or ``glfw``).
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
