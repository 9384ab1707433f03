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

`Program` is the section's Matlab listing (i) transcribed line by line: its own explicit Euler at
its own step (deltat = 5e-5 s, n_int = 60000), its own formulas with their slips kept, so that
the checks can expose them:
  - `ldd`: its parentheses, `(g*cos(psi)+(b*alfad^2*cos(beta)) + r*(alfad+betad)^2)*sin(psi)`,
    multiply g cos(psi) by sin(psi); (h) and Reference have g cos(psi) alone.
  - `Reaction(1)`, before the loop, is `m*( b*alfad^2*sin(beta) + (lo+l)*psid*(alfad+betad)*cos(psi)
    + 2*ld*(alfad+betad)*sin(psi))`: no leading minus, so exactly -R of (h) (the force of the
    particle on the arm), with (h)'s single L psi' Omega cos(psi) term.  `Reaction(i)`, in the
    loop, has `- 2*ld*...` instead: its first two terms are -R of (h), its third is +R of (h),
    so it is neither R nor -R.  Right (Reference): R = -m (b alpha'^2 sin(beta)
    + 2 L psi' Omega cos(psi) + 2 l' Omega sin(psi)).
  - `psidd` is (h)'s psi'' exactly.
The zeros the text lost in the listing, and where each comes from, are listed in `Program`.
"""

import math
import time

import numpy as np

from reference import printed

from reference.spinning_base import FRAMES, ParticleOnBase, T_z, add, base_terms, book_height, book_velocities, chain, particle_motion, scale, sub  # noqa: F401  (FRAMES: the student page shows them)

COORDS = ("psi", "l")
REACTIONS = ("R",)
COORD_ACCS = ("psi_acc", "l_acc")
STATE = ("beta", "K", "L", "l", "psi", "psi_rate", "l_rate")  # the printed symbols that change with the state


class Book:
    """The book's equations of motion and reaction as printed in 1.8.3 (h)."""

    coords = COORDS
    reaction_names = REACTIONS

    def __init__(self, params):
        self.p = dict(params)
        # The printed expressions as functions of the state's symbols, the rest bound once, with math's sin and
        # cos (on one number numpy's cost more and give the same values): an integrator evaluates them at every step.
        self._evaluate = printed.Functions(self.PRINTED, STATE, {**self._constants(), "sin": math.sin, "cos": math.cos})

    def accelerations(self, t, q, v):
        state = self._floats(t, q, v)
        return np.array([self._evaluate[key](*state) for key in COORD_ACCS])

    # R = m a_E,x with the printed a_E,x (one L psi' Omega cos(psi) term).  The string is the code
    # (evaluated with `symbols`), so that dyncheck can search edits of it.
    # The intermediate results the book prints: (c) w1 in B1, w2 in B2, w3 in B3, (e) w3', (f) a_C in
    # B2, a_D and the sum a_E of terms (I)-(V) in B3, with the book's own psi'' and l''.
    PRINTED = {"R": "-m*(b*alpha_rate**2*sin(beta) + L*psi_rate*Omega*cos(psi) + 2*l_rate*Omega*sin(psi))",
               "omega1": "array([0.0, 0.0, alpha_rate])",
               "omega2": "array([0.0, 0.0, Omega])",
               "a_C": "array([-b*alpha_rate**2*sin(beta), -b*alpha_rate**2*cos(beta), 0.0])",
               "omega3": "array([psi_rate, Omega*sin(psi), Omega*cos(psi)])",
               "omega3_dot": "array([psi_acc, Omega*psi_rate*cos(psi), -Omega*psi_rate*sin(psi)])",
               "a_D": "array([-b*alpha_rate**2*sin(beta), -K*cos(psi), K*sin(psi)])",
               "a_E": "array([-(b*alpha_rate**2*sin(beta) + L*psi_rate*Omega*cos(psi) + 2*l_rate*Omega*sin(psi)),"
                      " -K*cos(psi) - L*Omega**2*sin(psi)*cos(psi) + L*psi_acc + 2*l_rate*psi_rate,"
                      " K*sin(psi) + L*(psi_rate**2 + Omega**2*sin(psi)**2) - l_acc])",
               # (h), the equations of motion solved for psi'' (Y3) and l'' (Z3)
               "psi_acc": "-g/L*sin(psi) + K/L*cos(psi) + Omega**2*sin(psi)*cos(psi) - 2*l_rate*psi_rate/L",
               "l_acc": "-k/m*l + g*cos(psi) + K*sin(psi) + L*(psi_rate**2 + Omega**2*sin(psi)**2)"}

    def _constants(self):
        """The symbols of the printed expressions that stay constant."""
        p = self.p
        return {"m": p["m"], "k": p["k"], "g": p["g"], "b": p["b"], "alpha_rate": p["alpha_rate"],
                "Omega": p["alpha_rate"] + p["beta_rate"], "array": np.array}

    def _state(self, t, q, v):
        """The values of the symbols STATE at (t, q, v)."""
        beta, _, base = base_terms(self.p, t)
        return beta, base, self.p["l0"] + q[1], q[1], q[0], v[0], v[1]

    def _floats(self, t, q, v):
        """`_state` as floats, for `_evaluate` (`_names` keeps numpy's scalars: an edit that divides by zero gives
        inf there, as numpy does, where floats would raise)."""
        return [float(x) for x in self._state(t, q, v)]

    def _names(self, t, q, v):
        """The symbols of the printed expressions but psi'' and l''."""
        return {**self._constants(), **dict(zip(STATE, self._state(t, q, v))), "sin": np.sin, "cos": np.cos}

    def symbols(self, t, q, v):
        names = self._names(t, q, v)
        return {**names, **printed.evaluate(self.PRINTED, names, COORD_ACCS)}

    def point_accelerations(self, t, q, v):
        names = self.symbols(t, q, v)
        return printed.evaluate(self.PRINTED, names, ("omega1", "omega2", "a_C", "omega3", "omega3_dot", "a_D", "a_E"))

    def reactions(self, t, q, v):
        return {"R": self._evaluate["R"](*self._floats(t, q, v))}

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

    def printed_rows(self, t, q, v, acc, reactions):
        """(h), B3 R + B3 T + B3 P = m B3 a_E with the spring's B3 T = (0, 0, k l), row by row as
        printed before it is solved (L = l0 + l, K the base's bracket, `base`):

            X3:  R                   = m (-b alpha'^2 sin(beta) - L psi' Omega cos(psi) - 2 l' Omega sin(psi))
            Y3:  -m g sin(psi)        = m (-K cos(psi) - L Omega^2 sin(psi) cos(psi) + L psi'' + 2 l' psi')
            Z3:  -m g cos(psi) + k l  = m (K sin(psi) + L (psi'^2 + Omega^2 sin^2(psi)) - l'')

        each as left side minus right side.  X3 keeps (f)'s single L psi' Omega cos(psi) (finding
        1.8.3-R); Y3 and Z3 are the rows that (h) solves for psi'' and l''."""
        p = self.p
        m, g = p["m"], p["g"]
        (psi, l), (psi_rate, l_rate), (psi_acc, l_acc) = q, v, acc
        beta, omega, base = base_terms(p, t)
        length = p["l0"] + l
        s, c = np.sin(psi), np.cos(psi)
        return {"Newton X3 (1.8.3)": [reactions["R"], m * p["b"] * p["alpha_rate"] ** 2 * np.sin(beta),
                                      m * length * psi_rate * omega * c, 2 * m * l_rate * omega * s],
                "Newton Y3 (1.8.3)": [-m * g * s, m * base * c, m * length * omega**2 * s * c, -m * length * psi_acc,
                                      -2 * m * l_rate * psi_rate],
                "Newton Z3 (1.8.3)": [-m * g * c, p["k"] * l, -m * base * s, -m * length * psi_rate**2,
                                      -m * length * omega**2 * s**2, m * l_acc]}


class Reference(ParticleOnBase):
    """The book's method evaluated numerically: B3 a_E from the five-term formula frame by frame
    (`particle_motion`), Newton's law in B3 with the arm's force (R, 0, k l): psi'' from Y3, l''
    from Z3, R from X3.  It sums terms (II) and (III) as vectors, so it has both of their
    L psi' Omega cos(psi) contributions."""

    coords = COORDS
    reaction_names = REACTIONS
    reaction_axes = (0,)

    def _motion(self, t, q, v):
        """(psi'', l''), and the particle's position, velocity and the arm's force on it (ParticleOnBase)."""
        p = self.p
        (psi, l), (psi_rate, l_rate) = q, v
        length = p["l0"] + l
        # a_E is affine in psi'' (slope w3' x r_DE = (0, L, 0)) and in l'' (slope a_rel = (0, 0, -1)):
        # evaluate it without them, then solve Y3 (no force but gravity) and Z3 (the spring's k l).
        position, v_e, a_free, gravity = particle_motion(p, t, psi, psi_rate, 0.0, length, l_rate, 0.0)
        psi_acc = (gravity[1] - a_free[1]) / length
        l_acc = a_free[2] - gravity[2] - p["k"] * l / p["m"]
        a_e = add(a_free, (0.0, length * psi_acc, -l_acc))
        return (psi_acc, l_acc), position, v_e, scale(p["m"], sub(a_e, gravity))

    def point_accelerations(self, t, q, v):
        """B3 w3, w3', a_D and a_E from the chain of frames (a_D: the chain with DE of length 0)."""
        p = self.p
        (psi_acc, l_acc), _, _, force = self._at(t, q, v)
        *_, gravity, w, w_dot = chain(p, t, q[0], v[0], psi_acc, p["l0"] + q[1], v[1], l_acc)
        a_d = chain(p, t, q[0], v[0], psi_acc, 0.0)[2]
        beta, omega, _ = base_terms(p, t)
        # C sits on the arm at B's radius b: the arm's centripetal acceleration (0, -b alpha'^2, 0) in
        # B1, turned into B2 by T_z(beta); the frames turn about Z at alpha' and alpha' + beta'.
        a_c = T_z(beta) @ np.array([0.0, -p["b"] * p["alpha_rate"] ** 2, 0.0])
        return {"omega1": np.array([0.0, 0.0, p["alpha_rate"]]), "omega2": np.array([0.0, 0.0, omega]),
                "a_C": a_c, "omega3": w, "omega3_dot": w_dot, "a_D": a_d, "a_E": np.array(force) / p["m"] + gravity}

    def _energy(self, q, motion):
        """The particle's energy and the spring's."""
        return super()._energy(q, motion) + 0.5 * self.p["k"] * q[1] ** 2

    def _drive_power(self, q, v, motion):
        """The arm's whole force on the particle (R, 0, k l) at v_E, less the spring's own power
        -k l l' (the spring's energy is in E): R v_E,x + k l (v_E,z + l') = R v_E,x + k l v_D,z."""
        return super()._drive_power(q, v, motion) + self.p["k"] * q[1] * v[1]


def _tz_t(turn, x, y, z):
    """The 1.8.3 listing's Talfa' or Tbeta', [cos sin 0; -sin cos 0; 0 0 1]' * [x; y; z], for turn = (cos, sin)
    of the angle."""
    c, s = turn
    return c * x - s * y, s * x + c * y, z


def _tx_t(turn, x, y, z):
    """The 1.8.3 listing's Tpsi', [1 0 0; 0 cos sin; 0 -sin cos]' * [x; y; z], for turn = (cos, sin) of the
    angle."""
    c, s = turn
    return x, c * y - s * z, s * y + c * z


class Program:
    """The 1.8.3 Matlab listing (i), transcribed line by line, slips kept.

    Physical constants come from the case (`params`: a b c r h l0 m k g alpha0 beta0 alpha_rate
    beta_rate), so that overrides apply; the step, the number of points and the integrator are the
    program's own.  Initial conditions are `run`'s arguments (the listing's psi(1) = pi/6, the rest
    0, are case.toml's [initial]).

    The listing as the text prints it ("=" lost everywhere; zeros lost; MATLAB's ' shows as a
    blank, as in "mass m s trajectory"), and how it is read here:
        a.5; c.5; h.2; r.1; lo.1; m.2; k 2;   -> the case's a, c, h, r, l0, m, k
        alfa(1) ; beta(1) ; l(1).; ld(1) ; psid(1) ;   -> 0 (run's q0, v0 and alpha0, beta0)
        alfad 2*pi/2; betad 2*pi*4          -> the case's alpha_rate, beta_rate (no zero lost)
        deltat.5;  n_int 6;                 -> deltat = .00005 (5e-5 s), n_int = 60000
            n_int deltat must be 3 s (figure 1.5's time axes end at 3).  Replayed from the case's
            initial state: deltat = .005 and .0005 blow up (t = 0.25 s, 1.36 s); .00005 gives
            l in [-0.0069, 0.0358] m, .000005 gives [-0.0012, 0.0354] m.  Figure 1.5's l axis
            runs from -.01 to .04 in steps of .005 (its ticks, zeros restored), which MATLAB's
            automatic limits give only for a least l below -0.005: deltat = .00005.
        Iroa [; ; a]; B1rab [; b; ]; B2rbc [; ; c]; B2rcd [; r; h]; B3rde [; ; -(lo+l)]
                                            -> [0;0;a], [0;b;0], [0;0;c], [0;r;h], [0;0;-(lo+l)]
        Talfa [cos sin -sin cos 1]          -> [cos sin 0; -sin cos 0; 0 0 1]  (T_z of the book)
        Tpsi [1 cos sin; -sin cos]          -> [1 0 0; 0 cos sin; 0 -sin cos]  (T_x of the book)
        roe Iroa + Talfa *B1rab + ...       -> Iroa + Talfa'*B1rab + Talfa'*Tbeta'*(B2rbc+B2rcd)
                                               + Talfa'*Tbeta'*Tpsi'*B3rde
        "end" printed at the top of the next page, before "B2rbc": it closes the loop after
        rz(i) (rx, ry, rz are indexed by i and plotted as a trajectory).
    Not transcribed, being plots only: figure(4) plots `reaction(1:nplot)`, lower case, which
    MATLAB (case-sensitive) does not know: the listing as printed stops there with an error.

    The loop `for i=2:n_int` (n_int - 1 = 59999 steps): t_int(i-1) = (i-2)*deltat; psidd(i-1),
    ldd(i-1) from the state i-1; then alfa, beta advanced by their rates; psid(i), ld(i) from the
    accelerations i-1 and psi(i), l(i) from the velocities i-1 (explicit Euler); Reaction(i) and
    roe from the state i.  `run` returns the rows of t_int (n_int - 1 of them, 0 to 2.9999 s: the
    listing plots 1:nplot, nplot = n_int - 1); the last state psi(n_int), at (n_int - 1) deltat,
    is in the frame's attrs["final"].
    """

    coords = COORDS
    reaction_names = REACTIONS
    integrator = "explicit Euler"
    dt = 5e-5  # deltat = .00005
    n_int = 60000
    steps = n_int - 1  # for i=2:n_int

    def __init__(self, params):
        self.p = dict(params)

    # -- the listing's lines, at a state ------------------------------------------------------
    def _psidd(self, beta, psi, l, psid, ld):
        p = self.p
        g, b, r, lo = p["g"], p["b"], p["r"], p["l0"]
        alfad, betad = p["alpha_rate"], p["beta_rate"]
        return (-g / (lo + l) * math.sin(psi)
                + (b * alfad**2 * math.cos(beta) + r * (alfad + betad)**2) / (lo + l) * math.cos(psi)
                + (alfad + betad)**2 * math.sin(psi) * math.cos(psi)
                - 2 * ld * psid / (lo + l))

    def _ldd(self, beta, psi, l, psid, ld):
        p = self.p
        g, b, r, lo, k, m = p["g"], p["b"], p["r"], p["l0"], p["k"], p["m"]
        alfad, betad = p["alpha_rate"], p["beta_rate"]
        return (-k / m * l
                + (g * math.cos(psi) + (b * alfad**2 * math.cos(beta))
                   + r * (alfad + betad)**2) * math.sin(psi)
                + (lo + l) * (psid**2 + (alfad + betad)**2 * math.sin(psi)**2))

    def _reaction(self, beta, psi, l, psid, ld, ld_sign=-1.0):
        """The loop's Reaction(i), with a minus before 2*ld; Reaction(1) before the loop has a plus
        (ld_sign = +1)."""
        p = self.p
        m, b, lo = p["m"], p["b"], p["l0"]
        alfad, betad = p["alpha_rate"], p["beta_rate"]
        return m * (b * alfad**2 * math.sin(beta)
                    + (lo + l) * psid * (alfad + betad) * math.cos(psi)
                    + ld_sign * 2 * ld * (alfad + betad) * math.sin(psi))

    def _roe(self, alfa, beta, psi, l):
        """roe = Iroa + Talfa'*B1rab + Talfa'*Tbeta'*(B2rbc+B2rcd) + Talfa'*Tbeta'*Tpsi'*B3rde."""
        p = self.p
        # each angle's (cos, sin), computed once: Talfa' turns three vectors, Tbeta' two
        talfa = math.cos(alfa), math.sin(alfa)
        tbeta = math.cos(beta), math.sin(beta)
        tpsi = math.cos(psi), math.sin(psi)
        x1, y1, z1 = _tz_t(talfa, 0.0, p["b"], 0.0)
        x2, y2, z2 = _tz_t(talfa, *_tz_t(tbeta, 0.0, p["r"], p["c"] + p["h"]))  # B2rbc+B2rcd
        x3, y3, z3 = _tz_t(talfa, *_tz_t(tbeta, *_tx_t(tpsi, 0.0, 0.0, -(p["l0"] + l))))
        return x1 + x2 + x3, y1 + y2 + y3, p["a"] + z1 + z2 + z3  # Iroa = [0; 0; a]

    # -- the model interface ------------------------------------------------------------------
    # The listing's ldd and loop Reaction lines in Python syntax (^ -> **), for dyncheck's search
    # of edits; `accelerations` and `reactions` evaluate the same lines as plain floats.
    PRINTED = {
        "l_acc": "-k/m*l + (g*cos(psi)+(b*alfad**2*cos(beta)) + r*(alfad+betad)**2)*sin(psi)"
                 " + (lo+l)*(psid**2+(alfad+betad)**2*sin(psi)**2)",
        "R": "m*(b*alfad**2*sin(beta) + (lo+l)*psid*(alfad+betad)*cos(psi) - 2*ld*(alfad+betad)*sin(psi))",
    }
    # The listing's symbols' LaTeX (dyncheck.pages.typeset), where its defaults do not know them.
    LATEX = {"alfad": r"\dot{\alpha}", "betad": r"\dot{\beta}", "psid": r"\dot{\psi}", "ld": r"\dot{l}"}

    def symbols(self, t, q, v):
        p = self.p
        return {"k": p["k"], "m": p["m"], "g": p["g"], "b": p["b"], "r": p["r"], "lo": p["l0"],
                "alfad": p["alpha_rate"], "betad": p["beta_rate"], "beta": p["beta0"] + p["beta_rate"] * t,
                "psi": q[0], "l": q[1], "psid": v[0], "ld": v[1], "sin": np.sin, "cos": np.cos}

    def accelerations(self, t, q, v):
        """The listing's psidd, ldd at (t, q, v), beta = beta0 + beta_rate t."""
        beta = self.p["beta0"] + self.p["beta_rate"] * t
        args = (beta, float(q[0]), float(q[1]), float(v[0]), float(v[1]))
        return np.array([self._psidd(*args), self._ldd(*args)])

    def reactions(self, t, q, v):
        """The listing's loop line Reaction(i) at (t, q, v)."""
        beta = self.p["beta0"] + self.p["beta_rate"] * t
        return {"R": self._reaction(beta, float(q[0]), float(q[1]), float(v[0]), float(v[1]))}

    def energy(self, t, q, v):
        raise NotImplementedError("the 1.8.3 Matlab listing computes no energy")

    def drive_power(self, t, q, v):
        raise NotImplementedError("the 1.8.3 Matlab listing computes no drive power")

    def run(self, q0, v0):
        """The listing's loop from psi(1), l(1) = q0 and psid(1), ld(1) = v0.

        A DataFrame indexed by t (t_int): psi, l, psi_rate, l_rate, R (Reaction, its first
        element from the line before the loop), x, y, z (rx, ry, rz); attrs: method, dt, steps,
        wall, evaluations, final (t, q, v of the state n_int, which t_int does not reach).
        FloatingPointError, naming the time and step, if the state stops being finite.
        """
        import pandas as pd  # only here: the equations above are plain math

        start = time.perf_counter()
        p = self.p
        alfad, betad = p["alpha_rate"], p["beta_rate"]
        deltat, n_int = self.dt, self.n_int
        alfa, beta = p["alpha0"], p["beta0"]                    # alfa(1), beta(1)
        psi, l = float(q0[0]), float(q0[1])                     # psi(1), l(1)
        psid, ld = float(v0[0]), float(v0[1])                   # psid(1), ld(1)
        out_psi, out_l, out_psid, out_ld = [psi], [l], [psid], [ld]
        x, y, z = self._roe(alfa, beta, psi, l)
        out_x, out_y, out_z = [x], [y], [z]
        out_R = [self._reaction(beta, psi, l, psid, ld, ld_sign=1.0)]  # Reaction(1)
        t_int = []
        try:
            for i in range(2, n_int + 1):
                t_int.append((i - 2) * deltat)                      # t_int(i-1)
                psidd = self._psidd(beta, psi, l, psid, ld)         # psidd(i-1)
                ldd = self._ldd(beta, psi, l, psid, ld)             # ldd(i-1)
                alfa = alfa + alfad * deltat                        # alfa(i)
                beta = beta + betad * deltat                        # beta(i)
                psid_new = psid + psidd * deltat                    # psid(i)
                ld_new = ld + ldd * deltat                          # ld(i)
                psi = psi + psid * deltat                           # psi(i), from psid(i-1)
                l = l + ld * deltat                                 # l(i), from ld(i-1)
                psid, ld = psid_new, ld_new
                if not math.isfinite(psi + l + psid + ld):  # MATLAB would go on with NaN
                    raise FloatingPointError(f"the 1.8.3 listing's explicit Euler is unstable: state "
                                             f"not finite at t = {(i - 1) * deltat:.6g} s (step {i - 1})")
                out_R.append(self._reaction(beta, psi, l, psid, ld))  # Reaction(i)
                x, y, z = self._roe(alfa, beta, psi, l)             # rx(i), ry(i), rz(i)
                out_psi.append(psi), out_l.append(l), out_psid.append(psid), out_ld.append(ld)
                out_x.append(x), out_y.append(y), out_z.append(z)
        except (OverflowError, ValueError) as error:  # x**2 or cos of a huge or infinite state
            raise FloatingPointError(f"the 1.8.3 listing's explicit Euler is unstable: its state grew beyond "
                                     f"floats ({error.args[-1] if error.args else type(error).__name__}) at "
                                     f"t = {(i - 2) * deltat:.6g} s (step {i - 1})") from None
        rows = len(t_int)  # n_int - 1, as plotted (1:nplot)
        frame = pd.DataFrame({"psi": out_psi[:rows], "l": out_l[:rows], "psi_rate": out_psid[:rows],
                              "l_rate": out_ld[:rows], "R": out_R[:rows], "x": out_x[:rows],
                              "y": out_y[:rows], "z": out_z[:rows]},
                             index=pd.Index(np.array(t_int), name="t"))
        frame.attrs.update({"method": self.integrator, "dt": deltat, "steps": self.steps,
                            "wall": time.perf_counter() - start, "evaluations": self.steps,
                            "final": ((n_int - 1) * deltat, (psi, l), (psid, ld))})
        return frame
