"""What a CI system relies on (docs/results.md): the `run --json` file against its JSON Schema, the JUnit
XML, GitHub's annotations, the closing recap and summary line, and the checkout's commit."""

import json
import re
import subprocess
from dataclasses import replace
from pathlib import Path

import jsonschema
import junitparser
import pytest

from dyncheck import cli
from dyncheck.results import ci
from dyncheck.results.values import CaseResult, Failure, Status, case_json, no_number, row, to_json

SCHEMA = json.loads((Path(__file__).resolve().parent.parent / "docs" / "results.schema.json").read_text())


def validate(document):
    jsonschema.Draft202012Validator(SCHEMA, format_checker=jsonschema.FormatChecker()).validate(document)


def toy(name="toy", overrides=None, failing=True):
    """A small CaseResult with a row of every status (only passing ones if not `failing`)."""
    passing = row("pointwise", "F1", ("reference", "mujoco"), 1e-15, 1e-9, "100 random states", ceiling=1e-6)
    rows = [passing,
            replace(row("pointwise", "F2", ("reference", "book"), 0.1, 1e-9, ceiling=1e-6),
                    status=Status.FINDING, finding="0.1-typo"),
            replace(row("figure", "x, range", ("program run", "book figure"), 0.0, 0.0, ceiling=0.0),
                    status=Status.NOT_APPLICABLE, detail="the book printed this for its own parameters")]
    if failing:
        blew_up = Failure("RK4 dt=0.01", 0.43, 43, "a non-finite state")
        rows += [row("trajectory", "l", ("mujoco", "tight reference"), 2e-3, 1e-5, "RK4, max over 3 s", ceiling=1e-3),
                 row("energy", "energy drift", ("book",), 1e-4, 2e-2, ceiling=1e-3),
                 no_number("trajectory", "psi", ("book", "tight reference"), blew_up),
                 replace(passing, quantity="F3", status=Status.FAIL, finding="0.1-gone",
                         detail="registered finding 0.1-gone no longer reproduces; 100 random states")]
    spec = {"name": name, "section": "0.1", "title": "a toy", "params": {"k": {"value": 2.0}, "m": {"value": 1.0}},
            "coords": [], "coord_units": [], "sample": {"count": 3, "seed": 0, "t": [0.0, 1.0], "q": [], "v": []}}
    return CaseResult(folder="/nowhere", spec=spec, overrides=overrides or {}, rows=tuple(rows), findings=(),
                      sample={}, runs={}, program={}, drawings={}, wall=1.5)


def test_the_schema_is_a_valid_draft_2020_12_schema_of_every_status():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    assert SCHEMA["$defs"]["status"]["enum"] == [str(s) for s in Status], "docs/results.schema.json: statuses"
    assert SCHEMA["properties"]["version"]["const"] == to_json([])["version"]


def test_a_failing_overridden_run_fits_the_schema_and_says_why_each_row_fails():
    document = to_json([toy(overrides={"k": 5.0}), toy("calm", failing=False)], ci.tool_versions())
    validate(document)
    assert document["status"] == "fail" and document["counts"]["fail"] == 2
    failing_case, passing_case = document["cases"]
    assert (failing_case["status"], passing_case["status"]) == ("fail", "pass")
    assert failing_case["params"] == {"k": 5.0, "m": 1.0} and failing_case["overrides"] == {"k": 5.0}
    reasons = {r["quantity"]: r["reason"] for r in failing_case["checks"]}
    assert reasons["F1"] is None and reasons["F2"] is None and reasons["x, range"] is None
    assert reasons["l"] == "error 2.00e-03 > tolerance 1.00e-05"
    assert reasons["energy drift"] == "tolerance 2.00e-02 is above the ceiling 1e-03 of this comparison"
    assert reasons["psi"] == "RK4 dt=0.01 unstable at t = 0.43 s (step 43): a non-finite state"
    assert reasons["F3"] == "registered finding 0.1-gone no longer reproduces: error 1.00e-15 <= tolerance 1.00e-09"


def test_an_interrupted_run_does_not_pass():
    document = to_json([toy(failing=False)], ci.tool_versions(), interrupted="next")
    validate(document)
    assert document["status"] == "fail" and document["incomplete"] == "interrupted (Ctrl-C) during case next"


def test_the_tool_block_is_only_at_the_top_level():
    """The report's committed data/<case>.json come from case_json: a new commit alone must not change them."""
    assert "tool" not in json.dumps(case_json(toy())) and "commit" not in case_json(toy())


@pytest.mark.full
def test_a_real_run_writes_json_of_the_schema_and_junit_of_its_rows(tmp_path, capsys):
    json_path, junit_path = tmp_path / "piston.json", tmp_path / "piston.xml"
    assert cli.main(["run", "piston", "--json", str(json_path), "--junit", str(junit_path)]) == 0
    last = capsys.readouterr().out.splitlines()[-1]
    assert re.fullmatch(r"dyncheck: PASS: 1 case; \d+ pass, \d+ findings \(\d+ s\)", last), last
    document = json.loads(json_path.read_text())
    validate(document)
    assert re.fullmatch(r"[0-9a-f]{40}(-dirty)?", document["tool"]["commit"])  # the tests run in the checkout
    rows = document["cases"][0]["checks"]
    suite, = junitparser.JUnitXml.fromfile(str(junit_path))
    assert (suite.name, suite.tests, suite.failures, suite.errors, suite.skipped) == ("piston", len(rows), 0, 0, 0)
    cases = list(suite)
    assert [c.name for c in cases] == [f"{r['check']} {r['quantity']} {' vs '.join(r['sources'])}" for r in rows]
    assert all(c.is_passed and c.classname == "piston" for c in cases)
    assert [properties(c)["status"] for c in cases] == [r["status"] for r in rows]
    assert [properties(c).get("finding") for c in cases] == [r["finding"] for r in rows]


def properties(testcase):
    return {p.name: p.value for group in testcase.iterchildren(junitparser.Properties) for p in group}


def canned(monkeypatch, **results):
    """`dyncheck run CASE ...` answering each case with results[CASE], without running anything (by name: the
    cases run in parallel processes)."""
    monkeypatch.setattr(cli, "run_case", lambda case, localise=True, quick=False: results[case.name])


def test_junit_has_a_failure_per_failing_row_and_skips_the_not_applicable(monkeypatch, tmp_path):
    canned(monkeypatch, piston=toy())
    path = tmp_path / "out.xml"
    assert cli.main(["run", "piston", "--junit", str(path)]) == 1
    suite, = junitparser.JUnitXml.fromfile(str(path))
    assert (suite.tests, suite.failures, suite.errors, suite.skipped) == (7, 4, 0, 1)
    by_name = {c.name: c for c in suite}
    failure, = by_name["trajectory l mujoco vs tight reference"].result
    assert (failure.type, failure.message) == ("fail", "error 2.00e-03 > tolerance 1.00e-05")
    unstable, = by_name["trajectory psi book vs tight reference"].result
    assert unstable.type == "unstable" and "at t = 0.43 s (step 43)" in unstable.message
    skipped, = by_name["figure x, range program run vs book figure"].result
    assert isinstance(skipped, junitparser.Skipped)
    assert by_name["pointwise F2 reference vs book"].is_passed


@pytest.mark.parametrize("where, why", [
    ("{tmp}", "is not a regular file"),
    ("{tmp}/a_file/x.xml", "a_file is a file, not a folder"),
    ("/proc/x.xml", "cannot write in /proc"),
])
def test_a_junit_path_that_cannot_be_written_exits_2_before_any_work(where, why, monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(cli, "run_case", lambda case, localise=True, quick=False: pytest.fail("ran a case before checking --junit"))
    (tmp_path / "a_file").write_text("")
    path = where.format(tmp=tmp_path)
    for command in ("run", "report"):
        assert cli.main([command, "piston", "--junit", path]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"dyncheck: error: --junit {path}: ") and why in err, err


def test_a_run_ends_with_its_failing_rows_and_one_summary_line(monkeypatch, capsys):
    canned(monkeypatch, piston=toy(), double_pendulum=toy("calm", failing=False))
    monkeypatch.delenv("GITHUB_ACTIONS", raising=False)
    assert cli.main(["run", "piston", "double_pendulum"]) == 1
    out = capsys.readouterr().out.splitlines()
    assert "toy: FAIL: 1 pass, 1 finding, 2 fail, 1 inconclusive, 1 unstable, 1 not applicable (1.5 s)" in out
    assert "::error" not in "\n".join(out)
    recap = out[out.index("failing rows (4):"):]
    assert recap[1:5] == [
        "  toy: trajectory l (mujoco vs tight reference): fail: error 2.00e-03 > tolerance 1.00e-05",
        "  toy: energy energy drift (book): inconclusive: tolerance 2.00e-02 is above the ceiling 1e-03 of this comparison",
        "  toy: trajectory psi (book vs tight reference): unstable: RK4 dt=0.01 unstable at t = 0.43 s (step 43): "
        "a non-finite state",
        "  toy: pointwise F3 (reference vs mujoco): fail: registered finding 0.1-gone no longer reproduces: "
        "error 1.00e-15 <= tolerance 1.00e-09 [finding 0.1-gone]"]
    assert re.fullmatch(r"dyncheck: FAIL: 1 of 2 cases; 2 pass, 2 findings, 2 fail, 1 inconclusive, 1 unstable, "
                        r"2 not applicable \(\d+ s\)", recap[5]) and len(recap) == 6


def test_on_github_actions_each_failing_row_is_an_error_annotation(monkeypatch, capsys):
    canned(monkeypatch, piston=toy("a:b,c"))
    monkeypatch.setenv("GITHUB_ACTIONS", "true")
    assert cli.main(["run", "piston"]) == 1
    annotations = [line for line in capsys.readouterr().out.splitlines() if line.startswith("::")]
    assert len(annotations) == 4
    assert annotations[0] == ("::error title=dyncheck a%3Ab%2Cc::trajectory l (mujoco vs tight reference): fail: "
                              "error 2.00e-03 > tolerance 1.00e-05")


def test_annotations_escape_what_github_reads_as_syntax():
    assert ci.escape("50% off\r\nnext: a, b") == "50%25 off%0D%0Anext: a, b"
    assert ci.escape("dyncheck a:b,c%", property=True) == "dyncheck a%3Ab%2Cc%25"


def git(folder, *args):
    subprocess.run(["git", "-C", str(folder), *args], check=True, capture_output=True)


def test_the_commit_is_the_checkout_s_head_and_says_when_it_is_dirty(tmp_path, monkeypatch):
    assert ci.commit(tmp_path) is None  # not a checkout
    git(tmp_path, "init", "-q")
    assert ci.commit(tmp_path) is None  # no commit yet
    (tmp_path / "a.txt").write_text("a")
    git(tmp_path, "add", "a.txt")
    git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "a")
    head = subprocess.run(["git", "-C", str(tmp_path), "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    assert ci.commit(tmp_path) == head
    (tmp_path / "untracked.txt").write_text("b")
    assert ci.commit(tmp_path) == head + "-dirty"
    (tmp_path / "inner").mkdir()
    assert ci.commit(tmp_path / "inner") is None  # an installed copy inside another project's checkout
    monkeypatch.setenv("PATH", str(tmp_path / "no-git-here"))
    assert ci.commit(tmp_path) is None  # git missing
