"""Pinocchio adapter: a case's URDF or MJCF scene behind the model interface, in the book's coordinates.

Prescribed joints are handled by partitioning: RNEA with the driven joints'
imposed accelerations gives the free joints' bias, CRBA's free block is solved.
URDF has no springs and no gravity, so joint stiffness, spring rest positions and
gravity come from the case's bindings (`write`), and `read` reports them back from
this adapter; its dampers are the joints' <dynamics damping>.  An MJCF has them all,
but Pinocchio's parser drops them: this adapter reads them from the file.  Pinocchio's
algorithms model no spring and no damper: their forces -k (q - springref) - d q' are
generalised forces here.

This module holds the model: its construction, Pinocchio's state at the case's states, the engine step, the model
interface and the linearisation.  engines.pinocchio_scene reads and writes the scene file.
"""

import math

import numpy as np
import pinocchio as pin

from engines import coordinates, euler, scene as scene_rules
from engines.linalg import linear_solution
from engines.loops import PinocchioLoops
from engines.mjcf_joints import is_mjcf
from engines.pinocchio_scene import PinocchioScene, unmodelled


class PinocchioModel(PinocchioScene):
    """path: the scene's URDF, or its MJCF (a .xml file: the scene MuJoCo reads).
    scene: as for MujocoModel (coords, driven, reactions); reactions use the body, not the sensor."""

    def __init__(self, path, scene, writes=()):
        self.path = str(path)
        document, constraints = self._read(scene, writes)
        self.loops = PinocchioLoops(self.m, constraints, self.path)  # after the model is complete
        if self.loops.loops and self._composite:  # the loops' joints are the model's: a composite's parts are not
            raise ValueError(f"{self.path}: a scene with closed loops is evaluated with one joint on each body; "
                             "several joints on one body in it are not supported yet")
        self._closed = None  # the last closed configuration, where the next closing starts (`engine_state`)
        self.point_specs = {name: (self._point_frame(spec), spec.frame, spec.kind)
                            for name, spec in scene.points.items()}
        self.d = self.m.createData()  # after the frames the points add
        self.coords = tuple(scene.coords)
        self.reaction_names = tuple(scene.reactions)
        self.layout = [(c.kind, self._joint(c.joint), list(c.indices)) for c in scene.layout]
        self.free = np.array([i for _, joint, idx in self.layout for i in range(joint.idx_v, joint.idx_v + len(idx))],
                             dtype=int)
        self.driven = [(self._joint(j), (law.angle, law.rate, law.acc)) for j, law in scene.driven.items()]
        # after the case's joints are found: a renamed joint is missing before it is extra.  An MJCF's
        # are refused by MuJoCo's adapter, on the same file.
        unmodelled_element = None if is_mjcf(self.path) else next(unmodelled(document, scene), None)
        if unmodelled_element:
            raise scene_rules.refusal(self.path, "URDF", *unmodelled_element)
        self.forces = [(self._joint(joint).idx_v, force) for joint, force in scene.applied.items()]
        # Constant applied forces are evaluated once (`applied`); laws of the state at every evaluation.
        self.varying = not all(force.constant for _, force in self.forces)
        self.applied = None if self.varying else self._applied_at(0.0, np.zeros(len(self.coords)),
                                                                   np.zeros(len(self.coords)))
        loop_names = [loop.name for loop in self.loops.loops]
        self.reaction_specs = {name: (self._moved_joint(spec.body, f"reaction '{name}'"), spec.axis, spec.frame,
                                      spec.quantity) if spec.sensor not in loop_names
                               else ("loop", (loop_names.index(spec.sensor), spec.axis), "world", "force")
                               for name, spec in scene.reactions.items()}
        # (idx_q, idx_v, stiffness, rest position, damping) of each joint with a spring or a damper
        passive = set(self.joint_values["stiffness"]) | set(self.joint_values["damping"])
        self.passive = [(self._joint(j).idx_q, self._joint(j).idx_v, self.joint_values["stiffness"].get(j, 0.0),
                         self.joint_values["springref"].get(j, 0.0), self.joint_values["damping"].get(j, 0.0))
                        for j in sorted(passive)]
        wound = [j for j in self.joint_values["stiffness"] if self._joint(j).nq == 2]
        if wound:  # Pinocchio's continuous joint holds (cos q, sin q): no q for the spring beyond +-pi
            raise ValueError(f"{self.path}: joint '{wound[0]}' is continuous and has a spring: Pinocchio's continuous "
                             "joint cannot say how far it has wound; make it revolute with lower=\"-1e300\" "
                             "upper=\"1e300\"")
        # (nq, idx_q, idx_v) of the joints, read once: each of Pinocchio's attributes is a call.
        self._coord_joints = [(kind, (joint.nq, joint.idx_q, joint.idx_v), idx) for kind, joint, idx in self.layout]
        # the joints as engines.coordinates takes them: (kind, first dof, coordinate indices)
        self._dof_layout = [(kind, iv, idx) for kind, (_, _, iv), idx in self._coord_joints]
        self._driven_joints = [((joint.nq, joint.idx_q, joint.idx_v), motion) for joint, motion in self.driven]
        self._independent = [(c.kind, self.m.getJointId(c.joint), list(c.indices)) for c in scene.layout if c.kind == "scalar"]
        self.dependent_joints = [(j, self._joint(j)) for j in scene.dependent]
        self._driven_acc = np.zeros(self.m.nv)
        for (_, _, iv), (_, _, acc) in self._driven_joints:
            self._driven_acc[iv] = acc
        self.neutral = pin.neutral(self.m)
        # What engine_state and engine_dynamics do at every call, decided once: Python lists of the
        # joints' indices (one state's scalars cost least as Python floats), the branch engine_dynamics takes.
        self._neutral_list, self._nq, self._nv = self.neutral.tolist(), self.m.nq, self.m.nv
        self._scalars = [(nq, iq, iv, idx[0]) for kind, (nq, iq, iv), idx in self._coord_joints if kind == "scalar"]
        self._balls = [(iq, iv, idx) for kind, (_, iq, iv), idx in self._coord_joints if kind == "euler"]
        self._all_free = len(self.free) == self.m.nv
        self._coord_dofs = np.zeros(len(self.coords), dtype=int)  # each coordinate's dof, for scalar joints
        for nq, iq, iv, i in self._scalars:
            self._coord_dofs[i] = iv
        self._last = None, None  # the last state asked and its engine pass (`_dynamics`)
        # A lone ball joint under constant forces is integrated in Pinocchio's own coordinates (dyncheck.run.simulate)
        lone_ball = [kind for kind, _, _ in self.layout] == ["euler"] and not self.driven
        self.native = BallJointCoordinates(self) if lone_ball and not self.varying else None
        # CRBA fills the upper triangle of M: M[i, j] for i > j is read at [j, i].
        every = np.arange(self.m.nv)
        self._whole = np.minimum.outer(every, every), np.maximum.outer(every, every)
        # M[:, free] and its rows M[free, free], as indices into M and into M[:, free] flat (C order): `take` of
        # them costs a third of fancy indexing
        self._free_columns = (np.minimum.outer(every, self.free) * self.m.nv + np.maximum.outer(every, self.free))
        self._free_block = self.free[:, None] * len(self.free) + np.arange(len(self.free))

    # -- state -------------------------------------------------------------
    def engine_state(self, t, q, v):
        """Pinocchio's configuration and velocity at the book's state (t, q, v)."""
        return self._engine_state(t, np.asarray(q, dtype=float).tolist(), np.asarray(v, dtype=float).tolist())

    def _engine_state(self, t, q, v):
        """`engine_state` of q and v as lists of floats: on one state of a few joints, writes of Python floats
        into one list, made an array once, cost less than numpy's writes and index arrays."""
        state = self._neutral_list + [0.0] * self._nv  # the configuration, then the velocity
        for nq, iq, iv, i in self._scalars:
            self._write_dof(state, nq, iq, iv, q[i], v[i])
        for (nq, iq, iv), (q0, rate, acc) in self._driven_joints:
            self._write_dof(state, nq, iq, iv, q0 + rate * t + 0.5 * acc * t**2, rate + acc * t)
        for iq, iv, idx in self._balls:  # spherical: quaternion (x, y, z, w), the body's angular velocity
            angles, rates = [q[i] for i in idx], [v[i] for i in idx]
            w, x, y, z = euler.quaternion(angles).tolist()
            state[iq:iq + 4] = x, y, z, w
            iv += self._nq
            state[iv:iv + 3] = euler.angular_velocity(angles, rates).tolist()
        if self.loops.loops:  # the dependent joints closing the loops, from the last closing (its branch)
            positions = {self.m.names[j]: q[idx[0]] for kind, j, idx in self._independent}
            rates = {self.m.names[j]: v[idx[0]] for kind, j, idx in self._independent}
            self._closed, velocity = self.loops.close(positions, rates, self._closed)
            return self._closed, velocity
        state = np.array(state)
        return state[:self._nq], state[self._nq:]

    def engine_states(self, t, q, v):
        """`engine_state` of many states, t (N,), q and v (N, n): Pinocchio's configurations (N, nq) and velocities
        (N, nv), the same numbers, the conversions made in numpy over all the states at once."""
        t, q, v = (np.asarray(x, dtype=float) for x in (t, q, v))
        if self.loops.loops:  # each closing starts from the last (its branch): state after state
            states = [self._engine_state(*state) for state in zip(t.tolist(), q.tolist(), v.tolist())]
            return np.array([c for c, _ in states]), np.array([w for _, w in states])
        config, velocity = np.tile(self.neutral, (len(t), 1)), np.zeros((len(t), self._nv))
        # t**2 by Python's float power, as `_engine_state`'s: numpy's power of an array (t * t, or its SIMD pow of an
        # array exponent) rounds otherwise at times, and a driven joint's position with it
        squared = np.array([time ** 2 for time in t.tolist()]) if self._driven_joints else None
        one_dof = [(nq, iq, iv, q[:, i], v[:, i]) for nq, iq, iv, i in self._scalars] + [
            (nq, iq, iv, q0 + rate * t + 0.5 * acc * squared, rate + acc * t)
            for (nq, iq, iv), (q0, rate, acc) in self._driven_joints]
        for nq, iq, iv, position, rate in one_dof:
            if nq == 2:  # continuous joint: (cos, sin)
                config[:, iq], config[:, iq + 1] = np.cos(position), np.sin(position)
            else:
                config[:, iq] = position
            velocity[:, iv] = rate
        for iq, iv, idx in self._balls:  # spherical: quaternion (x, y, z, w), the body's angular velocity
            config[:, iq:iq + 4] = euler.quaternion(q[:, idx])[:, [1, 2, 3, 0]]
            velocity[:, iv:iv + 3] = euler.angular_velocity(q[:, idx], v[:, idx])
        return config, velocity

    def _write_dof(self, state, nq, iq, iv, position, rate):
        """A one-dof joint's position and rate into `_engine_state`'s list."""
        if nq == 2:  # continuous joint: (cos, sin)
            state[iq], state[iq + 1] = math.cos(position), math.sin(position)
        else:
            state[iq] = position
        state[self._nq + iv] = rate

    @property
    def algorithm(self):
        """The Pinocchio algorithms that `engine_dynamics` runs on this scene."""
        return "aba" if len(self.free) == self.m.nv else "rnea+crba" if len(self.free) else "rnea"

    def _applied_at(self, t, q, v):
        """The applied generalized forces at the case's state (t, q, v): every dof's, (nv,)."""
        return coordinates.applied_forces(self.forces, self.m.nv, t, q, v)

    def engine_dynamics(self, config, velocity, applied):
        """Pinocchio alone, on its own configuration and velocity under the applied generalized forces
        `applied` (nv,): every dof's acceleration, and the inverse-dynamics forces M acc + nle that give it
        (`algorithm` names the branch it takes)."""
        force = applied.copy() if self.passive else applied  # read, never written, by the callers
        for iq, iv, k, rest, damping in self.passive:
            force[iv] -= k * (config[iq] - rest) + damping * velocity[iv]
        if self.loops.loops:  # constraintDynamics (no prescribed joints: refused by MuJoCo's adapter)
            return self.loops.constrained(config, velocity, force)[0], force
        if self._all_free:  # nothing prescribed: Pinocchio's ABA solves it directly
            return pin.aba(self.m, self.d, config, velocity, force).copy(), force
        acc = self._driven_acc.copy()
        tau = pin.rnea(self.m, self.d, config, velocity, acc).copy()  # the free joints' bias
        if len(self.free):
            columns = pin.crba(self.m, self.d, config).take(self._free_columns)  # M[:, free]
            acc[self.free] = linear_solution(columns.take(self._free_block), force[self.free] - tau[self.free])
            tau += columns @ acc[self.free]
        return acc, tau

    def _dynamics(self, t, q, v):
        """Configuration, velocity, acceleration and inverse-dynamics forces at the book's state; the last
        state's are remembered: an integrator asks for the accelerations, then the drive power, of one state,
        and a trajectory's outputs for the reactions, then the energy."""
        state = t, np.asarray(q, dtype=float).tolist(), np.asarray(v, dtype=float).tolist()
        if state != self._last[0]:
            config, velocity = self._engine_state(*state)
            applied = self._applied_at(t, np.array(state[1]), np.array(state[2])) if self.varying else self.applied
            self._last = state, (config, velocity, *self.engine_dynamics(config, velocity, applied))
        return self._last[1]

    # -- model interface ---------------------------------------------------
    def accelerations(self, t, q, v):
        return self._book_accelerations(q, v, self._dynamics(t, q, v)[2])

    def accelerations_many(self, t, q, v):
        """`accelerations` at many states, t (N,), q and v (N, n): an array (N, n), the same numbers.  The book's
        coordinates become Pinocchio's state (`engine_states`), and its accelerations the book's, in numpy over all
        the states; the engine step alone goes state by state."""
        t, q, v = (np.asarray(x, dtype=float) for x in (t, q, v))
        # the answers' bytes joined: a quarter of numpy's cost of concatenating as many small arrays; the engine step
        # mapped over the inputs, no generator of ours between (dyncheck bench holds this call to the bare engine loop)
        acc = np.frombuffer(b"".join([dofs for dofs, _ in map(self.engine_dynamics, *self._engine_inputs(t, q, v))]))
        return self._book_accelerations(q, v, acc.reshape(len(t), self._nv))

    def _engine_inputs(self, t, q, v):
        """What `engine_dynamics` takes at many states, t (N,), q and v (N, n) arrays: Pinocchio's configurations,
        velocities (`engine_states`) and applied forces, the laws of the state given t as Python floats, as
        `engine_states` squares it (numpy's floats would round a law of t otherwise, at times)."""
        configs, velocities = self.engine_states(t, q, v)
        applied = list(map(self._applied_at, t.tolist(), q, v)) if self.varying else [self.applied] * len(t)
        return configs, velocities, applied

    def _book_accelerations(self, q, v, acc):
        """The accelerations of the case's coordinates from Pinocchio's, acc (nv,) at one state (q, v) or (N, nv)
        at many, q and v (N, n)."""
        if not self._balls:  # the case's coordinates are one-dof joints' positions (take: a third of indexing's cost)
            return acc.take(self._coord_dofs, axis=-1)
        return coordinates.case_accelerations(self._dof_layout, q, v, acc)

    def _dynamics_of_states(self, t, q, v):
        """`_dynamics` of many states, t (N,), q and v (N, n), one after another (an iterator), the same numbers: the
        book's coordinates made Pinocchio's in numpy (`engine_states`), the engine step state by state.  A scene with
        loops goes through `_dynamics` state by state, as one-state calls do: each closing starts from the last, and
        the loops' solver shares its data between closing the loops and their forces."""
        t, q, v = (np.asarray(x, dtype=float) for x in (t, q, v))
        if self.loops.loops:
            return map(self._dynamics, t.tolist(), q, v)
        return ((config, velocity, *self.engine_dynamics(config, velocity, forces))
                for config, velocity, forces in zip(*self._engine_inputs(t, q, v)))

    def reactions(self, t, q, v):
        return self._reactions_of(*self._dynamics(t, q, v))

    def reactions_many(self, t, q, v):
        """`reactions` at many states, t (N,), q and v (N, n): {name: array (N,)}, the same numbers."""
        each = [self._reactions_of(*dynamics) for dynamics in self._dynamics_of_states(t, q, v)]
        return {name: np.array([reactions[name] for reactions in each]) for name in self.reaction_names}

    def _reactions_of(self, config, velocity, acc, tau):
        """`reactions` at a state's configuration, velocity, accelerations and inverse-dynamics forces."""
        if self.loops.loops:  # their forces on the bodies: external to the tree, at anchors placed by data.oMi
            pin.forwardKinematics(self.m, self.d, config)
            loop_forces = self.loops.constrained(config, velocity, tau)[1]
            pin.rnea(self.m, self.d, config, velocity, acc, self._loop_wrenches(loop_forces))
        else:  # rnea reads no data.oMi (its joints' forces the same to the bit)
            pin.rnea(self.m, self.d, config, velocity, acc)
        # data.f: the force of each joint's parent on its subtree
        pin.forwardKinematics(self.m, self.d, config)  # rnea leaves data.oMi stale (Pinocchio 4.1)
        out = {}
        for name, (joint, axis, frame, quantity) in self.reaction_specs.items():
            if joint == "loop":  # world axes: the force on the <connect>'s body1 at its anchor
                out[name] = float(loop_forces[axis[0]][axis[1]])
                continue
            # the force, or the moment about the joint's origin (the body's), of the parent on the subtree
            force = self.d.f[joint].linear if quantity == "force" else self.d.f[joint].angular
            if frame == "world":
                force = self.d.oMi[joint].rotation @ force
            out[name] = float(force[axis])
        return out

    def _loop_wrenches(self, forces):
        """Pinocchio's external forces (each joint's, in its frame) of the loops' `forces` (world, on body1 at its
        anchor, and the opposite on body2 at its anchor), from data.oMi."""
        wrenches = pin.StdVec_Force()
        for _ in range(self.m.njoints):
            wrenches.append(pin.Force.Zero())
        for c, force in zip(self.loops.constraints, forces):
            for joint, anchor, sign in ((c.joint1_id, c.joint1_placement.translation, 1.0),
                                        (c.joint2_id, c.joint2_placement.translation, -1.0)):
                linear = self.d.oMi[joint].rotation.T @ (sign * force)
                wrenches[joint] = wrenches[joint] + pin.Force(linear, np.cross(anchor, linear))
        return wrenches

    def point_accelerations(self, t, q, v):
        """The named links' kinematics, in their own or the world frame: the absolute (classical)
        acceleration of the link's origin or of its centre of mass, or its angular velocity or
        angular acceleration."""
        config, velocity, acc, _ = self._dynamics(t, q, v)
        pin.forwardKinematics(self.m, self.d, config, velocity, acc)
        out = {}
        for name, (frame_id, frame, kind) in self.point_specs.items():
            reference = pin.LOCAL if frame == "body" else pin.LOCAL_WORLD_ALIGNED
            pin.updateFramePlacement(self.m, self.d, frame_id)
            if kind == "angular velocity":
                vector = pin.getFrameVelocity(self.m, self.d, frame_id, reference).angular
            elif kind == "angular acceleration":
                vector = pin.getFrameAcceleration(self.m, self.d, frame_id, reference).angular
            else:  # the origin of the link's frame, or of the frame added at its centre of mass
                vector = pin.getFrameClassicalAcceleration(self.m, self.d, frame_id, reference).linear
            out[name] = vector.copy()
        return out

    def ball_joint_acceleration(self, quaternion, omega):
        """The body's angular acceleration, in its own frame, of the scene's ball joint from Pinocchio's own
        state: the joint's quaternion, given (w, x, y, z) as MuJoCo orders it, and the body's angular
        velocity, under the scene's applied forces.  No Euler angles, so no singularity at zero nutation."""
        dofs, config, velocity = self._ball_joint_state("ball_joint_acceleration", quaternion, omega)
        return self.engine_dynamics(config, velocity, self.applied)[0][dofs]

    def ball_joint_linearisation(self, quaternion, omega):
        """The state matrix A of (dtheta, dw) about the scene's ball joint's state (as `ball_joint_acceleration`),
        engines.coordinates.ball_joint_state_matrix, with dw' from Pinocchio's analytic derivatives of ABA
        (computeABADerivatives: tangent perturbations quaternion * exp(dtheta), as dtheta's); and the estimated
        error of its entries, rounding (engines.coordinates.DERIVATIVE_ROUNDING)."""
        dofs, config, velocity = self._ball_joint_state("ball_joint_linearisation", quaternion, omega)
        acc_q, acc_v, _ = pin.computeABADerivatives(self.m, self.d, config, velocity, self.applied)
        matrix = coordinates.ball_joint_state_matrix(omega, acc_q[dofs, dofs], acc_v[dofs, dofs])
        return matrix, coordinates.DERIVATIVE_ROUNDING * np.max(np.abs(matrix))

    def _ball_joint_state(self, method, quaternion, omega):
        """The ball joint's dofs (a slice), and Pinocchio's configuration and velocity at its quaternion (w, x, y,
        z) and angular velocity; ValueError where `method` cannot apply (another joint, laws of the state)."""
        joint = coordinates.lone_ball_joint(self.path, self.layout, self.driven, method)
        coordinates.constant_forces(self.path, self.varying, method)
        config, velocity = self.neutral.copy(), np.zeros(self.m.nv)
        config[joint.idx_q:joint.idx_q + 4] = np.roll(quaternion, -1)  # Pinocchio's order: (x, y, z, w)
        velocity[joint.idx_v:joint.idx_v + 3] = omega
        return slice(joint.idx_v, joint.idx_v + 3), config, velocity

    def linearisation(self, t, q, v):
        """M q'' = f(t, q, q') linearised at the case's state (engines.coordinates.Linearisation): Pinocchio's analytic
        derivatives of RNEA (computeRNEADerivatives) at the state's accelerations, the prescribed joints' imposed,
        with the springs' -k and the dampers' -d on their dofs, in the case's coordinates
        (engines.coordinates.case_linearisation, which differences applied laws of the state).  Its error: RNEA's
        rounding (engines.coordinates.derivative_error), and the rounding of the springs' and dampers' sums with it.
        ValueError for a scene with loops."""
        if self.loops.loops:
            raise ValueError(f"{self.path}: linearisation of a scene with closed loops "
                             f"({', '.join(loop.name for loop in self.loops.loops)}) is not supported: its "
                             "coordinates' equations hold the loops' constraint forces, which RNEA does not give")
        config, velocity, acc, _ = self._dynamics(t, q, v)
        if self._composite:
            dtau_dq, dtau_dv, error = self._rnea_differences(config, velocity, acc)
            method = ("Pinocchio RNEA differenced (centred, extrapolated, at the step of least estimated error): its"
                      " analytic derivatives are wrong through a composite joint")
        else:
            dtau_dq, dtau_dv, error = self._rnea_derivatives(config, velocity, acc)
            method = "Pinocchio computeRNEADerivatives (analytic)"
        force_q, force_v = -dtau_dq, -dtau_dv
        mass = pin.crba(self.m, self.d, config)[self._whole]  # `mass_matrix`'s to the bit (RNEA's rounds otherwise)
        for _, iv, k, _, damping in self.passive:
            force_q[iv, iv] -= k
            force_v[iv, iv] -= damping
        # the sums' rounding: half an ulp of each, within eps of the term added (RNEA's share is in its own)
        error += np.finfo(float).eps * max((max(abs(k), abs(damping)) for _, _, k, _, damping in self.passive),
                                           default=0.0)
        return coordinates.case_linearisation(self._dof_layout, self.forces, t, q, v, self.accelerations(t, q, v),
                                              mass, force_q, force_v, error, method)

    def _rnea_derivatives(self, config, velocity, acc):
        """dtau/dq, dtau/dv of RNEA at the state's accelerations by computeRNEADerivatives, and their error."""
        derivatives = lambda c, w: [np.array(m) for m in pin.computeRNEADerivatives(self.m, self.d, c, w, acc)[:2]]
        dtau_dq, dtau_dv = derivatives(config, velocity)
        # RNEA's rounding is of RNEA's own entries: a stiff spring's -k, added here in one rounding, would make it
        # 1e3 eps of k on every entry (k = 4929 N/m on a spring pendulum's length row put 2e-6 on its angle's row,
        # whose entries are about 10, and its mode rows were inconclusive); or, where its entries are far below the
        # terms they sum, its noise as measured (engines.coordinates.derivative_error)
        error = coordinates.derivative_error(
            lambda step_q, step_v: derivatives(pin.integrate(self.m, config, step_q), velocity + step_v),
            (dtau_dq, dtau_dv), velocity)
        return dtau_dq, dtau_dv, error

    def _rnea_differences(self, config, velocity, acc):
        """dtau/dq, dtau/dv of RNEA at the state's accelerations by centred differences (positions stepped in
        Pinocchio's tangent space, pin.integrate, as MuJoCo's mj_integratePos), extrapolated at the step of least
        estimated error (engines.coordinates.least_error_differences, as MujocoModel's
        `_inverse_derivatives`), and that error.  For a model with a composite joint (several joints of one MJCF
        body), through which computeRNEADerivatives (Pinocchio 4.1) gives wrong derivatives: measured on a
        spherical pendulum of two hinges, dtau/dq of the second hinge off by 1.58 N m/rad and dtau/dv by 0.085 N m s,
        where differences of RNEA and MuJoCo's of its inverse dynamics agree (tests/test_scene_forms.py)."""
        nv, tau = self.m.nv, lambda c, w: np.array(pin.rnea(self.m, self.d, c, w, acc))
        relative = np.maximum(1.0, np.abs(velocity))

        def centred(step):
            dq, dv = np.zeros((nv, nv)), np.zeros((nv, nv))
            for j, unit in enumerate(np.eye(nv)):
                dq[:, j] = (tau(pin.integrate(self.m, config, step * unit), velocity)
                            - tau(pin.integrate(self.m, config, -step * unit), velocity)) / (2 * step)
                dv[:, j] = (tau(config, velocity + step * relative[j] * unit)
                            - tau(config, velocity - step * relative[j] * unit)) / (2 * step * relative[j])
            return [dq, dv]

        # the largest term RNEA sums: M acc, the velocity terms or gravity's
        inertial = pin.crba(self.m, self.d, config)[self._whole] @ acc
        bias, gravity = (np.array(pin.nonLinearEffects(self.m, self.d, config, velocity)),
                         np.array(pin.computeGeneralizedGravity(self.m, self.d, config)))
        size = max(float(np.max(np.abs(x))) for x in (inertial, bias - gravity, gravity))
        return coordinates.least_error_differences(centred, size)

    def dependent(self, t, q, v):
        """The dependent joints' positions and rates, {joint: value} each, on the closed state (`engine_state`)."""
        config, velocity = self.engine_state(t, np.asarray(q, dtype=float), np.asarray(v, dtype=float))
        position = lambda joint: (np.arctan2(config[joint.idx_q + 1], config[joint.idx_q]) if joint.nq == 2
                                  else config[joint.idx_q])  # a continuous joint holds (cos, sin)
        return ({name: float(position(joint)) for name, joint in self.dependent_joints},
                {name: float(velocity[joint.idx_v]) for name, joint in self.dependent_joints})

    def mass_matrix(self, t, q, v):
        """The mass matrix in the case's coordinates at (t, q) (engines.coordinates.case_mass_matrix): CRBA's, whose
        upper triangle is read for the whole."""
        config = self.engine_state(t, q, v)[0]
        mass = pin.crba(self.m, self.d, config)[self._whole]
        if self.loops.loops:  # N^T M N, N every dof's rate per independent rate (as MujocoModel.mass_matrix)
            rates = self.loops.rates(config, [self.m.joints[j].idx_v for _, j, _ in self._independent])
            return rates.T @ mass @ rates
        return coordinates.case_mass_matrix(mass, self._dof_layout, q)

    def energy(self, t, q, v):
        return self._energy_of(*self.engine_state(t, q, v))

    def energy_many(self, t, q, v):
        """`energy` at many states, t (N,), q and v (N, n): an array (N,), the same numbers, the book's coordinates
        made Pinocchio's in numpy (`engine_states`)."""
        return np.array([self._energy_of(config, velocity) for config, velocity in zip(*self.engine_states(t, q, v))])

    def _energy_of(self, config, velocity):
        """`energy` at Pinocchio's configuration and velocity: the kinematics once for both energies."""
        pin.forwardKinematics(self.m, self.d, config, velocity)
        kinetic, potential = pin.computeKineticEnergy(self.m, self.d), pin.computePotentialEnergy(self.m, self.d)
        springs = sum(0.5 * k * (config[iq] - rest) ** 2 for iq, _, k, rest, _ in self.passive)
        return float(kinetic + potential + springs)

    def drive_power(self, t, q, v):
        """Power of the prescribed motions (inverse-dynamics torques), of the applied forces and of the joints'
        dampers (negative): what changes the scene's energy."""
        _, velocity, _, tau = self._dynamics(t, q, v)
        driven = sum(tau[iv] * velocity[iv] for (_, _, iv), _ in self._driven_joints)
        dampers = -sum(damping * velocity[iv] ** 2 for _, iv, _, _, damping in self.passive)
        applied = self._applied_at(t, q, v) if self.varying else self.applied
        return float(driven + applied @ velocity + dampers)


class BallJointCoordinates:
    """A lone ball joint's state in Pinocchio's own coordinates, for an integrator (dyncheck.run.simulate's
    `native`): its quaternion (x, y, z, w) and the body's angular velocity w.  The rates q' = q (w, 0) / 2
    and ABA's w' take no Euler angle: no conversion at each evaluation, and no singularity at zero
    nutation; the book's Euler angles and rates come back at the outputs only (`book`)."""

    def __init__(self, model):
        self.model = model
        self.angles = model.layout[0][2]  # the Euler angles' places among the case's coordinates

    def state(self, q, v):
        """The state at the book's (q, v)."""
        return np.concatenate(self.model.engine_state(0.0, q, v))

    def rates(self, t, y, work):
        """The state's rates, and the drive power (the applied moments' work; 0 if not `work`)."""
        config, w = y[:4], y[4:]
        qx, qy, qz, qw, wx, wy, wz = y.tolist()
        acc = self.model.engine_dynamics(config, w, self.model.applied)[0]
        rates = np.array([0.5 * (qw * wx + qy * wz - qz * wy), 0.5 * (qw * wy + qz * wx - qx * wz),
                          0.5 * (qw * wz + qx * wy - qy * wx), -0.5 * (qx * wx + qy * wy + qz * wz), *acc.tolist()])
        return rates, float(self.model.applied @ w) if work else 0.0

    def book(self, y, start):
        """The book's coordinates and rates of states y (N, 7), the angles continuous from those at `start`."""
        quaternions = y[:, [3, 0, 1, 2]]  # (w, x, y, z)
        # the orientation of a quaternion off unit norm by the integration's error (the top's: 8e-11 after
        # 2.5 s at rtol 1e-10, 8e-13 at 1e-12; DOP853 needs no renormalisation between steps)
        angles = euler.angles(quaternions / np.linalg.norm(quaternions, axis=1)[:, None], np.asarray(start)[self.angles])
        q, v = np.empty((len(y), len(self.model.coords))), np.empty((len(y), len(self.model.coords)))
        q[:, self.angles], v[:, self.angles] = angles, euler.euler_rates(angles, y[:, 4:])
        return q, v
