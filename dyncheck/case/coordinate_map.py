"""A derivation in coordinates of its own over the scene's joints (`[scene.joints]` of case.toml, `JOINTS` of a plain
equations.py): each hinge or slide of the scene an affine function of the case's coordinates, q_joints = A q + b, as
absolute angles are over the relative angles of a chain's hinges (the elbow at phi2 - phi1), or a joint's zero and
sign differ from the derivation's.  The engines run in the joints (`CoordinateMap.joints`); `Mapped` presents an
engine model in the case's coordinates, so that every comparison, and every term localisation names, is in the
derivation's own coordinates and equations.

A is constant, so the map is exact to rounding: the joints' rates are A q', their accelerations A q''; the
generalized forces of the derivation's equations are A^T times the joints' (virtual work), so its mass matrix is
A^T M A and its f is A^T f_joints."""

from dataclasses import dataclass, replace

import numpy as np

from dyncheck.common import expressions

# An expression is taken as affine where it equals A q + b at PROBES states off the unit vectors it was read at, to
# within AFFINE_RTOL of its size: rounding of a few operations on numbers of order 1 is 1e-15; a term in q^2, q1 q2
# or sin q at the probes' |q| ~ 1 is off by order 1.
PROBES = 3
AFFINE_RTOL = 1e-9
# A must be invertible, and well enough that A^{-1} loses no more than a few digits: cond(A) above this is a
# coordinate that the joints do not determine (two coordinates that move the same joints alike).
MAX_CONDITION = 1e8


@dataclass(frozen=True, eq=False)
class CoordinateMap:
    """q_joints = matrix @ q + offset: the scene's `joints` (hinges and slides) from the case's `coords`."""
    joints: tuple[str, ...]
    coords: tuple[str, ...]
    matrix: np.ndarray  # A (n, n)
    offset: np.ndarray  # b (n,)
    inverse: np.ndarray  # A^{-1}

    def joint_state(self, q, v):
        """The joints' positions and rates at the case's (q, v): (n,) or (N, n) arrays."""
        return self.joint_positions(q), np.asarray(v, dtype=float) @ self.matrix.T

    def joint_positions(self, q):
        """The joints' positions at the case's coordinates q: (n,) or (N, n)."""
        return np.asarray(q, dtype=float) @ self.matrix.T + self.offset

    def case_state(self, q, v):
        """The case's coordinates and rates at the joints' (q, v)."""
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        return (q - self.offset) @ self.inverse.T, v @ self.inverse.T

    def case_vector(self, joint_vector):
        """A vector of the joints' rates or accelerations (or (N, n) of them) in the case's coordinates."""
        return np.asarray(joint_vector, dtype=float) @ self.inverse.T

    def case_matrix(self, joint_matrix):
        """A matrix of the joints' equations (mass, stiffness, damping) in the case's: A^T X A."""
        return self.matrix.T @ np.asarray(joint_matrix, dtype=float) @ self.matrix

    @property
    def error_factor(self):
        """How much A^T E A can magnify an entry's error e: each entry sums e |A_ki| |A_lj| over k and l, at most
        e times the largest column sum of |A|, squared."""
        return float(np.max(np.abs(self.matrix).sum(axis=0)) ** 2)


def parse(joints, coords, params, where):
    """The CoordinateMap of `joints` ({joint: expression of the coordinates `coords` and the parameters `params`}),
    whose names are the scene's hinges and slides; ValueError naming `where` (the field) and the entry."""
    coords = tuple(coords)
    if len(joints) != len(coords):
        raise ValueError(f"{where} gives {len(joints)} joints ({', '.join(joints)}) for {len(coords)} coordinates "
                         f"({', '.join(coords)}): one expression per coordinate, each joint's position")
    names = expressions.of_parameters(params)
    rng = np.random.default_rng(0)
    probes = rng.uniform(-1.0, 1.0, (PROBES, len(coords)))
    rows, offsets = [], []
    for joint, text in joints.items():
        if not isinstance(text, str):
            text = repr(text)
        try:
            unknown = expressions.names(text) - set(coords) - set(params) - {"pi"}
            if unknown:
                raise ValueError(f"names {sorted(unknown)[0]!r}, which is no coordinate ({', '.join(coords)}) "
                                 "and no parameter")
            value = lambda q: float(expressions.evaluate(text, {**names, **dict(zip(coords, q))}))
            offset = value(np.zeros(len(coords)))
            row = np.array([value(unit) - offset for unit in np.eye(len(coords))])
            for q in probes:
                size = max(1.0, abs(offset), float(np.abs(row) @ np.abs(q)))
                if abs(value(q) - (row @ q + offset)) > AFFINE_RTOL * size:
                    raise ValueError("is not affine in the coordinates (a sum of coordinates times constants, plus "
                                     f"a constant): at {dict(zip(coords, np.round(q, 3).tolist()))} it is "
                                     f"{value(q):.6g}, where the affine function through its values at 0 and at each "
                                     f"unit coordinate gives {row @ q + offset:.6g}")
        except ValueError as error:
            raise ValueError(f"{where}.{joint} = {text!r}: {error}") from None
        rows.append(row)
        offsets.append(offset)
    matrix = np.array(rows).reshape(len(coords), len(coords))
    condition = np.linalg.cond(matrix) if len(coords) else 1.0
    if not np.isfinite(condition) or condition > MAX_CONDITION:
        raise ValueError(f"{where} = {dict(joints)}: the joints do not determine the coordinates "
                         f"({', '.join(coords)}): the map's matrix {matrix.tolist()} is singular (condition "
                         f"{condition:.3g}); each coordinate must follow from the joints' positions")
    return CoordinateMap(tuple(joints), coords, matrix, np.array(offsets), np.linalg.inv(matrix))


# What a Mapped model passes through unchanged: no state goes in and nothing in coordinates comes out.
PLAIN = ("path", "reaction_names", "loops", "read", "tree", "body_id", "gravity", "varying", "loop_names", "m", "d")
# The methods that take a state (t, q, v) and return what does not depend on the coordinates: reactions, energies,
# powers and the bodies' accelerations are the scene's, whatever its coordinates.
STATE_IN = ("reactions", "reactions_many", "point_accelerations", "energy", "energy_many", "drive_power",
            "drive_powers")


class Mapped:
    """An engine `model` (its coordinates the scene's joints) in the case's coordinates through `coordinate_map`: the
    model interface (docs/model-interface.md) of the derivation's own coordinates.  What it does not map is no
    attribute of it (an AttributeError, never a value in the wrong coordinates)."""

    def __init__(self, model, coordinate_map):
        self.model, self.map = model, coordinate_map
        self.coords = coordinate_map.coords
        self.native = None  # a lone ball joint's own coordinates (engines): no map takes a ball joint

    def __getattr__(self, name):
        if name in PLAIN:
            return getattr(self.model, name)
        if name in STATE_IN:
            method = getattr(self.model, name)
            return lambda t, q, v: method(t, *self.map.joint_state(q, v))
        raise AttributeError(f"{type(self.model).__name__} in mapped coordinates has no {name!r}")

    def accelerations(self, t, q, v):
        return self.map.case_vector(self.model.accelerations(t, *self.map.joint_state(q, v)))

    @property
    def accelerations_many(self):
        many = self.model.accelerations_many  # an AttributeError where the engine has none
        return lambda t, q, v: self.map.case_vector(many(t, *self.map.joint_state(q, v)))

    def mass_matrix(self, t, q, v):
        return self.map.case_matrix(self.model.mass_matrix(t, *self.map.joint_state(q, v)))

    def linearisation(self, t, q, v):
        lin = self.model.linearisation(t, *self.map.joint_state(q, v))
        return replace(lin, mass=self.map.case_matrix(lin.mass), force_q=self.map.case_matrix(lin.force_q),
                       force_v=self.map.case_matrix(lin.force_v), error=lin.error * self.map.error_factor)

    def points(self, t, q):
        return self.model.points(t, self.map.joint_positions(q))

    def paths_many(self, t, q):
        return self.model.paths_many(t, self.map.joint_positions(q))

    def step(self, q0, v0, t_end, dt, integrator):
        run = self.model.step(*self.map.joint_state(q0, v0), t_end, dt, integrator)
        q, v = self.map.case_state(run["q"], run["v"])
        return {**run, "q": q, "v": v}

    def stepping(self, q0, v0, dt, integrator):  # MuJoCo's own stepping from the start: its model and data
        return self.model.stepping(*self.map.joint_state(q0, v0), dt, integrator)

    def approximations_doubled(self, scales):
        twin = self.model.approximations_doubled(scales)
        return self if twin is self.model else Mapped(twin, self.map)
