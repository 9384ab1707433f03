"""Section 1.8.1: simple pendulum hung from a spinning arm and disk (one equation of motion).

Frames (book, 1.8.1 (a)): B1 = T_z(alpha) I, B2 = T_z(beta) B1, B3 = T_x(psi) B2, with
T_z(a) = [[c, s, 0], [-s, c, 0], [0, 0, 1]] and T_x(a) = [[1, 0, 0], [0, c, s], [0, -s, c]].
Points (1.8.1 (b)): I r_OA = (0, 0, a), B1 r_AB = (0, b, 0), B2 r_BC = (0, 0, c),
B2 r_CD = (0, r, h), B3 r_DE = (0, 0, -l).  The arm turns about Z at A and the disk about Z1
at C, both at constant rates (alpha'' = beta'' = 0), so Omega = alpha' + beta' is constant;
the massless rigid rod DE of length l swings by psi about X2 = X3 at D and carries the tip
mass m at E.  Gravity is -Z.  Coordinate: psi.  Reactions (1.8.1 (h)): B3 R = (R, 0, 0) and
B3 T = (0, 0, T), the force of the rod on the particle; T > 0 pulls E towards D (tension).
The rod's force has no Y3 component: the hinge at D is free about X3 and the rod is massless,
so its moment about X3, (r_DE x F) . i3 = l F_y, vanishes.

Derivation (the book's (c)-(i)).  Angular velocity and acceleration of B3:

    B3 w3  = (psi', Omega sin(psi), Omega cos(psi)),
    B3 w3' = (psi'', Omega psi' cos(psi), -Omega psi' sin(psi)).

Acceleration of D (terms (I), 1.8.1 (e)-(g)): B1 a_B = (0, -b alpha'^2, 0), B2 a_C =
T_z(beta) B1 a_B = (-b alpha'^2 sin(beta), -b alpha'^2 cos(beta), 0), and with the disk's
centripetal term B2 a_D = B2 a_C + (0, -r Omega^2, 0), so

    B3 a_D = (-b alpha'^2 sin(beta), -K cos(psi), K sin(psi)),   K = b alpha'^2 cos(beta) + r Omega^2.

Term (II), w3 x (w3 x r_DE) = (-l psi' Omega cos(psi), -l Omega^2 sin(psi) cos(psi),
l (psi'^2 + Omega^2 sin^2(psi))); term (III), w3' x r_DE = (-l Omega psi' cos(psi), l psi'', 0).
Their sum, as the book prints it in (g) (this time with the factor 2 on l psi' Omega cos(psi),
which 1.8.3 (f) drops):

    B3 a_E = ( -b alpha'^2 sin(beta) - 2 l psi' Omega cos(psi),
               -K cos(psi) - l Omega^2 sin(psi) cos(psi) + l psi'',
                K sin(psi) + l (psi'^2 + Omega^2 sin^2(psi)) ).

Gravity in B3 is T_x(psi) T_z(beta) T_z(alpha) (0, 0, -m g) = (0, -m g sin(psi), -m g cos(psi)).
Newton, B3 R + B3 T + B3 P = m B3 a_E, gives R (X3), psi'' (Y3) and T (Z3); see `Book`.

`Book` transcribes the printed results; `Reference` evaluates the same Newton-Euler method
numerically (rotation matrices, the five-term formula frame by frame, Newton's law in B3) and so
checks the closed forms against the method they came from.  The two agree to rounding, and
MuJoCo and Pinocchio agree with both (cases/rotating_pendulum): the book is right in 1.8.1, and
`Reference` needs no correction.

Energy and drive power are not in the book for 1.8.1.  `Book` takes B3 v_E from 1.8.3 (d), which
prints it for the same chain, with (l0 + l) -> l and l' = 0:

    B3 v_E = (-b alpha' cos(beta) - r Omega - l Omega sin(psi),
               b alpha' sin(beta) cos(psi) + l psi',
              -b alpha' sin(beta) sin(psi)),

and the height of E from (b), z_E = a + c + h - l cos(psi).  The drive power is the power of the
rod's force on the particle, R v_E,x + T v_E,z: the rod is massless and D moves with the base,
so this is what the prescribed base puts in (gravity is in the energy).
"""

import numpy as np

from reference import printed

from reference.spinning_base import FRAMES, ParticleOnBase, add, base_terms, book_height, book_velocities, chain, particle_motion, scale, sub  # noqa: F401  (FRAMES: the student page shows them)

COORDS = ("psi",)
REACTIONS = ("R", "T")


def book_energy(p, t, psi, psi_rate):
    """Kinetic energy from B3 v_E of 1.8.3 (d) with L = l, L' = 0 (1.8.1 and 1.8.2 print no
    velocity), plus m g z_E, z_E = a + c + h - l cos(psi) (1.8.1 (b))."""
    _, v_e = book_velocities(p, t, psi, psi_rate, p["l"])
    return 0.5 * p["m"] * v_e @ v_e + p["m"] * p["g"] * book_height(p, psi, p["l"])


class Book:
    """1.8.1 (i) as printed, lost signs restored.

    The extraction prints (zeros, minus signs, equals signs and overdots lost):

        direction X3 : R m(b α 2 sinβ +2l ψ( α+ β)cosψ)
        direction Z3 : T m{gcosψ +[b α 2 cosβ +r( α+ β) 2 ]sinψ +l[ ψ 2 +( α+ β) 2 sin 2 ψ]}
        g direction Y3 : ψ + l sinψ (b α2 cosβ +r( α+ β) 2 ) cosψ ( α+ l β) 2 sinψcosψ

    R = -m (b alpha'^2 sin(beta) + 2 l psi' Omega cos(psi)).  The "+" inside survives, so the lost
    sign is the one in front.  It is restored from the book's own lines: its X3 line of
    (g) and (i), "R = m (b α 2 sinβ 2l ψ(α+β)cosψ)", is m B3 a_E,x, and both terms of a_E,x are
    negative when the printed cross products are evaluated: (e) w1 x (w1 x r_OB) = (0, -b alpha'^2, 0),
    turned by T_z(beta) (its -sin(beta) entry survives in the 1.8.3 listing's Tbeta) into
    -b alpha'^2 sin(beta) along X2, and (II), (III) give -l psi' Omega cos(psi) each.  This is
    the sign spring_pendulum.py restores for 1.8.3's R, and the engines' force sensor agrees.
    (The 1.8.3 Matlab listing's `Reaction = m*( b*alfad^2*sin(beta) + ...)` carries no minus:
    read literally it is -R, the force of the particle on the arm.  1.8.1 has no listing.)

    T = m {g cos(psi) + K sin(psi) + l (psi'^2 + Omega^2 sin^2(psi))}: every sign survives.  It
    agrees with the Z3 line of (i), -m g cos(psi) + T = m (K sin(psi) + l (...)), and the 1.8.3
    listing's `ldd` gives the same terms the same (+) signs.  (That listing's parentheses,
    `(g*cos(psi)+(b*alfad^2*cos(beta)) + r*(alfad+betad)^2)*sin(psi)`, also multiply g cos(psi)
    by sin(psi): a slip of the 1.8.3 program, not of its displayed equation nor of 1.8.1.)

    psi'' + (g / l) sin(psi) - (K / l) cos(psi) - Omega^2 sin(psi) cos(psi) = 0.  The "+" before
    g / l survives; the two minus signs are restored from the 1.8.3 listing's `psidd`, which
    prints the same Y3 equation with ASCII signs (-g/L sin + K/L cos + Omega^2 sin cos
    - 2 l' psi'/L, here L = l and l' = 0), and agree with the Y3 line of (i),
    -m g sin(psi) = m (-K cos(psi) - l Omega^2 sin(psi) cos(psi) + l psi'').  The stray "l" in
    "( α+ l β) 2" is the denominator of K / l set below the line, not a factor of Omega^2: the
    1.8.3 display shows the same artefact, "( α+ (l +l) β) 2", where its listing divides K,
    not Omega^2, by (l0 + l).
    """

    coords = COORDS
    reaction_names = REACTIONS

    # The intermediate results 1.8.1 prints, in B3: (c) w3, (e) w3', (f) a_D and (g) a_E, with the
    # book's own psi''.  The strings are the code (evaluated with `symbols`).
    PRINTED = {"omega3": "array([psi_rate, Omega*sin(psi), Omega*cos(psi)])",
               "omega3_dot": "array([psi_acc, Omega*psi_rate*cos(psi), -Omega*psi_rate*sin(psi)])",
               "a_D": "array([-b*alpha_rate**2*sin(beta), -K*cos(psi), K*sin(psi)])",
               "a_E": "array([-b*alpha_rate**2*sin(beta) - 2*l*psi_rate*Omega*cos(psi),"
                      " -K*cos(psi) - l*Omega**2*sin(psi)*cos(psi) + l*psi_acc,"
                      " K*sin(psi) + l*(psi_rate**2 + Omega**2*sin(psi)**2)])"}

    def __init__(self, params):
        self.p = dict(params)

    def symbols(self, t, q, v):
        p = self.p
        beta, omega, k = base_terms(p, t)
        return {"b": p["b"], "l": p["l"], "alpha_rate": p["alpha_rate"], "beta": beta, "Omega": omega, "K": k,
                "psi": q[0], "psi_rate": v[0], "psi_acc": self.accelerations(t, q, v)[0],
                "sin": np.sin, "cos": np.cos, "array": np.array}

    def point_accelerations(self, t, q, v):
        return printed.evaluate(self.PRINTED, self.symbols(t, q, v))

    def accelerations(self, t, q, v):
        p = self.p
        (psi,) = q
        _, omega, k = base_terms(p, t)
        s, c = np.sin(psi), np.cos(psi)
        return np.array([-p["g"] / p["l"] * s + k / p["l"] * c + omega**2 * s * c])

    def reactions(self, t, q, v):
        p = self.p
        (psi,), (psi_rate,) = q, v
        beta, omega, k = base_terms(p, t)
        s, c = np.sin(psi), np.cos(psi)
        R = -p["m"] * (p["b"] * p["alpha_rate"] ** 2 * np.sin(beta) + 2 * p["l"] * psi_rate * omega * c)
        T = p["m"] * (p["g"] * c + k * s + p["l"] * (psi_rate**2 + omega**2 * s**2))
        return {"R": R, "T": T}

    def energy(self, t, q, v):
        return book_energy(self.p, t, q[0], v[0])

    def drive_power(self, t, q, v):
        """Power of the rod's force (R, 0, T) on the particle, at B3 v_E (1.8.3 (d))."""
        f = self.reactions(t, q, v)
        _, v_e = book_velocities(self.p, t, q[0], v[0], self.p["l"])
        return f["R"] * v_e[0] + f["T"] * v_e[2]

    def printed_rows(self, t, q, v, acc, reactions):
        """(i), B3 R + B3 T + B3 P = m B3 a_E, row by row as printed before it is solved:

            X3:  R               = m (-b alpha'^2 sin(beta) - 2 l psi' Omega cos(psi))
            Y3:  -m g sin(psi)    = m (-K cos(psi) - l Omega^2 sin(psi) cos(psi) + l psi'')
            Z3:  -m g cos(psi) + T = m (K sin(psi) + l (psi'^2 + Omega^2 sin^2(psi)))

        (lost signs as in the class docstring: those of the printed a_E (g) and B3 P), each as
        left side minus right side."""
        p = self.p
        m, g, l = p["m"], p["g"], p["l"]
        (psi,), (psi_rate,), (psi_acc,) = q, v, acc
        beta, omega, k = base_terms(p, t)
        s, c = np.sin(psi), np.cos(psi)
        return {"Newton X3 (1.8.1)": [reactions["R"], m * p["b"] * p["alpha_rate"] ** 2 * np.sin(beta),
                                      2 * m * l * psi_rate * omega * c],
                "Newton Y3 (1.8.1)": [-m * g * s, m * k * c, m * l * omega**2 * s * c, -m * l * psi_acc],
                "Newton Z3 (1.8.1)": [-m * g * c, reactions["T"], -m * k * s, -m * l * psi_rate**2,
                                      -m * l * omega**2 * s**2]}


class Reference(ParticleOnBase):
    """Newton's law in B3 with B3 a_E from `particle_motion`; psi'' from Y3, where the rod pushes nothing."""

    coords = COORDS
    reaction_names = REACTIONS
    reaction_axes = (0, 2)

    def _motion(self, t, q, v):
        """psi'', and the position, velocity of E and the rod's force on it (ParticleOnBase), psi'' solved from Y3."""
        p = self.p
        (psi,), (psi_rate,) = q, v
        position, v_e, a_free, gravity = particle_motion(p, t, psi, psi_rate, 0.0, p["l"])
        # a_E is affine in psi'' with slope w3' x r_DE = i3 x (0, 0, -l) = (0, l, 0).
        psi_acc = (gravity[1] - a_free[1]) / p["l"]
        a_e = add(a_free, (0.0, p["l"] * psi_acc, 0.0))
        return (psi_acc,), position, v_e, scale(p["m"], sub(a_e, gravity))

    def point_accelerations(self, t, q, v):
        """B3 w3, w3', a_D and a_E from the chain of frames (a_D: the chain with DE of length 0)."""
        p = self.p
        (psi_acc,) = self._at(t, q, v)[0]
        _, _, a_e, _, w, w_dot = chain(p, t, q[0], v[0], psi_acc, p["l"])
        return {"omega3": w, "omega3_dot": w_dot, "a_D": chain(p, t, q[0], v[0], psi_acc, 0.0)[2], "a_E": a_e}
