"""The batched paths the benchmark measures give what the state-by-state ones give; the bench's table."""

import numpy as np

import dyncheck
from dyncheck.bench import bench_case
from engines import euler


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


def test_the_bench_table_names_each_rows_bare_loop():
    table = bench_case(dyncheck.load_case("piston"), steps=80, repeat=1)
    assert list(table.columns) == ["case", "source", "what", "count", "median s", "per second", "ratio to bare",
                                   "against"]
    compared = table[table["against"] != ""]
    assert set(compared["source"]) == {"mujoco", "pinocchio"}
    assert np.all(np.isfinite(compared["ratio to bare"])) and np.all(table["median s"] > 0)
    for source, against in zip(compared["source"], compared["against"]):
        bare = table[(table["source"] == source) & (table["what"] == against)]
        assert len(bare) == 1 and (bare["against"].iloc[0] or bare["ratio to bare"].iloc[0] == 1.0)
