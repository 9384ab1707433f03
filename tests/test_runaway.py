"""A physical runaway, reported as such: the spring pendulum below k_crit = m Omega^2 (issue 12)."""

import copy
import json

import pandas as pd
import pytest

import dyncheck
from dyncheck import cli
from dyncheck.case.folder import Case, Runaway
from dyncheck.checks.runs import run_sources, runaway_rows
from dyncheck.results.values import Failure, Outcome, Row, Status
from dyncheck.run.simulate import Escape, Escaped, simulate

K_CRIT = 0.2 * (9 * 3.141592653589793) ** 2  # m Omega^2 at the book's m = 0.2 kg, Omega = pi + 8 pi rad/s: 159.9 N/m


@pytest.mark.full
def test_below_k_crit_every_source_runs_away_and_the_run_passes(tmp_path, capsys):
    path = tmp_path / "run.json"
    assert cli.main(["run", "spring_pendulum", "--set", "k=100", "--json", str(path)]) == 0
    rows = json.loads(path.read_text())["cases"][0]["checks"]
    runaways = [r for r in rows if r["status"] == "runaway"]
    # every run's row: three trajectories of four coordinates, four energy balances
    assert len(runaways) == 16 and {r["check"] for r in runaways} == {"trajectory", "energy"}
    assert not [r for r in rows if r["status"] in ("unstable", "fail")]
    for r in runaways:  # the physical reason with its numbers, and when each source escaped
        assert "m Omega^2 = 159.9 N/m beats the spring k = 100 N/m" in r["detail"]
        assert "escaped at t = 0.35" in r["detail"] and "every source escaped (reference at 0.3518 s" in r["detail"]
    assert "16 runaways" in capsys.readouterr().out


def test_above_k_crit_nothing_is_bounded_and_nothing_runs_away():
    assert dyncheck.load_case("spring_pendulum").runaway() is None  # k = 2000 N/m
    # just above k_crit the equilibrium lies at l* ~ 285 m, beyond the escape bound: bounding it would be wrong
    assert dyncheck.load_case("spring_pendulum", k=160.0).runaway() is None
    assert dyncheck.load_case("spring_pendulum", k=159.8).runaway() is not None


def test_at_the_book_stiffness_the_runs_end_and_no_row_is_runaway(results):
    result = results["spring_pendulum"]  # k = 2000 N/m
    assert all(outcome.ok for outcome in result.runs.values())
    assert not [r for r in result.rows if r.status == Status.RUNAWAY]


def test_each_source_escapes_at_the_same_time():
    case = dyncheck.load_case("spring_pendulum", k=100.0)
    limit = case.runaway()
    assert limit.bound == ("l", 1, 100.0)
    runs = run_sources(case, limit.bound)
    times = {source: outcome.failure.t for source, outcome in runs.items()}
    assert all(isinstance(outcome.failure, Escape) for outcome in runs.values())
    # DOP853's escape is found on its dense output: the three DOP853 sources agree far below their steps
    assert max(times[s] for s in ("book", "pinocchio")) - min(times[s] for s in ("book", "pinocchio")) < 1e-9
    assert abs(times["book"] - times["reference"]) < 1e-9
    assert abs(times["mujoco"] - times["reference"]) <= 2 * case.integration["mujoco_step"]  # its first step beyond


def test_a_fixed_step_run_escapes_at_its_first_step_beyond():
    case = dyncheck.load_case("spring_pendulum", k=100.0)
    q0, v0, _ = case.initial
    with pytest.raises(Escaped, match=r"\|l\| = 100\.\d+ beyond 100") as escaped:
        simulate(case.model("book"), (q0, v0), 1.0, "RK4", dt=1e-4, output_step=1e-3, work=False,
                 bound=("l", 1, 100.0))
    assert isinstance(escaped.value.failure, Escape) and abs(escaped.value.t - 0.3518) < 1e-3


def synthetic_runs(bounded):
    """Every source escaped at 0.35 s but those in `bounded`, which ran to the end."""
    escape = lambda source: Escape("DOP853", 0.35, 38, "|l| reached 100")
    return {source: Outcome(run=pd.DataFrame(), twin=pd.DataFrame()) if source in bounded else Outcome(failure=escape(source))
            for source in ("reference", "book", "pinocchio", "mujoco")}


def rows_of(runs):
    """The rows the checks make of `runs`: a trajectory row per source against the reference, an energy row each."""
    def row(check, sources, outcome):
        if outcome.ok:
            return Row(check, "l", sources, 1e-9, 1e-8, 1e-3, Status.PASS)
        return Row(check, "l", sources, None, None, None, Status.UNSTABLE, None, str(outcome.failure))
    return ([row("trajectory", (source, "tight reference"), runs[source]) for source in ("book", "pinocchio", "mujoco")]
            + [row("energy", (source,), outcome) for source, outcome in runs.items()]
            + [Row("pointwise", "l_acc", ("reference", "mujoco"), 0.0, 1e-9, 1e-6, Status.PASS)])


LIMIT = Runaway(("l", 1, 100.0), "the spin beats the spring")


def test_every_source_escaped_is_a_runaway_and_ok():
    rows = runaway_rows(LIMIT, synthetic_runs(bounded=()), rows_of(synthetic_runs(bounded=())))
    assert [r.status for r in rows] == [Status.RUNAWAY] * 7 + [Status.PASS]  # the pointwise row is no run's
    assert all(r.status.ok for r in rows)
    assert rows[0].detail.startswith("the spin beats the spring: DOP853 escaped at t = 0.35 s (step 38)")


def test_a_source_that_stays_bounded_where_the_physics_runs_away_fails():
    runs = synthetic_runs(bounded=("mujoco",))
    rows = runaway_rows(LIMIT, runs, rows_of(runs))
    status = {(r.check, r.sources[0]): r.status for r in rows}
    assert status[("trajectory", "mujoco")] == status[("energy", "mujoco")] == Status.FAIL
    assert status[("energy", "reference")] == status[("trajectory", "book")] == Status.UNSTABLE
    assert not any(r.status == Status.RUNAWAY for r in rows) and not all(r.status.ok for r in rows)
    mujoco = next(r for r in rows if r.sources == ("mujoco",))
    assert mujoco.detail == ("mujoco did not run away where the case says it must (the spin beats the spring): escaped: "
                             "reference at 0.35 s, book at 0.35 s, pinocchio at 0.35 s; within |l| <= 100 to the end: "
                             "mujoco")


def test_no_source_escaped_within_the_run_leaves_the_rows_as_they_are():
    runs = synthetic_runs(bounded=("reference", "book", "pinocchio", "mujoco"))
    assert runaway_rows(LIMIT, runs, rows_of(runs)) == rows_of(runs)


def test_a_source_that_blew_up_otherwise_is_unstable():
    runs = {**synthetic_runs(bounded=()), "mujoco": Outcome(failure=Failure("mujoco:RK4", 0.2, 2000, "state is not finite"))}
    rows = runaway_rows(LIMIT, runs, rows_of(runs))
    assert {r.status for r in rows if r.check != "pointwise"} == {Status.UNSTABLE}
    assert "blew up before escaping: mujoco" in rows[0].detail


@pytest.fixture
def spec():
    return copy.deepcopy(dyncheck.load_case("spring_pendulum").spec)


@pytest.mark.parametrize("key, value, message", [
    ("when", "m*(alpha_rate + beta_rate)**2 - k", "runaway[0].when = 'm*(alpha_rate + beta_rate)**2 - k' is not a "
                                                   "comparison of the parameters, such as k < m*Omega**2"),
    ("when", "k < (", "runaway[0].when = 'k < (' cannot be parsed"),
    ("when", "kk < m", "cannot evaluate 'kk < m': name 'kk' is not defined (did you mean 'k'?) (at runaway[0].when)"),
    ("coordinate", "length", "runaway[0].coordinate = 'length' is not a coordinate"),
    ("escape", -1.0, "runaway[0].escape = -1.0 must be > 0"),
    ("why", "k = {= kk} N/m", "cannot evaluate 'kk': name 'kk' is not defined (did you mean 'k'?) (at runaway[0].why)"),
])
def test_a_bad_runaway_is_refused_on_load_naming_file_field_and_value(spec, key, value, message):
    spec["runaway"][0][key] = value
    folder = dyncheck.load_case("spring_pendulum").folder
    with pytest.raises(ValueError) as error:
        Case(folder, spec=spec)
    assert str(error.value).startswith(f"{folder / 'case.toml'}: ") and message in str(error.value)


def test_the_reason_carries_its_numbers_at_the_run_parameters():
    why = dyncheck.load_case("spring_pendulum", k=150.0).runaway().why
    assert why == ("the spin's centrifugal pull m Omega^2 = 159.9 N/m beats the spring k = 150 N/m "
                   "(Omega = alpha' + beta' = 28.27 rad/s): l grows without bound")
    assert f"{K_CRIT:.4g}" in why
