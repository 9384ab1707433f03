"""Drake (engines/drake_adapter.py) against MuJoCo's adapter on every scene of cases/ and examples/, and each
behaviour of Drake's MJCF and URDF parser that the adapter corrects or refuses (issue 39, docs/drake.md).

The tolerance, 1e-12 of the largest magnitude of each quantity over the sample: both engines evaluate the same
rigid-body recursions over at most four bodies (Drake's CRBA and RNEA, MuJoCo's), a few hundred operations per
number, each rounding by eps = 2.2e-16 of the terms it sums; those terms (gravity against the inertial forces, the
prescribed joints' fast rates) are up to ~10 times the result's scale, and a coordinate's acceleration goes through
one solve of the free block (condition below ~1e2 here): 100 eps x 10 x 10 ~ 2e-12 is the ceiling of this estimate,
and its typical value a tenth of that.  Measured worst (20 states each, pydrake 1.51.1 against MuJoCo 3.x): 8.6e-15
(the double pendulum's a_A), 5e-15 and below elsewhere (the slider-crank's loop force, through the loop's solve,
4.2e-15): 1e-12 leaves a margin of 100.  A difference of a modelled element (a spring, an armature, a parent's axes)
is 1e-3 or more: far above.
"""

import math
import shutil
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np
import pytest

pytest.importorskip("pydrake", reason="Drake is an optional extra: pip install -e '.[drake]'")

import dyncheck  # noqa: E402
from dyncheck.checks import linear  # noqa: E402
from dyncheck.case.scene import Coordinates, Driven, Reaction, Scene  # noqa: E402
from engines.bindings import SceneLocation  # noqa: E402
from engines.coordinates import case_accelerations  # noqa: E402
from engines.drake_adapter import DrakeModel, Refused  # noqa: E402
from engines.mujoco_adapter import MujocoModel  # noqa: E402
from engines.pinocchio_adapter import PinocchioModel  # noqa: E402
from pydrake.multibody.parsing import Parser  # noqa: E402
from pydrake.multibody.plant import MultibodyPlant  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SCENES = [(name, ROOT / "cases") for name in dyncheck.case_names()] + \
         [(name, ROOT / "examples") for name in dyncheck.case_names(ROOT / "examples")]
RTOL = 1e-12


def drake(case, file="scene.xml"):
    path = case.folder / file
    return DrakeModel(path, case.scene, case.writes(DrakeModel, path))


def quantities(model, case, t, q, v):
    """{name: array} of what the model interface gives at one state, and the equations' f = M q''."""
    acc, mass = model.accelerations(t, q, v), model.mass_matrix(t, q, v)
    out = {"acc": acc, "M": mass, "f = M q''": mass @ acc, "energy": [model.energy(t, q, v)],
           **{f"reaction {k}": [x] for k, x in model.reactions(t, q, v).items()}}
    if case.driven:
        out["drive power"] = [model.drive_power(t, q, v)]
    if case.scene.points:
        out.update({f"point {k}": x for k, x in model.point_accelerations(t, q, v).items()})
    if case.scene.dependent:
        positions, rates = model.dependent(t, q, v)
        out.update({f"dependent {k}": [positions[k], rates[k]] for k in positions})
    return out


def disagreement(first, second, states, case):
    """{quantity: largest difference relative to the quantity's largest magnitude over the states}."""
    pairs = [(quantities(first, case, *s), quantities(second, case, *s)) for s in states]
    out = {}
    for name in pairs[0][0]:
        a = np.array([np.ravel(x[name]) for x, _ in pairs])
        b = np.array([np.ravel(y[name]) for _, y in pairs])
        scale = max(np.max(np.abs(a), initial=0.0), np.max(np.abs(b), initial=0.0))
        out[name] = float(np.max(np.abs(a - b), initial=0.0) / scale) if scale else 0.0
    return out


@pytest.mark.parametrize("name, folder", SCENES, ids=[name for name, _ in SCENES])
def test_drake_agrees_with_mujoco_on_every_scene(name, folder):
    """M, f = M q'', q'', the reactions, the energy, the drive power, the points and the dependent joints at the
    case's random states (a scene without coordinates, every joint prescribed: reactions, energy and power)."""
    case = dyncheck.load_case(name, folder)
    errors = disagreement(case.model("mujoco"), drake(case), case.sample_states()[:20], case)
    assert errors and {k: e for k, e in errors.items() if not e <= RTOL} == {}


@pytest.mark.parametrize("name, overrides", [("double_pendulum", {"g": 3.7}), ("spring_pendulum", {"k": 150.0}),
                                             ("spinning_top", {"m": 0.6, "Izz": 0.0021}),
                                             ("rotating_pendulum", {"l": 0.13, "m": 0.3})])
def test_drake_takes_the_case_parameters(name, overrides):
    """A case's overrides written into Drake's context (gravity, masses, lengths, a spring, an inertia about the
    origin less a ball joint's armature): the same agreement, and the bindings read back."""
    case = dyncheck.load_case(name, **overrides)
    model = drake(case)
    errors = disagreement(case.model("mujoco"), model, case.sample_states()[:8], case)
    assert {k: e for k, e in errors.items() if not e <= RTOL} == {}
    for binding in case.bindings:
        assert model.read(binding.location) == pytest.approx(case.params[binding.param] * binding.scale,
                                                             rel=1e-14), binding


def test_drakes_tree_is_mujocos():
    """The bodies as Drake holds them pass the scene comparison against MuJoCo's, the top's armature counted in
    its inertia as MuJoCo's tree counts it."""
    from dyncheck.case.scene import compare_scenes
    for name, folder in SCENES:
        case = dyncheck.load_case(name, folder)
        compare_scenes(case.model("mujoco"), drake(case), name)


# -- each behaviour of Drake's parser ---------------------------------------------------------------

def scratch(tmp_path, body, head=""):
    path = tmp_path / "scene.xml"
    path.write_text(f'<mujoco model="scratch">{head}<worldbody>{body}</worldbody></mujoco>')
    return path


def hinge_scene(names, euler=None, driven=()):
    """A scene of hinge coordinates (and a ball joint's Euler angles `euler`: (joint, three coordinate names))."""
    coords = [n for n in names if n not in driven] + (list(euler[1]) if euler else [])
    layout = [Coordinates("scalar", j, (coords.index(j),)) for j in names if j not in driven]
    if euler:
        layout.append(Coordinates("euler", euler[0], tuple(coords.index(c) for c in euler[1])))
    return Scene(tuple(coords), tuple(layout), driven={j: Driven(0.3, 2.0, 0.5) for j in driven}, applied={},
                 reactions={}, points={})


def states(n, count=8, seed=3):
    rng = np.random.default_rng(seed)
    return [(float(rng.uniform(0, 1)), rng.uniform(-1.5, 1.5, n), rng.uniform(-2, 2, n)) for _ in range(count)]


def raw_mujoco(path, t, q, v):
    """MuJoCo's own qacc, M and energy at (q, v) of a scene of hinges, nothing imposed."""
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = q, v
    mujoco.mj_forward(m, d)
    mass = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, mass)
    mujoco.mj_energyPos(m, d)
    mujoco.mj_energyVel(m, d)
    return d.qacc.copy(), mass, d.energy[0] + d.energy[1]


LINK = ('<body name="{0}" pos="{1}"><joint name="{0}" axis="{2}" {3}/>'
        '<inertial pos="0.1 0.05 -0.2" mass="{4}" diaginertia="0.01 0.02 0.015"/>{5}</body>')


def test_armature_is_added_where_drakes_parser_drops_it(tmp_path):
    """Drake keeps armature only as a motor's rotor inertia: without a motor its plant has none.  The adapter adds
    it to M (and a v^2 / 2 to the energy): M, q'' and the energy equal MuJoCo's own (whose adapter refuses armature on
    a free hinge; its compiler models it) to 1e-12, where Drake's plant alone is off by the armature."""
    path = scratch(tmp_path, LINK.format("a", "0 0 0", "0 1 0", 'armature="0.07"', 1.0,
                                         LINK.format("b", "0.3 0 0", "1 0 1", 'armature="0.05"', 0.5, "")))
    model = DrakeModel(path, hinge_scene(["a", "b"]))
    for t, q, v in states(2):
        acc, mass, energy = raw_mujoco(path, t, q, v)
        assert np.max(np.abs(model.mass_matrix(t, q, v) - mass)) <= RTOL * np.max(np.abs(mass))
        assert np.max(np.abs(model.accelerations(t, q, v) - acc)) <= RTOL * np.max(np.abs(acc))
        assert abs(model.energy(t, q, v) - energy) <= RTOL * abs(energy)
        plain = model.plant.CalcMassMatrix(model.context)
        assert np.allclose(mass - plain, np.diag([0.07, 0.05]), rtol=0, atol=1e-12)


def test_springs_are_applied_where_drakes_parser_ignores_them(tmp_path):
    """Drake's parser ignores joint stiffness and springref with a warning; the adapter applies -k (q - springref)
    (springref in degrees, MJCF's default) and counts k x^2 / 2: q'', the energy and M equal MuJoCo's adapter's."""
    path = scratch(tmp_path, LINK.format("a", "0 0 0", "0 1 0", 'stiffness="3" springref="20"', 1.0,
                                         LINK.format("b", "0.3 0 0", "1 0 1", 'stiffness="1.5" damping="0.2"', 0.5, "")))
    model, reference = DrakeModel(path, hinge_scene(["a", "b"])), MujocoModel(path, hinge_scene(["a", "b"]))
    assert any("'stiffness'" in w for w in model.parser_warnings) and any("'springref'" in w
                                                                         for w in model.parser_warnings)
    for t, q, v in states(2):
        acc = reference.accelerations(t, q, v)
        assert np.max(np.abs(model.accelerations(t, q, v) - acc)) <= RTOL * np.max(np.abs(acc))
        assert abs(model.energy(t, q, v) - reference.energy(t, q, v)) <= RTOL * abs(reference.energy(t, q, v))
    assert model.read(SceneLocation("joint", "a", "springref")) == pytest.approx(math.radians(20))


def test_several_joints_on_one_body_are_refused(tmp_path):
    """Drake's MJCF parser puts all but a body's last joint on the parent's axes: on a turned body its M is off
    MuJoCo's by per cents (measured here), so the adapter refuses the scene, naming the body."""
    body = ('<body name="a" quat="0.8 0.2 0.5 0.26"><joint name="j1" axis="1 0 0"/><joint name="j2" axis="0 1 0"/>'
            '<inertial pos="0.2 0.1 0" mass="1" diaginertia="0.01 0.02 0.03"/></body>')
    path = scratch(tmp_path, body)
    plant = MultibodyPlant(0.0)
    Parser(plant).AddModels(str(path))
    plant.Finalize()
    context = plant.CreateDefaultContext()
    q = np.array([0.4, -0.7])
    plant.SetPositions(context, q)
    mass = raw_mujoco(path, 0.0, q, np.zeros(2))[1]
    assert np.max(np.abs(plant.CalcMassMatrix(context) - mass)) > 1e-2 * np.max(np.abs(mass))
    with pytest.raises(Refused, match=f"{path}: body 'a' has 2 joints"):
        DrakeModel(path, hinge_scene(["j1", "j2"]))


def test_a_ball_joint_under_a_turned_body_maps_to_the_cases_euler_angles(tmp_path):
    """Drake's ball joint is roll-pitch-yaw with the angular velocity in the parent's frame; the adapter maps the
    case's Euler angles and rates to it and its dofs to the body's axes.  Under a hinge, on a body turned in its
    parent (so that the parent's frame is neither the world's nor the body's): M, q'', the reactions and the
    energy equal MuJoCo's adapter's, which reads the quaternion and the body's angular velocity."""
    ball = ('<body name="top" pos="0.2 0 -0.1" quat="0.9 0.1 0.3 0.2"><joint name="tip" type="ball"/>'
            '<inertial pos="0 0.02 0.1" mass="0.6" diaginertia="0.002 0.003 0.004"/><site name="O"/></body>')
    body = LINK.format("arm", "0 0 0", "0 0 1", "", 1.0, ball)
    path = scratch(tmp_path, body)
    (tmp_path / "scene.xml").write_text(path.read_text().replace(
        "</mujoco>", '<sensor><force name="f" site="O"/></sensor></mujoco>'))
    scene = hinge_scene(["arm"], ("tip", ("precession", "nutation", "spin")))
    scene = replace(scene, reactions={f"R{axis}": Reaction(body="top", sensor="f", axis=i, frame="world")
                                      for i, axis in enumerate("xyz")})
    model, reference = DrakeModel(path, scene), MujocoModel(path, scene)
    for t, q, v in states(4):
        q[2] = 0.3 + abs(q[2])  # nutation away from the Euler angles' singularity at 0
        for method in ("mass_matrix", "accelerations"):
            expected = getattr(reference, method)(t, q, v)
            assert np.max(np.abs(getattr(model, method)(t, q, v) - expected)) <= RTOL * np.max(np.abs(expected))
        expected = reference.reactions(t, q, v)
        scale = max(abs(x) for x in expected.values())
        assert all(abs(model.reactions(t, q, v)[k] - x) <= RTOL * scale for k, x in expected.items())
        assert abs(model.energy(t, q, v) - reference.energy(t, q, v)) <= RTOL * abs(reference.energy(t, q, v))


def test_a_urdf_gets_the_cases_gravity_not_drakes_default():
    """Drake gives a URDF gravity -9.81 z; the adapter zeroes it and the case's binding writes the book's -9.81 y.
    Against Pinocchio on the same URDF (MuJoCo's scene holds placeholder inertias that the URDF has not): 1e-12."""
    case = dyncheck.load_case("double_pendulum")
    path = case.folder / "scene.urdf"
    assert DrakeModel(path, case.scene).gravity.tolist() == [0.0, 0.0, 0.0]
    model = drake(case, "scene.urdf")
    assert model.gravity.tolist() == [0.0, -9.81, 0.0]
    errors = disagreement(case.model("pinocchio"), model, case.sample_states()[:10], case)
    assert {k: e for k, e in errors.items() if k != "drive power" and not e <= RTOL} == {}


def test_a_urdf_root_link_hangs_on_the_cases_root_joint(tmp_path):
    """Drake makes a URDF's root link a free body; the adapter hangs it on the case's urdf_root_joint (the top's
    ball joint at its tip), and refuses a free body.  The top's own URDF holds the book's inertia about the centre of
    mass, which breaks the triangle inequality: Drake's parser replaces it (a warning), which is refused.  With an
    inertia that a body can have, Drake on the URDF agrees with Pinocchio on it."""
    top = dyncheck.load_case("spinning_top")
    with pytest.raises(Refused, match="triangle inequality"):
        drake(top, "scene.urdf")
    folder = tmp_path / "spinning_top"
    shutil.copytree(top.folder, folder)
    urdf = folder / "scene.urdf"
    urdf.write_text(urdf.read_text().replace('ixx="0.00112716152"', 'ixx="0.0014"').replace(
        'iyy="0.00112716152"', 'iyy="0.0014"'))
    case = dyncheck.load_case("spinning_top", tmp_path)
    pinocchio = PinocchioModel(urdf, case.scene, case.writes(PinocchioModel, urdf))
    errors = disagreement(pinocchio, drake(case, "scene.urdf"), case.sample_states()[:8], case)
    assert {k: e for k, e in errors.items() if not e <= RTOL} == {}
    free = replace(case.scene, urdf_root_joint=None)
    with pytest.raises(Refused, match="free body"):
        DrakeModel(urdf, free, case.writes(DrakeModel, urdf))


def test_a_connect_is_solved_rigidly_where_drakes_continuous_plant_refuses_it():
    """Drake's parser makes the slider-crank's <connect> a ball constraint, for which a continuous plant computes
    no dynamics; the adapter removes it and solves the loop rigidly (the slider-crank's agreement with MuJoCo's rigid
    loop is in test_drake_agrees_with_mujoco_on_every_scene)."""
    case = dyncheck.load_case("slider_crank", ROOT / "examples")
    plant = MultibodyPlant(0.0)
    Parser(plant).AddModels(str(case.folder / "scene.xml"))
    plant.Finalize()
    assert plant.num_constraints() == 1
    context = plant.CreateDefaultContext()
    with pytest.raises(RuntimeError):
        plant.EvalTimeDerivatives(context)
    model = drake(case)
    assert [loop.name for loop in model.loops.loops] == ["loop"] and model.plant.num_constraints() == 0


def test_a_site_form_connect_is_refused(tmp_path):
    """Drake's parser ignores sites: a site-form <connect> is refused, naming the form."""
    body = (LINK.format("a", "0 0 0", "0 1 0", "", 1.0, '<site name="s1" pos="0.3 0 0"/>')
            + LINK.format("b", "0.3 0 0", "1 0 0", "", 1.0, '<site name="s2"/>'))
    path = tmp_path / "scene.xml"
    path.write_text(f'<mujoco model="s"><worldbody><body name="g">{body}</body></worldbody>'
                    '<equality><connect site1="s1" site2="s2"/></equality></mujoco>')
    with pytest.raises(Refused, match="site-form|site1"):
        DrakeModel(path, hinge_scene(["a", "b"]))


@pytest.mark.parametrize("attribute, refused", [('frictionloss="1"', "frictionloss"),
                                                ('limited="true" range="-1 1"', "limits")])
def test_what_drake_drops_otherwise_is_refused(tmp_path, attribute, refused):
    """Any other element Drake's parser says it ignores is refused with its words (dry friction), and joint limits,
    which Drake reads but its continuous plant does not enforce."""
    path = scratch(tmp_path, LINK.format("a", "0 0 0", "0 1 0", attribute, 1.0, ""))
    with pytest.raises(Refused, match=f"{path}: .*{refused}"):
        DrakeModel(path, hinge_scene(["a"]))


@pytest.mark.parametrize("name", ["double_pendulum", "spinning_top", "spring_pendulum"])
def test_the_bare_drake_step_gives_the_adapters_accelerations(name):
    """engines.bench.drake_steps, Drake's engine step on its own state (what dyncheck bench times the adapter
    against), gives every dof's accelerations that the adapter turns into the case's: the same numbers."""
    from engines.bench import drake_steps
    case = dyncheck.load_case(name)
    model = drake(case)
    states = case.sample_states()[:5]
    bare = drake_steps(model, [model.engine_state(*state) for state in states])
    for (t, q, v), (acc, _, _) in zip(states, bare):
        np.testing.assert_array_equal(case_accelerations(model._dof_layout, q, v, acc), model.accelerations(t, q, v))


# -- linearisation -----------------------------------------------------------------------------------

# Every scene whose coordinates are not all prescribed (piston, rotating_particle: an empty linearisation) and
# without loops (the slider-crank: refused, below), and the rotating pendulum under g = 0, whose equilibrium at
# psi = -pi/2 is degenerate: A's entries there are 1e-8 of the terms they sum, so its error is the measured noise.
LINEAR = [(name, folder, {}) for name, folder in SCENES if name not in ("piston", "rotating_particle", "slider_crank")]
LINEAR += [("rotating_pendulum", ROOT / "cases", {"g": 0.0})]


# The least error of MuJoCo's linearisation, relative to its largest entry: centred differences of mj_inverse at the
# step of least estimated error (1e-3 to 3e-5) round by ~1.5 g eps |F| / h (engines.coordinates.difference_rounding), |F|
# the largest term summed, a few times the entries: at h = 1e-3 some 1e-12 of them (1.0e-12 measured, above), and
# 1e-11 allows ten times that.
MUJOCO_FLOOR = 1e-11


def linearisation_states(name, folder, overrides):
    """(case, states) pairs: the vibration analysis's equilibrium, on its linearised scene (dyncheck.checks.linear), and
    the case's initial state with two of the pointwise check's random ones (off equilibrium: the springs stretched,
    the drives turning; the top's second with a nutation in (0.3, 2.5), away from its Euler angles' singularity)."""
    case = dyncheck.load_case(name, folder, **overrides)
    table, scene = linear.settings(case), linear.linearised(case)
    eq = linear.equilibrium(scene.model("reference"), 0.0, table["q"], table["v"], table["solve"], case.coords,
                               scene.model("pinocchio").mass_matrix)
    (t, q, v), (random, other) = (0.0, *case.initial[:2]), case.sample_states()[:2]
    if "nutation" in case.coords:
        other[1][case.coords.index("nutation")] = np.random.default_rng(15).uniform(0.3, 2.5)
    return [(scene, [(eq.t, eq.q, eq.v)]), (case, [(t, q, v), random, other])]


def largest_difference(a, b):
    return max(np.max(np.abs(a.force_q - b.force_q)), np.max(np.abs(a.force_v - b.force_v)))


@pytest.mark.parametrize("name, folder, overrides", LINEAR,
                         ids=[name + ("-g0" if overrides else "") for name, _, overrides in LINEAR])
def test_drakes_linearisation_agrees_with_pinocchios_and_mujocos(name, folder, overrides):
    """Drake's AutoDiff derivatives against Pinocchio's analytic ones on the same file (scene.xml, by Pinocchio's
    own MJCF reader: MuJoCo's placeholder inertias in both), and against MuJoCo's differences of mj_inverse, at the
    vibration analysis's equilibrium and at random states.  Each linearisation's `error` bounds its entries' error:
    Drake's and Pinocchio's their rounding (1e3 eps of the largest entry, or 10 times the noise measured over a few
    ulps at a degenerate state), MuJoCo's the differences' truncation (extrapolated) and rounding; two of them
    differ by at most the sum.  MuJoCo's evaluation model holds approximations the others have not (its prescribed
    motions' armature: the rotating pendulum's A 1e-12 of its entries off): their effect, measured on MuJoCo's scene
    with them doubled (case.approximations_doubled, with its own error), is allowed besides, as
    tests/test_engine_linearisation.py allows it between MuJoCo and Pinocchio.  MuJoCo's estimate is not always a
    bound: at the rotating pendulum's equilibrium it says 1.8e-15, and its force_q lies 2.0e-13 (1.0e-12 of the
    entry) from Drake's and Pinocchio's, which agree there to 1e-16; so MuJoCo's error is taken at least as
    MUJOCO_FLOOR of the largest entry.  M is `mass_matrix`'s, which agrees to RTOL (argued at the top)."""
    path = ROOT / folder.name / name / "scene.xml"
    for case, states in linearisation_states(name, folder, overrides):
        model = drake(case)
        pinocchio = PinocchioModel(path, case.scene, case.writes(PinocchioModel, path))
        for t, q, v in states:
            ours, theirs, mujoco, doubled = (m.linearisation(t, q, v) for m in (model, pinocchio, case.model("mujoco"),
                                                                              case.approximations_doubled()))
            assert largest_difference(ours, theirs) <= ours.error + theirs.error, (name, t, q, v)
            approximations = largest_difference(doubled, mujoco) + doubled.error
            floor = MUJOCO_FLOOR * max(np.max(np.abs(mujoco.force_q)), np.max(np.abs(mujoco.force_v)))
            tolerance = ours.error + max(mujoco.error, floor) + approximations
            assert largest_difference(ours, mujoco) <= tolerance, (name, t, q, v)
            assert np.array_equal(ours.mass, model.mass_matrix(t, q, v))
            assert np.max(np.abs(ours.mass - theirs.mass)) <= RTOL * np.max(np.abs(theirs.mass))
            # the estimate is not vacuous: far below the entries (at the degenerate equilibrium, 1e-11 themselves)
            assert ours.error <= 1e-10 * max(1e-3, np.max(np.abs(ours.force_q)), np.max(np.abs(ours.force_v)))
            assert "AutoDiffXd" in ours.method


def test_drakes_linearisation_refuses_loops():
    """The slider-crank's coordinates' equations hold its loop's forces: refused, as the other adapters refuse it."""
    case = dyncheck.load_case("slider_crank", ROOT / "examples")
    t, q, v = case.sample_states()[0]
    with pytest.raises(Refused, match=r"scene\.xml: linearisation of a scene with closed loops \(loop\)"):
        drake(case).linearisation(t, q, v)
