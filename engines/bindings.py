"""Where a case's parameter sits in a scene (`SceneLocation`), and a body's inertia as the adapters write and read
it there.  dyncheck makes the locations of a case file's [scene.bindings] (dyncheck.case.scene.Binding),
engines.mjcf those of a scene's own numbers, and every adapter's `read` and `_write` takes them: the type lives
here, where both sides may import it, since engines/ imports nothing of dyncheck."""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SceneLocation:
    """A number of a scene: the `attribute` of the `element` ("body", "joint" or "option") named `name`, its
    component `index`.  An option's number is gravity's: name "gravity", no attribute."""
    element: str
    name: str
    attribute: str | None = None
    index: int = 0

    @classmethod
    def of(cls, table):
        """The location a [scene.bindings] table names (its scale and depends are the binding's, not the place's)."""
        return cls(table["element"], table["name"], table.get("attribute"), table.get("index", 0))

    @property
    def scalar(self):
        """Whether the number has no components: a joint's values and a body's mass are one number each; a
        position, a centre of mass, an inertia and gravity have components."""
        return self.element == "joint" or self.attribute == "mass"

    def table(self):
        """The location as a [scene.bindings] table writes it: an index only for a number with components."""
        return {"element": self.element, "name": self.name, **({"attribute": self.attribute} if self.attribute else {}),
                **({} if self.scalar else {"index": self.index})}

    def text(self):
        """The location in words, as messages name it: "body 'bob' ipos[2]", "joint 'theta' damping",
        "option 'gravity' [2]"."""
        return f"{self.element} '{self.name}' {self.attribute or ''}{'' if self.scalar else f'[{self.index}]'}"

# The six entries of a full inertia (MJCF fullinertia, URDF <inertia>: ixx iyy izz ixy ixz iyz) in the 3 x 3 tensor.
FULL_INERTIA = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def full_tensor(six):
    """The symmetric 3 x 3 inertia of its six entries (FULL_INERTIA's order)."""
    tensor = np.zeros((3, 3))
    for value, (row, column) in zip(six, FULL_INERTIA):
        tensor[row, column] = tensor[column, row] = value
    return tensor


# The principal moments of an inertia written by a binding are a rigid body's when each is positive and A + B >= C
# to within their rounding: eigvalsh of a 3 x 3 tensor rounds each by a few eps of the largest; 1e-12 of C allows a
# flat plate's A + B = C (as dyncheck's random parameter sets allow it).
TRIANGLE_ROUNDING = 1e-12


def unphysical(body, inertia):
    """Why `inertia` (about the centre of mass) is no rigid body's, naming the body; None if it is one."""
    moments = np.sort(np.linalg.eigvalsh(np.asarray(inertia, dtype=float)))
    if moments[0] > 0 and moments[0] + moments[1] >= moments[2] * (1 - TRIANGLE_ROUNDING):
        return None
    return (f"body '{body}': principal moments of inertia about its centre of mass "
            f"{', '.join(f'{x:.6g}' for x in moments)} kg m^2 are not a rigid body's (each > 0, A + B >= C)")


# A body's inertia as a binding sets it: about the body origin (a diagonal entry), the principal moments in the
# inertial frame (MJCF's diaginertia, index 0..2) or the full tensor about the centre of mass in the body's frame
# (MJCF's fullinertia, a URDF <inertia> where its <origin> has no rpy: index 0..5, FULL_INERTIA).
INERTIA_ATTRIBUTES = ("inertia_about_origin", "inertia", "fullinertia")


def parallel_axis(mass, com, index):
    """What a body's moment of inertia about its axis `index` through its origin adds to the one through its centre
    of mass `com`."""
    return mass * (com @ com - com[index] ** 2)


def written_inertia(location, value, mass, com, inertia, armature, frame):
    """A body's inertia about its centre of mass in its frame (a new array) once a binding of one of
    INERTIA_ATTRIBUTES writes `value` at `location`: its `inertia` before, its mass and centre of mass, the armature
    of a ball joint on the world that a moment about the origin holds (MuJoCo's evaluation model counts it in the
    body's inertia), and `frame()`, the rotation of its inertial frame in its frame, asked of a principal moment only
    (an orientation that an adapter does not read is refused there alone)."""
    i, inertia = location.index, np.array(inertia, dtype=float)
    if location.attribute == "inertia_about_origin":  # less the parallel-axis term and the armature
        inertia[i, i] = value - parallel_axis(mass, com, i) - armature
    elif location.attribute == "fullinertia":
        inertia[FULL_INERTIA[i]] = inertia[FULL_INERTIA[i][::-1]] = value
    else:  # a principal moment, in the inertial frame
        rotation = frame()
        principal = rotation.T @ inertia @ rotation
        principal[i, i] = value
        inertia = rotation @ principal @ rotation.T
    return inertia


def read_inertia(location, mass, com, inertia, armature, frame):
    """The number at `location` (one of INERTIA_ATTRIBUTES) of a body's inertia, as `written_inertia` writes it."""
    i = location.index
    if location.attribute == "inertia_about_origin":
        return float(inertia[i, i] + parallel_axis(mass, com, i) + armature)
    if location.attribute == "fullinertia":
        return float(inertia[FULL_INERTIA[i]])
    rotation = frame()
    return float((rotation.T @ inertia @ rotation)[i, i])
