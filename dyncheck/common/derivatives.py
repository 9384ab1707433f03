"""Derivatives by extrapolated central differences, and Newton-Raphson on them: the vibration analysis's equilibrium
and linearisation (dyncheck.checks.linear), the convergence check's motion frequency (dyncheck.checks.convergence),
and the start of a case of two files near its equilibrium (dyncheck.case.derived)."""

import math
from dataclasses import dataclass

import numpy as np

from dyncheck.common import ceilings

EPS = np.finfo(float).eps
# Central differences extrapolated once (Richardson: fourth order): truncation ~h^4 f^(5) and rounding eps f / h
# balance at h ~ eps^(1/5) (times the variable's scale), both then ~eps^(4/5) ~ 3e-13 of the derivative's scale.
STEP = EPS ** (1 / 5)
NEWTON_ITERATIONS = 50
# Newton stops when the accelerations are within a thousand ulps of the terms that balance there
# (the Jacobian times the unknowns' scale): rounding in one evaluation of the equations is tens of ulps.
NEWTON_TOLERANCE = ceilings.ROUNDING_FLOOR


def jacobian(f, x, scales):
    """df/dx by central differences at steps h, 2h and 4h, extrapolated (Richardson: R(h) = (4 D(h) - D(2h)) / 3,
    fourth order), and an estimate of each column's error: |R(h) - R(2h)| / 15 (R(2h)'s error is 16 times
    R(h)'s), plus the rounding of the quotients, 10 eps |f| / h.  h is STEP times the variable's scale, or a
    tenth, a hundredth or a thousandth of that, whichever has the least estimated error: the equations may
    vary on a shorter scale than the variable's (a mass ratio of 10 between two pendulums makes their
    accelerations change on a third of a radian)."""
    x = np.asarray(x, dtype=float)
    columns, errors = [], []
    for j, scale in enumerate(scales):
        best = None
        for shrink in (1.0, 1e-1, 1e-2, 1e-3):
            column, error = _extrapolated(f, x, j, STEP * shrink * max(abs(x[j]), scale))
            if best is None or error < best[1]:
                best = column, error
        columns.append(best[0])
        errors.append(best[1])
    return np.column_stack(columns), np.array(errors)


def _extrapolated(f, x, j, h):
    """Column j of `jacobian` at step h, and its error estimate."""
    quotients, size = [], 0.0
    for k in (1, 2, 4):
        step = np.zeros_like(x)
        step[j] = k * h
        plus, minus = f(x + step), f(x - step)
        quotients.append((plus - minus) / (2 * k * h))
        size = max(size, np.max(np.abs(plus)), np.max(np.abs(minus)))
    near, far = (4 * quotients[0] - quotients[1]) / 3, (4 * quotients[1] - quotients[2]) / 3
    return near, float(np.max(np.abs(far - near)) / 15 + 10 * EPS * size / h)


def scales_of(x):
    """Each state variable's scale for its difference step: its size, at least 1 (rad, m, rad/s, m/s)."""
    return np.maximum(np.abs(x), 1.0)


@dataclass(frozen=True)
class Newton:
    """Where Newton-Raphson stopped: the unknowns, and whether they converged (after how many iterations, with
    the largest |q''| left relative to `scale`, the balancing terms' size)."""
    u: np.ndarray
    converged: bool
    iterations: int = 0
    residual: float = math.nan
    scale: float = math.nan


def newton(equations, accelerations, u):
    """Newton-Raphson on `equations` (of the unknowns u) from u; least-squares steps (a cyclic coordinate's equation
    is identically zero), halved while they do not reduce the residual; converged when the accelerations are within
    NEWTON_TOLERANCE of the balancing terms, whatever the equations.  The terms' size is their Jacobian times the
    unknowns' scale, the largest met on the way: at a degenerate equilibrium the Jacobian vanishes while the terms
    that cancel there do not (a pendulum on a turning disk under g = 0 stops at psi = -pi/2 with |q''| 8e-24 and a zero
    Jacobian, which no tolerance relative to it would pass)."""
    residual = equations(u)
    scale = EPS
    iteration = 0
    while iteration < NEWTON_ITERATIONS:
        scales = scales_of(u)
        acc = residual if equations is accelerations else accelerations(u)
        acc_jac, _ = jacobian(accelerations, u, scales)
        scale = max(np.max(np.abs(acc_jac)) * np.max(scales), scale)
        jac = acc_jac if equations is accelerations else jacobian(equations, u, scales)[0]
        if not all(np.all(np.isfinite(a)) for a in (acc, acc_jac, residual, jac)):
            break
        if np.max(np.abs(acc)) <= NEWTON_TOLERANCE * scale:
            return Newton(u, True, iteration, float(np.max(np.abs(acc)) / scale), float(scale))
        step = np.linalg.lstsq(jac, -residual, rcond=None)[0]
        # at most a scale a step (a radian, a metre, a radian per second): far from the equilibrium the linear model
        # can send a step many turns away, to another equilibrium or a local minimum of |q''| (two pendulums with
        # m2 = 80 m1 stalled at theta1 = -187 rad from the guess 0.1 rad)
        step = step / max(1.0, float(np.max(np.abs(step) / scales)))
        for _ in range(30):
            trial = equations(u + step)
            if np.all(np.isfinite(trial)) and np.max(np.abs(trial)) < np.max(np.abs(residual)):
                break
            step = step / 2
        u, residual = u + step, trial
        iteration += 1
    return Newton(u, False, iteration)
