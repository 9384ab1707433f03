"""MuJoCo's own time stepping of a case's scene (engines.mujoco_adapter): its integrators, with the armature that
holds the prescribed motions put back (the evaluation model has none), rollouts, and the scene's twin with its
approximations of the case's physics doubled, whose runs measure their effect."""

import copy
import time

import mujoco
import mujoco.rollout
import numpy as np

from engines import coordinates, euler

# MuJoCo prints a line for each run that blows up, and the studies blow runs up on purpose: each
# is reported instead as an unstable row, from the warnings MuJoCo counts in its data.
mujoco.set_mju_user_warning(lambda message: None)

INTEGRATORS = {"Euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
               "RK4": mujoco.mjtIntegrator.mjINT_RK4}


class MujocoStepping:
    """MujocoModel's runs with MuJoCo's integrators, on its evaluation model `m` and data `d`, with `armature` (the
    scene's, put back for stepping), the driven dofs and their motions, the applied forces and the loops."""

    def approximations_doubled(self, scales):
        """This scene with its approximations of the case's physics doubled: some bodies' mass and inertia
        scaled, {body: (mass factor, inertia factor)} (set in the compiled model, which MuJoCo checks only
        when it compiles; mj_setConst redoes what follows), the armature that holds the prescribed
        motions halved (they drift by torque x time / armature), and the softness of the loops' constraints
        doubled (MujocoLoops.softness_doubled: the only thing by which MuJoCo's own stepping of a loop departs
        from the rigid loop; the evaluations, rigid, keep this scene's MujocoLoops).  A scene with none of them is
        its own twin: this model itself."""
        if not (self.loops.loops or len(self._driven_dofs) or any(factor != 1.0 for pair in scales.values()
                                                                 for factor in pair)):
            return self
        twin = copy.copy(self)
        twin.m = self.loops.softness_doubled() if self.loops.loops else copy.copy(self.m)
        twin.armature = self.armature.copy()
        twin.armature[self._driven_dofs] /= 2
        for name, (mass, inertia) in scales.items():
            twin.m.body_mass[self.body_id(name)] *= mass
            twin.m.body_inertia[self.body_id(name)] *= inertia
        twin.d = mujoco.MjData(twin.m)
        mujoco.mj_setConst(twin.m, twin.d)
        return twin

    def stepping(self, q0, v0, dt, integrator):
        """The scene as MuJoCo steps it from (q0, v0): the model with its armature back and `integrator`
        at step dt, its data, the full physics state, and the constant generalized forces of every
        step: the applied ones (where they are constant; laws of the state are added at each evaluation,
        `_rollout`), and armature x acceleration on each driven joint, which gives the armature the
        prescribed (constant) acceleration."""
        m = copy.copy(self.m)
        m.dof_armature[:] = self.armature
        m.opt.timestep = dt
        m.opt.integrator = INTEGRATORS[integrator]
        m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_SENSOR  # a run's sensor readings are never read
        d = mujoco.MjData(m)
        self._set_state(0.0, q0, v0, d)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state0 = np.empty(mujoco.mj_stateSize(m, spec))
        mujoco.mj_getState(m, d, state0, spec)
        forces = np.zeros(m.nv) if self.varying else self.applied.copy()
        forces[self._driven_dofs] += self.armature[self._driven_dofs] * self._driven_motion[2]
        return m, d, state0, forces

    def step(self, q0, v0, t_end, dt, integrator):
        """mj_step with `integrator` from (q0, v0); times, book q and v of every step, and the cost."""
        times, qpos, qvel, elapsed, warnings = self._rollout(q0, v0, t_end, dt, integrator)
        nstep = len(times) - 1
        q, v = self._book_states(qpos, qvel, q0)
        # How well the armatures held the prescribed rates, relative to the largest rate of the run,
        # prescribed or free (a prescribed motion may be at rate 0, or nearly).
        prescribed = self._driven_motion[1] + self._driven_motion[2] * times[:, None]
        drift = np.max(np.abs(qvel[:, self._driven_dofs] - prescribed), initial=0.0)
        # (rad/s, or m/s for a slider: at rest, the drift in SI units)
        scale = max(np.max(np.abs(prescribed), initial=0.0), np.max(np.abs(qvel), initial=0.0), 1.0)
        driven_error = float(drift / scale if scale > 0 else drift)
        return {"t": times, "q": q, "v": v, **elapsed, "steps": nstep, "warnings": warnings,
                "evaluations": nstep * (4 if integrator == "RK4" else 1), "driven_rate_error": driven_error}

    def ball_joint_quaternions(self, q0, v0, t_end, dt, integrator):
        """The (w, x, y, z) quaternion of the scene's ball joint at every step of `step`'s run from (q0, v0),
        the start included: MuJoCo's own orientation, free of the Euler angles' singularity."""
        qadr, _ = coordinates.lone_ball_joint(self.path, self.layout, self.driven, "ball_joint_quaternions")
        return self._rollout(q0, v0, t_end, dt, integrator)[1][:, qadr:qadr + 4]

    def _rollout(self, q0, v0, t_end, dt, integrator):
        """mj_step with `integrator` from the book's (q0, v0) to t_end, in MuJoCo's own coordinates: times,
        qpos and qvel of every step (the start included), the rollout's wall and CPU time ({"wall", "cpu"}:
        the process's CPU seconds, which other processes' load leaves out), and the warnings MuJoCo
        counted (a NaN or huge state, which it answers by resetting) in the data the rollout stepped."""
        m, d, state0, forces = self.stepping(q0, v0, dt, integrator)
        nstep = int(round(t_end / dt))
        start, start_cpu = time.perf_counter(), time.process_time()
        if self.varying:
            states = self._stepped(m, d, state0, forces, nstep, q0)
        else:
            states, _ = mujoco.rollout.rollout(m, d, state0[None], forces[None, None], nstep=nstep,
                                               control_spec=mujoco.mjtState.mjSTATE_QFRC_APPLIED)
            states = states[0]
        elapsed = {"wall": time.perf_counter() - start, "cpu": time.process_time() - start_cpu}
        states = np.concatenate([state0[None], states])
        warnings = {mujoco.mjtWarning(i).name: (w.number, w.lastinfo) for i, w in enumerate(d.warning) if w.number}
        return states[:, 0], states[:, 1:1 + m.nq], states[:, 1 + m.nq:1 + m.nq + m.nv], elapsed, warnings

    def _stepped(self, m, d, state0, forces, nstep, q0):
        """mj_step `nstep` times from state0 with applied forces that are laws of the state: MuJoCo's control
        callback sets them at every evaluation, each stage of RK4 included (at the stage's time and state),
        on top of the constant `forces`.  The full physics state after each step, as `rollout` gives it."""
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        states = np.empty((nstep, len(state0)))

        def control(m, d):
            q, v = self._book_states(d.qpos[None], d.qvel[None], q0)
            try:
                d.qfrc_applied[:] = forces + self._applied_at(d.time, q[0], v[0])
            except (ArithmeticError, ValueError):  # a law that fails here: MuJoCo's divergence check stops the run
                d.qfrc_applied[:] = np.nan

        mujoco.set_mjcb_control(control)  # MuJoCo's one global callback: set for this run only
        try:
            for i in range(nstep):
                mujoco.mj_step(m, d)
                mujoco.mj_getState(m, d, states[i], spec)
        finally:
            mujoco.set_mjcb_control(None)
        return states

    def _book_states(self, qpos, qvel, q0):
        q = np.zeros((len(qpos), len(self.coords)))
        v = np.zeros_like(q)
        for kind, (qadr, dof), idx in self.layout:
            if kind == "scalar":
                q[:, idx[0]], v[:, idx[0]] = qpos[:, qadr], qvel[:, dof]
                continue
            with np.errstate(all="ignore"):  # a blown-up run is reported by the caller
                q[:, idx] = euler.angles(qpos[:, qadr:qadr + 4], q0[idx])
                v[:, idx] = euler.euler_rates(q[:, idx], qvel[:, dof:dof + 3])
        return q, v
