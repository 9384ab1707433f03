"""Section 1.8.3: spring-mass pendulum on a spinning arm and disk.

Frames (book, sec. 1.8.3 (a)): B1 = T_z(alpha) I, B2 = T_z(beta) B1, B3 = T_x(psi) B2.
Points: I r_OA = (0, 0, a), B1 r_AB = (0, b, 0), B2 r_BC = (0, 0, c),
B2 r_CD = (0, r, h), B3 r_DE = (0, 0, -(l0 + l)).  The arm and the disk turn at
constant rates, so alpha'' = beta'' = 0 and Omega = alpha' + beta' is constant.
Coordinates: psi (pendulum angle about X2) and l (spring extension).

The book's (f) sums five terms for B3 a_E.  Its X3 component, printed as

    a_E,x = -( b alpha'^2 sin(beta) + L psi' Omega cos(psi) + 2 l' Omega sin(psi) ),

keeps only one of the two L psi' Omega cos(psi) contributions: term (II),
omega x (omega x r_DE), and term (III), omega' x r_DE, both have the X3 component
-L psi' Omega cos(psi) (the book writes them out itself, in (II) and (III)), so
their sum is -2 L psi' Omega cos(psi).  The reaction R = m a_E,x (Newton, X3)
inherits the missing term; the equations of motion (Y3 and Z3) do not.  The
book's sign of R is restored from (f) and (h): B3 R = (R, 0, 0) is the force of
the arm on the particle and R = m a_E,x, so R carries the minus of a_E,x.

`Reference` does not patch the printed sum: it evaluates the book's method numerically, frame by
frame (reference/spinning_base.py), so the correction above is found, not assumed.
"""

import numpy as np

from reference.spinning_base import base_terms, book_height, book_velocities, particle_motion

COORDS = ("psi", "l")
REACTIONS = ("R",)


class Book:
    """The book's equations of motion and reaction as printed in 1.8.3 (h)."""

    coords = COORDS
    reaction_names = REACTIONS

    def __init__(self, params):
        self.p = dict(params)

    def accelerations(self, t, q, v):
        p = self.p
        psi, l = q
        psi_rate, l_rate = v
        _, omega, base = base_terms(p, t)
        length = p["l0"] + l
        s, c = np.sin(psi), np.cos(psi)
        psi_acc = (-p["g"] / length * s + base / length * c
                   + omega**2 * s * c - 2 * l_rate * psi_rate / length)
        l_acc = (-p["k"] / p["m"] * l + p["g"] * c + base * s
                 + length * (psi_rate**2 + omega**2 * s**2))
        return np.array([psi_acc, l_acc])

    def reactions(self, t, q, v):
        """R = m a_E,x with the printed a_E,x: one L psi' Omega cos(psi) term."""
        p = self.p
        psi, l = q
        psi_rate, l_rate = v
        beta, omega, _ = base_terms(p, t)
        length = p["l0"] + l
        R = -p["m"] * (p["b"] * p["alpha_rate"] ** 2 * np.sin(beta)
                       + length * psi_rate * omega * np.cos(psi)
                       + 2 * l_rate * omega * np.sin(psi))
        return {"R": R}

    def energy(self, t, q, v):
        p = self.p
        psi, l = q
        _, v_e = book_velocities(p, t, psi, v[0], p["l0"] + l, v[1])
        return (0.5 * p["m"] * v_e @ v_e + p["m"] * p["g"] * book_height(p, psi, p["l0"] + l)
                + 0.5 * p["k"] * l**2)

    def drive_power(self, t, q, v):
        """Power the spinning base puts into particle and spring.

        The massless arm pushes the particle with R i3 (at v_E) and holds the
        spring's end at D with k l k3 (at v_D); gravity and the spring are in
        the energy.
        """
        p = self.p
        v_d, v_e = book_velocities(p, t, q[0], v[0], p["l0"] + q[1], v[1])
        return self.reactions(t, q, v)["R"] * v_e[0] + p["k"] * q[1] * v_d[2]


class Reference:
    """The book's method evaluated numerically: B3 a_E from the five-term formula frame by frame
    (`particle_motion`), Newton's law in B3 with the arm's force (R, 0, k l): psi'' from Y3, l''
    from Z3, R from X3.  It sums terms (II) and (III) as vectors, so it has both of their
    L psi' Omega cos(psi) contributions."""

    coords = COORDS
    reaction_names = REACTIONS

    def __init__(self, params):
        self.p = dict(params)

    def _motion(self, t, q, v):
        """psi'', l'', and the particle's position, velocity and the arm's force on it."""
        p = self.p
        (psi, l), (psi_rate, l_rate) = q, v
        length = p["l0"] + l
        # a_E is affine in psi'' (slope w3' x r_DE = (0, L, 0)) and in l'' (slope a_rel = (0, 0, -1)):
        # evaluate it without them, then solve Y3 (no force but gravity) and Z3 (the spring's k l).
        position, v_e, a_free, gravity = particle_motion(p, t, psi, psi_rate, 0.0, length, l_rate, 0.0)
        psi_acc = (gravity[1] - a_free[1]) / length
        l_acc = a_free[2] - gravity[2] - p["k"] * l / p["m"]
        a_e = a_free + np.array([0.0, length * psi_acc, -l_acc])
        return np.array([psi_acc, l_acc]), position, v_e, p["m"] * (a_e - gravity)

    def accelerations(self, t, q, v):
        return self._motion(t, q, v)[0]

    def reactions(self, t, q, v):
        return {"R": self._motion(t, q, v)[3][0]}

    def energy(self, t, q, v):
        p = self.p
        _, position, v_e, _ = self._motion(t, q, v)
        return 0.5 * p["m"] * v_e @ v_e + p["m"] * p["g"] * position[2] + 0.5 * p["k"] * q[1] ** 2

    def drive_power(self, t, q, v):
        """The arm's whole force on the particle (R, 0, k l) at v_E, less the spring's own power
        -k l l' (the spring's energy is in E): R v_E,x + k l (v_E,z + l') = R v_E,x + k l v_D,z."""
        _, _, v_e, force = self._motion(t, q, v)
        return force @ v_e + self.p["k"] * q[1] * v[1]
