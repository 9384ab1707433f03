"""Engines against the reference, with default and overridden parameters, and the scene-file guard."""

import shutil

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import dyncheck
from dyncheck.case import Case
from dyncheck.checks import compare, evaluate

TOL = 1e-9  # the cases' pointwise tolerance (see case.toml for its derivation)


def assert_engines_agree(case, count=10):
    states = case.sample_states()[:count]
    ref = evaluate(case, "reference", states)
    for engine in ("mujoco", "pinocchio"):
        for quantity, error in compare(case, ref, evaluate(case, engine, states)).items():
            assert error <= TOL, (case, engine, quantity, error)


@settings(max_examples=8, deadline=None)
@given(k=st.floats(50.0, 5000.0), m=st.floats(0.05, 2.0), b=st.floats(0.1, 1.0), r=st.floats(0.02, 0.3),
       h=st.floats(0.0, 0.3), l0=st.floats(0.05, 0.3), g=st.floats(1.0, 20.0),
       alpha_rate=st.floats(-10.0, 10.0), beta_rate=st.floats(-30.0, 30.0))
def test_spring_pendulum_engines_follow_overrides(**params):
    assert_engines_agree(dyncheck.load_case("spring_pendulum", **params))


# Domains where MuJoCo's placeholder inertia (1e-14 kg m^2, its minimum) stays below 1e-10 of the
# smallest m l^2, as the tolerance's error budget in case.toml assumes; outside it MuJoCo models a
# measurably different body (1.2e-9 at m2 l2^2 = 8.6e-6 kg m^2, found by hypothesis).
@settings(max_examples=8, deadline=None)
@given(m1=st.floats(0.05, 2.0), m2=st.floats(0.05, 2.0), l1=st.floats(0.05, 1.0), l2=st.floats(0.05, 1.0),
       g=st.floats(1.0, 20.0))
def test_double_pendulum_engines_follow_overrides(**params):
    assert_engines_agree(dyncheck.load_case("double_pendulum", **params))


def test_an_override_reaches_every_source():
    """Changing k changes the spring force by the same amount in every source."""
    base, stiff = dyncheck.load_case("spring_pendulum"), dyncheck.load_case("spring_pendulum", k=150.0)
    t, q, v = 0.3, np.array([0.4, 0.02]), np.array([1.0, 0.5])
    for source in ("reference", "book", "mujoco", "pinocchio"):
        change = stiff.model(source).accelerations(t, q, v)[1] - base.model(source).accelerations(t, q, v)[1]
        assert change == pytest.approx((2000.0 - 150.0) / 0.2 * 0.02, rel=1e-9), source


def copy_case(tmp_path, name):
    folder = tmp_path / name
    shutil.copytree(dyncheck.case.CASES_DIR / name, folder)
    return folder


@pytest.mark.parametrize("scene, old, new, message", [
    ("scene.xml", 'mass="0.2"', 'mass="0.25"', "body 'particle' mass[0] is 0.25, but case.toml gives m = 0.2"),
    ("scene.urdf", '<origin xyz="0 0.5 0.05"/>', '<origin xyz="0 0.55 0.05"/>',
     "body 'disk' pos[1] is 0.55, but case.toml gives b = 0.5"),
    ("scene.xml", 'stiffness="2000"', 'stiffness="1500"', "joint 'l' stiffness[0] is 1500.0, but case.toml gives k = 2000.0"),
])
def test_a_scene_that_disagrees_with_its_case_is_refused(tmp_path, scene, old, new, message):
    folder = copy_case(tmp_path, "spring_pendulum")
    text = (folder / scene).read_text()
    assert old in text
    (folder / scene).write_text(text.replace(old, new))
    engine = "mujoco" if scene.endswith(".xml") else "pinocchio"
    with pytest.raises(ValueError, match="spring_pendulum") as error:
        Case(folder).model(engine)
    assert message in str(error.value) and scene in str(error.value)


def test_a_scene_missing_a_joint_is_refused(tmp_path):
    folder = copy_case(tmp_path, "double_pendulum")
    text = (folder / "scene.urdf").read_text().replace('name="theta2"', 'name="phi2"')
    (folder / "scene.urdf").write_text(text)
    with pytest.raises(ValueError, match="no joint named 'theta2'"):
        Case(folder).model("pinocchio")


@pytest.mark.parametrize("overrides, message", [
    ({"kk": 1.0}, "has no parameter 'kk'"),
    ({"k": "stiff"}, "'stiff' is not a number"),
    ({"k": float("nan")}, "is not finite"),
])
def test_bad_overrides_are_named(overrides, message):
    with pytest.raises(ValueError, match=message):
        dyncheck.load_case("spring_pendulum", **overrides)


def test_unknown_case_and_source_are_named():
    with pytest.raises(ValueError, match="unknown case 'pendulum'"):
        dyncheck.load_case("pendulum")
    with pytest.raises(ValueError, match="unknown source 'drake'"):
        dyncheck.load_case("double_pendulum").model("drake")


def test_a_bad_expression_in_a_case_file_is_named(tmp_path):
    folder = copy_case(tmp_path, "spring_pendulum")
    text = (folder / "case.toml").read_text().replace('q = ["pi/6", 0.0]', 'q = ["pi/sixth", 0.0]')
    (folder / "case.toml").write_text(text)
    with pytest.raises(ValueError, match=r"case.toml: cannot evaluate 'pi/sixth': name 'sixth' is not defined"):
        Case(folder).initial


# Overrides that move every kind of parameter of each case away from the book's numbers.
OVERRIDES = {
    "spring_pendulum": dict(k=150.0, b=0.3, l0=0.2, g=3.0, alpha_rate=1.0, beta_rate=-5.0, beta0=0.4),
    "double_pendulum": dict(m1=0.3, m2=0.1, l1=0.2, l2=0.05, g=5.0),
    "rotating_pendulum": dict(l=0.3, m=0.5, alpha_rate=1.0, beta_rate=3.14, h=0.1, r=0.2, g=9.0),
    "rotating_particle": dict(psi=2.5, l=0.25, alpha_rate=-2.0, beta_rate=0.5, b=0.7),
    "piston": dict(m=0.5, L0=0.3, theta_rate=-2.0, theta_acc=1.0, L_rate=-0.05, L_acc=0.2, g=1.6),
    "spinning_top": dict(m=0.6, h=0.05, Ixx=0.003, Izz=0.002, Mz=-0.01, g=9.0),
}


@pytest.mark.parametrize("name", sorted(OVERRIDES))
def test_every_case_agrees_with_overridden_parameters(name):
    assert set(OVERRIDES) == set(dyncheck.case_names())
    case = dyncheck.load_case(name, **OVERRIDES[name])
    assert case.overrides == OVERRIDES[name]
    assert_engines_agree(case, count=20)
