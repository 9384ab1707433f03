"""The 1.8.x references run their Newton-Euler chain as straight-line code traced from it (reference/straight.py):
the same numbers as the plain code (`_motion` itself) at every state and parameter set, but for the sign of a
zero; the same exception or non-finite value where the plain code gives one; the plain code where a model cannot
be traced."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import dyncheck
from reference import straight
from reference.spinning_base import ParticleOnBase, particle_motion, scale, sub

CASES = ("rotating_particle", "rotating_pendulum", "spring_pendulum")


def plain_motion(model, t, q, v):
    """The untraced code: the model's `_motion` on floats, as `_at` called it before it was traced."""
    return model._motion(float(t), [float(x) for x in q], [float(x) for x in v])


def quantities(model, t, q, v, motion):
    """Accelerations, reactions, energy and drive power from a motion, as the model's methods make them."""
    force = motion[3]
    return (list(motion[0]), [force[axis] for axis in model.reaction_axes], model._energy(q, motion),
            model._drive_power(q, v, motion), motion)


def assert_same(model, t, q, v):
    straight_motion = model._at(t, q, v)
    assert model._straight_motion.__code__.co_filename == "<straight-line code>"  # traced, not the plain code
    got, expected = (quantities(model, t, q, v, m) for m in (straight_motion, plain_motion(model, t, q, v)))
    # == and NaN in the same places: +0.0 == -0.0 (the only difference the folded zeros may make)
    np.testing.assert_array_equal(np.hstack([np.ravel(x) for x in got[:4]]), np.hstack([np.ravel(x) for x in expected[:4]]))
    np.testing.assert_array_equal(np.hstack([np.ravel(x) for x in got[4][1:]]),
                                  np.hstack([np.ravel(x) for x in expected[4][1:]]))


@st.composite
def models_and_states(draw, name):
    """A case's reference at random parameters (each of [sample.params.ranges] at its value or drawn in its range),
    at a random state within twice its [sample] ranges."""
    case = dyncheck.load_case(name)
    ranges = case.spec["sample"]["params"]["ranges"]
    drawn = {}
    for parameter, (lo, hi) in ranges.items():
        if draw(st.booleans()):
            drawn[parameter] = draw(st.floats(case.value(lo), case.value(hi)))
    try:
        case = case.with_params(**drawn)
        model = case.model("reference")
    except ValueError:  # not physical (the case's own checks)
        assume(False)
    s = case.spec["sample"]
    widened = lambda lo, hi: st.floats(2 * case.value(lo) - case.value(hi), 2 * case.value(hi) - case.value(lo))
    t = draw(widened(*s["t"]))
    q = [draw(widened(lo, hi)) for lo, hi in s["q"]]
    v = [draw(widened(lo, hi)) for lo, hi in s["v"]]
    return model, t, np.array(q), np.array(v)


@pytest.mark.parametrize("name", CASES)
@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_the_straight_line_code_gives_the_plain_code_s_numbers(name, data):
    assert_same(*data.draw(models_and_states(name)))


def outcome(call):
    """A call's result as text (-0.0 and 0.0 alike), or its exception's type."""
    try:
        return repr(np.array(np.hstack([np.ravel(x) for x in call()]), dtype=float) + 0.0)
    except Exception as error:  # noqa: BLE001  (the exception is the outcome compared)
        return type(error).__name__


@pytest.mark.parametrize("name", CASES)
def test_a_non_finite_or_huge_state_gives_the_plain_code_s_outcome(name):
    """An infinity or NaN (or an overflow) in the state: the same NaN, infinity or exception (math's sin of an
    infinity raises ValueError), not a finite number that a folded zero hid."""
    model = dyncheck.load_case(name).model("reference")
    n = len(model.coords)
    model._at(0.3, [0.3] * n, [0.3] * n)
    for bad in (math.inf, -math.inf, math.nan, 1e200, -1e200, 1e155):
        for i in range(1 + 2 * n):
            x = [0.3] * (1 + 2 * n)
            x[i] = bad
            assert outcome(lambda: model._straight_motion(*x)) == outcome(lambda: model._motion(x[0], x[1:n + 1], x[n + 1:]))


class Branching(ParticleOnBase):
    """A model from outside the tree that the tracer cannot follow: a branch on the state, and numpy's sqrt."""

    coords = ("psi",)
    reaction_names = ("R",)
    reaction_axes = (0,)

    def _motion(self, t, q, v):
        p = self.p
        position, v_e, a_e, gravity = particle_motion(p, t, q[0], v[0], 0.0, p["l"])
        acc = -np.sqrt(abs(q[0])) if q[0] > 0 else 0.0
        return (acc,), position, v_e, scale(p["m"], sub(a_e, gravity))


def test_a_model_the_tracer_cannot_follow_runs_its_plain_code():
    params = dyncheck.load_case("rotating_pendulum").params
    model = Branching(params)
    for psi in (0.5, -0.5):
        assert model.accelerations(0.1, [psi], [1.0])[0] == (-np.sqrt(psi) if psi > 0 else 0.0)
        assert model.drive_power(0.1, [psi], [1.0]) == model._drive_power([psi], [1.0], plain_motion(model, 0.1, [psi], [1.0]))
    assert model._straight_motion.__code__.co_filename != "<straight-line code>"


def test_constants_are_folded_only_where_exact():
    """x * 0.0 and 0.0 + x are folded; a NaN or infinity they hid makes the code return the plain function's."""
    def f(x, y):
        return (0.0 + x * 0.0 + y, 2.0 * 3.0 * y, (x * 1.0) / 1.0 - 0.0)

    traced = straight.compiled(f, ["x", "y"])
    assert traced.__code__.co_filename == "<straight-line code>"
    for x, y in [(1.5, -2.0), (-0.0, 0.0), (math.inf, 1.0), (math.nan, 1.0), (1.0, math.inf)]:
        assert outcome(lambda: traced(x, y)) == outcome(lambda: f(x, y))
    assert straight.compiled(lambda x: (x if x > 0 else -x,), ["x"]).__code__.co_filename != "<straight-line code>"
