"""Spherical pendulum as two hinges on one body: a about x, then b about the turned y (MJCF's form).

A rigid body of mass m, its centre of mass l below the pivot, principal moments IXX, IYY, IZZ about it; its angular
velocity in its axes (a' cos b, b', a' sin b); T = (A(b) a'^2 + B b'^2) / 2 with A = (m l^2 + IXX) cos^2 b +
IZZ sin^2 b, B = m l^2 + IYY; V = -m g l cos a cos b.
"""
import numpy as np

COORDS = ["a", "b"]
PARAMS = {"m": 0.3, "l": 0.5, "g": 9.81}
IXX, IYY, IZZ = 2e-3, 3e-3, 1e-3


def mass_matrix(q, p):
    a, b = q
    m, l = p["m"], p["l"]
    return np.array([[(m * l**2 + IXX) * np.cos(b)**2 + IZZ * np.sin(b)**2, 0.0], [0.0, m * l**2 + IYY]])


def forces(t, q, v, p):
    a, b = q
    ar, br = v
    m, l, g = p["m"], p["l"], p["g"]
    c = (m * l**2 + IXX - IZZ) * np.sin(b) * np.cos(b)
    return np.array([2 * c * ar * br - m * g * l * np.sin(a) * np.cos(b),
                     -c * ar**2 - m * g * l * np.cos(a) * np.sin(b)])


def accelerations(t, q, v, p):
    return np.linalg.solve(mass_matrix(q, p), forces(t, q, v, p))


def energy(t, q, v, p):
    a, b = q
    ar, br = v
    m, l, g = p["m"], p["l"], p["g"]
    kinetic = 0.5 * (((m * l**2 + IXX) * np.cos(b)**2 + IZZ * np.sin(b)**2) * ar**2 + (m * l**2 + IYY) * br**2)
    return kinetic - m * g * l * np.cos(a) * np.cos(b)
