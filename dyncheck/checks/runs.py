"""Checks: each yields rows (dyncheck.results.values.Row); `run_case` runs them all into a CaseResult."""

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from dyncheck.checks import residuals, vibration
from dyncheck.checks.convergence import NoFrequency, convergence
from dyncheck.checks.drawings import drawings, frames, with_paths
from dyncheck.checks.horizon import agreement_horizon
from dyncheck.checks.pointwise import INTEGRATED, along_run, not_defined, parameter_sets, pointwise, random_parameters
from dyncheck.checks.programs import findings_of, program_checks, right_sides
from dyncheck.common import ceilings
from dyncheck.common.ceilings import ROUNDING_FLOOR
from dyncheck.results.values import OWN_WORDS, CaseResult, Outcome, Status, no_number, row
from dyncheck.run import cache
from dyncheck.run.simulate import (ERROR_EXPONENT, Escape, Unstable, energy_residual, fastest_frequency,
                                   richardson_factor, run_wall, simulate, state_columns)


# -- trajectories -----------------------------------------------------------------

def run_sources(case, bound=None):
    """The book's initial conditions integrated by every source, each with a tighter twin.

    Returns {source: Outcome}; the tight reference solution is the reference's twin, its outputs step ends or
    its steps capped (tight_steps).  DOP853 twins run at tight_rtol; MuJoCo's RK4 twin at dt/2, and MuJoCo's run once more with its
    scene's approximations doubled (Outcome.approximations).  A run that blew up is an
    Outcome with its failure; with `bound` (a Runaway's), a run that left it an Outcome with its Escape.
    """
    q0, v0, t_end = case.initial
    setting = case.integration
    out_step = setting["output_step"]
    runs = {}
    for source in INTEGRATED:
        options = dict(output_step=out_step, work=case.driven, omega=fastest_frequency(case), bound=bound,
                       wall=run_wall(case))
        try:
            runs[source] = Outcome(simulate(case.model(source), (q0, v0), t_end, "DOP853", rtol=setting["rtol"],
                                            **options),
                                   cache.solution(case, source, (q0, v0), t_end, "DOP853", rtol=setting["tight_rtol"],
                                                  **(tight_steps(case) if source == "reference" else TWIN), **options))
        except Unstable as failure:
            runs[source] = Outcome(failure=failure.failure)
    dt = setting["mujoco_step"]
    mujoco_run = lambda model, h, **twin: simulate(model, (q0, v0), t_end, "mujoco:RK4", dt=h, output_step=out_step,
                                                   work=case.driven, bound=bound, **twin)
    model, doubled = case.model("mujoco"), case.approximations_doubled()
    try:
        run = mujoco_run(model, dt)
        # a scene without approximations is its own doubled scene, whose run would repeat this one bit for bit
        runs["mujoco"] = Outcome(run, mujoco_run(model, dt / 2, **TWIN),
                                 approximations=run if doubled is model else mujoco_run(doubled, dt, **TWIN))
    except Unstable as failure:
        runs["mujoco"] = Outcome(failure=failure.failure)
    return runs


# A twin of a source's run, and MuJoCo's run with its approximations doubled, give an error estimate of the run's
# states and energy (trajectory, energy): nothing reads their reactions.
TWIN = {"quantities": ("energy",)}


def tight_steps(case):
    """How the tight reference solution steps, so that its outputs are as good as its step ends.  DOP853 controls
    its error at the ends of its steps; an output between them comes from its dense output, a 7th-order
    interpolant outside that control, whose error grows as its step^8.  Where the motion is slower than the case's
    fastest frequency omega the controller takes longer steps, and the interpolant strays far beyond the step
    ends: two pendulums under g = 1 m/s^2 (steps up to omega h = 0.3) are off by 4.7e-11 of their largest rate at
    rtol 1e-12 (3e-12 at the step ends), 17 times the estimate trajectory() makes of it.  So either every output
    is a step's end (simulate's land_on_outputs), or the steps are capped at tight_rtol^(1/8) / omega, the step
    the controller takes at omega (simulate.ERROR_EXPONENT), where the interpolant is as good as the ends.
    Landing costs a step per output at least, the cap one per capped step: the cheaper is taken, landing where
    the outputs are no closer than the cap.  Against DOP853 at rtol 2.2e-14 with steps a quarter of the cap, the
    book's four integrated cases at rtol 1e-12 are off by 6.5e-12 to 1.1e-9 of their largest values with neither,
    and by 6e-15 to 1.6e-10 as chosen (three landed, in 2,500 to 4,900 steps where the cap takes 4,000 to 9,900;
    one capped, in 2,500 where landing takes 8,000): each at least 1,000 times below its case's runs at rtol
    1e-10 (5e-10 to 1.6e-7).  Where the cap is the shorter step it is better still (50 times, on two pendulums),
    which no check needs.
    No cap without omega."""
    omega = fastest_frequency(case)
    cap = case.integration["tight_rtol"] ** (1 / ERROR_EXPONENT["DOP853"]) / omega if omega else np.inf
    return {"land_on_outputs": True} if case.integration["output_step"] >= cap else {"max_step": cap}


def error_estimate(outcome):
    """Estimated error of `run`, per column, from its tighter twin (Richardson for RK4)."""
    return twin_factor(outcome) * (outcome.run - outcome.twin).abs()


def twin_factor(outcome):
    """What a run's difference from its twin is multiplied by to estimate the run's error: 1 for an adaptive
    twin (its error is far below the run's), Richardson's for a fixed step (simulate.richardson_factor)."""
    run, twin = outcome.run.attrs, outcome.twin.attrs
    return richardson_factor(run["method"], run["dt"], twin["dt"]) if run["dt"] else 1.0


def approximations_effect(outcome):
    """What a scene's approximations of the case's physics (MuJoCo's placeholders, the drift of its
    prescribed motions) change in its run, per column: the run with them doubled minus the run, both
    linear in them; zero for a source without them.  It is allowed as it is, not times a safety factor:
    the two runs' common integration error cancels in it, and their rounding is the floor's."""
    if outcome.approximations is None:
        return 0 * outcome.run
    return (outcome.approximations - outcome.run).abs()


def trajectory(case, runs):
    """Each source's trajectory against the tight reference solution, up to the agreement horizon
    (where the motion's sensitivity would make a comparison test chaos rather than the equations)."""
    def every_comparison(failure, status=None):  # None: the failure's (unstable, or budget spent)
        return [no_number("trajectory", c, (source, "tight reference"), failure, status)
                for source in ("book", "pinocchio", "mujoco") for c in state_columns(case)]

    if not runs["reference"].ok:  # nothing to compare with
        return every_comparison(runs["reference"].failure)
    horizon, why = agreement_horizon(case)
    within = slice(None, horizon)
    tight = runs["reference"].twin.loc[within]
    # Errors need time to build: a span shorter than a radian of the fastest motion (or than ten
    # output steps, where the case names no frequency) compares starts, which agree by construction.
    omega = fastest_frequency(case)
    least = 1 / omega if omega else 10 * case.integration["output_step"]
    if tight.index[-1] < least:
        return every_comparison(f"the agreement horizon {horizon:.3g} s is shorter than {least:.3g} s "
                                f"({'1/omega' if omega else 'ten output steps'}): nothing to compare; "
                                f"{why['sentence']}", Status.INCONCLUSIVE)
    # 100x tighter rtol, order 8, and its outputs as good as its step ends (tight_steps): >= 100x better
    tight_error = error_estimate(runs["reference"]).loc[within] / 100
    safety = case.tolerance["trajectory"]["safety"]
    rows = []
    for source in ("book", "pinocchio", "mujoco"):
        label = (source, "tight reference")
        outcome = runs[source]
        if not outcome.ok:
            rows += [no_number("trajectory", c, label, outcome.failure) for c in state_columns(case)]
            continue
        attrs = outcome.run.attrs
        run = outcome.run.loc[within]
        estimate = error_estimate(outcome).loc[within]
        approximations = approximations_effect(outcome).loc[within]
        method = attrs["method"] + (f" dt={attrs['dt']:g}" if attrs["dt"] else f" rtol={attrs['rtol']:g}")
        for column in state_columns(case):
            scale = tight[column].abs().max() or 1.0  # a coordinate at rest: its error in SI units
            error = (run[column] - tight[column]).abs().max() / scale
            effect = approximations[column].max() / scale
            allowed = safety * (estimate[column].max() + tight_error[column].max()) / scale + effect + ROUNDING_FLOOR
            rows.append(row("trajectory", column, label, error, allowed,
                            f"{method}, max over {min(horizon, case.initial[2]):g} s"
                            + (f", the scene's approximations' effect {effect:.2g} allowed{soft_loops(case)}"
                               if outcome.approximations is not None else "")
                            + (f"; {why['sentence']}" if math.isfinite(horizon) else ""), ceiling=ceilings.RUN))
    if runs["mujoco"].ok and case.scene.driven:
        # The armature holds the driven rates while MuJoCo steps: small enough a drift that its effect on the
        # motion, allowed in the rows above, is measured to first order (ceilings.DRIVEN_RATE).
        rows.append(row("trajectory", "driven rate", ("mujoco", "prescribed"),
                        runs["mujoco"].run.attrs["driven_rate_error"], ceilings.DRIVEN_RATE,
                        "max |rate - prescribed| over the run and the driven joints / largest rate of the run (at least 1)",
                        ceiling=ceilings.DRIVEN_RATE))
    return rows


def soft_loops(case):
    """What a row's "the scene's approximations' effect" holds beyond placeholders and prescribed motions."""
    return " (MuJoCo's soft loops among them: its run with their softness doubled)" if case.scene.dependent else ""


def energy(case, runs):
    safety = case.tolerance["energy"]["safety"]
    quantity = "work-energy balance" if case.driven else "energy drift"
    rows = []
    for source in INTEGRATED + ("mujoco",):
        label = (source,)
        if not runs[source].ok:
            rows.append(no_number("energy", quantity, label, runs[source].failure))
            continue
        run, twin = runs[source].run, runs[source].twin
        lacking = [method for method, column in (("energy", "energy"), ("drive_power", "work")) if column not in run]
        if lacking:
            rows.append(not_defined(case, ("energy", quantity), label, source, lacking[0]))
            continue
        scale = max(run["energy"].abs().max(), run["work"].abs().max()) or 1.0  # at rest: in joules
        residual = energy_residual(run)
        estimate = (residual - energy_residual(twin)).abs().max() * twin_factor(runs[source])
        approximated = runs[source].approximations  # the scene's approximations' effect, as in `trajectory`
        effect = 0.0 if approximated is None else (energy_residual(approximated) - residual).abs().max()
        rows.append(row("energy", quantity, label, residual.abs().max() / scale,
                        safety * estimate / scale + effect / scale + ROUNDING_FLOOR,
                        f"max |E(t) - E(0) - W(t)| / max(|E|, |W|), {run.attrs['method']}"
                        + (f", the scene's approximations' effect {effect / scale:.2g} allowed{soft_loops(case)}"
                           if approximated is not None and case.scene.dependent else ""), ceiling=ceilings.RUN))
    return rows


# -- physical runaway -------------------------------------------------------------

RUN_CHECKS = ("trajectory", "energy")  # the checks of run_sources' runs: a row's first source is its run's


def runaway_rows(limit, runs, rows):
    """The rows of the runs where the case's physics runs away (`limit`, a Runaway; None: `rows` as they
    are).  Every source escaped: the physics, confirmed by each independent model; their rows are runaway,
    saying why and when each escaped.  Some escaped and others not: not that physics, whichever is
    wrong; a run that stayed within the bound to its end fails, the others are unstable.  None escaped
    (a growth too slow to reach the bound within the run): the rows as they are."""
    escapes = {source: outcome.failure for source, outcome in runs.items() if isinstance(outcome.failure, Escape)}
    if limit is None or not escapes:
        return rows
    name, _, escape = limit.bound
    escaped = ", ".join(f"{source} at {failure.t:.4g} s" for source, failure in escapes.items())
    bounded = [source for source, outcome in runs.items() if outcome.ok]
    blown = [source for source, outcome in runs.items() if not outcome.ok and source not in escapes]
    summary = "; ".join([f"escaped: {escaped}"]
                        + ([f"within |{name}| <= {escape:g} to the end: {', '.join(bounded)}"] if bounded else [])
                        + ([f"blew up before escaping: {', '.join(blown)}"] if blown else []))
    out = []
    for r in rows:
        source = r.sources[0]
        if r.check not in RUN_CHECKS or source not in runs:
            out.append(r)
        elif len(escapes) == len(runs):
            out.append(replace(r, status=Status.RUNAWAY, finding=None,
                               detail=f"{limit.why}: {escapes[source]}; every source escaped ({escaped})"))
        elif not runs[source].ok:
            out.append(replace(r, status=Status.UNSTABLE, finding=None, detail=f"{runs[source].failure}; not the "
                               f"runaway the case states ({limit.why}): {summary}"))
        else:
            out.append(no_number(r.check, r.quantity, r.sources, f"{source} did not run away where the case says "
                                 f"it must ({limit.why}): {summary}", Status.FAIL))
    return out


# -- findings ---------------------------------------------------------------------

def apply_findings(case, rows):
    """A failing row that a registered finding explains is a finding; a finding that no longer fails
    fails (at the book's own parameters: overridden ones may legitimately hide an error, e.g. a
    Coriolis term at zero spin, which is then said in the row)."""
    out = []
    for r in rows:
        for finding in case.findings:
            # A finding names whole sources ("book": every comparison with it) or one comparison.
            involved = (set(r.sources) | {r.comparison}) & set(finding["sources"])
            if involved and r.quantity in finding["quantities"] and r.status in (Status.PASS, Status.FAIL):
                if r.status == Status.FAIL:
                    r = replace(r, finding=finding["id"], status=Status.FINDING)
                elif case.overrides:
                    r = replace(r, finding=finding["id"],
                                detail=f"finding {finding['id']} does not show with these parameters; " + r.detail)
                else:
                    r = replace(r, finding=finding["id"], status=Status.FAIL,
                                detail=f"registered finding {finding['id']} no longer reproduces; " + r.detail)
        out.append(r)
    return out


BOOK_ONLY = ("figure", "data")  # compared with what the book printed, for its own parameters


def book_numbers_only(case, rows):
    """Under overrides, the rows that compare with the book's printed figures and data are not applicable (the
    book printed them for its own numbers): shown, counted apart, never a failure.  Whatever the run measures
    at the overrides (the book's program run at them against the exact motion, say) stays a measured row."""
    if not case.overrides:
        return rows
    return [replace(r, status=Status.NOT_APPLICABLE, finding=None,
                    detail=f"the book printed this for its own parameters, not for {case.overrides_text()}; "
                           + r.detail)
            if r.check in BOOK_ONLY and r.status in (Status.PASS, Status.FAIL, Status.FINDING) else r for r in rows]


def data_checks(case):
    """The book's printed data against its own formulas and geometry ([[data]] in the case file):
    `printed` must equal `formula` to the printed digits, or be at most it (`relation`)."""
    rows = []
    for item in case.spec.get("data", []):
        printed, formula = case.value(item["printed"]), case.value(item["formula"])
        if item.get("relation", "equal") == "equal":
            error = abs(printed - formula) / abs(formula)
        else:  # "at most"
            error = max(printed - formula, 0.0) / abs(formula)
        rows.append(row("data", item["name"], ("book data", "book formula"), error, item["tolerance"],
                        f"{item['where']}: printed {printed:.6g}, formula {item['formula']} = {formula:.6g}",
                        ceiling=ceilings.DATA))
    return rows


QUICK_LEAVES_OUT = ("trajectory", "energy", "along the run", "convergence", "vibration", "program", "figure")
"""The checks whose rows `run_case(quick=True)` leaves out: those of the runs along time (the book's initial conditions
integrated by every source, the convergence orders, the vibration analysis's runs, the book's programs)."""


@dataclass(frozen=True)
class InTime:
    """What the runs along time add to a case's result (`in_time`); nothing in the quick tier."""
    rows: list = field(default_factory=list)
    runs: dict = field(default_factory=dict)  # {source: Outcome} of the book's initial conditions
    program: dict = field(default_factory=dict)  # the book's program run (program_checks)
    vibration: object = None  # the vibration analysis, for a case with [vibration]
    limit: object = None  # the case's Runaway, which the runs' rows are judged by (runaway_rows)


def in_time(case, sample):
    """The checks along time: the book's initial conditions integrated by every source (trajectory, energy, the
    engines along the run), the convergence orders, the vibration analysis and the book's programs."""
    limit = case.runaway()
    runs = run_sources(case, None if limit is None else limit.bound)
    rows = trajectory(case, runs) + energy(case, runs) + along_run(case, runs)
    try:
        rows += convergence(case)
    except NoFrequency as error:  # nothing to converge on where nothing moves; a motion without omega is the case's fault
        reference = runs["reference"]
        at_rest = reference.ok and bool((reference.twin[state_columns(case)].nunique() == 1).all())
        rows.append(no_number("convergence", "every method", ("reference",),
                              f"not measured: {error}" + ("; nothing moves" if at_rest else ", yet the scene moves"),
                              Status.NOT_APPLICABLE if at_rest else Status.FAIL))
    except ValueError as error:  # a step within rounding
        rows.append(no_number("convergence", "every method", ("reference",), f"not measured: {error}", Status.FAIL))
    program_rows, program = program_checks(case, sample)
    vibrations = vibration.analyse(case)
    rows += [*(vibrations.rows if vibrations else []), *program_rows]
    return InTime(rows, runs, program, vibrations, limit)


def run_case(case, localise=True, quick=False):
    """All checks of a case, the findings they establish and what the figures draw: a CaseResult.
    `localise`: search each finding's smallest edit of the printed expression (seconds per finding;
    what is written or saved shows it, a table of rows does not need it).  `quick`: the checks at states alone,
    for the edit-run loop (a second where the runs along time take tens: QUICK_LEAVES_OUT), with no runs to draw."""
    start = time.perf_counter()
    rows, sample = pointwise(case)
    equations, residuals_found = residuals.equation_rows(case, sample)
    rows += equations + residuals.printed_rows(case, sample) + random_parameters(case)
    timed = InTime() if quick else in_time(case, sample)
    rows = book_numbers_only(case, apply_findings(case, rows + timed.rows + data_checks(case)))
    right_rows, right = right_sides(case, sample)
    rows += right_rows
    rows = runaway_rows(timed.limit, timed.runs, rows)  # a bounded run's failure is no finding of the book
    parameter_draws = parameter_sets(case)[0]
    localisations = residuals.localise(case, rows, residuals_found, parameter_draws)
    localisations += residuals.localise_values(case, rows, sample, parameter_draws,
                                               {loc.source for loc in localisations})
    # What the pages draw along runs: each source's run, and the reference's tight twin (report.trajectories).
    drawn = lambda source, outcome: replace(outcome, **({"twin": with_paths(case, outcome.twin)} if source == "reference"
                                                        else {"run": with_paths(case, outcome.run)}))
    runs = {source: drawn(source, outcome) if outcome.ok else outcome for source, outcome in timed.runs.items()}
    findings = tuple(findings_of(case, rows, sample, runs, localise, right, timed.program))
    if case.one_derivation:
        rows, localisations = in_own_words(rows), tuple(replace(loc, source=OWN_WORDS[loc.source])
                                                       for loc in localisations)
    return CaseResult(folder=str(case.folder), spec=case.spec, overrides=dict(case.overrides), rows=tuple(rows),
                      findings=findings, sample=sample, runs=runs, program=timed.program,
                      drawings={**drawings(case, runs), "animation": frames(case, runs, timed.program)} if runs else {},
                      wall=time.perf_counter() - start, localisations=localisations, vibration=timed.vibration)


def unfinished(case, why):
    """The result of a case whose checks could not finish (its process died or overran its budget, or its checks
    stopped on an error: dyncheck.case.isolation): one failing row that says why, and nothing else to show."""
    source = "derivation" if case.one_derivation else "reference"
    return CaseResult(folder=str(case.folder), spec=case.spec, overrides=dict(case.overrides),
                      rows=(no_number("checks", "every check", (source,), f"the checks did not finish: {why}",
                                      Status.FAIL),),
                      findings=(), sample={}, runs={}, program={}, drawings={}, wall=0.0)


def in_own_words(rows):
    """The rows of a case with one derivation (Case.one_derivation) in its own words: its Book is its
    Reference, so the rows that compare the two, or repeat a reference's row for the book, go; the book's
    run at the case's tolerance against the tight one stays, as the derivation's."""
    kept = [r for r in rows if "book" not in r.sources or r.check == "trajectory"]
    return [replace(r, sources=tuple(OWN_WORDS.get(s, s) for s in r.sources)) for r in kept]


# -- what the figures draw ------------------------------------------------------------
