"""What the stability studies share: runs that may blow up, recorded as data; the linear stability
of one-step schemes; a study's settings and result; the figures' style."""

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np
import pandas as pd
from scipy.optimize import brentq

from dyncheck.results.values import StudyResult
from dyncheck.run.simulate import METHODS, MUJOCO_METHODS, Unstable, check_mujoco_run, simulate

SHARP = {"semi-implicit Euler": 2.0, "mujoco:Euler": 2.0, "mujoco:implicitfast": 2.0,
         "RK4": 2 * math.sqrt(2.0), "mujoco:RK4": 2 * math.sqrt(2.0)}
"""omega h limits of the schemes on an undamped oscillator x'' = -omega^2 x (eigenvalues +-i omega):
semi-implicit (symplectic) Euler |x| < 2; classical RK4 on the imaginary axis |x| < 2 sqrt(2) = 2.83
(2.785 is its limit on the negative real axis, for decaying modes); MuJoCo's Euler is the same
semi-implicit Euler, and its implicitfast treats only velocity-dependent forces implicitly, so an
undamped spring is explicit to it.  Explicit Euler grows by sqrt(1 + (omega h)^2) every step, for
any h: it has no limit, only a horizon (see `limit_step`)."""

EPS = np.finfo(float).eps


# -- runs that may blow up --------------------------------------------------------------------


class Guarded:
    """`model` whose accelerations raise Unstable once coordinate `index` leaves +-`bound` (or is not
    finite): a run that has left the physics stops there, with its time and step."""

    def __init__(self, model, index, bound, method, per_step=1):
        self.model, self.index, self.bound, self.method, self.per_step = model, index, bound, method, per_step
        self.coords, self.reaction_names = model.coords, model.reaction_names
        self.evaluations = 0

    def accelerations(self, t, q, v):
        self.evaluations += 1
        x = q[self.index]
        if not -self.bound <= x <= self.bound:  # NaN fails too
            raise Unstable(self.method, t, self.evaluations // self.per_step,
                           f"|{self.coords[self.index]}| = {abs(x):.3g} beyond {self.bound:g}")
        return self.model.accelerations(t, q, v)

    def __getattr__(self, name):  # reactions, energy, drive_power: the model's, where it has them
        return getattr(self.model, name)


def grid_step(dt_target, t_end, max_out=1000):
    """(dt, steps, every): the largest step dt <= dt_target that divides t_end, output every `every`
    steps, at most `max_out` rows."""
    steps = max(1, math.ceil(t_end / dt_target - 1e-9))
    every = max(1, math.ceil(steps / max_out))
    steps = every * math.ceil(steps / every)
    return t_end / steps, steps, every


def run_fixed(case, source, method, dt_target, t_end, *, bound=None, index=None, max_out=1000):
    """`method` at the step of `grid_step`: fixed-step generic methods integrate `source` (guarded by
    `bound` on coordinate `index`), MuJoCo's its own scene.  Returns (run, dt, steps) or raises Unstable."""
    dt, steps, every = grid_step(dt_target, t_end, max_out)
    if method in MUJOCO_METHODS:
        model = case.model("mujoco")
        if bound is not None:  # no guard inside MuJoCo's loop: look at its raw steps first
            _mujoco_bound(model, case.initial[:2], t_end, dt, method, bound, index)
    else:
        model = case.model(source)
        if bound is not None:
            model = Guarded(model, index, bound, method, METHODS[method].evaluations)
    run = simulate(model, case.initial[:2], t_end, method, dt=dt, output_step=every * dt, work=False)
    return run, dt, steps  # simulate raises Unstable at a non-finite state or a MuJoCo reset


def _mujoco_bound(model, ic, t_end, dt, method, bound, index):
    """Raise Unstable at MuJoCo's first step beyond `bound` on coordinate `index`, non-finite, or reset."""
    run = model.step(ic[0], ic[1], t_end, dt, METHODS[method].engine_name)
    check_mujoco_run(run, method, dt, (model.coords[index], index, bound))


# -- linear stability of one-step schemes -------------------------------------------------------

FAMILY = {"explicit Euler": "explicit Euler", "semi-implicit Euler": "semi-implicit Euler",
          "mujoco:Euler": "semi-implicit Euler", "mujoco:implicitfast": "semi-implicit Euler",
          "RK4": "RK4", "mujoco:RK4": "RK4"}


def spectral_radius(method, x):
    """Spectral radius of one step of `method` on x'' = -omega^2 x, for omega h = x (array or scalar):
    explicit Euler sqrt(1 + x^2); semi-implicit Euler (the rate first, the position with the new rate:
    trace 2 - x^2, determinant 1) 1 up to x = 2; classical RK4 |R(i x)| = sqrt(1 - x^6/72 + x^8/576)."""
    x = np.asarray(x, dtype=float)
    family = FAMILY.get(method)
    if family == "explicit Euler":
        return np.sqrt(1.0 + x * x)
    if family == "semi-implicit Euler":
        half = np.abs(1.0 - x * x / 2)
        return np.where(half <= 1.0, 1.0, half + np.sqrt(np.maximum(half * half - 1.0, 0.0)))
    if family == "RK4":
        return np.sqrt(1.0 - x**6 / 72 + x**8 / 576)
    raise ValueError(f"no stability theory for method '{method}'")


def limit_step(method, omega, span, growth):
    """The largest h for which `method` amplifies an undamped oscillation of frequency omega by at
    most `growth` over `span` seconds: the first h with rho(omega h)^(span/h) = growth.  For the
    sharp methods this is their omega h limit pushed up by a hair; for explicit Euler, whose
    spectral radius sqrt(1 + (omega h)^2) exceeds 1 for every h, it is h ~ 2 ln(growth)/(omega^2 span)."""
    if not omega > 0:
        return math.inf
    excess = lambda h: span / h * np.log(spectral_radius(method, omega * h)) - math.log(growth)
    grid = np.geomspace(1e-7, 8.0, 1500) / omega
    above = np.nonzero(excess(grid) > 0)[0]
    if not above.size:
        return math.inf
    i = above[0]
    return brentq(lambda h: float(excess(h)), grid[i - 1], grid[i], xtol=1e-14, rtol=1e-12) if i else grid[0]


# -- common -------------------------------------------------------------------------------------


def fmt(x, spec=".3g", none="-"):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return none
    return format(x, spec)


class NotApplicable(ValueError):
    """Raised by a study that has nothing to measure at the case's parameters (a top whose centre of mass is below
    its tip has no least spin to stand upright); the message says why, and the page says so in the study's place."""


def not_applicable(case, study, settings, why):
    """The result of a study that raised NotApplicable: no numbers, no figure, the reason as its one finding."""
    return study_result(case, study, f"{study.replace('_', ' ').capitalize()}: not applicable", settings,
                        pd.DataFrame(), pd.DataFrame(), [f"Not applicable at these parameters: {why}"], {},
                        time.perf_counter())


def study_result(case, study, title, settings, data, table, findings, series, start):
    table = table.astype(object).where(table.notna(), "-").astype(str)
    # the why's numbers as `{= expression}`, computed at the case's parameters (Case.prose)
    why = case.prose(settings.get("why", ""), f"stability.{study}.why")
    return StudyResult(case=case.name, study=study, title=title, why=" ".join(why.split()),
                       data=data, table=table, findings=tuple(findings), series=series,
                       settings={k: v for k, v in settings.items() if k != "why"}, wall=time.perf_counter() - start)


def rms(x):
    x = np.asarray(x, dtype=float)
    return float(np.sqrt(np.mean(x * x))) if x.size else float("nan")


@dataclass(frozen=True)
class Study:
    """A study a case's [stability] table may name: how to run it ((case, settings, progress) ->
    StudyResult), how to draw its result ((result, path, name) -> caption: `name` the case's heading for
    the title, the caption what the figure shows and what to see in it), and the keys its table must have besides
    `why` (optional ones: `source`, `overrides`, `method`, `k_stiff`)."""
    run: Callable
    figure: Callable
    keys: tuple


@dataclass(frozen=True)
class Map:
    """A 2-D stability map a case's study module offers `dyncheck campaign` (its `MAPS`, by name): a grid of two
    parameters, each cell a task on its own.  `grid(case, n)` -> (x label, xs, y label, ys), n values each;
    `cell(case, x, y)` -> {"value", "theory", "status"}: what is measured there (NaN where nothing is, `status`
    saying why) and its closed form (NaN where there is none); `boundary(case, xs)` -> ys, a closed-form curve
    drawn over the map (e.g. where the physics runs away), or None.  `value` and `theory` say what the numbers
    are, with units; `log` whether the axes are logarithmic (x, y)."""
    title: str
    grid: Callable
    cell: Callable
    value: str
    theory: str
    boundary: Callable | None = None
    log: tuple = (False, False)
