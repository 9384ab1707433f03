"""The pieces of the vibration analysis (dyncheck.checks.vibration): the case file's [vibration] table, an
equilibrium by Newton-Raphson, each source's equations linearised about it (the derivation by extrapolated central
differences, each engine by its own derivatives), their eigenvalues and modes with first-order bounds, and a mode's
run."""

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg  # and scipy.integrate on first use (as in dyncheck.run.simulate)

from dyncheck.common import ceilings, expressions
from dyncheck.common.derivatives import EPS, jacobian, newton, scales_of
from dyncheck.results import store
from dyncheck.results.values import row
from dyncheck.run.simulate import Unstable, richardson_factor, simulate

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
                            f"in {found.iterations} iterations: the largest |q''| left is "
                            f"{np.max(np.abs(accelerations(found.u))):.3g} at {state_words(names, x)}")
    return Equilibrium(t, x[:n], x[n:], found.residual, found.scale, found.iterations)


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
    dop853 = scipy.integrate.DOP853
    stages = dop853.n_stages
    growth = 1 + z * dop853.B @ np.linalg.solve(np.eye(stages) - z * dop853.A[:stages, :stages], np.ones(stages))
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


# -- a vibration check's runs, shared with Floquet's -------------------------------------------------

ENGINES = ("mujoco", "pinocchio")
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
