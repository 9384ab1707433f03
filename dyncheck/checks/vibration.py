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

Sources: the derivation by central differences of its accelerations, extrapolated (an error estimate from the
same at twice the step); MuJoCo and Pinocchio by their own derivatives (their adapters' `linearisation`:
MuJoCo's finite-differenced inverse dynamics, Pinocchio's analytic RNEA derivatives).  Eigenvalues carry a
first-order perturbation bound from their matrix's error estimate, entry by entry (|d lambda| <= |y|^T |dA| |x|
/ |y^H x|, y and x the left and right eigenvectors), which sets every tolerance on them.

Where the base's motion makes the equations periodic in t, `[vibration.floquet]` linearises them about a
periodic motion instead (`floquet`): the orbit by shooting, each source's monodromy matrix along it, its
eigenvalues (the Floquet multipliers) and the largest one checked by stroboscopic runs.

`analyse(case)` returns a `Vibration` (rows included, the Floquet analysis in its `floquet`); the Campbell diagram and
the stability boundaries, a study of `dyncheck report`, are dyncheck.studies.campbell's.
"""

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
from scipy.integrate import DOP853

from dyncheck.common import ceilings, expressions
from dyncheck.results import store
from dyncheck.results.values import Status, no_number, row
from dyncheck.run.simulate import Unstable, fastest_frequency, richardson_factor, scipy_budget, simulate

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
# MuJoCo's step error in a mode's or a stroboscopic run comes from its twin at twice the step (Richardson,
# simulate.richardson_factor): on these small motions, linear and far from chaos, RK4's error goes as dt^4 at both
# steps (omega dt <= 0.02 in the book's cases), and the twin costs half the run where one at half the step costs two.
MUJOCO_TWIN = 2
MUJOCO_TWIN_FACTOR = richardson_factor("mujoco:RK4", 1, MUJOCO_TWIN)  # 1/15: the run's error per twin difference


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
    if "floquet" in table:
        of_parameters(case, "floquet.period", table["floquet"]["period"])
    guesses = {key: table[key] for key in ("q", "v")}
    guesses.update({f"floquet.{key}": table["floquet"][key] for key in ("q", "v") if "floquet" in table})
    for key, guess in guesses.items():
        if len(guess) != n:
            raise ValueError(f"{case.origin}: vibration.{key} has {len(guess)} entries; the case has {n} "
                             f"coordinates ({', '.join(case.coords)})")
    names = state_names(case.coords)
    for name in table["solve"]:
        if name not in names:
            raise ValueError(f"{case.origin}: vibration.solve names '{name}', which is neither a coordinate nor a "
                             f"rate; they are {', '.join(names)}")
    if not table["solve"]:
        raise ValueError(f"{case.origin}: vibration.solve is empty: name the coordinates (or rates) Newton-Raphson "
                         "solves for")
    for parameter in table.get("overrides", {}):
        if parameter not in case.params:
            raise ValueError(f"{case.origin}: vibration.overrides: no parameter '{parameter}'")
    swept = [("campbell", table["campbell"])] if "campbell" in table else []
    swept += [(f"boundary[{i}]", b) for i, b in enumerate(table.get("boundary", []))]
    for field, item in swept:
        name = item["parameter"]
        if name not in case.params and (name not in names or name in table["solve"]):
            raise ValueError(f"{case.origin}: vibration.{field}.parameter = '{name}' is neither a parameter nor a state "
                             f"variable held by Newton-Raphson (one of {', '.join(n for n in names if n not in table['solve'])})")
    linearised(case)  # the linearised scene must be physical too
    # A boundary's formula, and a sweep's or a bracket's scale, need not be a number at every parameter set: where it
    # is not (the top's least spin with its centre of mass below the tip, h < 0, a negative square root), the study
    # says that there is no boundary, or nothing to sweep.
    for i, boundary in enumerate(table.get("boundary", [])):
        for key in ("expected", "scale"):
            if key in boundary:
                of_parameters(case, f"boundary[{i}].{key}", boundary[key])
    if "scale" in table.get("campbell", {}):
        of_parameters(case, "campbell.scale", table["campbell"]["scale"])


def of_parameters(case, field, expression):
    """ValueError naming the file and field unless `expression` parses and names only parameters and pi."""
    try:
        unknown = expressions.names(expression) - set(case.params) - {"pi"}
    except ValueError as error:
        raise ValueError(f"{case.origin}: vibration.{field} = {expression!r} is not an expression: {error}") from None
    if unknown:
        raise ValueError(f"{case.origin}: vibration.{field} = {expression!r} names {', '.join(sorted(unknown))}, "
                         "not a parameter")


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

    @property
    def state(self):
        return np.concatenate([self.q, self.v])


def state_words(names, x):
    """A state for a sentence, each variable to 6 decimals: "psi = 1.526623, psi_rate = -102.132058"."""
    return ", ".join(f"{name} = {round(float(value), 6)}" for name, value in zip(names, x))


def equilibrium(model, t, q, v, solve, coords, mass_matrix=None):
    """Newton-Raphson (`newton`) for the state variables `solve` (names of coordinates and rates), the others held,
    on the generalized forces M q'' over M's diagonal with `mass_matrix(t, q, v)` (Pinocchio's CRBA, for every
    source: M is not singular, so they vanish where q'' does), else on the accelerations.  Where M is nearly
    singular (two pendulums with a light inner mass, m1 = 0.05 kg beside m2 = 2 kg: M's condition 1,000),
    q'' = M^-1 f is far from linear even 0.01 rad from the hanging state: Newton on it went to theta2 = 5 pi
    (m1 = 0.053 kg, l1 = 0.079 m, m2 = 0.71 kg, where every source agreed and the page called a hanging pendulum
    unstable) or did not converge, where on f, linear there, it converges in 3 iterations.  Over M's diagonal, the equations are q'' itself where M is
    diagonal: f alone weighs each equation by its inertia (a spring's angle row by m l^2, l = 20 m near its
    runaway), and Newton then found another equilibrium.  NoEquilibrium if it does not converge."""
    n = len(coords)
    names = state_names(coords)
    unknown = [names.index(name) for name in solve]
    start = np.concatenate([q, v]).astype(float)

    def state(u):
        y = start.copy()
        y[unknown] = u
        return y

    accelerations = lambda u: np.asarray(model.accelerations(t, *np.split(state(u), [n])), dtype=float)

    def forces(u):  # M q'' over M's diagonal: q'' itself where M is diagonal
        mass = np.asarray(mass_matrix(t, *np.split(state(u), [n])), dtype=float)
        return mass @ accelerations(u) / np.diag(mass)

    found = newton(accelerations if mass_matrix is None else forces, accelerations, start[unknown])
    x = state(found.u)
    if not found.converged:
        raise NoEquilibrium(f"Newton-Raphson for {', '.join(solve)} from {state_words(names, start)} did not converge "
                            f"in {NEWTON_ITERATIONS} iterations: the largest |q''| left is "
                            f"{np.max(np.abs(accelerations(found.u))):.3g} at {state_words(names, x)}")
    return Equilibrium(t, x[:n], x[n:], found.residual, found.scale, found.iterations)


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
    for iteration in range(NEWTON_ITERATIONS):
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
    return Newton(u, False)


def steady(model, eq, times):
    """How far the equilibrium is from one at every time: the largest |q''| along q* + q*' t (a relative
    equilibrium's coordinates move at their rates) at `times`, relative to the balancing terms; rounding where
    it is steady (a base whose motion the equations feel, as a spinning arm carrying a spinning disk, makes the
    linearised equations periodic instead)."""
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
        return full(self.errors)

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
    bounds: np.ndarray  # first-order bounds of the eigenvalues under the matrix's error estimate (`eigensystem`)
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
    """Eigenvalues, eigenvectors and the verdict of a linearisation."""
    values, bounds, left, right = eigensystem(linear.state_matrix, linear.full_errors())
    return Modes(values, bounds, left, right, verdict(values, bounds))


def eigensystem(a, errors):
    """(eigenvalues, their bounds, left and right eigenvectors) of a matrix `a` whose entries carry the absolute
    errors `errors`.  Each eigenvector is the null vector of A - lambda I from its singular value decomposition
    (left and right at once): accurate to the matrix's error over the rest of the spectrum's distance, where
    LAPACK's eigenvectors lose digits beside a cluster of near-zero eigenvalues (the top's cyclic coordinates:
    1e-7 from perturbations of 1e-14)."""
    values = scipy.linalg.eigvals(a)
    size = len(a)
    left, right = np.empty((size, size), complex), np.empty((size, size), complex)
    for i, lam in enumerate(values):
        u, _, vh = scipy.linalg.svd(a - lam * np.eye(size))
        left[:, i], right[:, i] = u[:, -1], vh[-1].conj()
    # the eigensolver's own rounding besides: what it leaves in each eigenpair, over the cosine
    cosines = np.abs(np.einsum("ij,ij->j", left.conj(), right))
    left_over = np.array([rounding(a, lam, right[:, i]) for i, lam in enumerate(values)])
    bounds = first_order_change(left, right, errors) + left_over / np.maximum(cosines, EPS)
    order = np.lexsort((values.imag, np.round(np.abs(values), 12)))
    return values[order], bounds[order], left[:, order], right[:, order]


def rounding(a, lam, x):
    """What rounding leaves in an eigenpair (lam, x) of `a`, x of unit length, measured: the residual |A x - lam x|
    as computed, plus a hundred eps times the terms it sums (|A| |x| + |lam| |x|), the rounding in computing it.
    (lam, x) is an exact eigenpair of a matrix that far from A; an eigenvalue moves by it over its cosine, an
    eigenvector over the distance to the rest of the spectrum.  A hundred eps times A's norm, the a priori bound,
    counts a state matrix's rounding |lambda| times over (its rates are |lambda| times its coordinates, its
    stiffness entries |lambda|^2 times its identity's): on a spring-mass pendulum spinning 2.3 times the book's
    rate, 75 times, and its mode shapes' tolerances came above their ceilings where every source agreed to 5e-11."""
    return float(np.linalg.norm(a @ x - lam * x)
                 + 1e2 * EPS * np.linalg.norm(np.abs(a) @ np.abs(x) + abs(lam) * np.abs(x)))


def first_order_change(left, right, errors):
    """The first-order change of each eigenvalue (columns of the eigenvectors `left`, `right`) under entry errors
    `errors` of its matrix, entry by entry: |y|^T |dA| |x| / |y^H x| (invariant under rescaling a coordinate, which
    the norm bound ||dA|| / s is not: psi in rad beside l in m)."""
    cosines = np.abs(np.einsum("ij,ij->j", left.conj(), right))
    return np.einsum("ij,ik,kj->j", np.abs(left), errors, np.abs(right)) / np.maximum(cosines, EPS)


def full(errors):
    """Errors (n, 2n) of A's lower block as a (2n, 2n) matrix: the upper block, [0, I], is exact."""
    return np.vstack([np.zeros_like(errors), errors])


def term_errors(linear):
    """Entry errors of a term of relative size ceilings.POINTWISE in every entry of A's lower block: what the
    linearisation rows' ceilings are made of.  An eigenvalue or a mode shape moves under them by its own
    condition (a shape beside a near eigenvalue by much more than 1e-6): a tolerance above that change could pass
    such a term, and proves nothing."""
    return ceilings.POINTWISE * np.abs(linear.state_matrix[linear.n:])


def verdict_row(quantity, sources, first, second):
    """Two sources' verdicts: the error counts a disagreement as 1, and none is allowed (a tolerance of 1 or more would
    pass one: the ceiling is half that)."""
    return row("vibration", quantity, sources, float(first != second), 0.0, f"{first} vs {second}", ceiling=0.5)


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


def along(vector, n):
    """The real state displacement along an eigenvector (coordinates, then rates), scaled so that its largest
    coordinate component is 1."""
    return (vector / vector[:n][np.argmax(np.abs(vector[:n]))]).real


STEPS_PER_PERIOD = 20  # a mode's DOP853 run steps at most a twentieth of its period (mode_run)


def step_cap(lam):
    """The longest step of a DOP853 run of the mode of eigenvalue lam: a STEPS_PER_PERIOD-th of its period."""
    return 2 * math.pi / lam.imag / STEPS_PER_PERIOD


def dop853_exponent_error(lam, step):
    """How far DOP853 at steps of `step` moves the exponent lambda of a linear motion exp(lambda t): per step its
    stability function R(z) = 1 + z b^T (I - z A)^-1 1 multiplies the state by R(lambda h) where the motion is
    multiplied by exp(lambda h), so |log R(lambda h) / h - lambda|.  Exact for the linear motion at that step, an
    upper bound where the tolerance takes shorter ones (the error falls as h^8).  At a mode's cap (|lambda| h =
    2 pi / 20) it is 6.1e-12 of |lambda|, which a mode's rows allowed nothing for: a spring-mass pendulum's 5.37 rad/s
    mode measured 6.3e-12 off in its run and failed at a tolerance of 5.0e-12 (pytest -m slow)."""
    z = lam * step
    stages = DOP853.n_stages
    growth = 1 + z * DOP853.B @ np.linalg.solve(np.eye(stages) - z * DOP853.A[:stages, :stages], np.ones(stages))
    return float(abs(np.log(growth) / step - lam))


def mode_run(case, model, source, eq, modes, i, amplitude, periods, method, dt=None):
    """The run of `model` from the equilibrium displaced by `amplitude` along mode i of `modes`, measured."""
    n = len(eq.q)
    lam = modes.eigenvalues[i]
    start = eq.state + amplitude * along(modes.right[:, i], n)
    period = 2 * math.pi / lam.imag
    coarsest = MUJOCO_TWIN * case.integration["mujoco_step"]  # MuJoCo's twin's step: the outputs fall on both runs' steps
    output_step = coarsest * max(1, round(period / RUNS_PER_PERIOD / coarsest))
    t_end = output_step * round(periods * period / output_step)
    options = {"dt": dt} if dt else {"rtol": case.integration["tight_rtol"], "max_step": step_cap(lam),
                                     "omega": abs(lam)}
    try:
        with np.errstate(all="ignore"):
            run = simulate(model, (start[:n], start[n:]), t_end, method, output_step=output_step, work=False,
                           quantities=(), **options)
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
    shift: tuple  # per oscillating mode of the reference: the nonlinear shift of its lambda at the amplitude
    rows: tuple
    failure: str = ""  # why there is no analysis (no equilibrium, a periodic one)
    floquet: "Floquet | None" = None  # about the periodic motion of [vibration.floquet]


ENGINES = ("mujoco", "pinocchio")


def analyse(case):
    """The equilibrium of `[vibration]`, each source's linearisation and modes, the motion of every
    oscillating mode in every source, and the rows that compare them; with `[vibration.floquet]` also the
    periodic motion's (`floquet`), its rows after the equilibrium's.  None for a case without the table."""
    table = settings(case)
    if table is None:
        return None
    # At absurd parameters (a mass of 1e300) an engine's or the derivation's arithmetic can fail anywhere in the
    # analysis (a singular mass matrix, an eigenvalue problem of infinities): a failing row that says where, no traceback.
    failed = lambda error: f"the analysis failed: {type(error).__name__}: {error}"
    try:
        about_equilibrium = equilibrium_analysis(case, table)
    except (ArithmeticError, ValueError) as error:  # LinAlgError is a ValueError
        why = failed(error)
        failing = no_number("vibration", "equilibrium", ("reference",) + ENGINES, why, Status.FAIL)
        about_equilibrium = no_equilibrium(table, [failing], why)
    try:
        periodic = floquet(case)
    except (ArithmeticError, ValueError) as error:
        why = failed(error)
        periodic = no_orbit(case, floquet_settings(case), math.nan,
                            [no_number("vibration", "periodic orbit", ("reference",), why, Status.FAIL)], why)
    if periodic is None:
        return about_equilibrium
    return replace(about_equilibrium, floquet=periodic, rows=about_equilibrium.rows + periodic.rows)


def equilibrium_analysis(case, table):
    """`analyse` about the equilibrium."""
    scene = linearised(case)
    check = "vibration"
    reference = scene.model("reference")
    try:
        eq = equilibrium(reference, 0.0, table["q"], table["v"], table["solve"], case.coords,
                         scene.model("pinocchio").mass_matrix)
    except NoEquilibrium as error:
        return without_equilibrium(scene, table, str(error))
    rows = []  # Newton-Raphson's residual is its own stopping rule, no check: the page states it
    horizon = case.initial[2]
    drift = steady(reference, eq, (0.29 * horizon, 0.71 * horizon))
    if drift > NEWTON_TOLERANCE * SAFETY:
        why = (f"not an equilibrium at every time: the accelerations along q* + q*' t reach {drift:.2e} of the "
               "balancing terms (the base's motion makes the linearised equations periodic: linearise about a "
               "periodic motion instead, [vibration.floquet])")
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
        found = equilibrium(scene.model("mujoco"), 0.0, table["q"], table["v"], table["solve"], scene.coords,
                            scene.model("pinocchio").mass_matrix)
    except NoEquilibrium:
        row_ = no_number("vibration", "equilibrium", ("reference", "mujoco"),
                         f"Newton-Raphson finds none from the guess in either: {why}", Status.NOT_APPLICABLE)
    else:
        row_ = no_number("vibration", "equilibrium", ("reference", "mujoco"),
                         f"MuJoCo has one at {state_words(state_names(scene.coords), found.state)}, the "
                         f"derivation none: {why}", Status.FAIL)
    return no_equilibrium(table, [row_], why)


def no_equilibrium(table, rows, why):
    """The analysis of a case without an equilibrium to linearise about: its rows and why."""
    return Vibration(table["why"], table["overrides"], None, {}, {}, (), (), tuple(rows), why)


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
                moved = first_order_change(mo_a.left[:, [i]], mo_a.right[:, [i]], full(term_errors(la)))[0] / abs(lam)
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
            rows.append(verdict_row("stability", (a, b), mo_a.verdict, mo_b.verdict))
    return rows


def shape_bound(linear, modes, i, errors=None):
    """First-order bound of mode i's shape (largest component 1) under the matrix's errors, entry by entry:
    dx = -R dA x with R the reduced resolvent of A - lambda I (its pseudo-inverse without the eigenvector's own
    null direction), so |dx| <= |R| |dA| |x|, plus the eigensolver's rounding (`rounding`) over R; twice that
    (rescaling to the largest component moves the others by as much again) over the largest component's size.
    `errors` (n, 2n): other entry errors than the matrix's own estimate."""
    a, lam = linear.state_matrix, modes.eigenvalues[i]
    u, sigma, vh = scipy.linalg.svd(a - lam * np.eye(len(a)))
    resolvent = (vh[:-1].conj().T / sigma[:-1]) @ u[:, :-1].conj().T
    x = np.abs(modes.right[:, i])
    entries = linear.full_errors() if errors is None else full(errors)
    spread = np.abs(resolvent) @ (entries @ x) + rounding(a, lam, modes.right[:, i]) / sigma[-2]
    n = linear.n
    return 2 * float(np.max(spread[:n])) / float(np.max(x[:n]))


MATRIX_NAMES = {"M": "mass", "K": "stiffness", "N": "circulatory", "D": "damping", "G": "gyroscopic"}


def mode_label(modes, i):
    """"mode 1" ... in the order of the oscillating modes' frequencies."""
    return f"mode {modes.oscillating().index(i) + 1}"


HALVINGS = 6  # of the case's amplitude at most (settled_amplitude): its nonlinear shift falls 4,096-fold


def settled_amplitude(amplitude, size, reference_run, shift_of):
    """The amplitude of a vibration check's runs, the reference's runs at it and at twice it, and the nonlinear shift
    they show (`shift_of(run, twin)`; inf where either failed): the case's amplitude, halved while SAFETY times the
    shift is above a tenth of ceilings.MOTION of `size` (|lambda|, |mu|), at most HALVINGS times.  At the book's
    numbers the case's amplitude keeps its share under that; off them (a faster disk, a lighter bob) it can put
    every source's row above its ceiling, inconclusive, where a smaller displacement measures the same linear
    motion.  `reference_run(amplitude)`: the reference's run at it; a halving's run at twice its amplitude is the
    last one's run."""
    doubled = reference_run(2 * amplitude)
    for halvings in range(HALVINGS + 1):
        run = reference_run(amplitude)
        shift = shift_of(run, doubled) if run.ok and doubled.ok else math.inf
        if halvings == HALVINGS or not (math.isfinite(shift) and SAFETY * shift > ceilings.MOTION / 10 * size):
            return amplitude, (run, doubled), shift
        amplitude, doubled = amplitude / 2, run


def motion_checks(case, scene, eq, modes, table):
    """Every oscillating mode of the reference run in each source at the case's amplitude (settled_amplitude): its
    runs (Motion), and per mode the nonlinear shift of lambda = growth + i frequency at the amplitude, estimated by
    the reference's run at twice it: their difference is three times the shift for a shift quadratic in the
    amplitude (a frequency's), once it for a linear one (a decay rate's may be), so it bounds both."""
    periods = table["periods"]
    dt = case.integration["mujoco_step"]
    ref = modes["reference"]
    motions, shift = [], []
    for i in ref.oscillating():
        # each source displaced along, and measured by, its own mode: its run tests its own linearisation
        own = {source: (scene.model(source), modes[source], match(ref, modes[source])[i]) for source in modes}
        run = lambda source, method, amplitude, step=None: mode_run(case, own[source][0], source, eq, own[source][1],
                                                                   own[source][2], amplitude, periods, method, step)
        amplitude, (reference, twin), mode_shift = settled_amplitude(
            table["amplitude"], abs(ref.eigenvalues[i]), lambda a: run("reference", "DOP853", a),
            lambda at, doubled: abs(doubled.exponent - at.exponent))
        motions += [reference, run("pinocchio", "DOP853", amplitude), run("mujoco", "mujoco:RK4", amplitude, dt),
                    twin, run("mujoco", "mujoco:RK4", amplitude, MUJOCO_TWIN * dt)]
        shift.append(mode_shift)
    return motions, shift


def unmeasured(motion, mujoco_twin, mujoco_doubled=None):
    """Why a source's run measures nothing (it failed; MuJoCo's twin failed, so that its step error is unknown, or
    its run with its approximations doubled, where there is one, so that their effect is unknown), or None."""
    if not motion.ok:
        return motion.why
    if motion.source == "mujoco" and not mujoco_twin.ok:
        return f"its step error is unknown: its twin at twice the step failed ({mujoco_twin.why})"
    if motion.source == "mujoco" and mujoco_doubled is not None and not mujoco_doubled.ok:
        return f"its approximations' effect is unknown: its run with them doubled failed ({mujoco_doubled.why})"
    return None


def motion_rows(case, modes, motions, shift):
    """Each source's lambda = growth + i frequency in its run against its own linearisation's eigenvalue,
    relative to |lambda|: allowed SAFETY times the nonlinear shift at the amplitude, plus the step error (MuJoCo's RK4
    at dt and at twice it: their difference is 15 times the error at dt; DOP853's at its cap, dop853_exponent_error),
    plus the eigenvalue's own bound; the
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
            why = unmeasured(motion, mujoco_twin)
            if why:
                rows.append(no_number("vibration", label, (source,), why))
                continue
            j = match(reference, modes[source])[i]
            lam = modes[source].eigenvalues[j]
            step_error = (abs(motion.exponent - mujoco_twin.exponent) * MUJOCO_TWIN_FACTOR if source == "mujoco"
                          else dop853_exponent_error(lam, step_cap(lam)))
            allowed = SAFETY * (shift[k] + step_error + modes[source].bounds[j]) / abs(lam) + ceilings.ROUNDING_FLOOR
            rows.append(row("vibration", label, (source,), abs(motion.exponent - lam) / abs(lam), allowed,
                            f"run {motion.growth:.3g} + {motion.frequency:.10g} i, linear {lam.real:.3g} + "
                            f"{lam.imag:.10g} i (1/s); amplitude {motion.amplitude:g}, its nonlinear shift "
                            f"{shift[k] / abs(lam):.1e}", ceiling=ceilings.MOTION))
    return rows


# -- about a periodic motion: Floquet ---------------------------------------------------------------
# Where the base's motion makes the equations periodic in t (the book's arm and disk both turning: seen from the
# disk, the arm's centripetal acceleration turns at the disk's rate), there is no equilibrium but a periodic
# motion, x(t + T) = x(t).  Small motions about it obey x' = A(t) x with A periodic; over one period they are
# multiplied by the monodromy matrix Phi(T), and its eigenvalues, the Floquet multipliers mu, say whether they grow
# (some |mu| > 1), decay (every |mu| < 1) or neither.

# A(t) is sampled along the orbit at SAMPLES points of the period and interpolated trigonometrically (it is
# periodic and smooth): the variational equations then cost no evaluation of a model, where integrating them with
# the orbit would evaluate a source's linearisation at each of DOP853's ~13 stages per step (MuJoCo's takes
# 0.5 ms, the derivation's `jacobian` 3 to 6 ms: 2 to 15 s per period of the book's 1.8.1 at its tight rtol).
# Along the book's orbits A's harmonics fall to the rounding of its entries by the 8th multiple of the
# period's frequency; SAMPLES resolves up to the 16th.  The twin from every other sample, integrated 100 times
# less tightly, measures the interpolation's error with the integrator's.
SAMPLES = 32
# Shooting stops when |x(T) - x(0)| stays within 10 % over STALL iterations: Newton's steps then do nothing, from a
# monodromy matrix the samples do not resolve (a spring-mass pendulum at m = 1e-4 kg, omega = 4,472 rad/s, kept it at
# 31 for all 50 iterations: 137 s of the reference's and MuJoCo's runs).  A step that shrinks it slowly, or only now
# and then, goes on (a pendulum on a disk turning at beta' = -40 rad/s: 0.6-fold per iteration from the 15th, after
# a dip at the 10th, and converges at the 27th); at the book's numbers it falls at least 300-fold at every one.
STALL = 5


class NoOrbit(ValueError):
    """Shooting found no periodic motion; the message says from where, and what was left."""


@dataclass(frozen=True)
class OrbitPoint:
    """A state of the periodic motion, where a source is linearised (what `derivation_linear` and
    `engine_linear` read of an equilibrium)."""
    t: float
    q: np.ndarray
    v: np.ndarray

    @property
    def state(self):
        return np.concatenate([self.q, self.v])


@store.register
@dataclass(frozen=True)
class Monodromy:
    """Phi(T) from one source, its error estimate (entry by entry), its eigenvalues (the Floquet multipliers, with
    first-order bounds from the error estimate, as `modal`'s), eigenvectors and the verdict."""
    source: str
    matrix: np.ndarray  # Phi(T), (2n, 2n), x = (dq, dq')
    errors: np.ndarray  # |Phi(T) - its twin's| (every other sample of A, the case's rtol instead of its tight one)
    trace_integral: float  # the integral of trace A over the period: det Phi(T) = exp of it (Liouville)
    multipliers: np.ndarray  # complex, sorted by |mu| then imaginary part
    bounds: np.ndarray
    left: np.ndarray
    right: np.ndarray
    verdict: str
    method: str  # of the source's linearisation

    @property
    def eigenvalues(self):
        """The multipliers, as `match` reads them."""
        return self.multipliers

    def distinct(self):
        """Indices of the multipliers shown: every real one and one of each complex pair (imaginary part >= 0)."""
        return [i for i, (mu, bound) in enumerate(zip(self.multipliers, self.bounds)) if mu.imag >= -SAFETY * bound]

    def largest(self):
        """The multiplier of largest |mu| (among those within SAFETY bounds of it, the largest imaginary part)."""
        size = np.abs(self.multipliers)
        near = np.flatnonzero(size >= np.max(size - SAFETY * self.bounds))
        return int(near[np.argmax(self.multipliers[near].imag)])


@store.register
@dataclass(frozen=True)
class Floquet:
    """The periodic motion of `[vibration.floquet]`, each source's monodromy matrix and multipliers, and their
    check by stroboscopic runs: what the page's subsection shows."""
    why: str
    period: float  # T, s
    orbit: np.ndarray  # the derivation's states over one period from t = 0, at 2 SAMPLES + 1 equal steps or more
    iterations: int  # of shooting Newton-Raphson
    monodromy: dict  # {source: Monodromy}
    motions: tuple  # of Motion: (reference, pinocchio, mujoco, reference at twice the amplitude, mujoco at twice the
    # step, and mujoco with its approximations doubled where its scene has any)
    shift: float  # the nonlinear shift of the largest multiplier at the amplitude
    rows: tuple
    failure: str = ""  # why there is no analysis (T not a period of the equations, no orbit)
    residual: float = math.nan  # |x(T) - x(0)| left by shooting (its stopping rule: within the run's own error estimate)
    residual_error: float = math.nan  # that estimate
    continued: int = 0  # steps of the continuation from the book's orbit that found it (continued_orbit), 0: none
    seeded: bool = False  # shot from MuJoCo's orbit, where neither the guess nor the continuation found it


def floquet_settings(case):
    """The case's `[vibration.floquet]` table with its guess evaluated (the period is evaluated by `period_of`), or
    None."""
    table = case.spec.get("vibration", {}).get("floquet")
    if table is None:
        return None
    return {**table, "q": np.array([case.value(x, "vibration.floquet.q") for x in table["q"]]),
            "v": np.array([case.value(x, "vibration.floquet.v") for x in table["v"]])}


def period_of(case, table):
    """T at the case's parameters; ValueError saying why there is none (a disk at rest relative to the arm: the
    equations do not depend on t, and 2 pi / beta' has no value)."""
    period = case.value(table["period"], "vibration.floquet.period")
    if period <= 0:
        raise ValueError(f"{case.origin}: vibration.floquet.period = {table['period']!r} is {period:g}, not > 0")
    return period


def no_orbit(case, table, period, rows, why):
    """The Floquet analysis of a case without a periodic motion to linearise about (no period, no orbit): its rows
    and why."""
    return Floquet(table["why"], period, np.empty((0, 2 * len(case.coords))), 0, {}, (), math.nan, tuple(rows), why)


def floquet(case):
    """The periodic motion of `[vibration.floquet]` at the case's own numbers: the period checked, the orbit by
    shooting, each source's monodromy matrix and multipliers, their comparison, the stroboscopic runs; None for a
    case without the table."""
    table = floquet_settings(case)
    if table is None:
        return None
    check = "vibration"
    try:
        period = period_of(case, table)
    except ValueError as error:
        why = f"no period at these parameters: {error}"
        return no_orbit(case, table, math.nan, [no_number(check, "periodic motion", ("reference",), why,
                                                           Status.NOT_APPLICABLE)], why)
    drift = periodicity(case, case.model("reference"), period)
    rows = [row(check, f"period T = {period:.10g} s of the equations", ("reference",), drift, NEWTON_TOLERANCE,
                "|q''(t + T, q, q') - q''(t, q, q')| at the case's random states, relative to the largest |q''|; "
                "allowed: rounding", ceiling=ceilings.POINTWISE)]
    if drift > NEWTON_TOLERANCE:
        why = f"T = {period:.10g} s is not a period of the equations (they change by {drift:.2e} of their size)"
        return no_orbit(case, table, period, rows, why)
    guess = np.concatenate([table["q"], table["v"]])
    seeded = False
    try:
        (states, iterations, residual, error), continued = continued_orbit(case, guess, period)
    except (NoOrbit, Unstable) as failure:
        shot, missing = shot_from_mujocos_orbit(case, guess, period, str(failure))
        if shot is None:
            rows.append(missing)
            return no_orbit(case, table, period, rows, missing.detail)
        (states, iterations, residual, error), continued, seeded = shot, 0, True
    states, monodromy = resolved_monodromy(case, states, period, rows)
    rows += floquet_rows(monodromy, case.tolerance["pointwise"]["value"])
    motions, shift = stroboscopic_checks(case, states[0], monodromy, table, period)
    rows += stroboscopic_rows(case, monodromy, motions, shift, period)
    return Floquet(table["why"], period, states, iterations, monodromy, tuple(motions), shift, tuple(rows),
                   residual=residual, residual_error=error, continued=continued, seeded=seeded)


def periodicity(case, model, period):
    """How much the accelerations change when t moves by `period`, at the case's random states, relative to the
    largest |q''|: rounding for a period of the equations."""
    change = size = 0.0
    for t, q, v in case.sample_states():
        now, later = (np.asarray(model.accelerations(s, q, v), dtype=float) for s in (t, t + period))
        change, size = max(change, float(np.max(np.abs(later - now)))), max(size, float(np.max(np.abs(now))))
    return change / max(size, EPS)


def orbit_run(case, model, x, period, rtol, steps=2 * SAMPLES):
    """The states of `model`'s run from x at t = 0 over one period by DOP853 at `rtol`, at `steps` + 1 equal times."""
    n = len(case.coords)
    with np.errstate(all="ignore"):
        run = simulate(model, (x[:n], x[n:]), period, "DOP853", rtol=rtol, output_step=period / steps,
                       work=False, omega=fastest_frequency(case), quantities=())
    return run[state_names(case.coords)].to_numpy()


def periodic_orbit(case, source, guess, period, iterations=NEWTON_ITERATIONS):
    """Shooting Newton-Raphson for x0 with phi_T(x0) = x0, phi_T the run over one period at the case's tight rtol,
    the Jacobian Phi(T) - I (the derivation's monodromy matrix along the run).  Converged
    when |phi_T(x0) - x0| is within the run's own error estimate, its difference from the same run at the case's
    rtol: below it, the residual is the integrator's error, and no step can reduce it further.  Returns (the
    states over the period at 2 SAMPLES + 1 times, iterations, the residual and its estimate, each the largest
    over the state variables relative to their scales); NoOrbit if it does not converge."""
    model = case.model(source)
    x = np.asarray(guess, dtype=float)
    integration = case.integration
    residual, error, residuals = math.inf, None, []
    names = state_names(case.coords)
    for iteration in range(iterations):
        states = orbit_run(case, model, x, period, integration["tight_rtol"])
        scale = scales_of(x)
        residual = float(np.max(np.abs(states[-1] - x) / scale))
        if error is None or residual <= error:  # the twin where it may decide: first, and where the last one says so
            loose = orbit_run(case, model, x, period, integration["rtol"])
            error = float(np.max(np.abs(loose[-1] - states[-1]) / scale))
            if residual <= error:
                return states, iteration, residual, error
        residuals = residuals[-STALL:] + [residual]
        if len(residuals) > STALL and max(residuals) <= 1.1 * min(residuals):
            raise NoOrbit(f"shooting Newton-Raphson on the {source} from {state_words(names, guess)} stalled: "
                          f"|x(T) - x(0)| stayed at {min(residuals):.3g} to {max(residuals):.3g} (relative) for "
                          f"{STALL} iterations, at {state_words(names, x)}")
        # from a quarter of the samples: the Jacobian's error (1e-10) is far below what slows Newton's convergence
        samples, _ = state_matrices(case, source, states[:-1:4], period)
        jacobian_, _ = transition(samples[:, None], period, integration["rtol"], fastest_frequency(case))
        try:
            x = x - np.linalg.solve(jacobian_[0] - np.eye(len(x)), states[-1] - x)
        except np.linalg.LinAlgError:  # a multiplier at 1: the orbit is not isolated, shooting cannot pick one
            raise NoOrbit(f"shooting Newton-Raphson on the {source} stopped at iteration {iteration + 1}: Phi(T) - I is "
                          f"singular at {state_words(names, x)} (a multiplier at 1: no isolated periodic "
                          f"motion there); |x(T) - x(0)| left {residual:.3g} (relative)") from None
    raise NoOrbit(f"shooting Newton-Raphson on the {source} from {state_words(names, guess)} did not converge in "
                  f"{iterations} iterations: |x(T) - x(0)| left {residual:.3g} (relative) at "
                  f"{state_words(names, x)}")


SHORTEST_STEP = 1 / 64  # of the continuation, of the way from the book's parameters to the case's
# Newton-Raphson's iterations at a step of the continuation: from the orbit before, a step short enough converges in
# a few (2 to 5 measured), and a longer one is halved rather than iterated on (near a fold it went on for 50)
CONTINUATION_ITERATIONS = 10
# The continuation's shots, the failed ones included: its cost is bounded (at most 10 iterations each, as many as
# two shots from the guess take at most), where steps of 1/64 failing and succeeding in turn would take 131
CONTINUATION_SHOTS = 10


def continued_orbit(case, guess, period):
    """The derivation's periodic orbit by shooting from the case file's guess (periodic_orbit's answer), and how
    many steps of continuation it took.  The guess is made for the book's numbers: where shooting from it fails under
    overrides (Newton-Raphson finds the orbit only from near it, and an orbit moves with the parameters), the
    orbit is continued from the book's, the overridden parameters moved from the book's values to the case's in
    steps of a quarter of the way, each shot from the orbit before at its own parameters' period, a step halved
    where it fails (down to SHORTEST_STEP) and doubled after it succeeds, in at most CONTINUATION_SHOTS shots; a
    step past a [[runaway]] fails (nothing bounded is left there to continue to: a spring-mass pendulum's orbit
    continued below k_crit put the mass through the pivot, at a negative spring length).  NoOrbit says how far it
    got.  (A pendulum whose arm turns at 4 times the book's rate: shot from the guess, Newton stalled at
    |x(T) - x(0)| = 1.7; continued, it converges.)"""
    try:
        return periodic_orbit(case, "reference", guess, period), 0
    except (NoOrbit, Unstable) as failure:
        if not case.overrides or case.runaway():
            raise
        direct = failure
    book = {name: case.defaults[name] for name in case.overrides}
    along = lambda s: case.with_params(**{name: book[name] + s * (value - book[name])
                                          for name, value in case.overrides.items()})

    def shot(at, start, iterations):
        """periodic_orbit at `at`'s parameters and period (the table's period and guess are expressions of them)."""
        table = floquet_settings(at)
        start = np.concatenate([table["q"], table["v"]]) if start is None else start
        return periodic_orbit(at, "reference", start, period_of(at, table), iterations)

    try:
        x = shot(along(0.0), None, NEWTON_ITERATIONS)[0][0]
    except (NoOrbit, Unstable, ValueError) as failure:
        raise NoOrbit(f"{direct}; nor at the book's numbers, to continue from: {failure}") from None
    done, step, steps, failure = 0.0, 0.25, 0, None
    for _ in range(CONTINUATION_SHOTS):
        target = min(1.0, done + step)
        try:
            at = case if target == 1.0 else along(target)
            if at.runaway():
                raise NoOrbit(f"the parameters {target:.3g} of the way are past the case's [[runaway]]")
            found = shot(at, x, CONTINUATION_ITERATIONS)
        except (NoOrbit, Unstable, ValueError) as error:  # ValueError: a step's parameters break a constraint
            failure, step = error, step / 2
            if step < SHORTEST_STEP:
                break
            continue
        steps += 1
        if target == 1.0:
            return found, steps
        done, step, x = target, 2 * step, found[0][0]
    raise NoOrbit(f"{direct}; continued from the book's orbit in {CONTINUATION_SHOTS} shots at most, shooting stopped "
                  f"{done:.3g} of the way to {case.overrides_text()}" + (f": {failure}" if failure else ""))


def shot_from_mujocos_orbit(case, guess, period, why):
    """Where the derivation's shooting from the guess (and the continuation) found no orbit: MuJoCo's shooting from the
    guess, then the derivation's from MuJoCo's orbit.  Returns (periodic_orbit's answer, None) where the derivation
    converges there, or (None, the row): `not applicable` where MuJoCo finds none either (the parameters leave none: a
    spring too soft for the spin), a failure where the derivation has none even from MuJoCo's.  (A pendulum whose arm
    and disk turn at -3.77 and 3.55 rad/s: the derivation's Newton-Raphson from the guess ran off to |psi'| = 282 and
    failed, MuJoCo's converged at psi = -146.04 (on AVX-512 kernels: a path that far from the guess turns on the
    last bits); the derivation converges from there.)"""
    sources = ("reference", "mujoco")
    try:
        found = periodic_orbit(case, "mujoco", guess, period)[0][0]
    except (ValueError, Unstable):  # NoOrbit, a blow-up, a scene MuJoCo cannot linearise
        return None, no_number("vibration", "periodic orbit", sources,
                               f"shooting (Newton-Raphson) finds none from the guess in either: {why}",
                               Status.NOT_APPLICABLE)
    try:
        return periodic_orbit(case, "reference", found, period), None
    except (NoOrbit, Unstable) as failure:
        return None, no_number("vibration", "periodic orbit", sources,
                               f"MuJoCo has one from {state_words(state_names(case.coords), found)}, the derivation "
                               f"none from the guess ({why}) nor from MuJoCo's ({failure})", Status.FAIL)


def state_matrices(case, source, states, period):
    """(A of `source` at `states`, equally spaced over the period from t = 0, (len(states), 2n, 2n), how it was
    linearised): the derivation's by `jacobian`, an engine's by its own derivatives (`engine_linear`)."""
    n = len(case.coords)
    model = case.model(source)
    linearise = derivation_linear if source == "reference" else engine_linear
    times = np.arange(len(states)) * period / len(states)
    linear = [linearise(model, source, OrbitPoint(t, x[:n], x[n:])) for t, x in zip(times, states)]
    return np.array([lin.state_matrix for lin in linear]), linear[0].method


def transition(samples, period, rtol, omega):
    """(Phi(T), the integral of trace A over [0, T]) of X' = A(t) X, X(0) = I, for each of several sources at once
    (one run: the same steps for all), by DOP853 at rtol = atol, with A(t) the trigonometric interpolant of
    `samples`, (N, sources, 2n, 2n): A at t_k = k T / N, k = 0 ... N - 1."""
    count, sources, size = samples.shape[:3]
    coefficients = np.fft.rfft(samples, axis=0) / count
    coefficients[1:(count + 1) // 2] *= 2  # each harmonic below the Nyquist frequency stands for its conjugate too
    frequencies = 2j * math.pi * np.arange(len(coefficients)) / period
    # A(t) = sum_k coefficients[k] exp(frequencies[k] t) as np.tensordot(np.exp(frequencies * t), coefficients,
    # axes=1) computes it (a row times the coefficients flattened, one np.dot), without its set-up at every evaluation
    flattened, shape = coefficients.reshape(len(coefficients), -1), coefficients.shape[1:]

    def variational(t, y):
        a = np.dot(np.exp(frequencies * t).reshape(1, -1), flattened).reshape(shape).real
        return np.concatenate([(a @ y[:-sources].reshape(sources, size, size)).ravel(),
                               np.trace(a, axis1=1, axis2=2)])

    start = np.concatenate([np.tile(np.eye(size).ravel(), sources), np.zeros(sources)])
    end = dop853(variational, start, period, rtol, omega)
    return end[:-sources].reshape(sources, size, size), end[-sources:]


def dop853(rhs, start, t_end, rtol, omega):
    """y(t_end) of y' = rhs(t, y), y(0) = start, by scipy's DOP853 at rtol = atol, within the step budget of a run
    of frequency omega (dyncheck.run.simulate.scipy_budget); Unstable if it blows up or exceeds it."""
    budget = scipy_budget("DOP853", t_end, rtol, np.inf, omega)
    solver = DOP853(rhs, 0.0, start, t_end, rtol=rtol, atol=rtol)
    steps = 0
    with np.errstate(all="ignore"):  # a blow-up is the Unstable below, not a warning on the way to it
        while solver.status == "running":
            message = solver.step()
            steps += 1
            if solver.status == "failed" or not np.all(np.isfinite(solver.y)):
                raise Unstable("DOP853", solver.t, steps, message or "state is not finite")
            budget.check(solver.t, steps)
    return solver.y


# The samples of A along the orbit are doubled (the orbit's run again with twice the outputs) while the monodromy
# matrix's error estimate would put its rows' tolerance above a tenth of their ceiling, at most REFINEMENTS times.  The
# estimate is the twin's, from every other sample: where A's harmonics reach past the twin's Nyquist frequency (the
# 16th multiple of 2 pi / T), it measures the twin's interpolation, not the samples'.  A pendulum whose arm and disk
# turn at -5 and -2.8 rad/s (T = 2.24 s): 1.5e-6 of Phi's largest entry from 64 samples (every row inconclusive), 8e-10
# from 128 (the twin's looser integration, now), and Phi from 64 and from 128 samples 6e-12 apart.  At the book's
# numbers the estimate keeps within its share: its 4.0e-9 and 1.7e-10 are the twin's integration, which more samples
# would not lower.
REFINEMENTS = 2


def resolved_monodromy(case, states, period, rows):
    """(the orbit's states, {source: Monodromy}) from A sampled at the orbit's `states` (2 SAMPLES + 1 over the
    period), the samples doubled while the error estimate is above its share (REFINEMENTS); a source that cannot be
    linearised (a scene with closed loops) is a row appended to `rows`."""
    sources, share = ("reference",) + ENGINES, math.inf
    for refinement in range(REFINEMENTS + 1):
        samples = {}
        for source in sources:
            try:
                samples[source] = state_matrices(case, source, states[:-1], period)
            except ValueError as failure:  # a scene the engine cannot linearise (closed loops)
                rows.append(no_number("vibration", "monodromy matrix", (source,), str(failure), Status.FAIL))
        sources = tuple(samples)  # a source that fails is a row once
        monodromy = monodromies(case, samples, period)
        # a tenth of the rows' ceiling for the estimate, SAFETY times for each of a row's two sources; more samples
        # go on only while they halve it (they do not lower the twin's integration error)
        last, share = share, max(2 * SAFETY * np.max(m.errors) / np.max(np.abs(m.matrix)) for m in monodromy.values())
        if refinement == REFINEMENTS or share <= ceilings.POINTWISE / 10 or share > last / 2:
            return states, monodromy
        states = orbit_run(case, case.model("reference"), states[0], period, case.integration["tight_rtol"],
                           2 * (len(states) - 1))


def monodromies(case, samples, period):
    """{source: Monodromy} from `samples`, {source: (A at equal steps over the period, method)}: Phi(T)
    by DOP853 at the case's tight rtol; its error estimate, the difference from the same from every other sample at
    the case's rtol (the twin's interpolation and integration errors both larger, so it bounds them)."""
    integration, omega = case.integration, fastest_frequency(case)
    stacked = np.stack([matrices for matrices, _ in samples.values()], axis=1)
    matrices, traces = transition(stacked, period, integration["tight_rtol"], omega)
    twins, _ = transition(stacked[::2], period, integration["rtol"], omega)
    monodromy = {}
    for (source, (_, method)), matrix, twin, trace in zip(samples.items(), matrices, twins, traces):
        errors = np.abs(matrix - twin)
        multipliers, bounds, left, right = eigensystem(matrix, errors)
        monodromy[source] = Monodromy(source, matrix, errors, float(trace), multipliers, bounds, left, right,
                                      floquet_verdict(multipliers, bounds), method)
    return monodromy


def floquet_verdict(multipliers, bounds):
    """"unstable" where some |mu| exceeds 1 by more than SAFETY times its bound; "asymptotically stable" where every
    |mu| is below 1 by more than that; else "marginally stable" (on the unit circle within the bounds: small motions
    neither grow nor decay over a period in the linear equations, and the nonlinear terms decide)."""
    size = np.abs(multipliers)
    if np.any(size - 1 > SAFETY * bounds):
        return "unstable"
    if np.all(1 - size > SAFETY * bounds):
        return "asymptotically stable"
    return "marginally stable"


def floquet_rows(monodromy, pointwise):
    """Each pair of sources: Phi(T), each multiplier (one of each complex pair, numbered as the derivation's), the
    verdict.  Allowed: both error estimates (bounds) times SAFETY plus the case's pointwise tolerance (what the scenes
    model differently), relative."""
    rows = []
    reference = monodromy["reference"]
    sources = list(monodromy)
    for k, a in enumerate(sources):
        for b in sources[k + 1:]:
            mo_a, mo_b = monodromy[a], monodromy[b]
            scale = np.max(np.abs(mo_a.matrix))
            rows.append(row("vibration", "monodromy matrix Phi(T)", (a, b),
                            np.max(np.abs(mo_a.matrix - mo_b.matrix)) / scale,
                            SAFETY * (np.max(mo_a.errors) + np.max(mo_b.errors)) / scale + pointwise,
                            f"relative to its largest entry ({scale:.3g})", ceiling=ceilings.POINTWISE))
            for label, r in enumerate(reference.distinct(), start=1):
                i, j = match(reference, mo_a)[r], match(reference, mo_b)[r]
                mu, other = mo_a.multipliers[i], mo_b.multipliers[j]
                # as an eigenvalue's of A: a small multiplier beside a large one (mu = 0.017 beside 59) moves under
                # Phi's errors by far more than 1e-6 of itself
                moved = first_order_change(mo_a.left[:, [i]], mo_a.right[:, [i]],
                                           ceilings.POINTWISE * np.abs(mo_a.matrix))[0] / abs(mu)
                rows.append(row("vibration", f"Floquet multiplier {label}", (a, b), abs(other - mu) / abs(mu),
                                SAFETY * (mo_a.bounds[i] + mo_b.bounds[j]) / abs(mu) + pointwise,
                                f"{multiplier_text(mu)} vs {multiplier_text(other)}; ceiling: the multiplier's change "
                                f"under a term of {ceilings.POINTWISE:g} of every entry of Phi(T)",
                                ceiling=max(ceilings.POINTWISE, moved)))
            rows.append(verdict_row("stability (Floquet)", (a, b), mo_a.verdict, mo_b.verdict))
    return rows


def multiplier_text(mu):
    """|mu| and its angle in degrees."""
    return f"|mu| {abs(mu):.10g} at {math.degrees(np.angle(mu)):.6g} deg"


def stroboscopic_checks(case, start, monodromy, table, period):
    """The largest multiplier of the derivation measured in runs of `period`s (T) from the orbit's x0 displaced by
    the amplitude (settled_amplitude) along each source's own eigenvector: the derivation and Pinocchio by DOP853 at
    the case's tight rtol, MuJoCo by its RK4 at the longest step no longer than the case's whose double divides T (its
    states, and its twin's, at the multiples of T: a `--set` of the disk's rate moves T off the case's steps), and the
    twins: the derivation at twice the amplitude, MuJoCo at twice the step (MUJOCO_TWIN).  Returns (motions, the
    nonlinear shift of mu at the amplitude, from the derivation's twin: as `motion_checks`'s)."""
    periods = table["periods"]
    twins = math.ceil(period / (MUJOCO_TWIN * case.integration["mujoco_step"]) * (1 - 1e-9))  # twin steps in T
    dt = period / (MUJOCO_TWIN * twins)
    reference = monodromy["reference"]
    i = reference.largest()

    def run(source, method, amplitude, step=None, model=None):
        own = monodromy[source]
        return stroboscopic_run(case, source, start, own, match(reference, own)[i], amplitude, periods,
                                period, method, step, model)

    amplitude, (run_at, twin), shift = settled_amplitude(
        table["amplitude"], abs(reference.multipliers[i]), lambda a: run("reference", "DOP853", a),
        lambda at, doubled: abs(multiplier(doubled, period) - multiplier(at, period)))
    # MuJoCo's scene with its approximations doubled (the drift of the disk's prescribed rate through its armature):
    # a spring held just above its runaway (k = 165 N/m, k_crit = 160) moved MuJoCo's |mu| by 2.7e-7, 50 times the
    # rest of its allowance; a scene without approximations is its own doubled scene, and has no such run
    doubled = case.approximations_doubled()
    approximations = [] if doubled is case.model("mujoco") else [run("mujoco", "mujoco:RK4", amplitude, dt, doubled)]
    return [run_at, run("pinocchio", "DOP853", amplitude), run("mujoco", "mujoco:RK4", amplitude, dt), twin,
            run("mujoco", "mujoco:RK4", amplitude, MUJOCO_TWIN * dt)] + approximations, shift


def stroboscopic_run(case, source, start, monodromy, j, amplitude, periods, period, method, dt=None, model=None):
    """The run of `source` (its `model`, else the case's) over `periods` periods from `start` displaced by
    `amplitude` along multiplier j's eigenvector, sampled once per period: its modal coordinate z_k (the left
    eigenvector's projection of x(kT) - x0) goes as mu^k; mu measured by least squares, z_{k+1} = mu z_k, as the
    exponent log(mu) / T."""
    n = len(start) // 2
    displaced = start + amplitude * along(monodromy.right[:, j], n)
    options = {"dt": dt} if dt else {"rtol": case.integration["tight_rtol"], "omega": fastest_frequency(case)}
    try:
        with np.errstate(all="ignore"):
            run = simulate(model or case.model(source), (displaced[:n], displaced[n:]), periods * period, method,
                           output_step=period, work=False, quantities=(), **options)
    except (Unstable, ArithmeticError, np.linalg.LinAlgError) as error:
        return Motion(source, j, amplitude, None, None, f"{method}: {error}")
    left = monodromy.left[:, j].conj()
    z = (run[state_names(case.coords)].to_numpy() - start) @ left / (left @ monodromy.right[:, j])
    exponent = np.log(np.vdot(z[:-1], z[1:]) / np.vdot(z[:-1], z[:-1])) / period
    return Motion(source, j, amplitude, float(exponent.imag), float(exponent.real))


def multiplier(motion, period):
    """The multiplier a stroboscopic run shows: exp(its exponent T)."""
    return np.exp(motion.exponent * period)


def stroboscopic_rows(case, monodromy, motions, shift, period):
    """Each source's measured multiplier against its own largest one, relative to |mu|: allowed SAFETY times the
    nonlinear shift, MuJoCo's step error (RK4 at dt and at twice it: their difference is 15 times the error at dt) and the
    multiplier's bound and MuJoCo's approximations' effect (its run with them doubled minus its run, which their
    response, linear to first order, makes the effect: at k = 165 N/m 2.58e-7 of an error of 2.70e-7); the ceiling
    that of a mode's run (ceilings.MOTION)."""
    rows = []
    mujoco_twin, doubled = motions[4], (motions[5] if len(motions) > 5 else None)
    for motion in motions[:3]:
        source = motion.source
        label = "largest Floquet multiplier, stroboscopic run"
        why = unmeasured(motion, mujoco_twin, doubled)
        if why:
            rows.append(no_number("vibration", label, (source,), why))
            continue
        own = monodromy[source]
        mu, bound = own.multipliers[motion.mode], own.bounds[motion.mode]
        measured = multiplier(motion, period)
        step_error = abs(measured - multiplier(mujoco_twin, period)) * MUJOCO_TWIN_FACTOR if source == "mujoco" else 0.0
        approximations = 0.0 if doubled is None or source != "mujoco" else abs(multiplier(doubled, period) - measured)
        rows.append(row("vibration", label, (source,), abs(measured - mu) / abs(mu),
                        SAFETY * (shift + step_error + bound + approximations) / abs(mu) + ceilings.ROUNDING_FLOOR,
                        f"run {multiplier_text(measured)}, linear {multiplier_text(mu)}; amplitude {motion.amplitude:g}, "
                        f"its nonlinear shift {shift / abs(mu):.1e}", ceiling=ceilings.MOTION))
    return rows
