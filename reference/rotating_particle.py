"""Section 1.8.2: particle rigidly fixed on a spinning arm and disk (no equation of motion).

The scene of 1.8.1 (frames, points, rates: see reference/rotating_pendulum.py) with the rod DE
welded to the disk at a constant angle psi (a parameter): "It is important to point out that
ψ[' = 0]! The arm connected to the particle is rigidly attached to point D, i.e. it is not
executing a pendular movement!" (1.8.2 (c), "' = 0" lost in the extraction), so psi' = psi'' = 0
and B3 = T_x(psi) B2 turns with the disk.
No coordinate; three reactions, the force of the rod on the particle in B3:
B3 R = (R1, R2, 0) (shear, 1.8.2 (h)) and B3 T = (0, 0, T) (normal, T > 0 pulls E towards D).

Derivation (the book's (c)-(i)).  B3 w3 = (0, Omega sin(psi), Omega cos(psi)) and B3 w3' = 0.
B3 a_D is that of 1.8.1, (-b alpha'^2 sin(beta), -K cos(psi), K sin(psi)) with
K = b alpha'^2 cos(beta) + r Omega^2, and term (II), w3 x (w3 x r_DE) with B3 r_DE = (0, 0, -l), is
(0, -l Omega^2 sin(psi) cos(psi), l Omega^2 sin^2(psi)); the book prints their sum (g):

    B3 a_E = ( -b alpha'^2 sin(beta),
               -K cos(psi) - l Omega^2 sin(psi) cos(psi),
                K sin(psi) + l Omega^2 sin^2(psi) ).

With gravity (0, -m g sin(psi), -m g cos(psi)) in B3, Newton's law B3 R + B3 T + B3 P = m B3 a_E
gives the three reactions directly; see `Book`.

`Book` transcribes them; `Reference` is 1.8.1's numerical Newton-Euler (`particle_motion` of
reference/rotating_pendulum.py) at psi' = psi'' = 0, the force being m (a_E - g).  They agree to
rounding: the book is right in 1.8.2.

Energy (not in the book): kinetic energy from 1.8.3 (d)'s B3 v_E at l' = psi' = 0, plus m g z_E.
The drive power is the rod's force dotted with B3 v_E: the rod is welded to the disk, so all of
it is work of the prescribed base.

`psi_rate` exists only because the harness names a driven joint's rate by a parameter: the
engines hold the rod by a joint driven at psi_rate, which must be 0 here (ValueError otherwise).
"""

import numpy as np

from reference import printed, rotating_pendulum
from reference.rotating_pendulum import book_energy
from reference.spinning_base import FRAMES, ParticleOnBase, base_terms, book_velocities, chain, particle_motion, scale, sub  # noqa: F401  (FRAMES: the student page shows them)

COORDS = ()
REACTIONS = ("R1", "R2", "T")


class _FixedParticle:
    coords = COORDS
    reaction_names = REACTIONS

    def __init__(self, params):
        self.p = dict(params)

    def accelerations(self, t, q, v):
        return np.zeros(0)

    def energy(self, t, q, v):
        return book_energy(self.p, t, self.p["psi"], 0.0)

    def drive_power(self, t, q, v):
        """Power of the rod's force (R1, R2, T) on the particle, at B3 v_E (1.8.3 (d), psi' = 0)."""
        f = self.reactions(t, q, v)
        _, v_e = book_velocities(self.p, t, self.p["psi"], 0.0, self.p["l"])
        return f["R1"] * v_e[0] + f["R2"] * v_e[1] + f["T"] * v_e[2]


class Book(_FixedParticle):
    """1.8.2 (i) as printed, lost signs restored.

    The extraction prints (zeros, minus signs, equals signs and overdots lost):

        direction X3 : R 1 mb α 2 sinβ
        direction Y3 : R 2 m(gsinψ (b α 2 cosβ +r( α+ β) 2 )cosψ l( α+ β) 2 sinψ cosψ )
        direction Z3 : T m{gcosψ +[b α 2 cosβ +r( α+ β) 2 ]sinψ +l[( α+ β) 2 sin 2 ψ ]}

    R1 = -m b alpha'^2 sin(beta): the minus is restored as for 1.8.1's R (the X3 component of the
    printed a_E, -b alpha'^2 sin(beta), from (e) and T_z(beta); see rotating_pendulum.Book).
    It is 1.8.1's R at psi' = 0.

    R2 = m (g sin(psi) - K cos(psi) - l Omega^2 sin(psi) cos(psi)): the two minus signs are
    restored from the Y3 line of (i), R2 - m g sin(psi) = m (-K cos(psi) - l Omega^2 sin(psi)
    cos(psi)), whose signs the 1.8.3 listing's `psidd` confirms: the same Y3 balance there,
    with the shear force zero, reads L psi'' = -g sin + K cos + L Omega^2 sin cos (ASCII signs),
    so R2 = -m L psi''(psi' = l' = 0) with L = l.

    T = m {g cos(psi) + K sin(psi) + l Omega^2 sin^2(psi)}: every sign survives; it is 1.8.1's T
    at psi' = 0.
    """

    # The intermediate results: 1.8.1's printed w3, w3', a_D and a_E at psi' = psi'' = 0.
    PRINTED = rotating_pendulum.Book.PRINTED

    def symbols(self, t, q, v):
        beta, omega, k = base_terms(self.p, t)
        return {"b": self.p["b"], "l": self.p["l"], "alpha_rate": self.p["alpha_rate"], "beta": beta,
                "Omega": omega, "K": k, "psi": self.p["psi"], "psi_rate": 0.0, "psi_acc": 0.0,
                "sin": np.sin, "cos": np.cos, "array": np.array}

    def point_accelerations(self, t, q, v):
        return printed.evaluate(self.PRINTED, self.symbols(t, q, v))

    def reactions(self, t, q, v):
        p = self.p
        psi = p["psi"]
        beta, omega, k = base_terms(p, t)
        s, c = np.sin(psi), np.cos(psi)
        return {"R1": -p["m"] * p["b"] * p["alpha_rate"] ** 2 * np.sin(beta),
                "R2": p["m"] * (p["g"] * s - k * c - p["l"] * omega**2 * s * c),
                "T": p["m"] * (p["g"] * c + k * s + p["l"] * omega**2 * s**2)}

    def printed_rows(self, t, q, v, acc, reactions):
        """(i), B3 R + B3 T + B3 P = m B3 a_E, row by row as printed before it is solved:

            X3:  R1                = m (-b alpha'^2 sin(beta))
            Y3:  -m g sin(psi) + R2 = m (-K cos(psi) - l Omega^2 sin(psi) cos(psi))
            Z3:  -m g cos(psi) + T  = m (K sin(psi) + l Omega^2 sin^2(psi))

        (lost signs as in the class docstring), each as left side minus right side.  Nothing is
        free, so the rows check the engine's three reactions against the prescribed motion."""
        p = self.p
        m, g, l, psi = p["m"], p["g"], p["l"], p["psi"]
        beta, omega, k = base_terms(p, t)
        s, c = np.sin(psi), np.cos(psi)
        return {"Newton X3 (1.8.2)": [reactions["R1"], m * p["b"] * p["alpha_rate"] ** 2 * np.sin(beta)],
                "Newton Y3 (1.8.2)": [-m * g * s, reactions["R2"], m * k * c, m * l * omega**2 * s * c],
                "Newton Z3 (1.8.2)": [-m * g * c, reactions["T"], -m * k * s, -m * l * omega**2 * s**2]}


class Reference(ParticleOnBase):
    """m (a_E - g) in B3 from 1.8.1's numerical Newton-Euler at psi' = psi'' = 0; energy from it too."""

    coords = COORDS
    reaction_names = REACTIONS
    reaction_axes = (0, 1, 2)

    def accelerations(self, t, q, v):
        return np.zeros(0)  # no coordinate: nothing to solve

    def _motion(self, t, q, v):
        """No acceleration, and the particle's position, velocity and the rod's force on it (ParticleOnBase)."""
        p = self.p
        position, v_e, a_e, gravity = particle_motion(p, t, p["psi"], 0.0, 0.0, p["l"])
        return (), position, v_e, scale(p["m"], sub(a_e, gravity))

    def point_accelerations(self, t, q, v):
        """B3 w3, w3', a_D and a_E from the chain of frames at psi' = psi'' = 0."""
        p = self.p
        _, _, a_e, _, w, w_dot = chain(p, t, p["psi"], 0.0, 0.0, p["l"])
        return {"omega3": w, "omega3_dot": w_dot, "a_D": chain(p, t, p["psi"], 0.0, 0.0, 0.0)[2], "a_E": a_e}
