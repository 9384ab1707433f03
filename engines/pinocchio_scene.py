"""The URDF or MJCF scene as Pinocchio's adapter (engines.pinocchio_adapter) reads and writes it: Pinocchio's
model of the file, completed with what its readers drop or read otherwise than MuJoCo's compiler (an MJCF's
gravity, springs, dampers and armature: engines.mjcf_joints), the file's names in it, the bindings written and read,
the bodies as Pinocchio models them (`tree`), and what a URDF says that Pinocchio's dynamics drop (`unmodelled`)."""

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from engines import scene as scene_rules
from engines.bindings import INERTIA_ATTRIBUTES, read_inertia, unphysical, written_inertia
from engines.mjcf_joints import NO_LIMIT, inertial_frame, inertial_frames, is_mjcf, joint_values

ROOT_JOINTS = {"spherical": pin.JointModelSpherical}


class PinocchioScene:
    """PinocchioModel's scene file: Pinocchio's model `m` of it (`_read`), the file's joints and links in it, its
    bindings' values (`read`), its bodies (`tree`) and gravity (on the model's `path` and `neutral`)."""

    @staticmethod
    def elements_in(path):
        """What the scene file at `path` holds of a case's bindings (the case writes the rest): an MJCF its
        bodies, joints and options, a URDF only its bodies (masses and lengths: no springs, no gravity)."""
        return {"body", "joint", "option"} if is_mjcf(path) else {"body"}

    def _read(self, scene, writes):
        """Pinocchio's model `m` of the scene file, with what its readers leave out (`_complete_mjcf`, a URDF's
        dampers) and the case's bindings written, every inertia judged once all are written; the file's document and
        its loops' constraints (named here: the reader keeps no names)."""
        root = scene.urdf_root_joint
        constraints = []  # the loops' (a URDF closes none: refused against the MJCF's, dyncheck.case.folder)
        try:
            if is_mjcf(self.path) and _equalities(self.path):
                self.m, constraints = pin.buildModelAndLegacyConstraintsFromMJCF(self.path)
            elif is_mjcf(self.path):  # MJCF has ball joints: Pinocchio's spherical, no root joint to add
                self.m = pin.buildModelFromMJCF(self.path)
            elif root:  # URDF has no ball joint: the file's root link hangs on a spherical root joint
                self.m = pin.buildModelFromXML(_urdf_text(self.path), ROOT_JOINTS[root.type](), root.name)
            else:
                self.m = pin.buildModelFromXML(_urdf_text(self.path))
        except (ValueError, RuntimeError) as error:
            raise ValueError(f"{self.path}: {_reader_error(self.path, error)}") from error
        try:
            document = ET.parse(self.path).getroot()
        except ET.ParseError as error:  # stricter than urdfdom's parser
            raise ValueError(f"{self.path}: {error}") from None
        self._links = self._links_by_joint()
        self._composite = any(joint.shortname() == "JointModelComposite" for joint in self.m.joints)
        self._ball_armature = {}  # joint id: the armature `_complete_mjcf` holds in its body's inertia
        self._joints = self._joints_by_name(document)
        if is_mjcf(self.path):
            self._complete_mjcf(document, scene)
        else:
            # URDF has no springs: bindings set them; its dampers are Pinocchio's model.damping
            self.joint_values = {"stiffness": {}, "springref": {},
                                 "damping": {self.m.names[j]: float(self.m.damping[self.m.joints[j].idx_v])
                                             for j in range(1, self.m.njoints) if self.m.joints[j].nv == 1
                                             and self.m.damping[self.m.joints[j].idx_v]}}
            self.m.gravity.linear[:] = 0.0  # URDF has no gravity: the case's binding sets it
        self._inertial_frames = inertial_frames(document, self.path)
        # each joint's welded links (Pinocchio's readers merge them into its inertia, and keep each link's own in the
        # frame of its weld) and its own link's inertia, which the bindings set: the model's is their sum
        self._welded = {j: sum((f.placement.act(f.inertia) for f in self.m.frames if f.parentJoint == j
                                and f.type == pin.FrameType.FIXED_JOINT), pin.Inertia.Zero())
                        for j in range(1, self.m.njoints)}
        self._own = {j: self.m.inertias[j] - self._welded[j] if self._welded[j].mass else self.m.inertias[j].copy()
                     for j in range(1, self.m.njoints)}
        self._touched = set()  # the joints whose own link's inertia a binding sets
        self._written = {}  # body: its inertia as the writes leave it (about the centre of mass, in its frame)
        for location, value in writes:
            self._write(location, value)
        for body, inertia in self._written.items():  # once all are written: several may pass through an unphysical one
            why = unphysical(body, inertia)
            if why:
                raise ValueError(f"{self.path}: {why}")
            joint = self._body_joint(body)
            self._own[joint] = pin.Inertia(self._own[joint].mass, self._own[joint].lever, inertia + self._armature_of(joint))
        for joint in self._touched:
            self.m.inertias[joint] = self._own[joint] + self._welded[joint]
        for constraint, element in zip(constraints, _equalities(self.path)):  # the reader keeps no names
            constraint.name = element.get("name", "")
        return document, constraints

    def _complete_mjcf(self, document, scene):
        """What Pinocchio's MJCF parser leaves out: the file's gravity and joints' springs and dampers, which it
        drops; and the armature of MuJoCo's evaluation model (engines.mujoco_adapter): none on the prescribed joints, and
        a ball joint's armature a on a body on the world as what it is there, the isotropic inertia a I about
        the joint (MujocoModel.tree), held in the body's inertia so that `tree`, `read` and `_write` count it
        as the URDF side's inertia does.  Refuses what the parser reads otherwise than MuJoCo's compiler."""
        for frame in document.iter("frame"):
            owner = f"frame '{frame.get('name')}'" if frame.get("name") else "a frame"
            raise scene_rules.refusal(self.path, "MJCF", "body-frame", "*", owner, "")
        misread = next(_misread(document), None)
        if misread:
            raise ValueError(f"{self.path}: {misread}")
        option = document.find("option")
        gravity = option.get("gravity", DEFAULT_GRAVITY) if option is not None else DEFAULT_GRAVITY
        self.m.gravity.linear[:] = [float(x) for x in gravity.split()]
        self.joint_values = joint_values(document, self.path)
        for joint in scene.driven:
            self.m.armature[self._joint(joint).idx_v] = 0.0
        for j in range(1, self.m.njoints):
            joint = self.m.joints[j]
            if joint.shortname() == "JointModelSpherical" and self.m.parents[j] == 0:
                dofs = slice(joint.idx_v, joint.idx_v + joint.nv)
                inertia = self.m.inertias[j]
                self._ball_armature[j] = float(self.m.armature[joint.idx_v])  # MJCF's one value for the 3 dofs
                self.m.inertias[j] = pin.Inertia(inertia.mass, inertia.lever,
                                                 inertia.inertia + np.diag(self.m.armature[dofs]))
                self.m.armature[dofs] = 0.0

    def _joints_by_name(self, document):
        """{joint name: Pinocchio's joint model (nq, nv, idx_q, idx_v)}: the model's joints, and the joints that
        Pinocchio's MJCF reader makes one composite joint of, for an MJCF body with several (named after the first,
        its parts keep no names: they are the body's joints, in the file's order, engines.scene.moving_body)."""
        joints = {}
        for j in range(1, self.m.njoints):
            joint = self.m.joints[j]
            if joint.shortname() != "JointModelComposite":
                joints[self.m.names[j]] = joint
                continue
            names = [e.get("name") for b in document.iter("body") if b.get("name") == self._links[j]
                     for e in b if e.tag == "joint"]
            joints.update(zip(names, joint.extract().joints))
        return joints

    def _links_by_joint(self):
        """{joint id: the link it moves}: the first body frame on each joint; the links welded to it follow."""
        links = {}
        for frame in self.m.frames:
            if frame.type == pin.FrameType.BODY:
                links.setdefault(frame.parentJoint, frame.name)
        return links

    def _joint(self, name):
        if name not in self._joints:
            raise ValueError(f"{self.path}: no joint named '{name}'")
        return self._joints[name]

    def _body_frame(self, body):
        if not self.m.existBodyName(body):
            raise ValueError(f"{self.path}: no link named '{body}'")
        return self.m.getBodyId(body)

    def _point_frame(self, spec):
        """The frame whose kinematics a point reads: the link's own, or one added at its centre of mass."""
        frame_id = self._body_frame(spec.body)
        if spec.kind != "com acceleration":
            return frame_id
        frame = self.m.frames[frame_id]
        at_com = pin.SE3(frame.placement.rotation, self._own_com(frame_id))  # the link's axes, at its centre of mass
        return self.m.addFrame(pin.Frame(spec.body + "_com", frame.parentJoint, frame_id, at_com,
                                         pin.FrameType.OP_FRAME))

    def _own_com(self, frame_id):
        """The centre of mass of the link of body frame `frame_id` alone, in its joint's frame: Pinocchio's readers
        merge welded links into the joint's inertia, and keep each welded link's own in the frame of its weld (the
        body frame's parent)."""
        frame = self.m.frames[frame_id]
        if self._links.get(frame.parentJoint) != frame.name:  # a welded link: its weld's inertia is its own
            weld = self.m.frames[frame.parentFrame]
            return weld.placement.act(weld.inertia.lever)
        return self._own[frame.parentJoint].lever

    def _body_joint(self, body):
        """Id of the joint that moves link `body` (URDF link frames are those joints' frames here)."""
        return self.m.frames[self._body_frame(body)].parentJoint

    def _moved_joint(self, body, what):
        """`_body_joint` of a link that a joint moves itself; ValueError naming `what` for a welded link, whose
        mass and inertia Pinocchio's readers merge into the link it is welded to."""
        joint = self._body_joint(body)
        if self._links.get(joint) != body:
            raise ValueError(f"{self.path}: {what} of body '{body}', which is welded to body '{self._links.get(joint, 'world')}':"
                             " Pinocchio's reader merges its mass and inertia into that body's, and the Pinocchio side"
                             " reads no force or value of the weld itself")
        return joint

    def _slot(self, location):
        """(object, attribute) holding a binding location's value in the Pinocchio model."""
        element, name, attribute = location.element, location.name, location.attribute
        if element == "option":
            return self.m.gravity, "linear"
        if element == "joint":
            return self.joint_values[attribute], name
        joint = self._moved_joint(name, f"a binding of {attribute}")
        if attribute == "pos":
            return self.m.jointPlacements[joint], "translation"
        if attribute in INERTIA_ATTRIBUTES:
            return self._own[joint], attribute
        return self._own[joint], {"mass": "mass", "ipos": "lever"}[attribute]

    def _write(self, location, value):
        """Set a binding location's value; an inertia's in `_written` (set in the model once all are written)."""
        holder, key = self._slot(location)
        name = location.name
        if location.element == "body" and key != "translation":
            self._touched.add(self._body_joint(name))
        if key in INERTIA_ATTRIBUTES:  # about the com, in the body's frame
            self._written[name] = written_inertia(location, value, holder.mass, holder.lever,
                                                  self._written.get(name, self._inertia_of(name)),
                                                  self._ball_armature.get(self._body_joint(name), 0.0),
                                                  lambda: inertial_frame(self._inertial_frames, name, self.path))
        elif location.element == "joint":
            holder[key] = value
        elif np.ndim(getattr(holder, key)) == 0:
            setattr(holder, key, value)
        else:  # Pinocchio's bindings return these arrays by reference
            getattr(holder, key)[location.index] = value

    def _inertia_of(self, body):
        """A moving body's inertia about its centre of mass in its frame, as the file writes it: without the
        armature of a ball joint on the world that `_complete_mjcf` holds in it."""
        joint = self._moved_joint(body, "the inertia")
        return self._own[joint].inertia.copy() - self._armature_of(joint)

    def _armature_of(self, joint):
        return self._ball_armature.get(joint, 0.0) * np.eye(3)

    def tree(self):
        """The moving bodies as Pinocchio models them (see engines.scene.Body, engines.scene.moving_body): one per
        joint, named after the link it moves (its welded links' mass and inertia merged into it by Pinocchio's
        readers), a composite joint's parts a chain; a joint's axis is its motion subspace at the neutral
        configuration."""
        bodies = []
        for j in range(1, self.m.njoints):
            placement, inertia = self.m.jointPlacements[j], self.m.inertias[j]
            # 6 x nv; eigenpy hands a one-column matrix (a scene of one joint) back as a vector
            jacobian = np.reshape(pin.computeJointJacobian(self.m, self.m.createData(), self.neutral, j), (6, -1))
            joints = []
            for name, joint in self._parts(j):
                motion = jacobian[:, joint.idx_v]
                if joint.nv == 1:  # motion = (linear, angular) per unit rate, in the joint's frame
                    kind, axis = ("hinge", motion[3:]) if np.any(motion[3:]) else ("slide", motion[:3])
                else:  # a ball joint (spherical: the top)
                    kind, axis = "ball", np.zeros(3)
                joints.append((name, kind, axis.copy(), [self.joint_values["stiffness"].get(name, 0.0), 0.0, 0.0],
                               self.joint_values["springref"].get(name, 0.0), self.joint_values["damping"].get(name, 0.0)))
            parent = self.m.parents[j]
            bodies += scene_rules.moving_body(self._links[j], self._links[parent] if parent else "world", joints,
                                              placement.translation.copy(), placement.rotation.copy(),
                                              float(inertia.mass), inertia.lever.copy(), inertia.inertia.copy())
        return bodies

    def _parts(self, j):
        """(name, joint model) of the case's joints that Pinocchio's joint j holds: itself, or a composite's parts."""
        joint = self.m.joints[j]
        return [(name, part) for name, part in self._joints.items()
                if joint.idx_v <= part.idx_v < joint.idx_v + joint.nv]

    @property
    def gravity(self):
        return self.m.gravity.linear.copy()

    def read(self, location):
        holder, key = self._slot(location)
        name = location.name
        if key in INERTIA_ATTRIBUTES:
            return read_inertia(location, holder.mass, holder.lever, self._inertia_of(name),
                                self._ball_armature.get(self._body_joint(name), 0.0),
                                lambda: inertial_frame(self._inertial_frames, name, self.path))
        if location.element == "joint":
            return float(holder.get(key, 0.0))
        return float(np.atleast_1d(getattr(holder, key))[location.index])


def _urdf_text(path):
    """The URDF at `path` with `NO_LIMIT` written into each revolute or prismatic joint without a <limit>, which
    urdfdom rejects ("does not specify limits"): a joint without a limit has none.  ValueError for a file that
    is not XML, saying where."""
    try:
        robot = ET.parse(path).getroot()
    except ET.ParseError as error:
        raise ValueError(f"not well-formed XML: {error}") from None
    for joint in robot.iter("joint"):
        if joint.get("type") in ("revolute", "prismatic") and joint.find("limit") is None:
            ET.SubElement(joint, "limit", lower=f"{-NO_LIMIT:g}", upper=f"{NO_LIMIT:g}", effort="0", velocity="0")
    return ET.tostring(robot, encoding="unicode")


def _reader_error(path, error):
    """Pinocchio's reader's error in words: its message without the C++ file and function it comes from, and
    for an MJCF body that it finds no inertia of, which one and what to write."""
    message = str(error).split("message:", 1)[-1].strip()
    if "Cannot get inertia from geom" not in message:
        return message
    root = ET.parse(path).getroot()  # parsed by Pinocchio's reader already
    body = next(b.get("name", "?") for b in root.iter("body") if b.find("geom") is not None and b.find("inertial") is None)
    return (f"body '{body}' has a geom and no <inertial>, and <compiler inertiafromgeom=\"false\"> keeps MuJoCo from "
            f"taking its inertia from its geoms: Pinocchio's MJCF reader then finds none and stops; give body '{body}' "
            "an <inertial>, or remove inertiafromgeom=\"false\"")


def _equalities(path):
    """The <equality> constraints of an MJCF, in the file's order (Pinocchio's reader keeps it, not their names)."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError:  # reported where the adapter reads the file
        return []
    return [element for equality in root.iter("equality") for element in equality]


DEFAULT_GRAVITY = "0 0 -9.81"  # MuJoCo's, where the MJCF has no <option gravity>

# A unit axis written in decimals has a norm within an ulp or two of 1; Pinocchio's rotation is off
# by about |axis| - 1, which the scene comparison would find beyond 16 eps (dyncheck.case.folder.SCENE_RTOL).
UNIT_AXIS_RTOL = 4 * np.finfo(float).eps


def _misread(document):
    """What Pinocchio's MJCF parser (Pinocchio 4.1) reads otherwise than MuJoCo's compiler, which both accept
    without a word: one message each."""
    for compiler in document.iter("compiler"):
        sequence = compiler.get("eulerseq", "xyz")
        if sequence != sequence.lower():
            yield (f'<compiler eulerseq="{sequence}">: Pinocchio\'s MJCF parser turns every Euler angle about '
                   "the moving axes, where MuJoCo's upper-case letters name fixed ones; write the sequence in "
                   "lower case, or the orientations as quat")
    worldbody = document.find("worldbody")
    roots = [] if worldbody is None else worldbody.findall("body")
    if len(roots) > 1:
        yield (f"<worldbody> holds {len(roots)} bodies ({', '.join(b.get('name', '?') for b in roots)}): Pinocchio's "
               "MJCF parser (4.1) reads the first and drops the others without a word; give the scene one body on "
               "the world, or a scene.urdf")
    for element in document.iter():
        if element.tag in ("body", "inertial", "geom") and "axisangle" in element.attrib:
            norm = np.linalg.norm([float(x) for x in element.get("axisangle").split()[:3]])
            if abs(norm - 1.0) > UNIT_AXIS_RTOL:
                yield (f'<{element.tag} axisangle="{element.get("axisangle")}">: Pinocchio\'s MJCF parser does '
                       f"not normalise the axis (its norm is {norm:.17g}), MuJoCo's compiler does; write a unit axis")
        if element.tag == "include":
            yield (f'<include file="{element.get("file")}">: Pinocchio\'s MJCF parser skips included files; '
                   "write their elements into the scene")


def unmodelled(robot, scene):
    """What the URDF says that Pinocchio's dynamics drop, as (element, attribute, owner, value) of
    engines.scene.RULES (Pinocchio itself parses these silently), and joints the case does not move."""
    moved = scene_rules.named_joints(scene)
    for joint in robot.iter("joint"):
        name, kind = joint.get("name"), joint.get("type")
        owner = f"joint '{name}'"
        if kind == "fixed":  # a welded link: no coordinate, its mass and inertia merged into its parent's
            continue
        if kind not in ("revolute", "continuous", "prismatic"):  # no coordinate, named in the case or not
            yield "joint", "type", owner, kind
        if name not in moved:
            yield "joint", "name", owner, name
        limit = joint.find("limit")
        if limit is not None and kind != "continuous":  # a continuous joint's limits are ignored by urdfdom
            for bound in ("lower", "upper"):
                if abs(float(limit.get(bound, 0.0))) < NO_LIMIT:
                    yield "joint/limit", bound, owner, limit.get(bound, "0 (by default)")
        dynamics = joint.find("dynamics")
        if dynamics is not None and float(dynamics.get("friction", 0.0)):
            yield "joint/dynamics", "friction", owner, dynamics.get("friction")
        if joint.find("mimic") is not None:
            yield "joint/mimic", "*", owner, ""
