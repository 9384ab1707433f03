"""The book's printed Newton and Euler rows, checked before they are solved (Book.printed_rows)."""

import pytest

import dyncheck
from dyncheck.checks import pointwise
from dyncheck.checks import runs as checks, residuals
from dyncheck.results.values import Status

BOOK_CASES = ("piston", "rotating_pendulum", "rotating_particle", "spring_pendulum", "double_pendulum",
              "spinning_top")


def printed_row_statuses(case):
    """{label: status} of the case's printed rows at its random states, its findings applied."""
    _, sample = pointwise.pointwise(case)
    rows = checks.apply_findings(case, residuals.printed_rows(case, sample))
    return {r.quantity: r.status for r in rows}


@pytest.mark.parametrize("name", BOOK_CASES)
def test_every_printed_row_holds_or_is_a_registered_finding(name):
    case = dyncheck.load_case(name)
    assert hasattr(case.model("book"), "printed_rows")
    statuses = printed_row_statuses(case)
    assert statuses, "no printed row"
    registered = {q for finding in case.findings for q in finding["quantities"]}
    # A registered row that held would have turned into a failure ("no longer reproduces").
    assert {label for label, status in statuses.items() if status == Status.FINDING} == registered & set(statuses)
    assert set(statuses.values()) <= {Status.PASS, Status.FINDING}


@pytest.mark.parametrize("name", BOOK_CASES)
def test_a_flipped_sign_in_one_printed_row_fails_that_row_alone(name, monkeypatch):
    case = dyncheck.load_case(name)
    before = printed_row_statuses(case)
    planted = next(label for label, status in before.items() if status == Status.PASS)
    book = case.model("book")
    as_printed = book.printed_rows

    def with_flipped_sign(t, q, v, acc, reactions):
        rows = dict(as_printed(t, q, v, acc, reactions))
        first, *rest = rows[planted]
        rows[planted] = [-first, *rest]
        return rows

    monkeypatch.setattr(book, "printed_rows", with_flipped_sign)  # this case's Book alone
    after = printed_row_statuses(case)
    assert after[planted] == Status.FAIL
    assert {k: s for k, s in after.items() if k != planted} == {k: s for k, s in before.items() if k != planted}
