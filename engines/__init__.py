"""Engine adapters: MuJoCo (MJCF) and Pinocchio (URDF) behind the model interface (docs/model-interface.md).

The only importers of `mujoco` and `pinocchio`: what the rest of dyncheck needs of an engine is an adapter
method (mujoco_adapter, pinocchio_adapter) or a bare-engine loop for timing (bench).  euler holds the book's
Euler angles of a ball joint; scene, what a scene file may hold; render, the bodies' positions at an animation's
frames and MuJoCo's renderer for them.
"""
