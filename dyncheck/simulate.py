"""Time integration of a model in the book's coordinates; a trajectory is a DataFrame indexed by time."""

import time

import numpy as np
import pandas as pd
from scipy.integrate import cumulative_simpson, solve_ivp

SCIPY_METHODS = ("RK45", "DOP853", "Radau", "LSODA")
FIXED_METHODS = ("explicit Euler", "semi-implicit Euler", "RK4")  # the book's programs use the Eulers
MUJOCO_METHODS = ("mujoco:Euler", "mujoco:implicitfast", "mujoco:RK4")
METHODS = SCIPY_METHODS + FIXED_METHODS + MUJOCO_METHODS


class Unstable(Exception):
    """An integration that blew up: when, which method, which step."""

    def __init__(self, method, t, step, why):
        super().__init__(f"{method} unstable at t = {t:.6g} s (step {step}): {why}")
        self.method, self.t, self.step, self.why = method, t, step, why


def simulate(model, ic, t_end, method, *, rtol=None, dt=None, output_step, work=True, max_step=np.inf):
    """Integrate `model` from ic = (q0, v0) over [0, t_end].

    method: one of SCIPY_METHODS (driven by model.accelerations, with tolerance `rtol` and steps of at
    most `max_step`),
    FIXED_METHODS (driven by model.accelerations at step `dt`: the explicit Euler of the book's
    Matlab program, the semi-implicit Euler of its Pascal programs, classical RK4), or
    MUJOCO_METHODS (MuJoCo's own mj_step at step `dt`; the model must be a MujocoModel).
    Returns a DataFrame indexed by t: coordinates, their rates, reactions, energy, and the work
    of the prescribed motions and applied forces so far (`work`; pass work=False for a scene where
    nothing does work, to skip the drive power), with the cost in `.attrs`.
    """
    q0, v0 = (np.asarray(x, dtype=float) for x in ic)
    n_out = int(round(t_end / output_step))
    grid = np.linspace(0.0, t_end, n_out + 1)
    if method in SCIPY_METHODS:
        t, q, v, w, cost = _scipy(model, q0, v0, grid, method, rtol, work, max_step)
    elif method in FIXED_METHODS:
        t, q, v, w, cost = _fixed(model, q0, v0, grid, method, dt, work)
    elif method in MUJOCO_METHODS:
        t, q, v, w, cost = _mujoco(model, q0, v0, grid, method, dt, work)
    else:
        raise ValueError(f"unknown method '{method}'; methods are {', '.join(METHODS)}")
    return _frame(model, t, q, v, w, {"method": method, "rtol": rtol, "dt": dt, **cost})


def _scipy(model, q0, v0, grid, method, rtol, work, max_step):
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
                        t_eval=grid, rtol=rtol, atol=rtol, max_step=max_step)
    wall = time.perf_counter() - start
    if sol.status != 0 or not np.all(np.isfinite(sol.y)):
        bad = sol.t[-1] if sol.t.size else grid[0]
        raise Unstable(method, float(bad), len(sol.t), sol.message)
    y = sol.y.T
    return sol.t, y[:, :n], y[:, n:2 * n], y[:, -1], {"wall": wall, "evaluations": evaluations}


def _fixed(model, q0, v0, grid, method, dt, work):
    """Fixed-step integration; the work W' = P rides along with the scheme's own update."""
    every = int(round((grid[1] - grid[0]) / dt))
    nstep = every * (len(grid) - 1)
    n = len(q0)
    evaluations = 0

    def rates(t, q, v):
        nonlocal evaluations
        evaluations += 1
        return model.accelerations(t, q, v), (model.drive_power(t, q, v) if work else 0.0)

    def derivative(t, y):
        acc, power = rates(t, y[:n], y[n:2 * n])
        return np.concatenate([y[n:2 * n], acc, [power]])

    q, v, w = q0.copy(), v0.copy(), 0.0
    out_q, out_v, out_w = [q.copy()], [v.copy()], [w]
    start = time.perf_counter()
    with np.errstate(all="ignore"):
        for i in range(nstep):
            t = i * dt
            if method == "RK4":
                y = np.concatenate([q, v, [w]])
                k1 = derivative(t, y)
                k2 = derivative(t + dt / 2, y + dt / 2 * k1)
                k3 = derivative(t + dt / 2, y + dt / 2 * k2)
                k4 = derivative(t + dt, y + dt * k3)
                y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
                q, v, w = y[:n], y[n:2 * n], y[-1]
            else:
                acc, power = rates(t, q, v)
                v_new = v + dt * acc
                q = q + dt * (v_new if method == "semi-implicit Euler" else v)
                v, w = v_new, w + dt * power
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
                raise Unstable(method, (i + 1) * dt, i + 1, "state is not finite")
            if (i + 1) % every == 0:
                out_q.append(q.copy())
                out_v.append(v.copy())
                out_w.append(w)
    wall = time.perf_counter() - start
    return grid, np.array(out_q).reshape(len(grid), n), np.array(out_v).reshape(len(grid), n), np.array(out_w), \
        {"wall": wall, "evaluations": evaluations, "steps": nstep}


def _mujoco(model, q0, v0, grid, method, dt, work):
    run = model.step(q0, v0, grid[-1], dt, method.split(":")[1])
    t, q, v = run["t"], run["q"], run["v"]
    check_mujoco_run(run, method, dt)
    # Work of the prescribed motions: drive power at every step, Simpson's rule (error ~ dt^4).
    if work:
        work = cumulative_simpson(model.drive_powers(t, q, v), x=t, initial=0.0)
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


def check_mujoco_run(run, method, dt, bound=None):
    """Raise Unstable at the first step of a MujocoModel.step run that is not finite, that MuJoCo reset,
    or (with `bound` = (coordinate name, its index, limit)) whose coordinate is beyond the limit; or,
    for a run with a MuJoCo warning but no reset, at its end."""
    t, q, v = run["t"], run["q"], run["v"]
    # MuJoCo answers a blow-up (NaN, Inf or |qvel| > 1e10) by resetting the state and the clock
    # to their initial values, silently for a rollout: a clock that stops advancing by dt marks it.
    finite = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(v), axis=1)
    advancing = np.concatenate([[True], np.abs(np.diff(t) - dt) < dt / 2])
    inside = np.ones(len(t), dtype=bool)
    if bound is not None:
        _, index, limit = bound
        inside = np.abs(np.where(finite, q[:, index], np.inf)) <= limit
    warned = "; ".join(f"MuJoCo warning {name} ({number} time{'s' if number > 1 else ''}, last with info {info})"
                       for name, (number, info) in run["warnings"].items())
    good = finite & advancing & inside
    if not good.all():
        step = int(np.argmin(good))
        if not finite[step]:
            why = "state is not finite"
        elif not advancing[step]:
            why = (warned or "non-finite or huge state") + "; MuJoCo reset the simulation"
        else:
            name, index, limit = bound
            why = f"|{name}| = {abs(q[step, index]):.3g} beyond {limit:g}"
        raise Unstable(method, step * dt, step, why)
    if warned:  # a warning without a reset: the run is not to be trusted either
        raise Unstable(method, t[-1], run["steps"], warned)


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
