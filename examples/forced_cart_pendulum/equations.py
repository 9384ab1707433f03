"""Damped, harmonically forced cart-pendulum, derived by Lagrange's equations.

A cart of mass M slides along x on a spring of stiffness k and a damper c, pushed by F0 cos(Omega t);
from it hangs a point mass m on a massless rod of length l, its hinge damped by ct; theta is the rod's
angle from the downward vertical.  T = (M + m) x'^2 / 2 + m l cos(theta) x' theta' + m l^2 theta'^2 / 2,
V = k x^2 / 2 - m g l cos(theta); the push and the dampers are the generalised forces
Q = (F0 cos(Omega t) - c x', -ct theta').
"""
import numpy as np

COORDS = ["x", "theta"]
PARAMS = {"M": 1.0, "m": 0.3, "l": 0.5, "k": 20.0, "c": 0.6, "ct": 0.1, "g": 9.81, "F0": 0.05, "Omega": 4.0}


def mass_matrix(q, p):
    x, theta = q
    M, m, l = p["M"], p["m"], p["l"]
    return np.array([[M + m, m * l * np.cos(theta)],
                     [m * l * np.cos(theta), m * l**2]])


def forces(t, q, v, p):
    x, theta = q
    x_rate, theta_rate = v
    m, l, k, g = p["m"], p["l"], p["k"], p["g"]
    push = p["F0"] * np.cos(p["Omega"] * t)
    return np.array([m * l * np.sin(theta) * theta_rate**2 - k * x - p["c"] * x_rate + push,
                     -m * g * l * np.sin(theta) - p["ct"] * theta_rate])


def accelerations(t, q, v, p):
    return np.linalg.solve(mass_matrix(q, p), forces(t, q, v, p))


def energy(t, q, v, p):
    x, theta = q
    x_rate, theta_rate = v
    M, m, l, k, g = p["M"], p["m"], p["l"], p["k"], p["g"]
    kinetic = 0.5 * (M + m) * x_rate**2 + m * l * np.cos(theta) * x_rate * theta_rate + 0.5 * m * l**2 * theta_rate**2
    return kinetic + 0.5 * k * x**2 - m * g * l * np.cos(theta)


def drive_power(t, q, v, p):
    """The power of the push and of the two dampers: what changes the energy."""
    x_rate, theta_rate = v
    return p["F0"] * np.cos(p["Omega"] * t) * x_rate - p["c"] * x_rate**2 - p["ct"] * theta_rate**2
