"""Drake adapter: a case's MJCF (or URDF) scene read by Drake's own parser into a continuous MultibodyPlant, behind
the model interface (docs/model-interface.md), in the book's coordinates; docs/drake.md says what it adds.

Drake's parser (pydrake 1.51.1) reads some elements otherwise than MuJoCo's compiler.  What this adapter does:
  - joint stiffness and springref are ignored (with a warning): the springs' force -k (q - springref) is a
    generalised force here and k x^2 / 2 part of the energy, the values read from the file as MuJoCo's compiler
    resolves them (engines.mjcf_joints), as Pinocchio's adapter does;
  - armature becomes rotor inertia only where a motor drives the joint, otherwise it is dropped without a word: it
    is added here to the mass matrix's diagonal (and a v^2 / 2 to the energy) on every dof but the prescribed ones,
    which MuJoCo's evaluation model also frees of it (engines.mujoco_adapter);
  - a ball joint becomes a roll-pitch-yaw joint whose velocities are the angular velocity in the parent's frame:
    the case's Euler angles are mapped to its angles, and Drake's dofs are turned into the body's axes, MuJoCo's and
    Pinocchio's dofs (`_rotations`), before anything is solved or compared;
  - several joints on one body take the parent's axes for all but the last: refused;
  - a body without a joint is welded (a WeldJoint): to the world, its constant potential energy left out of `energy`,
    or to a moving body, whose mass and inertia it joins in `tree`, as MuJoCo's and Pinocchio's adapters count it;
  - a <connect> becomes a ball constraint, for which a continuous plant refuses to compute dynamics: it is removed
    before the plant is finalised and the loop solved rigidly here (`DrakeLoops`);
  - a URDF gets gravity -9.81 z, and its root link becomes a free body: gravity is set to 0 (the case's binding sets
    it, as for Pinocchio), the root link hung on the case's `urdf_root_joint`, and a free body refused.
Whatever else the parser says it ignores is refused, with its words.  Refusals are `Refused`, a ValueError that
names the file: the harness can make Drake's rows of the case not applicable with the reason.

Prescribed joints are handled by partitioning, as in the other adapters: Drake's inverse dynamics with the driven
joints' imposed accelerations gives the free joints' bias, Drake's mass matrix's free block is solved.

This module holds the model: its construction, Drake's state at the case's states, the engine step, the model
interface and the linearisation.  engines.drake_scene reads and writes the scene file (and defines `Refused`);
engines.drake_loops closes and solves its loops.
"""

import numpy as np
from pydrake.autodiffutils import AutoDiffXd, ExtractGradient
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RollPitchYaw, RollPitchYaw_, RotationMatrix
from pydrake.multibody.tree import BallRpyJoint, BodyIndex, MultibodyForces, MultibodyForces_

from engines import coordinates, euler, scene as scene_rules
from engines.drake_loops import DrakeLoops
from engines.drake_scene import SCALAR_JOINTS, DrakeScene, Refused, plant_bodies
from engines.linalg import linear_solution
from engines.mjcf_joints import is_mjcf


class DrakeModel(DrakeScene):
    """path: the scene's MJCF (a .xml file: the scene MuJoCo reads) or a URDF.  scene: as for MujocoModel
    (coords, layout, driven, applied, reactions, points, dependent, urdf_root_joint); reactions use the body (its
    joint's cut force, at the body's origin), not the sensor, as Pinocchio's adapter does."""

    def __init__(self, path, scene, writes=()):
        self.path = str(path)
        self._last = None, None  # the last state asked and its dynamics (`_dynamics`); a binding's write forgets it
        self._ad = None  # Drake's AutoDiffXd plant and its context, made at the first linearisation (`_autodiff`)
        document = self._read(scene, writes)
        self.coords = tuple(scene.coords)
        self.reaction_names = tuple(scene.reactions)
        self.layout = [(c.kind, self._joint(c.joint), list(c.indices)) for c in scene.layout]
        for kind, joint, _ in self.layout:
            if (kind == "euler") != isinstance(joint, BallRpyJoint) or not isinstance(joint, (*SCALAR_JOINTS,
                                                                                              BallRpyJoint)):
                raise ValueError(f"{self.path}: joint '{joint.name()}' is a Drake {joint.type_name()} joint, but the "
                                 f"case maps it as {'Euler angles' if kind == 'euler' else 'one coordinate'}")
        # the joints as engines.coordinates takes them: (kind, first dof, coordinate indices)
        self._dof_layout = [(kind, joint.velocity_start(), idx) for kind, joint, idx in self.layout]
        self.driven = [(self._joint(j), (law.angle, law.rate, law.acc)) for j, law in scene.driven.items()]
        self.dependent_joints = [(j, self._joint(j)) for j in scene.dependent]
        moved = scene_rules.named_joints(scene)
        for name in self._joints():
            if name not in moved:
                raise ValueError(f"{self.path}: joint '{name}' is not one that the case's [scene] names")
        self.free = np.array([i for _, joint, idx in self.layout
                              for i in range(joint.velocity_start(), joint.velocity_start() + len(idx))], dtype=int)
        self._driven_dofs = np.array([joint.velocity_start() for joint, _ in self.driven], dtype=int)
        self._driven_acc = np.zeros(self.nv)
        for joint, (_, _, acc) in self.driven:
            self._driven_acc[joint.velocity_start()] = acc
        self.forces = [(self._joint(joint).velocity_start(), force) for joint, force in scene.applied.items()]
        self.varying = not all(force.constant for _, force in self.forces)
        n = len(self.coords)
        self.applied = None if self.varying else self._applied_at(0.0, np.zeros(n), np.zeros(n))
        # each spring's (position index, dof, stiffness, rest position), each dof's damping and armature; the
        # prescribed dofs carry no armature (MuJoCo's evaluation model drops it: they are imposed)
        self.springs = [(joint.position_start(), joint.velocity_start(), k, self.joint_values["springref"].get(name, 0.0))
                        for name, k in self.joint_values["stiffness"].items() for joint in [self._joint(name)]]
        self._refuse_ball_springs()
        self.damping, self.armature = np.zeros(self.nv), np.zeros(self.nv)
        for attribute, array in (("damping", self.damping), ("armature", self.armature)):
            for name, value in self.joint_values[attribute].items():
                joint = self._joint(name)
                array[joint.velocity_start():joint.velocity_start() + joint.num_velocities()] = value
        self.armature[self._driven_dofs] = 0.0
        self._armature = np.diag(self.armature)
        self.loops = DrakeLoops(self, document if is_mjcf(self.path) else None)
        if self.loops.loops and (self.driven or any(kind != "scalar" for kind, _, _ in self.layout)):
            raise Refused(f"{self.path}: a scene with closed loops is evaluated with hinges and slides that the case's "
                          "coordinates move or the loops close; prescribed motions and ball joints in it are not "
                          "supported yet (nor by MuJoCo's adapter)")
        self._closed = None  # the last closed configuration, where the next closing starts
        self._balls = [(joint.position_start(), joint.velocity_start()) for kind, joint, _ in self.layout
                       if kind == "euler"]
        self.reaction_specs = {name: self._reaction_spec(name, spec) for name, spec in scene.reactions.items()}
        self.point_specs = {name: (self._body(spec.body), spec.frame, spec.kind)
                            for name, spec in scene.points.items()}
        # the potential energy of the bodies welded to the world, a constant in Drake's that `energy` leaves out,
        # as MujocoModel's does (Pinocchio's readers fold those bodies into the world)
        gravity = self.plant.gravity_field().gravity_vector()
        self._grounds_potential = -sum(
            self._body_inertia(body)[0] * gravity @ (body.EvalPoseInWorld(self.context) @ self._body_inertia(body)[1])
            for body in plant_bodies(self.plant)[1:] if self._weld_root(body)[0].index() == self.plant.world_body().index())

    # -- state -------------------------------------------------------------
    def engine_state(self, t, q, v):
        """Drake's positions and velocities at the book's state (t, q, v): a ball joint's roll, pitch and yaw of the
        case's Euler angles, and the body's angular velocity turned into its parent's axes; the loops closed (from
        the last closing, its branch)."""
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        positions, velocities = np.zeros(self.nq), np.zeros(self.nv)
        for kind, joint, idx in self.layout:
            iq, iv = joint.position_start(), joint.velocity_start()
            if kind == "scalar":
                positions[iq], velocities[iv] = q[idx[0]], v[idx[0]]
                continue
            w, x, y, z = euler.quaternion(q[idx])
            rotation = RotationMatrix(Quaternion(w, x, y, z))
            positions[iq:iq + 3] = RollPitchYaw(rotation).vector()
            velocities[iv:iv + 3] = rotation.matrix() @ euler.angular_velocity(q[idx], v[idx])
        for joint, (q0, rate, acc) in self.driven:
            positions[joint.position_start()] = q0 + rate * t + 0.5 * acc * t**2
            velocities[joint.velocity_start()] = rate + acc * t
        if self.loops.loops:
            positions_of = {joint.name(): q[idx[0]] for _, joint, idx in self.layout}
            rates_of = {joint.name(): v[idx[0]] for _, joint, idx in self.layout}
            self._closed, velocities = self.loops.close(positions_of, rates_of, self._closed)
            positions = self._closed
        return positions, velocities

    def _put(self, positions, velocities):
        """Drake's state into the context, and `_rotations` at it."""
        self.plant.SetPositionsAndVelocities(self.context, np.concatenate([positions, velocities]))
        return self._rotations(positions)

    def _rotations(self, positions):
        """The map (nv, nv) from the dofs' velocities in the body's axes (MuJoCo's and Pinocchio's: a ball joint's
        the body's angular velocity in its own axes) to Drake's (a ball joint's in its parent's axes): its
        rotation, from Drake's roll, pitch and yaw, on each ball joint's dofs; 1 on the others'.  None (the
        identity) in a scene without a ball joint."""
        if not self._balls:  # hinges and slides: the same dofs (None: no products with an identity)
            return None
        rotations = np.eye(self.nv)
        for iq, iv in self._balls:
            rotations[iv:iv + 3, iv:iv + 3] = RollPitchYaw(positions[iq:iq + 3]).ToRotationMatrix().matrix()
        return rotations

    def _applied_at(self, t, q, v):
        """The applied generalized forces at the case's state, every dof's (nv,), in the body's axes."""
        return coordinates.applied_forces(self.forces, self.nv, t, q, v)

    def _inverse(self, rotations, acc, external=None):
        """Drake's inverse dynamics at the context's state, in the dofs of the body's axes: the generalised forces
        that give the dofs' accelerations `acc`, gravity and Drake's joint dampers acting (and `external`, a
        MultibodyForces, if given).  Drake's dofs are the body's turned by `rotations`, which turn their
        accelerations alike (a ball: d(R w)/dt = R w' + w_parent x w_parent = R w')."""
        forces = MultibodyForces(self.plant) if external is None else external
        self.plant.CalcForceElementsContribution(self.context, forces)
        if rotations is None:
            return self.plant.CalcInverseDynamics(self.context, acc, forces)
        return rotations.T @ self.plant.CalcInverseDynamics(self.context, rotations @ acc, forces)

    def _mass(self, rotations):
        """The mass matrix in the dofs of the body's axes, with the armature that Drake drops."""
        mass = self.plant.CalcMassMatrix(self.context)
        if rotations is not None:
            mass = rotations.T @ mass @ rotations
        return mass + self._armature if self.armature.any() else mass

    def _passive(self, positions):
        """The springs' generalised forces, in the dofs (Drake's dampers act in its inverse dynamics)."""
        force = np.zeros(self.nv)
        for iq, iv, k, rest in self.springs:
            force[iv] -= k * (positions[iq] - rest)
        return force

    def engine_dynamics(self, positions, velocities, applied):
        """Drake alone on its own state under the applied generalised forces `applied` (nv, the body's axes): every
        dof's acceleration in the body's axes, the inverse-dynamics forces that give them (M acc + bias - dampers,
        the loops' forces in it), and the loops' forces (None without loops)."""
        rotations = self._put(positions, velocities)
        force = applied + self._passive(positions)
        mass = self._mass(rotations)
        if self.loops.loops:
            acc, loop_forces = self.loops.constrained(mass, force - self._inverse(rotations, np.zeros(self.nv)))
            return acc, force + self.loops.generalised(loop_forces), loop_forces
        acc = self._driven_acc.copy()
        tau = self._inverse(rotations, acc)
        if len(self.free):
            columns = mass[:, self.free]
            acc[self.free] = linear_solution(columns[self.free], force[self.free] - tau[self.free])
            tau = tau + columns @ acc[self.free]
        return acc, tau, None

    def _dynamics(self, t, q, v):
        """(positions, dofs' velocities in the body's axes, rotations, dofs' accelerations, inverse-dynamics forces,
        loop forces) at the book's state; the last state's remembered (an integrator asks for the accelerations,
        then the drive power; a run's outputs for the reactions, then the energy)."""
        key = (t, np.asarray(q, dtype=float).tobytes(), np.asarray(v, dtype=float).tobytes())
        if key != self._last[0]:
            positions, velocities = self.engine_state(t, q, v)
            applied = self._applied_at(t, np.asarray(q), np.asarray(v)) if self.varying else self.applied
            acc, tau, loop_forces = self.engine_dynamics(positions, velocities, applied)
            rotations = self._rotations(positions)
            dofs = velocities if rotations is None else rotations.T @ velocities
            self._last = key, (positions, dofs, rotations, acc, tau, loop_forces)
        else:  # the context back at this state: another method may have moved it
            positions, dofs, rotations = self._last[1][:3]
            self._put(positions, dofs if rotations is None else rotations @ dofs)
        return self._last[1]

    # -- model interface ---------------------------------------------------
    def accelerations(self, t, q, v):
        return coordinates.case_accelerations(self._dof_layout, q, v, self._dynamics(t, q, v)[3])

    def accelerations_many(self, t, q, v):
        """`accelerations` at many states, t (N,), q and v (N, n): an array (N, n), the same numbers."""
        return np.array([self.accelerations(*state) for state in zip(np.asarray(t, dtype=float), q, v)]).reshape(
            len(t), len(self.coords))

    def mass_matrix(self, t, q, v):
        """The mass matrix in the case's coordinates (engines.coordinates.case_mass_matrix); with loops N^T M N, N every
        dof's rate per independent rate."""
        mass = self._mass(self._put(*self.engine_state(t, q, v)))
        if self.loops.loops:
            rates = self.loops.rates([joint.velocity_start() for _, joint, _ in self.layout])
            return rates.T @ mass @ rates
        return coordinates.case_mass_matrix(mass, self._dof_layout, q)

    def dependent(self, t, q, v):
        """The dependent joints' positions and rates, {joint: value} each, on the closed state."""
        positions, dofs = self._dynamics(t, q, v)[:2]
        return ({name: float(positions[joint.position_start()]) for name, joint in self.dependent_joints},
                {name: float(dofs[joint.velocity_start()]) for name, joint in self.dependent_joints})

    def energy(self, t, q, v):
        """Kinetic and gravity energy (Drake's, zero at the world origin), the springs' k x^2 / 2 and the
        armature's a v^2 / 2 (MuJoCo counts it in its kinetic energy)."""
        positions, velocities = self.engine_state(t, q, v)
        rotations = self._put(positions, velocities)
        dofs = velocities if rotations is None else rotations.T @ velocities
        springs = sum(0.5 * k * (positions[iq] - rest) ** 2 for iq, _, k, rest in self.springs)
        return float(self.plant.CalcKineticEnergy(self.context) + self.plant.CalcPotentialEnergy(self.context)
                     - self._grounds_potential + springs + 0.5 * self.armature @ dofs**2)

    def energy_many(self, t, q, v):
        return np.array([self.energy(*state) for state in zip(np.asarray(t, dtype=float), q, v)])

    def drive_power(self, t, q, v):
        """Power of the prescribed motions (the inverse-dynamics forces on them, less their springs), of the applied
        forces and of the dampers (negative), as MujocoModel.drive_powers."""
        positions, dofs, _, _, tau, _ = self._dynamics(t, q, v)
        applied = self._applied_at(t, np.asarray(q), np.asarray(v)) if self.varying else self.applied
        held = tau - self._passive(positions)  # M acc + bias - springs - dampers, as mj_inverse's
        return float(held[self._driven_dofs] @ dofs[self._driven_dofs] + applied @ dofs - self.damping @ dofs**2)

    def reactions(self, t, q, v):
        """Each reaction body's cut force (or moment about its origin): the force of its parent on the subtree it
        carries, from Drake's bodies' accelerations, gravity and the loops' forces (`_cut`), in the body's axes or
        the world's; a loop's force on its body1 at its anchor (world)."""
        _, _, rotations, acc, _, loop_forces = self._dynamics(t, q, v)
        kinematics = self._kinematics(acc if rotations is None else rotations @ acc)
        out = {}
        for name, (body, axis, frame, quantity) in self.reaction_specs.items():
            if body == "loop":
                out[name] = float(loop_forces[axis[0]][axis[1]])
                continue
            force, moment = self._cut(body, kinematics, loop_forces)
            vector = force if quantity == "force" else moment
            if frame == "body":
                vector = kinematics[int(body.index())][0].T @ vector
            out[name] = float(vector[axis])
        return out

    def reactions_many(self, t, q, v):
        rows = [self.reactions(*state) for state in zip(np.asarray(t, dtype=float), q, v)]
        return {name: np.array([row[name] for row in rows]) for name in self.reaction_names}

    def _kinematics(self, vdot):
        """Each body's (R_WB, p_WBo, angular velocity, angular acceleration, origin's acceleration), world axes, by
        body index, from Drake's kinematics at the context's state and Drake's accelerations vdot."""
        accelerations = self.plant.CalcSpatialAccelerationsFromVdot(self.context, vdot)
        out = {}
        for body in plant_bodies(self.plant):
            pose, velocity = body.EvalPoseInWorld(self.context), body.EvalSpatialVelocityInWorld(self.context)
            acceleration = accelerations[int(body.index())]
            out[int(body.index())] = (pose.rotation().matrix(), pose.translation(), velocity.rotational(),
                          acceleration.rotational(), acceleration.translational())
        return out

    def _cut(self, body, kinematics, loop_forces):
        """The force of `body`'s parent on the subtree `body` carries, and its moment about body's origin (world
        axes): Newton and Euler summed over the subtree's bodies, m a_cm - m g and I alpha + w x I w about each centre
        of mass, less the loops' forces on them."""
        gravity = self.gravity
        origin = kinematics[int(body.index())][1]
        force, moment = np.zeros(3), np.zeros(3)
        for index in self._subtree(body):
            rotation, position, w, alpha, a_origin = kinematics[index]
            mass, com, inertia = self._body_inertia(self.plant.get_body(BodyIndex(index)))
            lever = rotation @ com
            a_com = a_origin + np.cross(alpha, lever) + np.cross(w, np.cross(w, lever))
            inertia_world = rotation @ inertia @ rotation.T
            net = mass * (a_com - gravity)
            force += net
            moment += inertia_world @ alpha + np.cross(w, inertia_world @ w) + np.cross(position + lever - origin, net)
        for point, on_body, loop_force in self.loops.applied(loop_forces):
            if on_body in self._subtree(body):
                force -= loop_force
                moment -= np.cross(point - origin, loop_force)
        return force, moment

    def _subtree(self, body):
        """The indices of `body` and the bodies it carries."""
        found, grew = {int(body.index())}, True
        while grew:
            grew = False
            for j in self.plant.GetJointIndices():
                joint = self.plant.get_joint(j)
                if int(joint.parent_body().index()) in found and int(joint.child_body().index()) not in found:
                    found.add(int(joint.child_body().index()))
                    grew = True
        return found

    def point_accelerations(self, t, q, v):
        """The named bodies' kinematics, in their own or the world frame: the absolute acceleration of the body's
        origin or of its centre of mass, its angular velocity or angular acceleration."""
        _, _, rotations, acc, _, _ = self._dynamics(t, q, v)
        kinematics = self._kinematics(acc if rotations is None else rotations @ acc)
        out = {}
        for name, (body, frame, kind) in self.point_specs.items():
            rotation, _, w, alpha, a_origin = kinematics[int(body.index())]
            if kind == "angular velocity":
                vector = w
            elif kind == "angular acceleration":
                vector = alpha
            elif kind == "com acceleration":
                lever = rotation @ self._body_inertia(body)[1]
                vector = a_origin + np.cross(alpha, lever) + np.cross(w, np.cross(w, lever))
            else:
                vector = a_origin
            out[name] = rotation.T @ vector if frame == "body" else vector.copy()
        return out

    def linearisation(self, t, q, v):
        """M q'' = f(t, q, q') linearised at the case's state (engines.coordinates.Linearisation): Drake's inverse dynamics
        differentiated by automatic differentiation (its AutoDiffXd plant, `_inverse_gradient`) at the state's
        accelerations, the prescribed joints' imposed, with the springs' -k on their dofs, in the case's coordinates
        (engines.coordinates.case_linearisation, which differences applied laws of the state).  Its error: the rounding
        of Drake's arithmetic (engines.coordinates.derivative_error: at the rotating pendulum's degenerate equilibrium
        under g = 0 the noise is 5e-18, its df/dq 2.3e-11 and 4e-18 off MuJoCo's).  Refused for a scene with loops, as the other adapters refuse it."""
        if self.loops.loops:
            raise Refused(f"{self.path}: linearisation of a scene with closed loops "
                          f"({', '.join(loop.name for loop in self.loops.loops)}) is not supported: its coordinates' "
                          "equations hold the loops' constraint forces, which Drake's inverse dynamics does not give")
        positions, dofs, rotations, acc = self._dynamics(t, q, v)[:4]
        mass = self._mass(rotations)  # `mass_matrix`'s to the bit
        tangent = self.plant.MakeVelocityToQDotMap(self.context).toarray()  # Drake's q' per Drake's dof velocity
        if rotations is not None:
            tangent = tangent @ rotations  # per the body's axes' dofs: a turn dtheta of the body is R dtheta
        at = lambda step_q, step_v: self._inverse_gradient(positions + tangent @ step_q, dofs + step_v, acc, tangent)
        dtau_dq, dtau_dv = at(np.zeros(self.nv), np.zeros(self.nv))
        force_q, force_v = -dtau_dq, -dtau_dv  # Drake's dampers act in its inverse dynamics: they are in force_v
        for _, iv, k, _ in self.springs:
            force_q[iv, iv] -= k
        error = coordinates.derivative_error(at, (dtau_dq, dtau_dv), dofs)
        # the springs' sums, half an ulp
        error += np.finfo(float).eps * max((abs(k) for _, _, k, _ in self.springs), default=0.0)
        return coordinates.case_linearisation(self._dof_layout, self.forces, t, q, v,
                                              coordinates.case_accelerations(self._dof_layout, q, v, acc), mass,
                                              force_q, force_v, error, "Drake CalcInverseDynamics (AutoDiffXd)")

    def _inverse_gradient(self, positions, dofs, acc, tangent):
        """d(Drake's inverse dynamics, in the body's axes' dofs)/d(dof positions, dof velocities) (nv, nv each) at
        Drake's positions, the dofs' velocities and accelerations in the body's axes (as `_inverse`): Drake's
        AutoDiffXd plant seeded with positions + tangent dx (a ball's body turned by dx in its own axes) and
        velocities dofs + dv.  A ball's Drake velocity and acceleration are R(rpy) of the body's, R of the AutoDiff
        angles (so a turn at fixed body-axes velocity turns them), and its forces R^T of Drake's."""
        plant, context = self._autodiff()
        nv = self.nv
        seeds = np.eye(2 * nv)
        q_ad = np.array([AutoDiffXd(value, np.concatenate([row, np.zeros(nv)])) for value, row in zip(positions, tangent)])
        v_ad = np.array([AutoDiffXd(value, seed) for value, seed in zip(dofs, seeds[nv:])])
        vdot = acc.astype(object)
        turns = [(iv, RollPitchYaw_[AutoDiffXd](q_ad[iq:iq + 3]).ToRotationMatrix().matrix()) for iq, iv in self._balls]
        for iv, rotation in turns:
            v_ad[iv:iv + 3], vdot[iv:iv + 3] = rotation @ v_ad[iv:iv + 3], rotation @ vdot[iv:iv + 3]
        plant.SetPositions(context, q_ad)
        plant.SetVelocities(context, v_ad)
        forces = MultibodyForces_[AutoDiffXd](plant)
        plant.CalcForceElementsContribution(context, forces)
        tau = plant.CalcInverseDynamics(context, vdot, forces)
        for iv, rotation in turns:
            tau[iv:iv + 3] = rotation.T @ tau[iv:iv + 3]
        gradient = ExtractGradient(tau)
        return gradient[:, :nv], gradient[:, nv:]

    def _autodiff(self):
        """Drake's AutoDiffXd copy of the plant and a context of it with this model's parameters (the bindings'
        inertias, poses and dampers) and gravity."""
        if self._ad is None:
            plant = self.plant.ToAutoDiffXd()
            self._ad = plant, plant.CreateDefaultContext()
        plant, context = self._ad
        context.SetTimeStateAndParametersFrom(self.context)
        plant.mutable_gravity_field().set_gravity_vector(self.gravity)
        return plant, context
