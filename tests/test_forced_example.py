"""The forced cart-pendulum example's steady-state study (examples/forced_cart_pendulum/studies.py): its
table passes at the case's numbers, and an error planted in its linear theory makes it fail."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from dyncheck.case.folder import load_case, settings_of
from dyncheck.studies import stability

pytestmark = pytest.mark.full  # runs of the cases' engines, seconds each: `pytest -m full`

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.fixture(scope="module")
def case():
    return load_case("forced_cart_pendulum", EXAMPLES)


@pytest.fixture
def study(case):
    return stability.case_module(case)


def steady_state(case, study, **changes):
    return study.steady_state(case, {**settings_of(case, "steady_state"), **changes})


def planted(monkeypatch, study, change):
    """The study's linear theory with `change` (LinearTheory -> its replace() keywords) made to it."""
    right = study.linearisation
    monkeypatch.setattr(study, "linearisation",
                        lambda case, step: dataclasses.replace(theory := right(case, step), **change(theory)))


def test_steady_state_passes_at_the_case_numbers(case, study):
    result = steady_state(case, study)
    data = result.data
    assert len(data) == len(case.coords) * (1 + len(settings_of(case, "steady_state")["omegas"]))
    assert list(result.table["status"]) == ["pass"] * len(data)
    here = data[data["Omega"] == case.params["Omega"]].set_index("coordinate")
    # Every source measured, the engines against the derivation at the case's Omega.
    assert here[["derivation", "mujoco", "pinocchio"]].notna().all().all()
    assert here.loc["x", "theory"] == pytest.approx(3.4804e-3, rel=1e-4)  # the linear theory by hand: 3.48041 mm
    # The tolerance is about theta^2 (3e-4 here), not a blanket one that would pass anything.
    assert (here["tolerance"] < 2.5 * here.loc["theta", "theory"] ** 2).all()


def test_forcing_doubled_in_the_theory_fails(case, study, monkeypatch):
    planted(monkeypatch, study, lambda theory: {"F": 2 * theory.F})
    # A shorter settling (1e-4 of the transient left) keeps the test quick; the planted error is 100 %.
    result = steady_state(case, study, settle=1e-4, omegas=[])
    assert set(result.table["status"]) == {"fail"}
    assert np.allclose(result.data["theory_error"], -0.5, atol=1e-3)


def test_a_damper_of_the_wrong_sign_in_the_theory_fails(case, study, monkeypatch):
    hinge = case.coords.index("theta")
    planted(monkeypatch, study, lambda theory: {"C": theory.C * np.where(np.arange(len(case.coords)) == hinge, -1, 1)})
    result = steady_state(case, study)
    assert set(result.table["status"]) == {"fail (the linear theory has no steady state: a mode grows at 0.536 1/s)"}
    assert "nothing was run" in result.findings[0]
