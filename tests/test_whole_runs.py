"""Whole runs off the book's numbers (issue 12): for every case, random physically valid overrides, drawn
from the domain its case file states ([sample.params.ranges], within the schema's bounds and
[[constraints]]), must give a run that exits 0 wherever reference, MuJoCo and Pinocchio agree: every row
of run_case passes, is a registered finding, is not applicable or a runaway the case states.

Every check runs, over a shorter horizon (Case.with_horizon) so that a run takes seconds; the tolerances
that depend on it follow from the shorter runs as they do from the book's.  A few examples per case
here; `pytest -m slow` draws many more.  Derandomized: CI draws the same examples every time."""

import math

import pytest
from hypothesis import HealthCheck, Phase, assume, given, settings
from hypothesis import strategies as st

import dyncheck
from dyncheck import cli
from dyncheck.case import schema
from dyncheck.checks.runs import run_case
from dyncheck.run.simulate import fastest_frequency

CASES = dyncheck.case_names()
DEFAULT_EXAMPLES = 2  # per case: 1-5 s each, ~25 s of CPU for the six (the default run may add < 40 s)
SLOW_EXAMPLES = 25


def horizon(case):
    """One period 2 pi / omega of the case's fastest motion, at most the book's run: every error has a
    swing to build up in, beyond the 1/omega the trajectory check needs to compare anything.  A case
    that names no frequency (nothing integrated, only the balance of a prescribed motion) runs a tenth
    of the book's.  A whole number of output steps, as every run's (dyncheck.run.simulate)."""
    t_end, output_step = case.initial[2], case.integration["output_step"]
    omega = fastest_frequency(case)
    wanted = min(t_end, 2 * math.pi / omega) if omega else t_end / 10
    return math.ceil(wanted / output_step) * output_step


def physical(case, drawn):
    """Whether the drawn values satisfy the schema's bounds and the case's [[constraints]]."""
    try:
        schema.check_params(case.spec, {**case.params, **drawn}, drawn, case.file)
    except ValueError:
        return False
    return True


def overrides(case):
    """Every parameter of [sample.params.ranges], uniform over its range, the others at the book's values."""
    ranges = case.spec["sample"]["params"]["ranges"]
    return st.fixed_dictionaries({name: st.floats(case.value(lo), case.value(hi))
                                  for name, (lo, hi) in ranges.items()})


def check_whole_run(name, data):
    book = dyncheck.load_case(name)
    drawn = data.draw(overrides(book), label="overrides")
    assume(physical(book, drawn))
    case = book.with_params(**drawn)
    case = case.with_horizon(horizon(case))
    result = run_case(case, localise=False)
    failing = [r for r in result.rows if not r.status.ok]
    assert not failing, (f"{name} with {drawn} over {case.initial[2]:.3g} s: {len(failing)} rows fail\n"
                         + "\n".join(f"  {r.check} {r.quantity} {' vs '.join(r.sources)}: {r.status}, error "
                                     f"{r.error!r}, tolerance {r.tolerance!r}; {r.detail}" for r in failing))


def examples(n):
    # No shrinking: each example is a run of seconds, and a failing one is reported as drawn.
    return settings(max_examples=n, derandomize=True, deadline=None, phases=[Phase.explicit, Phase.generate],
                    suppress_health_check=[HealthCheck.too_slow])


@pytest.mark.full
@pytest.mark.parametrize("name", CASES)
@examples(DEFAULT_EXAMPLES)
@given(data=st.data())
def test_a_whole_run_with_valid_overrides_exits_0(name, data):
    check_whole_run(name, data)


@pytest.mark.slow
@pytest.mark.parametrize("name", CASES)
@examples(SLOW_EXAMPLES)
@given(data=st.data())
def test_many_whole_runs_with_valid_overrides_exit_0(name, data):
    check_whole_run(name, data)


# A lecturer's --set beyond the ranges that speeds up the fastest motion: MuJoCo's step follows omega
# (the case files' mujoco_step), so that its page is as true as the book's.  At the case file's fixed
# step of 1e-4 s, m2 = 3.7 kg (omega 55 -> 151 rad/s) left four MuJoCo trajectory rows inconclusive: RK4
# off by 1e-3, its tolerance above the ceiling.
FASTER = [("double_pendulum", {"m2": 3.7}, 5.6e-3, 1e-4), ("spring_pendulum", {"k": 3000.0}, 0.0105, 1e-4),
          ("rotating_pendulum", {"beta_rate": -40.0}, 2.6e-3, 2.5e-4)]


@pytest.mark.parametrize("name, override, most, book_step", FASTER)
def test_mujocos_step_follows_the_fastest_motion(name, override, most, book_step):
    assert dyncheck.load_case(name).integration["mujoco_step"] == book_step  # the book's pages unchanged
    case = dyncheck.load_case(name, **override)
    dt, output_step = case.integration["mujoco_step"], case.integration["output_step"]
    assert most / 1.1 < fastest_frequency(case) * dt <= most  # the longest step within the bound ...
    assert abs(output_step / dt - round(output_step / dt)) < 1e-9  # ... whose multiple the outputs are


@pytest.mark.full
def test_a_heavier_second_pendulum_gives_a_passing_page():
    result = run_case(dyncheck.load_case("double_pendulum", m2=3.7), localise=False)
    failing = [f"{r.check} {r.quantity} {' vs '.join(r.sources)}: {r.status}" for r in result.rows if not r.status.ok]
    assert not failing, failing


@pytest.mark.parametrize("name, override", [("double_pendulum", {"m2": 1e4}), ("spring_pendulum", {"k": 1e9}),
                                            ("rotating_pendulum", {"l": 1e-6})])
def test_mujocos_step_stops_following_where_its_twin_would_outrun_a_run(name, override):
    # far beyond the book: the case still loads (its other checks run; MuJoCo's rows say how far off its step is),
    # and the twin at half the step keeps within the steps one run may take
    from dyncheck.common.ceilings import MAX_STEPS
    case = dyncheck.load_case(name, **override)
    assert MAX_STEPS / 2 < 2 * case.initial[2] / case.integration["mujoco_step"] <= MAX_STEPS


@pytest.mark.full
@pytest.mark.parametrize("name, sets", [
    ("rotating_pendulum", ["l=0.5", "g=1", "beta_rate=10"]),  # no mode oscillates: the page drew the shapes of none
    ("spring_pendulum", ["k=100"]),  # the run leaves its bound: the student page's figures along it
])
def test_a_report_off_the_book_is_written(tmp_path, name, sets):
    # each raised a traceback (ZeroDivisionError, ValueError)
    args = ["report", name, "--no-studies", "--no-animations", "--out", str(tmp_path)]
    assert cli.main(args + [part for s in sets for part in ("--set", s)]) == 0
    assert (tmp_path / f"{name}.md").is_file() and (tmp_path / f"{name}_student.md").is_file()

