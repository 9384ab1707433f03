"""The book's Euler angles (1.10) for a ball joint: precession about Z, nutation about X1, spin about Z2.

The body's orientation is Rz(precession) Rx(nutation) Rz(spin) (world from body).  Both engines
give a ball joint's velocity and acceleration as the body's angular velocity and acceleration
in its own (spinning) frame, w = J(angles) angles' with

    w = T_z(spin) (nutation', precession' sin(nutation), precession' cos(nutation) + spin'),

the book's B2 vector turned into the spinning frame.  J is singular where sin(nutation) = 0.
"""

import numpy as np


def quaternion(angles):
    """(w, x, y, z) of Rz(precession) Rx(nutation) Rz(spin)."""
    phi, theta, spin = angles
    qz1 = np.array([np.cos(phi / 2), 0.0, 0.0, np.sin(phi / 2)])
    qx = np.array([np.cos(theta / 2), np.sin(theta / 2), 0.0, 0.0])
    qz2 = np.array([np.cos(spin / 2), 0.0, 0.0, np.sin(spin / 2)])
    return _multiply(_multiply(qz1, qx), qz2)


def _multiply(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def jacobian(angles):
    """J with w_local = J angles'; columns: precession, nutation, spin."""
    _, theta, spin = angles
    st, ct, ss, cs = np.sin(theta), np.cos(theta), np.sin(spin), np.cos(spin)
    return np.array([[ss * st, cs, 0.0],
                     [cs * st, -ss, 0.0],
                     [ct, 0.0, 1.0]])


def angular_velocity(angles, rates):
    return jacobian(angles) @ rates


def bias(angles, rates):
    """J' angles': the part of w_local' that the Euler-angle accelerations do not give."""
    _, theta, spin = angles
    dphi, dtheta, dspin = rates
    st, ct, ss, cs = np.sin(theta), np.cos(theta), np.sin(spin), np.cos(spin)
    return np.array([-ss * dspin * dtheta + (cs * dspin * st + ss * ct * dtheta) * dphi,
                     -cs * dspin * dtheta + (-ss * dspin * st + cs * ct * dtheta) * dphi,
                     -st * dtheta * dphi])


def angular_acceleration(angles, rates, accelerations):
    return jacobian(angles) @ accelerations + bias(angles, rates)


def euler_accelerations(angles, rates, angular_acc):
    """Euler-angle accelerations from the body's local angular acceleration."""
    return np.linalg.solve(jacobian(angles), angular_acc - bias(angles, rates))


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
