"""Floquet analysis about a periodic motion (`[vibration.floquet]`, where the base's motion makes the equations
periodic in t): the orbit by shooting (continued from the book's parameters where it must be), each source's
monodromy matrix along it, its eigenvalues (the Floquet multipliers), their verdict and rows, and the largest one
checked by stroboscopic runs."""

import math
from dataclasses import dataclass

import numpy as np
import scipy  # scipy.integrate on first use (as in dyncheck.run.simulate)

from dyncheck.checks.linear import (ENGINES, MUJOCO_TWIN, MUJOCO_TWIN_FACTOR, SAFETY, Motion, along, derivation_linear,
                                    eigensystem, engine_linear, first_order_change, match, settled_amplitude,
                                    state_names, state_words, unmeasured, verdict_row)
from dyncheck.common import ceilings
from dyncheck.common.derivatives import EPS, NEWTON_ITERATIONS, NEWTON_TOLERANCE, scales_of
from dyncheck.results import store
from dyncheck.results.values import Status, no_number, row
from dyncheck.run.simulate import Unstable, fastest_frequency, scipy_budget, simulate

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
    solver = scipy.integrate.DOP853(rhs, 0.0, start, t_end, rtol=rtol, atol=rtol)
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
