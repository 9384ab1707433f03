"""The MJCF scene as MuJoCo's adapter (engines.mujoco_adapter) reads and writes it: the bindings written into
MuJoCo's spec and read back from the compiled model, the bodies as MuJoCo models them (`tree`), a reaction's sensor,
and what the compiled model holds that dyncheck does not model (`unmodelled`, `options_set`: engines.scene.RULES)."""

import math
from xml.etree import ElementTree

import mujoco
import numpy as np

from engines import scene as scene_rules
from engines.bindings import FULL_INERTIA, full_tensor, parallel_axis, unphysical


class MujocoScene:
    """MujocoModel's scene file: its bindings' values (`read`), its bodies (`tree`), its gravity and a reaction's
    sensor, on the model's compiled MjModel `m` (and `path`, `armature`, `body_id`, `_id`)."""

    @staticmethod
    def elements_in(path):
        """What the scene file at `path` holds of a case's bindings (as PinocchioModel.elements_in): an
        MJCF holds them all."""
        return {"body", "joint", "option"}

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


def unmodelled(m, scene):
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


def refuse_nan(path):
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


def write_all(spec, writes):
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
