"""Engine adapters: MuJoCo (MJCF), Pinocchio (URDF or MJCF) and, where the optional extra is installed, Drake (MJCF
or URDF, drake_adapter: docs/drake.md) behind the model interface (docs/model-interface.md).

The only importers of `mujoco`, `pinocchio` and `pydrake`: what the rest of dyncheck needs of an engine is an adapter
method (mujoco_adapter, pinocchio_adapter, drake_adapter) or a bare-engine loop for timing (bench).  Each adapter is
split by job: its model, state, interface and linearisation in *_adapter; its reading and writing of the scene file
in *_scene; MuJoCo's own stepping in mujoco_stepping, Drake's loops in drake_loops (MuJoCo's and Pinocchio's in
loops).  What the adapters share: bindings, the place of a parameter in a scene and a body's inertia there;
coordinates, the case's coordinates on an engine's dofs and the linearisation's errors; mjcf_joints, what Pinocchio's
and Drake's read of a file's text (the MJCF joint values their parsers drop, the inertial frames).  euler holds the
book's Euler angles of a ball joint; scene, what a scene file may hold and the bodies as the adapters describe them;
mjcf, what an MJCF holds (for a case derived from it); render, the bodies' positions at an animation's frames and
MuJoCo's renderer for them.
"""

import os

# MuJoCo's import opens an OpenGL library (GLFW, through cffi: a quarter of a second, a third of MuJoCo's import)
# unless MUJOCO_GL turns its renderer off.  Its renderer draws only where MUJOCO_GL asks for egl or osmesa
# (dyncheck.pages.animation), so where MUJOCO_GL is unset it is off, before any module here imports MuJoCo.
os.environ.setdefault("MUJOCO_GL", "disable")
