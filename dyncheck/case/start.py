"""The initial state of a case of two files whose case.toml gives none (dyncheck.case.derived): a small
displacement from its stable equilibrium at rest, where it has one; otherwise AWAY from the scene's pose.

Why not AWAY always: 0.5 rad on every joint of a 7-link chain folds it over itself (its last link upside down), far
from any equilibrium.  Its linearisation there, from which the case's time scales follow, gives 9.3 rad/s where
its modes reach 27 rad/s hanging, and the motion from there runs at twice that 9.3 rad/s within 3 / (9.3 rad/s) (a
7-dof arm 0.5 rad on each joint from upright was chaotic: its runs at rtol 1e-8 and 1e-11 ended 43 rad apart)."""

import numpy as np

from dyncheck.common.derivatives import NEWTON_TOLERANCE, jacobian, newton, scales_of

# From the equilibrium: a tenth of a radian on every angle, a hundredth of the scene's size on every slide.  Far
# enough that every coordinate moves and the nonlinear terms show (sin departs from its angle by 0.2 %), near
# enough that the motion stays regular: the 7-link chain from 0.1 rad on each joint from hanging, its tip 0.7 rad
# out, runs at rtol 1e-8 and 1e-11 to within 6e-8 of its largest angle over its horizon.
DISPLACEMENT = {"rad": 0.1, "m": 0.01}
AWAY = {"rad": 0.5, "m": 0.1}  # without a stable equilibrium: the same on every coordinate, from the scene's pose
STEADY_TIMES = (0.29, 0.71)  # s: an equilibrium at t = 0 must be one at these too (no law of time moves it)
SAFETY = 10.0  # on Newton-Raphson's tolerance, for the equilibrium at the other times
# An eigenvalue of the linearisation whose real part is within this of the largest |eigenvalue| is neutral, not
# growing: the differences' error is ~3e-13 of the derivative's scale (dyncheck.common.derivatives.STEP).
NEUTRAL = 1e-8


def displaced(units, length, by=DISPLACEMENT):
    """The displacement `by` (from the equilibrium, or AWAY from the pose) in words: "0.1 rad on every angle,
    0.0035 m on every slide"."""
    words = {"rad": f"{by['rad']:g} rad on every angle",
             "m": f"{by['m'] * length:.3g} m on every slide ({by['m']:g} of the scene's size)"}
    return ", ".join(words[unit] for unit in dict.fromkeys(units))


def unsettled(units, length, q0):
    """Where a case starts AWAY from its pose, in words for its page, with the `[initial]` that would set another."""
    return (f"the runs start {displaced(units, length, AWAY)} from the scene's pose, q = {np.round(q0, 6).tolist()}: "
            "no stable equilibrium at rest was found to start near; where the motion from there is chaotic (the "
            "trajectory rows inconclusive), `[initial] q = [...]` in a case.toml beside the files sets another start")


def initial_q(equations, units, length):
    """(q0, equilibrium): q0 the equilibrium of `equations` (the model interface: accelerations(t, q, v)) at rest
    nearest the scene's pose, displaced by DISPLACEMENT (a slide's times `length`), if Newton-Raphson finds it from
    the pose, it holds at every time and no eigenvalue of its linearisation grows; otherwise AWAY from the pose
    and None.  Any failure of the derivation here is left to the calls that report it (at the initial state)."""
    n = len(units)
    away = np.array([AWAY[unit] * (1.0 if unit == "rad" else length) for unit in units])
    rest = np.zeros(n)
    try:
        with np.errstate(all="ignore"):
            at = lambda t: lambda q: np.asarray(equations.accelerations(t, q, rest), dtype=float)
            found = newton(at(0.0), at(0.0), rest)
            if not found.converged or any(np.max(np.abs(at(t)(found.u))) > SAFETY * NEWTON_TOLERANCE * found.scale
                                          for t in STEADY_TIMES):
                return away, None
            state = np.concatenate([found.u, rest])
            rates = lambda x: np.concatenate([x[n:], equations.accelerations(0.0, x[:n], x[n:])])
            eigenvalues = np.linalg.eigvals(jacobian(rates, state, scales_of(state))[0])
    except Exception:  # the derivation's own error: reported where the checks call it
        return away, None
    size = np.max(np.abs(eigenvalues)) if np.all(np.isfinite(eigenvalues)) else np.nan
    if not size > 0 or np.max(eigenvalues.real) > NEUTRAL * size:  # nothing restores it, or a mode grows
        return away, None
    return found.u + [DISPLACEMENT[unit] * (1.0 if unit == "rad" else length) for unit in units], found.u
