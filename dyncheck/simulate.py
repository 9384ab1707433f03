"""Time integration of a model in the book's coordinates; a trajectory is a DataFrame indexed by time."""

import time

import numpy as np
import pandas as pd
from scipy.integrate import cumulative_simpson, solve_ivp

SCIPY_METHODS = ("RK45", "DOP853", "Radau", "LSODA")
MUJOCO_METHODS = ("mujoco:Euler", "mujoco:implicitfast", "mujoco:RK4")


class Unstable(Exception):
    """An integration that blew up: when, which method, which step."""

    def __init__(self, method, t, step, why):
        super().__init__(f"{method} unstable at t = {t:.6g} s (step {step}): {why}")
        self.method, self.t, self.step, self.why = method, t, step, why


def simulate(model, ic, t_end, method, *, rtol=None, dt=None, output_step, work=True):
    """Integrate `model` from ic = (q0, v0) over [0, t_end].

    method: one of SCIPY_METHODS (driven by model.accelerations, with tolerance `rtol`) or
    MUJOCO_METHODS (MuJoCo's own mj_step at step `dt`; the model must be a MujocoModel).
    Returns a DataFrame indexed by t: coordinates, their rates, reactions, energy, and the work
    of the prescribed motions and applied forces so far (`work`; pass work=False for a scene where
    nothing does work, to skip the drive power), with the cost in `.attrs`.
    """
    q0, v0 = (np.asarray(x, dtype=float) for x in ic)
    n_out = int(round(t_end / output_step))
    grid = np.linspace(0.0, t_end, n_out + 1)
    if method in SCIPY_METHODS:
        t, q, v, w, cost = _scipy(model, q0, v0, grid, method, rtol, work)
    elif method in MUJOCO_METHODS:
        t, q, v, w, cost = _mujoco(model, q0, v0, grid, method, dt, work)
    else:
        raise ValueError(f"unknown method '{method}'; methods are {', '.join(SCIPY_METHODS + MUJOCO_METHODS)}")
    return _frame(model, t, q, v, w, {"method": method, "rtol": rtol, "dt": dt, **cost})


def _scipy(model, q0, v0, grid, method, rtol, work):
    n = len(q0)
    evaluations = 0

    def rhs(t, y):
        nonlocal evaluations
        evaluations += 1
        q, v = y[:n], y[n:2 * n]
        power = model.drive_power(t, q, v) if work else 0.0
        return np.concatenate([v, model.accelerations(t, q, v), [power]])

    start = time.perf_counter()
    with np.errstate(all="ignore"):
        sol = solve_ivp(rhs, (grid[0], grid[-1]), np.concatenate([q0, v0, [0.0]]), method=method,
                        t_eval=grid, rtol=rtol, atol=rtol)
    wall = time.perf_counter() - start
    if sol.status != 0 or not np.all(np.isfinite(sol.y)):
        bad = sol.t[-1] if sol.t.size else grid[0]
        raise Unstable(method, float(bad), len(sol.t), sol.message)
    y = sol.y.T
    return sol.t, y[:, :n], y[:, n:2 * n], y[:, -1], {"wall": wall, "evaluations": evaluations}


def _mujoco(model, q0, v0, grid, method, dt, work):
    run = model.step(q0, v0, grid[-1], dt, method.split(":")[1])
    t, q, v = run["t"], run["q"], run["v"]
    # MuJoCo answers a blow-up (NaN, Inf or |qvel| > 1e10) by resetting the state and the clock
    # to their initial values, silently for a rollout: a clock that stops advancing by dt marks it.
    finite = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(v), axis=1)
    advancing = np.concatenate([[True], np.abs(np.diff(t) - dt) < dt / 2])
    if not (finite & advancing).all():
        step = int(np.argmin(finite & advancing))
        raise Unstable(method, step * dt, step, "non-finite or huge state; MuJoCo reset the simulation"
                       if finite[step] else "state is not finite")
    # Work of the prescribed motions: drive power at every step, Simpson's rule (error ~ dt^4).
    if work:
        power = np.array([model.drive_power(ti, qi, vi) for ti, qi, vi in zip(t, q, v)])
        work = cumulative_simpson(power, x=t, initial=0.0)
    else:
        work = np.zeros(len(t))
    every = int(round((grid[1] - grid[0]) / dt))
    keep = slice(None, None, every)
    # Index by the nominal output times: MuJoCo accumulates time step by step, so its clock
    # differs from the grid by rounding, and trajectories are compared time by time.
    assert np.allclose(t[keep], grid, rtol=0, atol=dt / 2), "output_step must be a multiple of dt"
    return grid, q[keep], v[keep], work[keep], {
        "wall": run["wall"], "evaluations": run["evaluations"], "steps": run["steps"],
        "driven_rate_error": run["driven_rate_error"]}


def _frame(model, t, q, v, work, attrs):
    columns = {}
    for i, name in enumerate(model.coords):
        columns[name] = q[:, i]
        columns[name + "_rate"] = v[:, i]
    reactions = [model.reactions(ti, qi, vi) for ti, qi, vi in zip(t, q, v)]
    for name in model.reaction_names:
        columns[name] = [r[name] for r in reactions]
    columns["energy"] = [model.energy(ti, qi, vi) for ti, qi, vi in zip(t, q, v)]
    columns["work"] = work
    frame = pd.DataFrame(columns, index=pd.Index(t, name="t"))
    frame.attrs.update(attrs)
    return frame
