"""Shared fixtures of the simulation tests."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # before anything imports mujoco (rendering tests)
