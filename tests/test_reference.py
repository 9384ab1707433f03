"""The reference equations against themselves: derivations the modules claim."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import dyncheck

angle = st.floats(-np.pi, np.pi)
rate = st.floats(-20.0, 20.0)


@given(q=st.tuples(angle, angle), v=st.tuples(rate, rate))
def test_double_pendulum_closed_forms_equal_the_newton_equations(q, v):
    """(1.29)-(1.32) from the Pascal listing solve (1.27)-(1.28): agreement to rounding of a 4x4 solve."""
    case = dyncheck.load_case("double_pendulum")
    book, ref = case.model("book"), case.model("reference")
    scale_acc = 1e4  # rad/s^2: g / l1 (m2/m1 + 1) + rates^2, the largest terms for these ranges
    np.testing.assert_allclose(book.accelerations(0, q, v), ref.accelerations(0, q, v), rtol=0, atol=1e3 * np.finfo(float).eps * scale_acc)
    for name in ("T1", "T2"):
        assert abs(book.reactions(0, q, v)[name] - ref.reactions(0, q, v)[name]) < 1e3 * np.finfo(float).eps * 1e2


@settings(max_examples=50)
@given(q=st.tuples(angle, st.floats(-0.05, 0.05)), v=st.tuples(rate, st.floats(-2.0, 2.0)), t=st.floats(0.0, 3.0))
def test_spring_pendulum_book_and_reference_differ_by_one_coriolis_term(q, v, t):
    """The finding 1.8.3-R, derived: R_book - R_ref = m L psi' Omega cos(psi); the equations of motion agree."""
    case = dyncheck.load_case("spring_pendulum")
    p = case.params
    book, ref = case.model("book"), case.model("reference")
    # Reference evaluates the book's method numerically: rounding of a few hundred operations on
    # terms up to k/m l + L Omega^2 ~ 1e3 m/s^2 (psi'': that divided by L >= 0.05 m).
    eps = np.finfo(float).eps
    np.testing.assert_allclose(book.accelerations(t, q, v), ref.accelerations(t, q, v), rtol=0,
                               atol=1e3 * eps * 1e3 / 0.05)
    expected = p["m"] * (p["l0"] + q[1]) * v[0] * (p["alpha_rate"] + p["beta_rate"]) * np.cos(q[0])
    difference = book.reactions(t, q, v)["R"] - ref.reactions(t, q, v)["R"]
    assert abs(difference - expected) <= 1e3 * eps * 1e2  # |R| terms up to m (b alpha'^2 + 2 L psi' Omega) ~ 1e2 N


def energy_rate(model, t, q, v, h=1e-6):
    """dE/dt along the model's own motion, by central differences (error ~ h^2 E''' ~ 1e-9 here)."""
    a = model.accelerations(t, q, v)
    e = lambda s: model.energy(t + s, q + s * v + 0.5 * s**2 * a, v + s * a)
    return (e(h) - e(-h)) / (2 * h)


def test_reference_energy_rate_equals_drive_power():
    """Energy, drive power and accelerations of `reference` are consistent: dE/dt = P_drive."""
    for name in ("spring_pendulum", "double_pendulum"):
        case = dyncheck.load_case(name)
        ref = case.model("reference")
        for t, q, v in case.sample_states()[:20]:
            power = ref.drive_power(t, q, v)
            scale = abs(power) + abs(ref.energy(t, q, v)) * 100.0  # E / (10 ms): the size of dE/dt terms
            assert abs(energy_rate(ref, t, q, v) - power) < 1e-6 * scale, (name, t, q, v)


# PRINTED entries no model method evaluates: the book's Y2 row, which the run evaluates against the finding's
# right side (dyncheck.checks.right_sides), while the model checks the row term by term (Book.printed_rows).
ROW_ONLY = {("spinning_top", "Euler Y2 (1.10)")}


@pytest.mark.parametrize("name", ["piston", "double_pendulum", "spinning_top"])
def test_every_printed_expression_is_the_code_that_runs(name, monkeypatch):
    """The formulas the student's page typesets are what the models evaluate: doubling any one PRINTED entry changes
    what the book's or the reference's model computes (or the listing's run, which uses the book's formulas)."""
    case = dyncheck.load_case(name)
    book_class = case.derivation.Book
    states = case.sample_states()[:3]

    def outputs():
        values = []
        for source in ("book", "reference"):
            model = case.model(source)
            for t, q, v in states:
                values += [model.accelerations(t, q, v), list(model.reactions(t, q, v).values()),
                           *model.point_accelerations(t, q, v).values(), model.energy(t, q, v)]
        return np.concatenate([np.ravel(np.asarray(x, float)) for x in values])

    before = outputs()
    tables = [vars(cls)["PRINTED"] for cls in (case.derivation.Book, case.derivation.Reference)
              if "PRINTED" in vars(cls)]
    for key, expression in book_class.PRINTED.items():
        if (name, key) in ROW_ONLY:
            continue
        with monkeypatch.context() as patch:  # in the Book's table and the Reference's it copies
            for table in tables:
                if table.get(key) == expression:
                    patch.setitem(table, key, f"2*({expression})")
            assert not np.array_equal(outputs(), before), f"{name}: Book.PRINTED[{key!r}] is evaluated by no model"
