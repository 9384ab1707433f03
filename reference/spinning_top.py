"""Section 1.10: heavy symmetric top on the floor, tip O fixed (no slip), Euler angles.

Names.  The book writes varphi for the precession, theta for the nutation and phi for the spin;
its Pascal listing calls them psi, teta and phi.  Here (the case file's coords): precession = varphi = psi,
nutation = theta = teta, spin = phi; the velocities are the Euler-angle rates.  Below,
p = precession, n = nutation, s = spin, and ', '' are time derivatives.

Frames (book 1.10 (1)-(2)).  I = (X, Y, Z), Z up, gravity -Z.  B1 = T_z(p) I, B2 = T_x(n) B1 with
T_z(a) = [[c, s, 0], [-s, c, 0], [0, 0, 1]], T_x(a) = [[1, 0, 0], [0, c, s], [0, -s, c]]
(components: B2 x = T_x(n) T_z(p) I x).  The top turns by s about Z2 relative to B2, so its
orientation (world from body) is Rz(p) Rx(n) Rz(s) with the usual right-handed rotations
Rz = T_z^T, Rx = T_x^T.  The tip O is the origin of I and of B2; the centre of mass sits on the
spin axis, B2 r_O,CM = (0, 0, h).  For the symmetric top the inertia tensor about O is constant
in B2: I_O = diag(Ixx, Iyy, Izz), Iyy = Ixx (the book's (9): Ixx = CM_Ixx + m h^2,
Izz = CM_Izz).

Kinematics, the book's (3)-(7), all in B2 (these printed lines are right):

    Omega = (n', p' sin n, p' cos n)                       angular velocity of B2      (3)
    omega = (n', p' sin n, p' cos n + s')                  angular velocity of the top (4)
    v     = Omega x r = h (p' sin n, -n', 0)                                           (6)
    a     = Omega' x r + Omega x (Omega x r)
          = h (p'' sin n + 2 p' n' cos n,  p'^2 sin n cos n - n'',  -(n'^2 + p'^2 sin^2 n))   (7)

(The centre of mass is fixed in B2, not only in the top, so Omega carries it: the spin does not
move it.)

Euler about the fixed point O, the book's (10): M_O = I_O d(omega)/dt|_B2 + Omega x (I_O omega), with
B2 M_O = r x P + (0, 0, Mz) = (m g h sin n, 0, Mz) (weight B2 P = T_x(n) (0, 0, -m g)
= (0, -m g sin n, -m g cos n); the floor's force acts at O and has no moment about it):

    X2:  m g h sin n = Ixx n'' + p'^2 (Izz - Iyy) sin n cos n + Izz s' p' sin n
    Y2:  0           = Iyy (p'' sin n + p' n' cos n) + p' n' (Ixx - Izz) cos n - Izz s' n'
    Z2:  Mz          = Izz (p'' cos n - p' n' sin n + s'') + p' n' (Iyy - Ixx) sin n

The book prints them with CM inertias (p. 81) and solves them for the three accelerations;
`Book.accelerations` is that printed solution, with CM_Ixx = CM_Iyy = Ixx - m h^2 and
CM_Izz = Izz from the parameters:

    precession  p'' = n' / (sin n (CM_Ixx + m h^2)) [ s' CM_Izz
                          + p' cos n (CM_Izz - CM_Ixx - CM_Iyy - 2 m h^2) ]
    nutation    n'' = sin n / (CM_Ixx + m h^2) { m g h
                          + p' [ -CM_Izz s' + p' cos n (CM_Iyy - CM_Izz + m h^2) ] }
    spin        s'' = n' / (tan n (CM_Iyy + m h^2)) [ -CM_Izz s'
                          + p' cos n (CM_Ixx + CM_Iyy - CM_Izz + 2 m h^2) ]
                      + 1/CM_Izz [ Mz + p' n' sin n (CM_Ixx - CM_Iyy + CM_Izz) ]

Lost signs, restored term by term (the extraction keeps '+' and loses '-'):
- precession: the '+' between the bracket's terms survives; the three minus signs inside
  (CM_Izz - CM_Ixx - CM_Iyy - 2 m h^2) come from the book's own Y2 row (p. 81, whose bracket
  prints [CM_Ixx - CM_Izz + CM_Iyy + 2 m h^2] with its '+' signs) and from the listing,
  DDpsi := (Izz Dpsi Dteta cos + Dpsi Dteta cos (-Ixx - Iyy) + Izz Dphi Dteta) / (Iyy sin).
- nutation: -CM_Izz s' from the listing's `-izz*dphi*dpsi*sin(teta)` and the X2 row
  (Omega x I omega)_x = p'^2 (Izz - Iyy) sin cos + Izz s' p' sin moved to the right-hand side;
  (CM_Iyy - CM_Izz + m h^2) from the listing's `(-Izz+Iyy)`.
- spin: the leading -CM_Izz s' and the -CM_Izz inside follow from substituting the precession
  equation into the Z2 row, s'' = Mz/Izz + p' n' sin n + p' n' (Ixx - Iyy) sin n / Izz - p'' cos n,
  which is the listing's DDphi := (1/Izz)(-Izz DDpsi cos + Izz Dpsi Dteta sin
  + Dpsi Dteta (-Iyy + Ixx) sin + Mz); the visible '+' between CM_Ixx and CM_Iyy and before
  2 m h^2 leave no other reading.  (CM_Ixx - CM_Iyy + CM_Izz) from the Z2 row (p. 81,
  [CM_Iyy - CM_Ixx - CM_Izz] for p' n' sin n on the left-hand side).
The X2 row prints p'[s' CM_Izz sin n + (p'/2) sin 2n (...)] (= p'^2 sin n cos n (...)).  The Y2
row's first term shows the precession glyph where the spin rate belongs (-n' s' CM_Izz; the book's
p. 80 product Omega x (I omega) and its final precession equation have the spin): a slip of the
printed row only, which `Book.printed_rows` keeps (finding 1.10-euler-Y2).  The precession equation
divides by CM_Ixx + m h^2 where the Y2 row has CM_Iyy + m h^2: equal for the symmetric top.  The
equations of motion are right: `Reference` keeps them.

Reactions, Newton (the book's (10)): B2 R + B2 P = m B2 a, R = (Rx, Ry, Rz) in I, so
B2 R = T_x(n) T_z(p) I R and

    I R = T_z(p)^T T_x(n)^T F,   F = m a - B2 P = ( m a_x,  m g sin n + m a_y,  m g cos n + m a_z ).

The book prints exactly this line (p. 81, "R = T^T_varphi T^T_theta {...}"), with a from (7).
With Fx, Fy, Fz the components of F and c, s of the angles:

    Rx = cos p Fx - sin p (cos n Fy - sin n Fz)
    Ry = sin p Fx + cos p (cos n Fy - sin n Fz)
    Rz =                   sin n Fy + cos n Fz

What the book prints after "handling the equations" (p. 82), signs restored:

    Rx = cos p [F1] + sin p [-F2]
    Ry = cos n sin p [F1] + cos n cos p [F2] + sin n [-F3]
    Rz = sin n sin p [F1] + sin n cos p [F2] - cos n [-F3]

    F1 = m n' h (p' cos n + s') + m h (p'' sin n + p' n' cos n)
    F2 = m g sin n + m p' h sin n (p' cos n + s') - m h n''
    F3 = m g cos n - m h (n'^2 + p'^2 sin^2 n)

Signs: every '+' above is printed; the lost minus signs are those of B2 P = (0, -m g sin n,
-m g cos n) (p. 80) and of (7) (-m h n'' in a_y, -(n'^2 + p'^2 sin^2 n) in a_z): F2 and F3 are
the book's F_y and F_z, and the Rx bracket [ m g sin n  m p' h sin n (...) + m h n''] and the
brackets [ m g cos n + m h (n'^2 + p'^2 sin^2 n)] of Ry and Rz print exactly one visible '+'
each, which fixes them as -F2 and -F3; the lost sign before cos n in Rz is the minus that makes
Rz = m g for the top at rest upright.  These signs reproduce every printed '+', and no listing
line computes R (the program never evaluates the reactions).

Two errors, both in the printed reactions only (finding 1.10-R):

1. The spin in the transport term.  F1 and F2 contain (p' cos n + s') = omega_z where (7) has
   Omega_z = p' cos n: the book formed omega x v instead of Omega x v.  omega x v
   = h ((p' cos n + s') n', (p' cos n + s') p' sin n, -(n'^2 + p'^2 sin^2 n)), term by term the
   book's brackets.  The centre of mass is fixed in B2, so its velocity v = Omega x r is turned
   by Omega, not by the top's omega: the spin moves mass around the axis but not the centre of
   mass.  Right: F1 -> Fx = m h (p'' sin n + 2 p' n' cos n), F2 -> Fy = m g sin n
   + m h (p'^2 sin n cos n - n''); the book's F1 - Fx = m h n' s', F2 - Fy = m h p' s' sin n.
   With the book's case (a) (s' = 44 rad/s, p' = 7 rad/s, n = 30 deg) m h p' s' sin n is 5.0 N,
   against m g = 5.7 N.
2. The order of the rotations back to I.  The printed rows are those of T_x(n)^T T_z(p)^T,
   i.e. (T_z(p) T_x(n))^T, not of T_z(p)^T T_x(n)^T = (T_x(n) T_z(p))^T that the book's own
   previous line writes: e.g. Rx = cos p F1 - sin p F2 has no F3 and no cos n, whereas
   Rx = cos p Fx - sin p cos n Fy + sin p sin n Fz.  The two products agree only at p = 0 (or
   n = 0); in case (a) the precession makes 1.8 turns before the disk touches the floor.

Sizes (against MuJoCo and Pinocchio, which agree with `Reference` to 2e-15): over 100 random
states the book's Rx, Ry, Rz are off by 3.0, 2.6, 2.0 times the largest right reaction, error 1
alone 1.0, 1.0, 1.1 and error 2 alone 1.8, 1.6, 1.3.  Along case (a) the book's components are off
by up to 7.6, 8.3, 7.8 N where the right ones stay below 2.47, 2.45, 6.67 N; the book's Rz even
turns negative (-1.56 N), a floor that pulls.

`Reference.reactions` uses Fx, Fy, Fz and the book's own T_z^T T_x^T.  `Book.reactions` keeps
both errors; `Book._transport_rate` and `Book._to_inertial` isolate them.

Energy (not printed by the book; from its (4) and (9)): E = 1/2 omega . I_O omega + m g h cos n
= 1/2 [Ixx n'^2 + Iyy p'^2 sin^2 n + Izz (p' cos n + s')^2] + m g h cos n (potential zero at
the floor).  Drive power: the resisting moment Mz acts on the top about Z2 (= the top's own z
axis), P = Mz omega_z = Mz (p' cos n + s'); the floor force does no work at the fixed tip.  Then
dE/dt = P, which the accelerations above satisfy identically.

The book's data against its own formulas (parameters of case.toml, zeros restored):
- Inertias.  (9) with m = 0.582 kg, r = 0.05 m, l = 0.0215 m, h = 0.0558 m gives
  CM_Ixx = m r^2/4 + m l^2/12 = 3.862e-4, Ixx = CM_Ixx + m h^2 = 2.198e-3 and Izz = m r^2/2
  = 7.275e-4 kg m^2.  The listing prints Ixx = Iyy = 2.9393e-3 (1.34 times) and Izz = 2.258e-3
  (3.10 times).  Both printed values correspond to a disk of radius about 0.088 m (Izz = m r^2/2
  gives r = 0.0881 m; Ixx gives 0.0871 m), not the 0.05 m of the stop test; the printed Ixx
  matches Izz/2 + m h^2 = 2.9411e-3, the thin-disk value without the m l^2/12 term, to 0.06 %.
- Realisability.  CM_Ixx = Ixx - m h^2 = 1.12716e-3, and CM_Ixx + CM_Iyy = 2.25432e-3 is less
  than CM_Izz = 2.258e-3 by 3.68e-6 kg m^2 (0.16 %): the printed pair breaks the triangle
  inequality A + B >= C that every mass distribution satisfies, so no rigid body has these
  inertias (MuJoCo's compiler refuses them; scene.xml carries the excess as an isotropic
  armature of the ball joint).  The equations of motion do not care: they use I_O only.
- Stop constant.  The listing stops when teta > pi/2 - arctan(r/0.0442), i.e.
  tan(n) > 0.0442/r, n > 41.48 deg: the rim of a disk face at 0.0442 m from O along the axis
  reaches the floor (0.0442 cos n - r sin n < 0).  The disk's lower face of the book's model is at
  h - l/2 = 0.04505 m (stop at 42.02 deg); 0.0442 puts the disk's mid-plane at 0.05495 m, 0.85 mm
  below the centre of mass (plausible for a real top whose stem raises the centre of mass), or
  is a rounded measurement.  The difference moves the stop by 0.54 deg of nutation.

The Pascal listing (pp. 83-85, `program top`) and `Program`.  Names: the listing's psi is the
precession (hx := h*sin(teta)*sin(psi), hy := -h*sin(teta)*cos(psi): Rz(psi) Rx(teta) (0, 0, h),
the centre of mass of the module's frames exactly), teta the nutation and phi the spin (DDphi
carries Mz/Izz; files arqpsi, arqteta, arqphi).  Beware: the listing's phi is the book's spin,
not the book's varphi, which is the precession.

- Equations.  The loop computes, in this order, from the state before the step:
      DDteta := (1/Ixx)*(mp*g*h*sin(teta)+Sqr(Dpsi)*(-Izz+Iyy)*sin(teta)*cos(teta)-izz*dphi*dpsi*sin(teta))
      DDpsi  := (1/(Iyy*sin(teta)))*(Izz*Dpsi*Dteta*cos(teta)+Dpsi*Dteta*cos(teta)*(-Ixx-Iyy)+Izz*Dphi*Dteta)
      DDphi  := (1/Izz)*(-Izz*DDpsi*cos(teta)+Izz*Dpsi*Dteta*sin(teta)+Dpsi*Dteta*(-Iyy+Ixx)*sin(teta)+Mz)
  (ASCII minus signs survive; Pascal is case-insensitive, so izz, dphi, dpsi are Izz, Dphi,
  Dpsi).  These are the X2, Y2 and Z2 rows above solved one at a time, DDphi with the DDpsi just
  computed from the same state (no lag).  They equal the displayed equations of p. 81, and
  `Book`/`Reference`, identically: the precession line divides by Iyy where p. 81 has
  CM_Ixx + m h^2 (equal for the symmetric top), and substituting DDpsi into DDphi gives the
  printed spin equation term by term.  `Book` transcribes p. 81's closed forms, not these lines,
  so `Program` carries its own transcription (`Program._listing`).  Over the case's 100 sample
  states the two agree to rounding: largest difference 1.9e-16, 2.2e-16, 4.0e-16 of the largest
  acceleration (precession, nutation, spin), 25-42 of 100 bitwise equal; the largest pointwise
  relative difference, 1.3e-14 in the spin, is at a state where -DDpsi cos(teta) = 11.64 and
  Mz/Izz = -11.07 cancel to 0.395 rad/s^2.
- Integrator.  Per step: t := t + deltat; the three accelerations; Dpsi, Dphi, Dteta :=
  old + deltat * DD; psi, phi, teta := old + deltat * the new rates; hx, hy, hz from the new
  angles; write; stop test.  That is the semi-implicit Euler of `dyncheck.run.simulate`
  ("semi-implicit Euler"): along case (a) the listing and Reference's
  accelerations in that scheme at the same step differ by at most 1.6e-13 rad (spin) and 5.4e-13
  rad/s over all 7151 steps.  The accelerations depend on the rates (gyroscopic terms), so the
  scheme is not symplectic here and is only first order: against DOP853 at rtol 1e-12 the
  listing's case (a) is off by up to 0.18 rad (10.6 deg) in precession, 0.048 rad (2.7 deg) in
  nutation, 0.22 rad (12.4 deg) in spin and 1.3, 0.43, 1.2 rad/s in the rates; it touches at
  2.3837 s (step 7151) where the tight solution touches at 2.3948 s; its work-energy residual
  E - E0 - W (Reference.energy, W by Simpson's rule on Mz (p' cos n + s') along the run) reaches
  3.1e-3 J against E0 = 3.12 J, W = -2.195 J (the tight solution's: 3e-14 J).  At a tenth of the
  step the angle errors and the residual shrink twelvefold (0.016 rad, 2.6e-4 J) and the touch
  moves to 2.3941 s.  At a spin of 40*2*pi rad/s (fast nutation near Izz s'/Ixx = 193 rad/s,
  0.064 rad a step; the default start otherwise) the scheme grows without bound within 1 s where
  the true nutation stays within 10-10.07 deg.
- Outputs.  The files get t with psi, phi, teta, Dpsi, Dphi, Dteta and hz, and (hx, hy), once
  for the initial conditions and once per step; `run` returns them as the case's columns plus hx,
  hy, hz, indexed by the listing's accumulated t (2e-13 s from i*deltat at the touch).  The
  screen line ddpsi, ddteta, ddphi is not kept.  The listing computes no reaction, energy or
  power, and never the no-slip test: the errors of the printed reactions (finding 1.10-R) do not
  reach its results.  Turbo Pascal's `real` has a 40-bit mantissa (about 2e-12); `Program` uses
  doubles.
- Zeros restored in the listing's own numbers (the top's m, h, Ixx = Iyy, Izz, r, Mz come from
  the case's [params], its initial values from [initial]; 3.14159 there has no zero to lose; the
  stop test's PI is Pascal's built-in pi, no literal).  Evidence from replaying the loop against
  the text ("the disk touches the floor after 2,5 [s]") and the case (a) figures (height of the
  centre of mass: ticks .41 ... .51 -> 0.041-0.051 m over t = 0 ... 3 s in steps of 0.5; XY path:
  ticks -.4 ... .4 -> -0.04 ... 0.04 m on both axes):
  * `t :.;` -> t := 0.0 (`0.` with its zero lost).
  * `tempo : 1;` -> 10 s.  The loop covers tempo (n - 1)/n s at most: with tempo = 1 it ends at
    1 s, short of the touch at about 2.4 s that text and figure need.  10 is the smallest reading
    that reaches the touch.
  * `n : 3;`, `a : 1;` -> n = 30000, a = 1, deltat := (tempo/a)/n = 1/3000 s (a restores the
    zeros of a*n together).  deltat = 1/300 (n = 3000 with a = 1, or tempo 100 with n = 30000)
    touches at 0.83 s with the centre of mass up to 0.0539 m: outside text and figure.
    deltat = 1/3000 touches at 2.3837 s, height 0.04178-0.05189 m, |hx| <= 0.0369,
    |hy| <= 0.0303 m; deltat = 1/30000 (n = 30000, a = 10) touches at 2.3941 s, height
    0.04180-0.05149 m.  The figures cannot tell these two apart (both top out above the 0.051 m
    tick; see below), so the choice of 1/3000 is the simplest reading (one repetition, "number of
    points" 30000, within Turbo Pascal's 16-bit integer, which rules out n = 300000 but not
    a = 10): medium-to-weak evidence.  (a = 10, n = 3000) is the same step and the same run to
    the touch (7151 identical steps); only an untouched run would end at 9.9967 s, not 9.99967 s.
  * `fim : 1;`, `fim:;`, `if fim < > then` -> fim := 1, fim := 0, fim <> 0: only whether the
    files are closed once more; no number depends on it.
  * `arctan(r/.442)` -> 0.0442 (see "Stop constant").  0.442 stops at 83.5 deg of nutation, at
    3.09 s, with the centre of mass down to 0.006 m and |hy| up to 0.055 m (outside both
    figures); 0.00442 stops at 5.05 deg, i.e. after the first step of any start above it (case
    (a) starts at 30 deg, the default at 10 deg); 0.0442 stops at 41.48 deg, where the height is
    h cos = 0.0418 m, just above the figure's lowest tick 0.041 m.
  * `for j:1 to a`, `for i:2 to n`, and every `:` for `:=`, lose no digit.  The stop block sets
    j := a; i := n (Turbo Pascal lets a for loop's body assign its counter): the run ends on the
    step whose row the test first finds past the angle, after that row is written.
- Case (a) against the figures.  XY: the listing's path stays within |hx| <= 0.0369,
  |hy| <= 0.0303 m, the tight solution's within 0.0353, 0.0298 m: inside +-0.04 m.  Height: the
  lowest point, at the stop, is 0.04178 m (listing) and 0.04181 m (tight), inside; the highest is
  0.05189 m (listing, at each nutation minimum from t = 0.075 s on, rising from 0.05134 to
  0.05189 m) and 0.05146 m (tight, 0.05132-0.05146 m): above the 0.051 m tick by 0.9 and 0.46 mm.
  Time: both stop before the 2.5 s tick, where the text says "after 2,5 [s]" and the axis runs
  to 3 s.  Either the figure's axes were set by hand (the XY figure's y axis runs to +0.04 m where
  every run stays below +0.030 m) or the book's run is not exactly these parameters; the
  listing's own integrator does not explain the gap (its step moves the top by 0.4 mm and the
  touch by 11 ms, in the wrong direction for the height).
- The default run in the listing (nutation (5/180)*2*3.14159 = 10 deg, precession rate 0, spin
  4*2*3.14159 rad/s, Mz = -0.01 N m per the README, low confidence): the spin, 25.1 rad/s, is
  below the sleeping-top limit 2 sqrt(Ixx m g h)/Izz = 27.1 rad/s and the top falls at once: the
  listing touches at 0.3133 s (940 steps; nutation 10 -> 41.5 deg, precession to 1.96 rad,
  precession rate to 9.97 rad/s, spin rate 25.13 -> 16.22 rad/s, height 0.0550 -> 0.0418 m,
  |hx| <= 0.0343, |hy| <= 0.0160 m), the tight solution at 0.31366 s (angles within 2.3e-3 rad
  of the listing's; work-energy residual of the listing 2.5e-4 J against E0 = 1.027 J).  With
  Mz = -0.1 it touches at 0.2487 s.  The book shows no figure of it.
"""

import math
import time

import numpy as np

from reference import printed

# The book's T_z and T_x (1.10 (1)-(2)); FRAMES holds them as the expressions T_z and T_x evaluate, for the student's
# page.
from reference.spinning_base import FRAMES, T_x, T_z  # noqa: F401  (FRAMES: the student page shows them)

COORDS = ("precession", "nutation", "spin")
REACTIONS = ("Rx", "Ry", "Rz")
COORD_ACCS = ("precession_acc", "nutation_acc", "spin_acc")
STATE = ("p", "n", "dp", "dn", "ds")  # the printed symbols of the state


class Book:
    """The book's 1.10 equations of motion (p. 81) and reaction components (p. 82) as printed."""

    coords = COORDS
    reaction_names = REACTIONS

    def __init__(self, params):
        self.p = dict(params)
        # The printed expressions as functions of the state, the rest bound once, with math's functions (on one
        # number numpy's cost more and give the same values): an integrator evaluates them at every step.
        self._evaluate = printed.Functions(self.PRINTED, STATE, {**self._constants(), "sin": math.sin, "cos": math.cos,
                                                                 "tan": math.tan})

    # -- inertias ------------------------------------------------------------
    def _cm_inertias(self):
        """CM_Ixx, CM_Iyy, CM_Izz of the book's (9), from the parameters (Ixx, Izz about O)."""
        p = self.p
        shift = p["m"] * p["h"] ** 2
        return p["Ixx"] - shift, p["Ixx"] - shift, p["Izz"]

    # -- model interface -------------------------------------------------------
    def accelerations(self, t, q, v):
        state = printed.floats(q[:2], v)
        return np.array([self._evaluate[key](*state) for key in COORD_ACCS])

    # The transposes of the book's frames (spinning_base.FRAMES), T_z(a)^T and T_x(a)^T, laid out by rows as
    # a matrix built by rows is: numpy's product with a transposed view rounds differently.
    @staticmethod
    def _tz_t(a):
        return T_z(a).T.copy()

    @staticmethod
    def _tx_t(a):
        return T_x(a).T.copy()

    # The printed reaction: the rows are those of T_x(n)^T T_z(p)^T F, F = m a - B2 P in B2 with the
    # top's omega_z = p' cos n + s' in the transport term.  The string is the code (evaluated with
    # `symbols`), so that dyncheck can search edits of it.
    PRINTED = {"R": "TxT(n) @ TzT(p) @ array(["
                    "m*dn*h*(dp*cos(n) + ds) + m*h*(ddp*sin(n) + dp*dn*cos(n)),"
                    " m*g*sin(n) + m*dp*h*sin(n)*(dp*cos(n) + ds) - m*h*ddn,"
                    " m*g*cos(n) - m*h*(dn**2 + dp**2*sin(n)**2)])"}
    # The printed symbols' LaTeX (dyncheck.pages.typeset): the book's varphi, theta, phi; {} takes the argument.
    LATEX = {"p": r"\varphi", "n": r"\theta", "dp": r"\dot{\varphi}", "dn": r"\dot{\theta}", "ds": r"\dot{\phi}",
             "ddp": r"\ddot{\varphi}", "ddn": r"\ddot{\theta}", "dds": r"\ddot{\phi}", "TxT": "T_x({})^T",
             "TzT": "T_z({})^T", "CM_Ixx": "I^{CM}_{xx}", "CM_Iyy": "I^{CM}_{yy}", "CM_Izz": "I^{CM}_{zz}",
             # the case's coordinates by the same letters
             "precession": r"\varphi", "nutation": r"\theta", "spin": r"\phi", "precession_rate": r"\dot{\varphi}",
             "nutation_rate": r"\dot{\theta}", "spin_rate": r"\dot{\phi}"}

    # The top's angular velocity (4) and acceleration (5) as printed in B2, turned into the inertial
    # frame by T_z(p)^T T_x(n)^T to meet the engines (whose body frame spins with the top).
    PRINTED["omega"] = "TzT(p) @ TxT(n) @ array([dn, dp*sin(n), dp*cos(n) + ds])"
    PRINTED["omega_dot"] = ("TzT(p) @ TxT(n) @ array([ddn + dp*ds*sin(n), ddp*sin(n) + dp*dn*cos(n) - dn*ds,"
                            " ddp*cos(n) - dp*dn*sin(n) + dds])")

    def _constants(self):
        """The symbols of the printed expressions that stay constant."""
        p = self.p
        return {"m": p["m"], "g": p["g"], "h": p["h"], "Mz": p["Mz"], "array": np.array, "TxT": self._tx_t,
                "TzT": self._tz_t, **dict(zip(("CM_Ixx", "CM_Iyy", "CM_Izz"), self._cm_inertias()))}

    def _names(self, q, v):
        """The symbols of the printed expressions but the accelerations."""
        return {**self._constants(), **dict(zip(STATE, (q[0], q[1], v[0], v[1], v[2]))), "sin": np.sin, "cos": np.cos,
                "tan": np.tan}

    def symbols(self, t, q, v):
        ddp, ddn, dds = self.accelerations(t, q, v)
        return {**self._names(q, v), "ddp": ddp, "ddn": ddn, "dds": dds}

    # (7), the acceleration of the centre of mass in B2 (lost signs restored from Newton's rows (10)).
    PRINTED["a_CM"] = ("TzT(p) @ TxT(n) @ array([h*(2*dn*dp*cos(n) + ddp*sin(n)), h*(dp**2*cos(n)*sin(n) - ddn),"
                       " -h*(dp**2*sin(n)**2 + dn**2)])")

    # Euler's Y2 row of (10) as printed (p. 81), its right side (its left side is 0), with the precession
    # rate p' in the first term (finding 1.10-euler-Y2; printed_rows has it term by term).
    PRINTED["Euler Y2 (1.10)"] = ("-dn*dp*CM_Izz + dn*dp*cos(n)*(CM_Ixx - CM_Izz + CM_Iyy + 2*m*h**2)"
                                  " + ddp*sin(n)*(CM_Iyy + m*h**2)")

    # The equations of motion as printed (p. 81), solved for the precession, nutation and spin accelerations, lost
    # signs restored (module docstring); `accelerations` evaluates them.
    PRINTED["precession_acc"] = ("dn/(sin(n)*(CM_Ixx + m*h**2))"
                                 "*(ds*CM_Izz + dp*cos(n)*(CM_Izz - CM_Ixx - CM_Iyy - 2*m*h**2))")
    PRINTED["nutation_acc"] = ("sin(n)/(CM_Ixx + m*h**2)"
                               "*(m*g*h + dp*(-CM_Izz*ds + dp*cos(n)*(CM_Iyy - CM_Izz + m*h**2)))")
    PRINTED["spin_acc"] = ("dn/(tan(n)*(CM_Iyy + m*h**2))"
                           "*(-CM_Izz*ds + dp*cos(n)*(CM_Ixx + CM_Iyy - CM_Izz + 2*m*h**2))"
                           " + (Mz + dp*dn*sin(n)*(CM_Ixx - CM_Iyy + CM_Izz))/CM_Izz")

    def point_accelerations(self, t, q, v):
        names = self.symbols(t, np.asarray(q, float), np.asarray(v, float))
        return printed.evaluate(self.PRINTED, names, ("omega", "omega_dot", "a_CM"))

    def reactions(self, t, q, v):
        r = printed.evaluate(self.PRINTED, self.symbols(t, np.asarray(q, float), np.asarray(v, float)), ("R",))["R"]
        return {"Rx": float(r[0]), "Ry": float(r[1]), "Rz": float(r[2])}

    def energy(self, t, q, v):
        """1/2 omega . I_O omega + m g h cos n, from the book's (4) and (9)."""
        p = self.p
        n = q[1]
        dp, dn, ds = v
        sn, cn = np.sin(n), np.cos(n)
        kinetic = 0.5 * (p["Ixx"] * dn**2 + p["Ixx"] * (dp * sn) ** 2 + p["Izz"] * (dp * cn + ds) ** 2)
        return kinetic + p["m"] * p["g"] * p["h"] * cn

    def drive_power(self, t, q, v):
        """Power of the moment Mz about Z2: Mz omega_z = Mz (p' cos n + s')."""
        return self.p["Mz"] * (v[0] * np.cos(q[1]) + v[2])

    def printed_rows(self, t, q, v, acc, reactions):
        """(10) as printed on p. 81 before it is solved, in B2, each row left side minus right side.

        Newton, "T_theta T_varphi R = (0, m g sin n, m g cos n) + m h (2 n' p' cos n + p'' sin n,
        p'^2 cos n sin n - n'', -p'^2 sin^2 n - n'^2)": R in I is turned into B2 by T_x(n) T_z(p), the
        order the book writes; the acceleration is (7), with Omega.  (Its errors, finding 1.10-R, come
        after, in the components of p. 82.)

        Euler, with the CM inertias of (9) (CM_Iyy = CM_Ixx = Ixx - m h^2, CM_Izz = Izz):
            X2:  m g h sin n = p' [s' CM_Izz sin n + (p'/2) sin 2n (CM_Izz - CM_Iyy - m h^2)]
                               + n'' (CM_Ixx + m h^2)
            Y2:  0           = -n' p' CM_Izz + n' p' cos n [CM_Ixx - CM_Izz + CM_Iyy + 2 m h^2]
                               + p'' sin n (CM_Iyy + m h^2)
            Z2:  Mz          = p' n' sin n [CM_Iyy - CM_Ixx - CM_Izz] + (p'' cos n + s'') CM_Izz
        Signs as restored in the module docstring; Y2's first term as printed, with the precession rate
        p' where its own p. 80 product Omega x (I_O omega) and the precession equation solved from it
        have the spin rate s' (finding 1.10-euler-Y2); -n' s' CM_Izz there, from p. 80."""
        p = self.p
        m, g, h = p["m"], p["g"], p["h"]
        (prec, n, _), (dp, dn, ds), (ddp, ddn, dds) = q, v, acc
        cxx, cyy, czz = self._cm_inertias()
        mh2 = m * h**2
        sn, cn, sp, cp = np.sin(n), np.cos(n), np.sin(prec), np.cos(prec)
        rx, ry, rz = reactions["Rx"], reactions["Ry"], reactions["Rz"]
        # T_x(n) T_z(p) (Rx, Ry, Rz), term by term
        return {"Newton X2 (1.10)": [cp * rx, sp * ry, -m * h * 2 * dn * dp * cn, -m * h * ddp * sn],
                "Newton Y2 (1.10)": [-cn * sp * rx, cn * cp * ry, sn * rz, -m * g * sn, -m * h * dp**2 * cn * sn,
                                     m * h * ddn],
                "Newton Z2 (1.10)": [sn * sp * rx, -sn * cp * ry, cn * rz, -m * g * cn, m * h * dp**2 * sn**2,
                                     m * h * dn**2],
                "Euler X2 (1.10)": [m * g * h * sn, -dp * ds * czz * sn,
                                    -dp * (dp / 2) * np.sin(2 * n) * (czz - cyy - mh2), -ddn * (cxx + mh2)],
                "Euler Y2 (1.10)": [dn * dp * czz, -dn * dp * cn * (cxx - czz + cyy + 2 * mh2),
                                    -ddp * sn * (cyy + mh2)],
                "Euler Z2 (1.10)": [p["Mz"], -dp * dn * sn * (cyy - cxx - czz), -ddp * cn * czz, -dds * czz]}


class Reference(Book):
    """The book's equations of motion; reactions with Omega in (7) and T_z^T T_x^T (finding 1.10-R)."""

    def _transport_rate(self, q, v):
        """Omega_z = p' cos n: the centre of mass is carried by B2, the spin does not move it."""
        return v[0] * np.cos(q[1])

    def _newton(self, q, v, acc):
        """F = m a - B2 P in B2, from the acceleration (7) of the centre of mass."""
        p = self.p
        m, h, g = p["m"], p["h"], p["g"]
        n = q[1]
        dp, dn, _ = v
        p_acc, n_acc, _ = acc
        sn, cn = np.sin(n), np.cos(n)
        wz = self._transport_rate(q, v)
        f1 = m * dn * h * wz + m * h * (p_acc * sn + dp * dn * cn)
        f2 = m * g * sn + m * dp * h * sn * wz - m * h * n_acc
        f3 = m * g * cn - m * h * (dn**2 + dp**2 * sn**2)
        return np.array([f1, f2, f3])

    def reactions(self, t, q, v):
        q, v = np.asarray(q, float), np.asarray(v, float)
        force = self._newton(q, v, self.accelerations(t, q, v))
        r = self._tz_t(q[0]) @ (self._tx_t(q[1]) @ force)  # T_z(p)^T T_x(n)^T, the book's own line
        return {"Rx": float(r[0]), "Ry": float(r[1]), "Rz": float(r[2])}


class Program:
    """The 1.10 Pascal listing `program top` (pp. 83-85) transcribed line by line.

    The listing's psi, teta, phi are the precession, nutation and spin (see the module docstring,
    "The Pascal listing").  Its DDteta, DDpsi, DDphi lines are the Euler rows solved one by one, in
    that order, DDphi with the DDpsi just computed; its loop is a semi-implicit Euler at
    deltat = (tempo/a)/n = 1/3000 s that stops when "THE DISK TOUCHED THE FLOOR".  Its own numbers
    (tempo, n, a, the stop constant 0.0442) are the listing's literals with their zeros restored;
    the top (m, g, h, Ixx = Iyy, Izz, Mz, r) comes from the case's parameters, so overrides apply;
    the initial conditions come in through `run(q0, v0)`.  Plain Python floats (IEEE doubles; the
    original ran in Turbo Pascal's 6-byte `real`, 40-bit mantissa, about 12 digits).
    """

    coords = COORDS
    reaction_names = ()            # no listing line computes the floor's reaction
    integrator = "semi-implicit Euler"
    # The listing's own numbers, zeros restored (evidence in the module docstring).
    tempo = 10.0                   # tempo := 10;      {total time [s]}           printed `tempo : 1;`
    n = 30000                      # n := 30000;       {number of points}         printed `n : 3;`
    a = 1                          # a := 1;           {repetition of the ...}    printed `a : 1;`
    dt = (tempo / a) / n           # deltat := (tempo/a)/n;  = 1/3000 s
    steps = a * (n - 1)            # for j := 1 to a do for i := 2 to n do: 29999 steps at most
    stop_constant = 0.0442         # arctan(r/0.0442)                             printed `arctan(r/.442)`
    message = "THE DISK TOUCHED THE FLOOR"

    def __init__(self, params):
        self.p = dict(params)

    # -- the listing's three acceleration lines ----------------------------------------------
    def _listing(self, teta, Dpsi, Dteta, Dphi):
        """DDteta, DDpsi, DDphi as the listing computes them, in its order (plain floats).

        Pascal is case-insensitive (`izz*dphi*dpsi` is Izz*Dphi*Dpsi); `Sqr(x)` is x*x; Pascal and
        Python both evaluate * and / left to right, so the operations are the listing's own.
        """
        p = self.p
        mp, g, h, Ixx, Izz, Mz = p["m"], p["g"], p["h"], p["Ixx"], p["Izz"], p["Mz"]
        Iyy = Ixx                  # Iyy := .29393, the same literal as Ixx (DESIGN: Ixx = Iyy)
        # DDteta := (1/Ixx)*(mp*g*h*sin(teta)+Sqr(Dpsi)*(-Izz+Iyy)*sin(teta)*cos(teta)
        #           -izz*dphi*dpsi*sin(teta));
        DDteta = (1 / Ixx) * (mp * g * h * math.sin(teta) + (Dpsi * Dpsi) * (-Izz + Iyy) * math.sin(teta)
                              * math.cos(teta) - Izz * Dphi * Dpsi * math.sin(teta))
        # DDpsi := (1/(Iyy*sin(teta)))*(Izz*Dpsi*Dteta*cos(teta)+
        #          Dpsi*Dteta*cos(teta)*(-Ixx-Iyy)+Izz*Dphi*Dteta);
        DDpsi = (1 / (Iyy * math.sin(teta))) * (Izz * Dpsi * Dteta * math.cos(teta)
                                                + Dpsi * Dteta * math.cos(teta) * (-Ixx - Iyy) + Izz * Dphi * Dteta)
        # DDphi := (1/Izz)*(-Izz*DDpsi*cos(teta)+Izz*Dpsi*Dteta*sin(teta)+
        #          Dpsi*Dteta*(-Iyy+Ixx)*sin(teta)+Mz);
        DDphi = (1 / Izz) * (-Izz * DDpsi * math.cos(teta) + Izz * Dpsi * Dteta * math.sin(teta)
                             + Dpsi * Dteta * (-Iyy + Ixx) * math.sin(teta) + Mz)
        return DDteta, DDpsi, DDphi

    # -- model interface ----------------------------------------------------------------------
    def accelerations(self, t, q, v):
        """(DDpsi, DDteta, DDphi) at the state, in the order of `coords`; t is not used."""
        _, teta, _ = (float(x) for x in q)
        Dpsi, Dteta, Dphi = (float(x) for x in v)
        DDteta, DDpsi, DDphi = self._listing(teta, Dpsi, Dteta, Dphi)
        return np.array([DDpsi, DDteta, DDphi])

    def reactions(self, t, q, v):
        return {}

    def energy(self, t, q, v):
        raise NotImplementedError("the 1.10 listing computes no energy")

    def drive_power(self, t, q, v):
        raise NotImplementedError("the 1.10 listing computes no power")

    @property
    def stop_nutation(self):
        """The stop test's angle: teta > (PI/2) - arctan(r/0.0442) (Pascal's PI is the exact pi)."""
        return math.pi / 2 - math.atan(self.p["r"] / self.stop_constant)

    # -- the listing's loop -------------------------------------------------------------------
    def run(self, q0, v0):
        """The listing's run from (psi, teta, phi) = q0, (Dpsi, Dteta, Dphi) = v0.

        A DataFrame indexed by the listing's t (accumulated, t := t + deltat), one row for the
        initial conditions and one per step, as its files get them: `precession`, `nutation`,
        `spin` (arqpsi, arqteta, arqphi), their `_rate`s (arqdpsi, arqdteta, arqdphi) and the
        centre of mass hx, hy (arqh) and hz (arqhz).  The run ends after the row on which the stop
        test first holds (the listing writes that row, then sets j := a; i := n) or after
        a (n - 1) steps.  attrs: method, dt, steps (taken), evaluations, wall, touched (t of the
        stop, or None), message.
        """
        import pandas as pd       # only here: the equations above need numpy alone

        start = time.perf_counter()
        h = self.p["h"]
        stop = self.stop_nutation
        psi, teta, phi = (float(x) for x in q0)
        Dpsi, Dteta, Dphi = (float(x) for x in v0)
        sin, cos = math.sin, math.cos
        # t := 0; deltat := (tempo/a)/n;
        t = 0.0
        deltat = (self.tempo / self.a) / self.n
        # hx := h*sin(teta)*sin(psi); hy := -h*sin(teta)*cos(psi); hz := h*cos(teta);
        hx, hy, hz = h * sin(teta) * sin(psi), -h * sin(teta) * cos(psi), h * cos(teta)
        rows = [(t, psi, teta, phi, Dpsi, Dteta, Dphi, hx, hy, hz)]   # the initial conditions
        touched = None
        for j in range(1, self.a + 1):                     # for j := 1 to a do
            for i in range(2, self.n + 1):                 # for i := 2 to n do
                t = t + deltat
                DDteta, DDpsi, DDphi = self._listing(teta, Dpsi, Dteta, Dphi)
                # the angular velocities, then the angles with the new velocities
                Dpsi = Dpsi + deltat * DDpsi
                Dphi = Dphi + deltat * DDphi
                Dteta = Dteta + deltat * DDteta
                psi = psi + deltat * Dpsi
                phi = phi + deltat * Dphi
                teta = teta + deltat * Dteta
                hx = h * sin(teta) * sin(psi)
                hy = -h * sin(teta) * cos(psi)
                hz = h * cos(teta)
                rows.append((t, psi, teta, phi, Dpsi, Dteta, Dphi, hx, hy, hz))
                # if teta > (PI/2) - arctan(r/0.0442) then ... j := a; i := n; fim := 0
                if teta > stop:
                    touched = t
                    break
            if touched is not None:
                break
        wall = time.perf_counter() - start
        data = np.array(rows)
        names = ("precession", "nutation", "spin", "precession_rate", "nutation_rate", "spin_rate",
                 "hx", "hy", "hz")
        frame = pd.DataFrame(data[:, 1:], columns=names, index=pd.Index(data[:, 0], name="t"))
        frame.attrs.update({"method": "program", "integrator": self.integrator, "rtol": None, "dt": deltat,
                            "steps": len(rows) - 1, "evaluations": len(rows) - 1, "wall": wall,
                            "touched": touched, "message": self.message if touched is not None else None})
        return frame
