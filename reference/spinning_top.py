"""Section 1.10: heavy symmetric top on the floor, tip O fixed (no slip), Euler angles.

Names.  The book writes varphi for the precession, theta for the nutation and phi for the spin;
its Pascal listing calls them psi, teta and phi.  Here (DESIGN.md): precession = varphi = psi,
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
Two cosmetic points that change nothing: the X2 row prints p'[s' CM_Izz sin n + (p'/2) sin 2n (...)]
(= p'^2 sin n cos n (...)); the Y2 row's first term shows the precession glyph where the spin
rate belongs (-n' s' CM_Izz; the book's p. 80 product Omega x (I omega) and its final precession
equation have the spin).  The precession equation divides by CM_Ixx + m h^2 where the Y2 row has
CM_Iyy + m h^2: equal for the symmetric top.  The equations are right: `Reference` keeps them.

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
"""

import numpy as np

COORDS = ("precession", "nutation", "spin")
REACTIONS = ("Rx", "Ry", "Rz")


class Book:
    """The book's 1.10 equations of motion (p. 81) and reaction components (p. 82) as printed."""

    coords = COORDS
    reaction_names = REACTIONS

    def __init__(self, params):
        self.p = dict(params)

    # -- inertias ------------------------------------------------------------
    def _cm_inertias(self):
        """CM_Ixx, CM_Iyy, CM_Izz of the book's (9), from the parameters (Ixx, Izz about O)."""
        p = self.p
        shift = p["m"] * p["h"] ** 2
        return p["Ixx"] - shift, p["Ixx"] - shift, p["Izz"]

    # -- model interface -------------------------------------------------------
    def accelerations(self, t, q, v):
        p = self.p
        _, n = q[0], q[1]
        dp, dn, ds = v
        cxx, cyy, czz = self._cm_inertias()
        mh2 = p["m"] * p["h"] ** 2
        sn, cn = np.sin(n), np.cos(n)
        p_acc = dn / (sn * (cxx + mh2)) * (ds * czz + dp * cn * (czz - cxx - cyy - 2 * mh2))
        n_acc = sn / (cxx + mh2) * (p["m"] * p["g"] * p["h"]
                                    + dp * (-czz * ds + dp * cn * (cyy - czz + mh2)))
        s_acc = (dn / (np.tan(n) * (cyy + mh2)) * (-czz * ds + dp * cn * (cxx + cyy - czz + 2 * mh2))
                 + (p["Mz"] + dp * dn * sn * (cxx - cyy + czz)) / czz)
        return np.array([p_acc, n_acc, s_acc])

    def _transport_rate(self, q, v):
        """The z rate that turns v in the book's reactions: omega_z = p' cos n + s' (printed)."""
        return v[0] * np.cos(q[1]) + v[2]

    def _newton(self, q, v, acc):
        """F = m a - B2 P in B2, with the transport term Omega_z or omega_z (see _transport_rate)."""
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

    @staticmethod
    def _tz_t(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])  # T_z(a)^T

    @staticmethod
    def _tx_t(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])  # T_x(a)^T

    def _to_inertial(self, q, force):
        """The printed rows: T_x(n)^T T_z(p)^T F (the book's own previous line has T_z^T T_x^T)."""
        return self._tx_t(q[1]) @ (self._tz_t(q[0]) @ force)

    def reactions(self, t, q, v):
        q, v = np.asarray(q, float), np.asarray(v, float)
        acc = self.accelerations(t, q, v)
        r = self._to_inertial(q, self._newton(q, v, acc))
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


class Reference(Book):
    """The book's equations of motion; reactions with Omega in (7) and T_z^T T_x^T (finding 1.10-R)."""

    def _transport_rate(self, q, v):
        return v[0] * np.cos(q[1])  # Omega_z: the centre of mass is carried by B2

    def _to_inertial(self, q, force):
        return self._tz_t(q[0]) @ (self._tx_t(q[1]) @ force)
