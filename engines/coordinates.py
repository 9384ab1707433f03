"""The case's coordinates on an engine's dofs, as every adapter maps them: the accelerations (`case_accelerations`),
the mass matrix (`case_mass_matrix`), the applied forces (`applied_forces`) and the linearisation
(`case_linearisation`), with the steps of the engines' differences and the rounding of their derivatives.  A
`layout` is (kind, first dof, coordinate indices) of each joint the case's coordinates move: "scalar" a hinge or
slide, its own coordinate; "euler" a ball joint in the case's Euler angles (engines.euler)."""

from dataclasses import dataclass

import numpy as np

from engines import euler


def case_accelerations(layout, q, v, acc):
    """The accelerations of the case's coordinates from the dofs' `acc`, (nv,) at one state (q, v), or (N, nv) at
    many, q and v (N, n): a hinge's or slide's its dof's, a ball joint's Euler angles' from the body's angular
    acceleration."""
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    out = np.zeros(q.shape)
    for kind, dof, idx in layout:
        if kind == "scalar":
            out[..., idx[0]] = acc[..., dof]
        else:
            out[..., idx] = euler.euler_accelerations(q[..., idx], v[..., idx], acc[..., dof:dof + 3])
    return out


def case_mass_matrix(mass, layout, q):
    """An engine's dof mass matrix `mass` (nv, nv) in the case's coordinates q: J^T mass J, J (nv, n) the map
    from the coordinates' rates to the dofs' velocities (`_rates_to_dofs`), so that it multiplies the case's
    accelerations in its equations of motion.  Prescribed dofs are no coordinates: their rows and columns drop out."""
    rates_to_dofs = _rates_to_dofs(layout, len(mass), np.asarray(q, dtype=float))
    return rates_to_dofs.T @ mass @ rates_to_dofs


def _rates_to_dofs(layout, nv, q):
    """J (nv, n): the dofs' velocities per unit rate of each of the case's coordinates q: a hinge's or slide's rate is
    its dof's; a ball joint's Euler angles give the body's angular velocity J_ball rates (engines.euler), linear in the
    rates: its columns are the angular velocities of unit rates."""
    rates_to_dofs = np.zeros((nv, len(q)))
    for kind, dof, idx in layout:
        if kind == "scalar":
            rates_to_dofs[dof, idx[0]] = 1.0
        else:
            rates_to_dofs[dof:dof + 3, idx] = euler.angular_velocity(q[idx], np.eye(3)).T
    return rates_to_dofs


@dataclass(frozen=True, eq=False)
class Linearisation:
    """M q'' = f(t, q, q') of a scene, linearised at one state in the case's coordinates."""
    mass: np.ndarray  # M (n, n)
    force_q: np.ndarray  # df/dq (n, n), at fixed q' and t (prescribed joints follow their motion, unperturbed)
    force_v: np.ndarray  # df/dq' (n, n)
    error: float  # estimated absolute error of the entries of force_q and force_v (case_linearisation says how)
    method: str  # words for a report, e.g. "Pinocchio computeRNEADerivatives (analytic)"


def case_linearisation(layout, forces, t, q, v, acc, mass, force_q, force_v, error, method):
    """An engine's `Linearisation` in the case's coordinates, from its derivatives in its own dofs at the case's
    state (t, q, v), whose accelerations are `acc`:
      mass (nv, nv): dF/d(dof accelerations), F the engine's inverse dynamics (M acc + bias - springs - dampers);
      force_q, force_v (nv, nv): d(springs + dampers - F)/d(dof positions, dof velocities) at fixed dof
        accelerations, positions perturbed in the engine's tangent space (a ball joint's quaternion * exp(dtheta),
        the body's own axes, as MuJoCo's mj_integratePos and Pinocchio's integrate both do);
      error: a bound on the absolute error of every entry of force_q and force_v.
    `layout` as for `case_mass_matrix` (prescribed dofs are in no column: they follow their motion); `forces`
    the applied forces as for `applied_forces`.

    The engine's equations in the case's coordinates are J^T F(x(q), W(q, q'), A(q, q', q'')) = J^T applied, J the
    dofs' rates per coordinate rate (`_rates_to_dofs`), W = J q' the dofs' velocities, A = J q'' + J' q' their
    accelerations (a hinge's or slide's: its own; a ball joint's: the body's angular velocity and acceleration
    from its Euler angles, engines.euler), and dx/dq = J (w = J q' turns the body by J dq).  On the motion
    F = applied, so the derivative of J^T drops out:
      mass    = J^T M J
      force_q = J^T (force_q J + force_v dW/dq - M dA/dq + d(applied)/dq)
      force_v = J^T (force_v J - M dA/dq' + d(applied)/dq').
    dW/dq, dA/dq, dA/dq' (zero for hinges and slides) are complex steps of engines.euler's functions
    (`_euler_partials`), exact to rounding; the applied laws are differenced (`applied_derivatives`).
    The error: an entry of J^T E X sums at most |J|_1 |X|_1 entries of E (|.|_1 the largest column sum of
    absolute values), so `error` |J|_1 (|J|_1 + |dW/dq|_1), plus the laws' own error |J|_1."""
    q, v, acc = (np.asarray(x, dtype=float) for x in (q, v, acc))
    rates_to_dofs = _rates_to_dofs(layout, len(mass), q)
    velocity_q, acceleration_q, acceleration_v = _euler_partials(layout, len(mass), q, v, acc)
    applied_q, applied_v, applied_error = applied_derivatives(forces, len(mass), t, q, v)
    into_case = rates_to_dofs.T
    norm = lambda matrix: np.max(np.sum(np.abs(matrix), axis=0), initial=0.0)
    return Linearisation(
        mass=into_case @ mass @ rates_to_dofs,
        force_q=into_case @ (force_q @ rates_to_dofs + force_v @ velocity_q - mass @ acceleration_q + applied_q),
        force_v=into_case @ (force_v @ rates_to_dofs - mass @ acceleration_v + applied_v),
        error=float(error * norm(rates_to_dofs) * (norm(rates_to_dofs) + norm(velocity_q))
                    + applied_error * norm(rates_to_dofs)),
        method=method)


def _euler_partials(layout, nv, q, v, acc):
    """dW/dq, dA/dq and dA/dq' (nv, n each) of case_linearisation, nonzero for the ball joints' Euler angles only:
    by complex steps, f'(x) = Im f(x + i h) / h, which take no difference, so exact to rounding for any h whose
    square is lost beside 1 (h = 1e-100)."""
    h = 1e-100
    velocity_q, acceleration_q, acceleration_v = (np.zeros((nv, len(q))) for _ in range(3))
    for kind, dof, idx in layout:
        if kind != "euler":
            continue
        angles, rates, accelerations = q[idx], v[idx], acc[idx]
        for j, step in zip(idx, 1j * h * np.eye(3)):
            velocity_q[dof:dof + 3, j] = euler.angular_velocity(angles + step, rates).imag / h
            acceleration_q[dof:dof + 3, j] = (euler.angular_velocity(angles + step, accelerations)
                                              + euler.bias(angles + step, rates)).imag / h
            acceleration_v[dof:dof + 3, j] = euler.bias(angles, rates + step).imag / h
    return velocity_q, acceleration_q, acceleration_v


def lone_ball_joint(path, layout, driven, method):
    """The joint of the case's coordinates (its entry of the adapter's `layout`) where the scene has no other joint,
    which `method` (a ball joint's own state) needs; ValueError where it has others."""
    if [kind for kind, _, _ in layout] != ["euler"] or driven:
        raise ValueError(f"{path}: {method} needs a scene whose only joint is a ball joint; this one "
                         f"has {len(layout)} free joints and {len(driven)} driven")
    return layout[0][1]


def constant_forces(path, varying, method):
    """ValueError where `method` needs constant applied forces and the scene's are laws of the state (`varying`)."""
    if varying:
        raise ValueError(f"{path}: {method} needs constant applied forces; this scene's depend on the state")


def ball_joint_state_matrix(omega, acc_theta, acc_omega):
    """The 6 x 6 state matrix A of (dtheta, dw) about a ball joint's state R*, w = omega (the body's angular
    velocity in its own axes), R = R* exp(dtheta^): dtheta' = dw - w x dtheta (R' = R w^ on both sides, to first
    order), dw' = acc_theta dtheta + acc_omega dw, the engine's derivatives of the body's angular acceleration.
    Its eigenvalues are those of the motion seen in the body's axes: about a steady spin S about the body's
    z axis, the world's by -i S (a tilt that stands still in the world turns at -S in the body)."""
    wx, wy, wz = omega
    cross = np.array([[0.0, -wz, wy], [wz, 0.0, -wx], [-wy, wx, 0.0]])  # w x
    return np.block([[-cross, np.eye(3)], [acc_theta, acc_omega]])


# The step of the engines' and laws' differences (rad, m; rad/s, m/s; the laws' relative to max(1, |value|)),
# extrapolated (`extrapolated_differences`).  Their error: truncation ~h^4 |d5F| / 30, rounding ~1.5 g eps |F| / h
# (`difference_rounding`).  For forces that change on the scale of a radian or a metre (|d5F| ~ |F|:
# trigonometric in the angles) the sum is least near h = (45 g eps / 4)^(1/5) ~ 3e-3; at 1e-3 truncation is
# ~3e-14 |F| and rounding ~2e-11 |F| (an upper estimate), where plain centred differences (MuJoCo's at h = 1e-5
# against Pinocchio's analytic derivatives) are off by 1e-10 to 1e-9 |F|.  1e-3 rather than 3e-3 keeps truncation,
# which grows as h^4 for forces that change faster (over a short lever), far below rounding.
DIFFERENCE_STEP = 1e-3
# MuJoCo's inverse dynamics is differenced at each of these and the least estimated error kept: a fast spin (the
# top's 44 rad/s) curves the forces on a far shorter scale than a radian, and rounding, not truncation, then
# dominates only at the smaller steps.
DIFFERENCE_STEPS = (3e-3, 1e-3, 3e-4, 1e-4, 3e-5)

# How much rounding an evaluation of the forces accumulates, in units of eps |F|, |F| the largest of the terms it
# sums (its intermediate terms may be larger: gravity against the bodies' accelerations).  Measured on MuJoCo's
# inverse dynamics, as the scatter of its extrapolated differences at h, 1.1 h and 1.21 h over 31 states of each
# of the six scenes with springs, drives, a ball joint: up to 20; 50 leaves a margin of 2.5.
ROUNDING_GROWTH = 50.0


def rounding_noise(derivatives, at, velocity):
    """The largest second difference of an engine's analytic (or automatic) derivatives over 1 to 3 ulps of each
    dof's position and velocity, in which their slope cancels (their curvature, ~eps^2, is lost): their rounding as
    measured, where their entries are far below the terms they sum.  derivatives(step_q, step_v): the derivatives
    (a sequence of arrays) at the state moved by step_q (nv, in the engine's tangent space) and step_v (nv); `at`
    their values at the state; velocity: the dofs' velocities, whose steps are relative to max(1, |v|).  At a
    degenerate equilibrium (a pendulum on a turning disk under g = 0, at psi = -pi/2) Pinocchio's entries are 4e-11
    of the terms they sum, 1e3 eps of them 8e-24, and the measured noise 1.4e-17, against an error of 4e-17
    (Pinocchio's A beside the derivation's and MuJoCo's)."""
    eps, nv = np.finfo(float).eps, len(velocity)
    noise = 0.0
    for k in (1, 2, 3):
        for j in range(nv):
            step, still = np.zeros(nv), np.zeros(nv)
            step[j] = k * eps
            for moved in ((step, still), (still, step * max(1.0, abs(velocity[j])))):
                plus, minus = derivatives(*moved), derivatives(*(-x for x in moved))
                noise = max(noise, *(float(np.max(np.abs((p + m) / 2 - a), initial=0.0))
                                     for p, m, a in zip(plus, minus, at)))
    return noise


def difference_rounding(size, step):
    """The rounding error of `extrapolated_differences` of forces whose terms are at most `size`: each centred
    difference's g eps size / h, through (4 D(h) - D(2h)) / 3, which weighs them 4/3 and 1/6."""
    return 1.5 * ROUNDING_GROWTH * np.finfo(float).eps * size / step


def extrapolated_differences(centred, step):
    """Richardson's extrapolation of centred differences: `centred(h)` gives a list of arrays of centred differences
    at step h, whose error is c h^2 + O(h^4); E(h) = (4 D(h) - D(2h)) / 3 cancels c h^2, and its error, O(h^4), is
    estimated by |E(h) - E(2h)| / 15, E(2h)'s being 16 times E(h)'s.  The E(h)'s, and that estimate, the largest
    over their entries: truncation only (the caller adds `difference_rounding`)."""
    fine, middle, coarse = (centred(scale * step) for scale in (1, 2, 4))
    extrapolated = [(4 * f - m) / 3 for f, m in zip(fine, middle)]
    coarser = [(4 * m - c) / 3 for m, c in zip(middle, coarse)]
    return extrapolated, max(float(np.max(np.abs(e - c), initial=0.0)) for e, c in zip(extrapolated, coarser)) / 15


def least_error_differences(centred, size):
    """`extrapolated_differences` of `centred` (the engine's force derivatives (df/dq, df/dv) by centred differences
    at a step) at each of DIFFERENCE_STEPS: those of the step whose estimated error, truncation (falling as step^4)
    plus the rounding of forces whose terms are at most `size` (growing as 1/step), is least, and that error.  A fast
    spin curves the forces on a shorter scale than the default step's."""
    best = None
    for step in DIFFERENCE_STEPS:
        (force_q, force_v), truncation = extrapolated_differences(centred, step)
        error = truncation + difference_rounding(size, step)
        if best is None or error < best[2]:
            best = force_q, force_v, error
    return best


# The rounding error of an engine's analytic (Pinocchio's) or automatic (Drake's AutoDiffXd: forward mode carries each
# derivative through the same operations as the value, exactly but for rounding) derivatives, relative to their
# largest entry: each entry sums, over the chain's few bodies, products of placements, inertias, velocities and
# accelerations, a few dozen operations that each round by eps of a term that cancellation (gyroscopic against gravity
# terms) may make a few times the largest entry; 1e3 eps allows some ten times that.  Nothing measured contradicts it:
# Pinocchio's linearisation agrees with MuJoCo's to 1e-14 to 1e-12 of the largest entry (the top, the cart-pendulum: no
# placeholders), MuJoCo's own rounding (tests/test_engine_linearisation.py).
DERIVATIVE_ROUNDING = 1e3 * np.finfo(float).eps
# The rounding noise measured over a few ulps (`rounding_noise`) samples the rounding of one evaluation: the error of
# Pinocchio's A at the degenerate equilibrium there was 3 times it; 10 times allows for a sample that misses.
NOISE_MARGIN = 10.0


def derivative_error(derivatives, at, velocity):
    """The rounding error of an engine's analytic or automatic derivatives, `at` at the state (a sequence of arrays;
    `derivatives` and `velocity` as for `rounding_noise`): DERIVATIVE_ROUNDING of their largest entry, or, where
    their entries are far below the terms they sum (a degenerate equilibrium), NOISE_MARGIN times their noise."""
    largest = max(float(np.max(np.abs(d), initial=0.0)) for d in at)
    return max(DERIVATIVE_ROUNDING * largest, NOISE_MARGIN * rounding_noise(derivatives, at, velocity))


def applied_derivatives(forces, nv, t, q, v):
    """d(applied)/dq and d(applied)/dq' (nv, n each) of `applied_forces` at the case's state, by
    `extrapolated_differences` of the laws, and the error of each entry.  Constant forces and laws of time only give
    exact zeros, error 0: the same law at the same time, whatever the state, gives the same number."""
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    state = np.concatenate([q, v])
    at = lambda x: applied_forces(forces, nv, t, x[:len(q)], x[len(q):])
    relative = np.maximum(1.0, np.abs(state))

    def centred(h):
        out = np.zeros((nv, len(state)))
        for j, step in enumerate(h * relative):
            unit = np.eye(len(state))[j]
            out[:, j] = (at(state + step * unit) - at(state - step * unit)) / (2 * step)
        return [out]

    (derivatives,), truncation = extrapolated_differences(centred, DIFFERENCE_STEP)
    if not np.any(derivatives):
        return derivatives[:, :len(q)], derivatives[:, len(q):], 0.0
    size = np.max(np.abs(at(state)), initial=0.0)
    return (derivatives[:, :len(q)], derivatives[:, len(q):],
            truncation + difference_rounding(size, DIFFERENCE_STEP * np.min(relative)))


def applied_forces(forces, nv, t, q, v):
    """The applied generalized forces at the case's state (t, q, v), every dof's (nv,): `forces` are (first dof,
    force(t, q, v)) pairs, a joint's components from its first dof on."""
    out = np.zeros(nv)
    for dof, force in forces:
        value = force(t, q, v)
        out[dof:dof + len(value)] = value
    return out
