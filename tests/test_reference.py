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
# right side (dyncheck.checks.runs.right_sides), while the model checks the row term by term (Book.printed_rows).
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


@pytest.mark.parametrize("name", ["rotating_particle", "rotating_pendulum", "spring_pendulum"])
def test_the_remembered_state_is_the_state_asked(name):
    """ParticleOnBase._at remembers the last state's motion (accelerations, then drive power, at one state): the same
    state given as arrays or lists is the one calculation, and another state, or the first again, is not stale."""
    case = dyncheck.load_case(name)
    model = case.model("reference")
    states = case.sample_states(3)
    plain = [model._motion(float(t), [float(x) for x in q], [float(x) for x in v]) for t, q, v in states]
    for (t, q, v), expected in zip(states + states[:1], plain + plain[:1]):
        got = model._at(t, q, v)
        assert model._at(float(t), list(q), list(v)) is got  # remembered: no second calculation
        np.testing.assert_array_equal(np.hstack([np.ravel(x) for x in got]), np.hstack([np.ravel(x) for x in expected]))


def test_the_sample_s_first_states_do_not_depend_on_how_many_are_drawn():
    case = dyncheck.load_case("spinning_top")
    first, every = case.sample_states(7), case.sample_states()
    assert len(first) == 7 and len(every) == case.spec["sample"]["count"]
    for a, b in zip(first, every):
        np.testing.assert_array_equal(np.hstack(a), np.hstack(b))


@pytest.mark.parametrize("source", ["book", "reference"])
def test_the_piston_s_force_is_newton_s_law_with_the_acceleration_of_its_route(source):
    """_force evaluates only the acceleration its route takes: the same numbers as point_accelerations gives for it."""
    case = dyncheck.load_case("piston")
    model, p = case.model(source), case.params
    for t, q, v in case.sample_states(5):
        a = model.point_accelerations(t, q, v)[model._reaction_route]
        expected = p["m"] * a + np.array([0.0, 0.0, p["m"] * p["g"]])
        assert list(model.reactions(t, q, v).values()) == expected.tolist()


def test_the_double_pendulum_book_s_tensions_are_the_listing_s():
    """Book.reactions evaluates (1.29)-(1.30) alone: the same numbers as the listing's four expressions give."""
    case = dyncheck.load_case("double_pendulum")
    book, program = case.model("book"), case.model("program")
    for t, q, v in case.sample_states(10):
        assert book.reactions(t, q, v) == program.reactions(t, q, v)


def test_a_listing_that_overflows_says_so_in_words():
    # at 10 times the book's stiffness the 1.8.3 listing's explicit Euler squares a huge rate: Python's OverflowError
    # reached the row as "(34, 'Numerical result out of range')"
    case = dyncheck.load_case("spring_pendulum", k=20000.0)
    q0, v0, _ = case.initial
    with pytest.raises(FloatingPointError, match=r"unstable: its state grew beyond floats \(Numerical result out of "
                                                 r"range\) at t = 2\.0773 s \(step 41547\)$"):
        case.model("program").run(q0, v0)
