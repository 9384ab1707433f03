"""Slider-crank in the vertical x-z plane, gravity -z, derived by Lagrange's equation in the crank angle alone.

A crank O->A of length r (mass m1, centre of mass at r/2) turns about y at the origin O; a connecting rod A->B
of length l (mass m2, centre of mass at l/2) is hinged at the crank's tip A; a slider (mass m3) on a
frictionless guide along world x is pinned to the rod's end B.  Both links are uniform rods: I1 = m1 r^2 / 12,
I2 = m2 l^2 / 12 about their centres of mass.  A constant torque tau drives the crank.

Coordinates (those of scene.xml): angles in the x-z plane from +x toward +z (hinge axes 0 -1 0).  phi is the
crank's angle, psi the rod's relative to the crank, theta = phi + psi its absolute angle; x is the slider's
displacement from the outer dead centre r + l (the scene's assembly, phi = psi = 0).  A = r (cos phi, sin phi),
B = A + l (cos theta, sin theta).

Loop (B on the guide, z = 0), on the branch cos(theta) > 0 that the scene is assembled on:
    r sin(phi) + l sin(theta) = 0,    x = r cos(phi) + l cos(theta) - (r + l).
Differentiating the first, theta' = k phi' with k = dtheta/dphi = -r cos(phi) / (l cos(theta)), and
k' = dk/dphi = (r sin(phi) + l sin(theta) k^2) / (l cos(theta)).  Every point P(phi) then has velocity
P_phi phi' and acceleration P_phi phi'' + P_phiphi phi'^2 (subscripts: derivatives in phi).

Lagrange in phi, T = J(phi) phi'^2 / 2, V = g (m1 z_G1 + m2 z_G2):
    J(phi) phi'' + (1/2) J'(phi) phi'^2 = tau - dV/dphi,
    J      = m1 |G1_phi|^2 + I1 + m2 |G2_phi|^2 + I2 k^2 + m3 x_phi^2,
    J' / 2 = m1 G1_phi . G1_phiphi + m2 G2_phi . G2_phiphi + I2 k k' + m3 x_phi x_phiphi,
    dV/dphi = g (m1 G1_phi,z + m2 G2_phi,z).

Forces, from Newton-Euler on the slider and the rod with the accelerations above.  F is the force of the
slider on the rod at B (world x, z); the rod pushes the slider with -F.
    slider:  m3 x'' = -F_x,   N = m3 g + F_z     (N: the guide's normal force on the slider, along +z);
    rod, moments about A (a x b = a_x b_z - a_z b_x, positive from +x toward +z), with G2 - A = (l/2) e(theta):
        (B - A) x F + (G2 - A) x (0, -m2 g) = I2 theta'' + (G2 - A) x m2 a_G2
    =>  l (cos(theta) F_z - sin(theta) F_x) = I2 theta'' + (G2 - A) x m2 (a_G2 + (0, g)).
The crank's moment balance about O, which Lagrange's equation does not use, holds with these to rounding.
"""
import numpy as np

COORDS = ["phi"]
PARAMS = {"r": 0.1, "l": 0.3, "m1": 1.0, "m2": 0.5, "m3": 0.8, "g": 9.81, "tau": 2.0}


def _unit(angle):
    return np.array([np.cos(angle), np.sin(angle)])


def _normal(angle):  # d/dangle of _unit
    return np.array([-np.sin(angle), np.cos(angle)])


def _loop(phi, p):
    """theta, k = dtheta/dphi and k' = d2theta/dphi2 on the loop."""
    r, l = p["r"], p["l"]
    theta = np.arcsin(-r * np.sin(phi) / l)
    k = -r * np.cos(phi) / (l * np.cos(theta))
    k_phi = (r * np.sin(phi) + l * np.sin(theta) * k**2) / (l * np.cos(theta))
    return theta, k, k_phi


def _coefficients(phi, p):
    """theta, k, k' and the first and second phi-derivatives of the centres of mass G1, G2 (x, z) and of x."""
    r, l = p["r"], p["l"]
    theta, k, k_phi = _loop(phi, p)
    G1_phi, G1_phiphi = 0.5 * r * _normal(phi), -0.5 * r * _unit(phi)
    G2_phi = r * _normal(phi) + 0.5 * l * k * _normal(theta)
    G2_phiphi = -r * _unit(phi) + 0.5 * l * (k_phi * _normal(theta) - k**2 * _unit(theta))
    x_phi = -r * np.sin(phi) - l * np.sin(theta) * k
    x_phiphi = -r * np.cos(phi) - l * (np.cos(theta) * k**2 + np.sin(theta) * k_phi)
    return theta, k, k_phi, G1_phi, G1_phiphi, G2_phi, G2_phiphi, x_phi, x_phiphi


def _inertias(p):
    return p["m1"] * p["r"] ** 2 / 12, p["m2"] * p["l"] ** 2 / 12


def _crank_inertia(phi, p):
    """J(phi), the inertia the crank's motion meets."""
    _, k, _, G1_phi, _, G2_phi, _, x_phi, _ = _coefficients(phi, p)
    I1, I2 = _inertias(p)
    return p["m1"] * G1_phi @ G1_phi + I1 + p["m2"] * G2_phi @ G2_phi + I2 * k**2 + p["m3"] * x_phi**2


def accelerations(t, q, v, p):
    (phi,), (phi_rate,) = q, v
    _, k, k_phi, G1_phi, G1_phiphi, G2_phi, G2_phiphi, x_phi, x_phiphi = _coefficients(phi, p)
    _, I2 = _inertias(p)
    m1, m2, m3 = p["m1"], p["m2"], p["m3"]
    half_J_phi = m1 * G1_phi @ G1_phiphi + m2 * G2_phi @ G2_phiphi + I2 * k * k_phi + m3 * x_phi * x_phiphi
    V_phi = p["g"] * (m1 * G1_phi[1] + m2 * G2_phi[1])
    return np.array([(p["tau"] - V_phi - half_J_phi * phi_rate**2) / _crank_inertia(phi, p)])


def energy(t, q, v, p):
    """Kinetic plus potential energy, J; gravity's zero at the world origin (the slider stays at z = 0)."""
    (phi,), (phi_rate,) = q, v
    theta, _, _ = _loop(phi, p)
    r, l = p["r"], p["l"]
    heights = p["m1"] * 0.5 * r * np.sin(phi) + p["m2"] * (r * np.sin(phi) + 0.5 * l * np.sin(theta))
    return 0.5 * _crank_inertia(phi, p) * phi_rate**2 + p["g"] * heights


def drive_power(t, q, v, p):
    """The crank torque's power: what changes the energy."""
    return p["tau"] * v[0]


def reactions(t, q, v, p):
    """loop_x, loop_z: the force of the slider on the rod at the pin, world axes, N (the loop's closing force,
    on the <connect>'s body1); guide_z: the guide's normal force on the slider, along +z, N."""
    (phi,), (phi_rate,) = q, v
    (phi_acc,) = accelerations(t, q, v, p)
    theta, k, k_phi, _, _, G2_phi, G2_phiphi, x_phi, x_phiphi = _coefficients(phi, p)
    _, I2 = _inertias(p)
    theta_acc = k * phi_acc + k_phi * phi_rate**2
    x_acc = x_phi * phi_acc + x_phiphi * phi_rate**2
    G2_acc_and_gravity = G2_phi * phi_acc + G2_phiphi * phi_rate**2 + np.array([0.0, p["g"]])
    G2_from_A = 0.5 * p["l"] * _unit(theta)
    moment = I2 * theta_acc + p["m2"] * (G2_from_A[0] * G2_acc_and_gravity[1] - G2_from_A[1] * G2_acc_and_gravity[0])
    loop_x = -p["m3"] * x_acc
    loop_z = (moment / p["l"] + np.sin(theta) * loop_x) / np.cos(theta)
    return {"loop_x": loop_x, "loop_z": loop_z, "guide_z": p["m3"] * p["g"] + loop_z}


def dependent(q, v, p):
    """The position and velocity solve: the dependent joints' positions and rates from (phi, phi')."""
    (phi,), (phi_rate,) = q, v
    theta, k, _ = _loop(phi, p)
    r, l = p["r"], p["l"]
    x = r * np.cos(phi) + l * np.cos(theta) - (r + l)
    x_phi = -r * np.sin(phi) - l * np.sin(theta) * k
    return {"psi": theta - phi, "x": x}, {"psi": (k - 1) * phi_rate, "x": x_phi * phi_rate}
