"""The batched paths the benchmark measures give what the state-by-state ones give; the bench's table."""

from pathlib import Path

import numpy as np
import pytest

import dyncheck
from dyncheck.bench import bench_case, bench_table
from engines import euler
from engines.bench import MujocoLoops, pinocchio_rhs, pinocchio_steps

ROOT = Path(__file__).resolve().parent.parent


def test_drive_powers_of_a_run_equal_drive_power_state_by_state():
    for name in ("spring_pendulum", "spinning_top"):
        case = dyncheck.load_case(name)
        model = case.model("mujoco")
        q0, v0, _ = case.initial
        run = model.step(q0, v0, 0.01, case.integration["mujoco_step"], "RK4")
        batched = model.drive_powers(run["t"], run["q"], run["v"])
        single = [model.drive_power(t, q, v) for t, q, v in zip(run["t"], run["q"], run["v"])]
        np.testing.assert_allclose(batched, single, rtol=0, atol=1e-13 * np.max(np.abs(single)))


def test_euler_conversions_of_many_states_equal_those_of_each():
    rng = np.random.default_rng(1)
    angles = np.column_stack([rng.uniform(-3, 3, 50), rng.uniform(0.1, 3.0, 50), rng.uniform(-3, 3, 50)])
    rates, w_dot = rng.uniform(-50, 50, (50, 3)), rng.uniform(-50, 50, (50, 3))
    w = euler.angular_velocity(angles, rates)
    np.testing.assert_allclose(euler.euler_rates(angles, w), rates, rtol=0, atol=1e-12)
    for i in (0, 17, 49):
        np.testing.assert_array_equal(w[i], euler.angular_velocity(angles[i], rates[i]))
        np.testing.assert_array_equal(euler.quaternion(angles)[i], euler.quaternion(angles[i]))
        np.testing.assert_allclose(euler.euler_accelerations(angles, rates, w_dot)[i],
                                   euler.euler_accelerations(angles[i], rates[i], w_dot[i]), rtol=1e-14, atol=1e-12)


def test_the_bare_mujoco_loops_step_the_harness_scene():
    case = dyncheck.load_case("spinning_top")
    model, (q0, v0, _), dt = case.model("mujoco"), case.initial, case.integration["mujoco_step"]
    bare = MujocoLoops(model, q0, v0, dt, "RK4")
    bare.mj_step(100)
    # the top's qpos is its quaternion; mj_step and rollout step alike, to rounding
    np.testing.assert_allclose(bare.d.qpos, model.ball_joint_quaternions(q0, v0, 100 * dt, dt, "RK4")[-1],
                               rtol=0, atol=1e-12)


def assert_equal_to_rounding(actual, expected):
    # the same Pinocchio calls on the same numbers, reached by other arithmetic
    scale = np.max(np.abs(expected), initial=1.0)
    np.testing.assert_allclose(actual, expected, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("name", dyncheck.case_names())
def test_the_bare_pinocchio_loops_do_the_harness_work(name):
    """The bare right-hand side and engine step give the harness's accelerations and drive power."""
    case = dyncheck.load_case(name)
    model, (q0, v0, _) = case.model("pinocchio"), case.initial
    rhs, y0 = pinocchio_rhs(model, q0, v0, work=case.driven)
    dy = rhs(0.0, y0)
    if name == "spinning_top":  # the bare state is Pinocchio's quaternion and the body's angular velocity
        w = euler.angular_velocity(q0, v0)
        expected = model.ball_joint_acceleration(euler.quaternion(q0), w)
        assert_equal_to_rounding(dy[4:7], expected)
    else:  # the bare state is the book's: its coordinates are the free joints' positions
        n = len(q0)
        np.testing.assert_allclose(dy[:n], v0, rtol=0, atol=0)
        expected = model.accelerations(0.0, q0, v0)
        assert_equal_to_rounding(dy[n:2 * n], expected)
    power = model.drive_power(0.0, q0, v0) if case.driven else 0.0
    assert_equal_to_rounding(dy[-1], power)
    config, velocity = model.engine_state(0.0, q0, v0)
    (acc, _), = pinocchio_steps(model, [(config, velocity)])
    np.testing.assert_array_equal(acc, model.engine_dynamics(config, velocity, model.applied)[0])


def test_the_bench_table_names_each_rows_bare_loop():
    table = bench_case(dyncheck.load_case("piston"), steps=80, repeat=1)
    assert list(table.columns) == ["case", "source", "what", "count", "median s", "per second", "ratio to bare",
                                   "bound", "mark", "against"]
    compared = table[table["against"] != ""]
    assert set(compared["bound"]) == {"1.5"} and set(table[table["against"] == ""]["bound"]) == {""}
    assert all((mark == "EXCEEDED") == (ratio > 1.5) for mark, ratio in zip(compared["mark"], compared["ratio to bare"]))
    assert set(compared["source"]) == {"mujoco", "pinocchio"}
    assert np.all(np.isfinite(compared["ratio to bare"])) and np.all(table["median s"] > 0)
    for source, against in zip(compared["source"], compared["against"]):
        bare = table[(table["source"] == source) & (table["what"] == against)]
        assert len(bare) == 1 and (bare["against"].iloc[0] or bare["ratio to bare"].iloc[0] == 1.0)
    # the harness's accelerations (all the states in one call) against the engine step on as many states
    harness, loop = (table[table["what"] == what] for what in ("harness accelerations", "pin.rnea loop"))
    assert list(harness["against"]) == ["pin.rnea loop"] and list(harness["count"]) == list(loop["count"])


def test_a_scene_whose_forces_vary_has_no_throughput_rows_but_says_so():
    """No bare loop evaluates a law of the state (engines.bench): the forced cart-pendulum's rows are left out, with
    a line that says why (its whole runs, --runs, are still timed)."""
    forced = dyncheck.load_case("forced_cart_pendulum", ROOT / "examples")
    assert bench_table([forced]).startswith("no throughput rows of forced_cart_pendulum: its applied forces vary")
