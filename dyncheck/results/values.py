"""The values that flow from the checks to the report: rows, run outcomes, a case's and a study's results.

Data flows one way: case -> models -> checks and studies -> these results -> saved (dyncheck.results.store)
-> the report, which renders saved results only.  Their JSON form (`rows_json`, the `run --json`
file) carries RESULTS_VERSION; docs/results.md describes it.
"""

from __future__ import annotations  # unevaluated: they name pandas's types without importing pandas

import enum
import math
from dataclasses import asdict, dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # imported where a table is made (format_rows): `run --quick` prints its rows without it (0.4 s)
    import pandas as pd

from dyncheck.results import measured, store

RESULTS_VERSION = 7  # 1: rows with "sources" as "a vs b"; 2: "sources" a list, "version" at the top;
# 3: "status" and "counts" at the top and in each case, "reason" in each row, "tool" in run --json;
# 4: "localisations" in each case, check "equation", sources "derivation" and "tight solution"; 5: check "vibration";
# 6: "measured" in each finding, the listing's run against the exact motion measured under --set; 7: status
# "budget spent"


@store.register
class Status(enum.StrEnum):
    """A row's verdict (docs/statuses.md)."""
    PASS = "pass"
    FINDING = "finding"  # a failure that a registered error of the book explains
    FAIL = "fail"
    INCONCLUSIVE = "inconclusive"  # the tolerance is above the ceiling: the comparison proves nothing
    UNSTABLE = "unstable"  # an integration blew up: no number to compare
    SPENT = "budget spent"  # an integration spent its time before its end: no number, and no fault shown
    # the book's printed run under other parameters; a derivation's missing energy; a study with nothing to measure
    NOT_APPLICABLE = "not applicable"
    RUNAWAY = "runaway"  # every source's run left the case's physical limits, as the case says it must

    @property
    def ok(self):
        """Whether a run with this row exits 0.  A runaway is ok: the checks give it only when every
        source escaped as the case's [[runaway]] says the physics must (dyncheck.checks.runs.runaway_rows)."""
        return self in (Status.PASS, Status.FINDING, Status.NOT_APPLICABLE, Status.RUNAWAY)


@store.register
@dataclass(frozen=True)
class Row:
    """One comparison of one quantity between sources (one source: a balance of that source's run)."""
    check: str
    quantity: str
    sources: tuple
    error: float | None
    tolerance: float | None
    ceiling: float | None
    status: Status
    finding: str | None = None
    detail: str = ""

    @property
    def comparison(self):
        return " vs ".join(self.sources)

    @property
    def yes_or_no(self):
        """A comparison with no tolerance (inside a printed figure's axes or not): no error to weigh."""
        return self.tolerance == 0 and self.ceiling == 0


def row(check, quantity, sources, error, tolerance, detail="", *, ceiling):
    """A check's row; `ceiling` (dyncheck.common.ceilings) is the tolerance above which the comparison proves
    nothing: such a row is inconclusive, whatever its error."""
    if not isinstance(sources, tuple):  # ("a", "b"); a string would pass for a tuple of its letters
        raise TypeError(f"sources must be a tuple of source names, not {sources!r}")
    if not (math.isfinite(error) and math.isfinite(tolerance)):  # a source gave no number: never a NaN out
        return no_number(check, quantity, sources, f"no number to judge: error {error}, tolerance {tolerance}; "
                         + detail, Status.FAIL)
    if tolerance > ceiling:
        status = Status.INCONCLUSIVE
        detail = (f"tolerance {tolerance:.2e} is above the ceiling {ceiling:.0e} of this comparison, so it "
                  f"proves nothing (dyncheck/common/ceilings.py); " + detail)
    else:
        status = Status.PASS if error <= tolerance else Status.FAIL
    return Row(check, quantity, sources, float(error), float(tolerance), float(ceiling), status, None, detail)


def no_number(check, quantity, sources, why, status=None):
    """A check that has no error to show: an integration blew up or spent its budget (`why`, the Failure or the
    dyncheck.run.simulate.Unstable, says when, which method, which step; the row takes its status), or (status
    FAIL) the check could not be made, and `why` says why."""
    if not isinstance(sources, tuple):
        raise TypeError(f"sources must be a tuple of source names, not {sources!r}")
    status = getattr(why, "status", Status.UNSTABLE) if status is None else status
    return Row(check, quantity, sources, None, None, None, Status(status), None, str(why))


@store.register
@dataclass(frozen=True)
class Failure:
    """An integration that blew up, as a value: which method, when, which step (None: between steps), why."""
    method: str
    t: float | None
    step: int | None
    why: str
    status = Status.UNSTABLE  # a row's without the run

    def __str__(self):
        when = f" at t = {self.t:.6g} s" if self.t is not None else ""
        return f"{self.method} unstable{when}" + (f" (step {self.step})" if self.step is not None else "") \
            + f": {self.why}"


@store.register
@dataclass(frozen=True)
class Outcome:
    """A source's run of the book's initial conditions and its tighter twin, or why there is none; for
    MuJoCo also `approximations`, the run of its scene with its approximations of the case's physics
    doubled (Case.approximations_doubled)."""
    run: pd.DataFrame | None = None
    twin: pd.DataFrame | None = None
    failure: Failure | None = None
    approximations: pd.DataFrame | None = None

    @property
    def ok(self):
        return self.failure is None


@store.register
@dataclass(frozen=True)
class StudyResult:
    """One study of a case (a stability study, dyncheck.studies.stability): everything its page section draws."""
    case: str
    study: str
    title: str
    why: str
    data: pd.DataFrame  # every number measured (NaN only where a status column says why)
    table: pd.DataFrame  # the same for display: strings
    findings: tuple  # sentences with the numbers
    series: dict  # what the figure draws
    settings: dict
    wall: float


@store.register
@dataclass(frozen=True)
class Pair:
    """What a finding's book prints and what is right, as the errata typeset them side by side
    (dyncheck.pages.typeset.marked): expressions in Python syntax, those the code evaluates."""
    printed: str  # the book's: its module's PRINTED entry, or the value its listing, figure or data uses
    right: str  # the localised edit's expression, the case file's `right` (checked by a row), or a value measured
    printed_from: str  # in words, what the printed side is
    right_from: str  # in words, where the right side comes from
    lhs: str = ""  # what both sides are the value of ("R"); "" when the sides are relations
    symbols: dict = field(default_factory=dict)  # the names' LaTeX: the source module's LATEX


@store.register
@dataclass(frozen=True)
class Finding:
    """A registered error of the book with what this run measured of it."""
    id: str
    title: str
    where: str
    quantities: tuple
    sources: tuple
    error: float | None
    explanation: str
    established: str
    effect: str
    localised: str
    pairs: tuple = ()  # of Pair: the book's expressions or values and the right ones
    measured: str = ""  # what this run measures of it: the case file's text, its `{~ ...}` written by the pages


@store.register
@dataclass(frozen=True)
class Frames:
    """One run's skeleton at the animation's frame times (engines.render.skeleton), world coordinates in m."""
    times: np.ndarray  # (frame,) s
    segments: np.ndarray  # (frame, segment, 2, 3)
    dots: np.ndarray  # (frame, dot, 3): the massive bodies' centres of mass
    masses: np.ndarray  # (dot,) kg
    rims: np.ndarray  # (frame, rim, points, 3)


@store.register
@dataclass(frozen=True)
class Localisation:
    """A failing equation of a derivation (dyncheck.checks.residuals) and the terms its residual is fitted by."""
    source: str  # the derivation: "reference", "book" or "derivation"
    equation: str  # the coordinate whose equation is wrong; "" for a reaction
    place: str  # where: "equation x" (its force side, or its residual), a mass matrix entry "M[x,theta]", "reaction R",
    #             "energy"
    text: str  # what the fit found, in the derivation's own symbols
    exact: bool  # whether the terms explain the residual down to the engines' rounding
    identified: bool  # exact, and every coefficient a simple number times a product of the parameters
    residual: float  # the largest residual before the fit, N, N m, kg, kg m or kg m^2
    left: float  # and after it
    sets: int  # parameter sets fitted over

    def __str__(self):
        return f"the {self.source}'s {self.place}: {self.text}"


@store.register
@dataclass(frozen=True)
class CaseResult:
    """Everything a case's run produced; the report reads nothing else (apart from the case file's
    text, carried in `spec`)."""
    folder: str  # the case folder (its study module is there)
    spec: dict  # the case file as loaded: Case(folder, overrides, spec) rebuilds the case without reading it
    overrides: dict
    rows: tuple
    findings: tuple
    sample: dict  # states: (t, q, v) per random state; values: {source: {quantity: array}} or {source: why}
    runs: dict  # {source: Outcome}
    program: dict  # the book's program: {"listing", "same integrator", "tight": frames}, "integrator", "dt"
    drawings: dict  # what the figures draw beyond the runs (dyncheck.checks.runs.drawings)
    wall: float
    studies: dict | None = None  # {"work_precision": frame, "stability": [StudyResult]}; None: not run
    localisations: tuple = ()  # of Localisation: the failing equations of the derivation, their wrong terms
    vibration: object = None  # dyncheck.checks.vibration.Vibration of a case with [vibration]
    version: int = RESULTS_VERSION

    @property
    def name(self):
        return self.spec["name"]

    @property
    def status(self):
        """As the pages head it: PASS or FAIL (`verdict`)."""
        return verdict(self.rows).upper()

    @property
    def overrides_text(self):
        return overrides_in_words(self.overrides, self.spec)

    def with_studies(self, studies):
        return replace(self, studies=studies)


TIGHT = {"reference": "tight reference", "derivation": "tight solution"}  # a derivation's tight run, as rows name it
# A researcher's case has one derivation, no book beside a reference that corrects it: its rows and pages
# name the sources so (dyncheck.checks.runs.in_own_words).
OWN_WORDS = {"reference": "derivation", "book": "derivation", "tight reference": "tight solution"}


def consequences(result):
    """The failing rows, other than the equations' own, that compare quantities computed from a derivation
    whose equations are wrong (result.localisations): its accelerations feed its runs, the tight run every
    other run is compared with, their energy and whatever it computes from them.  Consequences, not
    further errors."""
    sources = {loc.source for loc in result.localisations if loc.equation}  # a wrong reaction feeds nothing
    sources |= {TIGHT[s] for s in sources if s in TIGHT}
    # a wrong energy feeds its own source's energy balance along the runs
    energies = {loc.source for loc in result.localisations if loc.place == "energy"}
    return [r for r in result.rows if not r.status.ok and r.check != "equation" and (
        sources & set(r.sources) or r.check == "energy" and energies & set(r.sources))]


def heading(spec):
    """A case as titles name it: "1.8.3 Spring-mass pendulum on a spinning arm", or its title alone where
    the case has no section (a case of your own)."""
    return " ".join(filter(None, (spec.get("section", ""), spec["title"])))


def overrides_in_words(overrides, spec):
    """Overrides as pages and rows show them: "k = 500 N/m (book: 2000)", or "(default: 2000)" for a case that
    is no section of the book (a case of your own); `spec`: the case file."""
    params, source = spec["params"], "book" if spec.get("section") else "default"
    return ", ".join(f"{name} = {value:g} {params[name]['unit']} ({source}: {float(params[name]['value']):g})"
                     for name, value in overrides.items())


def rows_json(rows):
    return [{"check": r.check, "quantity": r.quantity, "sources": list(r.sources), "error": r.error,
             "tolerance": r.tolerance, "ceiling": r.ceiling, "status": str(r.status), "finding": r.finding,
             "detail": r.detail, "reason": reason(r)} for r in rows]


def reason(row):
    """Why a row counts as a failure, in one line (None for a row that counts as success): its error
    against its tolerance, or, with no number, the row's own account (for an integration that blew up:
    when, which method, which step, why)."""
    if row.status.ok:
        return None
    if row.error is None:
        return row.detail
    if row.status == Status.INCONCLUSIVE:
        return f"tolerance {row.tolerance:.2e} is above the ceiling {row.ceiling:.0e} of this comparison"
    judged = inside_or_outside(row) + " the printed range" if row.yes_or_no else \
        f"error {row.error:.2e} {'>' if row.error > row.tolerance else '<='} tolerance {row.tolerance:.2e}"
    if row.finding:  # a registered error of the book that this row no longer shows
        return f"registered finding {row.finding} no longer reproduces: {judged}"
    return judged


def verdict(rows):
    """"pass" when every row counts as success (the exit code 0), else "fail"."""
    return "pass" if all(r.status.ok for r in rows) else "fail"


def status_counts(rows):
    """How many rows have each status, every status named (0 for none), in the order of Status."""
    return {str(status): sum(r.status == status for r in rows) for status in Status}


def findings_json(findings):
    return [{"id": f.id, "title": f.title, "quantity": list(f.quantities), "sources": list(f.sources),
             "error": f.error, "explanation": f.explanation, "where": f.where, "established": f.established,
             "effect": f.effect, "measured": f.measured, "localised": f.localised} for f in findings]


def case_json(result):
    """A case's entry in `dyncheck run --json` and in the report's data/<case>.json: results only, nothing
    of the machine or checkout that made them, so that a committed data/<case>.json changes only with them."""
    params = {name: float(p["value"]) for name, p in result.spec["params"].items()}
    return {"case": result.name, "section": result.spec.get("section", ""), "status": verdict(result.rows),
            "counts": status_counts(result.rows), "params": {**params, **result.overrides},
            "overrides": dict(result.overrides), "checks": rows_json(result.rows),
            "findings": findings_json([measured.finding(result, f) for f in result.findings]),
            "localisations": localisations_json(result.localisations)}


def localisations_json(localisations):
    return [asdict(loc) for loc in localisations]


def to_json(results, tool=None, interrupted=None, left_out=()):
    """The `dyncheck run --json` file of `results`: with `tool` (dyncheck.results.ci.tool_versions()), what ran
    them; with `interrupted`, the case that Ctrl-C stopped (the results are then of the cases before it,
    and the run does not pass); with `left_out`, the checks that `run --quick` left out."""
    rows = [r for result in results for r in result.rows]
    return {"version": RESULTS_VERSION, "status": "fail" if interrupted else verdict(rows),
            "counts": status_counts(rows), **({"tool": tool} if tool else {}),
            **({"incomplete": f"interrupted (Ctrl-C) during case {interrupted}"} if interrupted else {}),
            **({"quick": list(left_out)} if left_out else {}),
            "cases": [case_json(r) for r in results]}


TABLE_COLUMNS = ["check", "quantity", "sources", "error", "tolerance", "status"]


def row_cells(rows):
    """The rows as strings, {column: text} for each, as `dyncheck run` prints them and the pages list them."""
    number = lambda x: "-" if x is None else f"{x:.2e}"
    return [{"check": r.check, "quantity": r.quantity, "sources": r.comparison,
             "error": inside_or_outside(r) if r.yes_or_no else number(r.error),
             "tolerance": "-" if r.yes_or_no else number(r.tolerance), "status": str(r.status)} for r in rows]


def format_rows(rows):
    """The rows as a table of strings, as the pages list them."""
    import pandas as pd
    return pd.DataFrame(row_cells(rows), columns=TABLE_COLUMNS)


def rows_text(rows):
    """The rows as `dyncheck run` prints them: each column right-aligned under its heading, one space apart."""
    lines = [dict(zip(TABLE_COLUMNS, TABLE_COLUMNS))] + row_cells(rows)
    widths = {column: max(len(line[column]) for line in lines) for column in TABLE_COLUMNS}
    return "\n".join(" ".join(line[column].rjust(widths[column]) for column in TABLE_COLUMNS) for line in lines)


def inside_or_outside(row):
    """A yes-or-no comparison's error in words: "inside", or "outside by" its relative excess."""
    return "inside" if row.error == 0 else f"outside by {row.error:.2g}"


def save_results(results, folder):
    """Each case's result into folder/<case>/ (dyncheck.results.store), replacing what was there of that case."""
    folder.mkdir(parents=True, exist_ok=True)
    for result in results:
        store.save(result, folder / result.name)


def load_results(folder):
    """The CaseResults saved in folder/<case>/, in name order; ValueError naming what is not one.
    Hidden folders (a save in progress, or one a kill left) are not results."""
    if not folder.is_dir():
        raise ValueError(f"{folder}: no such folder")
    folders = sorted(p.parent for p in folder.glob("*/value.json") if not p.parent.name.startswith("."))
    if not folders:
        hint = " (the report's saved results are in its results/ folder)" if (folder / "results").is_dir() else ""
        raise ValueError(f"{folder}: holds no saved results (no <case>/value.json){hint}; `dyncheck run --results "
                         "DIR` and `dyncheck report` (in its results/) save them")
    return [load_result(path) for path in folders]


def load_result(path):
    """The CaseResult saved in `path`, a folder named after its case; ValueError naming what is wrong."""
    result = store.load(path)
    if not isinstance(result, CaseResult):
        raise ValueError(f"{path}: holds a {type(result).__name__}, not a case's results")
    if result.name != path.name:  # a copy set aside under another name would pass for the case's results
        raise ValueError(f"{path}: holds the results of case '{result.name}', not of '{path.name}'")
    return result

