"""What dyncheck takes from a scene file: the status of every MJCF and URDF element and attribute
(modelled by both engines and compared between the two files, refused on load, or without effect
on these scenes' dynamics), and the neutral description of the bodies that each adapter models and
the harness compares.  docs/scene-elements.md is `markdown()`.

MJCF elements are named by the anchors of MuJoCo's XML reference (doc/XMLschema.rst in the mujoco
wheel: "body-joint" is <joint> in a <body>); a rule for an anchor covers the anchors below it.
URDF elements are the tags that urdfdom parses for Pinocchio's buildModelFromUrdf.
"""

from dataclasses import dataclass

import numpy as np

from engines import euler

COMPARED, REFUSED, NO_EFFECT = "modelled, compared", "refused", "no effect"


@dataclass(frozen=True, eq=False)
class Body:
    """A moving body as an engine models it (SI units): its joint, its placement in its parent's frame
    (`rotation` maps body to parent coordinates), and its mass, centre of mass and inertia about the
    centre of mass in its own frame.  `axis` is a hinge's or slide's unit axis, zeros for a ball."""
    name: str
    parent: str  # "world" for a body on the world
    joint: str
    joint_type: str  # "hinge" | "slide" | "ball"
    axis: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    stiffness: np.ndarray  # (a, b, c) of the joint's spring force -(a x + b x^2 + c x^3), x = q - springref
    springref: float  # the joint position at which its spring is relaxed (rad or m; 0 for a ball joint)
    damping: float  # viscous damping of the joint's dofs, force -damping q' (N s/m, N m s/rad)


@dataclass(frozen=True)
class Rule:
    file: str  # "MJCF" | "URDF"
    element: str
    attribute: str  # "*": every attribute of the element and of the elements below it
    status: str
    why: str
    fix: str = "remove it"  # what a refusal asks the author to do


def case_mass_matrix(mass, layout, q):
    """An engine's dof mass matrix `mass` (nv, nv) in the case's coordinates q: J^T mass J, J (nv, n) the map
    from the coordinates' rates to the dofs' velocities, so that it multiplies the case's accelerations in its
    equations of motion.  `layout`: (kind, first dof, coordinate indices) of each joint the case's coordinates
    move: a hinge or slide ("scalar") is its own coordinate; a ball joint's Euler angles ("euler") give the
    body's angular velocity J_ball rates (engines.euler), linear in the rates: its columns are the angular
    velocities of unit rates.  Prescribed dofs are no coordinates: their rows and columns drop out."""
    q = np.asarray(q, dtype=float)
    rates_to_dofs = np.zeros((len(mass), len(q)))
    for kind, dof, idx in layout:
        if kind == "scalar":
            rates_to_dofs[dof, idx[0]] = 1.0
        else:
            rates_to_dofs[dof:dof + 3, idx] = euler.angular_velocity(q[idx], np.eye(3)).T
    return rates_to_dofs.T @ mass @ rates_to_dofs


def applied_forces(forces, nv, t, q, v):
    """The applied generalized forces at the case's state (t, q, v), every dof's (nv,): `forces` are (first dof,
    force(t, q, v)) pairs, a joint's components from its first dof on."""
    out = np.zeros(nv)
    for dof, force in forces:
        value = force(t, q, v)
        out[dof:dof + len(value)] = value
    return out


# Joint names the case's [scene] moves or its loops close; any other joint would sit locked at its reference position.
def named_joints(scene):
    return ({joint for _, joint, _ in scene["layout"]} | set(scene["driven"]) | set(scene.get("dependent", ()))
            | ({scene["urdf_root_joint"]["name"]} if scene.get("urdf_root_joint") else set()))


PINOCCHIO_IGNORES = "Pinocchio's dynamics ignore it"
NO_COUNTERPART = "URDF and Pinocchio have no counterpart"
SET_BY_HARNESS = "the harness sets it for every run and never steps the evaluation model"
COMPILED = "acts only through the compiled model, whose bodies and gravity are compared"
NO_CONTACTS = "acts only on contacts, and no two geoms can touch (see geom contype)"
NO_CONSTRAINTS = "acts only on constraints, and every constraint is refused"

RULES = [
    # -- MJCF: what the compiled mjModel must say ------------------------------------------------
    Rule("MJCF", "mujoco", "model", NO_EFFECT, "a name"),
    Rule("MJCF", "option", "gravity", COMPARED, "every component, against the case's g (the URDF side's gravity)"),
    Rule("MJCF", "option", "timestep", NO_EFFECT, SET_BY_HARNESS),
    Rule("MJCF", "option", "integrator", NO_EFFECT, SET_BY_HARNESS),
    Rule("MJCF", "option", "density", REFUSED, "fluid forces; " + NO_COUNTERPART),
    Rule("MJCF", "option", "viscosity", REFUSED, "fluid forces; " + NO_COUNTERPART),
    Rule("MJCF", "option", "wind", NO_EFFECT, "acts only through density and viscosity, which are refused"),
    Rule("MJCF", "option", "magnetic", NO_EFFECT, "read only by magnetometer sensors"),
    Rule("MJCF", "option", "*", NO_EFFECT, "solver, collision and sleeping settings: " + NO_CONSTRAINTS),
    Rule("MJCF", "option-flag", "gravity", REFUSED, "disabling gravity: the case's g would not act"),
    Rule("MJCF", "option-flag", "spring", REFUSED, "disabling springs: the case's stiffness would not act"),
    Rule("MJCF", "option-flag", "sensor", REFUSED, "disabling sensors: the reactions would read zeros"),
    Rule("MJCF", "option-flag", "sleep", REFUSED, "sleeping freezes slow bodies; " + NO_COUNTERPART),
    Rule("MJCF", "option-flag", "invdiscrete", REFUSED,
         "changes mj_inverse, which gives the reactions, for the one-step integrators"),
    Rule("MJCF", "option-flag", "*", NO_EFFECT, "switch off or on what is refused or unused here, or diagnostics"),
    Rule("MJCF", "compiler", "*", NO_EFFECT, COMPILED),
    Rule("MJCF", "size", "*", NO_EFFECT, "memory sizes"),
    Rule("MJCF", "statistic", "*", NO_EFFECT, "rendering scales"),
    Rule("MJCF", "visual", "*", NO_EFFECT, "rendering"),
    Rule("MJCF", "asset", "*", NO_EFFECT, "meshes and height fields act only through geoms; " + COMPILED),
    Rule("MJCF", "default", "*", NO_EFFECT, "reaches the elements that use the class; " + COMPILED),
    Rule("MJCF", "custom", "*", NO_EFFECT, "user data"),
    Rule("MJCF", "tuple", "*", NO_EFFECT, "user data (custom)"),
    Rule("MJCF", "keyframe", "*", NO_EFFECT, "the harness never loads a keyframe: every state comes from case.toml"),
    Rule("MJCF", "body", "name", COMPARED, "the body's name: both files hold the same bodies"),
    Rule("MJCF", "body", "(joints)", REFUSED,
         "a body without a joint (welded) or with several: each URDF link hangs on one joint; a jointless body"
         " welded to the world (a ground) is folded into it, as Pinocchio's MJCF reader does",
         "give every body one joint"),
    Rule("MJCF", "body", "pos", COMPARED, "the placement in the parent body, with the orientation below"),
    *[Rule("MJCF", "body", orientation, COMPARED, "the body's orientation in its parent (a rotation matrix)")
      for orientation in ("quat", "axisangle", "xyaxes", "zaxis", "euler")],
    Rule("MJCF", "body", "gravcomp", REFUSED, "an upward force; " + NO_COUNTERPART),
    Rule("MJCF", "body", "mocap", REFUSED, "a body moved by the user, not by the dynamics; " + NO_COUNTERPART),
    Rule("MJCF", "body", "*", NO_EFFECT, "defaults, sleeping policy (sleep is refused), fusing (bodies are compared)"
         " and user data"),
    Rule("MJCF", "body-inertial", "*", COMPARED,
         "mass, centre of mass and the full inertia about it in the body frame (iquat, fullinertia rotate it)"),
    Rule("MJCF", "body-joint", "name", COMPARED, "must be a joint that the case's [scene] names", "name it in the case"),
    Rule("MJCF", "body-joint", "type", COMPARED, "hinge, slide or ball (free is refused)"),
    Rule("MJCF", "body-joint", "axis", COMPARED, "the unit axis in the body frame"),
    Rule("MJCF", "body-joint", "pos", REFUSED, "a URDF joint sits at its link's origin", "move the body instead"),
    Rule("MJCF", "body-joint", "stiffness", COMPARED,
         "a b c of the spring force -(a x + b x^2 + c x^3), against the Pinocchio side's (the case's k, 0, 0)"),
    Rule("MJCF", "body-joint", "springdamper", COMPARED, "sets stiffness and damping (both compared)"),
    Rule("MJCF", "body-joint", "springref", COMPARED,
         "a spring's rest position, against the Pinocchio side's (the case's binding for a URDF, which has none)"),
    Rule("MJCF", "body-joint", "springyield", REFUSED, "a plastic spring; " + NO_COUNTERPART),
    Rule("MJCF", "body-joint", "ref", REFUSED, "shifts the joint's coordinate; URDF's are 0 at the link's placement"),
    Rule("MJCF", "body-joint", "damping", COMPARED,
         "a viscous joint damper, force -d q' (linear only: a polynomial damper is refused), against the Pinocchio"
         " side's generalised force; MuJoCo's Euler integrator treats it implicitly, its RK4 explicitly"),
    Rule("MJCF", "body-joint", "frictionloss", REFUSED, "dry friction; the Pinocchio side has none"),
    Rule("MJCF", "body-joint", "limited", REFUSED, "a joint limit; Pinocchio's dynamics have none"),
    Rule("MJCF", "body-joint", "range", NO_EFFECT, "acts only when limited, which is refused"),
    Rule("MJCF", "body-joint", "armature", REFUSED,
         "rotor inertia; allowed on prescribed joints, which it holds while MuJoCo steps (the evaluation model"
         " drops it), and on the ball joint of a body on the world, where it is the isotropic inertia a I about"
         " the joint and is compared as part of the body's inertia (the top)"),
    Rule("MJCF", "body-joint", "*", NO_EFFECT, "solver settings of limits and friction (both refused), actuator"
         " force limits (no actuators), gravity compensation routing (gravcomp refused), group and user data"),
    Rule("MJCF", "body-freejoint", "*", REFUSED, "a free body; no scene has one and URDF floating joints are refused"),
    Rule("MJCF", "body-geom", "contype", REFUSED,
         "with conaffinity, lets two geoms on different bodies touch: contacts have no counterpart in Pinocchio",
         "set contype=\"0\" conaffinity=\"0\""),
    Rule("MJCF", "body-geom", "conaffinity", REFUSED, "see contype", "set contype=\"0\" conaffinity=\"0\""),
    Rule("MJCF", "body-geom", "*", NO_EFFECT,
         "mass, density, size and placement act only through the body's inertia, which is compared; fluid"
         " settings only with density or viscosity (refused); the rest acts on contacts or rendering"),
    Rule("MJCF", "body-site", "quat", REFUSED, "on a reaction's site, any orientation (quat, euler, ...): turns"
         " the sensor's axes away from the body's, in which the Pinocchio side reads the force"),
    Rule("MJCF", "body-site", "pos", REFUSED, "on a moment reaction's site, off the body's origin: the torque"
         " sensor's moment is about the site, the Pinocchio side's about the joint at the body's origin",
         "put the site at the body's origin"),
    Rule("MJCF", "body-site", "*", NO_EFFECT, "a frame for sensors; a reaction's site is checked with its sensor"),
    Rule("MJCF", "body-camera", "*", NO_EFFECT, "rendering"),
    Rule("MJCF", "body-light", "*", NO_EFFECT, "rendering"),
    Rule("MJCF", "body-attach", "*", NO_EFFECT, "inserts bodies, which are compared"),
    Rule("MJCF", "body-flexcomp", "*", REFUSED, "deformable bodies; " + NO_COUNTERPART),
    Rule("MJCF", "body-plugin", "*", REFUSED, "engine plugins; " + NO_COUNTERPART),
    Rule("MJCF", "geom-plugin", "*", REFUSED, "engine plugins; " + NO_COUNTERPART),
    Rule("MJCF", "mesh-plugin", "*", NO_EFFECT, "makes a mesh, which acts only through geoms (see asset)"),
    Rule("MJCF", "plugin", "*", REFUSED, "engine plugins; " + NO_COUNTERPART),
    Rule("MJCF", "instance", "*", REFUSED, "engine plugins; " + NO_COUNTERPART),
    Rule("MJCF", "extension", "*", REFUSED, "engine plugins; " + NO_COUNTERPART),
    Rule("MJCF", "deformable-flex", "*", REFUSED, "deformable bodies; " + NO_COUNTERPART),
    Rule("MJCF", "flex", "*", REFUSED, "deformable bodies; " + NO_COUNTERPART),
    Rule("MJCF", "flexcomp", "*", REFUSED, "deformable bodies; " + NO_COUNTERPART),
    Rule("MJCF", "deformable-skin", "*", NO_EFFECT, "rendering"),
    Rule("MJCF", "skin", "*", NO_EFFECT, "rendering"),
    Rule("MJCF", "material", "*", NO_EFFECT, "rendering"),
    Rule("MJCF", "contact-pair", "*", REFUSED, "an explicit contact; " + NO_COUNTERPART),
    Rule("MJCF", "contact-exclude", "*", NO_EFFECT, "removes contacts, and none can happen"),
    Rule("MJCF", "equality-connect", "*", COMPARED,
         "closes a kinematic loop (engines.loops): its bodies and anchors against the Pinocchio side's constraint"
         " (an MJCF read by Pinocchio's MJCF reader; a URDF closes none and is refused); solimp below MuJoCo's"
         " stiffest (0.9999) or active=\"false\" is refused", "give the Pinocchio side the same loop"),
    Rule("MJCF", "equality", "*", REFUSED, "weld, joint, tendon and flex constraints: Pinocchio's MJCF reader drops"
         " joint and tendon equalities, and a weld's orientation is not compared", "close the loop with a <connect>"),
    Rule("MJCF", "tendon", "*", REFUSED, "tendons; " + NO_COUNTERPART),
    Rule("MJCF", "spatial", "*", REFUSED, "tendons; " + NO_COUNTERPART),
    Rule("MJCF", "fixed", "*", REFUSED, "tendons; " + NO_COUNTERPART),
    Rule("MJCF", "actuator", "*", REFUSED, "actuators; prescribed motions and applied forces come from case.toml"),
    Rule("MJCF", "sensor", "*", NO_EFFECT, "sensors do not act on the simulation; a reaction's sensor is checked"
         " (sensor-force site)"),
    Rule("MJCF", "sensor-force", "site", COMPARED,
         "a reaction's sensor must be a force sensor on a site of the case's body, with the body's axes: the"
         " Pinocchio side reads the force on that body's joint, in its frame"),
    Rule("MJCF", "sensor-torque", "site", COMPARED,
         "a moment reaction's sensor must be a torque sensor on a site at the case's body's origin, with the"
         " body's axes: the Pinocchio side reads the moment on that body's joint about the joint's origin (the"
         " body's: an MJCF joint pos is refused), in its frame"),
    Rule("MJCF", "sensor", "cutoff", REFUSED, "on a reaction's sensor: clamps the reading"),
    Rule("MJCF", "sensor", "nsample", REFUSED, "on a reaction's sensor: delays or holds the reading"),
    # -- URDF: what urdfdom parses and Pinocchio reads, or drops ---------------------------------
    Rule("URDF", "robot", "name", NO_EFFECT, "a name"),
    Rule("URDF", "link", "name", COMPARED, "the body's name: both files hold the same bodies"),
    Rule("URDF", "link/inertial/origin", "xyz", COMPARED, "the centre of mass in the link frame"),
    Rule("URDF", "link/inertial/origin", "rpy", COMPARED, "rotates the inertia into the link frame"),
    Rule("URDF", "link/inertial/mass", "value", COMPARED, "the mass"),
    Rule("URDF", "link/inertial/inertia", "*", COMPARED, "ixx ... izz: the inertia about the centre of mass"),
    Rule("URDF", "link/visual", "*", NO_EFFECT, "geometry: Pinocchio's dynamic model does not read it"),
    Rule("URDF", "link/collision", "*", NO_EFFECT, "geometry: Pinocchio's dynamic model does not read it"),
    Rule("URDF", "joint", "name", COMPARED, "must be a joint that the case's [scene] names", "name it in the case"),
    Rule("URDF", "joint", "type", COMPARED,
         "revolute and continuous (hinge), prismatic (slide); fixed, floating and planar are refused",
         "use revolute, continuous or prismatic"),
    Rule("URDF", "joint/origin", "*", COMPARED, "xyz, rpy: the link's placement in its parent"),
    Rule("URDF", "joint/axis", "xyz", COMPARED, "the unit axis in the link frame"),
    Rule("URDF", "joint/parent", "link", COMPARED, "the parent body"),
    Rule("URDF", "joint/child", "link", COMPARED, "the body the joint moves"),
    Rule("URDF", "joint/limit", "lower", REFUSED,
         "a joint limit: Pinocchio's dynamics ignore it and the MJCF has none; URDF cannot write 'no limit'"
         " for revolute and prismatic joints (urdfdom refuses inf), so dyncheck reads |limit| >= 1e300 as none",
         'write lower="-1e300" upper="1e300", or use a continuous joint'),
    Rule("URDF", "joint/limit", "upper", REFUSED, "see lower", 'write lower="-1e300" upper="1e300"'),
    Rule("URDF", "joint/limit", "*", NO_EFFECT, "effort and velocity: Pinocchio's dynamics do not clamp"),
    Rule("URDF", "joint/dynamics", "damping", COMPARED,
         "a viscous joint damper: Pinocchio's algorithms ignore it, so this adapter applies -d q' as a generalised force"),
    Rule("URDF", "joint/dynamics", "friction", REFUSED, PINOCCHIO_IGNORES),
    Rule("URDF", "joint/mimic", "*", REFUSED, "Pinocchio builds its models here without mimic joints"),
    Rule("URDF", "joint/calibration", "*", NO_EFFECT, "for controllers"),
    Rule("URDF", "joint/safety_controller", "*", NO_EFFECT, "for controllers"),
    Rule("URDF", "material", "*", NO_EFFECT, "rendering"),
    Rule("URDF", "transmission", "*", NO_EFFECT, "for controllers; urdfdom skips it"),
    Rule("URDF", "gazebo", "*", NO_EFFECT, "for Gazebo; urdfdom skips it"),
]


def rule(file, element, attribute):
    """The rule for an attribute of an element (MJCF: an anchor of the reference): the element's own,
    else its "*", else those of the elements above it."""
    sep = "-" if file == "MJCF" else "/"
    parts = element.split(sep)
    for n in range(len(parts), 0, -1):
        for candidate in (attribute, "*"):
            found = [r for r in RULES if (r.file, r.element, r.attribute) == (file, sep.join(parts[:n]), candidate)]
            if found:
                return found[0]
    raise KeyError(f"no rule for {file} {element} {attribute}")


def refusal(path, file, element, attribute, owner, value):
    """The one-line error for a refused attribute; `owner` names the element in its file, e.g. "joint 'psi'"."""
    found = rule(file, element, attribute)
    assert found.status != NO_EFFECT, found  # refused, or a compared attribute's value that cannot be compared
    tag = element.replace("-", "/").split("/")[-1]
    if attribute == "*":
        shown = f"<{tag}>"
    elif attribute.startswith("("):  # not an attribute: a count, such as a body's joints
        shown = f"<{tag}> with {attribute[1:-1]} = {value}"
    else:
        shown = f'<{tag} {attribute}="{value}">'

    return ValueError(f"{path}: {owner} {shown} is not modelled by dyncheck ({found.why}); {found.fix}")


def markdown():
    """docs/scene-elements.md."""
    lines = ["# Scene elements", "",
             "Generated by `engines.scene.markdown()` from `engines.scene.RULES`; a test checks that it is current.",
             "", "Every element and attribute of a case's scene.xml (MJCF) and scene.urdf (URDF) is either modelled"
             " by both engines and compared between the two files when both are loaded, refused on load (exit 2,"
             " naming the file, the element and the attribute), or without effect on these scenes' dynamics.",
             "MJCF elements are the anchors of MuJoCo's XML reference (`body-joint` is `<joint>` in a `<body>`); a"
             " rule for an element covers the elements below it, `*` every attribute not listed.",
             "The comparison's tolerances are in `dyncheck/case.py` (`compare_scenes`).", "",
             "| file | element | attribute | status | why |", "|---|---|---|---|---|"]
    lines += [f"| {r.file} | {r.element} | {r.attribute} | {r.status} | {r.why} |" for r in RULES]
    return "\n".join(lines) + "\n"
