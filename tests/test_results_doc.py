"""docs/results.md describes the JSON that dyncheck writes: every key that `run --json` (to_json) and the
report's data/<case>.json (write_summary) emit is named on it, its version is RESULTS_VERSION, and its
example has the layout of the real output, so that the page cannot drift from the code unnoticed."""

import json
import re
from pathlib import Path

from dyncheck.case.folder import Case
from dyncheck.pages.report import write_summary
from dyncheck.results.ci import tool_versions
from dyncheck.results.values import RESULTS_VERSION, to_json

DOC = Path(__file__).resolve().parent.parent / "docs" / "results.md"
# Objects whose keys are data (parameter names, accuracy levels), not the layout's keys.
KEYED_BY_DATA = {"params", "overrides", "cheapest"}


def keys(value):
    """Every key of every object in a JSON value, except inside the objects keyed by data."""
    if isinstance(value, dict):
        found = set(value)
        for key, item in value.items():
            if key not in KEYED_BY_DATA:
                found |= keys(item)
        return found
    if isinstance(value, list):
        return set().union(*map(keys, value)) if value else set()
    return set()


def summary(result, tmp_path):
    """The report's data/<case>.json of `result`."""
    (tmp_path / "data").mkdir()
    case = Case(result.folder, result.overrides, result.spec)
    return json.loads((tmp_path / write_summary(result, case, tmp_path)).read_text())


def example(text):
    """The page's first JSON example."""
    block = re.search(r"```json\n(.*?)```", text, re.S)
    assert block, f"{DOC}: no ```json example"
    return json.loads(block.group(1))


def test_every_emitted_key_is_documented(results, tmp_path):
    result = results["piston"]  # a case with a registered finding, so that a finding's keys are emitted
    assert result.findings
    interrupted = to_json([], tool_versions(), interrupted="piston")  # `run --json` stopped by Ctrl-C
    emitted = keys(to_json([result], tool_versions())) | keys(interrupted) | keys(summary(result, tmp_path))
    text = DOC.read_text()
    missing = sorted(key for key in emitted if f"`{key}`" not in text)
    assert not missing, f"{DOC}: keys that dyncheck writes but the page does not name (in backquotes): {missing}"


def test_the_documented_version_is_the_current_one():
    text = DOC.read_text()
    stated = re.search(r"The current version is (\d+)\.", text)
    assert stated, f"{DOC}: no sentence 'The current version is N.'"
    assert int(stated.group(1)) == RESULTS_VERSION, f"{DOC} says version {stated.group(1)}, RESULTS_VERSION is {RESULTS_VERSION}"
    assert example(text)["version"] == RESULTS_VERSION


def test_the_example_has_the_layout_of_the_output(results):
    real, shown = to_json([results["piston"]], tool_versions()), example(DOC.read_text())
    assert shown.keys() == real.keys()
    case, shown_case = real["cases"][0], shown["cases"][0]
    assert shown_case.keys() == case.keys()
    assert shown_case["checks"][0].keys() == case["checks"][0].keys()
    assert shown_case["findings"][0].keys() == case["findings"][0].keys()
    assert all(isinstance(row["sources"], list) for row in shown_case["checks"])
