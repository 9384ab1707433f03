"""A model's quantities of many states in one call (`*_many`: Pinocchio's accelerations, the 1.8.x references',
MuJoCo's and Pinocchio's reactions and energy, MuJoCo's paths) are its quantities state by state, to the bit; the checks that ask
for many states name the state where one fails."""

from pathlib import Path

import numpy as np
import pytest

import dyncheck
from dyncheck.checks.pointwise import evaluate

EXAMPLES = Path(__file__).parent.parent / "examples"


def columns(states):
    """t (N,), q and v (N, n) of a list of (t, q, v)."""
    return [np.array(column) for column in zip(*states)]


def random_states(case, count, seed):
    """`count` random states within the span of the case's sample states (its [sample] ranges: the top's nutation
    away from 0 and pi, where its Euler angles are singular)."""
    rng = np.random.default_rng(seed)
    return [rng.uniform(x.min(axis=0), x.max(axis=0), (count,) + x.shape[1:]) for x in columns(case.sample_states())]


def assert_many_is_each(case, t, q, v):
    # Fresh models both: a scene with loops closes each state from the last closing.  Bit for bit: the conversions
    # in numpy are the same operations on the same numbers as on one state's Python floats (numpy's sin and cos
    # are libm's, as math's; t**2 is libm's pow on both sides).
    one_state = case.with_params().model("pinocchio")
    each = np.array([one_state.accelerations(*state) for state in zip(t, q, v)]).reshape(len(t), len(case.coords))
    many = case.with_params().model("pinocchio").accelerations_many(t, q, v)
    np.testing.assert_array_equal(many, each)


@pytest.mark.parametrize("name", dyncheck.case_names())
def test_pinocchio_accelerations_of_many_states_are_those_of_each(name):
    case = dyncheck.load_case(name)
    assert_many_is_each(case, *columns(case.sample_states()))
    assert_many_is_each(case, *random_states(case, 3000, seed=17))


@pytest.mark.parametrize("name", dyncheck.case_names())
def test_pinocchio_engine_states_of_many_states_are_those_of_each(name):
    # the piston's driven joints accelerate: their positions take t**2, which numpy's power of an array rounds
    # otherwise than Python's at some 5% of times
    case = dyncheck.load_case(name)
    model = case.model("pinocchio")
    t, q, v = random_states(case, 3000, seed=17)
    each = [model.engine_state(*state) for state in zip(t, q, v)]
    configs, velocities = model.engine_states(t, q, v)
    np.testing.assert_array_equal(configs, [config for config, _ in each])
    np.testing.assert_array_equal(velocities, [velocity for _, velocity in each])


def one_by_one(model, quantity, t, q, v):
    """model.<quantity> state by state, stacked as its many-state form gives them."""
    values = [getattr(model, quantity)(*state) for state in zip(t, q, v)]
    if isinstance(values[0], dict):
        return {name: np.array([value[name] for value in values]) for name in values[0]}
    return np.array(values)


@pytest.mark.parametrize("name", dyncheck.case_names())
@pytest.mark.parametrize("source", ["reference", "book", "mujoco", "pinocchio"])
def test_reactions_energy_and_paths_of_many_states_are_those_of_each(name, source):
    case = dyncheck.load_case(name)
    model = case.model(source)
    t, q, v = columns(case.sample_states())
    many = [quantity for quantity in ("reactions", "energy") if hasattr(model, quantity + "_many")]
    for quantity in many:
        expected, got = one_by_one(model, quantity, t, q, v), getattr(model, quantity + "_many")(t, q, v)
        if isinstance(expected, dict):
            assert got.keys() == expected.keys()
            for key in expected:
                np.testing.assert_array_equal(got[key], expected[key], err_msg=f"{quantity} {key}")
        else:
            np.testing.assert_array_equal(got, expected, err_msg=quantity)
    if hasattr(model, "paths_many") and case.scene.paths:
        np.testing.assert_array_equal(model.paths_many(t, q), np.array([model.points(*s)[0] for s in zip(t, q)]))
    if source in ("mujoco", "pinocchio") or (source == "reference" and name in ("rotating_pendulum", "rotating_particle",
                                                                    "spring_pendulum")):
        assert "reactions" in many and "energy" in many  # the models that have them: not a test of nothing


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
@pytest.mark.parametrize("name", ["slider_crank", "forced_cart_pendulum"])  # a closed loop; applied laws of the state
def test_pinocchio_accelerations_of_many_states_in_the_examples(name):
    case = dyncheck.load_case(name, EXAMPLES)
    assert_many_is_each(case, *columns(case.sample_states()))


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
@pytest.mark.parametrize("name", ["slider_crank", "forced_cart_pendulum"])
def test_pinocchio_reactions_and_energy_of_many_states_in_the_examples(name):
    case = dyncheck.load_case(name, EXAMPLES)
    t, q, v = columns(case.sample_states())
    for quantity in ("reactions", "energy"):  # fresh models both: a scene with loops closes each state from the last
        expected = one_by_one(case.with_params().model("pinocchio"), quantity, t, q, v)
        got = getattr(case.with_params().model("pinocchio"), quantity + "_many")(t, q, v)
        for key in expected if quantity == "reactions" else [None]:
            np.testing.assert_array_equal(got[key] if key else got, expected[key] if key else expected,
                                          err_msg=f"{quantity} {key}")


def test_evaluate_names_the_state_where_the_many_state_call_fails(monkeypatch):
    case = dyncheck.load_case("double_pendulum")
    model, states = case.model("pinocchio"), case.sample_states()[:5]
    one_state = model.accelerations
    monkeypatch.setattr(model, "accelerations_many", lambda t, q, v: np.full((len(t), 2), np.nan))
    monkeypatch.setattr(model, "accelerations", lambda t, q, v: 1 / 0 if t == states[3][0] else one_state(t, q, v))
    with pytest.raises(ArithmeticError, match="pinocchio: accelerations at random state 3: ZeroDivisionError"):
        evaluate(case, "pinocchio", states)
