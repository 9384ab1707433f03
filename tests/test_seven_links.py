"""A 7-link chain given as generated inverse dynamics (tests/chain.py INVERSE: a recursive Newton-Euler pass,
tau(t, q, q', q'')), from two files: every row of its whole run passes, the scene figure's skeleton holds every mass,
and an error planted in one joint's moment is named by that equation and its term.  Measured (2 cores, idle):
`dyncheck run` 41 s at a peak of 436 MB over its processes; `dyncheck report` of it and its planted twin 2:02, 852 MB
(docs/speed.md)."""

import pytest

import chain
from dyncheck.case.folder import Case
from dyncheck.checks.runs import run_case
from dyncheck.results.values import Status
from test_bounded_localisation import PLANTED, equations


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_seven_link_chain_as_inverse_dynamics_passes(tmp_path):
    result = run_case(Case(chain.write(tmp_path / "inverse7", 7, inverse=True)), localise=False)
    failing = [(r.check, r.quantity, r.sources, r.detail) for r in result.rows
               if r.status not in (Status.PASS, Status.NOT_APPLICABLE)]
    assert not failing, failing
    assert {r.quantity for r in result.rows if r.status == Status.NOT_APPLICABLE} == {"energy", "energy drift"}
    assert result.drawings["animation"]["exact"].dots.shape[1] == 7  # each mass a dot of the scene figure


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_its_planted_error_is_named_by_equation_and_term(tmp_path):
    rows, localisations, _ = equations(Case(chain.write(tmp_path / "planted7", 7, PLANTED, inverse=True)))
    failing = {(r.quantity, r.sources[0]) for r in rows if r.status == Status.FAIL}
    assert failing == {("theta3 residual", "reference"), ("f[theta3]", "reference")}, failing
    assert [(loc.equation, loc.exact) for loc in localisations] == [("theta3", True)], localisations
    assert "- m3 g / 2 sin(theta3)" in localisations[0].text, localisations[0].text
