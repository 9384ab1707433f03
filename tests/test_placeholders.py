"""MuJoCo's placeholders (a mass or an inertia where the scene means none): measured on load and refused where they
are not negligible at the case's parameters; allowed at a random parameter set where a MuJoCo row fails."""

from dyncheck import cli
from dyncheck.case.folder import load_case
from dyncheck.checks import pointwise
from dyncheck.results.values import Status


def test_bodies_a_thousandth_of_the_book_s_are_refused_naming_file_override_bodies_and_quantity(capsys):
    assert cli.main(["run", "double_pendulum", "--set", "m1=1e-4"]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1
    for named in ("cases/double_pendulum/case.toml: override m1 = 0.0001 kg (book: 0.046): ", "link1 (inertia)",
                  "change its a_A_y by 5.3e-08", "[tolerance.pointwise] value of at least 1.1e-07"):
        assert named in error


def test_the_share_is_measured_against_the_case_s_own_tolerance():
    """The refusal follows the case file's pointwise tolerance, as its message says: at m1 = 1e-4 kg (5.3e-8) a
    tolerance of 1.1e-7 lets the case through, one a little lower does not."""
    for tolerance, refused in ((1.1e-7, False), (1.0e-7, True)):
        case = load_case("double_pendulum", m1=1e-4)
        case.spec["tolerance"]["pointwise"]["value"] = tolerance
        try:
            pointwise.validate_placeholders(case)
        except ValueError:
            assert refused
        else:
            assert not refused


def test_a_random_set_s_failing_mujoco_row_is_judged_with_that_set_s_placeholders_allowed(monkeypatch):
    """The rotating pendulum's m = 8e-4 kg passes the load's measure (4.7e-10), but at some random sets the
    placeholders change MuJoCo's drive power by more than the tolerance: the rows pass with each set's effect
    allowed, and fail where a smaller effect is measured.  (The effect is the largest over a set's states, allowed
    against the largest error over them: a derivation's error there still shows against Pinocchio.)"""
    case = load_case("rotating_pendulum", m=8e-4)
    pointwise.validate_placeholders(case)
    rows = pointwise.random_parameters(case)
    assert rows and all(r.status == Status.PASS for r in rows)
    assert all(r.tolerance == case.tolerance["pointwise"]["value"] for r in rows if "mujoco" not in r.sources)
    monkeypatch.setattr(pointwise, "placeholders_effect", lambda *args: dict.fromkeys(("drive_power", "energy"), 1e-12))
    failing = [r for r in pointwise.random_parameters(case) if r.status == Status.FAIL]
    assert failing and all("mujoco" in r.sources and "placeholders' effect there 1e-12 allowed" in r.detail
                           for r in failing)
