"""A student's page per case, <case>_student.md beside the validation page <case>.md: the book's procedure
step by step in plain words, each intermediate result typeset from the expression the code evaluates, and next
to it what the engines say of it, taken from the run's rows.

What each step says and shows is the case's `[course]` table (docs/student-pages.md); this module names no
case.  An expression is named by where the code keeps it:
    book:KEY      the derivation's Book.PRINTED[KEY] (the book's formula as printed, as evaluated)
    program:KEY   its Program.PRINTED[KEY] (a line of the book's listing)
    frames:KEY    the derivation module's FRAMES[KEY] (a transformation matrix of the angle `a`)
Rendered from saved results only, like every page."""

import math
import re
from dataclasses import dataclass

from dyncheck.common import style, words
from dyncheck.common.messages import ENGINE_NAMES
from dyncheck.pages import typeset
from dyncheck.pages.vibration_page import VERDICT_WORDS, equilibrium_value
from dyncheck.results import measured
from dyncheck.results.values import Status, heading

SUBJECT_WORDS = {"book": "The book's version", "program": "The listing's version", "reference": "It",
                 "mujoco": "MuJoCo's run", "pinocchio": "Pinocchio's run"}
OTHER_WORDS = {"tight reference": "the exact motion", "reference": "the right equations",
               "book equations, same integrator": "the book's equations integrated the same way"}
SAMPLE = re.compile(r"(\d+) random states|(\d+) of the program's rows|over ([0-9.]+ s)")


@dataclass(frozen=True)
class Shown:
    """One result a step shows: its expression (None: a check alone), typeset as `label` = ..., and the rows of
    `quantities` whose first source is `source` that check it; `checked` says in words what they compare."""
    expression: str | None
    label: str
    quantities: tuple
    source: str
    symbols: dict
    checked: str


@dataclass(frozen=True)
class Step:
    title: str
    text: str
    shown: tuple  # of Shown
    figures: tuple  # of (figure name on the validation page, caption)
    vibration: bool  # the step shows the vibration results


@dataclass(frozen=True)
class Course:
    intro: str
    steps: tuple  # of Step


def page_name(case):
    return f"{case.name}_student.md"


def course(case):
    """The case's [course] as a Course, every expression and quantity it names checked against the case; None for a
    case without one.  ValueError naming the file, the field and the value."""
    spec = case.spec.get("course")
    if spec is None:
        return None
    steps = []
    for i, step in enumerate(spec["steps"]):
        shown = []
        for j, item in enumerate(step.get("show", [])):
            field = f"course.steps[{i}].show[{j}]"
            expression = item.get("expression")
            if expression is not None:
                expression_text(case, expression, f"{field}.expression")  # refused here if it names nothing
            kind, _, key = (expression or "").partition(":")
            shown.append(Shown(expression, item.get("label", ""), tuple(item.get("quantities", [key])),
                               item.get("source", kind if kind in ("book", "program") else "reference"),
                               item.get("symbols", {}), item.get("checked", "")))
        steps.append(Step(step["title"], case.prose(step["text"], f"course.steps[{i}].text"), tuple(shown),
                          tuple((f["figure"], f["caption"]) for f in step.get("figures", [])),
                          step.get("vibration", False)))
    return Course(case.prose(spec["intro"], "course.intro"), tuple(steps))


def expression_text(case, name, field):
    """The expression string `name` (book:KEY, program:KEY or frames:KEY) as the code evaluates it."""
    kind, _, key = name.partition(":")
    derivation = case.derivation
    tables = {"book": lambda: getattr(getattr(derivation, "Book", None), "PRINTED", {}),
              "program": lambda: getattr(getattr(derivation, "Program", None), "PRINTED", {}),
              "frames": lambda: getattr(derivation, "FRAMES", {})}
    if kind not in tables:
        raise ValueError(f"{case.origin}: {field} = {name!r}: not book:KEY, program:KEY or frames:KEY")
    table = tables[kind]()
    if key not in table:
        raise ValueError(f"{case.origin}: {field} = {name!r}: {case.spec['derivation']} has no {kind} expression "
                         f"{key!r}" + (f"; it has {', '.join(table)}" if table else ""))
    return table[key]


def symbol_table(case, name, extra):
    """LaTeX names for the symbols of expression `name`: the derivation's LATEX tables, then the item's own."""
    kind = name.partition(":")[0]
    owner = {"book": "Book", "program": "Program"}.get(kind)
    derivation = case.derivation
    table = dict(getattr(derivation, "LATEX", {}))
    if owner:
        table.update(getattr(getattr(derivation, owner, None), "LATEX", {}))
    return {**table, **extra}


# -- the checks next to each result ---------------------------------------------------------

def components(quantities, rows):
    """The row quantities that shown quantities stand for: each itself, or a vector's components (a_E_x, ... or
    Rx, ...)."""
    names = {r.quantity for r in rows}
    found = set()
    for quantity in quantities:
        found |= next((set(parts) for parts in ([f"{quantity}_{axis}" for axis in "xyz"],
                                                [f"{quantity}{axis}" for axis in "xyz"])
                       if all(p in names for p in parts)), {quantity})
    return found


def where_sampled(rows):
    """"at 100 random states", "at 200 of the listing's states" or "over 3 s", from the rows' details."""
    for r in rows:
        match = SAMPLE.search(r.detail)
        if match:
            states, listing, span = match.groups()
            return (f"at {states} random states" if states else f"at {listing} of the listing's states" if listing
                    else f"over {span}")
    return ""


def other_side(row):
    """Whom a row compares with, in words: "MuJoCo", "the exact motion", ..."""
    other = row.sources[1]
    return next((w for e, w in ENGINE_NAMES.items() if other.startswith(e)), OTHER_WORDS.get(other, other))


def agreement(rows):
    """"agrees with MuJoCo to 3e-15 and Pinocchio exactly": the worst error against each engine (or other side),
    in the words dyncheck.common.words chooses from it: it agrees only where every row is within its tolerance ("differs
    from the exact motion by 95 %" where one is not)."""
    sides = {}
    for r in rows:
        sides.setdefault(other_side(r), []).append(r)
    return words.agreement([(whom, max(r.error for r in side), all(r.tolerance is not None and r.error <= r.tolerance
                                                                    for r in side)) for whom, side in sides.items()])


def _sentence(*parts):
    return " ".join(part for part in parts if part) + "."


def check_sentence(shown, rows):
    """The plain-words check of one shown result, from the rows of its quantities; None where no row checks it."""
    names = components(shown.quantities, rows)
    judged = [r for r in rows if r.quantity in names and r.error is not None and len(r.sources) == 2
              and r.check != "figure"]
    mine = [r for r in judged if r.sources[0] == shown.source and (r.sources[1].startswith(tuple(ENGINE_NAMES))
                                                                   or r.sources[1] in OTHER_WORDS)]
    if not mine:
        return None
    head = f"*Check* ({shown.checked}):" if shown.checked else "*Check:*"
    subject = SUBJECT_WORDS[shown.source]
    wrong = [r for r in mine if r.status == Status.FINDING]
    if not wrong:
        return _sentence(head, subject, agreement(mine), where_sampled(mine))
    ids = sorted({r.finding for r in wrong})
    worst = max(wrong, key=lambda r: r.error)
    right = [r for r in judged if r.sources[0] == "reference" and r.sources[1].startswith(tuple(ENGINE_NAMES))]
    return _sentence(head, subject, f"is off by {words.share(worst.error)} of its largest value against",
                     other_side(worst), where_sampled([worst]),
                     "(" + ", ".join(f"finding [{i}](errata.md#{i.replace('.', '').lower()})" for i in ids) + ")"
                     + (";" if right else ""),
                     right and f"the right one {agreement(right)}", right and where_sampled(right))


# -- the page -------------------------------------------------------------------------------

def right_side(result, printed):
    """(finding, right expression) where a finding of the run pairs the printed expression `printed` with the
    right one (dyncheck.results.values.Pair: a localised edit, or the case file's `right`, checked by a row); else None."""
    for finding in result.findings:
        for pair in getattr(finding, "pairs", ()):
            if pair.printed == printed:
                return finding, pair.right
    return None


def maths(case, result, shown):
    """Display maths of one shown result: its expression, or the book's and the right one with the difference
    boxed where a finding gives the right one."""
    text = expression_text(case, shown.expression, "course")
    symbols = symbol_table(case, shown.expression, shown.symbols)
    wrong = right_side(result, text)
    if wrong is None:
        return [f"$${shown.label} = {typeset.latex(text, symbols)}$$", ""]
    finding, right = wrong
    printed, corrected = typeset.marked(text, right, symbols)
    return ["As the book prints it (boxed: what differs):", "", f"$${shown.label} = {printed}$$", "",
            f"Right (finding [{finding.id}](errata.md#{finding.id.replace('.', '').lower()})):", "",
            f"$${shown.label} = {corrected}$$", ""]


def step_lines(number, step, case, result, tmp):
    lines = [f"## {number}. {step.title}", "", *paragraphs(measured.fill(result, step.text))]
    for shown in step.shown:
        if shown.expression:
            lines += maths(case, result, shown)
        sentence = check_sentence(shown, result.rows)
        if sentence:
            lines += [sentence, ""]
    if step.vibration:
        lines += vibration_lines(case, result)
    for figure, caption in step.figures:
        drawn = [path for path in (f"figures/{case.name}_{figure}.png", f"figures/{case.name}_{figure}.gif")
                 if (tmp / path).is_file()]
        if drawn:
            lines += style.embed(drawn[0], f"{case.title}: {figure}", " ".join(measured.fill(result, caption).split()))
        elif figure == "animation":  # `dyncheck report --no-animations`, or results without frames
            lines += ["(The animation is not in this report: the case page says why.)", ""]
        elif case.overrides:  # a --set may leave a figure undrawn: a run that ran away, no oscillating mode, ...
            why = ("it is drawn along the reference run, which did not reach its end" if not result.runs["reference"].ok
                   else "the case page could not draw it at these parameters")
            lines += [f"(The figure '{figure}' is not in this report: {why}; the case page says why.)", ""]
        else:  # at the book's numbers the case page draws every figure a course may name: this one it never draws
            raise ValueError(f"{case.origin}: course.steps: figure {figure!r}: the case page drew no "
                             f"figures/{case.name}_{figure}.png")
    return lines


def paragraphs(text):
    """The case file's text as Markdown paragraphs: blank lines part them, other line breaks are spaces."""
    return [line for p in text.strip().split("\n\n") for line in (" ".join(p.split()), "")]


def vibration_lines(case, result):
    """Step 9's numbers: the equilibrium, each natural frequency with its agreement, the stability verdict."""
    vib = result.vibration
    if vib is None or vib.equilibrium is None or not vib.modes:
        return ["This example has no vibration analysis here" + (f": {vib.failure}" if vib is not None else "")
                + ".", ""]
    units = dict(zip(case.coords, case.spec["coord_units"]))
    symbols = symbol_table(case, "book:", {})
    eq = vib.equilibrium
    moving = [(c, x) for c, x in zip(case.coords, eq.v) if equilibrium_value(x) != "0"]  # a steady motion's rates
    lines = ["The equilibrium the computer finds (Newton-Raphson): " + ", ".join(
        f"${typeset.latex(c, symbols)} = {equilibrium_value(x)}$ {units[c]}" for c, x in zip(case.coords, eq.q))
        + ("" if not moving else ", its angles turning steadily at " + ", ".join(
            f"${typeset.latex(c + '_rate', symbols)} = {equilibrium_value(x)}$ {units[c]}/s" for c, x in moving))
        + ".", ""]
    ref = vib.modes["reference"]
    table = ["| mode | frequency [rad/s] | [Hz] | check |", "|---|---|---|---|"]
    for k, i in enumerate(ref.oscillating()):
        rows = [r for r in vib.rows if r.quantity == f"frequency mode {k + 1}" and r.sources[0] == "reference"]
        omega = ref.eigenvalues[i].imag
        table.append(f"| {k + 1} | {omega:.6g} | {omega / (2 * math.pi):.4g} | {agreement(rows) or '-'} |")
    engines = {ENGINE_NAMES[s]: m.verdict for s, m in vib.modes.items() if s in ENGINE_NAMES}
    lines += ["Natural frequencies of small motions about it:", "", *table, "",
              f"Stability: **{ref.verdict}**" + (", and MuJoCo and Pinocchio find the same" if
                                                 set(engines.values()) == {ref.verdict} else
                                                 "; " + ", ".join(f"{e}: {v}" for e, v in engines.items()))
              + f".  {VERDICT_WORDS[ref.verdict]}", ""]
    return lines


def write(result, case, tmp):
    """<case>_student.md from the case's [course]; [] for a case without one."""
    spec = course(case)
    if spec is None:
        return []
    lines = [f"# {heading(case.spec)}: step by step", "",
             f"The book's procedure for this example, one step at a time.  Every formula below is the one the"
             f" computer evaluates; next to it, how far it is from what two independent physics engines, MuJoCo and"
             f" Pinocchio, compute for the same system (each difference relative to the largest value of the quantity"
             f" over the states tried).  The full validation is on [the case page]({case.name}.md).", "",
             *([f"This page is for other parameters than the book's: {case.overrides_text()}.  Its numbers and"
                " checks are this run's, at those parameters.", ""] if case.overrides else []),
             *paragraphs(measured.fill(result, spec.intro))]
    for number, step in enumerate(spec.steps, 1):
        lines += step_lines(number, step, case, result, tmp)
    page = page_name(case)
    (tmp / page).write_text("\n".join(lines))
    return [page]
