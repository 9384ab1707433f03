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

`Program` is the Pascal listing of 1.9.3 (`program pend2`) transcribed line by line: its loop
(semi-implicit Euler: the new rates first, then the angles from the new rates), its step
deltat = (tempo/na)/n, its rows (the initial one, then one per step), its mirrored positions
h1x = -l1 sin(theta1), and its four expressions, which are `Book`'s (the same closed forms, so
its accelerations and reactions equal Book's and agree with Reference to rounding).  The zeros
the extraction dropped from its numbers are restored in the class docstring, with the evidence.
"""

import math
import time

import numpy as np
from scipy.linalg import lapack

from reference import printed

COORDS = ("theta1", "theta2")
REACTIONS = ("T1", "T2")


STATE = ("t1", "t2", "d1", "d2")  # the symbols of the state in the printed expressions


def _linear_solution(a, b):
    """np.linalg.solve(a, b) by the LAPACK routine it calls (dgesv), without numpy's checks around it,
    which cost more than the solve of a 4 x 4 system."""
    _, _, x, info = lapack.dgesv(a, b)
    if info > 0:
        raise np.linalg.LinAlgError("Singular matrix")
    return x


class Reference:
    coords = COORDS
    reaction_names = REACTIONS

    def __init__(self, params):
        self.p = dict(params)
        # The printed expressions as functions of the state, the parameters bound once and math's sin and cos
        # (on one number numpy's cost more and give the same values): an integrator evaluates them at every step.
        self._evaluate = printed.Functions(self.PRINTED, STATE, {**self._constants(), "sin": math.sin, "cos": math.cos})

    def _constants(self):
        """The symbols of the printed expressions but the state and the accelerations."""
        p = self.p
        return {"m1": p["m1"], "m2": p["m2"], "l1": p["l1"], "l2": p["l2"], "g": p["g"], "array": np.array}

    def _names(self, q, v):
        """The symbols of the printed expressions but the accelerations."""
        return {**self._constants(), **dict(zip(STATE, (q[0], q[1], v[0], v[1]))), "sin": np.sin, "cos": np.cos}

    def _solve(self, q, v):
        """(T1, T2, theta1'', theta2'') from (1.27)-(1.28) in the book's matrix form."""
        state = printed.floats(q, v)
        return _linear_solution(self._evaluate["A"](*state), self._evaluate["b"](*state))

    def accelerations(self, t, q, v):
        return self._solve(q, v)[2:]

    # The accelerations of the masses as 1.9.2 prints them: B1 a_B (mass 1, in B1) and B2 a_A
    # (mass 2, in B2), with this source's own theta''; and (1.27)-(1.28) in the book's matrix form (p. 66),
    # A (T1, T2, theta1'', theta2'') = b, which `_solve` solves.  The strings are the code (see `symbols`).
    PRINTED = {"A": "array([[0.0, sin(t2), -m1*l1, 0.0], [1.0, -cos(t2), 0.0, 0.0],"
                    " [0.0, 0.0, -m2*(l1*cos(t2) + l2), -m2*l2], [0.0, 1.0, m2*l1*sin(t2), 0.0]])",
               "b": "array([m1*g*sin(t1), m1*g*cos(t1) + m1*l1*d1**2, m2*g*sin(t1 + t2) + m2*l1*d1**2*sin(t2),"
                    " m2*g*cos(t1 + t2) + m2*l1*d1**2*cos(t2) + m2*l2*(d1 + d2)**2])",
               "a_B": "array([l1*dd1, l1*d1**2, 0.0])",
               "a_A": "array([l1*(dd1*cos(t2) + d1**2*sin(t2)) + l2*(dd1 + dd2),"
                      " l1*(-dd1*sin(t2) + d1**2*cos(t2)) + l2*(d1 + d2)**2, 0.0])"}
    # The printed symbols' LaTeX (dyncheck.pages.typeset), where its defaults do not know them.
    LATEX = {"t2": r"\theta_2", "d1": r"\dot{\theta}_1", "d2": r"\dot{\theta}_2", "dd1": r"\ddot{\theta}_1",
             "dd2": r"\ddot{\theta}_2"}

    def symbols(self, t, q, v):
        dd1, dd2 = self.accelerations(t, q, v)
        return {**self._names(q, v), "dd1": dd1, "dd2": dd2}

    def point_accelerations(self, t, q, v):
        return printed.evaluate(self.PRINTED, self.symbols(t, q, v), ("a_B", "a_A"))

    def reactions(self, t, q, v):
        T1, T2, _, _ = self._solve(q, v)
        return {"T1": T1, "T2": T2}

    def energy(self, t, q, v):
        p = self.p
        t1, t2 = q
        w1, w2 = v
        c1, c12 = np.cos(t1), np.cos(t1 + t2)
        # Velocities in I from the book's 1.9.1 (4): v_B = w1 k x l1, v_A = v_B + (w1 + w2) k x l2.
        vb = p["l1"] * w1 * np.array([c1, np.sin(t1)])
        va = vb + p["l2"] * (w1 + w2) * np.array([c12, np.sin(t1 + t2)])
        y1 = -p["l1"] * c1
        y2 = y1 - p["l2"] * c12
        return (0.5 * p["m1"] * vb @ vb + 0.5 * p["m2"] * va @ va
                + p["g"] * (p["m1"] * y1 + p["m2"] * y2))

    def drive_power(self, t, q, v):
        return 0.0  # nothing is driven


class Book(Reference):
    """(1.29)-(1.32), transcribed from the Pascal listing (Tr1, Tr2, ddt1, ddt2)."""

    # Cramer's rule on the matrix form: (1.29) T1, (1.30) T2, (1.31) theta1'', (1.32) theta2'', each over the
    # common denominator, signs from the listing.  The strings are the code that `_solve` evaluates.
    PRINTED = {**Reference.PRINTED,
               "T1": "(-(d1**2*l1**2*l2*m1**2*m2) - g*l1*l2*m1**2*m2*cos(t1) - d1**2*l1*l2**2*m1*m2**2*cos(t2)"
                     " - 2*d1*d2*l1*l2**2*m1*m2**2*cos(t2) - d2**2*l1*l2**2*m1*m2**2*cos(t2)"
                     " - d1**2*l1**2*l2*m1*m2**2*cos(t2)**2 - g*l1*l2*m1*m2**2*cos(t2)*cos(t1 + t2)"
                     " - g*l1*l2*m1*m2**2*cos(t2)*sin(t1)*sin(t2) - d1**2*l1**2*l2*m1*m2**2*sin(t2)**2"
                     " - g*l1*l2*m1*m2**2*cos(t1)*sin(t2)**2)/(-(l1*l2*m1*m2) - l1*l2*m2**2*sin(t2)**2)",
               "T2": "(-(d1**2*l1*l2**2*m1*m2**2) - 2*d1*d2*l1*l2**2*m1*m2**2 - d2**2*l1*l2**2*m1*m2**2"
                     " - d1**2*l1**2*l2*m1*m2**2*cos(t2) - g*l1*l2*m1*m2**2*cos(t1 + t2)"
                     " - g*l1*l2*m1*m2**2*sin(t1)*sin(t2))/(-(l1*l2*m1*m2) - l1*l2*m2**2*sin(t2)**2)",
               "theta1_acc": "(g*l2*m1*m2*sin(t1) - d1**2*l2**2*m2**2*sin(t2) - 2*d1*d2*l2**2*m2**2*sin(t2)"
                             " - d2**2*l2**2*m2**2*sin(t2) - d1**2*l1*l2*m2**2*cos(t2)*sin(t2)"
                             " - g*l2*m2**2*cos(t1 + t2)*sin(t2))/(-(l1*l2*m1*m2) - l1*l2*m2**2*sin(t2)**2)",
               "theta2_acc": "(-(g*l2*m1*m2*sin(t1)) - g*l1*m1*m2*cos(t2)*sin(t1) + d1**2*l1**2*m1*m2*sin(t2)"
                             " + d1**2*l2**2*m2**2*sin(t2) + 2*d1*d2*l2**2*m2**2*sin(t2) + d2**2*l2**2*m2**2*sin(t2)"
                             " + 2*d1**2*l1*l2*m2**2*cos(t2)*sin(t2) + 2*d1*d2*l1*l2*m2**2*cos(t2)*sin(t2)"
                             " + d2**2*l1*l2*m2**2*cos(t2)*sin(t2) + d1**2*l1**2*m2**2*cos(t2)**2*sin(t2)"
                             " + g*l2*m2**2*cos(t1 + t2)*sin(t2) + g*l1*m2**2*cos(t2)*cos(t1 + t2)*sin(t2)"
                             " + d1**2*l1**2*m2**2*sin(t2)**3 + g*l1*m1*m2*sin(t1 + t2)"
                             " + g*l1*m2**2*sin(t2)**2*sin(t1 + t2))/(-(l1*l2*m1*m2) - l1*l2*m2**2*sin(t2)**2)"}
    CLOSED_FORMS = ("T1", "T2", "theta1_acc", "theta2_acc")

    def _solve(self, q, v, keys=CLOSED_FORMS):
        state = printed.floats(q, v)
        return np.array([self._evaluate[key](*state) for key in keys])

    def accelerations(self, t, q, v):
        return self._solve(q, v, self.CLOSED_FORMS[2:])  # (1.31)-(1.32): the tensions would cost as much again

    def reactions(self, t, q, v):
        T1, T2 = self._solve(q, v, self.CLOSED_FORMS[:2])  # (1.29)-(1.30): the accelerations would cost as much again
        return {"T1": T1, "T2": T2}

    def printed_rows(self, t, q, v, acc, reactions):
        """Newton's law for each mass as printed before it is solved, left side minus right side: in I,
        1.9.1's (1.25) (mass 1) and (1.26) (mass 2),

            (1.25)  X: -T1 sin(t1) + T2 sin(t1 + t2)          = m1 a_Bx
                    Y: -m1 g + T1 cos(t1) - T2 cos(t1 + t2)   = m1 a_By
            (1.26)  X: -T2 sin(t1 + t2)                       = m2 a_Ax
                    Y: -m2 g + T2 cos(t1 + t2)                = m2 a_Ay

        with 1.9.1's a_B and a_A (p. 60-61); and in B1 and B2, 1.9.2's (1.27) and (1.28), the rows that
        (1.29)-(1.32) solve.  Lost signs are restored from the printed cross products and terms that each
        sum adds: T1 = T^T (0, T1) = (-T1 sin, T1 cos) as printed with T_theta1, and so on.  The printed
        sum a_A shows a '+' before -theta1'^2 l2 sin(t1 + t2) and before -theta2'^2 l2 sin(t1 + t2) in its
        X row, where its own terms, printed just above it (the normal term I theta1' x (I theta1' x I l2)
        and I a_RelAB), have minus signs, and no '+' at all in its Y row, where every term is positive:
        '+' glyphs displaced in the extraction, not the book's signs, so the terms are written with theirs."""
        p = self.p
        m1, m2, l1, l2, g = p["m1"], p["m2"], p["l1"], p["l2"], p["g"]
        (t1, t2), (d1, d2), (dd1, dd2) = q, v, acc
        T1, T2 = reactions["T1"], reactions["T2"]
        s1, c1, s2, c2 = np.sin(t1), np.cos(t1), np.sin(t2), np.cos(t2)
        s12, c12 = np.sin(t1 + t2), np.cos(t1 + t2)
        a_b = ([-d1**2 * l1 * s1, dd1 * l1 * c1], [d1**2 * l1 * c1, dd1 * l1 * s1])
        # a_A: a_B, then the terms in l2 of p. 60-61, normal, tangential, Coriolis, relative (two)
        a_a = (a_b[0] + [-d1**2 * l2 * s12, dd1 * l2 * c12, -2 * d1 * d2 * l2 * s12, -d2**2 * l2 * s12,
                         dd2 * l2 * c12],
               a_b[1] + [d1**2 * l2 * c12, dd1 * l2 * s12, 2 * d1 * d2 * l2 * c12, d2**2 * l2 * c12, dd2 * l2 * s12])
        return {"(1.25) X": [-T1 * s1, T2 * s12] + [-m1 * a for a in a_b[0]],
                "(1.25) Y": [-m1 * g, T1 * c1, -T2 * c12] + [-m1 * a for a in a_b[1]],
                "(1.26) X": [-T2 * s12] + [-m2 * a for a in a_a[0]],
                "(1.26) Y": [-m2 * g, T2 * c12] + [-m2 * a for a in a_a[1]],
                "(1.27) X1": [-m1 * g * s1, T2 * s2, -m1 * l1 * dd1],
                "(1.27) Y1": [-m1 * g * c1, T1, -T2 * c2, -m1 * l1 * d1**2],
                "(1.28) X2": [-m2 * g * s12, -m2 * l1 * dd1 * c2, -m2 * l1 * d1**2 * s2, -m2 * l2 * (dd1 + dd2)],
                "(1.28) Y2": [-m2 * g * c12, T2, m2 * l1 * dd1 * s2, -m2 * l1 * d1**2 * c2, -m2 * l2 * (d1 + d2) ** 2]}


class Program:
    """The 1.9.3 Pascal listing `program pend2`, transcribed line by line.

    What it computes.  ddt1, ddt2, Tr1, Tr2 are the listing's four expressions, which `Book`
    already transcribes (Book._solve), so `accelerations` and `reactions` here are Book's closed
    forms (1.29)-(1.32) at the given state; the listing computes no energy and no drive power.
    `run(q0, v0)` replays the loop

        for nj := 1 to na do for ni := 2 to n do begin
          t := t + deltat;  ddt1 := ...; ddt2 := ...; Tr1 := ...; Tr2 := ...;
          dt1 := dt1 + deltat*ddt1;  dt2 := dt2 + deltat*ddt2;
          t1 := t1 + deltat*dt1;     t2 := t2 + deltat*dt2;      { the NEW rates }
          h1x := (-l1*sin(t1)); h1y := -(l1*cos(t1));
          h2x := (-l1*sin(t1) - l2*sin(t1 + t2)); h2y := -(l1*cos(t1) + l2*cos(t1 + t2));
          writeln(arq1, t, t1); writeln(arq2, t, t2);
          writeln(arq3, h1x, h1y); writeln(arq4, h2x, h2y)
        end

    after writing the initial row before the loop: na (n - 1) steps and as many rows plus one.
    The time index is the listing's accumulated t (t := t + deltat), not k deltat.  So the run
    ends at t = tempo - deltat = 3.9984 s, one step short of tempo: the loop counts the initial row
    as point 1 of n while deltat divides tempo by n.  The x axis is the listing's, mirrored from
    the derivation's (m1 at -l1 sin(theta1), not +l1 sin(theta1)).  The listing never writes Tr1,
    Tr2: it evaluates them at the start of each step from the state of the row before, so the
    T1, T2 of a row are those values, and for the last row the same expressions at its state.
    Rates are what the listing prints on the screen.  Masses, lengths and g come from the case
    parameters (overrides apply); tempo, n, na are the listing's own literals.  The listing's
    `real` is Turbo Pascal's 6-byte real (about 12 digits); this replay runs in doubles.

    Zeros restored (the extraction drops every 0).  Each reading was replayed against the tick
    labels of the 1.9 figures, which the plotter (apparently gnuplot: the keys name the plotted
    files, "arqt1.res") rounds outward to the next tick: theta1, theta2 in [-0.8, 0.8], ticks
    0.2; mass 1 (arqh1) x in [-0.05, 0.05], y in [-0.075, -0.045]; mass 2 (arqh2) x in
    [-0.06, 0.06], y in [-0.14, -0.115]; t in [0, 4].  The run must lie inside each range and
    reach into its outermost tick intervals.


    - `tempo : 4.;` is 4.0 s: the time axes run to 4 ("4." is no Pascal real; "4.0" lost its
      0).  `t :.;` and `dt1 :.; dt2 :.;` are 0.0.  `-3.1416/4.` is -3.1416/4.0.
    - `l1 :.7; l2 :.7;` are 0.07 m: mass 2 bottoms out at y = -(l1 + l2) = -0.14 ("-.14") and
      starts at -0.1195 (top tick "-.115"); 0.7 m would print "-1.4".
    - `m1 :.46; m2 :.46;` are 0.046 and 0.46 kg: only m2/m1 moves the angles, and the figures
      need 10.  Equal masses send theta2 to 1.12 rad and mass 2 up to y = -0.0995, off both
      axes; m2/m1 = 0.1 swings theta2 to 2.9 rad; m2/m1 = 100 stays inside but fills neither
      theta axis (theta1 <= 0.42, theta2 >= -0.20: gnuplot would stop them at 0.6 and -0.2).
      The absolute masses (0.046/0.46 against 0.0046/0.046, ...) move only T1 and T2, which no
      figure shows: they are the reading with the fewest restored zeros, nothing more.
    - `na : 1;` is 1: the reading without a restored zero, the same as the 1.10 listing's
      `a : 1;`; only n na matters to the step, so 250 x 10 would be the same dt.
    - `n : 25;` is 2500 (deltat = 1.6 ms).  n = 25 blows up at t = 0.64 s (deltat = 0.16 s);
      n = 250 puts mass 2 at |x| = 0.0613, past the 0.06 tick, and theta1 tops out at 0.47 (the
      axis would stop at 0.6); n = 250000 overflows Turbo Pascal's 16-bit integer.  n = 2500 and
      n = 25000 both land inside every range and fill it (theta1 reaches 0.618 and 0.746,
      theta2 -0.713 and -0.781, mass 2's |x| 0.0576 and 0.0547).  With na = 1 the figures admit
      n from about 2200 (theta1 must pass 0.6) to about 50000 (beyond, theta2 passes -0.8 and
      would have taken the axis to -1; the exact motion swings theta2 to -0.83 and +0.84).  So
      the figures do not choose between 2500 and 25000; the 1.10 listing's `n : 3;` (30000, near
      the integer limit) leans to 25000.  Kept: 2500, the project's recorded reading
      (book/README.md) and the larger of the two steps, so the program check sees the listing's
      integrator at its worst admissible step; 25000 is a one-line change of `n`.

    Its integrator, not its formulas, sets its error.  At deltat = 1.6 ms the run stays within
    0.1 rad of the exact motion (Reference, DOP853 at rtol 1e-12) only for the first 0.12 s, and
    sheds 0.04 J, 40 % of the swing energy above the rest position, most of it in the first
    second; at 0.16 ms it stays within 0.1 rad for 0.27 s and sheds 0.025 J.  That numerical
    damping keeps the program's theta2 inside the figure's +-0.8, where the exact motion does
    not stay: the figures fit this integrator's output better than the exact motion.
    """

    coords = COORDS
    reaction_names = REACTIONS
    integrator = "semi-implicit Euler"
    tempo = 4.0                   # tempo : 4.0;  {total time [s]}
    n = 2500                      # n : 2500;     {number of integration points}
    na = 1                        # na : 1;       {number of integration repetition}
    dt = (tempo / na) / n         # deltat := (tempo/na)/n = 1.6 ms
    steps = na * (n - 1)          # for nj := 1 to na do for ni := 2 to n do

    def __init__(self, params):
        self.p = dict(params)
        self._listing = Book(self.p)  # ddt1, ddt2, Tr1, Tr2: the listing's expressions

    def accelerations(self, t, q, v):
        """(ddt1, ddt2) of the listing: Book's (1.31)-(1.32)."""
        return self._listing.accelerations(t, q, v)

    def reactions(self, t, q, v):
        """Tr1, Tr2 of the listing: Book's (1.29)-(1.30)."""
        tr1, tr2, _, _ = self._listing._solve(q, v)
        return {"T1": tr1, "T2": tr2}

    def energy(self, t, q, v):
        raise NotImplementedError("program pend2 (1.9.3) computes no energy; "
                                  "use Reference.energy on its run")

    def drive_power(self, t, q, v):
        raise NotImplementedError("program pend2 (1.9.3) computes no drive power "
                                  "(nothing is driven in 1.9)")

    def _positions(self, t1, t2):
        """The listing's trajectory lines: x mirrored from the derivation's."""
        l1, l2 = self.p["l1"], self.p["l2"]
        h1x = (-l1 * math.sin(t1))
        h1y = -(l1 * math.cos(t1))
        h2x = (-l1 * math.sin(t1) - l2 * math.sin(t1 + t2))
        h2y = -(l1 * math.cos(t1) + l2 * math.cos(t1 + t2))
        return h1x, h1y, h2x, h2y

    def run(self, q0, v0):
        """The listing's run from (q0, v0), indexed by its t: one row per line it writes."""
        import pandas as pd  # for the run's table only: the equations need numpy alone

        start = time.perf_counter()
        t1, t2 = (float(x) for x in q0)
        dt1, dt2 = (float(x) for x in v0)
        deltat = (self.tempo / self.na) / self.n
        t = 0.0
        rows = [[t, t1, t2, dt1, dt2, *self._positions(t1, t2)]]
        reactions = []
        for nj in range(1, self.na + 1):
            for ni in range(2, self.n + 1):
                t = t + deltat
                tr1, tr2, ddt1, ddt2 = self._listing._solve((t1, t2), (dt1, dt2)).tolist()
                reactions.append((tr1, tr2))  # at the state of the row before
                dt1 = dt1 + deltat * ddt1
                dt2 = dt2 + deltat * ddt2
                t1 = t1 + deltat * dt1
                t2 = t2 + deltat * dt2
                rows.append([t, t1, t2, dt1, dt2, *self._positions(t1, t2)])
        tr1, tr2, _, _ = self._listing._solve((t1, t2), (dt1, dt2)).tolist()
        reactions.append((tr1, tr2))  # the last row's: never computed by the listing
        frame = pd.DataFrame(
            [row[1:5] + list(r) + row[5:] for row, r in zip(rows, reactions)],
            columns=["theta1", "theta2", "theta1_rate", "theta2_rate", "T1", "T2",
                     "h1x", "h1y", "h2x", "h2y"],
            index=pd.Index([row[0] for row in rows], name="t"))
        steps = self.na * (self.n - 1)
        frame.attrs.update({"method": "program", "integrator": self.integrator, "dt": deltat,
                            "steps": steps, "evaluations": steps + 1,
                            "wall": time.perf_counter() - start})
        return frame
