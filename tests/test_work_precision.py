"""Work-precision sweep, cheapest method, and the convergence checks (fast: small configurations)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import dyncheck
from dyncheck.checks import convergence
from dyncheck.common import ceilings
from dyncheck.run.simulate import simulate as real_simulate
from dyncheck.studies import work_precision


def test_convergence_observes_the_orders():
    for name in ("double_pendulum", "spinning_top"):
        rows = convergence.convergence(dyncheck.load_case(name))
        assert [r.quantity for r in rows] == list(convergence.EXPECTED_ORDER)
        assert all(r.check == "convergence" and r.status == "pass" for r in rows), rows
        assert all(0 < r.tolerance <= ceilings.CONVERGENCE for r in rows)  # an order off by one must fail


def test_convergence_fails_for_a_wrong_order(monkeypatch):
    case = dyncheck.load_case("spinning_top")
    # An integrator bug: "RK4" that is really explicit Euler (order 1, expected 4).
    swapped = lambda model, ic, t_end, method, **kw: real_simulate(
        model, ic, t_end, "explicit Euler" if method == "RK4" else method, **kw)
    monkeypatch.setattr(convergence, "simulate", swapped)
    rows = {r.quantity: r for r in convergence.convergence(case)}
    assert rows["RK4"].status == "fail" and rows["RK4"].error > 2.5
    assert rows["explicit Euler"].status == "pass"
    # A wrong expectation fails too.
    monkeypatch.setattr(convergence, "simulate", real_simulate)
    monkeypatch.setitem(convergence.EXPECTED_ORDER, "semi-implicit Euler", 2)
    rows = {r.quantity: r for r in convergence.convergence(case)}
    assert rows["semi-implicit Euler"].status == "fail"


def test_convergence_refuses_differences_at_rounding_level():
    case = dyncheck.load_case("spinning_top")
    # RK4 at omega h = 5e-4: its differences, ~(omega h)^4, drown in rounding.
    case.spec["work_precision"]["convergence"].update(omega_t=0.1, omega_h={"RK4": 5e-4})
    with pytest.raises(ValueError, match="within rounding"):
        convergence.convergence(case)


# A top with Izz = Ixx / 4 under g = 1 m/s^2 (drawn by `pytest -m slow`): 0.24 s in, its axis passes 0.003 rad from
# the Euler angles' singularity, where its precession rate turns at 1,170 rad/s against the case's omega of 11.5.
NEAR_SINGULAR = {"Izz": 0.002166779934105066, "m": 0.9837987364501684, "Mz": 3.8110158311579513e-299,
                 "Ixx": 0.00827376186236723, "g": 1.0, "h": 0.02}


def test_convergence_stops_its_horizon_where_the_motion_outruns_omega():
    """RK4 at the case's step blew up near the singularity (an `unstable` row for a motion every source runs
    through): the horizon now ends before the motion outruns omega, and the row says so.  Where the motion never
    does (the book's top), the horizon is the case's."""
    near = {r.quantity: r for r in convergence.convergence(dyncheck.load_case("spinning_top", **NEAR_SINGULAR))}
    assert all(r.status == "pass" for r in near.values()), near
    assert "the horizon ends before" in near["RK4"].detail and "omega = 11.5" in near["RK4"].detail
    book = {r.quantity: r for r in convergence.convergence(dyncheck.load_case("spinning_top"))}
    assert not any("the horizon ends" in r.detail for r in book.values())


def test_a_motion_outrunning_omega_at_once_leaves_the_order_unmeasured():
    case = dyncheck.load_case("spinning_top", **NEAR_SINGULAR)
    case.spec["work_precision"]["convergence"]["method_omega"]["RK4"] = "1.0"  # the motion: 7 rad/s from the start
    rows = {r.quantity: r for r in convergence.convergence(case)}
    assert rows["RK4"].status == "inconclusive" and "not measured: within 20 steps" in rows["RK4"].detail


@pytest.mark.full  # seconds of a chain's convergence runs
def test_the_orders_of_a_chain_far_from_equilibrium_pass(tmp_path):
    """Issue 37: explicit Euler failed on a correct derivation of 7 joints.  A case's omega is a linearisation at
    its start; folded up, a chain's motion is faster (3 links from 2 rad on each joint: 9 times omega within the
    horizon, which ends where it passes 4 times), and explicit Euler's deviation of 0.046 failed against the 0.027
    that omega allowed; it passes against the motion's frequency (convergence's error analysis).  The cut horizon
    leaves RK4 fewer than 50 steps, where choosing the instants to compare raised (max() of nothing)."""
    import chain
    folder = chain.write(tmp_path / "chain3", 3)
    (folder / "case.toml").write_text("[initial]\nq = [2.0, 2.0, 2.0]\nv = [0, 0, 0]\n")
    rows = convergence.convergence(dyncheck.Case(folder))
    assert len(rows) == 5 and all(r.status == "pass" for r in rows), rows  # a derived case has no implicitfast
    assert all("the horizon ends before" in r.detail for r in rows)


def tiny(case, sweep):
    case.spec["work_precision"].update(t_end=1.0, output_step=0.01, repeat=2, sweep=sweep,
                                       solution={"rtol": 1e-9, "max_step": 0.01})
    return case


@pytest.mark.full
def test_sweep_rows_and_an_unstable_point(tmp_path):
    case = tiny(dyncheck.load_case("spring_pendulum"), {
        "reference": {"DOP853": [1e-6], "explicit Euler": [1e-3]},  # explicit Euler blows up at 0.8 s
        "mujoco": {"mujoco:RK4": [5e-3]}})
    calls = []
    frame = work_precision.sweep(case, progress=calls.append)
    assert list(frame.columns) == work_precision.COLUMNS
    assert len(frame) == len(calls) == 3
    ok, unstable = frame[frame["status"] == "ok"], frame[frame["status"] == "unstable"]
    assert list(unstable["method"]) == ["explicit Euler"]
    assert np.isnan(unstable["error"]).all() and "t = 0.8" in unstable["detail"].iloc[0]
    assert (ok["error"] > 0).all() and (ok["error"] < 1e-2).all() and (ok["energy_error"] > 0).all()
    assert (ok["cpu"] > 0).all() and (ok["evaluations"] > 0).all()
    assert (ok["cpu_min"] <= ok["cpu"]).all() and (ok["cpu"] <= ok["cpu_max"]).all() and (ok["repeats"] >= 1).all()
    # the points that decide the CPU-time table are timed DECIDING_REPEATS times, the others `repeat` times
    table = work_precision.cheapest(frame, cost="cpu")
    deciding = {label for labels in table["points"] for label in labels} | set(table["runner_up"])
    assert deciding >= {"reference DOP853, rtol = 1e-06", "mujoco:RK4, dt = 0.005 s"}
    assert (ok["repeats"] == [work_precision.DECIDING_REPEATS if work_precision.point_label(r) in deciding else 2
                              for _, r in ok.iterrows()]).all()
    # The reference solution is named and its accuracy verified (tolerance 1e-9 here).
    assert frame.attrs["reference"]["accuracy"] < 1e-6
    for cost in work_precision.COSTS:
        work_precision.figure(frame, case, tmp_path / f"wp_{cost}.png", cost=cost)
        assert (tmp_path / f"wp_{cost}.png").stat().st_size > 0
    for timing in (False, True):
        work_precision.write_csv(frame, tmp_path / "wp.csv", timing=timing)
        written = pd.read_csv(tmp_path / "wp.csv", comment="#")
        assert len(written) == 3 and ("cpu" in written) == timing


def test_nothing_to_integrate():
    case = dyncheck.load_case("piston")
    assert work_precision.sweep(case).empty and convergence.convergence(case) == []
    assert "prescribed" in work_precision.NO_SWEEP


def test_a_step_must_divide_the_output_step():
    case = dyncheck.load_case("double_pendulum")
    case.spec["work_precision"]["sweep"]["mujoco"]["mujoco:RK4"] = [3e-3]
    with pytest.raises(ValueError, match="sweep.mujoco.mujoco:RK4"):
        work_precision.plan(case)


def test_cheapest_picks_the_cheapest_point_that_reaches_each_level():
    # source, method, error, CPU time, evaluations: by evaluations b's first point is cheapest at 1e-2, by
    # CPU time too; at 1e-4 only b's second point is left
    rows = [("a", "RK4", 1e-3, 0.10, 400), ("b", "DOP853", 5e-3, 0.05, 300), ("b", "DOP853", 1e-5, 0.20, 900),
            ("c", "Euler", 1e-9, 0.01, 50)]  # c: within 10x of the reference's accuracy, unresolved
    frame = pd.DataFrame([{"source": s, "method": m, "setting": "dt", "value": 0.1, "error": e, "cpu": w,
                           "cpu_min": 0.9 * w, "cpu_max": 1.1 * w,
                           "evaluations": n, "status": "ok", "resolved": e > 1e-8} for s, m, e, w, n in rows]
                         + [{"source": "d", "method": "RK45", "setting": "rtol", "value": 1.0, "error": np.nan,
                             "cpu": np.nan, "evaluations": np.nan, "status": "unstable", "resolved": False}])
    frame.attrs["reference"] = {"accuracy": 1e-9}
    by_cpu = work_precision.cheapest(frame, cost="cpu", levels=(1e-2, 1e-4)).set_index("level")
    assert by_cpu.loc[1e-2, "cheapest"].startswith("b DOP853") and by_cpu.loc[1e-2, "cpu"] == 0.9 * 0.05  # fastest run
    assert by_cpu.loc[1e-2, "runner_up"].startswith("a RK4") and by_cpu.loc[1e-2, "runner_up_cpu"] == 0.9 * 0.10
    frame.loc[1, "evaluations"] = 500  # now a's point is cheaper in evaluations, b's in CPU time
    table = work_precision.cheapest(frame, levels=(1e-2, 1e-4, 1e-8, 1e-10)).set_index("level")
    assert table.loc[1e-2, "cheapest"].startswith("a RK4") and table.loc[1e-2, "evaluations"] == 400
    assert table.loc[1e-2, "runner_up"].startswith("b DOP853") and table.loc[1e-2, "runner_up_evaluations"] == 500
    assert table.loc[1e-4, "evaluations"] == 900 and table.loc[1e-4, "runner_up"] == ""
    assert table.loc[1e-8, "cheapest"] == "none reached"
    assert table.loc[1e-10, "cheapest"].startswith("not resolvable")


def synthetic(points):
    """A resolved sweep frame from (source, method, error, evaluations, CPU times of its runs)."""
    return pd.DataFrame([{"source": s, "method": m, "setting": "rtol", "value": 1e-6, "error": e, "evaluations": n,
                          "cpu": float(np.median(w)), "cpu_min": min(w), "cpu_max": max(w),
                          "repeats": len(w),
                          "status": "ok", "resolved": True} for s, m, e, n, w in points])


def test_cheapest_in_cpu_time_by_the_fastest_run_beyond_the_reproducibility():
    # fastest runs 1.0 and 1.3: apart by more than 20% of 1.0: a alone, b the runner-up; a's three slowed runs of
    # five (slower than all of b's) do not change that
    apart = synthetic([("a", "LSODA", 1e-3, 300, [2.0, 1.0, 2.2, 1.05, 2.5]),
                       ("b", "DOP853", 1e-3, 200, [1.3, 1.35, 1.4, 1.45, 1.5])])
    table = work_precision.cheapest(apart, cost="cpu", levels=(1e-2,)).iloc[0]
    assert table["cheapest"] == "a LSODA, rtol = 1e-06" and table["points"] == ("a LSODA, rtol = 1e-06",)
    assert table["runner_up"] == "b DOP853, rtol = 1e-06" and table["cpu"] == 1.0 and table["runner_up_cpu"] == 1.3
    # fastest runs 1.1 and 1.0, within 20%: a tie, both named in the sweep's order; c is beyond it: the runner-up
    close = synthetic([("b", "DOP853", 1e-3, 200, [1.1, 1.2, 1.25, 1.3, 1.35]),
                       ("a", "LSODA", 1e-3, 300, [1.0, 1.05, 1.1, 1.15, 1.2]), ("c", "RK45", 1e-3, 900, [1.25, 2.1, 2.2])])
    table = work_precision.cheapest(close, cost="cpu", levels=(1e-2,)).iloc[0]
    assert table["cheapest"] == ("b DOP853, rtol = 1e-06 or a LSODA, rtol = 1e-06 (tie: fastest runs within 20%)")
    assert table["methods"] == ("DOP853", "LSODA") and table["runner_up"] == "c RK45, rtol = 1e-06"
    assert table["cpu"] == 1.0  # the cheapest's fastest run
    # single runs: within 20% of the faster they tie, beyond it they are apart
    single = synthetic([("a", "LSODA", 1e-3, 300, [1.0]), ("b", "DOP853", 1e-3, 300, [1.19])])
    assert work_precision.cheapest(single, cost="cpu", levels=(1e-2,)).iloc[0]["methods"] == ("LSODA", "DOP853")
    single.loc[1, "cpu_min"] = 1.21
    assert work_precision.cheapest(single, cost="cpu", levels=(1e-2,)).iloc[0]["points"] == ("a LSODA, rtol = 1e-06",)
    # a method stands by its point of fewest evaluations that reaches the level, whatever its CPU time
    two_points = synthetic([("a", "LSODA", 1e-3, 300, [1.0]), ("a", "LSODA", 1e-4, 400, [0.9])])
    assert work_precision.cheapest(two_points, cost="cpu", levels=(1e-2,)).iloc[0]["cpu"] == 1.0
    # evaluations are counts: equal counts tie, whatever the CPU times
    table = work_precision.cheapest(single, levels=(1e-2,)).iloc[0]
    assert table["cheapest"] == "a LSODA, rtol = 1e-06 or b DOP853, rtol = 1e-06 (tie: equal counts)"
    assert table["runner_up"] == "" and table["evaluations"] == 300
    # one method and setting from several sources: named once
    same = synthetic([("reference", "LSODA", 1e-3, 300, [1.0]), ("pinocchio", "LSODA", 1e-3, 300, [1.2])])
    assert work_precision.cheapest(same, levels=(1e-2,)).iloc[0]["cheapest"] == \
        "reference and pinocchio LSODA, rtol = 1e-06 (tie: equal counts)"


def test_in_short_counts_the_levels_each_method_wins():
    # evaluations: 1e-2 DOP853, 1e-4 LSODA in one, a tie at 1e-2 in two; CPU time: LSODA at all three
    one = synthetic([("a", "LSODA", 1e-5, 300, [1.0]), ("b", "DOP853", 1e-3, 200, [2.0])])
    two = synthetic([("a", "LSODA", 1e-3, 300, [1.0]), ("b", "DOP853", 1e-3, 300, [2.0])])
    sweeps = {"one": one, "two": two, "none": pd.DataFrame(columns=work_precision.COLUMNS)}
    assert work_precision.in_short(sweeps) == (
        "counted in right-hand-side evaluations, the cheapest method at each of the 3 accuracy levels (1e-02 to 1e-10)"
        " that the 2 integrated cases reach is an adaptive one: DOP853 at 2 of them and LSODA at 2; 1 level is a tie"
        " between methods (tie: equal counts), counted for each")
    assert work_precision.in_short(sweeps, cost="cpu").endswith("reach is an adaptive one: LSODA at 3 of them")


def test_the_overview_quotes_the_sentence_of_the_committed_sweeps():
    """docs/overview.md's "Speed against accuracy, in short" is the index's sentence, from the committed sweeps' rows."""
    data = Path(__file__).parents[1] / "reports" / "data"
    sweeps = {path.name.removesuffix("_work_precision.csv"): work_precision.read_csv(path)
              for path in sorted(data.glob("*_work_precision.csv"))}
    overview = " ".join((Path(__file__).parents[1] / "docs" / "overview.md").read_text().split())
    assert f"Speed against accuracy, in short: {work_precision.in_short(sweeps)}." in overview


def test_a_point_that_spends_its_wall_time_is_budget_spent_not_unstable(monkeypatch):
    """A run stopped by its wall-time budget (simulate's OverBudget) is its own status in the sweep, as in the
    checks' rows: the machine's load or a costly evaluation, not an instability of the method."""
    from dyncheck.run.simulate import OverBudget
    case = tiny(dyncheck.load_case("spring_pendulum"), {"reference": {"DOP853": [1e-6], "RK45": [1e-6]}})

    def slow(model, start, t_end, method, **kwargs):
        if method == "RK45":
            raise OverBudget(method, 0.25, 40, "gave up after 120 s of wall time")
        return real_simulate(model, start, t_end, method, **kwargs)

    monkeypatch.setattr(work_precision, "simulate", slow)
    frame = work_precision.sweep(case)
    spent = frame[frame["method"] == "RK45"]
    assert list(spent["status"]) == ["budget spent"] and "budget spent at t = 0.25 s, step 40" in spent["detail"].iloc[0]
    assert list(frame[frame["method"] == "DOP853"]["status"]) == ["ok"]
