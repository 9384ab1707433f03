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
"""

import logging
import xml.etree.ElementTree as ET

import numpy as np
from pydrake.autodiffutils import AutoDiffXd, ExtractGradient
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RigidTransform, RollPitchYaw, RollPitchYaw_, RotationMatrix
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import (BallRpyJoint, BodyIndex, JacobianWrtVariable, MultibodyForces, MultibodyForces_,
                                    PrismaticJoint, RevoluteJoint, RotationalInertia, SpatialInertia, WeldJoint)

from engines import coordinates, euler, scene as scene_rules
from engines.bindings import read_inertia, unphysical, written_inertia
from engines.linalg import linear_solution
from engines.loops import Loop, _continuation, _dependent_rates, _rates_map
from engines.mjcf_joints import NO_LIMIT, inertial_frame, inertial_frames, is_mjcf, joint_values
from engines.scene import Body

SCALAR_JOINTS = (RevoluteJoint, PrismaticJoint)  # Drake's MJCF joints without a range have infinite limits

# What Drake's MJCF parser says it ignores, and why that is no difference here (the other warnings are refused).
IGNORED = {
    "The tag 'site'": "a frame for sensors: the reactions are read at the body's origin in its axes, as Pinocchio's"
                      " (MuJoCo's adapter refuses a reaction site turned or off the origin)",
    "The tag 'sensor'": "sensors do not act on the dynamics",
    "The attribute 'timestep'": "the harness sets it for every run",
    "The attribute 'integrator'": "the harness sets it for every run",
    "The attribute 'stiffness' found in a 'joint'": "corrected: this adapter applies the spring",
    "The attribute 'springref' found in a 'joint'": "corrected: this adapter applies the spring",
}

class Refused(ValueError):
    """A scene element that Drake does not model as MuJoCo and Pinocchio do, and that this adapter does not
    correct: Drake's rows of the case are not applicable, for the reason in the message."""


class _Warnings(logging.Handler):
    """The messages Drake's parser logs while it reads a file."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages = []

    def emit(self, record):
        self.messages.append(record.getMessage())


class DrakeModel:
    """path: the scene's MJCF (a .xml file: the scene MuJoCo reads) or a URDF.  scene: as for MujocoModel
    (coords, layout, driven, applied, reactions, points, dependent, urdf_root_joint); reactions use the body (its
    joint's cut force, at the body's origin), not the sensor, as Pinocchio's adapter does."""

    @staticmethod
    def elements_in(path):
        """What the scene file holds of a case's bindings (as PinocchioModel.elements_in)."""
        return {"body", "joint", "option"} if is_mjcf(path) else {"body"}

    def __init__(self, path, scene, writes=()):
        self.path = str(path)
        try:
            document = ET.parse(self.path).getroot()
        except ET.ParseError as error:
            raise ValueError(f"{self.path}: {error}") from None
        self.plant = MultibodyPlant(0.0)  # continuous: no contact solver, no SceneGraph
        warnings = _Warnings()
        logger = logging.getLogger("drake")
        logger.addHandler(warnings)
        propagate, logger.propagate = logger.propagate, False  # kept, not printed
        try:
            Parser(self.plant).AddModels(self.path)
        except RuntimeError as error:
            raise Refused(f"{self.path}: Drake's parser refuses the file: {error}") from None
        finally:
            logger.removeHandler(warnings)
            logger.propagate = propagate
        self.parser_warnings = tuple(warnings.messages)
        for message in self.parser_warnings:
            if not any(known in message for known in IGNORED):
                raise Refused(f"{self.path}: Drake's parser drops or changes what MuJoCo's compiler reads: "
                              f"{' '.join(message.split())}")
        mjcf = is_mjcf(self.path)
        if mjcf:
            _refuse_misread(document, self.path)
            self.joint_values = joint_values(document, self.path)
        else:  # URDF: no springs (the bindings set them), Drake's gravity default -9.81 z (the binding sets it)
            self.joint_values = {"stiffness": {}, "springref": {}, "damping": {}, "armature": {}}
            self.plant.mutable_gravity_field().set_gravity_vector(np.zeros(3))
            self._hang_urdf_root(scene.urdf_root_joint)
        for constraint in self.plant.GetConstraintIds():  # a <connect>: solved here (DrakeLoops)
            self.plant.RemoveConstraint(constraint)
        self.plant.Finalize()
        self._refuse_free_bodies()
        self.context = self.plant.CreateDefaultContext()
        self.nq, self.nv = self.plant.num_positions(), self.plant.num_velocities()
        self._inertias = {}  # (mass, com, inertia about the com), body frame, of each body: `_body_inertia`
        self._last = None, None  # the last state asked and its dynamics (`_dynamics`)
        self._written = set()  # the bodies whose inertia `_write` changed
        self._inertial_frames = inertial_frames(document, self.path)
        self._ad = None  # Drake's AutoDiffXd plant and its context, made at the first linearisation (`_autodiff`)
        for location, value in writes:
            self._write(location, value)
        for index in self._written:  # once all are written: Drake refuses an inertia no body can have
            mass, com, inertia = self._inertias[index]
            why = unphysical(self.plant.get_body(BodyIndex(index)).name(), inertia)
            if why:
                raise ValueError(f"{self.path}: {why}")
            self.plant.get_body(BodyIndex(index)).SetSpatialInertiaInBodyFrame(
                self.context, SpatialInertia.MakeFromCentralInertia(mass, com, RotationalInertia(
                    *np.diag(inertia), inertia[0, 1], inertia[0, 2], inertia[1, 2])))
        if not mjcf:  # URDF dampers: Drake's joints' own (<dynamics damping>)
            self.joint_values["damping"] = {name: float(joint.GetDampingVector(self.context)[0])
                                            for name, joint in self._joints().items()
                                            if joint.num_velocities() == 1 and joint.GetDampingVector(self.context)[0]}
        self._check_damping()
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
        self.loops = DrakeLoops(self, document if mjcf else None)
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
            for body in _bodies(self.plant)[1:] if self._weld_root(body)[0].index() == self.plant.world_body().index())

    # -- reading ----------------------------------------------------------
    def _hang_urdf_root(self, root):
        """A URDF's root link on the case's root joint (a ball, as Pinocchio's spherical root joint), attached to the
        world at the link's origin; without one Drake would make it a free body (refused after Finalize)."""
        if not root:
            return
        if root.type != "spherical":
            raise Refused(f"{self.path}: urdf_root_joint type '{root.type}': this adapter hangs a URDF's root link on "
                          "a spherical joint only")
        children = {int(self.plant.get_joint(j).child_body().index()) for j in self.plant.GetJointIndices()}
        orphans = [body for body in _bodies(self.plant)[1:] if int(body.index()) not in children]
        if len(orphans) != 1:
            raise Refused(f"{self.path}: {len(orphans)} root links; a urdf_root_joint hangs one")
        self.plant.AddJoint(BallRpyJoint(root.name, self.plant.world_frame(), orphans[0].body_frame()))

    def _refuse_free_bodies(self):
        for j in self.plant.GetJointIndices():
            joint = self.plant.get_joint(j)
            if joint.num_velocities() == 6:
                raise Refused(f"{self.path}: Drake makes body '{joint.child_body().name()}' a free body "
                              f"({joint.type_name()}): a URDF's root link that no joint attaches to the world, and the "
                              "case names no urdf_root_joint; a free body is refused (as MuJoCo's <freejoint>)")
            if not isinstance(joint, (*SCALAR_JOINTS, BallRpyJoint, WeldJoint)):
                raise Refused(f"{self.path}: joint '{joint.name()}' is a Drake {joint.type_name()} joint: hinges, "
                              "slides and ball joints only")
            limits = np.concatenate([joint.position_lower_limits(), joint.position_upper_limits()])
            if np.any(np.abs(limits) < NO_LIMIT):
                raise Refused(f"{self.path}: joint '{joint.name()}' has limits, which Drake's continuous plant ignores")

    def _check_damping(self):
        """Drake's parser reads MJCF dampers itself: what it read must be what MuJoCo's compiler resolves."""
        for name, joint in self._joints().items():
            drake = joint.GetDampingVector(self.context)
            file = self.joint_values["damping"].get(name, 0.0)
            if not np.all(drake == file):
                raise Refused(f"{self.path}: joint '{name}': Drake's parser reads damping {drake.tolist()}, MuJoCo's "
                              f"compiler {file}")

    def _refuse_ball_springs(self):
        for name in self.joint_values["stiffness"]:
            if isinstance(self._joint(name), BallRpyJoint):
                raise Refused(f"{self.path}: joint '{name}' is a ball joint with a spring, which this adapter does not "
                              "model")

    def _joints(self):
        """{name: joint} of the plant's joints that move something (its welds left out)."""
        joints = (self.plant.get_joint(j) for j in self.plant.GetJointIndices())
        return {joint.name(): joint for joint in joints if joint.num_velocities()}

    def _joint(self, name):
        joint = self._joints().get(name)
        if joint is None:
            raise ValueError(f"{self.path}: no joint named '{name}'")
        return joint

    def _body(self, name):
        if not self.plant.HasBodyNamed(name):
            raise ValueError(f"{self.path}: no body named '{name}'")
        return self.plant.GetBodyByName(name)

    def _reaction_spec(self, name, spec):
        """(body, axis, frame, quantity) of a reaction: the cut force of the body's joint; a loop's force where the
        sensor names a <connect>."""
        if spec.sensor in self.loops.names:
            return "loop", (self.loops.names.index(spec.sensor), spec.axis), "world", "force"
        return self._body(spec.body), spec.axis, spec.frame, spec.quantity

    # -- the scene's values: bindings ----------------------------------------
    def _write(self, location, value):
        """Set a binding location's value (as MujocoModel._write): body mass, ipos, pos, inertia_about_origin, joint
        stiffness, springref, damping, option gravity.  A body's inertia is held in `_inertias` and set in Drake's
        context after all the writes: Drake refuses an inertia that no body can have, which one of several writes to
        a body may leave (the top's moments about its tip, written one axis after another)."""
        element, name, attribute, i = location.element, location.name, location.attribute, location.index
        if element == "option":
            gravity = self.plant.gravity_field().gravity_vector().copy()
            gravity[i] = value
            self.plant.mutable_gravity_field().set_gravity_vector(gravity)
        elif element == "joint":
            self.joint_values[attribute][name] = value
            if attribute == "damping":
                self._joint(name).SetDampingVector(self.context, [value])
        elif attribute == "pos":
            frame = self._inboard(name).frame_on_parent()
            pose = frame.GetPoseInParentFrame(self.context)
            translation = pose.translation().copy()
            translation[i] = value
            frame.SetPoseInParentFrame(self.context, RigidTransform(pose.rotation(), translation))
        else:
            mass, com, inertia = self._body_inertia(self._body(name))
            if attribute == "mass":
                mass = value
            elif attribute == "ipos":
                com = com.copy()
                com[i] = value
            else:  # an inertia (engines.bindings)
                inertia = written_inertia(location, value, mass, com, inertia, self._ball_armature(name),
                                          lambda: inertial_frame(self._inertial_frames, name, self.path))
            self._inertias[int(self._body(name).index())] = mass, com, inertia
            self._written.add(int(self._body(name).index()))  # set in the context after the writes
        self._last = None, None

    def _ball_armature(self, body):
        joint = self._inboard(body)
        return self.joint_values["armature"].get(joint.name(), 0.0) if isinstance(joint, BallRpyJoint) else 0.0

    def read(self, location):
        """The model's value at a binding location (as MujocoModel.read)."""
        element, name, attribute, i = location.element, location.name, location.attribute, location.index
        if element == "option":
            return float(self.plant.gravity_field().gravity_vector()[i])
        if element == "joint":
            return float(self.joint_values[attribute].get(name, 0.0))
        if attribute == "pos":
            return float(self._inboard(name).frame_on_parent().GetPoseInParentFrame(self.context).translation()[i])
        mass, com, inertia = self._body_inertia(self._body(name))
        if attribute == "mass":
            return mass
        if attribute == "ipos":
            return float(com[i])
        return read_inertia(location, mass, com, inertia, self._ball_armature(name),
                            lambda: inertial_frame(self._inertial_frames, name, self.path))

    def _inboard(self, body):
        """The joint (or weld) that carries body `body`."""
        index = self._body(body).index()
        return next(self.plant.get_joint(j) for j in self.plant.GetJointIndices()
                    if self.plant.get_joint(j).child_body().index() == index)

    def _body_inertia(self, body):
        """(mass, centre of mass, inertia about it) of a body in its frame, as the context holds them."""
        index = int(body.index())
        if index not in self._inertias:
            spatial = body.CalcSpatialInertiaInBodyFrame(self.context)
            mass, com = spatial.get_mass(), spatial.get_com()
            about_origin = spatial.CalcRotationalInertia().CopyToFullMatrix3()
            self._inertias[index] = mass, com, about_origin - mass * (com @ com * np.eye(3) - np.outer(com, com))
        return self._inertias[index]

    @property
    def gravity(self):
        return self.plant.gravity_field().gravity_vector().copy()

    def tree(self):
        """The moving bodies as Drake models them (see engines.scene.Body): one per joint, named after its child;
        a body welded to the world (MJCF's ground) folded into it, a body welded to a moving body into that body
        (its mass and inertia joined, engines.scene.combined_inertia), as the other adapters fold them; a ball
        joint's armature counted in its body's inertia, as MujocoModel.tree counts it."""
        bodies = []
        roots = {int(body.index()): self._weld_root(body) for body in _bodies(self.plant)[1:]}
        for name, joint in self._joints().items():
            parent, above = self._weld_root(joint.parent_body())
            pose = above @ joint.frame_on_parent().CalcPoseInBodyFrame(self.context)
            welded = parent.index() == self.plant.world_body().index()
            child = joint.child_body()
            parts = []
            for index, (root, placement) in roots.items():
                if root.index() == child.index():
                    part_mass, part_com, part_inertia = self._body_inertia(self.plant.get_body(BodyIndex(index)))
                    rotation = placement.rotation().matrix()
                    parts.append((part_mass, placement @ part_com, rotation @ part_inertia @ rotation.T))
            mass, com, inertia = scene_rules.combined_inertia(parts)
            kind = ("hinge" if isinstance(joint, RevoluteJoint) else "slide" if isinstance(joint, PrismaticJoint)
                    else "ball")
            axis = (joint.revolute_axis() if kind == "hinge" else joint.translation_axis() if kind == "slide"
                    else np.zeros(3))
            bodies.append(Body(name=joint.child_body().name(), parent="world" if welded else parent.name(), joint=name,
                               joint_type=kind, axis=np.array(axis), position=pose.translation().copy(),
                               rotation=pose.rotation().matrix().copy(), mass=float(mass), com=com.copy(),
                               inertia=inertia + self._ball_armature(joint.child_body().name()) * np.eye(3),
                               stiffness=np.array([self.joint_values["stiffness"].get(name, 0.0), 0.0, 0.0]),
                               springref=self.joint_values["springref"].get(name, 0.0),
                               damping=self.joint_values["damping"].get(name, 0.0)))
        return bodies

    def _weld_root(self, body):
        """The body that `body` is welded to through jointless bodies (itself if a joint moves it, the world if it
        is welded to the world), and body's pose in that body's frame."""
        pose = RigidTransform()
        while body.index() != self.plant.world_body().index():
            joint = self._inboard(body.name())
            if joint.num_velocities():
                break
            pose = self.plant.CalcRelativeTransform(self.context, joint.parent_body().body_frame(),
                                                    body.body_frame()) @ pose
            body = joint.parent_body()
        return body, pose

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
        for body in _bodies(self.plant):
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


class DrakeLoops:
    """The MJCF's <connect> loops on a Drake model (removed from Drake's plant, which refuses them in continuous
    time): each a point of body1 held on a point of body2, as engines.loops.Loop; closed by engines.loops'
    continuation on Drake's kinematics, and solved rigidly by Gauss's principle on Drake's M, bias and point
    Jacobians, as MujocoLoops does on MuJoCo's."""

    def __init__(self, model, document):
        self.model, self.plant, self.context = model, model.plant, model.context
        elements = [] if document is None else [e for equality in document.iter("equality") for e in equality]
        for element in elements:
            if element.tag != "connect":
                raise Refused(f"{model.path}: <{element.tag}>: only <connect> closes a loop here")
            if element.get("site1") is not None:
                raise Refused(f"{model.path}: <connect site1=...>: Drake's parser ignores sites; only the body form "
                              "(body1, body2, anchor) is read by this adapter")
        self.names = [e.get("name", "") for e in elements]
        self._points = [self._describe(e) for e in elements]  # (body1, anchor1, body2, anchor2)
        self.loops = tuple(Loop("connect", b1.name(), b2.name(), tuple(a1), tuple(a2), name)
                           for (b1, a1, b2, a2), name in zip(self._points, self.names))

    def _describe(self, element):
        """body1, its anchor, body2 and its anchor: where body1's is at the default configuration (MuJoCo's
        compiler puts body2's anchor at qpos0, which is Drake's zero)."""
        body1, body2 = (self.model._body(element.get(b)) for b in ("body1", "body2"))
        anchor1 = np.array([float(x) for x in element.get("anchor", "0 0 0").split()])
        self.plant.SetPositions(self.context, np.zeros(self.model.nq))
        world = body1.EvalPoseInWorld(self.context) @ anchor1
        return body1, anchor1, body2, body2.EvalPoseInWorld(self.context).inverse() @ world

    def _constraint(self, positions):
        """The loops' residual p1 - p2 (world, m) and its Jacobian d/dq at `positions` (hinges and slides: q = v)."""
        self.plant.SetPositions(self.context, positions)
        residuals, jacobians = [], []
        for body1, anchor1, body2, anchor2 in self._points:
            ends = [(self.plant.CalcPointsPositions(self.context, b.body_frame(), a, self.plant.world_frame())[:, 0],
                     self.plant.CalcJacobianTranslationalVelocity(self.context, JacobianWrtVariable.kV, b.body_frame(),
                                                                  a, self.plant.world_frame(), self.plant.world_frame()))
                    for b, a in ((body1, anchor1), (body2, anchor2))]
            residuals.append(ends[0][0] - ends[1][0])
            jacobians.append(ends[0][1] - ends[1][1])
        return np.concatenate(residuals), np.vstack(jacobians)

    def close(self, positions, rates, start=None):
        """Drake's positions and velocities with the independent joints at `positions`, `rates` ({joint: value})
        and the dependent ones closing every loop, on the branch of `start` (default the assembly, Drake's zero)."""
        joints = [self.model._joint(name) for name in positions]
        independent = np.array([joint.velocity_start() for joint in joints], dtype=int)
        begin = np.zeros(self.model.nq) if start is None else np.array(start, dtype=float)
        extent = max(np.linalg.norm(self.plant.get_joint(j).frame_on_parent().CalcPoseInBodyFrame(
            self.context).translation()) for j in self.plant.GetJointIndices())
        slides = [isinstance(joint, PrismaticJoint) for joint in joints]
        q, jacobian = _continuation(begin, [joint.position_start() for joint in joints],
                                    np.array(list(positions.values())), slides, independent, self.model.nv,
                                    self._constraint, lambda q, step: q + step, extent, self.model.path)
        self.plant.SetPositions(self.context, q)
        return q, _dependent_rates(jacobian, independent, np.array(list(rates.values())))

    def rates(self, independent):
        """Every dof's rate per unit rate of each independent dof, at the context's (closed) positions."""
        return _rates_map(self._constraint(self.plant.GetPositions(self.context))[1], independent)

    def constrained(self, mass, force):
        """The rigid loop's accelerations and each loop's force on body1 at its anchor (world, (nloops, 3)) at the
        context's state: M acc = force + J^T f, J acc = -Jdot v, `force` the generalised forces less the bias.
        Rows that carry no force direction (a planar loop's normal) are left out of the solve (as MujocoLoops)."""
        jacobian = self._constraint(self.plant.GetPositions(self.context))[1]
        bias = np.concatenate([self._bias(b1, a1) - self._bias(b2, a2) for b1, a1, b2, a2 in self._points])
        free = np.linalg.solve(mass, force)
        inverse_mass_jt = np.linalg.solve(mass, jacobian.T)
        live = np.any(jacobian != 0, axis=1)
        loop_force = np.zeros(len(jacobian))
        loop_force[live] = np.linalg.solve((jacobian @ inverse_mass_jt)[np.ix_(live, live)],
                                           (-bias - jacobian @ free)[live])
        self._jacobian = jacobian
        return free + inverse_mass_jt @ loop_force, loop_force.reshape(-1, 3)

    def _bias(self, body, anchor):
        return self.plant.CalcBiasTranslationalAcceleration(self.context, JacobianWrtVariable.kV, body.body_frame(),
                                                            anchor, self.plant.world_frame(),
                                                            self.plant.world_frame())[:, 0]

    def generalised(self, loop_forces):
        """J^T f: the loops' forces as generalised forces (at the last `constrained` state)."""
        return self._jacobian.T @ loop_forces.reshape(-1)

    def applied(self, loop_forces):
        """(world point, body index, force) of each loop's force on body1 at its anchor and the opposite on body2,
        at the context's positions; none without loops."""
        if loop_forces is None:
            return []
        out = []
        for (body1, anchor1, body2, anchor2), force in zip(self._points, loop_forces):
            for body, anchor, sign in ((body1, anchor1, 1.0), (body2, anchor2, -1.0)):
                out.append((body.EvalPoseInWorld(self.context) @ anchor, int(body.index()), sign * force))
        return out


def _bodies(plant):
    """Every body of the plant, the world first."""
    return [plant.get_body(BodyIndex(i)) for i in range(plant.num_bodies())]


def _refuse_misread(document, path):
    """What Drake's MJCF parser reads otherwise than MuJoCo's compiler without a word: several joints on one body
    (all but the last take the parent's axes)."""
    for body in document.iter("body"):
        joints = [j for j in body if j.tag in ("joint", "freejoint")]
        if len(joints) > 1:
            raise Refused(f"{path}: body '{body.get('name', '?')}' has {len(joints)} joints: Drake's MJCF parser puts "
                          "all but the last on the parent's axes, where MuJoCo's compiler puts them on the body's; "
                          "give every body one joint")
