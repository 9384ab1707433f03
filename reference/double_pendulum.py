"""Section 1.9: planar double pendulum, theta1 absolute, theta2 relative to arm 1.

Frames: B1 = T_z(theta1) I, B2 = T_z(theta2) B1; arm vectors B1 l1 = (0, -l1, 0),
B2 l2 = (0, -l2, 0); gravity is -Y.  Arms are rigid and massless, so each
carries only a force along itself: T1 (on m1, along +j1) and T2 (on m2, along
+j2; on m1 the opposite), both positive in tension.

`Reference` solves the book's own four Newton equations (1.27)-(1.28) for
(T1, T2, theta1'', theta2'') as a linear system, the way 1.9.2 sets them up
before Cramer's rule:

    m1:  -m1 g s1 + T2 s2            = m1 l1 theta1''
         -m1 g c1 + T1 - T2 c2       = m1 l1 theta1'^2
    m2:  -m2 g s12                   = m2 [l1 (theta1'' c2 + theta1'^2 s2) + l2 (theta1'' + theta2'')]
         -m2 g c12 + T2              = m2 [l1 (-theta1'' s2 + theta1'^2 c2) + l2 (theta1' + theta2')^2]

`Book` is the closed form Cramer's rule gives, (1.29)-(1.32).  The displayed
equations lost their signs in extraction; the signs are taken from the Pascal
listing of 1.9.3, which prints the same four expressions with ASCII operators
(ddt1, ddt2, Tr1, Tr2).  The book's x axis: the derivation puts m1 at
(l1 sin theta1, -l1 cos theta1); the listing plots -l1 sin theta1.  The mirror
leaves the equations of motion unchanged (they are odd in the angles).
"""

import numpy as np

COORDS = ("theta1", "theta2")
REACTIONS = ("T1", "T2")


class Reference:
    coords = COORDS
    reaction_names = REACTIONS

    def __init__(self, params):
        self.p = dict(params)

    def _solve(self, q, v):
        """(T1, T2, theta1'', theta2'') from (1.27)-(1.28)."""
        p = self.p
        m1, m2, l1, l2, g = p["m1"], p["m2"], p["l1"], p["l2"], p["g"]
        t1, t2 = q
        w1, w2 = v
        s1, c1, s2, c2 = np.sin(t1), np.cos(t1), np.sin(t2), np.cos(t2)
        s12, c12 = np.sin(t1 + t2), np.cos(t1 + t2)
        matrix = np.array([
            [0.0, s2, -m1 * l1, 0.0],
            [1.0, -c2, 0.0, 0.0],
            [0.0, 0.0, -m2 * (l1 * c2 + l2), -m2 * l2],
            [0.0, 1.0, m2 * l1 * s2, 0.0],
        ])
        rhs = np.array([
            m1 * g * s1,
            m1 * g * c1 + m1 * l1 * w1**2,
            m2 * g * s12 + m2 * l1 * w1**2 * s2,
            m2 * g * c12 + m2 * l1 * w1**2 * c2 + m2 * l2 * (w1 + w2) ** 2,
        ])
        return np.linalg.solve(matrix, rhs)

    def accelerations(self, t, q, v):
        return self._solve(q, v)[2:]

    def reactions(self, t, q, v):
        T1, T2, _, _ = self._solve(q, v)
        return {"T1": T1, "T2": T2}

    def energy(self, t, q, v):
        p = self.p
        t1, t2 = q
        w1, w2 = v
        # Velocities in I from the book's 1.9.1 (4): v_B = w1 k x l1, v_A = v_B + (w1 + w2) k x l2.
        vb = p["l1"] * w1 * np.array([np.cos(t1), np.sin(t1)])
        va = vb + p["l2"] * (w1 + w2) * np.array([np.cos(t1 + t2), np.sin(t1 + t2)])
        y1 = -p["l1"] * np.cos(t1)
        y2 = y1 - p["l2"] * np.cos(t1 + t2)
        return (0.5 * p["m1"] * vb @ vb + 0.5 * p["m2"] * va @ va
                + p["g"] * (p["m1"] * y1 + p["m2"] * y2))

    def drive_power(self, t, q, v):
        return 0.0  # nothing is driven


class Book(Reference):
    """(1.29)-(1.32), transcribed from the Pascal listing (Tr1, Tr2, ddt1, ddt2)."""

    def _solve(self, q, v):
        p = self.p
        m1, m2, l1, l2, g = p["m1"], p["m2"], p["l1"], p["l2"], p["g"]
        t1, t2 = q
        dt1, dt2 = v
        s1, c1, s2, c2 = np.sin(t1), np.cos(t1), np.sin(t2), np.cos(t2)
        s12, c12 = np.sin(t1 + t2), np.cos(t1 + t2)
        den = -(l1 * l2 * m1 * m2) - l1 * l2 * m2**2 * s2**2
        ddt1 = (g * l2 * m1 * m2 * s1 - dt1**2 * l2**2 * m2**2 * s2
                - 2 * dt1 * dt2 * l2**2 * m2**2 * s2 - dt2**2 * l2**2 * m2**2 * s2
                - dt1**2 * l1 * l2 * m2**2 * c2 * s2 - g * l2 * m2**2 * c12 * s2) / den
        ddt2 = (-(g * l2 * m1 * m2 * s1) - g * l1 * m1 * m2 * c2 * s1
                + dt1**2 * l1**2 * m1 * m2 * s2 + dt1**2 * l2**2 * m2**2 * s2
                + 2 * dt1 * dt2 * l2**2 * m2**2 * s2 + dt2**2 * l2**2 * m2**2 * s2
                + 2 * dt1**2 * l1 * l2 * m2**2 * c2 * s2 + 2 * dt1 * dt2 * l1 * l2 * m2**2 * c2 * s2
                + dt2**2 * l1 * l2 * m2**2 * c2 * s2 + dt1**2 * l1**2 * m2**2 * c2**2 * s2
                + g * l2 * m2**2 * c12 * s2 + g * l1 * m2**2 * c2 * c12 * s2
                + dt1**2 * l1**2 * m2**2 * s2**3 + g * l1 * m1 * m2 * s12
                + g * l1 * m2**2 * s2**2 * s12) / den
        tr1 = (-(dt1**2 * l1**2 * l2 * m1**2 * m2) - g * l1 * l2 * m1**2 * m2 * c1
               - dt1**2 * l1 * l2**2 * m1 * m2**2 * c2 - 2 * dt1 * dt2 * l1 * l2**2 * m1 * m2**2 * c2
               - dt2**2 * l1 * l2**2 * m1 * m2**2 * c2 - dt1**2 * l1**2 * l2 * m1 * m2**2 * c2**2
               - g * l1 * l2 * m1 * m2**2 * c2 * c12 - g * l1 * l2 * m1 * m2**2 * c2 * s1 * s2
               - dt1**2 * l1**2 * l2 * m1 * m2**2 * s2**2
               - g * l1 * l2 * m1 * m2**2 * c1 * s2**2) / den
        tr2 = (-(dt1**2 * l1 * l2**2 * m1 * m2**2) - 2 * dt1 * dt2 * l1 * l2**2 * m1 * m2**2
               - dt2**2 * l1 * l2**2 * m1 * m2**2 - dt1**2 * l1**2 * l2 * m1 * m2**2 * c2
               - g * l1 * l2 * m1 * m2**2 * c12 - g * l1 * l2 * m1 * m2**2 * s1 * s2) / den
        return np.array([tr1, tr2, ddt1, ddt2])
