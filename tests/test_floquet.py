"""Floquet analysis about the book's periodic motions (dyncheck/checks/vibration.py, `floquet`): with the arm and the disk
both turning, the 1.8.1 and 1.8.3 equations are periodic in t; the periodic orbit, each source's monodromy matrix
and multipliers agree, Liouville's formula holds, the arm at rest gives back the equilibrium's exp(lambda T), and a
bad table is refused naming its field."""

import re
from pathlib import Path

import numpy as np
import pytest

import dyncheck
from dyncheck.checks import floquet, linear
from dyncheck.results.values import Status
from dyncheck.run import simulate
from test_vibration import edited_case

pytestmark = pytest.mark.full  # runs of the cases' engines, seconds each: `pytest -m full`

CASES = Path(__file__).resolve().parent.parent / "cases"
BOOK = ("rotating_pendulum", "spring_pendulum")


@pytest.fixture(scope="module")
def periodic():
    """The Floquet analysis of both cases at the book's numbers."""
    return {name: floquet.floquet(dyncheck.load_case(name)) for name in BOOK}


@pytest.mark.parametrize("name", BOOK)
def test_every_floquet_row_passes_at_the_books_numbers(periodic, name):
    floquet = periodic[name]
    assert floquet.rows and all(r.status == Status.PASS for r in floquet.rows), [r for r in floquet.rows
                                                                                 if r.status != Status.PASS]
    assert set(floquet.monodromy) == {"reference", "mujoco", "pinocchio"}
    quantities = {r.quantity for r in floquet.rows}
    assert {"monodromy matrix Phi(T)", "Floquet multiplier 1", "stability (Floquet)",
            "largest Floquet multiplier, stroboscopic run"} <= quantities
    # the orbit closes: its last state (after one period) is its first
    assert np.allclose(floquet.orbit[-1], floquet.orbit[0], rtol=0, atol=1e-10)


@pytest.mark.parametrize("name", BOOK)
def test_the_multipliers_product_is_liouvilles_exp_of_the_integrated_trace(periodic, name):
    """det Phi(T) = exp(integral of trace A over the period); undamped, the trace integrates to 0 over a period
    (it is -2 l'/(l0 + l) for the spring pendulum, a derivative of a periodic function), so the product is 1."""
    for source, monodromy in periodic[name].monodromy.items():
        product = np.prod(monodromy.multipliers)
        # first order: d(prod mu) = prod mu * sum(d mu / mu)
        allowed = linear.SAFETY * abs(product) * np.sum(monodromy.bounds / np.abs(monodromy.multipliers))
        assert abs(product - np.exp(monodromy.trace_integral)) <= allowed, source
        assert abs(monodromy.trace_integral) < 1e-9, source
        assert abs(product - 1) <= allowed, source


@pytest.mark.parametrize("name", BOOK)
def test_with_the_arm_at_rest_the_multipliers_are_the_equilibriums_exp_lambda_t(name):
    """alpha' = 0: the vibration table's overrides (alpha' = 0, beta' = alpha' + beta') leave the scene as it is, the
    periodic motion is the relative equilibrium and Phi(T) = exp(A T), its multipliers exp(lambda T)."""
    case = dyncheck.load_case(name, alpha_rate=0.0)
    analysis = floquet.floquet(case)
    assert all(r.status == Status.PASS for r in analysis.rows), [r for r in analysis.rows if r.status != Status.PASS]
    table, scene = linear.settings(case), linear.linearised(case)
    assert scene.params == case.params
    eq = linear.equilibrium(scene.model("reference"), 0.0, table["q"], table["v"], table["solve"], case.coords)
    # the orbit stays at the equilibrium, within what shooting leaves: a swing of 1e-11 rad, 1e-10 rad/s
    assert np.allclose(analysis.orbit, eq.state, rtol=0, atol=1e-9)
    period = analysis.period
    for source, monodromy in analysis.monodromy.items():
        model = scene.model(source)
        equations = (linear.derivation_linear(model, source, eq) if source == "reference"
                  else linear.engine_linear(model, source, eq))
        modes = linear.modal(equations)
        expected = np.exp(modes.eigenvalues * period)
        for mu, bound in zip(monodromy.multipliers, monodromy.bounds):
            k = int(np.argmin(np.abs(expected - mu)))
            # exp(lambda T) moves by |exp(lambda T)| T |d lambda|
            allowed = linear.SAFETY * (bound + abs(expected[k]) * period * modes.bounds[k])
            assert abs(mu - expected[k]) <= allowed, (source, mu, expected[k], allowed)


def test_a_wrong_period_fails_and_stops_the_analysis():
    # half the period: the arm's pull, seen from the disk, points the other way
    case = dyncheck.load_case("rotating_pendulum")
    case.spec["vibration"]["floquet"]["period"] = "pi/abs(beta_rate)"
    analysis = floquet.floquet(case)
    assert [r.status for r in analysis.rows] == [Status.FAIL] and analysis.rows[0].quantity.startswith("period T = 4 s")
    assert "is not a period of the equations" in analysis.failure and not analysis.monodromy


def test_a_disk_at_rest_has_no_period_and_is_not_applicable():
    analysis = floquet.floquet(dyncheck.load_case("rotating_pendulum", beta_rate=0.0))
    assert [r.status for r in analysis.rows] == [Status.NOT_APPLICABLE] and "no period" in analysis.rows[0].detail


@pytest.mark.parametrize("edit, message", [
    (("q = [0.06]", "q = [0.06, 0.0]"), "vibration.floquet.q has 2 entries"),
    (("v = [0.0]\nperiods = 1", "v = []\nperiods = 1"), "vibration.floquet.v has 0 entries"),
    (('period = "2*pi/abs(beta_rate)"', 'period = "2*pi/abs(beta_rat)"'),
     "vibration.floquet.period = '2*pi/abs(beta_rat)' names beta_rat, not a parameter"),
    (('period = "2*pi/abs(beta_rate)"', 'period = "2*pi/"'), "vibration.floquet.period = '2*pi/' is not an expression"),
])
def test_a_bad_floquet_table_is_refused_naming_its_field(tmp_path, edit, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        linear.validate(edited_case(tmp_path, CASES / "rotating_pendulum", ("case.toml", *edit)))


@pytest.mark.parametrize("edit, message", [
    (("periods = 1", "periods = 0"), "vibration.floquet.periods"),
    (("amplitude = 2e-4", "amplitude = -2e-4"), "vibration.floquet.amplitude"),
])
def test_a_bad_floquet_number_is_refused_on_load(tmp_path, edit, message):
    with pytest.raises(ValueError, match=message):
        edited_case(tmp_path, CASES / "rotating_pendulum", ("case.toml", *edit))


def test_a_disk_rate_whose_period_mujocos_step_does_not_divide_is_still_run():
    """--set beta_rate=20: T = 2 pi / 20 s is no whole number of the case's 1e-4 s steps; MuJoCo's stroboscopic run
    takes the longest step below it that divides T, and its row is judged like the others'."""
    analysis = floquet.floquet(dyncheck.load_case("spring_pendulum", beta_rate=20.0))
    rows = [r for r in analysis.rows if r.quantity.startswith("largest Floquet multiplier")]
    assert [r.sources for r in rows] == [("reference",), ("pinocchio",), ("mujoco",)]
    assert all(r.status == Status.PASS for r in rows), rows
