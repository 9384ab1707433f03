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
    frame: bool = False  # a massless frame between the joints of one body of the file (`moving_body`), no body of it


def joint_frame(body, joint):
    """The name, in `tree`, of the frame of a body with several joints that its joint `joint` moves and its next joint
    moves on (a massless Body: see `moving_body`)."""
    return f"{body}/{joint}"


def moving_body(name, parent, joints, position, rotation, mass, com, inertia):
    """A moving body as the adapters' `tree` describes it: a Body per joint of `joints` ((joint, joint_type, axis,
    stiffness, springref, damping) each, in the file's order).  Several joints on one body act in turn at the body's
    origin (MuJoCo's kinematics, and Pinocchio's composite joint): each turns or slides the frame that the one before
    leaves, about its axis in the body's frame; so they are a chain of massless frames (`joint_frame`), the first at
    the body's placement, the others on it, and the body, with all its mass, on the last."""
    bodies = []
    for k, (joint, joint_type, axis, stiffness, springref, damping) in enumerate(joints):
        first, last = k == 0, k == len(joints) - 1
        bodies.append(Body(name=name if last else joint_frame(name, joint), parent=parent if first else bodies[-1].name,
                           joint=joint, joint_type=joint_type, axis=np.asarray(axis, dtype=float),
                           position=position if first else np.zeros(3), rotation=rotation if first else np.eye(3),
                           mass=mass if last else 0.0, com=com if last else np.zeros(3),
                           inertia=inertia if last else np.zeros((3, 3)), stiffness=np.asarray(stiffness, dtype=float),
                           springref=springref, damping=damping, frame=not last))
    return bodies


def combined_inertia(parts):
    """(mass, centre of mass, inertia about it) of rigidly joined parts, each (mass, centre of mass, inertia about its
    centre of mass) in one frame: a body and the bodies welded to it."""
    mass = sum(part_mass for part_mass, _, _ in parts)
    com = sum(part_mass * np.asarray(part_com) for part_mass, part_com, _ in parts) / mass if mass else np.zeros(3)
    inertia = np.zeros((3, 3))
    for part_mass, part_com, part_inertia in parts:
        lever = np.asarray(part_com) - com
        inertia = inertia + part_inertia + part_mass * (lever @ lever * np.eye(3) - np.outer(lever, lever))
    return float(mass), com, inertia


@dataclass(frozen=True)
class Rule:
    file: str  # "MJCF" | "URDF"
    element: str
    attribute: str  # "*": every attribute of the element and of the elements below it
    status: str
    why: str
    fix: str = "remove it"  # what a refusal asks the author to do
    with_loops: bool = False  # refused only in a scene with a loop (<connect>), without effect in one without


# Joint names the case's [scene] moves or its loops close; any other joint would sit locked at its reference position.
def named_joints(scene):
    return ({c.joint for c in scene.layout} | set(scene.driven) | set(scene.dependent)
            | ({scene.urdf_root_joint.name} if scene.urdf_root_joint else set()))


PINOCCHIO_IGNORES = "Pinocchio's dynamics ignore it"
NO_COUNTERPART = "URDF and Pinocchio have no counterpart"
SET_BY_HARNESS = "the harness sets it for every run and never steps the evaluation model"
COMPILED = "acts only through the compiled model, whose bodies and gravity are compared"
NO_CONTACTS = "acts only on contacts, and no two geoms can touch (see geom contype)"
NO_ACTUATORS = "acts only on actuators, which are refused"
LOOP_SOLVER = ("MuJoCo steps a loop (<connect>) with its constraint solver, and the allowance for its runs measures the"
               " loop's softness with the default solver; without a loop no constraint row arises")

RULES = [
    # -- MJCF: what the compiled mjModel must say ------------------------------------------------
    Rule("MJCF", "mujoco", "model", NO_EFFECT, "a name"),
    # every <option> attribute and <flag> of MuJoCo's, each with its own rule (tests/test_scene_options.py walks
    # the installed MuJoCo's): a flag's rule judges its value other than the default
    Rule("MJCF", "option", "timestep", NO_EFFECT, SET_BY_HARNESS),
    Rule("MJCF", "option", "integrator", NO_EFFECT, "the harness sets it for every run, and evaluates under MuJoCo's"
         " Euler (the discrete integrator changes mj_forward's accelerations in a loop)"),
    Rule("MJCF", "option", "gravity", COMPARED, "every component, against the case's g (the URDF side's gravity)"),
    Rule("MJCF", "option", "density", REFUSED, "fluid forces; " + NO_COUNTERPART),
    Rule("MJCF", "option", "viscosity", REFUSED, "fluid forces; " + NO_COUNTERPART),
    Rule("MJCF", "option", "wind", NO_EFFECT, "acts only through density and viscosity, which are refused"),
    Rule("MJCF", "option", "magnetic", NO_EFFECT, "read only by magnetometer sensors"),
    *[Rule("MJCF", "option", solver, REFUSED, LOOP_SOLVER, with_loops=True)
      for solver in ("solver", "iterations", "tolerance", "ls_iterations", "ls_tolerance")],
    Rule("MJCF", "option", "jacobian", NO_EFFECT, "dense or sparse constraint Jacobian: the same loop forces up to"
         " rounding (measured on the slider-crank's runs: 1e-12)"),
    Rule("MJCF", "option", "noslip_iterations", REFUSED, "the noslip solver acts only on contacts and dry friction"
         " (refused), and MuJoCo's derivatives (mjd_inverseFD), which the linearisation takes, refuse it"),
    Rule("MJCF", "option", "noslip_tolerance", NO_EFFECT, "acts only through noslip_iterations, which are refused"),
    *[Rule("MJCF", "option", contact, NO_EFFECT, NO_CONTACTS)
      for contact in ("impratio", "cone", "o_margin", "o_solref", "o_solimp", "o_friction", "ccd_iterations",
                      "ccd_tolerance", "sdf_iterations", "sdf_initpoints")],
    Rule("MJCF", "option", "sleep_tolerance", NO_EFFECT, "acts only with the sleep flag, which is refused"),
    Rule("MJCF", "option", "actuatorgroupdisable", NO_EFFECT, NO_ACTUATORS),
    *[Rule("MJCF", "option-flag", flag, REFUSED, "opens every loop in MuJoCo alone; without a loop no constraint"
           " row arises (the harness switches MuJoCo's constraint stage off)", with_loops=True)
      for flag in ("constraint", "equality")],
    Rule("MJCF", "option-flag", "frictionloss", NO_EFFECT, "switches off dry friction, which is refused"),
    Rule("MJCF", "option-flag", "limit", NO_EFFECT, "switches off joint and tendon limits, which are refused"),
    Rule("MJCF", "option-flag", "contact", NO_EFFECT, "switches off contacts, and no two geoms can touch (see geom"
         " contype)"),
    Rule("MJCF", "option-flag", "override", NO_EFFECT, "overrides contacts' parameters: " + NO_CONTACTS),
    Rule("MJCF", "option-flag", "spring", REFUSED, "disabling springs: the case's stiffness would not act"),
    Rule("MJCF", "option-flag", "damper", REFUSED, "disabling dampers: MuJoCo alone would drop the joints' damping,"
         " which the Pinocchio side applies and the case binds"),
    Rule("MJCF", "option-flag", "gravity", REFUSED, "disabling gravity: the case's g would not act"),
    Rule("MJCF", "option-flag", "clampctrl", NO_EFFECT, NO_ACTUATORS),
    Rule("MJCF", "option-flag", "actuation", NO_EFFECT, NO_ACTUATORS),
    Rule("MJCF", "option-flag", "warmstart", NO_EFFECT, "the constraint solver's starting point: a loop's same"
         " forces to the solver's tolerance (measured on the slider-crank's runs: 1.3e-10 of its rates)"),
    Rule("MJCF", "option-flag", "island", NO_EFFECT, "splits the constraint solve into independent islands: the"
         " same loop forces (measured on the slider-crank's runs: bit for bit)"),
    Rule("MJCF", "option-flag", "refsafe", REFUSED, "lets a loop's stabilisation be faster than MuJoCo's steps"
         " resolve; " + LOOP_SOLVER, with_loops=True),
    Rule("MJCF", "option-flag", "diagexact", REFUSED, "changes the impedance of a loop's soft constraint (measured:"
         " 4e-5 of the slider-crank's runs); " + LOOP_SOLVER, with_loops=True),
    Rule("MJCF", "option-flag", "filterparent", NO_EFFECT, "adds parent-child pairs of geoms to contacts; every"
         " pair of geoms on two bodies that could touch is refused, parent and child included (geom contype)"),
    *[Rule("MJCF", "option-flag", collision, NO_EFFECT, "collision detection: " + NO_CONTACTS)
      for collision in ("midphase", "nativeccd", "multiccd", "speculative")],
    Rule("MJCF", "option-flag", "sensor", REFUSED, "disabling sensors: the reactions would read zeros"),
    Rule("MJCF", "option-flag", "eulerdamp", REFUSED, "makes MuJoCo's Euler integrator step the joints' damping"
         " explicitly, unlike the Euler runs that body-joint damping describes (measured: 2.5e-5 of the tutorial's"
         " cart-pendulum's Euler run with a damper)"),
    Rule("MJCF", "option-flag", "autoreset", NO_EFFECT, "a run's blow-up is found from its state and MuJoCo's"
         " warnings, which it counts with or without the reset (dyncheck.run.simulate)"),
    Rule("MJCF", "option-flag", "energy", NO_EFFECT, "fills mjData.energy in mj_forward; the harness computes the"
         " energy itself (mj_energyPos, mj_energyVel)"),
    Rule("MJCF", "option-flag", "fwdinv", NO_EFFECT, "a diagnostic (mjData.solver_fwdinv) that the harness does not"
         " read (measured: every evaluation bit for bit)"),
    Rule("MJCF", "option-flag", "sleep", REFUSED, "sleeping freezes slow bodies; " + NO_COUNTERPART),
    Rule("MJCF", "option-flag", "invdiscrete", REFUSED,
         "changes mj_inverse, which gives the reactions, for the one-step integrators"),
    Rule("MJCF", "option-flag", "ipc", REFUSED, "the discrete integrator's contact mode: needs that integrator,"
         " which the harness replaces, and has no inverse dynamics (mj_inverse gives the reactions)"),
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
    Rule("MJCF", "body", "(joints)", COMPARED,
         "several joints on one body act in turn at its origin (MuJoCo's kinematics; Pinocchio's MJCF reader makes"
         " them one composite joint): compared as a chain of massless frames named body/joint, the body on the last"
         " (engines.scene.moving_body); Drake's parser puts all but the last on the parent's axes, so Drake refuses"
         " them.  A body without a joint is welded: to the world (a ground, folded into it as Pinocchio's MJCF"
         " reader folds it; its constant potential energy left out of MuJoCo's) or to the moving body above it,"
         " whose mass and inertia it joins (as Pinocchio's readers merge it); a reaction on a welded body (the"
         " weld's force) is refused, Pinocchio keeping no joint there"),
    Rule("MJCF", "body", "pos", COMPARED, "the placement in the parent body, with the orientation below"),
    *[Rule("MJCF", "body", orientation, COMPARED, "the body's orientation in its parent (a rotation matrix)")
      for orientation in ("quat", "axisangle", "xyaxes", "zaxis", "euler")],
    Rule("MJCF", "body", "gravcomp", REFUSED, "an upward force; " + NO_COUNTERPART),
    Rule("MJCF", "body", "mocap", REFUSED, "a body moved by the user, not by the dynamics; " + NO_COUNTERPART),
    Rule("MJCF", "body", "*", NO_EFFECT, "defaults, sleeping policy (sleep is refused), fusing (bodies are compared)"
         " and user data"),
    Rule("MJCF", "body-inertial", "*", COMPARED,
         "mass, centre of mass and the full inertia about it in the body frame (iquat, fullinertia rotate it);"
         " bindable as body attributes mass, ipos, inertia (diaginertia: the principal moments in the inertial"
         " frame, index 0..2; the Pinocchio side reads that frame from quat only) and fullinertia (ixx iyy izz ixy"
         " ixz iyz in the body frame, index 0..5, read back from MuJoCo's principal moments and rotation); writes"
         " that leave a body without positive moments or A + B >= C are refused, naming it"),
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
         " drops it), and on the ball joint of a body on the world that has no other joint, where it is the"
         " isotropic inertia a I about the joint and is compared as part of the body's inertia (the top)"),
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
    Rule("MJCF", "body-frame", "*", REFUSED, "where Pinocchio reads the MJCF (no scene.urdf): its MJCF reader (4.1)"
         " drops the bodies inside it without a word, which MuJoCo's compiler places in the frame; with a scene.urdf"
         " they are compared", "write its pos and orientation into the bodies inside it"),
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
    Rule("URDF", "link/inertial/inertia", "*", COMPARED,
         "ixx ... izz: the inertia about the centre of mass; bindable as fullinertia (the tensor in the link frame,"
         " index 0..5: these six numbers where the inertial <origin> has no rpy) and inertia (its diagonal in the"
         " inertial frame, index 0..2), writes that leave a link unphysical refused, naming it"),
    Rule("URDF", "link/visual", "*", NO_EFFECT, "geometry: Pinocchio's dynamic model does not read it"),
    Rule("URDF", "link/collision", "*", NO_EFFECT, "geometry: Pinocchio's dynamic model does not read it"),
    Rule("URDF", "joint", "name", COMPARED, "must be a joint that the case's [scene] names", "name it in the case"),
    Rule("URDF", "joint", "type", COMPARED,
         "revolute and continuous (hinge), prismatic (slide), fixed (welds the child link to its parent, whose"
         " mass and inertia it joins, as the MJCF's body without a joint: a base link welded to the world, a tool"
         " link to the last link); floating and planar are refused",
         "use revolute, continuous, prismatic or fixed"),
    Rule("URDF", "joint/origin", "*", COMPARED, "xyz, rpy: the link's placement in its parent"),
    Rule("URDF", "joint/axis", "xyz", COMPARED, "the unit axis in the link frame"),
    Rule("URDF", "joint/parent", "link", COMPARED, "the parent body"),
    Rule("URDF", "joint/child", "link", COMPARED, "the body the joint moves"),
    Rule("URDF", "joint/limit", "lower", REFUSED,
         "a joint limit: Pinocchio's dynamics ignore it and the MJCF has none; a revolute or prismatic joint"
         " without <limit> has none (urdfdom rejects it: the adapter writes |limit| = 1e300 into it), and since"
         " urdfdom refuses inf, dyncheck reads |limit| >= 1e300 as none",
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


def judged(file, element, attribute):
    """`rule`, or for what RULES does not name (an option or flag of a newer MuJoCo: <option> has no "*") a
    refusal that says so."""
    try:
        return rule(file, element, attribute)
    except KeyError:
        return Rule(file, element, attribute, REFUSED, "not yet classified against both engines: a MuJoCo newer"
                    " than engines.scene.RULES", "remove it, or classify it in engines/scene.py")


def refusal(path, file, element, attribute, owner, value):
    """The one-line error for a refused attribute; `owner` names the element in its file, e.g. "joint 'psi'"."""
    found = judged(file, element, attribute)
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
             "Every `<option>` attribute and `<flag>` of MuJoCo has its own rule (a test walks the installed MuJoCo's);"
             " a flag's judges its value other than the default.  \"refused with a loop\": refused in a scene with a"
             " `<connect>`, without effect in one without.",
             "MJCF elements are the anchors of MuJoCo's XML reference (`body-joint` is `<joint>` in a `<body>`); a"
             " rule for an element covers the elements below it, `*` every attribute not listed.",
             "The comparison's tolerances are in `dyncheck/case/scene.py` (`compare_scenes`).", "",
             "| file | element | attribute | status | why |", "|---|---|---|---|---|"]
    lines += [f"| {r.file} | {r.element} | {r.attribute} | {r.status}{' with a loop' * r.with_loops} | {r.why} |"
              for r in RULES]
    return "\n".join(lines) + "\n"
