"""A case's page (`write_case_page`): its summary, tables, figures, sections of the studies and the vibration
analysis, and its timing page; the page of a case whose run did not finish (`write_unfinished_page`)."""

import math
import os
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd

from dyncheck.case.folder import CASES_DIR
from dyncheck.checks.pointwise import ENGINES
from dyncheck.common import expressions
from dyncheck.common.expressions import evaluate
from dyncheck.common.messages import plural, statuses_in_words
from dyncheck.common.style import embed
from dyncheck.pages import animation, student_page, vibration_page
from dyncheck.pages.figures import (departures, figure_energy, figure_extra, figure_pointwise, figure_program,
                                    figure_scene, figure_series, named, quantity_label, reaction_unit,
                                    report_namespaces, state_unit)
from dyncheck.results import measured
from dyncheck.results.values import OWN_WORDS, Status, consequences, format_rows, heading, inside_or_outside, reason
from dyncheck.run.simulate import state_columns
from dyncheck.studies import stability, work_precision

# The sources that must agree everywhere, the reference named in a researcher's words too (a case of one
# derivation calls it "derivation": dyncheck.checks.runs.in_own_words)
AGREEING = {*ENGINES, OWN_WORDS["reference"]}
CPU_TIME = ("A run's CPU time is the wall time it takes on an idle core: other processes' load on the machine,"
            " which stretches wall times by factors, leaves it out.")
CPU_TIES = ("Each point ranks by its fastest run: what slows a run only adds time, and on a shared machine it adds it"
            " to most runs now and then, while the fastest run of a point moves by about 10% between regenerations."
            f"  A method is the cheapest only when its fastest run is faster than every other method's by more than"
            f" {work_precision.REPRODUCIBILITY:.0%}; else the methods that cannot be told apart are named together.  The"
            f" runs that decide it are {work_precision.DECIDING_REPEATS} of each point, taken in turns with the other"
            " points' runs.")


def values_table(case, spaces):
    """A case's named results (e.g. the least friction coefficient), computed for every source."""
    rows = []
    for key, item in case.spec["report"].get("values", {}).items():
        row = {"result": item["about"], "unit": item["unit"]}
        for label, names in spaces.items():
            value = float(evaluate(item["expression"], names))
            row[label] = "not reached" if np.isnan(value) else f"{value:.4g}"
        rows.append(row)
    return markdown_table(pd.DataFrame(rows))


# -- pages --------------------------------------------------------------------------

def size(error, spec=".3g"):
    """A finding's largest error, or why there is none (its rows compare with what the book printed, not applicable
    under overrides)."""
    return "none: not applicable with these parameters" if error is None else format(error, spec)


def worst_engine_error(rows):
    """Largest pointwise error among the reference (or derivation), MuJoCo and Pinocchio."""
    errors = [r.error for r in rows if r.check == "pointwise" and set(r.sources) <= AGREEING and r.error is not None]
    return max(errors, default=float("nan"))


def random_tried(result, case):
    """What the random pointwise checks tried: states at the case's parameters, parameter sets and
    states at each, their seeds, and whether reference and both engines agreed at all of them (None where they
    were not compared: the case's checks did not finish)."""
    sample, params = case.spec["sample"], case.spec["sample"].get("params", {})
    engine_rows = [r for r in result.rows if r.check in ("pointwise", "random parameters")
                   and set(r.sources) <= AGREEING]
    return {"states": sample["count"], "seed": sample["seed"], "parameter_sets": params.get("sets", 0),
            "states_per_set": params.get("states", 0), "parameter_seed": params.get("seed"),
            "agreed": all(r.status == Status.PASS for r in engine_rows) if engine_rows else None}


def random_sentence(tried):
    text = f"{plural(tried['states'], 'random state')} at these parameters (seed {tried['seed']})"
    if tried["parameter_sets"]:
        text += (f" and {plural(tried['parameter_sets'], 'random parameter set')} (seed {tried['parameter_seed']})"
                 f" over the ranges of the case file, {plural(tried['states_per_set'], 'state')} each")
    return text


def as_written(text):
    """A docstring or a case file's text as Markdown, its paragraphs kept: a paragraph with an indented line (a
    matrix set out over lines, an aligned formula) as a block of its lines as written, a list as its items, any
    other paragraph's lines joined (Markdown would join them, and flatten an indented formula, too)."""
    blocks = []
    for paragraph in textwrap.dedent(text).strip().split("\n\n"):
        lines = paragraph.strip("\n").splitlines()
        if any(line[:1].isspace() for line in lines):
            blocks.append("\n".join(["```text", *textwrap.dedent("\n".join(lines)).splitlines(), "```"]))
        elif all(line.lstrip().startswith(("- ", "* ")) for line in lines):
            blocks.append("\n".join(lines))
        else:
            blocks.append(" ".join(paragraph.split()))
    return "\n\n".join(blocks)


def markdown_table(frame):
    """The frame as a Markdown table: text as written ("0.0200" stays, tabulate would print 0.02), numbers
    as tabulate writes them (6 significant digits), nothing (an empty text, None, NaN) as "-", a | in a
    cell escaped (it would end the cell), and the columns of numbers aligned right."""
    cells = frame.map(lambda x: "-" if x is None or x == "" or (isinstance(x, float) and math.isnan(x)) else
                      format(x, "g") if isinstance(x, float) else str(x).replace("|", "\\|"))
    numeric = [any(map(is_number, cells[column])) and all(is_number(x) or x == "-" for x in cells[column])
               for column in cells]
    cells.columns = [str(column).replace("|", "\\|") for column in cells.columns]
    return cells.to_markdown(index=False, disable_numparse=True,
                             colalign=["right" if n else "left" for n in numeric] or None)


def is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def summary_table(rows):
    """One line per (check, comparison): how many quantities, their statuses, the worst error/tolerance."""
    frame = pd.DataFrame([{"check": r.check, "sources": r.comparison, "quantity": r.quantity, "status": str(r.status),
                           "error": np.nan if r.error is None else r.error,
                           "tolerance": np.nan if r.tolerance is None else r.tolerance, "row": r} for r in rows])
    out = []
    for (check, sources), group in frame.groupby(["check", "sources"], sort=False):
        judged = group.dropna(subset=["error", "tolerance"])
        with np.errstate(divide="ignore", invalid="ignore"):  # a zero tolerance: any error is infinitely over
            ratios = np.where(judged["error"] > 0, judged["error"] / judged["tolerance"], 0.0)
        worst = judged.iloc[int(np.argmax(ratios))] if len(judged) else None
        out.append({"check": check, "comparison": sources, "quantities": len(group),
                    "status": statuses_in_words(group["status"].value_counts()),
                    "worst": "-" if worst is None else f"{worst['quantity']}: " + (
                        inside_or_outside(worst["row"]) if worst["row"].yes_or_no
                        else f"{worst['error']:.2e} / {worst['tolerance']:.2e}")})
    return pd.DataFrame(out)


def not_passed(rows):
    """Page lines naming every row that neither passed nor is a finding or not applicable, and why: a
    failure's error against its tolerance, an integration's blow-up or a physical runaway (when, which
    method, which step)."""
    shown = [r for r in rows if r.status not in (Status.PASS, Status.FINDING, Status.NOT_APPLICABLE)]
    if not shown:
        return []
    why = {}  # one line per status and reason: a runaway or a blow-up stops every row of a run alike
    for r in shown:
        why.setdefault((r.status, reason(r) or r.detail), []).append(f"{r.check} {r.quantity} ({r.comparison})")
    return ["Rows that did not pass, and why:", "",
            *[f"- {'; '.join(names)}: **{status}**: {text}" for (status, text), names in why.items()], ""]


def not_checked(rows):
    """Page lines naming the `not applicable` rows that have nothing to compare (a derivation without
    energy), and why; those under overrides show their comparison in the table."""
    why = {}
    for r in rows:
        if r.status == Status.NOT_APPLICABLE and r.error is None:
            why.setdefault(r.detail, []).append(f"{r.check} {r.quantity} ({r.comparison})")
    return [line for text, names in why.items() for line in (f"Not applicable: {'; '.join(names)}: {text}.", "")]


def scene_table(case):
    """The joints of the engine models: what is free, what is prescribed, what is applied."""
    scene = case.scene
    rows = [{"joint": joint, "role": f"prescribed: {law_of_time(law)}"} for joint, law in scene.driven.items()]
    whose = "the coordinate " if case.one_derivation else "the book's "
    mapped = case.spec["scene"].get("joints", {})  # the joints as functions of the coordinates
    rows += [{"joint": joint, "role": f"free: at {mapped[joint]} (the map of the coordinates)" if mapped else
              "free: " + whose + ", ".join(case.coords[i] for i in idx)
              + (" (ball joint, in Euler angles)" if kind == "euler" else "")}
             for kind, joint, idx in ((c.kind, c.joint, c.indices) for c in scene.layout)]
    rows += [{"joint": joint, "role": "dependent: each engine solves it from the coordinates, closing the loop"}
             for joint in scene.dependent]
    written = lambda x: f"{case.value(x):g}" if not isinstance(x, str) or not {"t", *case.coords} & \
        {n.removesuffix("_rate") for n in expressions.names(x)} else x  # a number, or the law of t and the state
    rows += [{"joint": joint, "role": "applied generalized force (" + ", ".join(map(written, force.components))
              + ") (joint frame)"} for joint, force in scene.applied.items()]
    return markdown_table(pd.DataFrame(rows))


def write_case_page(result, case, tmp, animations=True):
    rows = result.rows
    name = case.name
    words = OWN_WORDS if case.one_derivation else {}
    unit = lambda column: state_unit(case, column)
    force = lambda column: reaction_unit(case, column)
    tight = named(words, "tight reference")
    run_of = initial_words(case)

    def coordinates(path):
        worst = figure_series(result, case, case.coords, lambda c: f"{quantity_label(c)} [{unit(c)}]", "coordinates over time",
                              path, words=words)
        return (f"Each coordinate along the run of {run_of}, every source overlaid (line style, marker and"
                f" colour per source). Largest departure from the {tight}: {departures(worst, unit, words)}.")

    def errors(path):
        worst = figure_series(result, case, state_columns(case), lambda c: f"|{quantity_label(c)} error| [{unit(c)}]",
                              f"error against the {tight}", path, words=words, log_error=True)
        return (f"How far each source's run of {run_of} is from the {tight} ({result.runs['reference'].twin.attrs['method']},"
                " a tighter tolerance), each coordinate and rate on a log scale that follows the data; exact"
                f" agreement lies on the bottom edge. Largest: {departures(worst, unit, words)}.")

    def reactions(path):
        worst = figure_series(result, case, list(case.reaction_names), lambda c: f"{quantity_label(c)} [{force(c)}]",
                              "reactions over time", path, words=words)
        return (f"Each reaction along the run of {run_of}, every source overlaid. Largest departure from the"
                f" {tight}: {departures(worst, force, words)}.")

    plots = {  # figure -> how to draw it, returning its caption; the coordinate plots only where there are coordinates
        "scene": lambda path: figure_scene(result, case, path, words=words),
        "coordinates": coordinates,
        "errors": errors,
        "energy": lambda path: figure_energy(result, case, path, words=words),
        "reactions": reactions,
        "pointwise": lambda path: figure_pointwise(result, case, path, words=words),
    }
    if "reference" not in result.sample["values"]:  # nothing to measure the deviations from
        del plots["pointwise"]
    if not case.coords:
        del plots["coordinates"], plots["errors"]
    if not case.reaction_names:
        del plots["reactions"]
    if result.program.get("listing") is not None and case.spec.get("program", {}).get("plots"):
        plots["program"] = lambda path: figure_program(result, case, path)
    along_runs = result.runs["reference"].ok
    if not along_runs:  # the reference run blew up or ran away (rows say when): nothing to draw along it
        plots = {kind: draw for kind, draw in plots.items() if kind in ("pointwise", "program")}
    extras = case.spec["report"].get("figures", {}) if along_runs else {}
    values = case.spec["report"].get("values") if along_runs else None
    spaces = report_namespaces(result, case) if extras or values else {}
    for key, item in extras.items():
        plots[key] = lambda path, item=item: figure_extra(spaces, case, item, path, words=words)
    figures, captions = {}, {}
    for kind, draw in plots.items():
        figures[kind] = f"figures/{name}_{kind}.png"
        captions[kind] = draw(tmp / figures[kind])

    counts = pd.Series([str(r.status) for r in rows]).value_counts()
    table = format_rows(rows)
    table["finding"] = [r.finding or "" for r in rows]
    findings = result.findings
    runs = result.runs
    cost = cost_table(runs, case.one_derivation).drop(columns="wall time [s]")
    lines = [
        f"# {heading(case.spec)}",
        "",
        f"**{result.status}**: " + statuses_in_words(counts)
        + f"; worst pointwise error among {'the derivation' if case.one_derivation else 'reference'}, MuJoCo and Pinocchio"
        f": {worst_engine_error(rows):.1e}"
        + f" (tolerance {case.tolerance['pointwise']['value']:g}). [All cases](index.md)"
        + ("" if case.one_derivation else ", [errata](errata.md)")
        + (f"  \nParameters overridden (`--set`): {case.overrides_text()}; the book's figures and printed data"
           " do not apply to them" if case.overrides else ""),
        "",
        *([f"For students: [the book's procedure step by step]({student_page.page_name(case)}).", ""]
          if "course" in case.spec else []),
        *wrong_equations(result),  # first: what a researcher came for
        "## The scene",
        "",
        as_written(case.prose(case.spec["summary"], "summary")),
        "",
        *(embed(figures["scene"], "scene", captions["scene"]) if "scene" in figures else ["", ""]),
        "## Parameters",
        "",
        *parameters_table(case, tmp),
        initial_conditions(case),
        "",
        "## How each source models it",
        "",
        "\n\n".join(" ".join(p.split()) for p in case.prose(case.spec["report"]["modelling"], "report.modelling")
                    .strip().split("\n\n")),
        "",
        "Joints of `scene.xml`, which MuJoCo and Pinocchio both read:" if case.pinocchio_scene.name == "scene.xml"
        else f"Joints of `scene.xml` (MuJoCo) and `{case.pinocchio_scene.name}` (Pinocchio), the same in both:",
        "",
        scene_table(case),
        "",
        *(["## Results", "", f"Computed along each source's run of {initial_words(case)}.", "",
           values_table(case, spaces), ""] if values else []),
        "## Checks",
        "",
        f"Random states tried: {random_sentence(random_tried(result, case))}.",
        "",
        "Errors are relative: pointwise to the largest magnitude of the quantity over the random states,"
        " trajectories to the largest magnitude of the coordinate over the run, energy to the largest"
        " |E| or |W|." + ("" if case.one_derivation else
                          "  `finding` marks a disagreement explained by a registered error of the book."),
        "",
        "In short, the worst row of each comparison (error over its tolerance):",
        "",
        markdown_table(summary_table(rows)),
        "",
        *not_passed(rows),
        *not_checked(rows),
        f"<details><summary>All {len(rows)} checks</summary>",
        "",
        markdown_table(table),
        "",
        "</details>",
        "",
    ]
    if findings:
        lines += ["## Findings: where the book is wrong", ""]
        for f in (measured.finding(result, f) for f in findings):
            lines += [f"### {f.id}: {f.title}", "",
                      f"*Where:* {f.where}.  *Largest relative error:* {size(f.error)}"
                      f" (quantities {', '.join(f.quantities)}; comparisons: {', '.join(f.sources)};"
                      f" {f.established})."
                      + (f"  {f.effect}" if f.effect else ""), "",
                      *([f"*Measured in this run:* {f.measured}", ""] if f.measured else []),
                      f"*Localised automatically* (edits of the printed expression searched until one agrees"
                      f" with the engines): {f.localised}.", "", f.explanation, ""]
    vibration_lines, vibration_files = vibration_page.section(result, case, tmp)
    animation_lines, animation_files = animation.section(result, case, tmp, animations)
    sections, study_files = study_sections(result, case, tmp)
    study_files += vibration_files + animation_files
    lines += animation_lines + vibration_lines + sections + [
        "## Figures",
        "",
        *[line for kind, path in figures.items() if kind != "scene" for line in embed(path, kind, captions[kind])],
        "## Tolerances and why",
        "",
    ]
    for kind, tol in case.tolerance.items():
        value = f"{tol['value']:g}" if "value" in tol else f"safety factor {tol['safety']:g}"
        lines += [f"- **{kind}** ({value}): " + " ".join(case.prose(tol["why"], f"tolerance.{kind}.why").split())]
    lines += ["", "## Cost of the runs", "", markdown_table(cost), "",
              f"Wall times, which differ from run to run, are on the [timing page]({timing_page_name(case)}).", ""]
    page = f"{name}.md"
    (tmp / page).write_text("\n".join(lines))
    return [page] + list(figures.values()) + study_files + write_timing_page(result, case, tmp)


def write_unfinished_page(result, case, tmp):
    """The page of a case whose checks did not finish (its process died or overran its budget): its one row says
    why, and there is nothing else to show."""
    (row,) = result.rows
    page = f"{case.name}.md"
    (tmp / page).write_text("\n".join([
        f"# {heading(case.spec)}", "", f"**{result.status}**: {row.detail}. [All cases](index.md)", "",
        "Nothing else was checked: the rows, runs and figures of this case are those of a run that finishes "
        "(docs/isolation.md).", ""]))
    return page


def cost_table(runs, one_derivation):
    """Each source's run of the initial state and its twin: method, setting, wall time, right-hand-side
    evaluations.  A case of one derivation names them in its own words: its run and twin (the book's)
    and the tight solution (the reference's twin; the reference's run repeats the book's)."""
    shown = ([("derivation", runs["book"].run), ("derivation", runs["book"].twin),
              ("tight solution", runs["reference"].twin)] if runs["book"].ok else []) if one_derivation else \
        [(s, run) for s in ("reference", "book") if runs[s].ok for run in (runs[s].run, runs[s].twin)]
    shown += [(s, run) for s in ("pinocchio", "mujoco") if runs[s].ok for run in (runs[s].run, runs[s].twin)]
    return pd.DataFrame([{"source": s, "method": run.attrs["method"],
                          "setting": f"dt = {run.attrs['dt']:g} s" if run.attrs["dt"] else f"rtol = {run.attrs['rtol']:g}",
                          "wall time [s]": f"{run.attrs['wall']:.3f}", "evaluations": run.attrs["evaluations"]}
                         for s, run in shown], columns=["source", "method", "setting", "wall time [s]", "evaluations"])


def sweep_in_words(sweep, case):
    """The work-precision sweep with its sources named as the case's pages name them (OWN_WORDS for a case
    of one derivation), for its tables and charts."""
    if not case.one_derivation:
        return sweep
    shown = sweep.assign(source=sweep["source"].map(lambda s: OWN_WORDS.get(s, s)))
    shown.attrs = sweep.attrs
    return shown


def initial_words(case):
    return "the initial state" if case.one_derivation else "the book's initial conditions"


def timing_page_name(case):
    return f"{case.name}_timing.md"


def write_timing_page(result, case, tmp):
    """<case>_timing.md and its chart and CSV: every time of the run, apart from the case page because times
    differ from run to run (the page stays the same when nothing else changed)."""
    studies = result.studies
    lines = [f"# {heading(case.spec)}: times", "",
             f"Times of this run on this machine, which differ from run to run; [the case page]({case.name}.md).",
             "", f"All checks of this case took {result.wall:.1f} s.", "",
             f"## The runs of {initial_words(case)}", "",
             markdown_table(cost_table(result.runs, case.one_derivation)), ""]
    files = [timing_page_name(case)]
    if studies and not studies["work_precision"].empty:
        frame = sweep_in_words(studies["work_precision"], case)
        missing = set(work_precision.TIMING_COLUMNS) - set(frame.columns)
        if missing:  # results saved before the column was measured: nothing to rank by
            raise ValueError(f"{case.name}: the saved work-precision sweep lacks {', '.join(sorted(missing))} (saved"
                             " by an earlier dyncheck); make the results again with `dyncheck report`")
        csv, chart = (f"data/{case.name}_work_precision_timing.csv",
                      f"figures/{case.name}_work_precision_timing.png")
        work_precision.write_csv(frame, tmp / csv, timing=True)
        cpu_caption = work_precision.figure(frame, case, tmp / chart, cost="cpu")
        files += [csv, chart]
        best = work_precision.cheapest(frame, cost="cpu")
        labels = {work_precision.point_label(r): r for _, r in frame.iterrows()}

        def cpu_times(label):
            r = labels.get(label)
            return "-" if r is None or pd.isna(r["cpu"]) else \
                f"{r['cpu_min']:.3g} (median {r['cpu']:.3g}, slowest {r['cpu_max']:.3g}; {r['repeats']:g} run{'s' * (r['repeats'] > 1)})"
        table = pd.DataFrame({"level": best["level"].map(lambda x: f"{x:.0e}"),
                              "fewest evaluations": work_precision.cheapest(frame)["cheapest"],
                              "least CPU time": best["cheapest"],
                              "CPU [s]: fastest (median, slowest)": best["points"].map(
                                  lambda points: "; ".join(map(cpu_times, points)) or "-"),
                              "runner-up in CPU time": best["runner_up"],
                              "runner-up CPU [s]": best["runner_up"].map(cpu_times)})
        lines += ["## Speed against accuracy in CPU time", "",
                  f"The work-precision sweep of [the case page]({case.name}.md#speed-against-accuracy) against CPU"
                  " time: the integration alone, the median of repeated runs (quick runs are repeated, as the"
                  " case file's `work_precision.repeat` says), the bars from the fastest to the slowest.  "
                  + CPU_TIME + "  " + work_precision.CPU_NOTE, "",
                  *embed(chart, "work-precision, CPU time", cpu_caption),
                  "Which method reaches each accuracy level (relative trajectory error) in the least CPU time, beside"
                  " the fewest evaluations (the case page's ranking).  " + CPU_TIES, "",
                  markdown_table(table), "", f"The rows behind the chart: [{csv}]({csv}).", ""]
    if studies and studies["stability"]:
        lines += ["## Stability studies", "", markdown_table(pd.DataFrame(
            [{"study": s.title, "wall time [s]": f"{s.wall:.1f}"} for s in studies["stability"]])), ""]
    (tmp / files[0]).write_text("\n".join(lines))
    return files


def wrong_equations(result):
    """The page's account of where the derivation's equations are wrong (dyncheck.checks.residuals): each with the
    terms that explain it, and how many failing rows are its consequences."""
    if not result.localisations:
        return []
    follow = consequences(result)
    return ["## Where the derivation is wrong", "",
            "Each equation whose residual M_engine (q''_derivation - q''_engine) fails against MuJoCo, and each"
            " reaction that fails while the equations hold, fitted over the random states and parameter sets by a"
            " few terms in the derivation's own symbols:", "",
            *[f"- {loc}" for loc in result.localisations], "",
            *([f"Other failing rows, which compare quantities computed from these equations (accelerations, runs,"
               f" energy): {len(follow)}, consequences, not further errors.", ""] if follow else [])]


def study_sections(result, case, tmp):
    """The page's speed-against-accuracy, convergence and stability sections, and the files they use.
    result.studies is None when `dyncheck report --no-studies` left them out."""
    studies = result.studies
    convergence = [r for r in result.rows if r.check == "convergence"]
    lines, files = ["## Speed against accuracy", ""], []
    if studies is None:
        lines += ["Not run this time (`dyncheck report --no-studies`).", ""]
    elif studies["work_precision"].empty:
        lines += [work_precision.NO_SWEEP, ""]
    else:
        frame = sweep_in_words(studies["work_precision"], case)
        csv, chart = f"data/{case.name}_work_precision.csv", f"figures/{case.name}_work_precision.png"
        work_precision.write_csv(frame, tmp / csv)
        caption = work_precision.figure(frame, case, tmp / chart)
        files += [csv, chart]
        reference = frame.attrs["reference"]
        unfinished = frame[frame["status"].isin(work_precision.UNFINISHED)]
        best = work_precision.cheapest(frame).drop(columns=["points", "methods"])
        best["level"] = best["level"].map(lambda x: f"{x:.0e}")
        for column in ("evaluations", "runner_up_evaluations"):
            best[column] = best[column].map(lambda x: "-" if pd.isna(x) else f"{x:.0f}")
        best["error"] = best["error"].map(lambda x: "-" if pd.isna(x) else f"{x:.3g}")
        solution = ("the tight solution: the derivation" if case.one_derivation else
                    "the reference solution: the reference's equations")
        lines += [f"Every method from {initial_words(case)} over {reference['t_end']:g} s, against"
                  f" {solution} by {reference['label']}.  Error is the largest deviation of any"
                  " coordinate or rate, relative to its largest magnitude; the rows behind the chart are in"
                  f" [{csv}]({csv}).  {work_precision.EVALUATIONS_NOTE}", "",
                  *embed(chart, "work-precision", caption),
                  "Which method is cheapest (fewest evaluations) at each accuracy level (relative trajectory"
                  f" error); in CPU time on the [timing page]({timing_page_name(case)}):", "",
                  markdown_table(best.rename(columns={"runner_up": "runner-up",
                                                      "runner_up_evaluations": "runner-up evaluations"})), ""]
        for status, words in zip(work_precision.UNFINISHED, ("Unstable (blew up; not drawn)",
                                                             "Budget spent (stopped at its wall time; not drawn)")):
            points = unfinished[unfinished["status"] == status]
            if len(points):
                lines += [f"{words}: " + "; ".join(f"{work_precision.point_label(r)}: {r['detail']}"
                                                    for _, r in points.iterrows()) + ".", ""]
    if convergence:
        lines += ["## Convergence", "",
                  "Observed order of each fixed-step method, from runs at h, h/2, h/4 (checks; tolerance from"
                  " the next term of the error expansion, see the case file):", "",
                  markdown_table(pd.DataFrame([{"method": r.quantity, "source": r.comparison,
                                                "|observed - expected|": "-" if r.error is None else f"{r.error:.3f}",
                                                "tolerance": "-" if r.tolerance is None else f"{r.tolerance:.3f}",
                                                "status": str(r.status), "detail": r.detail} for r in convergence])),
                  ""]
    elif case.coords:  # without coordinates the speed section has said that nothing is integrated
        lines += ["## Convergence", "", "No fixed-step method is checked for this case.", ""]
    if studies and studies["stability"]:
        lines += ["## Stability: where methods fail", ""]
        for study in studies["stability"]:
            lines += [f"### {study.title}", "", *[f"- {sentence}" for sentence in study.findings], ""]
            chart = f"figures/{case.name}_{study.study}.png"
            caption = stability.figure(case, study, tmp / chart)
            if caption is None:  # not applicable at these parameters: nothing measured, nothing drawn
                lines += [f"*How, where it applies:* {study.why}", ""]
                continue
            if not (tmp / chart).is_file():  # a case's own figure function that drew nothing
                raise ValueError(f"{case.origin}: stability study {study.study}: its figure function wrote no {chart}")
            files.append(chart)
            lines += [*embed(chart, study.study, caption),
                      f"*How:* {study.why}", "",
                      f"<details><summary>The numbers ({plural(len(study.table), 'row')})</summary>", "",
                      markdown_table(study.table), "", "</details>", ""]
    return lines, files


def parameters_table(case, tree):
    """The page's table of parameters, and where the book's program gives one, what the listing shows; `tree`: the
    folder the page is written in, from which the link to docs/book-numbers.md goes."""
    printed = any(p.printed for p in case.parameters)
    table = pd.DataFrame([{"parameter": p.name, "value": f"{p.value:.10g}", "unit": p.unit, "allowed": p.allowed,
                           **({"as printed": as_printed(p)} if printed else {}),
                           "meaning": p.about + (" (overridden)" if p.name in case.overrides else "")}
                          for p in case.parameters])
    # ../docs from the book's report trees, top-level folders of the checkout (reports/, reports-NAME=VALUE/); from
    # an --out elsewhere, the way to this checkout's docs
    book_numbers = Path(os.path.relpath(CASES_DIR.parent / "docs" / "book-numbers.md", tree)).as_posix()
    return [markdown_table(table), "",
            *(["*As printed*: the value in the book's program listing as the book's text extraction shows it.  The"
               " extraction lost every digit 0; each value was read back by replaying the listing for every way of"
               " restoring the zeros and keeping the one that lands inside the book's figures ([the book's"
               f" numbers]({book_numbers}), example by example).", ""] if printed else [])]


def as_printed(parameter):
    """A parameter's value as the book's listing shows it and as read, for the parameters table."""
    if parameter.printed is None:
        return "-"
    read = f"{parameter.default:.10g}"
    return f"printed `{parameter.printed}`" + ("" if parameter.printed == read else
                                                f", read {read} (digits 0 lost in extraction)")


def initial_conditions(case):
    """The page's line on the initial state and the horizon; a scene with no free coordinate starts where its
    prescribed motions put it, and the line gives their laws instead."""
    q0, v0, t_end = case.initial
    state = _state(case.coords, q0, v0) if case.coords else "none, every joint moves as prescribed: " + ", ".join(
        f"{joint} = {law_of_time(law)}" for joint, law in case.scene.driven.items())
    label = "Initial conditions" if case.one_derivation else "Initial conditions (the book's)"
    return f"{label}: {state}; horizon {t_end:g} s."


def _state(coords, q, v):
    return ", ".join(f"{c} = {x:.6g}" for c, x in zip(coords, q)) + ", " + \
        ", ".join(f"{c}' = {x:.6g}" for c, x in zip(coords, v))


def law_of_time(law):
    """A prescribed motion (dyncheck.case.scene.Driven) angle + rate t + acc t^2/2 with its zero terms left out:
    "0.8 + 0.3 t - 0.05 t^2"."""
    terms = [f"{coefficient:.6g}{power}" for coefficient, power in ((law.angle, ""), (law.rate, " t"), (law.acc / 2, " t^2"))
             if coefficient]
    return " + ".join(terms).replace("+ -", "- ") or "0"


SUMMARY_KEYS = {"case", "section", "params", "checks", "findings", "title", "status", "worst_engine_error",
                "random", "cheapest", "one_derivation"}  # what write_summary writes
