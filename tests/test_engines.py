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


def parameter_ranges(name):
    """The case's physically valid parameter ranges ([sample.params.ranges]), as numbers."""
    case = dyncheck.load_case(name)
    return {k: (case.value(lo), case.value(hi)) for k, (lo, hi) in case.spec["sample"]["params"]["ranges"].items()}


@pytest.mark.parametrize("name", dyncheck.case_names())
def test_engines_follow_random_valid_parameters(name):
    """Property: at any parameters in the case's valid ranges, reference and both engines agree.
    The ranges keep m l^2 >= 1e-4 kg m^2: below it MuJoCo's placeholder inertia (1e-14 kg m^2) makes
    a measurably different body (1.2e-9 at m2 l2^2 = 8.6e-6, found by hypothesis)."""
    ranges = parameter_ranges(name)

    @settings(max_examples=6, deadline=None)
    @given(st.fixed_dictionaries({k: st.floats(lo, hi) for k, (lo, hi) in ranges.items()}))
    def agree(params):
        case = dyncheck.load_case(name, **params)
        assert case.overrides == params
        assert_engines_agree(case)

    agree()


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
