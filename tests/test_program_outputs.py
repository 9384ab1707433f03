"""What the book's programs write out against MuJoCo at the same states (dyncheck.checks.runs.program_output_checks)."""

import copy

import pytest

import dyncheck
from dyncheck.case.folder import Case
from dyncheck.checks.programs import program_output_checks
from dyncheck.checks.runs import apply_findings
from dyncheck.results.values import Status

CASES = ("double_pendulum", "spinning_top", "spring_pendulum")


def output_rows(case):
    q0, v0, _ = case.initial
    return program_output_checks(case, case.model("program").run(q0, v0))


@pytest.mark.parametrize("name", CASES)
def test_every_written_column_passes_or_is_a_finding(name):
    case = dyncheck.load_case(name)
    rows = apply_findings(case, output_rows(case))
    assert [r.quantity for r in rows] == list(case.spec["program"]["outputs"])
    assert all(r.sources == ("program", "mujoco at the program's states") for r in rows)
    assert all(r.status in (Status.PASS, Status.FINDING) for r in rows), [(r.quantity, r.status, r.detail) for r in rows]


def test_the_listing_reaction_is_its_finding():
    case = dyncheck.load_case("spring_pendulum")
    by_quantity = {r.quantity: r for r in apply_findings(case, output_rows(case))}
    assert by_quantity["R"].finding == "1.8.3-listing-R"
    assert by_quantity["x"].status == Status.PASS


@pytest.mark.parametrize("name, column, wrong", [("double_pendulum", "h1x", "link1_x"),
                                                  ("spinning_top", "hy", "-top_y"),
                                                  ("spring_pendulum", "z", "-particle_z")])
def test_a_wrong_sign_fails_its_row(name, column, wrong):
    right = dyncheck.load_case(name)
    spec = copy.deepcopy(right.spec)
    spec["program"]["outputs"][column] = wrong
    rows = {r.quantity: r for r in output_rows(Case(right.folder, spec=spec))}
    assert rows[column].status == Status.FAIL and rows[column].error > 0.1
    assert all(r.status == Status.PASS for q, r in rows.items() if q not in (column, "R"))


def test_an_unknown_name_is_refused_on_load():
    right = dyncheck.load_case("double_pendulum")
    spec = copy.deepcopy(right.spec)
    spec["program"]["outputs"]["h1x"] = "-lnik1_x"
    with pytest.raises(ValueError, match=r"program\.outputs\.h1x.*-lnik1_x.*lnik1_x"):
        Case(right.folder, spec=spec)


def test_a_column_the_program_does_not_write_fails_its_row():
    right = dyncheck.load_case("spinning_top")
    spec = copy.deepcopy(right.spec)
    spec["program"]["outputs"]["hw"] = "top_z"
    rows = {r.quantity: r for r in output_rows(Case(right.folder, spec=spec))}
    assert rows["hw"].status == Status.FAIL and "writes no column 'hw'" in rows["hw"].detail
