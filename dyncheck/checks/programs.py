"""The book's programs checked (a listing's formulas pointwise, its run, its printed output rows), and the
findings localised: the smallest edit of a printed expression that explains a finding, and the values the pages
show beside it (`findings_of`)."""

import re

import numpy as np

from dyncheck.checks.drawings import with_paths
from dyncheck.checks.localise import localise, values_at
from dyncheck.checks.pointwise import ENGINES, EPS, relative_error
from dyncheck.common import ceilings
from dyncheck.common.ceilings import ROUNDING_FLOOR
from dyncheck.common.expressions import evaluate as evaluate_expression
from dyncheck.common.expressions import namespace, of_parameters
from dyncheck.common.messages import suggest
from dyncheck.results.values import Finding, Pair, Status, no_number, row
from dyncheck.run import cache
from dyncheck.run.simulate import (Unstable, energy_residual, fastest_frequency, richardson_factor, simulate,
                                   state_columns)


# -- the book's programs ------------------------------------------------------------

def program_checks(case, sample):
    """The book's printed program against its derived equations, the engines and its own figures.

    (1) its formulas at the random states, against `reference`; (2) its run against the book's
    derived equations integrated by the same integrator and step (isolates formula errors from
    integrator errors); (3) its run against the tight reference solution (the integrator's own
    error, allowed up to `safety` times the Richardson estimate of that integrator at that step);
    (4) its run inside the ranges of the book's figures; (5) what it writes out against MuJoCo at its
    own states (program_output_checks).  Returns rows and the runs.
    """
    if not case.has_program:
        return [], {}
    program = case.model("program")
    rows = program_pointwise(case, sample)
    try:
        run_rows, runs = program_run_checks(case, program)
    except (Unstable, ArithmeticError) as failure:  # the listing's integrator, or its twins, blew up
        return rows + [no_number("program", column, ("program run",), failure) for column in state_columns(case)], {}
    return rows + run_rows, runs


def program_pointwise(case, sample):
    """The program's formulas at the pointwise check's random states (`sample`), against the reference."""
    program = case.model("program")
    states, right = sample["states"], sample["values"].get("reference")
    tolerance = case.tolerance["pointwise"]["value"]
    rows = []
    try:
        if "reference" in sample["failures"]:  # the reference's evaluation failed there (pointwise)
            raise ArithmeticError(sample["failures"]["reference"])
        with np.errstate(all="ignore"):
            acc = np.array([program.accelerations(t, q, v) for t, q, v in states])
            reactions = [program.reactions(t, q, v) for t, q, v in states]
        mine = {f"{coord}_acc": acc[:, i] for i, coord in enumerate(case.coords)}
        mine.update({name: np.array([r[name] for r in reactions]) for name in program.reaction_names})
        for quantity, values in mine.items():
            rows.append(row("program", quantity, ("program", "reference"), relative_error(values, right[quantity]),
                            tolerance, f"{len(states)} random states", ceiling=ceilings.POINTWISE))
    except ArithmeticError as failure:  # an overflow in the program's or the reference's float arithmetic
        rows = [no_number("program", "every quantity", ("program", "reference"), failure, Status.FAIL)]
    return rows


def program_run_checks(case, program):
    """The program's run against the book's equations run the same way, the tight reference solution,
    the book's figures and MuJoCo at its own states (see program_checks)."""
    rows = []
    q0, v0, _ = case.initial
    every = max(1, int(round(case.integration["output_step"] / program.dt)))
    listing = with_paths(case, program.run(q0, v0).iloc[::every])
    t_end = (len(listing) - 1) * every * program.dt
    book = case.model("book")
    same = lambda q, dt, work=False, **twin: simulate(book, (q, v0), t_end, program.integrator, dt=dt,
                                                      output_step=every * program.dt, work=work, **twin)
    # Richardson's twin at half the step: a listing's step may be far from the asymptotic range (the book's explicit
    # Euler amplifies a fast spring's free oscillation by exp(omega^2 dt T / 2), twofold over 1.8.3's run), and a
    # twin at twice it would stray further, or blow up where the listing does not.  The run at the listing's step
    # carries the work of the drives, so that the pages can say how much energy the listing's integrator makes.
    twin_runs = {"same": same(q0, program.dt, work=True), "half": same(q0, program.dt / 2, quantities=())}
    # Rounding: the same run from a start moved by a few ulps shows how the motion amplifies them.
    twin_runs["nudged"] = same(q0 + 4 * EPS * np.maximum(np.abs(q0), 1.0), program.dt, quantities=())
    tight = with_paths(case, cache.solution(case, "reference", (q0, v0), t_end, "DOP853",
                                            rtol=case.integration["tight_rtol"], output_step=every * program.dt,
                                            work=False, omega=fastest_frequency(case)))
    safety = case.tolerance["trajectory"]["safety"]
    label = f"{program.integrator}, dt = {program.dt:.4g} s, {t_end:.4g} s"
    for column in state_columns(case):
        x = listing[column].to_numpy()
        scale = np.max(np.abs(tight[column])) or 1.0  # a coordinate at rest: its error in SI units
        rounding = np.max(np.abs(twin_runs["same"][column] - twin_runs["nudged"][column])) / scale
        rows.append(row("program", column, ("program", "book equations, same integrator"),
                        np.max(np.abs(x - twin_runs["same"][column].to_numpy())) / scale,
                        safety * rounding + ROUNDING_FLOOR, label, ceiling=ceilings.RUN))
        # Does the listing draw the right curve?  Judged at a figure's resolution; whether its
        # integrator or its formulas stray shows beside it: the scheme's own error at its step, by
        # Richardson, while its steps are in the asymptotic range.
        integrator = richardson_factor(program.integrator, program.dt, program.dt / 2) * np.max(
            np.abs(twin_runs["same"][column] - twin_runs["half"][column])) / scale
        rows.append(row("program", column, ("program", "tight reference"),
                        np.max(np.abs(x - tight[column].to_numpy())) / scale, ceilings.LISTING,
                        f"{label}; its integrator's own error at this step, by Richardson: {integrator:.2g}",
                        ceiling=ceilings.LISTING))
    for name, figure in case.spec.get("program", {}).get("figures", {}).items():
        lo, hi = figure["range"]
        for source, run in (("program", listing), ("tight reference", tight)):
            values = evaluate_expression(figure["expression"], namespace(case, run))
            outside = max(lo - np.min(values), np.max(values) - hi, 0.0) / (hi - lo)
            rows.append(row("figure", name, (source, "book figure"), outside, ceilings.FIGURE,
                            f"{figure['where']}: range [{lo:g}, {hi:g}]; run [{np.min(values):.4g}, {np.max(values):.4g}]",
                            ceiling=ceilings.FIGURE))
    rows += program_output_checks(case, listing)
    return rows, {"listing": listing, "same integrator": twin_runs["same"], "tight": tight,
                  "integrator": program.integrator, "dt": program.dt}


OUTPUT_ROWS = 200  # the program's output rows compared with MuJoCo: evenly over its run, ends included


def program_output_checks(case, listing):
    """What the program writes out (its figures' positions, its reactions) against MuJoCo at the same
    states: each column of [program.outputs] against its expression of MuJoCo's values at that row's
    (t, q, v), at up to OUTPUT_ROWS of the program's own rows.  At the same state both evaluate closed
    forms (the listing's formula, MuJoCo's kinematics or dynamics) in doubles, so the pointwise
    tolerance, argued for the same kind of evaluation, applies; a wrong sign, axis or term is of the
    order of the value itself.  The difference is relative to the largest value of either side and at
    least a scale, as the pointwise check's: for a position the scene's size (the farthest body origin
    or traced centre of mass from the world origin over these rows), so that a coordinate that stays
    zero (the plane's normal) is not judged by rounding noise; for a reaction the case's force scale."""
    outputs = case.spec.get("program", {}).get("outputs", {})
    if not outputs:
        return []
    chosen = np.unique(np.linspace(0, len(listing) - 1, min(OUTPUT_ROWS, len(listing))).round().astype(int))
    rows_at = listing.iloc[chosen]
    model = case.model("mujoco")
    states = list(zip(rows_at.index, rows_at[list(case.coords)].to_numpy(),
                      rows_at[[f"{c}_rate" for c in case.coords]].to_numpy()))
    # The engine's values only: the program's own columns (R, x, ...) must not shadow them.
    names = of_parameters(case.params)
    points = [model.points(t, q) for t, q, _ in states]  # traced centres of mass, body origins
    paths = np.array([traced for traced, _, _ in points])  # (row, body, xyz)
    names.update({f"{body}_{axis}": paths[:, b, i]
                  for b, body in enumerate(case.scene.paths) for i, axis in enumerate("xyz")})
    size = max(np.max(np.linalg.norm(np.vstack([traced, origins]), axis=1)) for traced, origins, _ in points)
    reactions = [model.reactions(t, q, v) for t, q, v in states]
    names.update({name: np.array([r[name] for r in reactions]) for name in case.reaction_names})
    force_scale = case.value(case.tolerance["pointwise"]["force_scale"])
    rows = []
    for column, expression in outputs.items():
        if column not in listing:
            rows.append(no_number("program", column, ("program", "mujoco at the program's states"),
                                  f"{case.origin}: program.outputs.{column}: the program writes no column '{column}'"
                                  f"{suggest(column, listing.columns)}", Status.FAIL))
            continue
        engine = np.broadcast_to(evaluate_expression(expression, names), len(states))
        printed = rows_at[column].to_numpy()
        floor = force_scale if set(re.findall(r"[A-Za-z_]\w*", expression)) & set(case.reaction_names) else size
        scale = max(np.max(np.abs(printed)), np.max(np.abs(engine)), floor)
        at = int(np.argmax(np.abs(printed - engine)))
        rows.append(row("program", column, ("program", "mujoco at the program's states"),
                        relative_error(printed, engine, scale), case.tolerance["pointwise"]["value"],
                        f"{len(states)} of the program's rows; {column} = {expression}; largest difference at "
                        f"t = {rows_at.index[at]:.4g} s: program {printed[at]:.6g}, MuJoCo {engine[at]:.6g} "
                        f"(scale {scale:.3g})", ceiling=ceilings.POINTWISE))
    return rows


def finding_effect(case, finding, runs):
    """What a finding changes in the book's own results: for an error of its equations, its reactions
    in newtons and its energy balance in joules along its run; otherwise (or without that run: the quick tier)
    the case file's `effect`."""
    if "book" not in finding["sources"] or not all(s in runs and runs[s].ok for s in ("book", "reference")):
        return account(case, finding, "effect") if finding.get("effect") else ""
    book, tight = runs["book"].run, runs["reference"].twin
    parts = [f"the book's {q} is off by up to {(book[q] - tight[q]).abs().max():.3g} N"
             f" (|{q}| up to {tight[q].abs().max():.3g} N)"
             for q in finding["quantities"] if q in case.reaction_names]
    if "work-energy balance" in finding["quantities"]:
        parts.append(f"its work-energy balance misses by up to {energy_residual(book).abs().max():.3g} J")
    return (f"Over the book's run ({case.initial[2]:g} s from the book's initial conditions), "
            + "; ".join(parts) + ".") if parts else ""


# How a page under overrides marks a finding's explanation and effect: what the case file says of the book's numbers.
BOOK_ACCOUNT = "At the book's numbers (the case file's account; a number it computes from the parameters is this run's)"


def account(case, finding, field):
    """A finding's text from the case file, its `{= formulas}` at these parameters; under overrides
    marked as the case file's account of the book's numbers (the measured error is this run's, and so is what the
    finding's `measured` text says)."""
    where = f"findings[{case.findings.index(finding)}].{field}"
    text = " ".join(case.prose(finding[field], where).split())
    return f"*{BOOK_ACCOUNT}:* {text}" if case.overrides else text


def measured_account(case, finding):
    """A finding's `measured` text, its `{= formulas}` at these parameters and its `{~ measures}` left for the pages
    to write from the saved results (dyncheck.results.measured): never marked, every number in it this run's."""
    field = f"findings[{case.findings.index(finding)}].measured"
    return " ".join(case.prose(finding.get("measured", ""), field).split())


def finding_source(case, finding):
    """The model a finding's printed expressions belong to: the book's derived equations, or its program."""
    return case.model("program" if any("program" in s for s in finding["sources"]) else "book")


def components(key, values):
    """A printed vector's components as the checks name them in `values`: a_eq110_x, ... or Rx, ..."""
    for names in ([f"{key}_{axis}" for axis in "xyz"], [f"{key}{axis}" for axis in "xyz"]):
        if all(n in values for n in names):
            return names
    return [key]


def localise_finding(case, finding, sample):
    """The smallest edit of the book's printed expression that explains `finding` (dyncheck.checks.localise), in
    words, and the pairs (printed, edited expression) of the quantities it explains."""
    book = finding_source(case, finding)
    printed = getattr(book, "PRINTED", {})
    if "mujoco" in sample["failures"]:
        return f"not searched: MuJoCo's values at the random states failed ({sample['failures']['mujoco']})", ()
    engine = sample["values"]["mujoco"]
    quantities = [k for k in printed if set(components(k, engine)) & set(finding["quantities"])
                  and all(n in engine for n in components(k, engine))]
    if not quantities:
        return ("not searched: the book's module declares no printed expression of the engines' values for "
                + ", ".join(finding["quantities"])), ()
    parts, pairs = [], []
    for quantity in quantities:
        names = components(quantity, engine)
        target = engine[names[0]] if len(names) == 1 else np.column_stack([engine[n] for n in names])
        namespaces = [book.symbols(t, q, v) for t, q, v in sample["states"]]
        found, tried, printed_error = localise(printed[quantity], namespaces, target,
                                               case.tolerance["pointwise"]["value"])
        if found:
            parts.append(f"{quantity}: " + "; or ".join(f"{label} (then off by {err:.1e})" for label, err, _ in found)
                         + f" [{tried} edits tried; as printed off by {printed_error:.2g}]")
            label, err, edited = found[0]
            pairs.append(Pair(printed[quantity], edited, "the book's expression, the code that runs",
                              f"the localised edit: {label} (then off by {err:.1e} from MuJoCo at the random states)",
                              quantity, getattr(book, "LATEX", {})))
        else:
            parts.append(f"{quantity}: none of the {tried} searched edits (single and pairs) explains it"
                         f" (as printed off by {printed_error:.2g})")
    return "; ".join(parts), tuple(pairs)


def right_sides(case, sample):
    """Each finding's `right` expressions (case file) at the random states against the reference, a row
    each: the right side the errata typeset is proven, not retyped.  The target is the reference's value
    of the quantity, or 0 for a printed row (right side minus left side, which is 0 when the row holds)."""
    rows, pairs = [], {}
    for i, finding in enumerate(case.findings):
        if not finding.get("right"):
            continue
        model = finding_source(case, finding)
        printed = getattr(model, "PRINTED", {})
        for key, expression in finding["right"].items():
            if key not in printed:
                raise ValueError(f"{case.folder / 'case.toml'}: findings[{i}].right: '{key}' is not a printed "
                                 f"expression of the book's module{suggest(key, printed)}")
            sources = ("finding's right", "reference")
            if "reference" in sample["failures"]:
                rows.append(no_number("pointwise", key, sources, sample["failures"]["reference"], Status.FAIL))
                continue
            reference = sample["values"]["reference"]
            names = components(key, reference)
            namespaces = [model.symbols(t, q, v) for t, q, v in sample["states"]]
            right, book = values_at(expression, namespaces), values_at(printed[key], namespaces)
            of_reference = all(n in reference for n in names)
            target = (np.column_stack([reference[n] for n in names]).reshape(right.shape) if of_reference
                      else np.zeros_like(right))
            scale = max(np.max(np.abs(target)), np.max(np.abs(book))) or 1.0
            rows.append(row("pointwise", key, sources, relative_error(right, target, scale),
                            case.tolerance["pointwise"]["value"], f"finding {finding['id']}: {key} = {expression}, "
                            f"at {len(namespaces)} random states, relative to the larger of the printed and the "
                            f"reference's largest magnitude ({scale:.3g})", ceiling=ceilings.POINTWISE))
            pairs.setdefault(finding["id"], []).append(
                Pair(printed[key], expression, "the book's expression, the code that runs", "the case file's right "
                     "expression, checked against the reference at the random states", key if of_reference else "0",
                     getattr(model, "LATEX", {})))
    return rows, pairs


def value_pairs(case, finding, program):
    """The book's values against the right ones, for a finding of its data, its figures or its program's
    integrator: the printed datum against its formula, a figure's axis against the exact motion's range,
    the listing's run against the exact motion at the end of the run."""
    pairs = []
    for item in case.spec.get("data", []):
        if item["name"] in finding["quantities"] and "book data vs book formula" in finding["sources"]:
            valued = lambda expression: (expression if re.fullmatch(r"[\d.e+-]+", expression)
                                         else f"{expression} == {case.value(expression):.6g}")
            bound = "" if item.get("relation", "equal") == "equal" else ", the most the printed value may be"
            pairs.append(Pair(valued(item["printed"]), valued(item["formula"]), f"printed ({item['where']})",
                              f"the book's formula at the case's parameters{bound}"))
    if not program:
        return pairs
    figures = case.spec.get("program", {}).get("figures", {})
    for name, figure in figures.items():
        if name in finding["quantities"] and any("book figure" in s for s in finding["sources"]):
            lo, hi = figure["range"]
            values = evaluate_expression(figure["expression"], namespace(case, program["tight"]))
            pairs.append(Pair(f"{lo:g} <= {figure['expression']} <= {hi:g}",
                              f"{np.min(values):.4g} <= {figure['expression']} <= {np.max(values):.4g}",
                              f"the figure's axis ({figure['where']})",
                              "the exact motion (the reference integrated tightly) over the book's run"))
    columns = [q for q in finding["quantities"] if q in program["listing"].columns]
    if columns and "program vs tight reference" in finding["sources"]:
        end = program["listing"].index[-1]
        at = lambda run: ", ".join(f"{run[c].iloc[-1]:.4g}" for c in columns)
        pairs.append(Pair(f"array([{at(program['listing'])}])", f"array([{at(program['tight'])}])",
                          f"the listing's run ({program['integrator']} at dt = {program['dt']:.4g} s) at "
                          f"t = {end:.4g} s", f"the exact motion at t = {end:.4g} s",
                          f"array([{', '.join(columns)}])", getattr(case.model("book"), "LATEX", {})))
    return pairs


def findings_of(case, rows, sample, runs, localise=True, right=None, program=None):
    """The case's registered findings with their measured size, where and how established, and effect;
    with their book-vs-right pairs: the localised edits, the case file's checked `right` ({id: pairs},
    right_sides), or the values `program` (program_checks' runs) and the case's data give."""
    engines = [r.error for r in rows if r.check == "pointwise" and set(r.sources) <= set(ENGINES)]
    out = []
    for finding in case.findings:
        errors = [r.error for r in rows if r.finding == finding["id"] and r.error is not None]
        localised, pairs = localise_finding(case, finding, sample) if localise else (
            "not searched in this run (`dyncheck run` searches with --json or --results)", ())
        pairs += tuple((right or {}).get(finding["id"], ())) + tuple(value_pairs(case, finding, program))
        out.append(Finding(
            id=finding["id"], title=finding["title"], where=finding["where"],
            quantities=tuple(finding["quantities"]), sources=tuple(finding["sources"]),
            error=max(errors, default=None), explanation=account(case, finding, "explanation"),
            established=f"reference, MuJoCo and Pinocchio agree with each other to {max(engines, default=0):.1e} "
                        f"at {len(sample['states'])} random states",
            effect=finding_effect(case, finding, runs), localised=localised, pairs=pairs,
            measured=measured_account(case, finding)))
    return out
