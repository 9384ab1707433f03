"""A correct derivation at degenerate scales of the tutorial's cart-pendulum (docs/own-case.md) passes, or is refused
where MuJoCo's scene cannot model it: no false failure where a force vanishes, a spring is stiff, or a body is a
placeholder's size."""

import pytest

from dyncheck.case.folder import Case
from dyncheck.checks import runs as checks, residuals
from dyncheck.cli import main
from dyncheck.results.values import Status
from test_planted_errors import tutorial_subject


def equation_rows(folder, **overrides):
    case = Case(folder, overrides)
    return [r for r in checks.run_case(case, localise=False).rows if r.check == residuals.CHECK], case


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_without_gravity_the_theta_equation_is_judged_against_its_terms_not_its_vanishing_force(tmp_path):
    """At g = 0 the theta equation's force is 0 at every state (the engines give 3.8e-15 of rounding) while its
    M q'' terms are of the order of 1 N m: against the force its residual was 1.0, against its terms' sizes 7e-14
    (MuJoCo's placeholder inertia times theta'')."""
    rows, case = equation_rows(tutorial_subject(tmp_path).folder, g=0.0)
    assert rows and all(r.status == Status.PASS for r in rows), [str(r) for r in rows if r.status != Status.PASS]
    theta = [r for r in rows if r.quantity == "theta residual"]
    assert theta and all(r.error < 1e-12 for r in theta)


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_without_gravity_a_wrong_term_still_fails(tmp_path):
    """The scale is the terms' sizes, no more: the cart's centrifugal term with its sign flipped fails as before."""
    subject = tutorial_subject(tmp_path)
    equations = subject.folder / "equations.py"
    text = equations.read_text()
    right = "m * l * np.sin(theta) * theta_rate**2 - k * x"
    assert right in text
    equations.write_text(text.replace(right, "-m * l * np.sin(theta) * theta_rate**2 - k * x"))
    rows, _ = equation_rows(subject.folder, g=0.0)
    failing = {r.quantity for r in rows if r.status == Status.FAIL}
    assert "x residual" in failing and "theta residual" not in failing, failing


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_stiff_spring_s_equations_pass(tmp_path):
    """k = 1e9 N/m: the spring's k x (5e7 N) drives x'', whose M q'' terms in the theta row (7.5e6 N m) cancel to
    its 1.5 N m of force; the rounding and MuJoCo's placeholder inertia times theta'' (1e-6 N m) failed four rows
    at 3.3e-6 and 4.4e-9 against that force.  Against the terms' sizes they are 7e-14 and below."""
    rows, _ = equation_rows(tutorial_subject(tmp_path).folder, k=1e9)
    assert rows and all(r.status == Status.PASS for r in rows), [str(r) for r in rows if r.status != Status.PASS]


def test_a_bob_whose_inertia_is_the_placeholder_s_is_refused(tmp_path, capsys):
    """l = 1e-7 m: the bob's m l^2 = 3e-15 kg m^2 is a third of MuJoCo's placeholder inertia, and MuJoCo puts its centre
    of mass at the hinge (its theta'' is 0 with the placeholder and with it doubled: a change of 0 of 0).  The
    placeholder's share of theta's inertia, M[theta,theta], is 1: refused before any work (19 rows failed)."""
    cases = tutorial_subject(tmp_path).folder.parent
    assert main(["run", "--cases", str(cases), "--set", "l=1e-7"]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "override l = 1e-07 m" in error and "bob (inertia)" in error
    assert "change its M[theta,theta] by 1 of its size" in error
