"""Bare-engine loops for `dyncheck bench`: the work a user of MuJoCo, Pinocchio or Drake alone does for a case's
scene, to time the harness against (see dyncheck/bench.py).  Drake is optional: `drake_steps` takes a DrakeModel,
and this module imports no pydrake."""

import mujoco
import mujoco.rollout
import numpy as np
import pinocchio as pin

FULL_PHYSICS, APPLIED = mujoco.mjtState.mjSTATE_FULLPHYSICS, mujoco.mjtState.mjSTATE_QFRC_APPLIED


class MujocoLoops:
    """MuJoCo alone on the scene as `MujocoModel.step` steps it from the book's (q0, v0): the model with its
    armature back, `integrator` at step dt, the same constant generalized forces at every step."""

    def __init__(self, model, q0, v0, dt, integrator):
        if model.varying:  # a bare loop has no law of the state to evaluate: nothing alike to time against
            raise ValueError(f"{model.path}: dyncheck bench times scenes whose applied forces are constant; this "
                             "one's depend on the state")
        self.model, self.dt, self.integrator = model, dt, integrator
        self.m, self.d, self.start, self.forces = model.stepping(q0, v0, dt, integrator)
        # the data a rollout steps, on one thread or on two (made here, outside the timed calls)
        self.data = {1: self.d, 2: [mujoco.MjData(self.m) for _ in range(2)]}

    def engine_start(self, q0, v0):
        """MuJoCo's full physics state at the book's (q0, v0): a start for `rollout`."""
        return self.model.stepping(q0, v0, self.dt, self.integrator)[2]

    def mj_step(self, nstep):
        """One mj_step call stepping nstep steps from the start."""
        mujoco.mj_setState(self.m, self.d, self.start, FULL_PHYSICS)
        self.d.qfrc_applied[:] = self.forces
        mujoco.mj_step(self.m, self.d, nstep=nstep)

    def rollout(self, nstep, starts=None, threads=1):
        """`mujoco.rollout` of nstep steps from each of `starts` (engine states; default the start), on 1 or 2
        threads."""
        starts = self.start[None] if starts is None else starts
        mujoco.rollout.rollout(self.m, self.data[threads], starts, self.forces[None, None], nstep=nstep,
                               control_spec=APPLIED)


def pinocchio_steps(model, engine_states):
    """Pinocchio's engine step (`PinocchioModel.engine_dynamics`) at each of `engine_states`, (configuration,
    velocity) pairs already in its own coordinates (`PinocchioModel.engine_state`)."""
    return [model.engine_dynamics(config, velocity, model.applied) for config, velocity in engine_states]


def pinocchio_rhs(model, q0, v0, work):
    """A right-hand side written for Pinocchio alone, and its initial state at the book's (q0, v0): the free
    joints' positions and rates, made a configuration by `pin.integrate` from the neutral one, or a lone ball
    joint's quaternion and angular velocity.  Like the harness's, its last component is the drive power if
    `work` (anything does work on the scene), else 0."""
    m, n = model.m, len(model.coords)
    if any(kind == "euler" for kind, _, _ in model.layout):  # the top: Pinocchio's quaternion (x, y, z, w), and w
        assert len(model.layout) == 1 and not model.driven, "a bare right-hand side for a lone ball joint only"

        def rhs(t, y):
            config, w = y[:4], y[4:7]
            (qx, qy, qz, qw), (wx, wy, wz) = config, w
            turning = 0.5 * np.array([qw * wx + qy * wz - qz * wy, qw * wy + qz * wx - qx * wz,
                                      qw * wz + qx * wy - qy * wx, -(qx * wx + qy * wy + qz * wz)])
            return np.concatenate([turning, model.engine_dynamics(config, w, model.applied)[0],
                                   [model.applied @ w if work else 0.0]])

        return rhs, np.concatenate([*model.engine_state(0.0, q0, v0), [0.0]])

    # the book's coordinates of these scenes are the free joints' positions
    coord = np.array([idx[0] for _, _, idx in model.layout], dtype=int)
    coord_v = np.array([joint.idx_v for _, joint, _ in model.layout], dtype=int)
    driven_v = np.array([joint.idx_v for joint, _ in model.driven], dtype=int)
    start, rate, acc = np.array([motion for _, motion in model.driven]).reshape(-1, 3).T

    def rhs(t, y):
        position, velocity = np.empty(m.nv), np.empty(m.nv)
        position[coord_v], velocity[coord_v] = y[coord], y[n + coord]
        position[driven_v], velocity[driven_v] = start + rate * t + 0.5 * acc * t**2, rate + acc * t
        accelerations, tau = model.engine_dynamics(pin.integrate(m, model.neutral, position), velocity, model.applied)
        power = tau[driven_v] @ velocity[driven_v] + model.applied @ velocity if work else 0.0
        out = np.empty(2 * n + 1)
        out[:n], out[n + coord], out[-1] = y[n:2 * n], accelerations[coord_v], power
        return out

    return rhs, np.concatenate([q0, v0, [0.0]])


def drake_steps(model, engine_states):
    """Drake's engine step (`DrakeModel.engine_dynamics`: its mass matrix and inverse dynamics, the free block solved)
    at each of `engine_states`, (positions, velocities) pairs already in Drake's own coordinates
    (`DrakeModel.engine_state`)."""
    if model.varying:  # a bare loop has no law of the state to evaluate (as MujocoLoops)
        raise ValueError(f"{model.path}: the bare Drake step takes constant applied forces; this scene's depend on the "
                         "state")
    return [model.engine_dynamics(positions, velocities, model.applied) for positions, velocities in engine_states]
