"""The fixed-step integrators (simulate's FIXED_METHODS), stepped on lists of floats, give the floats of the same
schemes in numpy's array arithmetic, bit for bit."""

import numpy as np
import pytest

from dyncheck.case.folder import load_case
from dyncheck.run.simulate import FIXED_METHODS, Unstable, simulate


def numpy_scheme(model, q, v, dt, steps, method):
    """The scheme in numpy arrays, as written before the lists: (q, v, w) after each step."""
    n, w, states = len(q), 0.0, []

    def derivative(t, y):
        q, v = y[:n], y[n:2 * n]
        return np.concatenate([v, model.accelerations(t, q, v), [model.drive_power(t, q, v)]])

    for step in range(steps):
        t = step * dt
        if method == "RK4":
            y = np.concatenate([q, v, [w]])
            k1 = derivative(t, y)
            k2 = derivative(t + dt / 2, y + dt / 2 * k1)
            k3 = derivative(t + dt / 2, y + dt / 2 * k2)
            k4 = derivative(t + dt, y + dt * k3)
            y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            q, v, w = y[:n], y[n:2 * n], y[-1]
        else:
            acc, power = model.accelerations(t, q, v), model.drive_power(t, q, v)
            v_new = v + dt * acc
            q = q + dt * (v_new if method == "semi-implicit Euler" else v)
            v, w = v_new, w + dt * power
        states.append(np.concatenate([q, v, [w]]))
    return np.array(states)


@pytest.mark.parametrize("name", ["spring_pendulum", "spinning_top"])
@pytest.mark.parametrize("method", FIXED_METHODS)
def test_each_scheme_gives_numpys_floats(name, method):
    case = load_case(name)  # the spring pendulum is driven: its work rides along
    model, (q0, v0) = case.model("book"), case.initial[:2]
    run = simulate(model, (q0, v0), 0.1, method, dt=1e-3, output_step=1e-3)
    columns = [*case.coords, *(c + "_rate" for c in case.coords), "work"]
    assert np.array_equal(run[columns].to_numpy()[1:], numpy_scheme(model, q0, v0, 1e-3, 100, method))
    assert run.attrs["evaluations"] == (4 if method == "RK4" else 1) * 100


def test_a_blow_up_is_unstable_at_its_step():
    case = load_case("spring_pendulum")  # explicit Euler at 50 ms: the spring's 100 rad/s is far beyond it
    with pytest.raises(Unstable, match=r"explicit Euler unstable at t = 0\.6 s \(step 12\): state is not finite"):
        simulate(case.model("book"), case.initial[:2], 3.0, "explicit Euler", dt=0.05, output_step=0.1)


def test_an_output_step_shorter_than_the_step_is_refused():
    case = load_case("spring_pendulum")
    with pytest.raises(ValueError, match="shorter than the step"):
        simulate(case.model("book"), case.initial[:2], 0.1, "RK4", dt=0.01, output_step=0.001)


class AsColumn:
    """A model whose accelerations come as a column (n, 1), as a researcher's matrix algebra may leave them."""

    def __init__(self, model):
        self.model = model

    def __getattr__(self, name):
        return getattr(self.model, name)

    def accelerations(self, t, q, v):
        return np.reshape(self.model.accelerations(t, q, v), (-1, 1))


@pytest.mark.parametrize("method", FIXED_METHODS + ("DOP853",))
def test_accelerations_as_a_column_step_as_a_flat_vector(method):
    # every integrator takes a model's answer flattened (simulate._floats): the same floats as the flat answer
    case = load_case("spring_pendulum")
    model, ic = case.model("book"), case.initial[:2]
    options = {"rtol": 1e-8} if method == "DOP853" else {"dt": 1e-3}
    flat, column = (simulate(m, ic, 0.05, method, output_step=1e-2, **options) for m in (model, AsColumn(model)))
    assert flat.equals(column)
