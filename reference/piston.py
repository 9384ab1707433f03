"""Section 1.7, Examples 3-4: a mass at the end of a hydraulic piston turning about Z.

Sources in the extraction (one page per line): Example 3 statement line 41, solution (a)-(e)
lines 43-45, (1.17)-(1.20) lines 45-47, (1.21)-(1.23) and Example 4 line 49, the four terms and
(1.24) line 51; (1.10) itself (printed "(1.1)") and its B1 form at the end of 1.6, line 35.

Scene (book 1.7.3, Example 3).  "An hydraulic piston
with a mass m located at its end, rotating with angular speed theta' relative to the axis Z
(inertial frame).  A moving reference frame X1 Y1 Z1, fixed to the piston, also rotates with
angular speed theta' ... the origin point coincides with the origin of the inertial frame,
since the moving frame does not exhibit translation ... the mass m exhibit[s] motion in the
positive direction of axis X1."  Hence:

    frames     I (X Y Z, unit vectors i j k);  B1 = T_z(theta) I, (b) of the solution:
               i1 = cos(theta) i + sin(theta) j,  j1 = -sin(theta) i + cos(theta) j,  k1 = k
               ("positive rotation of the system B1 around the axis Z (inertial)")
    origin     O = A, fixed: I a_A = 0
    mass B     B1 L = (L, 0, 0);  I L = T^T B1 L = (L cos(theta), L sin(theta), 0)   ((d))
    rotation   I omega = (0, 0, theta'),  I omega' = (0, 0, theta'')                  ((c))
    motions    prescribed (this project): theta = theta0 + theta_rate t + theta_acc t^2/2,
               L = L0 + L_rate t + L_acc t^2/2; no free coordinate, q = v = ().

Gravity.  Examples 3-4 are pure kinematics and never mention gravity.  The chapter's rule
(gravity along -Z, book README) puts the arm in the horizontal plane Z = 0, so gravity is
I g = (0, 0, -g) = B1 g (Z1 = Z).  It does no work (the mass stays at Z = 0) and only the
arm's vertical support F3 = m g carries it.

What the book prints (extraction: overdots, minus signs and zeros lost; '+' survives).

  (1.13) = (1.15)  I v_B = d/dt(I L) = (L' cos - L theta' sin,  L' sin + L theta' cos,  0)
  (1.18)           I v_Rel + I omega x I L: the same vector (printed once more, signs lost)
  (1.20)           d2/dt2(I L) = d/dt(1.13), printed term by term
                     (L'' cos - L' theta' sin - L' theta' sin - L theta'' sin - L theta'^2 cos,
                      L'' sin + L' theta' cos + L' theta' cos + l theta'' cos - L theta'^2 sin, 0)
                   and collected
                     (L'' cos - 2 L' theta' sin - L theta'' sin - L theta'^2 cos,
                      L'' sin + 2 L' theta' cos + L theta'' cos - L theta'^2 sin,  0)
  (1.23)           Example 4, "1st way": the same collected vector as (1.20).
  (1.10)           I a_B = I a_A + I omega' x I r_AB + I omega x (I omega x I r_AB)
                           + 2 I omega x I v_Rel + I a_Rel       (printed "(1.1)", zero lost)
  Example 4, "2nd way", its four terms (I a_A = 0):
    normal         I omega x (I omega x I L) = (-L theta'^2 cos, -L theta'^2 sin, 0)
    tangential     I omega' x I L            = (-L theta'' sin,   L theta'' cos,   0)
    Coriolis       2 I omega x I v_Rel       = (-2 theta' L' sin,  2 theta' L' cos, 0)
    relative       I a_Rel = T^T (L'', 0, 0) = ( L'' cos,          L'' sin,         0)   (1.22)
  (1.24)           "By adding up the four terms":
                     (L'' cos - 2 L' theta' sin - L theta'' sin - L theta'^2 cos,
                      L'' sin + 2 L' theta' SIN + L theta'' cos - L theta'^2 sin,  0)

Restored signs and symbols, and where from:
  * every lost minus in (1.13), (1.20), (1.23) and in the four terms: the book's own
    determinants "i j k / 0 0 theta' / L cos L sin 0" printed with each cross product give
    k x i1-type products (-sin, cos), and the un-collected line of (1.20) is d/dt of (1.13)
    term by term; its surviving '+' signs in the Y row fix the rest (d/dt cos = -sin);
  * the lowercase "l theta'' cos" in (1.20), (1.23), (1.24) is L theta'' cos(theta): the
    example has no other length;
  * the zero Z entries of every vector (zeros are lost everywhere).
Nothing else is restored: the '+2 L' theta' sin' of (1.24) is printed with its '+' and with
'sin', and is kept as printed (see below).

The book gives no numbers in Examples 3-4 (no m, L, theta or rates, no numerical results);
they are symbolic throughout.  Nothing numerical to transcribe.

Quantities (all vectors with components in B1; T = T_z(theta) maps I to B1):

  a_eq110   T (1.24): the five-term formula as the book sums it.
  a_d2dt2   T (1.23): the double differentiation of I L.
  reactions F = (F1, F2, F3), the force of the arm on the mass in B1 (this project's definition;
            the book computes none in 1.7): Newton for the mass, m B1 a_B = F + m B1 g, so
            F = m B1 a_B + (0, 0, m g).  `Book` takes B1 a_B from (1.24), the route the book
            recommends "when one desires to express the absolute acceleration of a particle in a
            moving reference frame" (end of Example 4) -- the one a reader uses for reactions
            in B1 (flip `_reaction_route` to "a_d2dt2" to take (1.23) instead).
  energy    (1/2) m |I v_B|^2 + m g Z_B, with (1.15) and Z_B = 0.
  drive_power  F . v_B: the power of the arm (both prescribed motions) on the mass; gravity
            does no work.  Equals dE/dt.

Correction (class `Reference`).  Sum the four printed terms of Example 4, component Y:

    Y = -L theta'^2 sin + L theta'' cos + 2 theta' L' cos + L'' sin,

so the Coriolis contribution to Y is +2 L' theta' cos(theta), as the Coriolis term itself is
printed two lines above (1.24) and as (1.20)/(1.23) print it.  (1.24) prints
+2 L' theta' sin(theta): a typo in the sum, cos -> sin.  The inertial error of (1.24) is

    delta = (1.24) - a = (0, 2 L' theta' (sin(theta) - cos(theta)), 0)          (in I)
    T delta = 2 L' theta' (sin(theta) - cos(theta)) (sin(theta), cos(theta), 0)  (in B1)

so a_eq110_x and a_eq110_y of `Book` are off by those amounts, F1 and F2 by m times them, and
the drive power by m delta . v_B = 2 m L' theta' (sin - cos)(L' sin + L theta' cos).  F3,
a_eq110_z, a_d2dt2 and the energy are right.  The corrected vector in B1, by either route, is

    B1 a_B = (L'' - L theta'^2,  2 L' theta' + L theta'',  0),

which is also what the B1 form of (1.10) printed at the end of 1.6 gives directly
(B1 omega' x B1 r + B1 omega x (B1 omega x B1 r) + 2 B1 omega x d/dt(B1 r) + d2/dt2(B1 r)).
`Reference._acceleration` computes a_eq110 as the vector sum of the five terms
(numpy cross products in I, then T), and a_d2dt2 from (1.23) -- two independent routes.
"""

import numpy as np

from reference import printed

# The book's T_z, B1 s = T_z(theta) I s (solution (b)), the matrix every section uses: FRAMES holds it as the
# expression that T_z evaluates and the student's page typesets.
from reference.spinning_base import FRAMES, T_z, cross  # noqa: F401  (FRAMES: the student page shows them)

COORDS = ()
REACTIONS = ("F1", "F2", "F3")


class Book:
    """Examples 3-4 as printed: (1.15) velocity, (1.23) double differentiation, (1.24) five terms."""

    coords = COORDS
    reaction_names = REACTIONS
    _reaction_route = "a_eq110"  # which acceleration the reactions use (see module docstring)

    def __init__(self, params):
        self.p = dict(params)

    def _motion(self, t):
        """theta, theta', theta'', L, L', L'' at time t (constant second derivatives)."""
        p = self.p
        theta = p["theta0"] + p["theta_rate"] * t + 0.5 * p["theta_acc"] * t**2
        L = p["L0"] + p["L_rate"] * t + 0.5 * p["L_acc"] * t**2
        return (theta, p["theta_rate"] + p["theta_acc"] * t, p["theta_acc"],
                L, p["L_rate"] + p["L_acc"] * t, p["L_acc"])

    # -- kinematics, inertial components ----------------------------------------
    def _velocity_inertial(self, t):
        """(1.13) = (1.15) = (1.18)."""
        return printed.evaluate(self.PRINTED, self.symbols(t), ("v_B",))["v_B"]

    # The book's intermediate results and the two accelerations as printed, the accelerations in the inertial
    # frame turned into B1 by T_z(theta); the strings are the code (evaluated with `symbols`), so that dyncheck
    # can search edits of them and the student's page typesets what runs.
    PRINTED = {
        # (c) the frame's angular velocity and acceleration, in I
        "omega": "array([0.0, 0.0, w])",
        "omega_dot": "array([0.0, 0.0, wd])",
        # (d) the mass's position, (1.17) its relative velocity and (1.22) relative acceleration: B1's vectors
        # (L, 0, 0), (L', 0, 0), (L'', 0, 0) turned into I
        "r": "Tz(th).T @ array([L, 0.0, 0.0])",
        "v_rel": "Tz(th).T @ array([Ld, 0.0, 0.0])",
        "a_rel": "Tz(th).T @ array([Ldd, 0.0, 0.0])",
        # (1.13) = (1.15), the absolute velocity in I
        "v_B": "array([Ld*cos(th) - L*w*sin(th), Ld*sin(th) + L*w*cos(th), 0.0])",
        # (1.20) collected = (1.23)
        "a_d2dt2": "Tz(th) @ array([Ldd*cos(th) - 2*Ld*w*sin(th) - L*wd*sin(th) - L*w**2*cos(th),"
                   " Ldd*sin(th) + 2*Ld*w*cos(th) + L*wd*cos(th) - L*w**2*sin(th), 0.0])",
        # (1.24) as printed: the Y row's Coriolis part reads 2 L' theta' sin(theta)
        "a_eq110": "Tz(th) @ array([Ldd*cos(th) - 2*Ld*w*sin(th) - L*wd*sin(th) - L*w**2*cos(th),"
                   " Ldd*sin(th) + 2*Ld*w*sin(th) + L*wd*cos(th) - L*w**2*sin(th), 0.0])",
        # the arm's force on the mass in B1, m a = F + m g with g = (0, 0, -g): this project's (1.7 computes no
        # force), `a` the acceleration of `_reaction_route`
        "F": "m*a + array([0.0, 0.0, m*g])",
    }
    # The printed symbols' LaTeX (dyncheck.pages.typeset), where its defaults do not know them.
    LATEX = {"th": r"\theta", "w": r"\dot{\theta}", "wd": r"\ddot{\theta}", "Ld": r"\dot{L}", "Ldd": r"\ddot{L}"}

    def symbols(self, t, q=(), v=()):
        th, w, wd, L, Ld, Ldd = self._motion(t)
        return {"th": th, "w": w, "wd": wd, "L": L, "Ld": Ld, "Ldd": Ldd, "m": self.p["m"], "g": self.p["g"],
                "sin": np.sin, "cos": np.cos, "array": np.array, "Tz": T_z}

    # -- model interface -----------------------------------------------------------
    def accelerations(self, t, q, v):
        return np.zeros(0)

    def point_accelerations(self, t, q, v):
        """Absolute acceleration of the mass, components in B1, by the book's two routes."""
        names = self.symbols(t)
        return {route: self._acceleration(names, route) for route in ("a_d2dt2", "a_eq110")}

    def _acceleration(self, names, route):
        """The mass's acceleration in B1 by `route`, "a_d2dt2" or "a_eq110", at the symbols `names`."""
        return printed.evaluate(self.PRINTED, names, (route,))[route]

    def _force(self, t):
        """Force of the arm on the mass in B1: m a - m g, gravity (0, 0, -g); only the route it takes is evaluated."""
        names = self.symbols(t)
        a = self._acceleration(names, self._reaction_route)
        return printed.evaluate(self.PRINTED, {**names, "a": a}, ("F",))["F"]

    def reactions(self, t, q, v):
        F = self._force(t)
        return {"F1": float(F[0]), "F2": float(F[1]), "F3": float(F[2])}

    def energy(self, t, q, v):
        """Kinetic + gravity potential of the mass; the mass stays at Z = 0."""
        p = self.p
        vel = self._velocity_inertial(t)
        height = 0.0  # I L = (L cos, L sin, 0)
        return float(0.5 * p["m"] * vel @ vel + p["m"] * p["g"] * height)

    def drive_power(self, t, q, v):
        """Power of the arm on the mass, F . v (F from B1 to I by T^T)."""
        T = T_z(self._motion(t)[0])
        return float((T.T @ self._force(t)) @ self._velocity_inertial(t))

    def printed_rows(self, t, q, v, acc, reactions):
        """(1.23) and (1.24), X and Y in I, term by term as printed, each times m against the arm's force.

        1.7 prints no Newton row: Examples 3-4 stop at the acceleration.  Its two printed accelerations
        are put to the engine through Newton's law for the mass, m I a_B = I F + m I g, with I F = T^T
        (F1, F2, F3) the arm's force that the engine measures (X = cos F1 - sin F2, Y = sin F1 + cos F2);
        gravity has no X or Y component.  The Z rows are left out: the book prints 0 there, and F3 = m g
        is this project's (1.7 never mentions gravity).  The four terms of Example 4 are those of (1.23)
        one by one, so they add no row of their own; (1.24) Y carries its printed 2 L' theta' sin(theta)
        (finding 1.7-eq1.24)."""
        th, w, wd, L, Ld, Ldd = self._motion(t)
        m, s, c = self.p["m"], np.sin(th), np.cos(th)
        force_x = [-c * reactions["F1"], s * reactions["F2"]]
        force_y = [-s * reactions["F1"], -c * reactions["F2"]]
        # (1.23) = (1.20) collected, and (1.24) whose X row is the same
        x = [m * Ldd * c, -2 * m * Ld * w * s, -m * L * wd * s, -m * L * w**2 * c, *force_x]
        return {"(1.23) X": x,
                "(1.23) Y": [m * Ldd * s, 2 * m * Ld * w * c, m * L * wd * c, -m * L * w**2 * s, *force_y],
                "(1.24) X": x,
                "(1.24) Y": [m * Ldd * s, 2 * m * Ld * w * s, m * L * wd * c, -m * L * w**2 * s, *force_y]}


class Reference(Book):
    """Right: (1.24) replaced by the vector sum of the five terms of (1.10); the rest is the book's."""

    def _acceleration(self, names, route):
        """a_eq110: I a_B = I a_A + I omega' x I L + I omega x (I omega x I L) + 2 I omega x I v_Rel + I a_Rel, with
        the book's vectors (c), (d), (1.17), (1.22) (PRINTED), turned into B1; a_d2dt2: the book's (1.23)."""
        if route != "a_eq110":
            return super()._acceleration(names, route)
        book = printed.evaluate(self.PRINTED, names, ("omega", "omega_dot", "r", "v_rel", "a_rel"))
        omega, r = book["omega"], book["r"]
        a_A = np.zeros(3)                     # origin fixed
        # spinning_base.cross: numpy's cross costs more than the rest on 3-vectors, and gives the same numbers
        five_terms = (a_A + np.array(cross(book["omega_dot"], r)) + np.array(cross(omega, cross(omega, r)))
                      + 2 * np.array(cross(omega, book["v_rel"])) + book["a_rel"])
        return T_z(names["th"]) @ five_terms
