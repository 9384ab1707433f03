"""Pinocchio on a case's MJCF (issue 13: a case may bring scene.xml without scene.urdf), and both engines'
mass matrix in the case's coordinates."""

from dataclasses import replace

import mujoco
import numpy as np
import pytest

import dyncheck
from dyncheck.case.scene import Coordinates, Driven, Scene, compare_scenes
from dyncheck.checks.pointwise import compare, evaluate
from engines.mujoco_adapter import MujocoModel
from engines.pinocchio_adapter import PinocchioModel

NAMES = dyncheck.case_names()
WITH_COORDS = [name for name in NAMES if dyncheck.load_case(name).coords]


def pinocchio_on_mjcf(case):
    path = case.folder / "scene.xml"
    return PinocchioModel(path, case.scene, case.writes(PinocchioModel, path))


class WithModel:
    """The case, with `model` answering every source with one given model (for dyncheck.checks.runs.evaluate)."""

    def __init__(self, case, model):
        self.case, self._model = case, model

    def model(self, source):
        return self._model

    def __getattr__(self, name):
        return getattr(self.case, name)


def differences(case, count=20):
    """{quantity: error as the pointwise check measures it} between Pinocchio on scene.urdf and on scene.xml."""
    states = case.sample_states()[:count]
    return compare(case, evaluate(case, "pinocchio", states),
                   evaluate(WithModel(case, pinocchio_on_mjcf(case)), "pinocchio", states))


# -- Pinocchio on the MJCF ---------------------------------------------------------------------------

@pytest.mark.parametrize("name, overrides", [(name, {}) for name in NAMES] + [
    ("double_pendulum", {"g": 3.7}), ("spring_pendulum", {"k": 150.0}), ("spinning_top", {"m": 0.6, "Izz": 0.0021})])
def test_pinocchio_on_the_mjcf_agrees_with_pinocchio_on_the_urdf(name, overrides):
    """Accelerations, reactions, energy, drive power and points, relative to the largest magnitude, within the
    case's pointwise tolerance.  Measured worst: 4.0e-11 double_pendulum theta1_acc, 2.1e-11 spring_pendulum
    psi_acc (the MJCF's placeholder masses and inertias, which the URDF has not), 3e-12 and below elsewhere."""
    case = dyncheck.load_case(name, **overrides)
    errors = differences(case)
    assert {q: e for q, e in errors.items() if not e <= case.tolerance["pointwise"]["value"]} == {}


@pytest.mark.parametrize("name", NAMES)
def test_the_mjcf_models_the_same_scene_in_both_engines(name):
    """Pinocchio's reading of scene.xml (with what the adapter adds: gravity, springs, armature) passes the
    scene comparison against MuJoCo's, and the bindings read back the case's values."""
    case = dyncheck.load_case(name)
    model = pinocchio_on_mjcf(case)
    compare_scenes(case.model("mujoco"), model, name)
    for binding in case.bindings:
        assert model.read(binding.location) == pytest.approx(case.params[binding.param] * binding.scale,
                                                             rel=1e-14), binding


def test_the_evaluation_models_armature_is_mujocos():
    """None on the prescribed joints; the top's ball-joint armature (-1e-5 kg m^2) held in its inertia, where
    the URDF has the book's inertia about the tip."""
    for name in NAMES:
        assert not pinocchio_on_mjcf(dyncheck.load_case(name)).m.armature.any(), name
    top = dyncheck.load_case("spinning_top")
    (mjcf,), (urdf,) = pinocchio_on_mjcf(top).tree(), top.model("pinocchio").tree()
    assert np.allclose(mjcf.inertia, urdf.inertia, rtol=0, atol=1e-17)


def test_gravity_comes_from_the_file():
    """Pinocchio's MJCF parser gives every scene (0, 0, -9.81); the book's double pendulum falls along -Y."""
    case = dyncheck.load_case("double_pendulum")
    assert pinocchio_on_mjcf(case).gravity.tolist() == [0.0, -9.81, 0.0]


def scratch(tmp_path, body, head=""):
    path = tmp_path / "scene.xml"
    path.write_text(f'<mujoco>{head}<worldbody>{body}</worldbody></mujoco>')
    return path


def hinges(path):
    """Pinocchio on a scratch scene whose joints are all hinges, each a coordinate."""
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
             for m in [mujoco.MjModel.from_xml_path(str(path))] for j in range(m.njnt)]
    scene = Scene(tuple(names), tuple(Coordinates("scalar", j, (i,)) for i, j in enumerate(names)), driven={},
                  applied={}, reactions={}, points={})
    return PinocchioModel(path, scene)


BODY = '<body name="{0}" {1}><joint name="j{0}" axis="0 0 1" {2}/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>{3}</body>'


def test_joint_stiffness_follows_mjcfs_default_classes(tmp_path):
    """Own attribute, the joint's class, the enclosing childclass, "main", and classes inheriting: MuJoCo's."""
    head = ('<default><joint stiffness="7"/><default class="soft"><joint stiffness="11"/>'
            '<default class="softer"/></default><default class="none"><joint stiffness="0"/></default></default>')
    inner = BODY.format("c", "", "", BODY.format("d", "", 'class="softer"', BODY.format("e", "", 'class="none"', "")))
    body = BODY.format("a", "", "", BODY.format("b", 'childclass="soft"', 'stiffness="3"', inner))
    path = scratch(tmp_path, body, head)
    model, compiled = hinges(path), mujoco.MjModel.from_xml_path(str(path))
    stiffness = {body.joint: body.stiffness[0] for body in model.tree()}
    assert stiffness == {"ja": 7.0, "jb": 3.0, "jc": 11.0, "jd": 11.0, "je": 0.0}
    assert list(stiffness.values()) == compiled.jnt_stiffness.tolist()


@pytest.mark.parametrize("head, body, refused", [
    ('<compiler eulerseq="XYZ"/>', BODY.format("a", 'euler="30 40 50"', "", ""), 'eulerseq="XYZ"'),
    ("", BODY.format("a", 'axisangle="1 1 0 60"', "", ""), 'axisangle="1 1 0 60"'),
    ("", BODY.format("a", "", 'stiffness="1 0 2"', ""), 'stiffness="1 0 2"'),
    ('<include file="more.xml"/>', BODY.format("a", "", "", ""), '<include file="more.xml">'),
    ("", BODY.format("a", "", "", "") + BODY.format("b", "", "", ""), "<worldbody> holds 2 bodies")])
def test_what_pinocchios_parser_misreads_is_refused(tmp_path, head, body, refused):
    """MuJoCo compiles these; Pinocchio's parser reads them otherwise (a rotation about moving axes, a rotation
    matrix that is none, a linear spring, nothing, the first of two bodies on the world only): refused with the
    file and the attribute named."""
    (tmp_path / "more.xml").write_text('<mujoco><option timestep="0.001"/></mujoco>')
    path = scratch(tmp_path, body, head)
    mujoco.MjModel.from_xml_path(str(path))
    with pytest.raises(ValueError, match=f"{path}: .*{refused}"):
        hinges(path)


# -- the mass matrix in the case's coordinates -------------------------------------------------------

def engines(case):
    return case.model("mujoco"), case.model("pinocchio"), pinocchio_on_mjcf(case)


@pytest.mark.parametrize("name", NAMES)
def test_the_engines_mass_matrices_agree_and_are_symmetric(name):
    """MuJoCo, Pinocchio on the URDF and on the MJCF, within 1e-9 of the largest entry (measured: 8.9e-12
    double pendulum, the placeholder inertias; 1e-12 and below elsewhere), and symmetric."""
    case = dyncheck.load_case(name)
    for t, q, v in case.sample_states()[:10]:
        matrices = [model.mass_matrix(t, q, v) for model in engines(case)]
        assert all(m.shape == (len(case.coords),) * 2 for m in matrices)
        if not case.coords:  # every joint prescribed (piston, rotating particle)
            continue
        scale = np.max(np.abs(matrices[0]))
        for m in matrices:
            assert np.max(np.abs(m - matrices[0])) <= 1e-9 * scale
            assert np.max(np.abs(m - m.T)) <= 1e-15 * scale


def frozen(case, t):
    """The case's scene with its prescribed motions stopped where they are at time t."""
    driven = {j: Driven(law.at(t), 0.0, 0.0) for j, law in case.scene.driven.items()}
    return replace(case.scene, driven=driven)


@pytest.mark.parametrize("name", WITH_COORDS)
def test_the_mass_matrix_gives_the_kinetic_energy(name):
    """T = E(q, v) - E(q, 0) = v^T M v / 2 with the prescribed motions stopped (their rates would add terms
    linear in v), the case's Euler-angle rates included (the top).  Rounding: E is a sum of a few dozen terms,
    the potential much larger than T where v is small: 1e-12 of the largest energy."""
    case = dyncheck.load_case(name)
    for t, q, v in case.sample_states()[:10]:
        scene = frozen(case, t)
        for Model, path in ((MujocoModel, case.folder / "scene.xml"), (PinocchioModel, case.folder / "scene.urdf"),
                            (PinocchioModel, case.folder / "scene.xml")):
            model = Model(path, scene, case.writes(Model, path))
            moving, still = model.energy(t, q, v), model.energy(t, q, np.zeros_like(v))
            kinetic = 0.5 * v @ model.mass_matrix(t, q, v) @ v
            assert abs(moving - still - kinetic) <= 1e-12 * max(abs(moving), abs(still)), (path, t)


def test_the_tops_mass_matrix_is_its_euler_equations():
    """In the top's Euler angles (precession p, nutation n, spin s) its kinetic energy about the tip O is
    (Ixx (p'^2 sin^2 n + n'^2) + Izz (p' cos n + s')^2) / 2 with the book's inertias about O: M is its Hessian
    in the rates."""
    top = dyncheck.load_case("spinning_top")
    Ixx, Izz = top.params["Ixx"], top.params["Izz"]
    for t, q, v in top.sample_states()[:5]:
        n = q[1]
        expected = np.array([[Ixx * np.sin(n) ** 2 + Izz * np.cos(n) ** 2, 0.0, Izz * np.cos(n)],
                             [0.0, Ixx, 0.0],
                             [Izz * np.cos(n), 0.0, Izz]])
        for model in engines(top):
            assert np.allclose(model.mass_matrix(t, q, v), expected, rtol=0, atol=1e-14 * Ixx)
