"""The agreement horizon of two sources (`agreement_horizon`, for the trajectory check): how long two runs that
differ by the integrators' error can be expected to agree, from the amplification of a difference along the book's
initial conditions; and the Benettin separation of two copies, which the Lyapunov study shares
(dyncheck.studies.stability.long_runs)."""

import math
import time

import numpy as np
import scipy  # scipy.integrate on first use (as in dyncheck.run.simulate)

from dyncheck.case.folder import settings_of
from dyncheck.run.simulate import Unstable, attempt, describe


def state_weights(case):
    """Weights of the state (coordinates, rates) in the distance: rates divided by the case's
    [stability.lyapunov] rate_scale (a frequency of the motion, so that both halves count alike)."""
    n = len(case.coords)
    rate_scale = settings_of(case, "lyapunov")["rate_scale"]
    return np.concatenate([np.ones(n), np.full(n, 1.0 / rate_scale)])


def copies_rhs(model, n, copies):
    def rhs(t, y):
        out = np.empty_like(y)
        for c in range(copies):
            s = y[c * 2 * n:(c + 1) * 2 * n]
            out[c * 2 * n:c * 2 * n + n] = s[n:]
            out[c * 2 * n + n:(c + 1) * 2 * n] = model.accelerations(t, s[:n], s[n:])
        return out
    return rhs


def benettin(case, q0, v0, horizon, renormalise, d0, rtol):
    """Largest finite-time Lyapunov exponent by two neighbouring trajectories (Benettin): the neighbour
    is pulled back to distance d0 every `renormalise` seconds and the logarithms of the stretches are
    summed.  Returns times and ln(stretch) accumulated (lambda(t) = that / t)."""
    model = case.model("reference")
    n = len(case.coords)
    scale = state_weights(case)
    x = np.concatenate([q0, v0]).astype(float)
    u = np.ones(2 * n) / scale
    u *= d0 / np.linalg.norm(u * scale)
    y = np.concatenate([x, x + u])
    rhs = copies_rhs(model, n, 2)
    steps = int(round(horizon / renormalise))
    times, logs, total = [0.0], [0.0], 0.0
    for i in range(steps):
        sol = scipy.integrate.solve_ivp(rhs, (i * renormalise, (i + 1) * renormalise), y, method="DOP853", rtol=rtol,
                                        atol=rtol * 1e-2)
        if sol.status != 0 or not np.all(np.isfinite(sol.y)):
            raise Unstable("DOP853", sol.t[-1], i, sol.message)
        y = sol.y[:, -1].copy()
        dx = y[2 * n:] - y[:2 * n]
        dist = np.linalg.norm(dx * scale)
        total += math.log(dist / d0)
        y[2 * n:] = y[:2 * n] + dx * (d0 / dist)
        times.append((i + 1) * renormalise)
        logs.append(total)
    return np.array(times), np.array(logs)


def amplification(case, horizon, rtol, delta=1e-7, points=200):
    """The largest singular value of the state-transition matrix along the book's initial conditions,
    by finite differences (one neighbour per state direction, in the scaled state), at `points` times."""
    model = case.model("reference")
    n = len(case.coords)
    scale = state_weights(case)
    q0, v0, _ = case.initial
    x = np.concatenate([q0, v0]).astype(float)
    y0 = np.concatenate([x] + [x + delta * e / scale for e in np.eye(2 * n)])
    grid = np.linspace(0.0, horizon, points + 1)
    sol = scipy.integrate.solve_ivp(copies_rhs(model, n, 2 * n + 1), (0.0, horizon), y0, method="DOP853", rtol=rtol,
                                    atol=rtol * 1e-2, t_eval=grid)
    if sol.status != 0:
        raise Unstable("DOP853", sol.t[-1], len(sol.t), sol.message)
    y = sol.y.reshape(2 * n + 1, 2 * n, -1)
    phi = (y[1:] - y[0]) * scale[None, :, None] / delta  # [direction, component, time]
    sigma = np.array([np.linalg.svd(phi[:, :, i], compute_uv=False)[0] for i in range(phi.shape[2])])
    return sol.t, sigma


def agreement_horizon(case):
    """How long two sources can be expected to agree: (horizon in s, details).

    Two sources that integrate the same motion differ by about eps0 (the integrators' error level,
    relative, [stability.lyapunov] eps0) early on; a difference grows with the motion's sensitivity
    to its initial state, the largest singular value sigma(t) of the state-transition matrix along the
    book's initial conditions.  The horizon is the first t with eps0 sigma(t) = tol (the difference
    beyond which a trajectory comparison tests the chaos, not the equations).  If that lies beyond the
    case's horizon t_end, it is extrapolated with the finite-time exponent ln sigma(t_end) / t_end
    (an overestimate of the growth for a regular motion, so the horizon is on the safe side).
    A case without [stability.lyapunov] has no limit: (inf, {...})."""
    t_end = case.initial[2]
    spec = case.spec.get("stability", {}).get("lyapunov")
    if spec is None:
        return math.inf, {"t_end": t_end, "within": True,
                          "sentence": "no agreement horizon: the case declares no [stability.lyapunov]"}
    s = settings_of(case, "lyapunov")
    eps0, tol = s["eps0"], s["tol"]
    start = time.perf_counter()
    result, fail = attempt(lambda: amplification(case, t_end, s["check_rtol"], delta=1e-6))
    if fail is not None:
        return t_end, {"t_end": t_end, "within": True, "eps0": eps0, "tol": tol,
                       "sentence": f"amplification not computed ({describe(fail)}); the case's horizon is kept"}
    t, sigma = result
    ftle = math.log(sigma[-1]) / t_end
    reached = np.nonzero(eps0 * sigma >= tol)[0]
    if reached.size:
        i = reached[0]
        horizon = float(t[i])
    else:
        horizon = t_end + (math.log(tol / (eps0 * sigma[-1])) / ftle if ftle > 0 else math.inf)
    within = horizon >= t_end
    sentence = (f"a difference of {eps0:g} grows by {sigma[-1]:.3g} over the case's {t_end:g} s (finite-time "
                f"exponent {ftle:.3g} 1/s), to {eps0 * sigma[-1]:.2g}; it reaches {tol:g} at "
                + (f"t = {horizon:.3g} s" if math.isfinite(horizon) else "no time")
                + (f": the case's {t_end:g} s lie within the agreement horizon" if within
                   else f": sources can be compared only up to {horizon:.3g} s"))
    return horizon, {"t_end": t_end, "within": within, "eps0": eps0, "tol": tol, "amplification": float(sigma[-1]),
                     "ftle": ftle, "horizon": horizon, "wall": time.perf_counter() - start, "sentence": sentence}
