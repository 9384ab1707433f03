"""The checks of both cases, the strict findings, and unstable integrations."""

import numpy as np
import pytest

import dyncheck
from dyncheck.checks.pointwise import pointwise
from dyncheck.checks.runs import apply_findings
from dyncheck.run.simulate import Unstable, simulate
from reference import spring_pendulum


def test_every_check_passes_or_is_a_registered_finding(results):
    for name, res in results.items():
        bad = [r for r in res.rows if r.status not in ("pass", "finding")]
        assert not bad, bad


def test_engines_and_reference_agree_pointwise_to_1e9(results):
    for res in results.values():
        rows = [r for r in res.rows if r.check == "pointwise" and "book" not in r.sources]
        assert rows and all(r.error <= 1e-9 for r in rows)


def test_the_books_reaction_is_a_finding_of_the_size_of_the_missing_term(results):
    rows = [r for r in results["spring_pendulum"].rows if r.finding == "1.8.3-R"]
    assert {r.quantity for r in rows} == {"R", "a_E_x", "drive_power", "work-energy balance", "Newton X3 (1.8.3)"}
    assert all(r.status == "finding" for r in rows)
    # The missing term m L psi' Omega cos(psi) is a large part of R over the random states.
    assert all(r.error > 0.1 for r in rows if r.quantity == "R")


def test_a_finding_that_stops_reproducing_fails(monkeypatch):
    """Strict findings: correct the book's term and its registered finding must turn into a failure
    (at the book's own parameters; with overrides the row passes with a note)."""
    fixed = {k: v.replace("L*psi_rate*Omega*cos(psi)", "2*L*psi_rate*Omega*cos(psi)")
             for k, v in spring_pendulum.Book.PRINTED.items()}
    monkeypatch.setattr(spring_pendulum.Book, "PRINTED", fixed)
    case = dyncheck.load_case("spring_pendulum")
    rows, _ = pointwise(case)
    rows = apply_findings(case, rows)
    stale = [r for r in rows if r.finding == "1.8.3-R"]
    assert stale and all(r.status == "fail" and "no longer reproduces" in r.detail for r in stale)


def test_every_source_gives_the_same_trajectory_and_mujoco_holds_the_drive(results):
    res = results["spring_pendulum"]
    driven = [r for r in res.rows if r.quantity == "driven rate"]
    assert driven and driven[0].status == "pass"
    tight = res.runs["reference"].twin
    for source in ("book", "pinocchio", "mujoco"):
        run = res.runs[source].run
        assert np.max(np.abs(run["psi"] - tight["psi"])) < 1e-7


def test_a_blown_up_mujoco_run_is_reported_unstable_with_time_and_step():
    """RK4 is unstable for omega dt > 2.8; the spring's omega = 100 rad/s at dt = 0.05 s gives 5."""
    case = dyncheck.load_case("spring_pendulum")
    with pytest.raises(Unstable) as error:
        simulate(case.model("mujoco"), case.initial[:2], 1.0, "mujoco:RK4", dt=0.05, output_step=0.05)
    assert error.value.method == "mujoco:RK4" and 0 < error.value.t <= 1.0 and error.value.step > 0
    assert "MuJoCo warning mjWARN_BADQVEL" in error.value.why and "reset" in error.value.why


def test_unknown_method_is_named():
    case = dyncheck.load_case("double_pendulum")
    with pytest.raises(ValueError, match="unknown method 'Verlet'"):
        simulate(case.model("reference"), case.initial[:2], 1.0, "Verlet", output_step=0.1)


def test_the_programs_are_checked_against_their_own_equations_and_figures(results):
    rows = {(name, r.check, r.quantity, r.comparison): r for name, res in results.items() for r in res.rows}
    same = "program vs book equations, same integrator"
    # The Pascal double pendulum computes with the book's closed forms: its run is the book's, bit for bit.
    assert rows[("double_pendulum", "program", "theta2", same)].error == 0.0
    # The Matlab listing's bracket slip shows in its l'' and, integrated, in its run: a registered finding.
    assert rows[("spring_pendulum", "program", "l_acc", "program vs reference")].status == "finding"
    assert rows[("spring_pendulum", "program", "l", same)].status == "finding"
    # The book's double-pendulum figure holds the listing's run but not the exact motion.
    assert rows[("double_pendulum", "figure", "theta2", "program vs book figure")].status == "pass"
    assert rows[("double_pendulum", "figure", "theta2", "tight reference vs book figure")].status == "finding"


def test_a_case_without_a_program_says_so():
    with pytest.raises(ValueError, match="the book prints no program for 1.8.1"):
        dyncheck.load_case("rotating_pendulum").model("program")


def test_an_override_that_hides_a_finding_passes_with_a_note():
    """Without the spin (Omega = 0) the missing Coriolis term vanishes: the book's R is then right."""
    case = dyncheck.load_case("spring_pendulum", alpha_rate=0.0, beta_rate=0.0)
    rows = apply_findings(case, pointwise(case)[0])
    hidden = [r for r in rows if r.finding == "1.8.3-R" and r.quantity == "R"]
    assert hidden and all(r.status == "pass" and "does not show" in r.detail for r in hidden)


def test_two_runs_give_identical_json(results):
    """Determinism: the same inputs give the same JSON (it holds no timing); seeds are in the case file."""
    import json

    from dyncheck.checks.runs import run_case
    from dyncheck.results.values import to_json
    again = run_case(dyncheck.load_case("double_pendulum"))
    assert json.dumps(to_json([again])) == json.dumps(to_json([results["double_pendulum"]]))


def test_random_parameter_sets_agree_and_say_what_was_tried(results):
    rows = [r for r in results["spring_pendulum"].rows if r.check == "random parameters"]
    assert {r.comparison for r in rows} == {"reference vs mujoco", "reference vs pinocchio", "mujoco vs pinocchio"}
    assert all(r.status == "pass" and "20 parameter sets (seed 31) x 20 states" in r.detail for r in rows)


def test_a_listing_that_blows_up_gives_unstable_rows_not_a_crash():
    """At k = 1e5 N/m the Matlab listing's explicit Euler at 5e-5 s grows by exp(omega^2 dt t / 2): it
    blows up within the run, and its run checks say when and at which step."""
    from dyncheck.checks.programs import program_checks
    case = dyncheck.load_case("spring_pendulum", k=1e5)
    rows, runs = program_checks(case, pointwise(case)[1])
    rows = apply_findings(case, rows)
    unstable = [r for r in rows if r.status == "unstable"]
    assert runs == {} and {r.quantity for r in unstable} == {"psi", "psi_rate", "l", "l_rate"}
    assert all("unstable: state not finite at t = " in r.detail and "(step " in r.detail for r in unstable)
    # its formulas are still checked, with the listing's registered slips
    assert {r.status for r in rows if r not in unstable} == {"pass", "finding"}


@pytest.mark.full
def test_a_scene_at_rest_is_judged_in_si_units_and_an_unmeasurable_order_says_so():
    """Without gravity the double pendulum released from rest stays put: every trajectory and energy
    row passes (errors in SI units, not 0/0), and the convergence order, which has nothing to measure
    (omega = 0, nothing moves), is not applicable and says why rather than a crash or a failure."""
    from dyncheck.checks.runs import run_case
    rows = run_case(dyncheck.load_case("double_pendulum", g=0.0)).rows
    assert {r.status for r in rows} == {"pass", "not applicable"}  # the book's figures are for g = 9.81
    [order] = [r for r in rows if r.check == "convergence"]
    assert order.status == "not applicable" and "omega" in order.detail and "nothing moves" in order.detail


@pytest.mark.full
def test_the_book_s_printed_figures_and_data_do_not_apply_to_other_parameters():
    """`--set k=500` once failed on the axes of the book's figures (drawn for k = 2000): such rows are
    not applicable under overrides, say why, and the physics decides the exit code.  What the run measures
    there, the listing's run against the exact motion, stays a measured row (issue 35): its finding."""
    from dyncheck.checks.runs import run_case
    result = run_case(dyncheck.load_case("spring_pendulum", k=500.0), localise=False)
    book_only = [r for r in result.rows if r.check in ("figure", "data")]
    assert book_only and all(r.status == "not applicable" and "k = 500 N/m (book: 2000)" in r.detail for r in book_only)
    assert result.status == "PASS" and all(r.status in ("pass", "finding") for r in result.rows if r not in book_only)
    listing = [r for r in result.rows if (r.check, r.sources) == ("program", ("program", "tight reference"))]
    assert listing and all(r.status == "finding" and r.finding == "1.8.3-listing-integrator" for r in listing)
    [finding] = [f for f in result.findings if f.id == "1.8.3-listing-integrator"]
    assert finding.error == max(r.error for r in listing)  # measured, not "not measured with these parameters"
