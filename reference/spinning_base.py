"""The spinning arm and disk that 1.8.1, 1.8.2 and 1.8.3 share, and the book's method on it.

Frames (1.8 (a)): B1 = T_z(alpha) I, B2 = T_z(beta) B1, B3 = T_x(psi) B2, with
T_z(a) = [[c, s, 0], [-s, c, 0], [0, 0, 1]] and T_x(a) = [[1, 0, 0], [0, c, s], [0, -s, c]].
Points (1.8 (b)): I r_OA = (0, 0, a), B1 r_AB = (0, b, 0), B2 r_BC = (0, 0, c),
B2 r_CD = (0, r, h), B3 r_DE = (0, 0, -L), L the length DE (l in 1.8.1-2, l0 + l in 1.8.3).
The arm and the disk turn at constant rates, Omega = alpha' + beta'; gravity is -Z.
"""

import functools

import numpy as np

from reference import printed

# Vectors and matrices of the chain are tuples of floats: on 3-vectors numpy's overhead per
# operation is most of the time, and the integrators evaluate the chain at every step.
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
# student's page typesets them (dyncheck/student_page.py, `frames:T_z`).
FRAMES = {"T_z": "array([[cos(a), sin(a), 0.0], [-sin(a), cos(a), 0.0], [0.0, 0.0, 1.0]])",
          "T_x": "array([[1.0, 0.0, 0.0], [0.0, cos(a), sin(a)], [0.0, -sin(a), cos(a)]])"}


def T_z(angle):
    return printed.evaluate(FRAMES, {"a": angle, "sin": np.sin, "cos": np.cos, "array": np.array}, ("T_z",))["T_z"]


def T_x(angle):
    return printed.evaluate(FRAMES, {"a": angle, "sin": np.sin, "cos": np.cos, "array": np.array}, ("T_x",))["T_x"]


def cross(a, b):
    """a x b."""
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


def _add(*vectors):
    """The sum of 3-vectors, left to right."""
    (x, y, z), *rest = vectors
    for a in rest:
        x, y, z = x + a[0], y + a[1], z + a[2]
    return x, y, z


def _scale(k, a):
    return k * a[0], k * a[1], k * a[2]


def _apply(matrix, x):
    """matrix @ x, the matrix given by rows."""
    (m0, m1, m2), (x0, x1, x2) = matrix, x
    return (m0[0] * x0 + m0[1] * x1 + m0[2] * x2, m1[0] * x0 + m1[1] * x1 + m1[2] * x2,
            m2[0] * x0 + m2[1] * x1 + m2[2] * x2)


def particle_motion(p, t, psi, psi_rate, psi_acc, length, length_rate=0.0, length_acc=0.0):
    """I r_OE, B3 v_E, B3 a_E and gravity per unit mass in B3 (see `chain`)."""
    return chain(p, t, psi, psi_rate, psi_acc, length, length_rate, length_acc)[:4]


def chain(p, t, psi, psi_rate, psi_acc, length, length_rate=0.0, length_acc=0.0):
    """I r_OE, B3 v_E, B3 a_E, gravity per unit mass in B3, and B3 w3, w3', by the book's method.

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
    alpha = p["alpha0"] + p["alpha_rate"] * t
    beta = p["beta0"] + p["beta_rate"] * t
    # floats: arithmetic on numpy's scalars is slower
    psi_rate, psi_acc, length, length_rate, length_acc = (float(x) for x in (psi_rate, psi_acc, length,
                                                                             length_rate, length_acc))
    chain = [(T_z(alpha), p["alpha_rate"], 0.0, K3, (0.0, p["b"], 0.0), 0.0, 0.0),
             (T_z(beta), p["beta_rate"], 0.0, K3, (0.0, p["r"], p["c"] + p["h"]), 0.0, 0.0),
             (T_x(psi), psi_rate, psi_acc, I3, (0.0, 0.0, -length), length_rate, length_acc)]
    position, to_inertial = (0.0, 0.0, p["a"]), IDENTITY  # at A; to_inertial: I components from the frame's
    v = a = w = w_dot = ZERO
    for turn, rate, acc, axis, r, r_rate, r_acc in chain:
        turn = turn.tolist()
        w_in, w_dot_in = _apply(turn, w), _apply(turn, w_dot)
        w = _add(w_in, _scale(rate, axis))
        w_dot = _add(w_dot_in, cross(w_in, _scale(rate, axis)), _scale(acc, axis))
        v_rel, a_rel = _scale(-r_rate, K3), _scale(-r_acc, K3)
        v = _add(_apply(turn, v), cross(w, r), v_rel)
        a = _add(_apply(turn, a), cross(w, cross(w, r)), cross(w_dot, r), _scale(2, cross(w, v_rel)), a_rel)
        to_inertial = tuple(_apply(turn, row) for row in to_inertial)  # (I from child) = (I from parent) turn^T
        position = _add(position, _apply(to_inertial, r))
    gravity = _scale(-p["g"], to_inertial[2])  # (0, 0, -g) in the last frame: -g times its components of K
    return tuple(np.array(x) for x in (position, v, a, gravity, w, w_dot))


def last_state(method):
    """Remember a model method's result for the last (t, q, v): an integrator asks a model for its
    accelerations and then its drive power at the same state, and both come from one calculation."""
    @functools.wraps(method)
    def remembered(self, t, q, v):
        key = (t, tuple(q), tuple(v))
        if getattr(self, "_last", (None,))[0] != key:
            self._last = (key, method(self, t, q, v))
        return self._last[1]
    return remembered
