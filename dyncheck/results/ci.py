"""What a CI system reads of `dyncheck run` and `report` besides the exit code (docs/results.md): the
versions of what ran, the JUnit XML file, GitHub's annotations, and the closing recap and summary line."""

import platform
import subprocess
import xml.etree.ElementTree as ET
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from dyncheck.common import expressions
from dyncheck.common.messages import plural, statuses_in_words
from dyncheck.results.values import Status, consequences, reason, status_counts

CHECKOUT = Path(__file__).resolve().parents[2]  # where the package runs from, if it is a git checkout
VERSIONED = {"dyncheck": "dyncheck", "mujoco": "mujoco", "pinocchio": "pin", "numpy": "numpy"}  # name: distribution


def tool_versions():
    """The versions of dyncheck, Python, the engines and numpy, and the checkout's commit: the `tool`
    object of `run --json`.  A package that is not installed has the version None."""
    def installed(distribution):
        try:
            return version(distribution)
        except PackageNotFoundError:
            return None
    return {"python": platform.python_version(),
            **{name: installed(distribution) for name, distribution in VERSIONED.items()},
            "commit": commit(CHECKOUT)}


def commit(folder):
    """`git rev-parse HEAD` of the checkout at `folder`, with "-dirty" if it has changes or untracked
    files; None if `folder` is not the top of a git checkout (an installed copy inside another
    project's repository must not report that project's commit) or git is missing or fails."""
    def git(*args):
        return subprocess.run(["git", "-C", str(folder), *args], capture_output=True, text=True, check=True,
                              timeout=30).stdout.strip()
    try:
        if Path(git("rev-parse", "--show-toplevel")).resolve() != folder.resolve():
            return None
        return git("rev-parse", "HEAD") + ("-dirty" if git("status", "--porcelain") else "")
    except (OSError, subprocess.SubprocessError):  # no git, not a checkout, no commit yet, a hung git
        return None


def failing(results):
    """(case name, row) of every row that counts as a failure, in the order they ran."""
    return [(result.name, r) for result in results for r in result.rows if not r.status.ok]


def describe(row):
    """A failing row in one line: what it compares, its status and why, and its finding if it has one."""
    return (f"{row.check} {row.quantity} ({row.comparison}): {row.status}: {reason(row)}"
            + (f" [finding {row.finding}]" if row.finding else ""))


def recap(results, seconds, quick=False):
    """The lines that close a run: every failing row, then one summary line, e.g. `dyncheck: FAIL: 2 of 6
    cases; 351 pass, 40 findings, 3 fail, 1 unstable, 25 not applicable (71 s)`; `quick`: `run --quick`'s,
    `dyncheck: PASS (quick tier): ...`."""
    rows = failing(results)
    lines = [f"failing rows ({len(rows)}):"] + [f"  {name}: {describe(r)}" for name, r in rows] if rows else []
    lines += [line for result in results for line in wrong_equations(result)]
    failed_cases = len({name for name, _ in rows})
    cases = plural(len(results), "case")
    verdict = (f"FAIL{' (quick tier)' * quick}: {failed_cases} of {cases}" if rows
               else f"PASS{' (quick tier)' * quick}: {cases}")
    return lines + [f"dyncheck: {verdict}; {tally([r for result in results for r in result.rows])} ({seconds:.0f} s)"]


def states_covered(result):
    """Where a case's pointwise checks looked, in one line: its random states and the box they span (t, each
    coordinate and rate), its parameter sets' states (their own, over the same box)."""
    spec, sample = result.spec, result.spec["sample"]
    params = {**{name: float(p["value"]) for name, p in spec["params"].items()}, **result.overrides}
    names = expressions.of_parameters(params)
    value = lambda x: float(expressions.evaluate(x, names)) if isinstance(x, str) else float(x)
    spans = [("t", sample["t"], "s")] + list(zip(spec["coords"], sample["q"], spec["coord_units"])) + \
        [(f"{c}'", span, f"{unit}/s") for c, span, unit in zip(spec["coords"], sample["v"], spec["coord_units"])]
    sets = sample.get("params")
    count = len(result.sample["states"]) if result.sample else sample["count"]  # [sample] budget may give more
    return (f"{result.name}: {plural(count, 'random state')} over "
            + ", ".join(f"{name} [{value(lo):.3g}, {value(hi):.3g}] {unit}" for name, (lo, hi), unit in spans)
            + (f"; {plural(sets['sets'], 'random parameter set')}, {sets['states']} states of its own each"
               if sets else ""))


def wrong_equations(result):
    """Where a case's derivation is wrong (dyncheck.checks.residuals): each failing equation (or reaction) with the
    terms that explain it, then how many other failing rows follow from the equations."""
    if not result.localisations:
        return []
    follow = consequences(result)
    return [f"{result.name}: where the derivation is wrong:"] + [f"  {loc}" for loc in result.localisations] + (
        [f"  {len(follow)} other failing rows compare quantities computed from these equations: consequences, "
         "not further errors"] if follow else [])


def tally(rows):
    """How many rows have each status, in words: "58 pass, 16 findings" (statuses with no row left out)."""
    return statuses_in_words(status_counts(rows))


def github_annotations(results):
    """One `::error` workflow command per failing row, which GitHub Actions shows on the run's page."""
    return [f"::error title={escape(f'dyncheck {name}', property=True)}::{escape(describe(r))}"
            for name, r in failing(results)]


def escape(text, property=False):
    """GitHub's escaping of a workflow command's message (%, CR, LF) and of its properties (also : and ,)."""
    text = text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")
    return text.replace(":", "%3A").replace(",", "%2C") if property else text


def junit_xml(results):
    """The results as JUnit XML: a <testsuite> per case, a <testcase> per row.  A failing row has a
    <failure> (its reason as message, its status as type), a row whose run spent its budget an <error> (the
    test could not be made, which is no failure of the derivation), a row not applicable is <skipped>, a
    finding names its id in a property; every testcase carries the row's status in a property (a finding or
    a runaway passes) and its detail in <system-out>."""
    suites = ET.Element("testsuites", name="dyncheck")
    for result in results:
        counts = status_counts(result.rows)
        suite = ET.SubElement(suites, "testsuite", name=result.name, tests=str(len(result.rows)),
                              failures=str(sum(not r.status.ok for r in result.rows) - counts[str(Status.SPENT)]),
                              errors=str(counts[str(Status.SPENT)]),
                              skipped=str(counts[str(Status.NOT_APPLICABLE)]), time=f"{result.wall:.3f}")
        for r in result.rows:
            case = ET.SubElement(suite, "testcase", classname=result.name,
                                 name=f"{r.check} {r.quantity} {r.comparison}")
            properties = ET.SubElement(case, "properties")  # what a passed testcase cannot say otherwise
            ET.SubElement(properties, "property", name="status", value=str(r.status))
            if r.finding:
                ET.SubElement(properties, "property", name="finding", value=r.finding)
            if not r.status.ok:
                verdict = "error" if r.status == Status.SPENT else "failure"
                ET.SubElement(case, verdict, message=reason(r), type=str(r.status)).text = describe(r)
            elif r.status == Status.NOT_APPLICABLE:
                ET.SubElement(case, "skipped", message=r.detail)
            ET.SubElement(case, "system-out").text = r.detail
    for key in ("tests", "failures", "errors", "skipped"):
        suites.set(key, str(sum(int(suite.get(key)) for suite in suites)))
    ET.indent(suites)
    return ET.tostring(suites, encoding="unicode", xml_declaration=True) + "\n"
