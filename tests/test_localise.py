"""The search for the edit that explains a finding."""

import numpy as np
import pytest

from dyncheck.checks.localise import edits, localise

RNG = np.random.default_rng(7)
NAMESPACES = [{"x": x, "y": y, "sin": np.sin, "cos": np.cos} for x, y in RNG.uniform(-3, 3, (50, 2))]
RIGHT = "2*sin(x) + x*y*cos(y) - 3*y"
TARGET = np.array([eval(RIGHT, {"__builtins__": {}}, names) for names in NAMESPACES])
TOL = 1e-12  # the edited expression is the right one up to rounding of a few operations


@pytest.mark.parametrize("printed, edit", [
    ("2*sin(x) - x*y*cos(y) - 3*y", "sign of `x * y * cos(y)`"),
    ("2*sin(x) + x*y*cos(y) - 6*y", "`6 * y` / 2"),
    ("2*cos(x) + x*y*cos(y) - 3*y", "swap sin/cos in `cos(x)` in `2 * cos(x)`"),
    ("2*sin(x) + x*y*cos(y) - 3*y + y**2", "drop `y ** 2`"),
    ("(2*sin(x) + x*y)*cos(y) - 3*y", "close the bracket before `cos(y)` so that it leaves out `2 * sin(x)`"),
])
def test_a_single_slip_is_found(printed, edit):
    found, tried, error = localise(printed, NAMESPACES, TARGET, TOL)
    assert error > 1e-3 and tried == len(edits(printed))
    assert edit in [label for label, *_ in found]


def test_two_slips_are_found_as_a_pair():
    found, _, _ = localise("2*sin(x) - x*y*cos(y) - 6*y", NAMESPACES, TARGET, TOL)
    assert any("sign of `x * y * cos(y)`" in label and "`6 * y` / 2" in label for label, *_ in found)


def test_an_unrelated_expression_is_reported_unexplained():
    found, tried, error = localise("x**3 + y", NAMESPACES, TARGET, TOL)
    assert found == [] and tried > len(edits("x**3 + y")) and error > 0.1


def test_the_books_errors_are_localised(results):
    localised = {f.id: f.localised for res in results.values() for f in res.findings}
    assert localised["1.8.3-R"].startswith("R: `L * psi_rate * Omega * cos(psi)` x 2")
    assert "close the bracket before `sin(psi)` so that it leaves out `g * cos(psi)`" in localised["1.8.3-listing-ldd"]
    assert "swap sin/cos in `sin(th)` in `2 * Ld * w * sin(th)`" in localised["1.7-eq1.24"]
    assert "swap the factors of `TxT(n) @ TzT(p)`, and `ds` = 0 everywhere" in localised["1.10-R"]
    assert "none of the" in localised["1.8.3-listing-R"]  # three slips: beyond the pair search


@pytest.mark.full
def test_a_plain_run_leaves_the_search_out_and_says_so():
    """The search costs seconds per finding; a run that writes nothing of it skips it, and says so."""
    import dyncheck
    from dyncheck.checks.runs import run_case
    result = run_case(dyncheck.load_case("piston"), localise=False)
    assert result.findings and all(f.localised.startswith("not searched in this run") for f in result.findings)

