"""Localisation is bounded in memory and time at any number of coordinates, and never loses a case's rows: the term
library is counted before it is built, narrowed or not searched where it would not fit (dyncheck.checks.terms.MEMORY,
WORK), and a search that fails is a localisation that says so."""

import tracemalloc

import numpy as np
import pytest

import chain
from dyncheck.case.folder import Case
from dyncheck.checks import pointwise
from dyncheck.checks import runs as checks, residuals, terms
from dyncheck.results.values import Status
from test_planted_errors import tutorial_subject

# The planted error: half the middle mass's weight moment about its own joint, in that joint's equation only.
PLANTED = '0.5 * p["m3"] * p["g"] * np.sin(q[2]) * (np.arange(len(q)) == 2)'


@pytest.mark.parametrize("coords, units, driven", [
    (["x"], ["m"], ()), (["x", "theta"], ["m", "rad"], ()), (["a", "b", "c"], ["rad"] * 3, ()),
    (["a", "b"], ["rad", "m"], (("alpha", "rad"), ("(F0 * cos(Omega * t))", terms.FORCE)))])
def test_the_library_is_counted_before_it_is_built(coords, units, driven):
    for products in (2, 1):
        assert terms.library_size(coords, units, driven, products) == len(terms.library(coords, units, driven, products))


def test_the_full_library_grows_as_n_to_the_sixth():
    sizes = [terms.library_size([f"a{k}" for k in range(n)], ["rad"] * n) for n in (3, 5, 7)]
    assert sizes == [1810, 27321, 176436]
    assert terms.within_budget(1810, 9) and not terms.within_budget(27321, 9)


def equations(case):
    """The equation rows and localisations of a case as `dyncheck run` makes them, with the peak of the memory the
    localisation takes (tracemalloc: numpy's arrays are counted)."""
    _, sample = pointwise.pointwise(case)
    rows, found = residuals.equation_rows(case, sample)
    drawn = pointwise.parameter_sets(case)[0]
    tracemalloc.start()
    try:
        localisations = residuals.localise(case, rows, found, drawn)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return rows, localisations, peak


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
@pytest.mark.parametrize("n, searched", [(5, "candidates of one position factor each"), (7, "not searched")])
def test_a_chain_s_wrong_equation_is_named_within_the_budget(tmp_path, monkeypatch, n, searched):
    """An n-link pendulum: its derivation passes; with one planted error in the third joint's equation the rows
    fail, and that equation, no other, is named, by its term where the narrowed library fits (5 links: 1,071
    candidates) and as where the search would not fit (7: even the narrowed 3,564 candidates are 1.5 GB over 9
    sets).  Measured: 91 MB at 5 links, under 1 MB at 7; before, MemoryError (232 GiB) at 5 and every row lost.
    Every angle a candidate, as where the residual depends on them all (this one depends on theta3 alone, and
    left as it is the search leaves the others out: test_a_residual_in_one_angle_is_named_in_a_long_chain)."""
    monkeypatch.setattr(residuals, "cyclic_angles", lambda case, r, shifted, place: ())
    right, _, _ = equations(Case(chain.write(tmp_path / "right" / f"chain{n}", n)))
    assert right and all(r.status == Status.PASS for r in right), [str(r) for r in right if r.status != Status.PASS]
    rows, localisations, peak = equations(Case(chain.write(tmp_path / "planted" / f"chain{n}", n, PLANTED)))
    failing = {(r.quantity, r.sources[0]) for r in rows if r.status == Status.FAIL}
    assert failing == {("theta3 residual", "reference"), ("f[theta3]", "reference")}, failing
    assert [(loc.equation, loc.place) for loc in localisations] == [("theta3", "equation theta3")]
    assert searched in localisations[0].text
    if n == 5:
        assert localisations[0].exact and "- m3 g / 2 sin(theta3)" in localisations[0].text, localisations[0].text
    assert peak < terms.MEMORY / 4, f"{peak / 1e6:.0f} MB"


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_residual_in_one_angle_is_named_in_a_long_chain(tmp_path):
    """The planted term depends on theta3 alone: the six other angles are left out of the candidates
    (residuals.cyclic_angles), the library is small enough to search whole, and the term is named exactly."""
    _, localisations, _ = equations(Case(chain.write(tmp_path / "planted" / "chain7", 7, PLANTED)))
    assert [(loc.equation, loc.exact, loc.identified) for loc in localisations] == [("theta3", True, True)]
    assert "- m3 g / 2 sin(theta3)" in localisations[0].text, localisations[0].text


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_search_that_fails_keeps_the_rows_and_says_where(tmp_path, monkeypatch):
    """Whatever the term search raises, the case's rows stay and each failing equation is named with the error."""
    subject = tutorial_subject(tmp_path)
    equations_file = subject.folder / "equations.py"
    equations_file.write_text(equations_file.read_text().replace(
        "m * l * np.sin(theta) * theta_rate**2 - k * x", "-k * x"))

    def exhausted(*args, **kwargs):
        raise MemoryError("Unable to allocate 232. GiB for an array")

    monkeypatch.setattr(terms, "fit", exhausted)
    result = checks.run_case(Case(subject.folder), localise=False)
    assert any(r.check == residuals.CHECK and r.status == Status.FAIL for r in result.rows)
    assert [loc.place for loc in result.localisations] == ["equation x"]
    assert "not localised: the term search failed (MemoryError: Unable to allocate 232. GiB" in \
        result.localisations[0].text
    assert np.isfinite(result.localisations[0].residual)
