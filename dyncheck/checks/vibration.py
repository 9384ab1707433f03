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

from dyncheck.checks.floquet import Floquet, floquet, floquet_settings, no_orbit
from dyncheck.checks.linear import (ENGINES, MUJOCO_TWIN, MUJOCO_TWIN_FACTOR, SAFETY, Equilibrium, NoEquilibrium,
                                    derivation_linear, dop853_exponent_error, engine_linear,
                                    equilibrium, first_order_change, full, linearised, match, modal, mode_run,
                                    rounding, settings, settled_amplitude, state_names, state_words, steady, step_cap,
                                    term_errors, unmeasured, verdict_row)
from dyncheck.common import ceilings
from dyncheck.common.derivatives import NEWTON_TOLERANCE
from dyncheck.results import store
from dyncheck.results.values import Status, no_number, row


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
