"""Vibration analysis, the book's step 16: an equilibrium, the equations linearised about it, their
matrices, natural frequencies, modes and stability, each from the derivation and from both engines, and
each frequency checked against the motion itself.

The equilibrium is a state (q*, q*') at which the derivation's accelerations vanish: at rest (a hanging
pendulum), or a relative equilibrium, where some coordinates move at constant rates that the equations do
not feel (the spinning base's angle, the top's precession and spin).  Newton-Raphson (the book's step 14)
finds it from the guess of the case file's `[vibration]`, solving for the coordinates and rates it names.
About it, with x = (dq, dq'), the linearised equations are x' = A x.  Where a source gives its mass matrix
M (the engines always; a derivation with `mass_matrix`), they are also M dq'' + C dq' + K dq = 0 with
K = -df/dq (its symmetric part the stiffness, its skew part the circulatory forces) and C = -df/dq' (its
symmetric part the damping, its skew part the gyroscopic forces), f the force side of M q'' = f.

Sources: the derivation by central differences of its accelerations (an error estimate from the same at
twice the step); MuJoCo and Pinocchio by their own derivatives (their adapters' `linearisation`: MuJoCo's
finite-differenced inverse dynamics, Pinocchio's analytic RNEA derivatives).  Eigenvalues carry a
first-order perturbation bound from their matrix's error estimate (|d lambda| <= ||dA|| / s, s the
cosine between the left and right eigenvectors), which sets every tolerance on them.

`analyse(case)` returns a `Vibration` (rows included); `sweep(case)` the Campbell diagram's data and the
stability boundary (a study: `dyncheck report` runs it).
"""

import math
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.linalg

from dyncheck import ceilings, store
from dyncheck.results import Status, no_number, row
from dyncheck.simulate import Unstable, simulate

EPS = np.finfo(float).eps
# Central differences extrapolated once (Richardson: fourth order): truncation ~h^4 f^(5) and rounding eps f / h
# balance at h ~ eps^(1/5) (times the variable's scale), both then ~eps^(4/5) ~ 3e-13 of the derivative's scale.
STEP = EPS ** (1 / 5)
NEWTON_ITERATIONS = 50
# Newton stops when the accelerations are within a thousand ulps of the terms that balance there
# (the Jacobian times the unknowns' scale): rounding in one evaluation of the equations is tens of ulps.
NEWTON_TOLERANCE = ceilings.ROUNDING_FLOOR
SAFETY = 10.0  # on first-order estimates (of a difference quotient's error, of an eigenvalue's perturbation)
RUNS_PER_PERIOD = 64  # outputs per period of a mode's run: its phase is fitted, not interpolated


class NoEquilibrium(ValueError):
    """Newton-Raphson found no equilibrium; the message says from where, and what was left."""


def settings(case):
    """The case's `[vibration]` table with its numbers evaluated, or None."""
    table = case.spec.get("vibration")
    if table is None:
        return None
    return {**table, "q": np.array([case.value(x, "vibration.q") for x in table["q"]]),
            "v": np.array([case.value(x, "vibration.v") for x in table["v"]]),
            "overrides": {name: case.value(x, f"vibration.overrides.{name}")
                          for name, x in table.get("overrides", {}).items()}}


def validate(case):
    """The `[vibration]` table against the case: one guess per coordinate, unknowns that are coordinates or
    their rates, parameters that exist; ValueError naming the file and field."""
    table = case.spec.get("vibration")
    if table is None:
        return
    n = len(case.coords)
    for key in ("q", "v"):
        if len(table[key]) != n:
            raise ValueError(f"{case.file}: vibration.{key} has {len(table[key])} entries; the case has {n} "
                             f"coordinates ({', '.join(case.coords)})")
    names = state_names(case.coords)
    for name in table["solve"]:
        if name not in names:
            raise ValueError(f"{case.file}: vibration.solve names '{name}', which is neither a coordinate nor a "
                             f"rate; they are {', '.join(names)}")
    if not table["solve"]:
        raise ValueError(f"{case.file}: vibration.solve is empty: name the coordinates (or rates) Newton-Raphson "
                         "solves for")
    for parameter in table.get("overrides", {}):
        if parameter not in case.params:
            raise ValueError(f"{case.file}: vibration.overrides: no parameter '{parameter}'")
    swept = [("campbell", table["campbell"])] if "campbell" in table else []
    swept += [(f"boundary[{i}]", b) for i, b in enumerate(table.get("boundary", []))]
    for field, item in swept:
        name = item["parameter"]
        if name not in case.params and (name not in names or name in table["solve"]):
            raise ValueError(f"{case.file}: vibration.{field}.parameter = '{name}' is neither a parameter nor a state "
                             f"variable held by Newton-Raphson (one of {', '.join(n for n in names if n not in table['solve'])})")
    scene = linearised(case)  # the linearised scene must be physical too
    for i, boundary in enumerate(table.get("boundary", [])):
        scene.value(boundary["expected"], f"vibration.boundary[{i}].expected")


def state_names(coords):
    return list(coords) + [f"{c}_rate" for c in coords]


def linearised(case):
    """The case as it is linearised: with the `[vibration]` overrides (the base at rest, no resisting moment)."""
    return case.with_params(**settings(case)["overrides"])


# -- derivatives ------------------------------------------------------------------------------

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


@store.register
@dataclass(frozen=True)
class Equilibrium:
    """The state the case is linearised about, and how Newton-Raphson got there."""
    t: float
    q: np.ndarray
    v: np.ndarray
    residual: float  # the largest |q''| left, relative to `scale`
    scale: float  # the balancing terms' size: the Jacobian times the unknowns' scale (rad/s^2 or m/s^2)
    iterations: int
    solved: tuple  # the state variables solved for

    @property
    def state(self):
        return np.concatenate([self.q, self.v])


def equilibrium(model, t, q, v, solve, coords):
    """Newton-Raphson on the accelerations for the state variables `solve` (names of coordinates and rates),
    the others held; least-squares steps (a cyclic coordinate's equation is identically zero), halved while
    they do not reduce the residual.  NoEquilibrium if it does not converge."""
    n = len(coords)
    names = state_names(coords)
    unknown = [names.index(name) for name in solve]
    x = np.concatenate([q, v]).astype(float)

    def accelerations(u):
        y = x.copy()
        y[unknown] = u
        return np.asarray(model.accelerations(t, y[:n], y[n:]), dtype=float)

    residual = accelerations(x[unknown])
    for iteration in range(NEWTON_ITERATIONS):
        jac, _ = jacobian(accelerations, x[unknown], scales_of(x[unknown]))
        scale = max(np.max(np.abs(jac)) * np.max(scales_of(x[unknown])), EPS)
        if not np.all(np.isfinite(residual)) or not np.all(np.isfinite(jac)):
            break
        if np.max(np.abs(residual)) <= NEWTON_TOLERANCE * scale:
            return Equilibrium(t, x[:n].copy(), x[n:].copy(), float(np.max(np.abs(residual)) / scale), float(scale),
                               iteration, tuple(solve))
        step = np.linalg.lstsq(jac, -residual, rcond=None)[0]
        for _ in range(30):
            trial = accelerations(x[unknown] + step)
            if np.all(np.isfinite(trial)) and np.max(np.abs(trial)) < np.max(np.abs(residual)):
                break
            step = step / 2
        x[unknown] += step
        residual = trial
    raise NoEquilibrium(f"Newton-Raphson for {', '.join(solve)} from {dict(zip(names, np.round(np.concatenate([q, v]), 6)))} "
                        f"did not converge in {NEWTON_ITERATIONS} iterations: the largest |q''| left is "
                        f"{np.max(np.abs(residual)):.3g} at {dict(zip(names, np.round(x, 6)))}")


def steady(model, eq, times):
    """Whether the equilibrium is one at every time: the accelerations vanish along q* + q*' t (a relative
    equilibrium's coordinates move at their rates) at `times` as at t (a base whose motion the equations
    feel, as a spinning arm carrying a spinning disk, makes the linearised equations periodic instead)."""
    worst = 0.0
    for t in times:
        acc = model.accelerations(eq.t + t, eq.q + eq.v * t, eq.v)
        worst = max(worst, float(np.max(np.abs(acc))) / eq.scale)
    return worst


# -- the linearisations ------------------------------------------------------------------------

@store.register
@dataclass(frozen=True)
class Linear:
    """x' = A x about the equilibrium, x = (dq, dq'), from one source; M where the source gives it."""
    source: str
    state_matrix: np.ndarray  # A, (2n, 2n)
    errors: np.ndarray  # (n, 2n): an estimate of each entry's absolute error in A's lower block (the upper is exact)
    mass: np.ndarray | None
    method: str

    @property
    def n(self):
        return len(self.state_matrix) // 2

    @property
    def error(self):
        return float(np.max(self.errors))

    def full_errors(self):
        """The entries' errors as a (2n, 2n) matrix, zeros in the exact upper block."""
        return np.vstack([np.zeros_like(self.errors), self.errors])

    def second_order(self):
        """(M, C, K) of M dq'' + C dq' + K dq = 0, or None without a mass matrix."""
        if self.mass is None:
            return None
        n = self.n
        return self.mass, -self.mass @ self.state_matrix[n:, n:], -self.mass @ self.state_matrix[n:, :n]

    def matrices(self):
        """{name: matrix}: M, stiffness, circulatory, damping, gyroscopic (the symmetric and skew parts of K
        and C); {} without a mass matrix."""
        parts = self.second_order()
        if parts is None:
            return {}
        mass, c, k = parts
        return {"M": mass, "K": (k + k.T) / 2, "N": (k - k.T) / 2, "D": (c + c.T) / 2, "G": (c - c.T) / 2}


def derivation_linear(model, source, eq):
    """The derivation's A by central differences of its accelerations."""
    n = len(eq.q)
    acc = lambda x: np.asarray(model.accelerations(eq.t, x[:n], x[n:]), dtype=float)
    lower, errors = jacobian(acc, eq.state, scales_of(eq.state))
    a = np.block([[np.zeros((n, n)), np.eye(n)], [lower]])
    mass = np.asarray(model.mass_matrix(eq.t, eq.q, eq.v), dtype=float) if hasattr(model, "mass_matrix") else None
    return Linear(source, a, np.tile(errors, (n, 1)), mass, "central differences of its accelerations")


def engine_linear(model, source, eq):
    """An engine's A = [[0, I], [M^-1 df/dq, M^-1 df/dq']] from its own derivatives (its adapter's
    `linearisation`), the errors of M^-1 df entry by entry |M^-1| times those of df."""
    lin = model.linearisation(eq.t, eq.q, eq.v)
    n = len(eq.q)
    inverse = np.linalg.inv(lin.mass)
    lower = inverse @ np.hstack([lin.force_q, lin.force_v])
    a = np.block([[np.zeros((n, n)), np.eye(n)], [lower]])
    errors = np.abs(inverse) @ np.full((n, 2 * n), lin.error)
    return Linear(source, a, errors, np.asarray(lin.mass), lin.method)


# -- modes ----------------------------------------------------------------------------------------

@store.register
@dataclass(frozen=True)
class Modes:
    """The eigenvalues of A with their first-order bounds, the left and right eigenvectors (columns, unit
    length), and the stability verdict."""
    eigenvalues: np.ndarray  # complex, sorted by |lambda| then imaginary part
    bounds: np.ndarray  # |d lambda| <= ||dA||_F / s for the matrix's error estimate
    left: np.ndarray
    right: np.ndarray
    verdict: str

    def oscillating(self):
        """Indices of the modes that oscillate: positive imaginary part beyond its bound (one of each pair)."""
        return [i for i, (lam, bound) in enumerate(zip(self.eigenvalues, self.bounds)) if lam.imag > bound]

    def shape(self, i, n):
        """Mode i's coordinate part, scaled so that its largest component is 1 (real, positive)."""
        part = self.right[:n, i]
        return part / part[np.argmax(np.abs(part))]


def modal(linear):
    """Eigenvalues, eigenvectors and the verdict of a linearisation.  Each eigenvector is the null vector of
    A - lambda I from its singular value decomposition (left and right at once): accurate to the matrix's
    error over the rest of the spectrum's distance, where LAPACK's eigenvectors lose digits beside a cluster
    of near-zero eigenvalues (the top's cyclic coordinates: 1e-7 from perturbations of 1e-14)."""
    a = linear.state_matrix
    values = scipy.linalg.eigvals(a)
    size = len(a)
    left, right = np.empty((size, size), complex), np.empty((size, size), complex)
    for i, lam in enumerate(values):
        u, _, vh = scipy.linalg.svd(a - lam * np.eye(size))
        left[:, i], right[:, i] = u[:, -1], vh[-1].conj()
    cosines = np.abs(np.einsum("ij,ij->j", left.conj(), right))
    # First order, entry by entry: |d lambda| <= |y|^T |dA| |x| / |y^H x| (invariant under rescaling a coordinate,
    # which the norm bound ||dA|| / s is not: psi in rad beside l in m), plus the eigensolver's rounding, a hundred
    # eps times the matrix's norm over the cosine.
    spread = np.einsum("ij,ik,kj->j", np.abs(left), linear.full_errors(), np.abs(right))
    bounds = (spread + 1e2 * EPS * np.linalg.norm(a)) / np.maximum(cosines, EPS)
    order = np.lexsort((values.imag, np.round(np.abs(values), 12)))
    values, bounds, left, right = values[order], bounds[order], left[:, order], right[:, order]
    return Modes(values, bounds, left, right, verdict(values, bounds))


def eigenvalue_sensitivity(linear, modes, i, errors):
    """The first-order change of eigenvalue i under entry errors `errors` (n, 2n) of A's lower block:
    |y|^T |dA| |x| / |y^H x|."""
    full = np.vstack([np.zeros_like(errors), errors])
    left, right = modes.left[:, i], modes.right[:, i]
    return float(np.abs(left) @ full @ np.abs(right) / max(abs(left.conj() @ right), EPS))


def term_errors(linear):
    """Entry errors of a term of relative size ceilings.POINTWISE in every entry of A's lower block: what the
    linearisation rows' ceilings are made of.  An eigenvalue or a mode shape moves under them by its own
    condition (a shape beside a near eigenvalue by much more than 1e-6): a tolerance above that change could pass
    such a term, and proves nothing."""
    return ceilings.POINTWISE * np.abs(linear.state_matrix[linear.n:])


def verdict(values, bounds):
    """"unstable" where an eigenvalue's real part is positive beyond its bound; "asymptotically stable" where
    every one is negative beyond it; else "marginally stable" (on the imaginary axis within the bounds:
    linearly stable, and the nonlinear terms decide)."""
    nonzero = np.abs(values) > SAFETY * bounds
    if np.any(values.real > SAFETY * bounds):
        return "unstable"
    if np.all(values.real[nonzero] < -SAFETY * bounds[nonzero]) and np.all(nonzero):
        return "asymptotically stable"
    return "marginally stable"


def match(reference, other):
    """For each of `reference`'s eigenvalues, the index of `other`'s nearest one."""
    return [int(np.argmin(np.abs(other.eigenvalues - lam))) for lam in reference.eigenvalues]


# -- motion -------------------------------------------------------------------------------------

@store.register
@dataclass(frozen=True)
class Motion:
    """A mode measured in a run from the equilibrium displaced along it: the frequency and growth rate of
    its modal coordinate (the left eigenvector's projection of the displacement from q* + q*' t)."""
    source: str
    mode: int  # index into its source's Modes
    amplitude: float  # the largest coordinate displacement at the start (rad or m)
    frequency: float | None  # rad/s
    growth: float | None  # 1/s
    why: str = ""  # why there is no number

    @property
    def ok(self):
        return self.frequency is not None

    @property
    def exponent(self):
        """growth + i frequency: the eigenvalue the run shows."""
        return complex(self.growth, self.frequency)


def mode_run(case, model, source, eq, modes, i, amplitude, periods, method, dt=None):
    """The run of `model` from the equilibrium displaced by `amplitude` along mode i of `modes`, measured."""
    n = len(eq.q)
    lam = modes.eigenvalues[i]
    full = modes.right[:, i] / modes.right[:n, i][np.argmax(np.abs(modes.right[:n, i]))]
    start = eq.state + amplitude * full.real
    period = 2 * math.pi / lam.imag
    mujoco_step = case.integration["mujoco_step"]
    output_step = mujoco_step * max(1, round(period / RUNS_PER_PERIOD / mujoco_step))
    t_end = output_step * round(periods * period / output_step)
    options = {"dt": dt} if dt else {"rtol": case.integration["tight_rtol"], "max_step": period / 20,
                                     "omega": abs(lam)}
    try:
        with np.errstate(all="ignore"):
            run = simulate(model, (start[:n], start[n:]), t_end, method, output_step=output_step, work=False, **options)
    except (Unstable, ArithmeticError, np.linalg.LinAlgError) as error:
        return Motion(source, i, amplitude, None, None, f"{method}: {error}")
    t = run.index.to_numpy()
    x = run[state_names(case.coords)].to_numpy()
    displacement = x - (eq.state + np.outer(t, np.concatenate([eq.v, np.zeros(n)])))
    z = displacement @ modes.left[:, i].conj() / (modes.left[:, i].conj() @ modes.right[:, i])
    phase = np.unwrap(np.angle(z))
    frequency = np.polyfit(t, phase, 1)[0]
    growth = np.polyfit(t, np.log(np.abs(z)), 1)[0]
    return Motion(source, i, amplitude, float(frequency), float(growth))


# -- the analysis ----------------------------------------------------------------------------------

@store.register
@dataclass(frozen=True)
class Vibration:
    """Everything the page's "Vibration analysis" section shows."""
    why: str
    overrides: dict  # the parameters changed for the linearised scene
    equilibrium: Equilibrium | None
    linear: dict  # {source: Linear}
    modes: dict  # {source: Modes}
    motions: tuple  # of Motion
    shift: tuple  # per oscillating mode of the reference: the nonlinear shift of its frequency at the amplitude
    rows: tuple
    failure: str = ""  # why there is no analysis (no equilibrium, a periodic one)


ENGINES = ("mujoco", "pinocchio")


def analyse(case):
    """The equilibrium of `[vibration]`, each source's linearisation and modes, the motion of every
    oscillating mode in every source, and the rows that compare them; None for a case without the table."""
    table = settings(case)
    if table is None:
        return None
    scene = linearised(case)
    check = "vibration"
    reference = scene.model("reference")
    try:
        eq = equilibrium(reference, 0.0, table["q"], table["v"], table["solve"], case.coords)
    except NoEquilibrium as error:
        return without_equilibrium(scene, table, str(error))
    rows = [row(check, "equilibrium (Newton-Raphson: |q''| left)", ("reference",), eq.residual, NEWTON_TOLERANCE,
                f"{eq.iterations} iterations; relative to {eq.scale:.3g}, the balancing terms' size",
                ceiling=ceilings.POINTWISE)]
    horizon = case.initial[2]
    drift = steady(reference, eq, (0.29 * horizon, 0.71 * horizon))
    if drift > NEWTON_TOLERANCE * SAFETY:
        why = (f"not an equilibrium at every time: the accelerations along q* + q*' t reach {drift:.2e} of the "
               "balancing terms (the base's motion makes the linearised equations periodic; a Floquet analysis "
               "is not built)")
        rows.append(no_number(check, "steady equilibrium", ("reference",), why, Status.FAIL))
        return Vibration(table["why"], table["overrides"], eq, {}, {}, (), (), tuple(rows), why)
    pointwise = case.tolerance["pointwise"]["value"]
    for source in ENGINES:
        left = np.max(np.abs(scene.model(source).accelerations(eq.t, eq.q, eq.v))) / eq.scale
        rows.append(row(check, "equilibrium (|q''| there)", (source,), left, pointwise,
                        "the engine's accelerations at the derivation's equilibrium, relative to the balancing terms; "
                        "allowed: the pointwise tolerance", ceiling=ceilings.POINTWISE))
    linear = {"reference": derivation_linear(reference, "reference", eq)}
    for source in ENGINES:
        try:
            linear[source] = engine_linear(scene.model(source), source, eq)
        except ValueError as error:
            rows.append(no_number(check, "linearisation", (source,), str(error), Status.FAIL))
    modes = {source: modal(lin) for source, lin in linear.items()}
    rows += comparison_rows(linear, modes, pointwise)
    if modes["reference"].verdict == "unstable":  # a run from it leaves it, along the growing mode
        rows.append(no_number(check, "modes by motion", ("reference", "mujoco", "pinocchio"),
                              "an unstable equilibrium: every run leaves it along its growing mode, so no mode's "
                              "frequency can be measured in one", Status.NOT_APPLICABLE))
        return Vibration(table["why"], table["overrides"], eq, linear, modes, (), (), tuple(rows))
    motions, shift = motion_checks(case, scene, eq, modes, table)
    rows += motion_rows(case, modes, motions, shift)
    return Vibration(table["why"], table["overrides"], eq, linear, modes, tuple(motions), tuple(shift), tuple(rows))


def without_equilibrium(scene, table, why):
    """The analysis of a scene whose derivation has no equilibrium near the guess: not applicable if MuJoCo
    has none there either (the parameters leave none: a spring too soft for the spin), a failure if it has."""
    try:
        found = equilibrium(scene.model("mujoco"), 0.0, table["q"], table["v"], table["solve"], scene.coords)
    except NoEquilibrium:
        row_ = no_number("vibration", "equilibrium", ("reference", "mujoco"), f"neither has one near the guess: {why}",
                         Status.NOT_APPLICABLE)
    else:
        row_ = no_number("vibration", "equilibrium", ("reference", "mujoco"),
                         f"MuJoCo has one at {dict(zip(state_names(scene.coords), np.round(found.state, 6)))}, the "
                         f"derivation none: {why}", Status.FAIL)
    return Vibration(table["why"], table["overrides"], None, {}, {}, (), (), (row_,), why)


def comparison_rows(linear, modes, pointwise):
    """Each pair of sources: A's lower block, the second-order matrices where both give M, each eigenvalue,
    each oscillating mode's shape, the verdict.  Allowed: both estimates (times SAFETY) plus the case's
    pointwise tolerance (what the engines' scenes model differently, placeholders, at one state), relative."""
    rows = []
    sources = list(linear)
    for k, a in enumerate(sources):
        for b in sources[k + 1:]:
            la, lb = linear[a], linear[b]
            n = la.n
            scale = max(np.max(np.abs(la.state_matrix[n:])), np.max(np.abs(lb.state_matrix[n:])))
            difference = np.max(np.abs(la.state_matrix[n:] - lb.state_matrix[n:]))
            if scale <= SAFETY * (la.error + lb.error):  # no force depends on the state (a pendulum without gravity)
                rows.append(no_number("vibration", "A = d(q', q'')/d(q, q')", (a, b),
                                      f"no force depends on the state: both lower blocks are zero within their "
                                      f"estimates (largest entry {scale:.1e}, difference {difference:.1e})",
                                      Status.NOT_APPLICABLE))
            else:
                rows.append(row("vibration", "A = d(q', q'')/d(q, q')", (a, b), difference / scale,
                                SAFETY * (la.error + lb.error) / scale + pointwise, ceiling=ceilings.POINTWISE))
            ma, mb = la.matrices(), lb.matrices()
            for name in ma if mb else ():
                size = max(np.max(np.abs(ma[name])), np.max(np.abs(mb[name])))
                big = max(np.max(np.abs(m)) for m in ma.values() if m.shape == ma[name].shape)
                error = np.max(np.abs(ma[name] - mb[name])) / big
                rows.append(row("vibration", f"{name} ({MATRIX_NAMES[name]})", (a, b), error,
                                SAFETY * (la.error + lb.error) * np.max(np.abs(ma["M"])) / big + pointwise,
                                f"relative to the largest entry of M, K, D, G, N ({big:.3g}); this one's {size:.3g}",
                                ceiling=ceilings.POINTWISE))
            mo_a, mo_b = modes[a], modes[b]
            pairs = match(mo_a, mo_b)
            for i in mo_a.oscillating():
                j = pairs[i]
                lam, other = mo_a.eigenvalues[i], mo_b.eigenvalues[j]
                moved = eigenvalue_sensitivity(la, mo_a, i, term_errors(la)) / abs(lam)
                rows.append(row("vibration", f"frequency {mode_label(mo_a, i)}", (a, b),
                                abs(other - lam) / abs(lam),
                                SAFETY * (mo_a.bounds[i] + mo_b.bounds[j]) / abs(lam) + pointwise,
                                f"{lam.imag:.10g} vs {other.imag:.10g} rad/s (damping {-lam.real:.3g} vs "
                                f"{-other.real:.3g} 1/s); ceiling: the eigenvalue's change under a term of "
                                f"{ceilings.POINTWISE:g} of every entry of A", ceiling=max(ceilings.POINTWISE, moved)))
                shape_a, shape_b = mo_a.shape(i, n), mo_b.shape(j, n)
                allowed = SAFETY * (shape_bound(la, mo_a, i) + shape_bound(lb, mo_b, j)) + pointwise
                rows.append(row("vibration", f"mode shape {mode_label(mo_a, i)}", (a, b),
                                np.max(np.abs(shape_a - shape_b)), allowed,
                                "largest component 1; allowed: each matrix's error over the distance of the "
                                "eigenvalue from the rest of the spectrum (its reduced resolvent); ceiling: the "
                                f"shape's change under a term of {ceilings.POINTWISE:g} of every entry of A",
                                ceiling=max(ceilings.POINTWISE, shape_bound(la, mo_a, i, term_errors(la)))))
            same = mo_a.verdict == mo_b.verdict
            rows.append(row("vibration", "stability", (a, b), 0.0 if same else 1.0, 0.0,
                            f"{mo_a.verdict} vs {mo_b.verdict}", ceiling=0.0))
    return rows


def shape_bound(linear, modes, i, errors=None):
    """First-order bound of mode i's shape (largest component 1) under the matrix's errors, entry by entry:
    dx = -R dA x with R the reduced resolvent of A - lambda I (its pseudo-inverse without the eigenvector's own
    null direction), so |dx| <= |R| |dA| |x|, plus the eigensolver's rounding over R; twice that (rescaling to
    the largest component moves the others by as much again) over the largest component's size.  `errors`
    (n, 2n): other entry errors than the matrix's own estimate."""
    a = linear.state_matrix
    u, sigma, vh = scipy.linalg.svd(a - modes.eigenvalues[i] * np.eye(len(a)))
    resolvent = (vh[:-1].conj().T / sigma[:-1]) @ u[:, :-1].conj().T
    x = np.abs(modes.right[:, i])
    full = linear.full_errors() if errors is None else np.vstack([np.zeros_like(errors), errors])
    spread = np.abs(resolvent) @ (full @ x) + 1e2 * EPS * np.linalg.norm(a) / sigma[-2]
    n = linear.n
    return 2 * float(np.max(spread[:n])) / float(np.max(x[:n]))


MATRIX_NAMES = {"M": "mass", "K": "stiffness", "N": "circulatory", "D": "damping", "G": "gyroscopic"}


def mode_label(modes, i):
    """"mode 1" ... in the order of the oscillating modes' frequencies."""
    return f"mode {modes.oscillating().index(i) + 1}"


def motion_checks(case, scene, eq, modes, table):
    """Every oscillating mode of the reference run in each source at the case's amplitude: its runs (Motion),
    and per mode the nonlinear shift of lambda = growth + i frequency at the amplitude, estimated by the
    reference's run at twice it: their difference is three times the shift for a shift quadratic in the
    amplitude (a frequency's), once it for a linear one (a decay rate's may be), so it bounds both."""
    amplitude, periods = table["amplitude"], table["periods"]
    dt = case.integration["mujoco_step"]
    ref = modes["reference"]
    motions, shift = [], []
    for i in ref.oscillating():
        # each source displaced along, and measured by, its own mode: its run tests its own linearisation
        own = {source: (scene.model(source), modes[source], match(ref, modes[source])[i]) for source in modes}
        run = lambda source, method, scale=1.0, step=None: mode_run(case, own[source][0], source, eq, own[source][1],
                                                                   own[source][2], scale * amplitude, periods,
                                                                   method, step)
        runs = [run("reference", "DOP853"), run("pinocchio", "DOP853"), run("mujoco", "mujoco:RK4", step=dt),
                run("reference", "DOP853", 2.0), run("mujoco", "mujoco:RK4", step=dt / 2)]
        motions += runs
        shift.append(abs(runs[3].exponent - runs[0].exponent) if runs[0].ok and runs[3].ok else math.inf)
    return motions, shift


def motion_rows(case, modes, motions, shift):
    """Each source's lambda = growth + i frequency in its run against its own linearisation's eigenvalue,
    relative to |lambda|: allowed SAFETY times the nonlinear shift at the amplitude, plus MuJoCo's step error
    (RK4 at dt and dt/2: their difference is 15/16 of the error at dt), plus the eigenvalue's own bound; the
    ceiling: a shift above ceilings.MOTION of |lambda| hides a term of that size."""
    rows = []
    reference = modes["reference"]
    per_mode = len(motions) // max(len(reference.oscillating()), 1)
    for k, i in enumerate(reference.oscillating()):
        runs = motions[k * per_mode:(k + 1) * per_mode]
        mujoco_twin = runs[4]
        for motion in runs[:3]:
            source = motion.source
            label = f"mode {k + 1} by motion (growth + i frequency)"
            if not motion.ok:
                rows.append(no_number("vibration", label, (source,), motion.why))
                continue
            j = match(reference, modes[source])[i]
            lam = modes[source].eigenvalues[j]
            step_error = (abs(motion.exponent - mujoco_twin.exponent) * 16 / 15
                          if source == "mujoco" and mujoco_twin.ok else 0.0)
            allowed = SAFETY * (shift[k] + step_error + modes[source].bounds[j]) / abs(lam) + ceilings.ROUNDING_FLOOR
            rows.append(row("vibration", label, (source,), abs(motion.exponent - lam) / abs(lam), allowed,
                            f"run {motion.growth:.3g} + {motion.frequency:.10g} i, linear {lam.real:.3g} + "
                            f"{lam.imag:.10g} i (1/s); amplitude {motion.amplitude:g}, its nonlinear shift "
                            f"{shift[k] / abs(lam):.1e}", ceiling=ceilings.MOTION))
    return rows


# -- the Campbell diagram and the stability boundary (a study: dyncheck report) ----------------------

@store.register
@dataclass(frozen=True)
class Sweep:
    """The frequencies against a parameter, and where the equilibrium stops being stable."""
    parameter: str
    unit: str
    why: str
    data: pd.DataFrame  # source, value, mode (1, 2, ... by frequency), frequency [rad/s], largest_real [1/s]
    boundary: float | None  # the swept parameter's boundary, where [vibration.boundary] has one in it
    findings: tuple  # sentences with the numbers
    wall: float


def sweep(case, progress=None):
    """The `[vibration.campbell]` sweep and the `[vibration.boundary]` search; None without them."""
    table = settings(case)
    if table is None or "campbell" not in table:
        return None
    start = time.perf_counter()
    scene = linearised(case)
    campbell = table["campbell"]
    parameter = campbell["parameter"]
    if progress:
        progress(f"{case.name}: Campbell diagram over {parameter}")
    records, missing, guess = [], [], (table["q"], table["v"])
    for value in [scene.value(x, "vibration.campbell.values") for x in campbell["values"]]:
        point, eq, _ = stable_equilibrium(scene, table, parameter, value, guess)
        if eq is None:
            missing.append(value)
            continue
        guess = (eq.q, eq.v)
        for source in ("reference",) + ENGINES:
            model = point.model(source)
            lin = derivation_linear(model, source, eq) if source == "reference" else engine_linear(model, source, eq)
            modes = modal(lin)
            real = np.where(np.abs(modes.eigenvalues.real) > SAFETY * modes.bounds, modes.eigenvalues.real, 0.0)
            for k, i in enumerate(modes.oscillating()):
                records.append({"source": source, "value": value, "mode": k + 1,
                                "frequency": modes.eigenvalues[i].imag, "largest_real": float(np.max(real))})
    findings = []
    if missing:
        findings.append(f"No equilibrium near the last one at {parameter} = "
                        + ", ".join(f"{x:.4g}" for x in missing) + ": not drawn.")
    boundaries = {}
    for settings_ in table.get("boundary", []):
        boundary, sentences = boundary_search(case, scene, table, settings_, progress)
        if boundary is not None:
            boundaries[settings_["parameter"]] = boundary
        findings += sentences
    return Sweep(parameter, unit(case, parameter), campbell["why"], pd.DataFrame(records),
                 boundaries.get(parameter), tuple(findings), time.perf_counter() - start)


def vary(scene, name, value, q, v):
    """(scene, q, v) with `name` set to `value`: a parameter of the scene, or a state variable Newton-Raphson holds
    (the top's spin rate)."""
    if name in scene.params:
        return scene.with_params(**{name: value}), q, v
    x = np.concatenate([q, v])
    x[state_names(scene.coords).index(name)] = value
    n = len(q)
    return scene, x[:n], x[n:]


def stable_equilibrium(scene, table, name, value, guess):
    """(scene, equilibrium, verdict) of the derivation with `name` at `value`, starting from `guess` (q, v);
    (scene, None, why) where there is none."""
    scene, q, v = vary(scene, name, value, *guess)
    try:
        eq = equilibrium(scene.model("reference"), 0.0, q, v, table["solve"], scene.coords)
    except NoEquilibrium as error:
        return scene, None, str(error)
    return scene, eq, modal(derivation_linear(scene.model("reference"), "reference", eq)).verdict


BOUNDARY_RESOLUTION = 1e-6  # the bisection's relative width: far below any formula's difference worth naming
GROWN = 10.0  # a run whose displacement grows beyond this many times its start's has left the equilibrium
EITHER_SIDE = 0.02  # the runs either side of the boundary, this far from it (relative)


def boundary_search(case, scene, table, settings_, progress):
    """Bisection on the parameter between the bracket's stable and unstable ends (unstable: no equilibrium
    near the last stable one, or an eigenvalue with a positive real part), each equilibrium from the last
    stable one; then the derivation's runs from the stable side's equilibrium, displaced along its slowest
    mode, with the parameter either side of the boundary.  Returns (boundary, sentences)."""
    parameter = settings_["parameter"]
    if progress:
        progress(f"{case.name}: stability boundary in {parameter}")
    ends = [scene.value(x, "vibration.boundary.bracket") for x in settings_["bracket"]]
    guess = (table["q"], table["v"])
    states = [stable_equilibrium(scene, table, parameter, x, guess)[1:] for x in ends]
    stable = [eq is not None and verdict_ != "unstable" for eq, verdict_ in states]
    if stable[0] == stable[1]:
        return None, [f"The bracket {parameter} in [{ends[0]:g}, {ends[1]:g}] does not hold the boundary: the "
                      f"equilibrium is {'stable' if stable[0] else 'unstable or absent'} at both ends."]
    good, bad = (0, 1) if stable[0] else (1, 0)
    x_good, x_bad, eq_good = ends[good], ends[bad], states[good][0]
    while abs(x_bad - x_good) > BOUNDARY_RESOLUTION * abs(x_good):
        mid = 0.5 * (x_good + x_bad)
        _, eq, verdict_ = stable_equilibrium(scene, table, parameter, mid, (eq_good.q, eq_good.v))
        if eq is not None and verdict_ != "unstable":
            x_good, eq_good = mid, eq
        else:
            x_bad = mid
    boundary = 0.5 * (x_good + x_bad)
    expected = scene.value(settings_["expected"], "vibration.boundary.expected")
    sentences = [f"Boundary from the eigenvalues: {parameter} = {boundary:.7g} {unit(case, parameter)} (bisection to "
                 f"{BOUNDARY_RESOLUTION:.0e}); the formula `{settings_['expected']}` gives {expected:.7g}: "
                 f"{(boundary / expected - 1):+.1e} relative.  {' '.join(settings_['why'].split())}"]
    sentences += [either_side(case, scene, table, parameter, boundary, side, x_good > x_bad) for side in (+1, -1)]
    return boundary, sentences


def unit(case, name):
    """The unit of a parameter or a state variable."""
    if name in case.units:
        return case.units[name]
    coord = name.removesuffix("_rate")
    base = dict(zip(case.coords, case.spec["coord_units"]))[coord]
    return f"{base}/s" if name.endswith("_rate") else base


def either_side(case, scene, table, parameter, boundary, side, stable_above):
    """A sentence on the derivation's run with the parameter at boundary (1 + side EITHER_SIDE): started at the
    stable side's equilibrium displaced by the amplitude along its slowest mode, over `periods` of that mode;
    its largest displacement over the start's says whether the motion stays near the equilibrium."""
    stable_value = boundary * (1 + EITHER_SIDE if stable_above else 1 - EITHER_SIDE)
    value = boundary * (1 + side * EITHER_SIDE)
    stable_scene, eq, _ = stable_equilibrium(scene, table, parameter, stable_value, (table["q"], table["v"]))
    if eq is None:
        return f"No run at {parameter} = {value:.5g}: no equilibrium on the stable side to start from."
    linear_ = derivation_linear(stable_scene.model("reference"), "reference", eq)
    modes = modal(linear_)
    slowest = modes.oscillating()[0]
    n = len(eq.q)
    period = 2 * math.pi / modes.eigenvalues[slowest].imag
    full = modes.right[:, slowest] / modes.right[:n, slowest][np.argmax(np.abs(modes.right[:n, slowest]))]
    amplitude = table["amplitude"]
    start = eq.state + amplitude * full.real
    run_scene, q0, v0 = vary(scene, parameter, value, start[:n], start[n:])
    start = np.concatenate([q0, v0])
    model = run_scene.model("reference")
    t_end = table["periods"] * period
    output_step = t_end / (table["periods"] * RUNS_PER_PERIOD)
    try:
        with np.errstate(all="ignore"):
            run = simulate(model, (start[:n], start[n:]), t_end, "DOP853", rtol=case.integration["rtol"],
                           output_step=output_step, work=False, max_step=period / 20, omega=2 * math.pi / period)
        # the coordinates at rest in the equilibrium: a cyclic one's angle drifts at a changed rate, and stays one
        resting = eq.v == 0
        q = (run[list(case.coords)].to_numpy() - (eq.q + np.outer(run.index.to_numpy(), eq.v)))[:, resting]
        grown = float(np.max(np.abs(q)) / amplitude)
        ended = f"its displacement reaches {grown:.3g} times the start's"
    except (Unstable, ArithmeticError) as error:
        grown, ended = math.inf, f"it blew up ({error})"
    stays = grown < GROWN  # a stable mode's linear motion stays at its start's size
    expect_stable = (value > boundary) == stable_above
    agree = "as the eigenvalues say" if stays == expect_stable else "AGAINST the eigenvalues"
    return (f"Run at {parameter} = {value:.5g} ({side * EITHER_SIDE:+.0%} of the boundary), from the equilibrium at "
            f"{stable_value:.5g} displaced by {amplitude:g} along its slowest mode, over {t_end:.3g} s: {ended} "
            f"(beyond {GROWN:g} counts as leaving): {'stays near' if stays else 'leaves'} the equilibrium, {agree}.")
