"""The MJCF or URDF scene as Drake's adapter (engines.drake_adapter) reads and writes it: Drake's parser on the
file, what it drops or reads otherwise than MuJoCo's compiler refused (`Refused`) or corrected, the file's joints and
bodies in the plant, the bindings written into the context and read back, and the bodies as Drake models them."""

import logging
import xml.etree.ElementTree as ET

import numpy as np
from pydrake.math import RigidTransform
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import (BallRpyJoint, BodyIndex, PrismaticJoint, RevoluteJoint, RotationalInertia,
                                    SpatialInertia, WeldJoint)

from engines import scene as scene_rules
from engines.bindings import read_inertia, unphysical, written_inertia
from engines.mjcf_joints import NO_LIMIT, inertial_frame, inertial_frames, is_mjcf, joint_values

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


class DrakeScene:
    """DrakeModel's scene file: Drake's plant and context of it (`_read`), the file's joints and bodies in the plant,
    its bindings' values (`read`), its bodies (`tree`) and gravity (on the model's `path`)."""

    @staticmethod
    def elements_in(path):
        """What the scene file holds of a case's bindings (as PinocchioModel.elements_in)."""
        return {"body", "joint", "option"} if is_mjcf(path) else {"body"}

    def _read(self, scene, writes):
        """Drake's continuous plant of the scene file and its context, with what its parser drops or reads otherwise
        refused or corrected (the springs' values from the file, engines.mjcf_joints; a URDF's root link hung on the
        case's root joint), its loops' constraints removed (DrakeLoops solves them) and the case's bindings written;
        the file's document."""
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
            refuse_misread(document, self.path)
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
        self._written = set()  # the bodies whose inertia `_write` changed
        self._inertial_frames = inertial_frames(document, self.path)
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
        return document

    def _hang_urdf_root(self, root):
        """A URDF's root link on the case's root joint (a ball, as Pinocchio's spherical root joint), attached to the
        world at the link's origin; without one Drake would make it a free body (refused after Finalize)."""
        if not root:
            return
        if root.type != "spherical":
            raise Refused(f"{self.path}: urdf_root_joint type '{root.type}': this adapter hangs a URDF's root link on "
                          "a spherical joint only")
        children = {int(self.plant.get_joint(j).child_body().index()) for j in self.plant.GetJointIndices()}
        orphans = [body for body in plant_bodies(self.plant)[1:] if int(body.index()) not in children]
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
        """The moving bodies as Drake models them (see engines.scene.Body, engines.scene.moving_body): one per joint
        (several on one body are refused), named after its child; a body welded to the world (MJCF's ground) folded
        into it, a body welded to a moving body into that body (its mass and inertia joined,
        engines.scene.combined_inertia), as the other adapters fold them; a ball joint's armature counted in its
        body's inertia, as MujocoModel.tree counts it."""
        bodies = []
        roots = {int(body.index()): self._weld_root(body) for body in plant_bodies(self.plant)[1:]}
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
            spring = ([self.joint_values["stiffness"].get(name, 0.0), 0.0, 0.0],
                      self.joint_values["springref"].get(name, 0.0), self.joint_values["damping"].get(name, 0.0))
            bodies += scene_rules.moving_body(child.name(), "world" if welded else parent.name(),
                                              [(name, kind, np.array(axis), *spring)], pose.translation().copy(),
                                              pose.rotation().matrix().copy(), float(mass), com.copy(),
                                              inertia + self._ball_armature(child.name()) * np.eye(3))
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


def plant_bodies(plant):
    """Every body of the plant, the world first."""
    return [plant.get_body(BodyIndex(i)) for i in range(plant.num_bodies())]


def refuse_misread(document, path):
    """What Drake's MJCF parser reads otherwise than MuJoCo's compiler without a word: several joints on one body
    (all but the last take the parent's axes)."""
    for body in document.iter("body"):
        joints = [j for j in body if j.tag in ("joint", "freejoint")]
        if len(joints) > 1:
            raise Refused(f"{path}: body '{body.get('name', '?')}' has {len(joints)} joints: Drake's MJCF parser puts "
                          "all but the last on the parent's axes, where MuJoCo's compiler puts them on the body's; "
                          "give every body one joint")
