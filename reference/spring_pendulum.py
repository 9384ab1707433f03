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
"""

import numpy as np

COORDS = ("psi", "l")
REACTIONS = ("R",)


class Book:
    """The book's equations of motion and reaction as printed in 1.8.3 (h)."""

    coords = COORDS
    reaction_names = REACTIONS

    def __init__(self, params):
        self.p = dict(params)

    def _base(self, t):
        """beta(t), Omega and the centripetal acceleration of D along -Y2, b alpha'^2 cos(beta) + r Omega^2."""
        p = self.p
        beta = p["beta0"] + p["beta_rate"] * t
        omega = p["alpha_rate"] + p["beta_rate"]
        return beta, omega, p["b"] * p["alpha_rate"] ** 2 * np.cos(beta) + p["r"] * omega**2

    def accelerations(self, t, q, v):
        p = self.p
        psi, l = q
        psi_rate, l_rate = v
        beta, omega, base = self._base(t)
        length = p["l0"] + l
        s, c = np.sin(psi), np.cos(psi)
        psi_acc = (-p["g"] / length * s + base / length * c
                   + omega**2 * s * c - 2 * l_rate * psi_rate / length)
        l_acc = (-p["k"] / p["m"] * l + p["g"] * c + base * s
                 + length * (psi_rate**2 + omega**2 * s**2))
        return np.array([psi_acc, l_acc])

    def _coriolis_factor(self):
        return 1.0  # printed: one L psi' Omega cos(psi) term

    def reactions(self, t, q, v):
        p = self.p
        psi, l = q
        psi_rate, l_rate = v
        beta, omega, _ = self._base(t)
        length = p["l0"] + l
        R = -p["m"] * (p["b"] * p["alpha_rate"] ** 2 * np.sin(beta)
                       + self._coriolis_factor() * length * psi_rate * omega * np.cos(psi)
                       + 2 * l_rate * omega * np.sin(psi))
        return {"R": R}

    def _velocities(self, t, q, v):
        """B3 v_D and B3 v_E from the book's 1.8.3 (d)."""
        p = self.p
        psi, l = q
        psi_rate, l_rate = v
        beta, omega, _ = self._base(t)
        length = p["l0"] + l
        s, c = np.sin(psi), np.cos(psi)
        ba = p["b"] * p["alpha_rate"]
        v_d = np.array([-ba * np.cos(beta) - p["r"] * omega,
                        ba * np.sin(beta) * c,
                        -ba * np.sin(beta) * s])
        v_e = v_d + np.array([-length * omega * s, length * psi_rate, -l_rate])
        return v_d, v_e

    def energy(self, t, q, v):
        p = self.p
        psi, l = q
        _, v_e = self._velocities(t, q, v)
        height = p["a"] + p["c"] + p["h"] - (p["l0"] + l) * np.cos(psi)
        return 0.5 * p["m"] * v_e @ v_e + p["m"] * p["g"] * height + 0.5 * p["k"] * l**2

    def drive_power(self, t, q, v):
        """Power the spinning base puts into particle and spring.

        The massless arm pushes the particle with R i3 (at v_E) and holds the
        spring's end at D with k l k3 (at v_D); gravity and the spring are in
        the energy.
        """
        v_d, v_e = self._velocities(t, q, v)
        return self.reactions(t, q, v)["R"] * v_e[0] + self.p["k"] * q[1] * v_d[2]


class Reference(Book):
    """Book's equations with term (II) + (III) of a_E,x summed: 2 L psi' Omega cos(psi)."""

    def _coriolis_factor(self):
        return 2.0
