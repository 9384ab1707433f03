"""Issue 37, any number of joints: a case of two files starts near its stable equilibrium (dyncheck/case/start.py),
and a 7-link chain (tests/chain.py) runs green within minutes, a planted error named by its equation."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import chain
from dyncheck.case import start
from dyncheck.case.folder import Case
from dyncheck.run.simulate import fastest_frequency, simulate, state_columns

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def equations(accelerations):
    return SimpleNamespace(accelerations=lambda t, q, v: np.array(accelerations(t, q, v)))


def test_the_start_is_near_a_stable_equilibrium_and_away_from_the_pose_otherwise():
    # a pendulum whose equilibrium is 0.3 rad off the pose, with a cart beside it on a spring: 0.1 rad and a
    # hundredth of the scene's size (2 m) from it
    stable = equations(lambda t, q, v: [-25 * np.sin(q[0] - 0.3) - 0.1 * v[0], -4 * q[1]])
    q0, found = start.initial_q(stable, ["rad", "m"], 2.0)
    assert np.allclose(found, [0.3, 0.0], atol=1e-12) and np.allclose(q0, [0.4, 0.02], atol=1e-12)
    away = [0.5, 0.2]  # 0.5 rad, a tenth of the size
    for unstable in (lambda t, q, v: [25 * np.sin(q[0]), -4 * q[1]],  # upright: a mode grows
                     lambda t, q, v: [-25 * np.sin(q[0]) + np.cos(3 * t), -4 * q[1]],  # forced: no rest holds at every t
                     lambda t, q, v: [0.0, 0.0],  # nothing restores it
                     lambda t, q, v: [-25 * q[0] + 1 / q[1], 0.0]):  # the derivation fails at the pose
        q0, found = start.initial_q(equations(unstable), ["rad", "m"], 2.0)
        assert found is None and np.allclose(q0, away)


def test_a_chain_of_seven_starts_near_hanging_and_its_runs_agree(tmp_path):
    """0.5 rad on every joint folded the chain over itself (its linearisation there gave 9.3 rad/s for modes up to
    27 rad/s): now 0.1 rad from hanging, its time scales from the modes, its runs at rtol 1e-8 and 1e-11 agreeing."""
    case = Case(chain.write(tmp_path / "chain7", 7))
    q0, v0, t_end = case.initial
    assert np.allclose(q0, 0.1) and not v0.any()
    assert 24 < fastest_frequency(case) < 27  # 27.2 rad/s hanging
    assert "0.1 rad on every angle, from the stable equilibrium at rest, q = [0.0," in case.spec["report"]["modelling"]
    runs = [simulate(case.model("reference"), (q0, v0), t_end, "DOP853", rtol=rtol, work=False, quantities=(),
                     output_step=case.integration["output_step"], omega=fastest_frequency(case)) for rtol in (1e-8, 1e-11)]
    columns = state_columns(case)
    assert ((runs[0][columns] - runs[1][columns]).abs().max() / runs[1][columns].abs().max()).max() < 1e-6


def test_a_forced_example_keeps_its_start():
    """The forced cart pendulum has no rest that holds at every time (F0 cos(Omega t)): it starts where its committed
    report does, 0.5 rad and a tenth of the scene's size from the pose (examples/ sets no [initial])."""
    q0, v0, _ = Case(EXAMPLES / "forced_cart_pendulum").initial
    assert q0.tolist() == [0.05, 0.5] and not v0.any()
