"""What Pinocchio's and Drake's adapters read of a scene file's text, with no engine of their own: the joint values
of an MJCF that an engine's own MJCF reader drops or reads otherwise than MuJoCo's compiler (springs, their rest
positions, dampers, rotor inertia), resolved as MuJoCo's compiler resolves them; the bodies' inertial frames (MJCF
or URDF), which the readers fold into the inertia; and what a URDF's joint limits mean (NO_LIMIT)."""

import math

import numpy as np

JOINT_VALUES = {"stiffness": "spring", "springref": "spring's rest position", "damping": "damper",
                "armature": "rotor inertia"}
JOINT_DEFAULTS = {**dict.fromkeys(JOINT_VALUES, "0"), "type": "hinge"}  # MuJoCo's, where no class sets them
# URDF cannot write an unlimited revolute or prismatic joint (urdfdom requires <limit> and refuses inf): limits at or
# beyond this are read as none.
NO_LIMIT = 1e300


def is_mjcf(path):
    """Whether the scene file at `path` is an MJCF (a .xml file: the scene MuJoCo reads), not a URDF."""
    return str(path).endswith(".xml")


def joint_values(document, path):
    """{attribute: {joint: value}} of an MJCF's named joints for each of JOINT_VALUES, where not 0, as MuJoCo's
    compiler resolves it: the joint's own attribute, else the joint default of its class (its `class`, else the
    `childclass` of the nearest element around it that has one, else "main"), else of the classes around that
    one; a hinge's springref in rad, from the file's degrees under <compiler angle="degree"> (MJCF's default).
    ValueError for a polynomial spring or damper ("a b c"): the adapters' are linear."""
    defaults = {}

    def collect(default, inherited):
        joint = default.find("joint")
        own = {a: joint.get(a, inherited[a]) for a in JOINT_DEFAULTS} if joint is not None else inherited
        defaults[default.get("class", "main")] = own
        for child in default.findall("default"):
            collect(child, own)

    for default in document.findall("default"):
        collect(default, JOINT_DEFAULTS)
    degrees = all(compiler.get("angle", "degree") == "degree" for compiler in document.iter("compiler"))
    values = {attribute: {} for attribute in JOINT_VALUES}

    def walk(element, childclass):
        childclass = element.get("childclass", childclass)
        for child in element:
            if child.tag == "joint" and child.get("name"):  # an unnamed joint: the case cannot move it (refused)
                inherited = defaults.get(child.get("class", childclass), JOINT_DEFAULTS)
                for attribute, what in JOINT_VALUES.items():
                    text = child.get(attribute, inherited[attribute])
                    a, *higher = [float(x) for x in text.split()]
                    if any(higher):
                        raise ValueError(f'{path}: joint \'{child.get("name")}\' {attribute}="{text}": a polynomial '
                                         f"{what}, which the Pinocchio and Drake sides do not model; give the linear term only")
                    if attribute == "springref" and degrees and child.get("type", inherited["type"]) == "hinge":
                        a = math.radians(a)
                    if a:
                        values[attribute][child.get("name")] = a
            else:
                walk(child, childclass)

    walk(document.find("worldbody"), "main")
    return values


def inertial_frames(document, path):
    """{body: the rotation of its inertial frame in the body's frame} where it is not the identity: an MJCF
    <inertial quat>, a URDF <inertial><origin rpy>; for an MJCF orientation written otherwise, the words of the
    refusal of a binding that needs it (a body's `inertia`: diaginertia, in that frame)."""
    frames = {}
    if is_mjcf(path):
        for body in document.iter("body"):
            inertial = body.find("inertial")
            written = [] if inertial is None else [a for a in ("quat", "axisangle", "euler", "xyaxes", "zaxis")
                                                    if a in inertial.attrib]
            if inertial is not None and "fullinertia" in inertial.attrib:
                frames[body.get("name")] = ("its <inertial> gives fullinertia, whose principal moments are MuJoCo's"
                                            " decomposition of it; bind fullinertia")
            elif written == ["quat"]:
                frames[body.get("name")] = _quaternion_matrix([float(t) for t in inertial.get("quat").split()])
            elif written:
                frames[body.get("name")] = (f"its <inertial {written[0]}> is read here only as quat: write the inertial"
                                            " frame's orientation as quat, or bind fullinertia")
    else:
        for link in document.iter("link"):
            origin = link.find("inertial/origin")
            if origin is not None and origin.get("rpy"):
                frames[link.get("name")] = _rpy_matrix([float(t) for t in origin.get("rpy").split()])
    return frames


def inertial_frame(frames, body, path):
    """The rotation of `body`'s inertial frame in its frame from its `inertial_frames`, in which a binding of
    `inertia` is a diagonal entry (MJCF's diaginertia); ValueError naming the file and body for an orientation read
    here only as its refusal's words."""
    frame = frames.get(body)
    if isinstance(frame, str):
        raise ValueError(f"{path}: body '{body}': {frame}")
    return np.eye(3) if frame is None else frame


def _quaternion_matrix(quaternion):
    """The rotation of a quaternion (w, x, y, z), normalised as MuJoCo's compiler normalises it."""
    w, x, y, z = np.asarray(quaternion) / np.linalg.norm(quaternion)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _rpy_matrix(rpy):
    """URDF's roll, pitch, yaw: Rz(yaw) Ry(pitch) Rx(roll)."""
    (cr, cp, cy), (sr, sp, sy) = np.cos(rpy), np.sin(rpy)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])
