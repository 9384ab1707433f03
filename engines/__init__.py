"""Engine adapters: MuJoCo (MJCF), Pinocchio (URDF or MJCF) and, where the optional extra is installed, Drake (MJCF
or URDF, drake_adapter: docs/drake.md) behind the model interface (docs/model-interface.md).

The only importers of `mujoco`, `pinocchio` and `pydrake`: what the rest of dyncheck needs of an engine is an adapter
method (mujoco_adapter, pinocchio_adapter, drake_adapter) or a bare-engine loop for timing (bench).  mjcf_joints
reads the MJCF joint values that Pinocchio's and Drake's parsers drop.  euler holds the book's
Euler angles of a ball joint; scene, what a scene file may hold; render, the bodies' positions at an animation's
frames and MuJoCo's renderer for them.
"""

import os

# MuJoCo's import opens an OpenGL library (GLFW, through cffi: a quarter of a second, a third of MuJoCo's import)
# unless MUJOCO_GL turns its renderer off.  Its renderer draws only where MUJOCO_GL asks for egl or osmesa
# (dyncheck.pages.animation), so where MUJOCO_GL is unset it is off, before any module here imports MuJoCo.
os.environ.setdefault("MUJOCO_GL", "disable")
