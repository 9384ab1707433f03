"""Engines against the reference, with default and overridden parameters, and the scene-file guard."""

import copy
import shutil
from pathlib import Path

import mujoco
import mujoco.rollout
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import dyncheck
from dyncheck.case.folder import CASES_DIR, Case
from dyncheck.checks.pointwise import compare, evaluate
from engines import euler, mujoco_adapter

EXAMPLES = Path(__file__).parent.parent / "examples"
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
    shutil.copytree(dyncheck.case.folder.CASES_DIR / name, folder)
    return folder


@pytest.mark.parametrize("scene, old, new, message", [
    ("scene.xml", 'mass="0.2"', 'mass="0.25"', "body 'particle' mass is 0.25, but case.toml gives m = 0.2"),
    ("scene.urdf", '<origin xyz="0 0.5 0.05"/>', '<origin xyz="0 0.55 0.05"/>',
     "body 'disk' pos[1] is 0.55, but case.toml gives b = 0.5"),
    ("scene.xml", 'stiffness="2000"', 'stiffness="1500"', "joint 'l' stiffness is 1500.0, but case.toml gives k = 2000.0"),
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


def top_states(count=8):
    """(quaternion (w, x, y, z), body angular velocity) pairs of the top, upright ones among them."""
    rng = np.random.default_rng(3)
    quaternions = np.vstack([[1.0, 0.0, 0.0, 0.0], euler.quaternion([0.3, 1e-9, 2.0]), rng.normal(size=(count, 4))])
    quaternions /= np.linalg.norm(quaternions, axis=1)[:, None]
    return list(zip(quaternions, rng.uniform(-50, 50, (len(quaternions), 3))))


def top_applied(case):
    return np.array([0.0, 0.0, case.params["Mz"]])  # case.toml's [scene] applied: Mz about the top's axis


def assert_close(engine, adapter):
    # The same engine call on the same numbers: equal to rounding.
    np.testing.assert_allclose(adapter, engine, rtol=0, atol=1e-12 * max(1.0, np.max(np.abs(engine))))


def test_mujoco_ball_joint_acceleration_is_mj_forward():
    case = dyncheck.load_case("spinning_top")
    m = mujoco.MjModel.from_xml_path(str(case.folder / "scene.xml"))
    d = mujoco.MjData(m)
    for quaternion, omega in top_states():
        d.qpos[:], d.qvel[:], d.qfrc_applied[:] = quaternion, omega, top_applied(case)
        mujoco.mj_forward(m, d)
        assert_close(d.qacc, case.model("mujoco").ball_joint_acceleration(quaternion, omega))


def test_pinocchio_ball_joint_acceleration_is_aba():
    case = dyncheck.load_case("spinning_top")
    m = pin.buildModelFromUrdf(str(case.folder / "scene.urdf"), pin.JointModelSpherical(), "tip")
    m.gravity.linear[:] = [0.0, 0.0, -case.params["g"]]  # URDF has no gravity
    d = m.createData()
    for quaternion, omega in top_states():
        acc = pin.aba(m, d, np.roll(quaternion, -1), omega, top_applied(case))  # Pinocchio's (x, y, z, w)
        assert_close(acc, case.model("pinocchio").ball_joint_acceleration(quaternion, omega))


def test_mujoco_ball_joint_quaternions_are_mujoco_rollout():
    case = dyncheck.load_case("spinning_top")
    q0, v0, _ = case.initial
    dt, nstep = case.integration["mujoco_step"], 200
    m = mujoco.MjModel.from_xml_path(str(case.folder / "scene.xml"))
    m.opt.timestep, m.opt.integrator = dt, mujoco.mjtIntegrator.mjINT_RK4
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = euler.quaternion(q0), euler.angular_velocity(q0, v0)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    start = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, start, spec)
    states, _ = mujoco.rollout.rollout(m, d, start[None], top_applied(case)[None, None], nstep=nstep,
                                       control_spec=mujoco.mjtState.mjSTATE_QFRC_APPLIED)
    quaternions = case.model("mujoco").ball_joint_quaternions(q0, v0, nstep * dt, dt, "RK4")
    assert quaternions.shape == (nstep + 1, 4)
    assert_close(np.vstack([start, states[0]])[:, 1:1 + m.nq], quaternions)  # time, qpos, qvel, ...


SKIPPED = {"constraint": int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT), "sensor": int(mujoco.mjtDisableBit.mjDSBL_SENSOR)}


@pytest.mark.parametrize("name, folder", [(name, CASES_DIR) for name in dyncheck.case_names()]
                         + [(name, EXAMPLES) for name in ("slider_crank", "forced_cart_pendulum")])  # a loop; laws
def test_mujoco_skips_only_stages_that_change_no_number(name, folder, monkeypatch):
    """MuJoCo's runs skip their sensors, and a scene without loops skips the constraint stage in its runs and its
    evaluations: a run, and the drive power, reactions and energy at its states, are those of the scene with every
    stage on, to the bit."""
    case = dyncheck.load_case(name, folder)
    q0, v0, _ = case.initial
    dt = case.integration["mujoco_step"]
    model = case.model("mujoco")
    assert bool(model.m.opt.disableflags & SKIPPED["constraint"]) == (not model.loops.loops)
    plain = copy.copy(model)
    plain.m = copy.copy(model.m)
    plain.m.opt.disableflags &= ~SKIPPED["constraint"]
    plain.d = mujoco.MjData(plain.m)

    def every_stage(*args):
        m, d, start, forces = model.stepping(*args)
        assert m.opt.disableflags & SKIPPED["sensor"]
        m.opt.disableflags &= ~(SKIPPED["constraint"] | SKIPPED["sensor"])
        return m, d, start, forces

    monkeypatch.setattr(plain, "stepping", every_stage)
    run, plain_run = (source._rollout(q0, v0, 200 * dt, dt, "RK4") for source in (model, plain))
    t, qpos, qvel = run[:3]
    np.testing.assert_array_equal(qpos, plain_run[1])
    np.testing.assert_array_equal(qvel, plain_run[2])
    q, v = model._book_states(qpos, qvel, q0)
    np.testing.assert_array_equal(model.drive_powers(t, q, v), plain.drive_powers(t, q, v))
    np.testing.assert_array_equal(model.energy_many(t, q, v), plain.energy_many(t, q, v))
    reactions, plain_reactions = model.reactions_many(t, q, v), plain.reactions_many(t, q, v)
    for name in case.scene.reactions:
        np.testing.assert_array_equal(reactions[name], plain_reactions[name], err_msg=name)


def test_a_kept_closure_of_the_loops_gives_the_numbers_of_a_fresh_one(monkeypatch):
    """A scene with loops keeps its last closures from the assembly (`_assembled`): a state's quantities, with some
    closures kept and some dropped, are a fresh model's, to the bit; the oldest is dropped first."""
    monkeypatch.setattr(mujoco_adapter, "CLOSURES", 3)
    case = dyncheck.load_case("slider_crank", EXAMPLES)
    states = case.sample_states()[:5]
    model = case.model("mujoco")
    values = lambda x: np.array(list(x.values()) if isinstance(x, dict) else x)
    for quantity in ("accelerations", "reactions", "energy", "drive_power"):
        for state in states:
            kept, fresh = (getattr(source, quantity)(*state) for source in (model, case.with_params().model("mujoco")))
            np.testing.assert_array_equal(values(kept), values(fresh), err_msg=quantity)
    closures, close = [], model.loops.close

    def counted(*args):
        closures.append(args)
        return close(*args)

    monkeypatch.setattr(model.loops, "close", counted)
    model.energy(*states[2])  # kept (the last three: 2, 3, 4)
    assert not closures
    model.energy(*states[1])  # dropped
    assert len(closures) == 1 and len(model._closures) == 3


@pytest.mark.parametrize("engine", ["mujoco", "pinocchio"])
def test_ball_joint_methods_refuse_a_scene_of_other_joints(engine):
    model = dyncheck.load_case("piston").model(engine)
    with pytest.raises(ValueError, match=r"scene\.(xml|urdf): ball_joint_acceleration needs a scene whose only joint"):
        model.ball_joint_acceleration(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3))
