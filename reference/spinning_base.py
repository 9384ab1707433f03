"""The spinning arm and disk that 1.8.1, 1.8.2 and 1.8.3 share, and the book's method on it.

Frames (1.8 (a)): B1 = T_z(alpha) I, B2 = T_z(beta) B1, B3 = T_x(psi) B2, with
T_z(a) = [[c, s, 0], [-s, c, 0], [0, 0, 1]] and T_x(a) = [[1, 0, 0], [0, c, s], [0, -s, c]].
Points (1.8 (b)): I r_OA = (0, 0, a), B1 r_AB = (0, b, 0), B2 r_BC = (0, 0, c),
B2 r_CD = (0, r, h), B3 r_DE = (0, 0, -L), L the length DE (l in 1.8.1-2, l0 + l in 1.8.3).
The arm and the disk turn at constant rates, Omega = alpha' + beta'; gravity is -Z.
"""

import functools

import numpy as np

I3, K3 = np.eye(3)[0], np.eye(3)[2]


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


def T_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def T_x(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])


def cross(a, b):
    """a x b for 3-vectors (np.cross costs ten times more on vectors this small)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


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
    chain = [(T_z(alpha), p["alpha_rate"], 0.0, K3, np.array([0.0, p["b"], 0.0]), 0.0, 0.0),
             (T_z(beta), p["beta_rate"], 0.0, K3, np.array([0.0, p["r"], p["c"] + p["h"]]), 0.0, 0.0),
             (T_x(psi), psi_rate, psi_acc, I3, np.array([0.0, 0.0, -length]), length_rate, length_acc)]
    position, rotation = np.array([0.0, 0.0, p["a"]]), np.eye(3)  # at A; rotation: frame from I
    v, a, w, w_dot = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    for turn, rate, acc, axis, r, r_rate, r_acc in chain:
        w_in, w_dot_in = turn @ w, turn @ w_dot
        w = w_in + rate * axis
        w_dot = w_dot_in + cross(w_in, rate * axis) + acc * axis
        v_rel, a_rel = -r_rate * K3, -r_acc * K3
        v = turn @ v + cross(w, r) + v_rel
        a = turn @ a + cross(w, cross(w, r)) + cross(w_dot, r) + 2 * cross(w, v_rel) + a_rel
        rotation = turn @ rotation
        position = position + rotation.T @ r
    gravity = rotation @ np.array([0.0, 0.0, -p["g"]])
    return position, v, a, gravity, w, w_dot


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
