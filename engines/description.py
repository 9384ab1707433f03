"""The scene description a case hands the engine adapters (dyncheck.case.scene builds it from case.toml's [scene]):
typed values, so that an adapter reads `scene.reactions[name].sensor`, not a nested dict.  Plain data: nothing
here reads a file or imports an engine.  The joints are named as in the scene files."""

from dataclasses import dataclass
from typing import Callable, Mapping


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
class Scene:
    """What the adapters take of a case: its coordinates and the joints they move (`layout`), the prescribed
    motions and applied forces by joint, the reactions and points by name, the bodies whose paths are traced,
    the URDF's root joint and the joints that closed loops move (`dependent`, engines.loops)."""
    coords: tuple[str, ...]
    layout: tuple[Coordinates, ...]
    driven: Mapping[str, Driven]
    applied: Mapping[str, Callable]  # joint -> force(t, q, v), with `constant` (dyncheck.case.scene.AppliedForce)
    reactions: Mapping[str, Reaction]
    points: Mapping[str, Point]
    paths: tuple[str, ...] = ()
    urdf_root_joint: RootJoint | None = None
    dependent: tuple[str, ...] = ()
