"""The spinning arm and disk that 1.8.1, 1.8.2 and 1.8.3 share, and the book's method on it.

Frames (1.8 (a)): B1 = T_z(alpha) I, B2 = T_z(beta) B1, B3 = T_x(psi) B2, with
T_z(a) = [[c, s, 0], [-s, c, 0], [0, 0, 1]] and T_x(a) = [[1, 0, 0], [0, c, s], [0, -s, c]].
Points (1.8 (b)): I r_OA = (0, 0, a), B1 r_AB = (0, b, 0), B2 r_BC = (0, 0, c),
B2 r_CD = (0, r, h), B3 r_DE = (0, 0, -L), L the length DE (l in 1.8.1-2, l0 + l in 1.8.3).
The arm and the disk turn at constant rates, Omega = alpha' + beta'; gravity is -Z.
"""

import numpy as np

from reference import printed, straight

# Vectors and matrices of the chain are tuples of floats (or of arrays over many states): on 3-vectors
# numpy's overhead per operation is most of the time, and the integrators evaluate the chain at every step.
I3, K3, ZERO = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
IDENTITY = (I3, (0.0, 1.0, 0.0), K3)


def base_terms(p, t):
    """beta(t), Omega = alpha' + beta', and the book's bracket K = b alpha'^2 cos(beta) + r Omega^2
    (the centripetal acceleration of D along -Y2)."""
    beta = p["beta0"] + p["beta_rate"] * t
    omega = p["alpha_rate"] + p["beta_rate"]
    return beta, omega, p["b"] * p["alpha_rate"] ** 2 * np.cos(beta) + p["r"] * omega**2


def book_velocities(p, t, psi, psi_rate, length, length_rate=0.0):
    """B3 v_D and B3 v_E as 1.8.3 (d) prints them, for a pendulum of length L growing at L'."""
    beta, omega, _ = base_terms(p, t)
    s, c = np.sin(psi), np.cos(psi)
    ba = p["b"] * p["alpha_rate"]
    v_d = np.array([-ba * np.cos(beta) - p["r"] * omega, ba * np.sin(beta) * c, -ba * np.sin(beta) * s])
    return v_d, v_d + np.array([-length * omega * s, length * psi_rate, -length_rate])


def book_height(p, psi, length):
    """z_E = a + c + h - L cos(psi), from the position vectors (b)."""
    return p["a"] + p["c"] + p["h"] - length * np.cos(psi)


# The book's transformation matrices (1.8 (a)) as expressions of the angle `a`: T_z and T_x evaluate them, and the
# student's page typesets them (dyncheck/pages/student_page.py, `frames:T_z`).
FRAMES = {"T_z": "array([[cos(a), sin(a), 0.0], [-sin(a), cos(a), 0.0], [0.0, 0.0, 1.0]])",
          "T_x": "array([[1.0, 0.0, 0.0], [0.0, cos(a), sin(a)], [0.0, -sin(a), cos(a)]])"}


_MATRICES = printed.Functions(FRAMES, ("a",), {"sin": np.sin, "cos": np.cos, "array": np.array})


def T_z(angle):
    return _MATRICES["T_z"](angle)


def T_x(angle):
    return _MATRICES["T_x"](angle)


# The same expressions for the chain, rows as tuples: on one state with math's sin and cos (numpy's cost more
# on one number and give the same values; straight's are math's on floats, and also follow a trace), on many
# with numpy's.
_TURNS = printed.Functions(FRAMES, ("a",), {"sin": straight.sin, "cos": straight.cos, "array": tuple})
_TURNS_MANY = printed.Functions(FRAMES, ("a",), {"sin": np.sin, "cos": np.cos, "array": tuple})


# Vectors are (x, y, z) components, each a float at one state or an array at many: the same operations,
# in the same order, give the same numbers either way.
def cross(a, b):
    """a x b."""
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


def add(first, *rest):
    """The sum of 3-vectors, left to right."""
    x, y, z = first
    for a in rest:
        x, y, z = x + a[0], y + a[1], z + a[2]
    return x, y, z


def sub(a, b):
    """a - b."""
    return a[0] - b[0], a[1] - b[1], a[2] - b[2]


def scale(k, a):
    return k * a[0], k * a[1], k * a[2]


def dot(a, b):
    """a . b, summed left to right (as numpy's a @ b of two 3-vectors)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _apply(matrix, x):
    """matrix @ x, the matrix given by rows."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = matrix
    x0, x1, x2 = x
    return m00 * x0 + m01 * x1 + m02 * x2, m10 * x0 + m11 * x1 + m12 * x2, m20 * x0 + m21 * x1 + m22 * x2


def particle_motion(p, t, psi, psi_rate, psi_acc, length, length_rate=0.0, length_acc=0.0):
    """I r_OE, B3 v_E, B3 a_E and gravity per unit mass in B3 (see `chain`) as components: at one state
    (floats) or at many (t and the rest arrays of shape (N,), or floats where constant)."""
    turns = _TURNS_MANY if isinstance(t, np.ndarray) or isinstance(psi, np.ndarray) else _TURNS
    return _chain(p, t, psi, psi_rate, psi_acc, length, length_rate, length_acc, turns)[:4]


def chain(p, t, psi, psi_rate, psi_acc, length, length_rate=0.0, length_acc=0.0):
    """I r_OE, B3 v_E, B3 a_E, gravity per unit mass in B3, and B3 w3, w3', by the book's method, at one
    state: arrays of shape (3,).

    The chain is three rotations, each about an axis through a point that is fixed in both the
    parent and the child frame (A, then B on the disk's axis, then D), each followed by the vector
    to the next such point, fixed in the child frame:
        B1 = T_z(alpha) I   about K at A,   then B1 r_AB
        B2 = T_z(beta) B1   about K1 at B,  then B2 (r_BC + r_CD)
        B3 = T_x(psi) B2    about X2 at D,  then B3 r_DE = (0, 0, -L), L growing at L'
    For a frame turning relative to its parent at `rate` (acceleration `acc`) about `axis`:
    w = T w_parent + rate axis and w' = T w'_parent + (T w_parent) x (rate axis) + acc axis (both
    in the child frame); for the point at the end of r, the five-term formula (1.10):
    v = T v_0 + w x r + v_rel,  a = T a_0 + w x (w x r) + w' x r + 2 w x v_rel + a_rel,
    with v_rel = (0, 0, -L') and a_rel = (0, 0, -L'') on the last link only.
    """
    # floats: arithmetic on numpy's scalars is slower
    state = (float(x) for x in (t, psi, psi_rate, psi_acc, length, length_rate, length_acc))
    return tuple(np.array(x) for x in _chain(p, *state, _TURNS))


def _chain(p, t, psi, psi_rate, psi_acc, length, length_rate, length_acc, turns):
    """`chain` as components, its turns evaluated by `turns` (_TURNS at one state, _TURNS_MANY at many)."""
    alpha = p["alpha0"] + p["alpha_rate"] * t
    beta = p["beta0"] + p["beta_rate"] * t
    t_z, t_x = turns["T_z"], turns["T_x"]
    chain = [(t_z(alpha), p["alpha_rate"], 0.0, K3, (0.0, p["b"], 0.0), 0.0, 0.0),
             (t_z(beta), p["beta_rate"], 0.0, K3, (0.0, p["r"], p["c"] + p["h"]), 0.0, 0.0),
             (t_x(psi), psi_rate, psi_acc, I3, (0.0, 0.0, -length), length_rate, length_acc)]
    position, to_inertial = (0.0, 0.0, p["a"]), IDENTITY  # at A; to_inertial: I components from the frame's
    v = a = w = w_dot = ZERO
    for turn, rate, acc, axis, r, r_rate, r_acc in chain:
        # the parent's vectors in the child frame; (I from child) = (I from parent) turn^T
        w_in, w_dot_in, v_in, a_in = _apply(turn, w), _apply(turn, w_dot), _apply(turn, v), _apply(turn, a)
        to_inertial = _apply(turn, to_inertial[0]), _apply(turn, to_inertial[1]), _apply(turn, to_inertial[2])
        spin = scale(rate, axis)
        w = add(w_in, spin)
        w_dot = add(w_dot_in, cross(w_in, spin), scale(acc, axis))
        v_rel, a_rel, w_r = scale(-r_rate, K3), scale(-r_acc, K3), cross(w, r)
        v = add(v_in, w_r, v_rel)
        a = add(a_in, cross(w, w_r), cross(w_dot, r), scale(2, cross(w, v_rel)), a_rel)
        position = add(position, _apply(to_inertial, r))
    gravity = scale(-p["g"], to_inertial[2])  # (0, 0, -g) in the last frame: -g times its components of K
    return position, v, a, gravity, w, w_dot


class ParticleOnBase:
    """The numerical Newton-Euler of a particle on the spinning base (1.8.1-3) behind the model interface, at
    one state or at many.  A subclass's `_motion(t, q, v)` gives the accelerations, and I r_OE, B3 v_E and the
    force on the particle in B3, as components (`particle_motion`): floats at one state (q, v the coordinates),
    arrays at many (q, v their columns); `reaction_axes` are the B3 components of its `reaction_names`."""

    def __init__(self, params):
        self.p = dict(params)

    def _at(self, t, q, v):
        """`_motion` at one state, on floats (numpy's scalars cost more), remembered for the last state: an integrator
        asks a model for its accelerations and then its drive power at the same state, and both come from one
        calculation.  Run as the straight-line code traced from it for this model's parameters at the first call
        (reference/straight.py: the same floats, a fraction of the time), or as itself where it cannot be traced."""
        state = (float(t), *printed.floats(q, v))
        last = self.__dict__.get("_last")
        if last is None or last[0] != state:
            if "_straight_motion" not in self.__dict__:
                n = len(q)
                self._straight_motion = straight.compiled(lambda t, *x: self._motion(t, list(x[:n]), list(x[n:])),
                                                          ["t", *(f"q{i}" for i in range(n)), *(f"v{i}" for i in range(n))])
            self._last = last = (state, self._straight_motion(*state))
        return last[1]

    def _at_many(self, t, q, v):
        """`_motion` at many states: t of shape (N,), q and v (N, n); and the columns of q and v."""
        q, v = np.asarray(q, dtype=float).T, np.asarray(v, dtype=float).T
        return self._motion(np.asarray(t, dtype=float), q, v), q, v

    def accelerations(self, t, q, v):
        return np.array(self._at(t, q, v)[0])

    def reactions(self, t, q, v):
        force = self._at(t, q, v)[3]
        return {name: force[axis] for name, axis in zip(self.reaction_names, self.reaction_axes)}

    def energy(self, t, q, v):
        return self._energy(q, self._at(t, q, v))

    def drive_power(self, t, q, v):
        return self._drive_power(q, v, self._at(t, q, v))

    def reactions_many(self, t, q, v):
        """`reactions` at many states: t of shape (N,), q and v (N, n) -> {name: (N,)}, the same numbers."""
        force = self._at_many(t, q, v)[0][3]
        return {name: np.broadcast_to(force[axis], np.shape(t)).copy()
                for name, axis in zip(self.reaction_names, self.reaction_axes)}

    def energy_many(self, t, q, v):
        """`energy` at many states (as `reactions_many`) -> (N,)."""
        motion, q, _ = self._at_many(t, q, v)
        return np.broadcast_to(self._energy(q, motion), np.shape(t)).copy()

    def _energy(self, q, motion):
        """The particle's kinetic and potential energy."""
        p = self.p
        _, position, v_e, _ = motion
        return dot(scale(0.5 * p["m"], v_e), v_e) + p["m"] * p["g"] * position[2]

    def _drive_power(self, q, v, motion):
        """The power of the force on the particle, F . v_E."""
        _, _, v_e, force = motion
        return dot(force, v_e)
