"""MuJoCo adapter: a case's MJCF scene behind the model interface, in the book's coordinates.

Prescribed joints ("driven") are handled exactly in the pointwise evaluations:
their accelerations are imposed and only the free block of the mass matrix is
solved, so the evaluation model carries no armature at all.  For time stepping
with MuJoCo's own integrators the scene's armature is put back: a very large
armature on the driven joints, pushed by armature x the prescribed acceleration,
so that the reaction torques of the free motion change their rates by about
torque * time / armature (< 1e-11 rad/s).  Its
kinetic energy (~1e14 J) is never part of `energy`: subtracting it would
cancel every digit of the scene's ~1 J.

This module holds the model: its construction, the state of MuJoCo's data at the case's states, the model
interface and the linearisation.  engines.mujoco_scene reads and writes the scene file; engines.mujoco_stepping
steps it with MuJoCo's own integrators.
"""

import math

import mujoco
import numpy as np

from engines import coordinates, euler, scene as scene_rules
from engines.linalg import linear_solution
from engines.loops import MujocoLoops
from engines.mujoco_scene import MujocoScene, refuse_nan, unmodelled, write_all
from engines.mujoco_stepping import MujocoStepping

CLOSURES = 4096
"""How many closures of a scene's loops from its assembly a model keeps (`_close`)."""


class MujocoModel(MujocoScene, MujocoStepping):
    """scene (from the case, a dyncheck.case.scene.Scene, read by attribute): `layout` (the joints the book's coordinates move: a
    hinge or slide, or a ball joint in the book's Euler angles), `driven` (joint -> its prescribed motion),
    `applied` (joint -> its generalized force in the joint's frame, a function force(t, q, v) of the case's state
    with an attribute `constant`), `dependent` (the joints that close the scene's loops, engines.loops: no
    coordinate of their own), `reactions` (name -> its sensor, axis and frame: a loop's force where `sensor` names a
    <connect>), `points` (name -> its body and frame), `paths` (bodies).

    A scene with loops is evaluated on its closed states: the independent joints at the case's coordinates, the
    dependent ones solved (MujocoLoops.close), the accelerations and loop forces MuJoCo's rigid ones
    (MujocoLoops.constrained); MuJoCo steps it with its own soft constraint, whose effect on a run
    `approximations_doubled` measures (the softness doubled)."""

    def __init__(self, path, scene, writes=()):
        self.path = str(path)
        try:
            spec = mujoco.MjSpec.from_file(self.path)
            write_all(spec, writes)
            self.m = spec.compile()
        except (ValueError, KeyError) as error:
            raise ValueError(f"{self.path}: {error}") from error
        refuse_nan(self.path)
        self.loops = MujocoLoops(self.m, self.path)  # refuses an equality that is not a loop's <connect>
        self.armature = self.m.dof_armature.copy()
        self.d = mujoco.MjData(self.m)
        self._grounds_potential = self._potential_of_grounds()
        self.coords = tuple(scene.coords)
        self.reaction_names = tuple(scene.reactions)
        self.layout = [(c.kind, self._joint(c.joint), list(c.indices)) for c in scene.layout]
        self.free = np.array([dof for _, (_, dof), idx in self.layout for dof in range(dof, dof + len(idx))], dtype=int)
        # the joints as engines.coordinates takes them: (kind, first dof, coordinate indices)
        self._dof_layout = [(kind, dof, idx) for kind, (_, dof), idx in self.layout]
        self.driven = [(self._joint(j), (law.angle, law.rate, law.acc)) for j, law in scene.driven.items()]
        # after the case's joints are found: a renamed joint is missing before it is extra
        unmodelled_element = next(unmodelled(self.m, scene), None)
        if unmodelled_element:
            raise scene_rules.refusal(self.path, "MJCF", *unmodelled_element)
        if self.loops.loops:
            self._refuse_unclosable(scene)
        # The evaluations' mj_forward under one integrator: the file's "discrete" changes a loop's accelerations
        # (by 51 rad/s^2 of the slider-crank's phi''); the others give the same numbers.  Runs set their own (`stepping`).
        self.m.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
        if not self.m.neq:
            # No constraint row can arise but a loop's (`unmodelled` refuses contacts, joint limits, friction loss,
            # tendons): MuJoCo's constraint stage, a sixth of an RK4 step here, would find none.  The same numbers.
            self.m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
        for (_, dof), _ in self.driven:  # the evaluation model imposes these exactly: no armature
            self.m.dof_armature[dof] = 0.0
        self.forces = [(self._joint(joint)[1], force) for joint, force in scene.applied.items()]
        # Constant applied forces are evaluated once (`applied`); laws of the state at every evaluation.
        self.varying = not all(force.constant for _, force in self.forces)
        self.applied = None if self.varying else self._applied_at(0.0, np.zeros(len(self.coords)),
                                                                   np.zeros(len(self.coords)))
        self._driven_dofs = np.array([dof for (_, dof), _ in self.driven], dtype=int)
        self._driven_motion = np.array([motion for _, motion in self.driven]).reshape(-1, 3).T  # q0, rate, acc
        self._driven_qacc = np.zeros(self.m.nv)
        self._driven_qacc[self._driven_dofs] = self._driven_motion[2]
        self.loop_names = [loop.name for loop in self.loops.loops]
        self.reaction_specs = {name: (self._reaction_sensor(name, spec) if spec.sensor not in self.loop_names
                                      else ("loop", self.loop_names.index(spec.sensor)), spec.axis, spec.frame)
                               for name, spec in scene.reactions.items()}
        self.independent = [(c.joint, self._joint(c.joint)) for c in scene.layout if c.kind == "scalar"]
        self._closures = {}  # `_assembled`'s
        self.dependent_joints = [(joint, self._joint(joint)) for joint in scene.dependent]
        self.point_specs = {name: (self.body_id(spec.body), spec.frame, spec.kind)
                            for name, spec in scene.points.items()}
        self.paths = [self.body_id(b) for b in scene.paths]

    def _potential_of_grounds(self):
        """The potential energy of the bodies welded to the world (a ground, a URDF base link), a constant in
        MuJoCo's that Pinocchio's readers, which fold them into the world, do not count: `_energy` leaves it out."""
        mujoco.mj_kinematics(self.m, self.d)
        return -sum(float(self.m.body_mass[b] * (self.m.opt.gravity @ self.d.xipos[b]))
                    for b in range(1, self.m.nbody) if self.m.body_weldid[b] == 0)

    def _refuse_unclosable(self, scene):
        """ValueError for a loop scene that dyncheck cannot evaluate: prescribed motions or a ball joint (not yet
        modelled with loops), or coordinates that are not the scene's degrees of freedom at its assembly (qpos0):
        nv less the loops' rank."""
        if self.driven or any(kind != "scalar" for kind, _, _ in self.layout):
            raise ValueError(f"{self.path}: a scene with closed loops ({', '.join(l.name for l in self.loops.loops)}) "
                             "is evaluated with hinges and slides that the case's coordinates move or the loops "
                             "close; prescribed motions and ball joints in it are not supported yet")
        freedom = self.loops.freedom()
        if freedom != len(self.coords):
            raise ValueError(f"{self.path}: the loops ({', '.join(l.name for l in self.loops.loops)}) leave "
                             f"{freedom} of the {self.m.nv} joints' degrees of freedom at the assembly (qpos0), but "
                             f"the case has {len(self.coords)} coordinates ({', '.join(self.coords)})")

    # -- names -------------------------------------------------------------
    def _id(self, kind, name):
        i = mujoco.mj_name2id(self.m, kind, name)
        if i < 0:
            raise ValueError(f"{self.path}: no {kind.name[6:].lower()} named '{name}'")
        return i

    def body_id(self, name):
        return self._id(mujoco.mjtObj.mjOBJ_BODY, name)

    def _joint(self, name):
        """(qpos address, dof address) of a joint."""
        j = self._id(mujoco.mjtObj.mjOBJ_JOINT, name)
        return int(self.m.jnt_qposadr[j]), int(self.m.jnt_dofadr[j])

    # -- state -------------------------------------------------------------
    def _engine_states(self, t, q, v):
        """MuJoCo's qpos and qvel of the book's state (t, q, v), or of many: t of shape (N,), q and v (N, n).
        A loop over the few joints: on one state, scalar writes cost less than index arrays."""
        qpos, qvel = np.empty(q.shape[:-1] + (self.m.nq,)), np.zeros(v.shape[:-1] + (self.m.nv,))
        qpos[...] = self.m.qpos0
        for kind, (qadr, dof), idx in self.layout:
            if kind == "scalar":
                qpos[..., qadr], qvel[..., dof] = q[..., idx[0]], v[..., idx[0]]
            else:
                qpos[..., qadr:qadr + 4] = euler.quaternion(q[..., idx])
                qvel[..., dof:dof + 3] = euler.angular_velocity(q[..., idx], v[..., idx])
        for (qadr, dof), (q0, rate, acc) in self.driven:
            qpos[..., qadr] = q0 + rate * t + 0.5 * acc * t**2
            qvel[..., dof] = rate + acc * t
        if self.loops.loops:
            self._close(qpos, qvel)
        return qpos, qvel

    def _close(self, qpos, qvel):
        """`qpos` and `qvel` (as in `_engine_states`) with the dependent joints closing every loop, in place: each
        state solved from the one before (the first from the assembly), so that a run's states stay on one branch."""
        start = None
        for i in np.ndindex(qpos.shape[:-1]):
            positions = {joint: qpos[i][qadr] for joint, (qadr, _) in self.independent}
            rates = {joint: qvel[i][dof] for joint, (_, dof) in self.independent}
            qpos[i], qvel[i] = (self._assembled(positions, rates) if start is None
                                else self.loops.close(positions, rates, start))
            start = qpos[i]

    def _assembled(self, positions, rates):
        """self.loops.close(positions, rates) from the assembly, the last CLOSURES kept by their values' bits: a
        state's accelerations, reactions and energy, each evaluated on its own, close it alike, from the assembly
        (a twin, `approximations_doubled`, shares them with its loops)."""
        key = np.array([*positions.values(), *rates.values()]).tobytes()
        if key not in self._closures:
            if len(self._closures) == CLOSURES:
                del self._closures[next(iter(self._closures))]  # the oldest
            self._closures[key] = self.loops.close(positions, rates)
        return self._closures[key]

    def _set_state(self, t, q, v, d=None):
        d = self.d if d is None else d
        d.time = t
        d.qpos[:], d.qvel[:] = self._engine_states(t, np.asarray(q, dtype=float), np.asarray(v, dtype=float))
        d.qfrc_applied[:] = self._applied_many(t, q, v)

    def _applied_at(self, t, q, v):
        """The applied generalized forces at the case's state (t, q, v): every dof's, (nv,)."""
        return coordinates.applied_forces(self.forces, self.m.nv, t, q, v)

    def _applied_many(self, t, q, v):
        """`_applied_at` at one state or many (as in `_engine_states`): (..., nv)."""
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        states = q.shape[:-1]
        if not self.varying:
            return np.broadcast_to(self.applied, states + (self.m.nv,)) if states else self.applied
        t = np.broadcast_to(t, states)
        out = np.empty(states + (self.m.nv,))
        for i in np.ndindex(states):
            out[i] = self._applied_at(t[i], q[i], v[i])
        return out

    def _solve(self, t, q, v):
        """Accelerations of every dof at the book's state, or at many (as in `_engine_states`): driven
        ones imposed, free ones solved from M_ff; with qvel, the mass matrix and the smooth forces.
        Leaves self.d at the (last) state."""
        qpos, qvel = self._engine_states(t, np.asarray(q, dtype=float), np.asarray(v, dtype=float))
        nv, states = self.m.nv, qvel.shape[:-1]
        count = math.prod(states)
        mass, smooth, qacc = np.zeros((count, nv, nv)), np.empty((count, nv)), np.empty((count, nv))
        qacc[:] = self._driven_qacc
        smooth_forces = self.d.qfrc_smooth
        for i in self._each_state(qpos, qvel, self._applied_many(t, q, v)):
            mujoco.mj_forward(self.m, self.d)
            mujoco.mj_fullM(self.m, self.d, mass[i])
            smooth[i] = smooth_forces
            if self.loops.loops:  # MuJoCo's rigid loop, not its soft one (no prescribed joints: refused)
                qacc[i] = self.loops.constrained(self.d)[0]
        mass, smooth, qacc = (x.reshape(states + x.shape[1:]) for x in (mass, smooth, qacc))
        if len(self.free) and not self.loops.loops:
            force = smooth - (mass @ qacc[..., None])[..., 0]
            free_block = mass[..., self.free[:, None], self.free]
            qacc[..., self.free] = linear_solution(free_block, force[..., self.free])
        return qvel, mass, smooth, qacc

    def _each_state(self, qpos, qvel, applied=None):
        """Put each state (rows of qpos, qvel and applied: (..., n)) into self.d in turn, yielding its index in the
        states taken as a flat list.  The views of self.d's arrays are taken once: one costs a sixth of mj_forward."""
        position, velocity, forces = self.d.qpos, self.d.qvel, self.d.qfrc_applied
        qpos, qvel = qpos.reshape(-1, self.m.nq), qvel.reshape(-1, self.m.nv)
        applied = None if applied is None else applied.reshape(-1, self.m.nv)
        for i in range(len(qpos)):
            position[:], velocity[:] = qpos[i], qvel[i]
            if applied is not None:
                forces[:] = applied[i]
            yield i

    def _inverse(self, t, q, v):
        """self.d at the book's state with its accelerations and the sensors of its forces; with loops, MuJoCo's
        rigid loop forces put in (MujocoLoops.impose: its inverse dynamics would give the soft ones), each loop's
        force on its body1 in `self.loop_forces`."""
        qacc = self._solve(t, q, v)[3]
        if self.loops.loops:
            self.loop_forces = self.loops.impose(self.d)
            mujoco.mj_rnePostConstraint(self.m, self.d)
            mujoco.mj_sensorAcc(self.m, self.d)
        else:
            self.d.qacc[:] = qacc
            mujoco.mj_inverse(self.m, self.d)

    # -- model interface ---------------------------------------------------
    def accelerations(self, t, q, v):
        return coordinates.case_accelerations(self._dof_layout, q, v, self._solve(t, q, v)[3])

    def reactions(self, t, q, v):
        self._inverse(t, q, v)
        reactions = self._sensed_reactions(self.d.sensordata, self.d.site_xmat,
                                           self.loop_forces if self.loops.loops else None)
        return {name: float(value) for name, value in reactions.items()}

    def _sensed_reactions(self, sensordata, site_xmat, loop_forces):
        """The reactions in MuJoCo's sensor readings (sensordata), with its sites' frames (site_xmat) and its loop
        forces (`_inverse`), at one state or many (arrays of shape (..., n)): {name: (...)}.  A frame's rotation
        by matmul, one gufunc, which does at many states the arithmetic it does at one."""
        out = {}
        for name, ((adr, site), axis, frame) in self.reaction_specs.items():
            if adr == "loop":  # world axes: the force on the <connect>'s body1 at its anchor
                out[name] = loop_forces[..., site, axis]
                continue
            force = sensordata[..., adr:adr + 3]
            if frame == "world":
                rotation = site_xmat[..., site, :].reshape(force.shape[:-1] + (3, 3))
                force = (rotation @ force[..., None])[..., 0]
            out[name] = force[..., axis].copy()
        return out

    def reactions_many(self, t, q, v):
        """`reactions` at many states, the same numbers: t of shape (N,), q and v (N, n) -> {name: (N,)}.  The
        accelerations of all states solved at once (`_solve`), then mj_inverse state by state, the sensors of all
        read at once; with loops, state by state as `reactions` (each closed from the assembly)."""
        t, q, v = (np.asarray(x, dtype=float) for x in (t, q, v))
        if self.loops.loops:
            rows = [self.reactions(*state) for state in zip(t, q, v)]
            return {name: np.array([row[name] for row in rows]) for name in self.reaction_names}
        qpos, _ = self._engine_states(t, q, v)
        qvel, _, _, qacc = self._solve(t, q, v)
        sensordata, site_xmat = np.empty((len(t), self.m.nsensordata)), np.empty((len(t), self.m.nsite, 9))
        acceleration, readings, frames = self.d.qacc, self.d.sensordata, self.d.site_xmat
        for i in self._each_state(qpos, qvel, self._applied_many(t, q, v)):
            acceleration[:] = qacc[i]
            mujoco.mj_inverse(self.m, self.d)
            sensordata[i], site_xmat[i] = readings, frames
        return self._sensed_reactions(sensordata, site_xmat, None)

    def point_accelerations(self, t, q, v):
        """The named bodies' kinematics, in their own or the world frame: the absolute acceleration
        of the body's origin or of its centre of mass, or the body's angular velocity or angular
        acceleration."""
        self._inverse(t, q, v)
        mujoco.mj_rnePostConstraint(self.m, self.d)
        out = {}
        for name, (body, frame, kind) in self.point_specs.items():
            res = np.zeros(6)
            if kind == "angular velocity":
                mujoco.mj_objectVelocity(self.m, self.d, mujoco.mjtObj.mjOBJ_XBODY, body, res, 0)
                vector = res[:3]
            else:
                at = mujoco.mjtObj.mjOBJ_BODY if kind == "com acceleration" else mujoco.mjtObj.mjOBJ_XBODY
                mujoco.mj_objectAcceleration(self.m, self.d, at, body, res, 0)
                # MuJoCo's cacc is offset by -gravity (the world's cacc), in its linear part only.
                vector = res[:3] if kind == "angular acceleration" else res[3:] + self.m.opt.gravity
            out[name] = self.d.xmat[body].reshape(3, 3).T @ vector if frame == "body" else vector
        return out

    def dependent(self, t, q, v):
        """The dependent joints' positions and rates, {joint: value} each, on the closed state (`_close`)."""
        qpos, qvel = self._engine_states(t, np.asarray(q, dtype=float), np.asarray(v, dtype=float))
        return ({joint: float(qpos[qadr]) for joint, (qadr, _) in self.dependent_joints},
                {joint: float(qvel[dof]) for joint, (_, dof) in self.dependent_joints})

    def mass_matrix(self, t, q, v):
        """The mass matrix in the case's coordinates at (t, q) (engines.coordinates.case_mass_matrix): mj_fullM's in
        the evaluation model, with the armature of a ball joint on the world, as `accelerations` solves it; with
        loops N^T M N, N the every dof's rate per independent rate on the closed state."""
        mass = self._solve(t, q, v)[1]
        if self.loops.loops:
            rates = self.loops.rates(self.d, [dof for _, (_, dof) in self.independent])
            return rates.T @ mass @ rates
        return coordinates.case_mass_matrix(mass, self._dof_layout, q)

    def energy(self, t, q, v):
        self._set_state(t, q, v)
        return self._energy()

    def _energy(self):
        """The energy of self.d's qpos and qvel: what it takes of the forward dynamics is the positions' stage
        (the kinematics and the mass matrix)."""
        mujoco.mj_fwdPosition(self.m, self.d)
        mujoco.mj_energyPos(self.m, self.d)
        mujoco.mj_energyVel(self.m, self.d)
        return float(self.d.energy[0] - self._grounds_potential + self.d.energy[1])

    def energy_many(self, t, q, v):
        """`energy` at many states, the same numbers: t of shape (N,), q and v (N, n) -> (N,); with loops, state by
        state as `energy` (each closed from the assembly)."""
        t, q, v = (np.asarray(x, dtype=float) for x in (t, q, v))
        if self.loops.loops:
            return np.array([self.energy(*state) for state in zip(t, q, v)])
        qpos, qvel = self._engine_states(t, q, v)
        out = np.empty(len(t))
        for i in self._each_state(qpos, qvel):
            out[i] = self._energy()
        return out

    def drive_power(self, t, q, v):
        """Power of the prescribed motions (inverse-dynamics forces), of the applied forces and of the joints'
        dampers (negative): what changes the scene's energy."""
        return float(self.drive_powers(t, q, v))

    def drive_powers(self, t, q, v):
        """`drive_power` at many states at once: t of shape (N,), q and v (N, n) -> (N,)."""
        qvel, mass, smooth, qacc = self._solve(t, q, v)
        applied = self._applied_many(t, q, v)
        # mj_inverse's force, M qacc + bias - passive = M qacc - smooth + applied, from what _solve has
        inverse = (mass @ qacc[..., None])[..., 0] - smooth + applied
        dofs = self._driven_dofs
        dampers = -np.sum(self.m.dof_damping * qvel**2, axis=-1)
        return np.sum(inverse[..., dofs] * qvel[..., dofs], axis=-1) + np.sum(qvel * applied, axis=-1) + dampers

    def ball_joint_acceleration(self, quaternion, omega):
        """The body's angular acceleration, in its own frame, of the scene's ball joint from MuJoCo's own
        state: the joint's (w, x, y, z) quaternion and the body's angular velocity, under the scene's applied
        forces.  No Euler angles, so no singularity at zero nutation."""
        dofs = self._ball_joint_state("ball_joint_acceleration", quaternion, omega)
        return self.d.qacc[dofs].copy()

    def ball_joint_linearisation(self, quaternion, omega):
        """The state matrix A of (dtheta, dw) about the scene's ball joint's state (as `ball_joint_acceleration`),
        engines.coordinates.ball_joint_state_matrix, and the estimated error of its entries.  dw' = -Ma^-1 (Dq dtheta +
        Dv dw) from the derivatives of the inverse dynamics F(x, w, w') = applied (`_inverse_derivatives`:
        continuous time, where mjd_transitionFD would give one step's), Ma the mass matrix; their error goes
        through Ma^-1: |Ma^-1|_inf times it."""
        dofs = self._ball_joint_state("ball_joint_linearisation", quaternion, omega)
        mass = np.zeros((self.m.nv, self.m.nv))
        mujoco.mj_fullM(self.m, self.d, mass)
        inverse_mass = np.linalg.inv(mass[dofs, dofs])
        force_q, force_v, error = self._inverse_derivatives()
        matrix = coordinates.ball_joint_state_matrix(omega, -inverse_mass @ force_q[dofs, dofs],
                                                     -inverse_mass @ force_v[dofs, dofs])
        return matrix, float(np.max(np.sum(np.abs(inverse_mass), axis=1)) * error)

    def _ball_joint_state(self, method, quaternion, omega):
        """The ball joint's dofs (a slice), with self.d at its quaternion (w, x, y, z) and angular velocity and
        their acceleration under the scene's applied forces (qacc); ValueError where `method` cannot apply."""
        qadr, dof = coordinates.lone_ball_joint(self.path, self.layout, self.driven, method)
        coordinates.constant_forces(self.path, self.varying, method)
        self.d.qpos[qadr:qadr + 4], self.d.qvel[dof:dof + 3] = quaternion, omega
        self.d.qfrc_applied[:] = self.applied
        mujoco.mj_forward(self.m, self.d)
        return slice(dof, dof + 3)

    def linearisation(self, t, q, v):
        """M q'' = f(t, q, q') linearised at the case's state (engines.coordinates.Linearisation): MuJoCo's inverse
        dynamics differenced (`_inverse_derivatives`) at the state's accelerations, the prescribed joints'
        imposed, in the case's coordinates (engines.coordinates.case_linearisation, which differences applied laws of
        the state).  f = applied - qfrc_inverse, qfrc_inverse = M qacc + bias - springs - dampers.  The
        evaluation model holds no armature on the prescribed joints, which are no coordinates: only the free
        rows and columns are used, and its M is `mass_matrix`'s.  ValueError for a scene with loops."""
        if self.loops.loops:
            raise ValueError(f"{self.path}: linearisation of a scene with closed loops "
                             f"({', '.join(self.loop_names)}) is not supported: its coordinates' equations hold "
                             "the loops' constraint forces, which mj_inverse does not give for a rigid loop")
        _, mass, _, qacc = self._solve(t, q, v)  # leaves self.d at the state
        self.d.qacc[:] = qacc
        force_q, force_v, error = self._inverse_derivatives()
        method = "MuJoCo mjd_inverseFD (centred differences, extrapolated, at the step of least estimated error)"
        return coordinates.case_linearisation(self._dof_layout, self.forces, t, q, v,
                                              coordinates.case_accelerations(self._dof_layout, q, v, qacc),
                                              mass, -force_q, -force_v, error, method)

    def _inverse_derivatives(self):
        """d(qfrc_inverse)/dqpos and /dqvel (nv, nv, a row per force) at self.d's state and qacc, the positions
        perturbed by mj_integratePos (a ball joint's quaternion * exp(dtheta)), and the estimated error of their
        entries.  mjd_inverseFD takes forward differences only, and a negative eps the backward ones: their mean
        is the centred difference, extrapolated (engines.coordinates.extrapolated_differences) with its truncation
        error, plus rounding (engines.coordinates.difference_rounding) of the largest term of qfrc_inverse (M qacc, the
        bias, the passive forces)."""
        nv = self.m.nv

        def centred(step):
            ends = []
            for eps in (step, -step):
                force_q, force_v = np.zeros((nv, nv)), np.zeros((nv, nv))
                mujoco.mjd_inverseFD(self.m, self.d, eps, False, force_q, force_v, None, None, None, None, None)
                ends.append((force_q.T, force_v.T))  # mjd_inverseFD's are transposed: a row per perturbed dof
            return [(forward + backward) / 2 for forward, backward in zip(*ends)]

        # the evaluation model's Euler (mjd_inverseFD refuses RK4); mj_inverse in continuous time: invdiscrete is refused
        mujoco.mj_inverse(self.m, self.d)
        inertial = self.d.qfrc_inverse - self.d.qfrc_bias + self.d.qfrc_passive  # M qacc
        size = max(np.max(np.abs(x)) for x in (inertial, self.d.qfrc_bias, self.d.qfrc_passive))
        return coordinates.least_error_differences(centred, size)

    def points(self, t, q):
        """World positions of the traced bodies' centres of mass, and the chain of body origins."""
        self._set_state(t, q, np.zeros(len(q)))
        mujoco.mj_kinematics(self.m, self.d)
        return self.d.xipos[self.paths].copy(), self.d.xpos[1:].copy(), self.m.body_parentid[1:].copy()

    def paths_many(self, t, q):
        """The traced bodies' centres of mass (`points`' first) at many states, the same numbers: t of shape (N,),
        q (N, n) -> (N, bodies, 3); with loops, state by state as `points` (each closed from the assembly)."""
        t, q = np.asarray(t, dtype=float), np.asarray(q, dtype=float)
        if self.loops.loops:
            return np.array([self.points(*state)[0] for state in zip(t, q)]).reshape(len(t), len(self.paths), 3)
        qpos, qvel = self._engine_states(t, q, np.zeros_like(q))
        out = np.empty((len(t), len(self.paths), 3))
        for i in self._each_state(qpos, qvel):  # mj_kinematics reads the positions alone
            mujoco.mj_kinematics(self.m, self.d)
            out[i] = self.d.xipos[self.paths]
        return out
