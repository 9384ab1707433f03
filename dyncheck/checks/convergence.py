"""The convergence check: the observed order of every fixed-step method (`convergence`), and the case file's
[work_precision] table it shares with the work-precision sweep (`settings`, dyncheck.studies.work_precision)."""

import math

import numpy as np

from dyncheck.case.schema import MAX_OUTPUTS
from dyncheck.common import ceilings
from dyncheck.common.ceilings import LEAST_RTOL, MAX_STEPS, ROUNDING_FLOOR
from dyncheck.common.derivatives import jacobian, scales_of
from dyncheck.results.values import Status, no_number, row
from dyncheck.run.simulate import (FIXED_METHODS, METHODS, MUJOCO_METHODS, SCIPY_METHODS, Unstable, fastest_frequency,
                                   run_wall, simulate, state_columns)

EXPECTED_ORDER = {name: method.order for name, method in METHODS.items() if method.order}  # the fixed steps
SWEEP_METHODS = {"reference": SCIPY_METHODS + FIXED_METHODS, "pinocchio": SCIPY_METHODS, "mujoco": MUJOCO_METHODS}
KEYS = ("t_end", "output_step", "repeat", "repeat_under", "why", "solution", "sweep", "convergence")
CONVERGENCE_KEYS = ("omega", "omega_t", "omega_h", "why")
OPTIONAL_KEYS = ("method_omega",)
MAX_REPEAT = 100  # timed repetitions of a quick run (under repeat_under seconds in all)


# -- the case file's [work_precision] table ---------------------------------------------------------

def settings(case):
    """The case's [work_precision] table, checked (ValueError names the file and the field); None
    for a case without one (nothing to integrate)."""
    spec = case.spec.get("work_precision")
    if spec is None:
        return None

    def fail(field, why):
        raise ValueError(f"{case.origin}: work_precision.{field} {why}")

    def positive(field, x):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not 0 < x < math.inf:
            fail(field, f"= {x!r} must be a positive finite number")
        return float(x)

    def within(field, x, count, limit, what):  # the bounds of a run's size (schema.MAX_OUTPUTS, ceilings.MAX_STEPS)
        if count > limit:
            fail(field, f"= {x:g} asks for {count:.3g} {what}, more than the {limit:.0e} a run allows")

    def multiple(field, step, of):
        if abs(of / step - round(of / step)) > 1e-9 * of / step:
            fail(field, f"= {step:g} must divide {of:g} s (outputs and horizons fall on steps)")

    def honoured(field, rtol):  # scipy raises a smaller rtol to LEAST_RTOL: the point would not be the one it says
        if rtol < LEAST_RTOL:
            fail(field, f"= {rtol:g} is below {LEAST_RTOL:.3g}, the least rtol scipy's integrators honour "
                        "(dyncheck.common.ceilings.LEAST_RTOL)")
        return rtol

    for table, keys, field in ((spec, KEYS, ""), (spec.get("convergence", {}), CONVERGENCE_KEYS, "convergence.")):
        for key in (set(keys) ^ set(table)) - set(OPTIONAL_KEYS):
            fail(field + key, "is missing" if key in keys else
                 f"is not a known key; expected {', '.join(keys + OPTIONAL_KEYS)}")
    out = {key: positive(key, spec[key]) for key in ("t_end", "output_step", "repeat_under")}
    if not isinstance(spec["repeat"], int) or not 1 <= spec["repeat"] <= MAX_REPEAT:
        fail("repeat", f"= {spec['repeat']!r} must be an integer from 1 to {MAX_REPEAT}")
    out["repeat"] = spec["repeat"]
    multiple("output_step", out["output_step"], out["t_end"])
    within("output_step", out["output_step"], out["t_end"] / out["output_step"], MAX_OUTPUTS, "output rows per run")
    out["solution"] = {key: positive(f"solution.{key}", spec["solution"].get(key)) for key in ("rtol", "max_step")}
    honoured("solution.rtol", out["solution"]["rtol"])
    within("solution.max_step", out["solution"]["max_step"], out["t_end"] / out["solution"]["max_step"], MAX_STEPS,
           "steps")
    out["sweep"] = {}
    for source, methods in spec["sweep"].items():
        if source not in SWEEP_METHODS:
            fail(f"sweep.{source}", f"is not a source of the sweep ({', '.join(SWEEP_METHODS)})")
        for method, values in methods.items():
            field = f"sweep.{source}.{method}"
            if method not in SWEEP_METHODS[source]:
                fail(field, f"is not a method of the sweep; {source} runs {', '.join(SWEEP_METHODS[source])}")
            values = [positive(field, x) for x in values]
            if method in SCIPY_METHODS:
                values = [honoured(field, rtol) for rtol in values]
            else:
                for dt in values:
                    multiple(field, dt, out["output_step"])
                    within(field, dt, out["t_end"] / dt, MAX_STEPS, "steps")
            out["sweep"].setdefault(source, {})[method] = values
    # The convergence runs are set in units of the scene's fastest frequency omega (an expression of
    # the parameters), so that they stay in the asymptotic range, and as cheap, when a parameter is
    # overridden: step h = omega_h / omega, horizon the whole number of steps nearest omega_t / omega.
    # A method that integrates other coordinates may see another fastest motion (`method_omega`: MuJoCo's
    # quaternions turn with the body's angular velocity, where the Euler angles see its nutation).
    conv = spec["convergence"]
    omega_t = positive("convergence.omega_t", conv["omega_t"])
    method_omega = conv.get("method_omega", {})
    if not isinstance(method_omega, dict) or set(method_omega) - set(conv["omega_h"]):
        fail("convergence.method_omega", f"= {method_omega!r} must be a table of methods of convergence.omega_h")
    out["convergence"] = {"steps": {}}
    for method, omega_h in conv["omega_h"].items():
        if method not in EXPECTED_ORDER:
            fail(f"convergence.omega_h.{method}", f"is not a fixed-step method ({', '.join(EXPECTED_ORDER)})")
        positive(f"convergence.omega_h.{method}", omega_h)
        within(f"convergence.omega_h.{method}", omega_h, 4 * omega_t / omega_h, MAX_STEPS, "steps (at h/4)")
        field = f"convergence.method_omega.{method}" if method in method_omega else "convergence.omega"
        omega = case.value(method_omega.get(method, conv["omega"]), f"work_precision.{field}")
        if not omega > 0:  # parameters may leave nothing to converge (g = 0): convergence() says so in a row
            out["convergence"]["steps"][method] = (None, None, omega)
            continue
        h = omega_h / omega
        out["convergence"]["steps"][method] = (h, max(1, round(omega_t / omega_h)) * h, omega)
    return out


# -- convergence ----------------------------------------------------------------------------------

class NoFrequency(ValueError):
    """The parameters give the scene no frequency (omega = 0: two pendulums without gravity), so the convergence
    study has no steps: not applicable where nothing moves (released from rest), a failure where something does."""


def convergence(case):
    """The observed order of every fixed-step method of the case file's [work_precision.convergence]:
    check rows (check "convergence", quantity the method, error |observed - expected order|).

    Observed order: runs at h, h/2, h/4 from the book's initial conditions over a short horizon T,
    p = log2(D1 / D2) with D1 = |x_h - x_h/2|, D2 = |x_h/2 - x_h/4|, each the largest difference
    over the trajectory (at 50 or more of the coarsest run's steps) and the state coordinates,
    relative to the coordinate's largest magnitude (rates: the largest of the rates of its unit).  Over the trajectory, not at the final state: the error of one
    instant can pass near zero and bend the ratio (measured: RK4 on the book's chaotic example shows 5.05
    at the final state and 3.89 over the trajectory, 4.00 and 3.94 at halved steps).

    Tolerance, from the error expansion x_h - x = h^p e_p + h^(p+1) e_(p+1) + ...:
    D1 / D2 = 2^p (1 + c rho h) / (1 + c rho h / 2), c = (1 - 2^-(p+1)) / (1 - 2^-p) <= 1.5, with
    rho = |e_(p+1) / e_p|, so the observed order is off by about c rho h / (2 ln 2) <= 1.1 rho h.
    The next term carries one more factor of the fastest frequency omega of the scene than the
    leading one, and where the error accumulates over the horizon (the Eulers' growing amplitude)
    one more factor omega T, so rho <= omega (1 + omega T) and the allowed deviation is
    omega h (1 + omega T), omega from the case file (measured over the four cases: 0.02 to 0.45 of
    it, halving with h as the expansion says).  Steps are chosen to keep it at most 0.25 at omega (an order
    off by one fails fourfold); a faster motion raises it (below), to the ceiling of 0.5.  Differences at
    rounding level would make p meaningless, so a setup whose D2 is under ROUNDING_FLOOR raises instead of
    reporting.

    The argument needs a frequency that bounds the motion's, and the case's omega is one linearisation's, at one state;
    the motion's own (`motion_frequency`, the spectral radius of the state Jacobian along the reference's run) can be
    faster: its rates feed the equations' velocity terms, and away from an equilibrium its configuration is stiffer or
    softer.  The more joints, the further a start can be from an equilibrium: from 0.5 rad on every joint a chain of one
    link reaches 1.07 times its omega within the horizon, of 3 to 9 links 2.1 to 2.3 times; 3 links from 2 rad on each
    reach 4 times omega (where the horizon ends, below), and their explicit Euler deviated by 0.046 where omega h (1 +
    omega T) allowed 0.027 (from (3, 1, 1) rad, 0.134 against 0.034; 0.136 is allowed now: an estimate, not a bound with
    room to spare).  So the allowance's frequency is Omega, the mean over the horizon of omega or the motion's frequency
    where that is faster: the factor omega T of the error's growth is the motion's frequency integrated over the
    horizon, and the next term's factor of a frequency is each local error's, summed over it. With the largest frequency
    instead, the two pendulums' RK4 (their motion passes 2.6 omega for instants, 1.22 omega on average) would be
    inconclusive.  Where the motion outruns omega more than OUTRUN times, the horizon ends before, and the row says
    where: a top with Izz = Ixx / 4 under g = 1 m/s^2 passes 0.003 rad from its Euler angles' singularity 0.24 s in,
    where the frequency of its Euler-angle equations passes 600 rad/s against the case's 11.5, and RK4 at the case's
    step blew up; before 0.198 s it shows order 3.92."""
    wp = settings(case)
    if wp is None:
        return []
    q0, v0, _ = case.initial
    columns = state_columns(case)
    units = dict(zip(case.coords, case.spec["coord_units"]))
    steps = wp["convergence"]["steps"]
    if any(omega == 0 for _, _, omega in steps.values()):
        raise NoFrequency("the case's fastest frequency omega (work_precision.convergence.omega) is 0 at these "
                          "parameters, and the study's steps h = omega_h / omega follow from it")
    for method, (_, _, omega) in steps.items():
        if not omega > 0:
            raise ValueError(f"{case.origin}: work_precision.convergence: omega = {omega!r} for {method} must be a "
                             "positive number (the fastest frequency it integrates, with these parameters)")
    times, frequency = motion_frequency(case, max(t_end for _, t_end, _ in steps.values()))
    rows = []
    for method, (h, t_end, omega) in steps.items():
        source = "mujoco" if method in MUJOCO_METHODS else "reference"
        outrun = (times <= t_end) & (frequency > OUTRUN * omega)
        cut = ""
        if outrun.any():
            first = times[np.argmax(outrun)]
            cut = (f"; the horizon ends before {first:.3g} s, where the motion's frequency passes {OUTRUN:g} omega "
                   f"(to {frequency[times <= t_end].max():.3g} rad/s within {t_end:.3g} s)")
            t_end = math.floor(first / h) * h
            if t_end < MIN_STEPS * h:
                rows.append(no_number("convergence", method, (source,), f"not measured: within {MIN_STEPS} steps of "
                                      f"h = {h:.3g} s{cut}", Status.INCONCLUSIVE))
                continue
        model = case.model(source)
        # Compare at least 50 instants on the coarsest run's steps (every one of fewer), not every one of them:
        # each output costs a frame row; the states are all these runs give (no reactions, no energy).
        n = round(t_end / h)
        every = max(k for k in range(1, max(1, n // 50) + 1) if n % k == 0)
        try:
            runs = [simulate(model, (q0, v0), t_end, method, dt=h / 2**i, output_step=every * h,
                             work=False, quantities=(), wall=run_wall(case))[columns] for i in range(3)]
        except Unstable as failure:
            rows.append(no_number("convergence", method, (source,), failure))
            continue
        scale = runs[2].abs().max()
        # Rates of one unit share one scale, the largest of them: a rate that stays near zero over the short
        # horizon (a top's nutation rate beside its spin) would otherwise be judged by its own size, where it
        # carries only the leak of the whole angular velocity's error through the coordinate map.
        for unit in set(units.values()):
            rates = [f"{name}_rate" for name, its in units.items() if its == unit]
            scale[rates] = scale[rates].max()
        d1, d2 = ((runs[i] - runs[i + 1]).abs().max().div(scale).max() for i in range(2))
        if not d2 > ROUNDING_FLOOR:
            raise ValueError(f"{case.origin}: work_precision.convergence.omega_h.{method} gives h = {h:g} s: the runs at "
                             f"h/2 and h/4 differ by {d2:.1e}, within rounding ({ROUNDING_FLOOR:.1e}); choose a larger step")
        observed = math.log2(d1 / d2)
        expected = EXPECTED_ORDER[method]
        along = np.maximum(omega, frequency[times <= t_end]).mean()  # Omega: omega, or the motion's where faster
        rows.append(row("convergence", method, (source,), abs(observed - expected), along * h * (1 + along * t_end),
                        f"observed order {observed:.3f} (expected {expected}) from dt = {h:g}, {h / 2:g}, "
                        f"{h / 4:g} s over {t_end:g} s; differences {d1:.2e}, {d2:.2e}; allowed "
                        f"Omega h (1 + Omega T) with Omega = {along:.4g} rad/s, the case's omega = {omega:g} rad/s or "
                        f"the motion's frequency where faster, over the horizon{cut}", ceiling=ceilings.CONVERGENCE))
    return rows


# The argument above needs omega to bound the motion's frequency.  Measured as the spectral radius of the
# state Jacobian along the reference's motion, the book's cases reach 0.68 to 1.15 of the case's omega, and the
# two pendulums' chaotic swings 2.6 of it for instants, where the orders are observed as the argument says.  A top
# passing 0.003 rad from its Euler angles' singularity (Izz = Ixx / 4, g = 1 m/s^2) passes 50 times its
# omega there, and RK4 at the case's step blew up: the horizon ends where the motion passes OUTRUN omega.
OUTRUN = 4.0
MIN_STEPS = 20  # the fewest steps of h a convergence run's horizon may hold
MOTION_POINTS = 50  # the instants of the reference's motion whose frequency is measured


def motion_frequency(case, t_end):
    """The reference's motion from the book's start over [0, t_end] (DOP853 at the case's rtol): MOTION_POINTS + 1
    times, and at each the spectral radius of the state Jacobian [[0, I], [dq''/dq, dq''/dq']] (the vibration
    analysis's differences): the local frequency, from rest or not, which a coordinate singularity makes large.
    Zero where the run fails (the convergence runs then say how)."""
    q0, v0, _ = case.initial
    model = case.model("reference")
    n = len(q0)
    try:
        run = simulate(model, (q0, v0), t_end, "DOP853", rtol=case.integration["rtol"],
                       output_step=t_end / MOTION_POINTS, work=False, omega=fastest_frequency(case), quantities=(),
                       wall=run_wall(case))
    except Unstable:
        return np.array([0.0]), np.array([0.0])
    states = run[state_columns(case)].to_numpy()[:, np.r_[0:2 * n:2, 1:2 * n:2]]  # (q, q') per instant
    radius = []
    with np.errstate(all="ignore"):
        for t, x in zip(run.index, states):
            acc = lambda y: np.asarray(model.accelerations(t, y[:n], y[n:]), dtype=float)
            state_matrix = np.block([[np.zeros((n, n)), np.eye(n)], [jacobian(acc, x, scales_of(x))[0]]])
            radius.append(np.max(np.abs(np.linalg.eigvals(state_matrix))) if np.all(np.isfinite(state_matrix))
                          else np.inf)
    return run.index.to_numpy(), np.array(radius)
