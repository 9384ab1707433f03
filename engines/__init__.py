"""Engine adapters: MuJoCo (MJCF) and Pinocchio (URDF) behind the model interface of DESIGN.md."""
