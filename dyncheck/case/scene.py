"""The scene a case hands the engine adapters, as typed values (`Scene` and its parts: plain data, which the adapters
read by attribute, so that engines/ imports nothing of dyncheck), built from its case file at its parameters
(`describe`), the applied forces in it (`AppliedForce`), the parameters' places in the scene files (`Binding`), and
the comparison of the case's two scene files (`compare_scenes`), body by body, with the placeholders MuJoCo needs
where the scene means no mass."""

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

import numpy as np

from dyncheck.case.coordinate_map import CoordinateMap, parse
from dyncheck.common import expressions


@dataclass(frozen=True)
class Coordinates:
    """A joint the case's coordinates move: `kind` "scalar" (a hinge or slide joint, one coordinate) or "euler"
    (a ball joint in the case's Euler angles, three); `indices` are their positions in the case's coordinates."""
    kind: str
    joint: str
    indices: tuple[int, ...]


@dataclass(frozen=True)
class Driven:
    """A joint's prescribed motion, at constant acceleration: angle + rate t + acc t^2 / 2 (rad or m)."""
    angle: float
    rate: float
    acc: float

    def at(self, t):
        return self.angle + self.rate * t + 0.5 * self.acc * t**2


@dataclass(frozen=True)
class Reaction:
    """A reaction the case compares: the force (or moment, `quantity`) component `axis` in `frame` ("world" or
    "body") that body `body` receives through its joint, read in MJCF from sensor `sensor` (or a loop's
    equality of that name)."""
    body: str
    sensor: str
    axis: int
    frame: str
    quantity: str = "force"


@dataclass(frozen=True)
class Point:
    """A point the case compares: `kind` (an acceleration, the centre of mass's, an angular velocity or
    acceleration) of body `body` in `frame`."""
    body: str
    frame: str
    kind: str = "acceleration"


@dataclass(frozen=True)
class RootJoint:
    """The joint Pinocchio gives the URDF's root (its `type`: "spherical"), named as the MJCF names it."""
    name: str
    type: str


@dataclass(frozen=True)
class Binding:
    """A parameter's place in the scene files (case.toml [scene.bindings]): the scene number at `location` (an
    engines.bindings.SceneLocation) is parameter `param` times `scale`; `depends` names the other parameters whose
    change rewrites it (an inertia about the origin follows the mass and the centre of mass)."""
    param: str
    location: object
    scale: float = 1.0
    depends: tuple[str, ...] = ()


def bindings(spec):
    """The Binding of each location of a case file's [scene.bindings], parameter by parameter in the file's order."""
    from engines.bindings import SceneLocation  # here, not above: rendering saved results imports no engine module
    return tuple(Binding(param, SceneLocation.of(table), table.get("scale", 1.0), tuple(table.get("depends", ())))
                 for param, tables in spec["scene"].get("bindings", {}).items() for table in tables)


@dataclass(frozen=True)
class Scene:
    """What the adapters take of a case: its coordinates and the joints they move (`layout`), the prescribed
    motions and applied forces by joint, the reactions and points by name, the bodies whose paths are traced,
    the URDF's root joint and the joints that closed loops move (`dependent`, engines.loops).  Where the case's
    coordinates are a map of the joints (`coordinate_map`, dyncheck.case.coordinate_map), `coords` are the joints:
    the adapters run in them, and the case's models are Mapped."""
    coords: tuple[str, ...]
    layout: tuple[Coordinates, ...]
    driven: Mapping[str, Driven]
    applied: Mapping[str, Callable]  # joint -> force(t, q, v), with `constant` (dyncheck.case.scene.AppliedForce)
    reactions: Mapping[str, Reaction]
    points: Mapping[str, Point]
    paths: tuple[str, ...] = ()
    urdf_root_joint: RootJoint | None = None
    dependent: tuple[str, ...] = ()
    coordinate_map: CoordinateMap | None = None


# The two scene files' bodies and gravity (engines.scene.Body) must agree to within SCENE_RTOL of the
# largest entry compared: each number is parsed from decimal text (half an ulp) and passes through a
# few roundings in each loader (a quaternion or rpy to a rotation matrix, a normalised axis,
# R diag(I) R^T, a ball joint's armature added back), each within an ulp or two of that entry.
SCENE_RTOL = 16 * np.finfo(float).eps
# MuJoCo needs mass and inertia on every moving body: the MJCF's massless bodies carry placeholders of at
# most 1e-12 kg and 1e-14 kg m^2 where the URDF has nothing.  Each case.toml (`why` of its pointwise
# tolerance) bounds their effect below that tolerance, and the engine tests keep m l^2 >= 1e-4 kg m^2,
# where 1e-14 is 1e-10 of it.  Mass and inertia may differ by these much more; a centre of mass is
# compared only on a body heavier than a placeholder.
PLACEHOLDER_MASS = 1e-12
PLACEHOLDER_INERTIA = 1e-14


class AppliedForce:
    """A joint's generalised force (case.toml [scene.applied]) at a state: force(t, q, v) in the case's
    coordinates, one number per degree of freedom of the joint, each a number or an expression of t, the
    coordinates, their rates (<coordinate>_rate) and the parameters.  `constant` when none names t, a
    coordinate or a rate: the engines then evaluate it once."""

    def __init__(self, components, coords, params):
        self.components = tuple(components)
        self._coords, self._rates = tuple(coords), tuple(f"{c}_rate" for c in coords)
        self._names = expressions.of_parameters(params)
        named = set().union(*(expressions.names(x) for x in self.components if isinstance(x, str)))
        self.of_state = bool(named & {*self._coords, *self._rates})
        self.constant = not (self.of_state or "t" in named)

    def __call__(self, t, q, v):
        names = {**self._names, "t": t, **dict(zip(self._coords, q)), **dict(zip(self._rates, v))}
        return np.array([float(expressions.evaluate(x, names)) if isinstance(x, str) else float(x)
                         for x in self.components])


def describe(case):
    """The scene of `case` (its [scene] table, every number at its parameters) as the adapters take it."""
    s = case.spec["scene"]
    mapped = parse(s["joints"], case.coords, case.params, f"{case.origin}: scene.joints") if "joints" in s else None
    if mapped and ("euler" in s or s.get("dependent")):
        raise ValueError(f"{case.origin}: scene.joints = {dict(s['joints'])}: a map of the coordinates takes hinges "
                         "and slides of an open chain; this scene has " + (
                             "a ball joint (scene.euler)" if "euler" in s else "closed loops (scene.dependent)"))
    coords = mapped.joints if mapped else tuple(case.coords)  # the adapters' coordinates
    index = {c: i for i, c in enumerate(coords)}
    layout = [Coordinates("scalar", joint, (i,)) for i, joint in enumerate(mapped.joints)] if mapped else \
        [Coordinates("scalar", joint, (index[c],)) for c, joint in s.get("coords", {}).items()]
    if "euler" in s:
        layout.append(Coordinates("euler", s["euler"]["joint"], tuple(index[c] for c in s["euler"]["coords"])))
    driven = {joint: Driven(*(case.value(m.get(key, 0.0)) for key in ("angle", "rate", "acc")))
              for joint, m in s["driven"].items()}
    applied = {}
    for joint, force in s.get("applied", {}).items():
        try:
            applied[joint] = AppliedForce(force, case.coords, case.params)
            if mapped and applied[joint].of_state:  # the adapters would evaluate it at the joints' state
                raise ValueError("with scene.joints (a map of the coordinates), an applied force may be a law of t "
                                 "and the parameters only, not of the coordinates or their rates")
        except ValueError as error:  # an expression that does not parse, or names what it may not
            raise ValueError(f"{case.origin}: scene.applied.{joint} = {force!r}: {error}") from None
    reactions = {name: Reaction(r["body"], r["sensor"], r["axis"], r["frame"], r.get("quantity", "force"))
                 for name, r in s["reactions"].items()}
    points = {name: Point(p["body"], p["frame"], p.get("kind", "acceleration")) for name, p in s.get("points", {}).items()}
    root = s.get("urdf_root_joint")
    return Scene(coords, tuple(layout), driven, applied, reactions, points, tuple(s.get("paths", [])),
                 RootJoint(root["name"], root["type"]) if root else None, tuple(s.get("dependent", [])), mapped)


def compare_scenes(mujoco_model, pinocchio_model, case_name):
    """Refuse two scene files that model different bodies or gravity (see engines.scene): ValueError
    naming both files, the body and the attribute."""
    mjcf, urdf = Path(mujoco_model.path).name, Path(pinocchio_model.path).name

    def differ(what, a, b, absolute=0.0):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        tolerance = SCENE_RTOL * max(np.max(np.abs(a)), np.max(np.abs(b))) + absolute
        if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))) or np.max(np.abs(a - b)) > tolerance:
            show = lambda x: np.array2string(x, precision=17, separator=", ").replace("\n", "")
            raise ValueError(f"{mjcf} and {urdf} of case '{case_name}' disagree: {what} is {show(a)} in {mjcf} "
                             f"and {show(b)} in {urdf} (tolerance {tolerance:.2g})")

    differ("gravity", mujoco_model.gravity, pinocchio_model.gravity)
    bodies = {engine: {b.name: b for b in model.tree()}
              for engine, model in (("mujoco", mujoco_model), ("pinocchio", pinocchio_model))}
    for name in bodies["mujoco"].keys() ^ bodies["pinocchio"].keys():
        present, absent = (mjcf, urdf) if name in bodies["mujoco"] else (urdf, mjcf)
        raise ValueError(f"{mjcf} and {urdf} of case '{case_name}' disagree: body '{name}' is in {present} "
                         f"but not in {absent}")
    for name, mj in bodies["mujoco"].items():
        pn = bodies["pinocchio"][name]
        for attribute in ("parent", "joint", "joint_type"):
            if getattr(mj, attribute) != getattr(pn, attribute):
                raise ValueError(f"{mjcf} and {urdf} of case '{case_name}' disagree: body '{name}' {attribute} "
                                 f"is '{getattr(mj, attribute)}' in {mjcf} and '{getattr(pn, attribute)}' in {urdf}")
        for attribute in ("axis", "position", "rotation", "stiffness", "springref", "damping"):
            differ(f"body '{name}' {attribute}", getattr(mj, attribute), getattr(pn, attribute))
        differ(f"body '{name}' mass", mj.mass, pn.mass, PLACEHOLDER_MASS)
        if max(mj.mass, pn.mass) > PLACEHOLDER_MASS:
            differ(f"body '{name}' centre of mass", mj.com, pn.com)
        for file, body in ((mjcf, mj), (urdf, pn)):  # a placeholder's centre of mass, about the body origin
            if body.mass <= PLACEHOLDER_MASS and not body.mass * (body.com @ body.com) <= PLACEHOLDER_INERTIA:
                raise ValueError(f"{file} of case '{case_name}': body '{name}' is a placeholder of {body.mass:.3g} kg "
                                 f"whose centre of mass {body.com.tolist()} puts {body.mass * (body.com @ body.com):.3g} "
                                 f"kg m^2 about its origin, beyond the {PLACEHOLDER_INERTIA:g} a placeholder may carry")
        differ(f"body '{name}' inertia about the centre of mass", mj.inertia, pn.inertia, PLACEHOLDER_INERTIA)
