"""Time integration of a model in the book's coordinates; a trajectory is a DataFrame indexed by time."""

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy  # scipy.integrate and .optimize as attributes, which scipy imports on first use: runs need
#               them, the checks at states (`run --quick`) not, and their import is 0.3 s

from dyncheck.common.ceilings import MAX_STEPS
from dyncheck.results import store
from dyncheck.results.values import Failure, Status


def failure(error):
    """An integration that blew up (or spent its budget), as data: {status, t, step, why}."""
    if isinstance(error, Unstable):
        step = None if error.step is None else int(error.step)  # None: in a run's outputs
        return {"status": str(error.status), "t": float(error.t), "step": step, "why": str(error.why)}
    return {"status": "unstable", "t": None, "step": None, "why": f"{type(error).__name__}: {error}"}


def attempt(run):
    """(result, None) or (None, failure): a blow-up is recorded, never raised."""
    try:
        with np.errstate(all="ignore"):
            return run(), None
    except (Unstable, ArithmeticError, np.linalg.LinAlgError) as error:
        return None, failure(error)


def describe(fail):
    """'unstable at t = 0.31 s (step 62): why' for a failure dict."""
    if fail is None:
        return "ran"
    when = f" at t = {fail['t']:.4g} s" if fail.get("t") is not None else ""
    step = f" (step {fail['step']})" if fail.get("step") is not None else ""
    return f"{fail['status']}{when}{step}: {fail['why']}"


@dataclass(frozen=True)
class Method:
    """An integration method as case files and pages name it, and who steps it."""
    name: str
    stepper: str  # "scipy": adaptive, to a tolerance rtol; "python": fixed step dt, stepped here; "mujoco": fixed
    #               step dt, MuJoCo's own integrator stepping its own scene
    engine_name: str  # the stepper's name for it: scipy's solver, MuJoCo's integrator
    evaluations: int = 1  # right-hand sides per step (fixed steps)
    order: int = 0  # a fixed step's order: the run's error goes as C dt^order (0: adaptive, to rtol)


METHODS = {m.name: m for m in (
    Method("RK45", "scipy", "RK45"), Method("DOP853", "scipy", "DOP853"), Method("Radau", "scipy", "Radau"),
    Method("LSODA", "scipy", "LSODA"),
    Method("explicit Euler", "python", "explicit Euler", order=1),  # the book's programs use the Eulers
    Method("semi-implicit Euler", "python", "semi-implicit Euler", order=1),
    Method("RK4", "python", "RK4", evaluations=4, order=4),
    Method("mujoco:Euler", "mujoco", "Euler", order=1), Method("mujoco:implicitfast", "mujoco", "implicitfast", order=1),
    Method("mujoco:RK4", "mujoco", "RK4", order=4))}
SCIPY_METHODS, FIXED_METHODS, MUJOCO_METHODS = (tuple(n for n, m in METHODS.items() if m.stepper == stepper)
                                                for stepper in ("scipy", "python", "mujoco"))
LANDING = ("RK45", "DOP853", "Radau")  # the solvers that read their t_bound afresh at every step (LSODA's Fortran does not)


class Unstable(Exception):
    """An integration that blew up: when, which method, which step."""

    def __init__(self, method, t, step, why):
        # step None: the failure is in the outputs of a run, between steps
        self.method, self.t, self.step, self.why = method, t, step, why
        super().__init__(str(self.failure))

    kind = Failure  # what `failure` makes of it

    @property
    def failure(self):
        """The blow-up as a value, for the results."""
        return self.kind(self.method, None if self.t is None else float(self.t),
                         None if self.step is None else int(self.step), str(self.why))

    @property
    def status(self):
        """The status of the rows the run would have given."""
        return self.kind.status


@store.register
class Escape(Failure):
    """A run stopped where its coordinate left the bound it was given (simulate's `bound`): the state
    was still finite there, so this is not a numerical failure unless the physics says it cannot be."""

    def __str__(self):
        return f"{self.method} escaped at t = {self.t:.6g} s (step {self.step}): {self.why}"


class Escaped(Unstable):
    """A run whose coordinate left its bound (simulate's `bound`)."""
    kind = Escape


@store.register
class Spent(Failure):
    """A run stopped where it spent its wall-time budget (Budget): it went as far as the time allowed, its state
    finite; not a failure of the equations (a loaded machine, an evaluation costlier than it was measured)."""
    status = Status.SPENT

    def __str__(self):
        return f"{self.method} stopped at t = {self.t:.6g} s (step {self.step}): {self.why}"


class OverBudget(Unstable):
    """A run past its wall-time budget (Budget)."""
    kind = Spent


def check_bound(bound, method, t, step, q):
    """Raise Escaped when q[index] is beyond +-limit, for bound = (coordinate name, index, limit) (None:
    no bound)."""
    if bound is not None:
        name, index, limit = bound
        if abs(q[index]) > limit:
            raise Escaped(method, t, step, f"|{name}| = {abs(q[index]):.6g} beyond {limit:g}")


def finite(values):
    """Whether every value is finite."""
    return _finite_numbers(_floats(values))


def _floats(values):
    """`values` (any shape) as a flat list of Python floats: what the integrators step and test."""
    return np.asarray(values, dtype=float).ravel().tolist()


def _finite_numbers(numbers):
    """Whether every number of a list of floats is finite.  On the few numbers of a state, which the integrators
    test at every step, Python's sum is several times quicker than numpy's reduction: a NaN or an infinity among
    them makes the sum NaN or infinite (inf - inf is NaN), so a finite sum answers for all of them, and only a sum
    that is not (a number that is not finite, or finite ones whose sum overflows) has them looked at one by one."""
    return math.isfinite(sum(numbers)) or all(map(math.isfinite, numbers))


def state_columns(case):
    """A trajectory's state columns in the book's order: each coordinate, then its rate."""
    return [c for name in case.coords for c in (name, name + "_rate")]


def richardson_factor(method, step, twin_step):
    """What |x(step) - x(twin_step)|, the difference between a run of a fixed-step `method` and its twin, is
    multiplied by to estimate the run's error, the method's error going as C step^order (Richardson):
    1 / |(twin_step / step)^order - 1|.  RK4: 16/15 with the twin at half the step, 1/15 at twice it; a first-order
    method: 2 and 1."""
    return 1 / abs((twin_step / step) ** METHODS[method].order - 1)


def energy_residual(run):
    """E(t) - E(0) - W(t): zero for exact dynamics (W = 0 when nothing is driven)."""
    return run["energy"] - run["energy"].iloc[0] - run["work"]


# -- budgets: no integration runs unbounded --------------------------------------------------------
# An adaptive method's step controller keeps the local error of its estimator, ~ (omega h)^(p+1) for an
# estimator of order p on a motion of frequency omega, near rtol (atol = rtol here): omega h ~ rtol^(1/(p+1)),
# so a run over T takes about omega T / rtol^(1/(p+1)) steps, and at least T / max_step.  p: scipy's
# error estimators (RK45 4, DOP853 7, Radau 3); LSODA varies its order (Adams 1-12, BDF 1-5): counted as 4.
ERROR_EXPONENT = {"RK45": 5, "DOP853": 8, "Radau": 4, "LSODA": 5}
START_STEPS = 50  # the controller's first steps, which search for the step size
BUDGET_FACTOR = 10  # allowed steps over the expected ones; the 412 adaptive runs of a report take 0.04 to 1.6 of them
# A run's wall time is bounded by what its steps may take at the cost per step of its first MEASURED_STEPS, LOAD times
# over (a loaded machine; a derivation whose calls cost more in some states), and WALL_FLOOR at least: the steps bound
# the work, the wall time what each step of it costs.  A fixed 120 s stopped a 7-dof arm's derivation (2-6 ms an
# evaluation) as if it had blown up.  The book's longest run takes 9 s.
MEASURED_STEPS = 20
LOAD = 4.0
WALL_FLOOR = 10.0  # s


class Budget:
    """How far one integration may go: `steps` steps (`why` says where that number comes from), and `wall` seconds of
    wall time (None: what those steps take at the cost of its first ones, see LOAD); `check` raises Unstable past the
    steps, OverBudget past the time."""

    def __init__(self, method, t_end, steps, why, wall=None):
        self.method, self.t_end, self.steps, self.why = method, t_end, steps, why
        if steps > MAX_STEPS:
            raise Unstable(method, 0.0, 0, f"not started: it needs {why}, beyond the cap of {MAX_STEPS:.0e} steps "
                                           f"for one run")
        self.started = time.perf_counter()
        self.wall, self.spent_on = wall, "case.toml's [budget] run"
        self.deadline = math.inf if wall is None else self.started + wall

    def check(self, t, step):
        if step > self.steps:
            raise Unstable(self.method, t, step, f"gave up after {step} steps at t = {t:.4g} s of {self.t_end:g} s "
                                                 f"(budget: {self.why})")
        now = time.perf_counter()
        if self.wall is None and step >= MEASURED_STEPS:
            cost = (now - self.started) / step
            self.wall = max(WALL_FLOOR, LOAD * self.steps * cost)
            self.spent_on = (f"{LOAD:g} x its {self.steps} steps at {cost * 1e3:.3g} ms each, the cost of its first "
                             f"{step}, at least {WALL_FLOOR:g} s; case.toml's [budget] run sets another")
            self.deadline = self.started + self.wall
        if now > self.deadline:
            raise OverBudget(self.method, t, step, f"spent its budget of {self.wall:.3g} s of wall time "
                                                   f"({self.spent_on}) at step {step}, t = {t:.4g} s of {self.t_end:g} s")


def scipy_budget(method, t_end, rtol, max_step, omega, wall=None):
    """The Budget of an adaptive run: BUDGET_FACTOR times its expected steps (see ERROR_EXPONENT), or
    MAX_STEPS for a scene without a frequency (`omega` None: nothing free moves); `wall` as Budget's."""
    if omega is None:
        return Budget(method, t_end, MAX_STEPS, f"{MAX_STEPS:.0e} steps, the cap for one run", wall)
    expected = START_STEPS + max(omega * t_end / rtol ** (1 / ERROR_EXPONENT[method]), t_end / max_step)
    return Budget(method, t_end, math.ceil(BUDGET_FACTOR * expected),
                  f"{BUDGET_FACTOR} x the {expected:.3g} steps expected from omega = {omega:.4g} rad/s over "
                  f"{t_end:g} s at rtol = {rtol:g}", wall)


QUANTITIES = ("reactions", "energy")  # what a run's frame holds at its outputs beside the state and the work


def fastest_frequency(case):
    """The case's fastest frequency in rad/s (its [work_precision.convergence] omega, an expression of the
    parameters), from which the budget of an adaptive run follows; None for a case without one."""
    omega = case.spec.get("work_precision", {}).get("convergence", {}).get("omega")
    return None if omega is None else abs(case.value(omega, "work_precision.convergence.omega"))


def run_wall(case):
    """The wall time in s that each of the case's runs may take (case.toml's [budget] run), or None: each run's
    own, from its steps and its cost per step (Budget)."""
    return case.spec.get("budget", {}).get("run")


def simulate(model, ic, t_end, method, *, rtol=None, dt=None, output_step, work=True, max_step=np.inf, omega=None,
             bound=None, land_on_outputs=False, quantities=QUANTITIES, wall=None):
    """Integrate `model` from ic = (q0, v0) over [0, t_end].

    method: one of SCIPY_METHODS (driven by model.accelerations, with tolerance `rtol` and steps of at
    most `max_step`, within a budget of steps from the scene's fastest frequency `omega`, see
    scipy_budget; with `land_on_outputs`, a step ends at every output time, so that each output is a step's
    end, where the solver controls its error, rather than read from its dense output between them),
    FIXED_METHODS (driven by model.accelerations at step `dt`: the explicit Euler of the book's
    Matlab program, the semi-implicit Euler of its Pascal programs, classical RK4), or
    MUJOCO_METHODS (MuJoCo's own mj_step at step `dt`; the model must be a MujocoModel).
    Returns a DataFrame indexed by t: coordinates, their rates, reactions, energy (where the model has it), and the work
    of the prescribed motions, applied forces and dampers so far (`work`; pass work=False for a scene where
    nothing does work, to skip the drive power; absent where work is asked of a model without drive_power),
    with the cost in `.attrs`.  `quantities`: which of QUANTITIES the frame holds, fewer for a run of which
    nothing reads them (a twin's reactions, a mode's run): each costs a model call per output.
    Raises Unstable (when, which method, which step) for a run that blows up, whose model's arithmetic
    fails, or that goes past its Budget's steps, OverBudget past its wall time (`wall` s, or None: Budget's
    own); a fixed-step run longer than MAX_STEPS is not started.  With `bound` = (coordinate name, its index,
    limit), raises Escaped at the first step that ends with the coordinate beyond +-limit.
    """
    q0, v0 = (np.asarray(x, dtype=float) for x in ic)
    # A derivation may define no drive power (docs/model-interface.md): its run then has no work column,
    # and its energy balance cannot be drawn up.
    unknown_work = work and not hasattr(model, "drive_power")
    work = work and not unknown_work
    n_out = int(round(t_end / output_step))
    if abs(n_out * output_step - t_end) > 1e-9 * t_end:  # the fixed steps would reach the outputs off their times
        raise ValueError(f"t_end = {t_end!r} s is not a whole number of output steps of {output_step!r} s")
    grid = np.linspace(0.0, t_end, n_out + 1)
    if method in SCIPY_METHODS:
        if land_on_outputs and method not in LANDING:
            raise ValueError(f"{method} cannot land its steps on the outputs; {', '.join(LANDING)} can")
        # landing, a run takes at least a step per output
        budget = scipy_budget(method, t_end, rtol, min(max_step, output_step) if land_on_outputs else max_step, omega,
                              wall)
        t, q, v, w, cost = _scipy(model, q0, v0, grid, method, rtol, work, max_step, budget, bound, land_on_outputs)
    elif method in FIXED_METHODS + MUJOCO_METHODS:
        every = round(output_step / dt)  # steps per output
        if every < 1:
            raise ValueError(f"output_step = {output_step!r} s is shorter than the step dt = {dt!r} s")
        budget = Budget(method, t_end, every * n_out, f"{every * n_out} steps of {dt:g} s", wall)
        run = _fixed if method in FIXED_METHODS else _mujoco
        t, q, v, w, cost = run(model, q0, v0, grid, method, dt, every, work, budget, bound)
    else:
        raise ValueError(f"unknown method '{method}'; methods are {', '.join(METHODS)}")
    return _frame(model, t, q, v, None if unknown_work else w, {"method": method, "rtol": rtol, "dt": dt, **cost},
                  quantities)


def stopwatch():
    """A started clock: calling it gives the wall and the CPU seconds since then (`cpu`: this process's, which
    other processes' load on the machine leaves out; on an idle core the two agree)."""
    wall, cpu = time.perf_counter(), time.process_time()
    return lambda: {"wall": time.perf_counter() - wall, "cpu": time.process_time() - cpu}


def _model_failure(method, t, step, error):
    """The Unstable that a failure in the model (an overflow in its float arithmetic, a singular matrix, any
    error of a case's own code) at time t, step `step`, is raised as: a row that says why, never a traceback."""
    if isinstance(error, (ArithmeticError, np.linalg.LinAlgError)):
        return Unstable(method, t, step, f"the model's arithmetic failed: {type(error).__name__}: {error}")
    return Unstable(method, t, step, f"the model failed: {type(error).__name__}: {error}")


def _arithmetic(method, t, step, call, *args):
    """call(*args), with a failure in the model raised as Unstable at time t, step `step` (_model_failure)."""
    try:
        return call(*args)
    except Exception as error:
        raise _model_failure(method, t, step, error) from None


def _scipy(model, q0, v0, grid, method, rtol, work, max_step, budget, bound, land_on_outputs):
    """scipy's solver stepped here rather than by solve_ivp (the same steps and outputs), so that the
    budget is checked at every step and right-hand side.  A model whose `native` is not None is integrated
    in the engine's own coordinates (`native.state`, `native.rates`) and answered in the book's
    (`native.book`): a ball joint's quaternion and angular velocity have no Euler-angle singularity and
    cost the engine no conversion at each evaluation.  atol = rtol holds for every component as ever: on a
    quaternion's components (at most 1) it bounds a step's rotation error to about 2 atol, where on an Euler
    angle it is atol + rtol |angle|.  The run's error then differs (the book's top at rtol 1e-10: 13 times
    the Euler-angle run's, in a quarter fewer evaluations); its twin at tight_rtol measures it alike.
    `land_on_outputs`: the solver's t_bound (a documented attribute, which these solvers clip every step to)
    is the next output time, moved on, and the solver set running again, each time a step ends there."""
    n = len(q0)
    evaluations = steps = 0
    native = getattr(model, "native", None)

    def rhs(t, y):  # y's rates, the last the work's: the drive power
        nonlocal evaluations
        evaluations += 1
        budget.check(t, steps)
        # The rates as one list made an array: the same floats as np.concatenate, at a fifth of its cost on so
        # few numbers.
        try:
            if native is None:
                q, v = y[:n], y[n:-1]
                acc = _finite(model.accelerations(t, q, v), "accelerations")
                return np.array(v.tolist() + acc + [model.drive_power(t, q, v) if work else 0.0])
            rates, power = native.rates(t, y[:-1], work)
            return np.array(_finite(rates, "rates") + [power])
        except Exception as error:
            raise _model_failure(method, t, steps, error) from None

    if native is None:
        y0, book = np.concatenate([q0, v0]), lambda y, start: (y[..., :n], y[..., n:])
    else:  # book(y, start): the book's coordinates and rates of states y, the angles continuous from `start`
        y0, book = native.state(q0, v0), native.book
    # The book's coordinates of a solver state, for `bound` (a native state's angles within half a turn of q0's:
    # bound no winding angle)
    coordinates = lambda y: book(y[None, :-1], q0)[0][0]
    elapsed = stopwatch()
    outputs, done = [], 0  # the states at grid[:done]
    with np.errstate(all="ignore"):
        y0 = np.append(y0, 0.0)
        if land_on_outputs:
            outputs, done = [y0[None]], 1
        solver = getattr(scipy.integrate, METHODS[method].engine_name)(
            rhs, grid[0], y0, grid[done] if land_on_outputs else grid[-1], rtol=rtol, atol=rtol, max_step=max_step)
        while solver.status == "running":
            message = solver.step()
            steps += 1
            if solver.status == "failed":
                raise Unstable(method, solver.t, steps, message)
            if not finite(solver.y):
                raise Unstable(method, solver.t, steps, "state is not finite")
            if bound is not None and abs(coordinates(solver.y)[bound[1]]) > bound[2]:
                _escape_within_step(solver, bound, method, steps, coordinates)
            budget.check(solver.t, steps)
            if not land_on_outputs:
                reached = np.searchsorted(grid, solver.t, side="right")
                if reached > done:
                    outputs.append(solver.dense_output()(grid[done:reached]).T)
                    done = reached
            elif solver.status == "finished":  # the step ended at grid[done]
                outputs.append(solver.y[None])
                done += 1
                if done < len(grid):
                    solver.t_bound, solver.status = grid[done], "running"
        y = np.vstack(outputs)
        q, v = book(y[:, :-1], q0)
    return grid, q, v, y[:, -1], {**elapsed(), "evaluations": evaluations, "steps": steps}


def _finite(values, what):
    """`values` as a list of floats (flattened), raising ArithmeticError at once where one is not finite: a solver
    shrinks its step on NaN until the budget ends."""
    numbers = _floats(values)
    if not _finite_numbers(numbers):
        raise ArithmeticError(f"{what} {values} are not finite")
    return numbers


def _escape_within_step(solver, bound, method, step, coordinates):
    """Raise Escaped at the time the coordinate crossed the bound within the solver's last step, found on
    its dense output: an adaptive step is long (DOP853 at 1e-10 takes 10 ms steps where l runs away),
    and the step's end would put different sources' escapes that far apart.  coordinates(y): the book's
    coordinates of the solver's state."""
    name, index, limit = bound
    dense = solver.dense_output()
    # inside at t_old, beyond at t
    t = scipy.optimize.brentq(lambda s: abs(coordinates(dense(s))[index]) - limit, solver.t_old, solver.t)
    raise Escaped(method, t, step, f"|{name}| reached {limit:g} (by the step's dense output)")


def _fixed(model, q0, v0, grid, method, dt, every, work, budget, bound):
    """Fixed-step integration (FIXED_STEPS); the work W' = P rides along with the scheme's own update.  The state
    is stepped as lists of Python floats, made arrays only for the model: on so few numbers each numpy operation
    costs more than its arithmetic, and each number goes through the same operations in the same order as in
    numpy's elementwise ones (`_plus_times`), so the floats are the same.  The budget is checked once a step."""
    n = len(q0)
    steps = every * (len(grid) - 1)

    def rates(t, q, v):  # the accelerations (a list) and the drive power at the state of floats q, v, at `step`
        q, v = np.array(q), np.array(v)
        try:
            acc = model.accelerations(t, q, v)
            power = model.drive_power(t, q, v) if work else 0.0
        except Exception as error:
            raise _model_failure(method, t, step, error) from None
        return _floats(acc), power

    advance = FIXED_STEPS[method]
    q, v, w = q0.tolist(), v0.tolist(), 0.0
    # The states at the outputs one after another, in flat lists: floats, which the garbage collector does not
    # count, where a list per output would set off more of its passes.
    out_q, out_v, out_w = q.copy(), v.copy(), [w]
    elapsed = stopwatch()
    with np.errstate(all="ignore"):  # for the model's numpy arithmetic
        for output in range(1, len(grid)):
            for step in range((output - 1) * every, output * every):
                t = step * dt
                budget.check(t, step)
                q, v, w = advance(rates, t, dt, q, v, w)
                if not _finite_numbers(q + v):
                    raise Unstable(method, (step + 1) * dt, step + 1, "state is not finite")
                check_bound(bound, method, (step + 1) * dt, step + 1, q)
            out_q += q
            out_v += v
            out_w.append(w)
    return grid, np.array(out_q).reshape(len(grid), n), np.array(out_v).reshape(len(grid), n), np.array(out_w), \
        {**elapsed(), "evaluations": METHODS[method].evaluations * steps, "steps": steps}


def _plus_times(x, h, y):
    """x + h y, elementwise on lists of floats: numpy's x + h * y, number by number."""
    return [xi + h * yi for xi, yi in zip(x, y)]


def _explicit_euler(rates, t, dt, q, v, w):
    """One step of the explicit Euler of the book's Matlab program: q advances with the step's starting v."""
    acc, power = rates(t, q, v)
    return _plus_times(q, dt, v), _plus_times(v, dt, acc), w + dt * power


def _semi_implicit_euler(rates, t, dt, q, v, w):
    """One step of the semi-implicit Euler of the book's Pascal programs: q advances with the new v."""
    acc, power = rates(t, q, v)
    v_new = _plus_times(v, dt, acc)
    return _plus_times(q, dt, v_new), v_new, w + dt * power


def _rk4(rates, t, dt, q, v, w):
    """One step of classical RK4 of y = (q, v, w)."""
    n = len(q)

    def derivative(t, y):
        acc, power = rates(t, y[:n], y[n:2 * n])
        return y[n:2 * n] + acc + [power]

    y = q + v + [w]
    k1 = derivative(t, y)
    k2 = derivative(t + dt / 2, _plus_times(y, dt / 2, k1))
    k3 = derivative(t + dt / 2, _plus_times(y, dt / 2, k2))
    k4 = derivative(t + dt, _plus_times(y, dt, k3))
    y = _plus_times(y, dt / 6, [a + 2 * b + 2 * c + d for a, b, c, d in zip(k1, k2, k3, k4)])
    return y[:n], y[n:2 * n], y[-1]


FIXED_STEPS = {"explicit Euler": _explicit_euler, "semi-implicit Euler": _semi_implicit_euler, "RK4": _rk4}


def _mujoco(model, q0, v0, grid, method, dt, every, work, budget, bound):
    # MuJoCo steps in C, out of reach of the budget's clock: its steps are bounded before it starts (Budget).
    run = model.step(q0, v0, grid[-1], dt, METHODS[method].engine_name)
    t, q, v = run["t"], run["q"], run["v"]
    check_mujoco_run(run, method, dt, bound)
    # Work of the prescribed motions: drive power at every step, Simpson's rule (error ~ dt^4).
    if work:
        work = scipy.integrate.cumulative_simpson(model.drive_powers(t, q, v), x=t, initial=0.0)
    else:
        work = np.zeros(len(t))
    keep = slice(None, None, every)
    # Index by the nominal output times: MuJoCo accumulates time step by step, so its clock
    # differs from the grid by rounding, and trajectories are compared time by time.
    # (summed rounding: at most half an ulp of t per step, so the step count times eps t_end; a millionth of a step
    # besides, for output steps that are no multiple of dt)
    drift = 1e-6 * dt + len(t) * np.finfo(float).eps * grid[-1]
    assert np.allclose(t[keep], grid, rtol=0, atol=drift), "output_step must be a multiple of dt"
    return grid, q[keep], v[keep], work[keep], {
        "wall": run["wall"], "cpu": run["cpu"], "evaluations": run["evaluations"], "steps": run["steps"],
        "driven_rate_error": run["driven_rate_error"]}


def check_mujoco_run(run, method, dt, bound=None):
    """Raise Unstable at the first step of a MujocoModel.step run that is not finite, that MuJoCo reset,
    or (with `bound` = (coordinate name, its index, limit)) whose coordinate is beyond the limit (then
    Escaped); or, for a run with a MuJoCo warning but no reset, at its end."""
    t, q, v = run["t"], run["q"], run["v"]
    # MuJoCo answers a blow-up (NaN, Inf or |qvel| > 1e10) by resetting the state and the clock
    # to their initial values, silently for a rollout: a clock that stops advancing by dt marks it.
    finite_steps = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(v), axis=1)
    advancing = np.concatenate([[True], np.abs(np.diff(t) - dt) < dt / 2])
    inside = np.ones(len(t), dtype=bool)
    if bound is not None:
        _, index, limit = bound
        inside = np.abs(np.where(finite_steps, q[:, index], np.inf)) <= limit
    warned = "; ".join(f"MuJoCo warning {name} ({number} time{'s' if number > 1 else ''}, last with info {info})"
                       for name, (number, info) in run["warnings"].items())
    good = finite_steps & advancing & inside
    if not good.all():
        step = int(np.argmin(good))
        if not finite_steps[step]:
            raise Unstable(method, step * dt, step, "state is not finite")
        if not advancing[step]:
            raise Unstable(method, step * dt, step, (warned or "non-finite or huge state") + "; MuJoCo reset the simulation")
        check_bound(bound, method, step * dt, step, q[step])  # finite and advancing: beyond the bound, Escaped
    if warned:  # a warning without a reset: the run is not to be trusted either
        raise Unstable(method, t[-1], run["steps"], warned)


def _frame(model, t, q, v, work, attrs, quantities):
    method = attrs["method"]
    columns = {}
    for i, name in enumerate(model.coords):
        columns[name] = q[:, i]
        columns[name + "_rate"] = v[:, i]
    with np.errstate(all="ignore"):
        if "reactions" in quantities:
            reactions = _at_every_state(model, "reactions", method, t, q, v)
            for name in model.reaction_names:
                columns[name] = reactions[name] if isinstance(reactions, dict) else [r[name] for r in reactions]
        if "energy" in quantities and hasattr(model, "energy"):  # optional of a derivation (docs/model-interface.md)
            columns["energy"] = _at_every_state(model, "energy", method, t, q, v)
    if work is not None:
        columns["work"] = work
    import pandas as pd  # here, not above: the checks at states (`run --quick`) make no run, and its import is 0.4 s
    frame = pd.DataFrame(columns, index=pd.Index(t, name="t"))
    finite_cells = np.isfinite(frame.to_numpy(dtype=float))
    if not finite_cells.all():  # a finite state whose reactions, energy or work overflow
        at, column = np.argwhere(~finite_cells)[0]
        raise Unstable(method, t[at], None, f"{frame.columns[column]} is not finite")
    frame.attrs.update(attrs)
    return frame


def _at_every_state(model, quantity, method, t, q, v):
    """model.<quantity> at each state of a run: in one call where the model has a many-state form
    (`at_many_states`), else state by state, which names the time where one fails."""
    values = at_many_states(model, quantity, t, q, v)
    if values is not None:
        return values
    return [_arithmetic(method, ti, None, getattr(model, quantity), ti, qi, vi) for ti, qi, vi in zip(t, q, v)]


def at_many_states(model, quantity, t, q, v):
    """model.<quantity>_many(t, q, v) (t of shape (N,), q and v (N, n)) where the model has it: the same numbers as
    model.<quantity> state by state, in one call.  None where it has none, or where the call raises or gives a
    number that is not finite: the caller then goes state by state, and names the state that fails."""
    many = getattr(model, quantity + "_many", None)
    if many is None:
        return None
    try:
        with np.errstate(all="ignore"):
            values = many(t, q, v)
        return values if all(finite(x) for x in (values.values() if isinstance(values, dict) else [values])) else None
    except Exception:  # named by the caller, state by state
        return None
