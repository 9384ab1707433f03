"""The book's Euler angles (1.10) for a ball joint: precession about Z, nutation about X1, spin about Z2.

The body's orientation is Rz(precession) Rx(nutation) Rz(spin) (world from body).  Both engines
give a ball joint's velocity and acceleration as the body's angular velocity and acceleration
in its own (spinning) frame, w = J(angles) angles' with

    w = T_z(spin) (nutation', precession' sin(nutation), precession' cos(nutation) + spin'),

the book's B2 vector turned into the spinning frame.  J is singular where sin(nutation) = 0.

Every function takes one state, angles of shape (3,), or many, shape (N, 3), and answers in kind:
the conversions of a whole trajectory are one call each.  The states may be complex: the complex steps
of engines.coordinates.case_linearisation differentiate angular_velocity and bias exactly.
"""

import numpy as np


def _components(x):
    """The three components of one state, as Python numbers (the arithmetic on one state then costs
    a tenth of numpy's on its scalars), or of many, as columns."""
    x = np.asarray(x)
    return x.tolist() if x.ndim == 1 else x.T


def _stack(a, b, c):
    """The inverse of `_components`."""
    return np.array([a, b, c]).T


def quaternion(angles):
    """(w, x, y, z) of Rz(precession) Rx(nutation) Rz(spin): the product qz qx qz multiplied out."""
    half = np.asarray(angles) / 2
    (sa, sb, sc), (ca, cb, cc) = _components(np.sin(half)), _components(np.cos(half))
    return np.array([ca * cb * cc - sa * cb * sc,
                     ca * sb * cc + sa * sb * sc,
                     sa * sb * cc - ca * sb * sc,
                     ca * cb * sc + sa * cb * cc]).T


def _trig(angles):
    """sin and cos of nutation and spin."""
    (_, st, ss), (_, ct, cs) = _components(np.sin(angles)), _components(np.cos(angles))
    return st, ct, ss, cs


def angular_velocity(angles, rates):
    """w = J(angles) angles'."""
    st, ct, ss, cs = _trig(angles)
    dphi, dtheta, dspin = _components(rates)
    return _stack(ss * st * dphi + cs * dtheta, cs * st * dphi - ss * dtheta, ct * dphi + dspin)


def euler_rates(angles, w):
    """angles' = J(angles)^-1 w."""
    return _inverse(_trig(angles), w)


def _inverse(trig, w):
    """J^-1 w, J's sines and cosines `trig` (`_trig`): the rows of J^-1 multiplied out."""
    st, ct, ss, cs = trig
    w0, w1, w2 = _components(w)
    dphi = (ss * w0 + cs * w1) / st
    return _stack(dphi, cs * w0 - ss * w1, w2 - ct * dphi)


def bias(angles, rates):
    """J' angles': the part of w' that the Euler-angle accelerations do not give."""
    return _bias(_trig(angles), rates)


def _bias(trig, rates):
    """`bias`, J's sines and cosines `trig` (`_trig`)."""
    st, ct, ss, cs = trig
    dphi, dtheta, dspin = _components(rates)
    return _stack(-ss * dspin * dtheta + (cs * dspin * st + ss * ct * dtheta) * dphi,
                  -cs * dspin * dtheta + (-ss * dspin * st + cs * ct * dtheta) * dphi,
                  -st * dtheta * dphi)


def euler_accelerations(angles, angle_rates, angular_acc):
    """Euler-angle accelerations from the body's local angular acceleration: J angles'' = w' - J' angles'
    (the sines and cosines computed once for both)."""
    trig = _trig(angles)
    return _inverse(trig, np.asarray(angular_acc) - _bias(trig, angle_rates))


def angles(quaternions, start):
    """Euler angles of a time series of (w, x, y, z) quaternions, continuous in time, starting at `start`.

    Nutation is taken in [0, pi] (the book's top leans, 0 < nutation < pi); precession and spin
    are unwrapped and shifted by whole turns to begin at `start`.
    """
    w, x, y, z = np.atleast_2d(quaternions).T
    r02 = 2 * (x * z + w * y)
    r12 = 2 * (y * z - w * x)
    r20 = 2 * (x * z - w * y)
    r21 = 2 * (y * z + w * x)
    r22 = 1 - 2 * (x * x + y * y)
    out = np.column_stack([np.arctan2(r02, -r12), np.arccos(np.clip(r22, -1.0, 1.0)), np.arctan2(r20, r21)])
    for k in (0, 2):
        out[:, k] = np.unwrap(out[:, k])
        out[:, k] += 2 * np.pi * np.round((start[k] - out[0, k]) / (2 * np.pi))
    return out
