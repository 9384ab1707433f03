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
"""

import copy
import math
import time
from xml.etree import ElementTree

import mujoco
import mujoco.rollout
import numpy as np

from engines import coordinates, euler, scene as scene_rules
from engines.bindings import FULL_INERTIA, full_tensor, parallel_axis, unphysical
from engines.linalg import linear_solution
from engines.loops import MujocoLoops

# MuJoCo prints a line for each run that blows up, and the studies blow runs up on purpose: each
# is reported instead as an unstable row, from the warnings MuJoCo counts in its data.
mujoco.set_mju_user_warning(lambda message: None)

INTEGRATORS = {"Euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
               "RK4": mujoco.mjtIntegrator.mjINT_RK4}
CLOSURES = 4096
"""How many closures of a scene's loops from its assembly a model keeps (`_close`)."""


class MujocoModel:
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

    @staticmethod
    def elements_in(path):
        """What the scene file at `path` holds of a case's bindings (as PinocchioModel.elements_in): an
        MJCF holds them all."""
        return {"body", "joint", "option"}

    def __init__(self, path, scene, writes=()):
        self.path = str(path)
        try:
            spec = mujoco.MjSpec.from_file(self.path)
            _write_all(spec, writes)
            self.m = spec.compile()
        except (ValueError, KeyError) as error:
            raise ValueError(f"{self.path}: {error}") from error
        _refuse_nan(self.path)
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
        unmodelled = next(_unmodelled(self.m, scene), None)
        if unmodelled:
            raise scene_rules.refusal(self.path, "MJCF", *unmodelled)
        if self.loops.loops:
            self._refuse_unclosable(scene)
        # The evaluations' mj_forward under one integrator: the file's "discrete" changes a loop's accelerations
        # (by 51 rad/s^2 of the slider-crank's phi''); the others give the same numbers.  Runs set their own (`stepping`).
        self.m.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
        if not self.m.neq:
            # No constraint row can arise but a loop's (`_unmodelled` refuses contacts, joint limits, friction loss,
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

    def _sensor(self, name):
        i = self._id(mujoco.mjtObj.mjOBJ_SENSOR, name)
        return int(self.m.sensor_adr[i]), int(self.m.sensor_objid[i])

    def _reaction_sensor(self, reaction, spec):
        """The sensor of a reaction: a force sensor (a torque sensor for a moment, on a site at the body's origin)
        on a site of the case's body, with the body's axes (the Pinocchio side reads the force or moment on that
        body's joint, in its frame, about its origin), its reading neither clamped nor delayed.  Its sensordata
        address and site."""
        i = self._id(mujoco.mjtObj.mjOBJ_SENSOR, spec.sensor)
        site = int(self.m.sensor_objid[i])
        kind = mujoco.mjtSensor(self.m.sensor_type[i]).name[7:].lower()
        where = f"{self.path}: sensor '{spec.sensor}' of reaction '{reaction}'"
        quantity = spec.quantity
        expected = {"force": "force", "moment": "torque"}[quantity]
        if kind != expected:
            raise ValueError(f"{where} is a <{kind}> sensor: a {quantity} reaction reads a <{expected}> sensor")
        if quantity == "moment" and not np.max(np.abs(self.m.site_pos[site])) <= 0.0:  # NaN too
            raise scene_rules.refusal(self.path, "MJCF", "body-site", "pos", f"site of sensor '{spec.sensor}'",
                                      _text(self.m.site_pos[site]))
        body = mujoco.mj_id2name(self.m, mujoco.mjtObj.mjOBJ_BODY, self.m.site_bodyid[site])
        if body != spec.body:
            raise ValueError(f"{where} is on body '{body}', but case.toml's reaction is on body '{spec.body}'")
        if not self.m.body_jntnum[self.m.site_bodyid[site]]:
            raise ValueError(f"{where} is on body '{body}', which has no joint: the weld's force, which the Pinocchio"
                             " side does not read (its reader merges a welded body into the body it is welded to)")
        # A site's quat is normalised from decimal text: identity to a few ulps when it is one.
        if not np.max(np.abs(self.m.site_quat[site] - [1, 0, 0, 0])) <= 4 * np.finfo(float).eps:  # NaN too
            raise scene_rules.refusal(self.path, "MJCF", "body-site", "quat", f"site of sensor '{spec.sensor}'",
                                      _text(self.m.site_quat[site]))
        if self.m.sensor_cutoff[i] > 0:
            raise scene_rules.refusal(self.path, "MJCF", f"sensor-{kind}", "cutoff", f"sensor '{spec.sensor}'",
                                      _text(self.m.sensor_cutoff[i]))
        if self.m.sensor_history[i][0] > 0:
            raise scene_rules.refusal(self.path, "MJCF", f"sensor-{kind}", "nsample", f"sensor '{spec.sensor}'",
                                      int(self.m.sensor_history[i][0]))
        return int(self.m.sensor_adr[i]), site

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

    def tree(self):
        """The moving bodies as MuJoCo models them (see engines.scene.Body, engines.scene.moving_body: a body with
        several joints is a chain of them).  A body without a joint under a moving body is welded to it: its mass
        and inertia ride with that body (engines.scene.combined_inertia), as Pinocchio's readers merge them.  A ball
        joint's armature a on a body on the world is the isotropic inertia a I about the joint (no mass, so the same
        about the centre of mass), and is counted in the body's inertia."""
        m, bodies = self.m, []
        for b in range(1, m.nbody):
            if not m.body_jntnum[b]:  # a ground (folded into the world) or welded to a moving body (below)
                continue
            parts = []  # the body and those welded to it, in its frame
            for w in range(b, m.nbody):
                if m.body_weldid[w] == b:
                    position, rotation = _in_body(m, w, b)
                    principal = rotation @ _matrix(m.body_iquat[w])
                    parts.append((float(m.body_mass[w]), position + rotation @ m.body_ipos[w],
                                  principal @ np.diag(m.body_inertia[w]) @ principal.T))
            mass, com, inertia = scene_rules.combined_inertia(parts)
            joints = []
            for j in range(m.body_jntadr[b], m.body_jntadr[b] + m.body_jntnum[b]):
                kind = mujoco.mjtJoint(m.jnt_type[j]).name[6:].lower()
                if kind == "ball":
                    inertia = inertia + self.armature[m.jnt_dofadr[j]] * np.eye(3)
                joints.append((_name(m, mujoco.mjtObj.mjOBJ_JOINT, j), kind,
                               m.jnt_axis[j].copy() if kind != "ball" else np.zeros(3),
                               np.r_[m.jnt_stiffness[j], m.jnt_stiffnesspoly[j]],
                               float(m.qpos_spring[m.jnt_qposadr[j]]) if kind != "ball" else 0.0,
                               float(m.dof_damping[m.jnt_dofadr[j]])))
            parent, position, rotation = _placement(m, b)
            bodies += scene_rules.moving_body(_name(m, mujoco.mjtObj.mjOBJ_BODY, b),
                                              _name(m, mujoco.mjtObj.mjOBJ_BODY, parent) if parent else "world",
                                              joints, position, rotation, mass, com, inertia)
        return bodies

    @property
    def gravity(self):
        return self.m.opt.gravity.copy()

    def read(self, location):
        """The compiled model's value at a binding location (see `_write`)."""
        element, name, index = location.element, location.name, location.index
        if element == "option":
            return float(getattr(self.m.opt, name)[index])
        if element == "body" and location.attribute == "inertia_about_origin":
            body = self.body_id(name)
            ipos, mass = self.m.body_ipos[body], self.m.body_mass[body]
            ball = self.m.dof_armature[self.m.body_dofadr[body]:][:self.m.body_dofnum[body]]
            armature = ball[index] if len(ball) == 3 else 0.0
            return float(self.m.body_inertia[body][index] + parallel_axis(mass, ipos, index) + armature)
        if element == "body" and location.attribute == "fullinertia":  # about the centre of mass, body frame
            body = self.body_id(name)
            frame = _matrix(self.m.body_iquat[body])
            return float((frame @ np.diag(self.m.body_inertia[body]) @ frame.T)[FULL_INERTIA[index]])
        if element == "body":
            array = getattr(self.m, "body_" + location.attribute)[self.body_id(name)]
        else:
            qadr, dof = self._joint(name)
            array = {"stiffness": lambda: self.m.jnt_stiffness[self._id(mujoco.mjtObj.mjOBJ_JOINT, name)],
                     "springref": lambda: self.m.qpos_spring[qadr], "damping": lambda: self.m.dof_damping[dof]
                     }[location.attribute]()
        return float(np.atleast_1d(array)[index])

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

    # -- time stepping with MuJoCo's own integrators -------------------------
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


def _name(m, kind, i):
    return mujoco.mj_id2name(m, kind, i)


def _matrix(quat):
    matrix = np.empty(9)
    mujoco.mju_quat2Mat(matrix, quat)
    return matrix.reshape(3, 3)


def _in_body(m, w, b):
    """The position and rotation of body w's frame in body b's, w welded to b (only jointless bodies between)."""
    position, rotation = np.zeros(3), np.eye(3)
    while w != b:
        position, rotation = m.body_pos[w] + _matrix(m.body_quat[w]) @ position, _matrix(m.body_quat[w]) @ rotation
        w = m.body_parentid[w]
    return position, rotation


def _placement(m, b):
    """Body b's parent, its position and its rotation in it: the jointless bodies between folded in, a ground (welded
    to the world, as Pinocchio's MJCF reader needs one body on <worldbody>) into the world as that reader folds it,
    a body welded to a moving body into that body (`tree`)."""
    parent, position, rotation = m.body_parentid[b], m.body_pos[b].copy(), _matrix(m.body_quat[b])
    while parent and not m.body_jntnum[parent]:
        above = _matrix(m.body_quat[parent])
        position, rotation = m.body_pos[parent] + above @ position, above @ rotation
        parent = m.body_parentid[parent]
    return parent, position, rotation


def _text(values):
    return " ".join(f"{x:g}" for x in np.atleast_1d(values))


DEFAULT_OPTION = mujoco.MjModel.from_xml_string("<mujoco/>").opt
OPTION_ATTRIBUTES = {"disableactuator": "actuatorgroupdisable"}  # MjOption's fields named otherwise in <option>
FLAGS = ((mujoco.mjtDisableBit, "disableflags", "mjDSBL_", "disable"),  # each <flag>'s bits, and its value when set
         (mujoco.mjtEnableBit, "enableflags", "mjENBL_", "enable"))


def options_set(opt):
    """(element, attribute, value) of every <option> attribute and <flag> that `opt` (an MjOption) holds otherwise
    than MuJoCo's default, walked from MuJoCo's own lists (MjOption's fields, mjtDisableBit, mjtEnableBit), named as
    in MJCF: ("option", "density", "1.2"), ("option-flag", "damper", "disable")."""
    for field in dir(DEFAULT_OPTION):
        if field.startswith("_") or field in ("disableflags", "enableflags"):
            continue
        value = getattr(opt, field)
        if np.any(np.asarray(value) != np.asarray(getattr(DEFAULT_OPTION, field))):
            yield "option", OPTION_ATTRIBUTES.get(field, field), (mujoco.mjtSolver(value).name[6:] if field == "solver"
                                                                  else _text(value))
    for bits, field, prefix, value in FLAGS:
        for name, bit in bits.__members__.items():
            if name.startswith(prefix) and (getattr(opt, field) ^ getattr(DEFAULT_OPTION, field)) & bit:
                yield "option-flag", name[len(prefix):].lower(), value


def _unmodelled(m, scene):
    """What the compiled model holds that dyncheck does not model, as (element, attribute, owner, value) of
    engines.scene.RULES: forces and constraints that the Pinocchio side lacks, joints the case does not move."""
    obj = mujoco.mjtObj
    named = lambda kind, i: f"{kind.name[6:].lower()} '{_name(m, kind, i) or i}'"
    for count, element, kind in ((m.nplugin, "plugin", obj.mjOBJ_PLUGIN), (m.nu, "actuator", obj.mjOBJ_ACTUATOR),
                                 (m.ntendon, "tendon", obj.mjOBJ_TENDON),
                                 (m.nflex, "deformable-flex", obj.mjOBJ_FLEX), (m.npair, "contact-pair", obj.mjOBJ_PAIR)):
        if count:
            yield element, "*", named(kind, 0), ""
    for element, attribute, value in options_set(m.opt):
        found = scene_rules.judged("MJCF", element, attribute)
        if found.status == scene_rules.REFUSED and (m.neq or not found.with_loops):
            yield element, attribute, "<option>", value
    for g1 in range(m.ngeom):  # a pair of geoms on two bodies that MuJoCo's contact filter lets touch
        for g2 in range(g1 + 1, m.ngeom):
            if m.geom_bodyid[g1] == m.geom_bodyid[g2]:
                continue
            if m.geom_contype[g1] & m.geom_conaffinity[g2]:
                yield "body-geom", "contype", named(obj.mjOBJ_GEOM, g1), _text(m.geom_contype[g1])
            if m.geom_contype[g2] & m.geom_conaffinity[g1]:
                yield "body-geom", "conaffinity", named(obj.mjOBJ_GEOM, g1), _text(m.geom_conaffinity[g1])
    moved, driven = scene_rules.named_joints(scene), set(scene.driven)
    for j in range(m.njnt):
        name, kind = _name(m, obj.mjOBJ_JOINT, j), mujoco.mjtJoint(m.jnt_type[j])
        dof, qadr = m.jnt_dofadr[j], m.jnt_qposadr[j]
        owner = f"joint '{name}'"
        if kind == mujoco.mjtJoint.mjJNT_FREE:
            yield "body-freejoint", "*", owner, ""
        if name not in moved:
            yield "body-joint", "name", owner, name
        scalar = kind in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)
        dofs = slice(dof, dof + (1 if scalar else 3))
        on_world_ball = (kind == mujoco.mjtJoint.mjJNT_BALL and m.body_parentid[m.jnt_bodyid[j]] == 0
                         and m.body_jntnum[m.jnt_bodyid[j]] == 1)
        checks = [("pos", m.jnt_pos[j]), ("limited", m.jnt_limited[j]), ("springyield", m.jnt_springyield[j]),
                  ("frictionloss", m.dof_frictionloss[dofs]),
                  ("damping", m.dof_dampingpoly[dofs].ravel()),  # the linear damping is compared (tree)
                  ("armature", 0.0 if name in driven or on_world_ball else m.dof_armature[dofs])]
        if scalar:
            checks += [("ref", m.qpos0[qadr])]
        for attribute, value in checks:
            if np.any(value):
                yield "body-joint", attribute, owner, _text(value)
    for b in range(1, m.nbody):
        if m.body_mocapid[b] >= 0:
            yield "body", "mocap", named(obj.mjOBJ_BODY, b), "true"
        if m.body_gravcomp[b]:
            yield "body", "gravcomp", named(obj.mjOBJ_BODY, b), _text(m.body_gravcomp[b])


def _refuse_nan(path):
    """MuJoCo's compiler quietly replaces some NaN values (an inertial pos): a NaN in the file is refused."""
    try:
        tree = ElementTree.parse(path)
    except ElementTree.ParseError as error:  # MuJoCo's parser lets through what XML forbids (control characters)
        raise ValueError(f"{path}: not well-formed XML: {error}") from None
    for element in tree.iter():
        for attribute, text in element.attrib.items():
            if any(token.lower() == "nan" for token in text.split()):
                raise ValueError(f"{path}: <{element.tag}> {attribute}=\"{text}\" holds a NaN, which MuJoCo's "
                                 "compiler may quietly replace")


def _write_all(spec, writes):
    """`_write` each (location, value) into an MjSpec; then ValueError naming the body for an inertia they leave
    unphysical (several writes may pass through one: checked once all are written)."""
    # the inertial frame of a body that the file gives diaginertia, for a write of its fullinertia
    compiled = spec.compile() if any(location.attribute == "fullinertia" for location, _ in writes) else None
    written = set()
    for location, value in writes:
        if location.element == "body" and location.attribute in ("inertia", "fullinertia"):
            written.add(location.name)
        _write(spec, location, value, compiled)
    for name in written:
        body = spec.body(name)
        why = unphysical(name, np.diag(body.inertia) if np.isnan(body.fullinertia[0]) else full_tensor(body.fullinertia))
        if why:
            raise ValueError(why)


def _write(spec, location, value, compiled=None):
    """Set a scene value in an MjSpec: body pos/ipos/mass/inertia_about_origin/inertia (diaginertia, a body
    without fullinertia)/fullinertia (the body frame's, from `compiled`'s inertia where the file gives
    diaginertia), joint stiffness, damping, springref (a hinge's in rad), option gravity."""
    element, name, attribute, index = location.element, location.name, location.attribute, location.index
    if element == "option":
        target, attribute = spec.option, name
    elif element == "body":
        target = spec.body(name)
    else:
        target = spec.joint(name)
    if target is None:
        raise KeyError(f"no {element} named '{name}'")
    if attribute == "springref" and spec.compiler.degree and target.type == mujoco.mjtJoint.mjJNT_HINGE:
        value = math.degrees(value)  # the case's rad, the file's degrees (<compiler angle>, MJCF's default degree)
    if attribute == "inertia" and not np.isnan(target.fullinertia[0]):
        raise ValueError(f"body '{name}' inertia[{index}]: its <inertial> gives fullinertia, whose principal moments"
                         " are MuJoCo's decomposition of it; bind fullinertia")
    if attribute == "fullinertia" and np.isnan(target.fullinertia[0]):  # the file's diaginertia and frame, as one
        body = compiled.body(name)
        frame = _matrix(body.iquat)
        tensor = frame @ np.diag(body.inertia) @ frame.T
        target.fullinertia = [tensor[entry] for entry in FULL_INERTIA]
        target.inertia, target.iquat = np.zeros(3), [1.0, 0.0, 0.0, 0.0]
        target.ialt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    if attribute == "inertia_about_origin":
        # The moment of inertia about body axis `index` through the body origin: subtract the
        # parallel-axis term of the centre of mass and the body's ball-joint armature (see the top).
        ipos = np.array(target.ipos)
        armature = sum(j.armature for j in target.joints if j.type == mujoco.mjtJoint.mjJNT_BALL)
        value = value - parallel_axis(target.mass, ipos, index) - armature
        attribute = "inertia"
    current = getattr(target, attribute)
    if np.ndim(current) == 0:
        setattr(target, attribute, value)
    else:
        array = np.array(current, dtype=float)
        array[index] = value
        setattr(target, attribute, array)
