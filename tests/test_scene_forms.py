"""Scenes as MJCF and URDF write them (issue 37): several joints on one body, bodies welded to a moving body, URDF
fixed joints and joints without <limit>, a body's inertia about its centre of mass as a binding.  MuJoCo's and
Pinocchio's adapters on the same scene: both describe the same bodies (dyncheck.case.scene.compare_scenes) and give
the same mass matrix, generalised forces, accelerations, reactions, point accelerations and energy.

Tolerance: RTOL = 1e-12 of the largest magnitude of each quantity.  Each engine's numbers are sums over these few
bodies of products of placements, inertias and velocities of order 1, a few dozen roundings of eps each: some
5e-15 of the largest term; the accelerations are M^-1 of the forces, which multiplies that by the condition number
of M scaled by its diagonal (the coordinates' own scales: a slide's kg beside a ball's kg m^2), at most 60 in these
scenes (`test_the_scenes_are_well_conditioned`): 3e-13, and 1e-12 keeps a factor of three over it.  Its ceiling:
the joints of one body taken in the other order move M by 1e-2 and more
(`test_the_comparison_sees_the_order_of_a_body_s_joints`)."""

import shutil
from pathlib import Path

import numpy as np
import pytest

from dyncheck.case.folder import Case
from dyncheck.case.scene import Coordinates, Point, Reaction, Scene, compare_scenes
from dyncheck.cli import main
from engines.bindings import SceneLocation
from engines.mujoco_adapter import MujocoModel
from engines.pinocchio_adapter import PinocchioModel

RTOL = 1e-12
CONDITION = 100.0

SPHERICAL = """<mujoco model="spherical pendulum">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="bob" pos="0 0 1" euler="10 20 30">
      <joint name="a" type="hinge" axis="1 0 0" stiffness="0.7" damping="0.05"/>
      <joint name="b" type="hinge" axis="0 1 0" damping="0.02"/>
      <inertial pos="0.05 0.02 -0.5" mass="0.3" diaginertia="1e-3 2e-3 2.5e-3"/>
      <site name="s"/>
    </body>
  </worldbody>
  <sensor><force name="f" site="s"/><torque name="t" site="s"/></sensor>
</mujoco>"""

# a slide and a hinge on one body, a body hanging on it with its own hinge, a body welded under that one with its
# own mass, and a massless tool welded at the end
SLIDE_HINGE = """<mujoco model="cart and pendulum on one body">
  <worldbody>
    <body name="rail">
      <body name="cart" euler="0 0 15">
        <joint name="x" type="slide" axis="1 0 0"/>
        <joint name="theta" type="hinge" axis="0 1 0"/>
        <inertial pos="0 0 -0.3" mass="0.8" fullinertia="4e-3 3e-3 2e-3 1e-4 -2e-4 3e-4"/>
        <body name="arm" pos="0 0.1 -0.6">
          <joint name="phi" type="hinge" axis="0 1 0"/>
          <inertial pos="0 0 -0.25" mass="0.2" diaginertia="2e-3 2e-3 1e-4" quat="0.9 0.1 0.2 0.3"/>
          <site name="s"/>
          <body name="weight" pos="0 0 -0.5" euler="0 30 0">
            <inertial pos="0.02 0 0" mass="0.5" diaginertia="3e-4 4e-4 5e-4"/>
            <body name="tool" pos="0 0 -0.1"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <sensor><force name="f" site="s"/></sensor>
</mujoco>"""

# the same welded scene as a URDF: a base link welded to the world, a revolute joint without <limit>, a tool link
# welded to the last link
WELDED_MJCF = """<mujoco model="welded">
  <worldbody>
    <body name="base" pos="0 0 1">
      <inertial pos="0 0 0" mass="2" diaginertia="1 1 1"/>
      <body name="arm">
        <joint name="theta" type="hinge" axis="0 1 0"/>
        <inertial pos="0 0 -0.5" mass="0.3" diaginertia="1e-3 2e-3 3e-3"/>
        <body name="forearm" pos="0 0 -1">
          <joint name="phi" type="hinge" axis="1 0 0"/>
          <inertial pos="0 0 -0.4" mass="0.2" diaginertia="1e-3 1e-3 5e-4"/>
          <site name="s"/>
          <body name="tool" pos="0 0 -0.8">
            <inertial pos="0 0.1 0" mass="0.1" diaginertia="1e-4 1e-4 1e-4"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <sensor><force name="f" site="s"/></sensor>
</mujoco>"""

WELDED_URDF = """<robot name="welded">
  <link name="world"/>
  <joint name="base_weld" type="fixed"><parent link="world"/><child link="base"/><origin xyz="0 0 1"/></joint>
  <link name="base"><inertial><mass value="2"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="theta" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/></joint>
  <link name="arm"><inertial><origin xyz="0 0 -0.5"/><mass value="0.3"/>
    <inertia ixx="1e-3" iyy="2e-3" izz="3e-3" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="phi" type="continuous"><parent link="arm"/><child link="forearm"/><origin xyz="0 0 -1"/>
    <axis xyz="1 0 0"/></joint>
  <link name="forearm"><inertial><origin xyz="0 0 -0.4"/><mass value="0.2"/>
    <inertia ixx="1e-3" iyy="1e-3" izz="5e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="tool_weld" type="fixed"><parent link="forearm"/><child link="tool"/><origin xyz="0 0 -0.8"/></joint>
  <link name="tool"><inertial><origin xyz="0 0.1 0"/><mass value="0.1"/>
    <inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>"""


def scene(coords, reactions=(), points=(), layout=None):
    """A case's scene of hinges and slides, one coordinate per joint (or `layout`): force reactions on sensor 'f'
    (and a moment on 't') of `reactions`' bodies, the accelerations of `points`' bodies' centres of mass."""
    forces = {}
    for body in reactions:
        for axis in range(3):
            forces[f"F{axis}"] = Reaction(body, "f", axis, "body")
            if body == "bob":
                forces[f"M{axis}"] = Reaction(body, "t", axis, "world", "moment")
    kinds = {}
    for body in points:
        kinds[f"a_{body}"] = Point(body, "world", "com acceleration")
        kinds[f"o_{body}"] = Point(body, "body", "acceleration")
    layout = layout or tuple(Coordinates("scalar", joint, (i,)) for i, joint in enumerate(coords))
    return Scene(tuple(coords), layout, driven={}, applied={}, reactions=forces, points=kinds)


# a slide and a ball joint on one body (a top on a sliding base); the ball's Euler angles as the case's coordinates
SLIDE_BALL = """<mujoco model="slide and ball">
  <worldbody>
    <body name="top" pos="0 0 0.2">
      <joint name="x" type="slide" axis="1 0 0" damping="0.1"/>
      <joint name="ball" type="ball"/>
      <inertial pos="0 0 0.05" mass="0.5" diaginertia="1e-3 1e-3 2e-3"/>
      <site name="s"/>
    </body>
  </worldbody>
  <sensor><force name="f" site="s"/></sensor>
</mujoco>"""
BALL_SCENE = scene(["x", "psi", "theta", "phi"], ["top"], ["top"],
                   (Coordinates("scalar", "x", (0,)), Coordinates("euler", "ball", (1, 2, 3))))

SCENES = {  # name: (MJCF, URDF or None, [scene])
    "spherical": (SPHERICAL, None, scene(["a", "b"], ["bob"], ["bob"])),
    "slide_hinge": (SLIDE_HINGE, None, scene(["x", "theta", "phi"], ["arm"], ["cart", "arm", "weight"])),
    "welded": (WELDED_MJCF, WELDED_URDF, scene(["theta", "phi"], ["forearm"], ["arm", "forearm", "tool"])),
    "slide_ball": (SLIDE_BALL, None, BALL_SCENE),
}


def models(tmp_path, name, writes=()):
    mjcf, urdf, spec = SCENES[name]
    (tmp_path / "scene.xml").write_text(mjcf)
    if urdf:
        (tmp_path / "scene.urdf").write_text(urdf)
    pinocchio_file = tmp_path / ("scene.urdf" if urdf else "scene.xml")
    mujoco = MujocoModel(tmp_path / "scene.xml", spec, writes)
    gravity = [(SceneLocation("option", "gravity", index=2), -9.81)] if urdf else []  # URDF has none
    pinocchio = PinocchioModel(pinocchio_file, spec, [*writes, *gravity])
    return mujoco, pinocchio


def states(n_coords, count=6):
    """Random states; with Euler angles (4 coordinates: the slide and the ball) the nutation kept within 0.3..2.8
    rad, away from the angles' singularity."""
    rng = np.random.default_rng(37)
    out = [(0.0, rng.uniform(-2, 2, n_coords), rng.uniform(-3, 3, n_coords)) for _ in range(count)]
    for _, q, _ in out:
        if n_coords == 4:
            q[2] = 1.55 + 0.6 * q[2]
    return out


def quantities(model, t, q, v):
    """{quantity: array} of one state: M, the generalised forces M q'' (springs, dampers, gravity and the bias),
    q'', the reactions, the points, the energy."""
    mass, acc = model.mass_matrix(t, q, v), model.accelerations(t, q, v)
    out = {"M": mass, "forces": mass @ acc, "q''": acc, "energy": np.array([model.energy(t, q, v)])}
    if model.reaction_names:
        out["reactions"] = np.array([model.reactions(t, q, v)[name] for name in model.reaction_names])
    for name, vector in model.point_accelerations(t, q, v).items():
        out[name] = vector
    return out


def relative(a, b, floor=0.0):
    """The largest difference relative to the largest magnitude (at least `floor`)."""
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), np.max(np.abs(b)), floor))


def differences(a, b):
    """{quantity: `relative`} of two engines' `quantities`; a point's relative to at least g (a body's origin on
    the world is at rest: both engines' zeros to rounding)."""
    return {q: relative(a[q], b[q], 9.81 if q.startswith(("a_", "o_")) else 0.0) for q in a}


@pytest.mark.parametrize("name", SCENES)
def test_both_engines_model_the_same_bodies(tmp_path, name):
    mujoco, pinocchio = models(tmp_path, name)
    compare_scenes(mujoco, pinocchio, name)
    assert [b.name for b in mujoco.tree()] == [b.name for b in pinocchio.tree()]


@pytest.mark.parametrize("name", SCENES)
def test_both_engines_agree_on_every_quantity(tmp_path, name):
    """Measured worst over 6 states (relative to each quantity's largest magnitude): spherical 1.0e-15 (reactions),
    slide_hinge 2.2e-14 (energy: kinetic and potential terms of 1e1 J cancel to 1 J) and 1.3e-14 (reactions),
    welded 6.8e-15 (energy); M 9e-16 and q'' 3.1e-15 at most."""
    mujoco, pinocchio = models(tmp_path, name)
    worst = {}
    for state in states(len(SCENES[name][2].coords)):
        a, b = quantities(mujoco, *state), quantities(pinocchio, *state)
        assert a.keys() == b.keys()
        for quantity, error in differences(a, b).items():
            worst[quantity] = max(worst.get(quantity, 0.0), error)
    assert {q: e for q, e in worst.items() if not e <= RTOL} == {}, worst


@pytest.mark.parametrize("name", SCENES)
def test_the_scenes_are_well_conditioned(tmp_path, name):
    """The tolerance's argument: the condition number of M scaled by its diagonal at the states compared (measured:
    1.5 spherical, 57 slide_hinge, 1.0 welded, 24 slide_ball)."""
    mujoco, _ = models(tmp_path, name)
    for state in states(len(SCENES[name][2].coords)):
        mass = mujoco.mass_matrix(*state)
        scale = 1 / np.sqrt(np.diag(mass))
        assert np.linalg.cond(scale[:, None] * mass * scale) < CONDITION


def test_the_comparison_sees_the_order_of_a_body_s_joints(tmp_path):
    """The tolerance's ceiling: the spherical pendulum's hinges swapped in Pinocchio's file change its M by 1e-2 and
    more of its largest entry, and the scene comparison refuses the pair."""
    mujoco, _ = models(tmp_path, "spherical")
    swapped = tmp_path / "swapped.xml"
    swapped.write_text(SPHERICAL.replace('<joint name="a" type="hinge" axis="1 0 0" stiffness="0.7" damping="0.05"/>\n'
                                         '      <joint name="b" type="hinge" axis="0 1 0" damping="0.02"/>',
                                         '<joint name="b" type="hinge" axis="0 1 0" damping="0.02"/>\n'
                                         '      <joint name="a" type="hinge" axis="1 0 0" stiffness="0.7" damping="0.05"/>'))
    pinocchio = PinocchioModel(swapped, SCENES["spherical"][2])
    assert min(relative(mujoco.mass_matrix(*s), pinocchio.mass_matrix(*s)) for s in states(2)) > 1e-2
    with pytest.raises(ValueError, match="body 'bob/[ab]' is in (scene|swapped).xml but not in"):
        compare_scenes(mujoco, pinocchio, "spherical")


def test_a_body_s_joints_are_a_chain_of_massless_frames(tmp_path):
    """The spherical pendulum: 'bob/a' at the body's placement, massless, on hinge a; 'bob' on it, on hinge b, with
    the mass; the springs and dampers on their joints."""
    bodies = {b.name: b for b in models(tmp_path, "spherical")[1].tree()}
    assert (bodies["bob/a"].parent, bodies["bob/a"].joint, bodies["bob/a"].mass) == ("world", "a", 0.0)
    assert (bodies["bob"].parent, bodies["bob"].joint, bodies["bob"].mass) == ("bob/a", "b", 0.3)
    assert bodies["bob/a"].position.tolist() == [0, 0, 1] and bodies["bob"].position.tolist() == [0, 0, 0]
    assert (bodies["bob/a"].stiffness[0], bodies["bob/a"].damping, bodies["bob"].damping) == (0.7, 0.05, 0.02)


def test_a_welded_body_rides_with_the_body_it_is_welded_to(tmp_path):
    """The weight (0.5 kg) welded under the arm (0.2 kg): one body of 0.7 kg in both engines, its centre of mass
    their mean."""
    for model in models(tmp_path, "slide_hinge"):
        arm = {b.name: b for b in model.tree()}["arm"]
        assert arm.mass == pytest.approx(0.7, rel=1e-15)
        assert "weight" not in {b.name for b in model.tree()}


@pytest.mark.parametrize("body, error", [("weight", "welded to body 'arm'"), ("tool", "no joint")])
def test_a_reaction_on_a_welded_body_is_refused(tmp_path, body, error):
    """The weld's own force: MuJoCo's sensor would read it, Pinocchio's reader keeps no joint there."""
    mjcf = SLIDE_HINGE.replace('<body name="tool" pos="0 0 -0.1"/>', '<body name="tool" pos="0 0 -0.1"><site name="w"/></body>')
    mjcf = mjcf.replace('<force name="f" site="s"/>', '<force name="f" site="w"/>')
    (tmp_path / "scene.xml").write_text(mjcf)
    spec = scene(["x", "theta", "phi"], ["tool"])
    with pytest.raises(ValueError, match="no joint"):
        MujocoModel(tmp_path / "scene.xml", spec)
    spec = scene(["x", "theta", "phi"], [body])
    with pytest.raises(ValueError, match=error if body == "weight" else "welded to body 'arm'"):
        PinocchioModel(tmp_path / "scene.xml", spec)


# -- a body's inertia about its centre of mass as a binding ------------------------------------------------------

INERTIAS = [  # (scene, body, attribute, index, value written)
    ("spherical", "bob", "inertia", 0, 1.5e-3),  # diaginertia, in the inertial frame (here the body's)
    ("slide_hinge", "arm", "inertia", 2, 2e-4),  # diaginertia in an inertial frame turned by quat
    ("slide_hinge", "cart", "fullinertia", 3, -2e-4),  # the file's fullinertia, body frame
    ("slide_hinge", "arm", "fullinertia", 4, 1e-4),  # fullinertia of a body the file gives diaginertia
    ("welded", "forearm", "fullinertia", 0, 1.2e-3),  # a URDF <inertia> ixx (its <origin> has no rpy)
    ("welded", "arm", "inertia", 1, 2.5e-3),
]


@pytest.mark.parametrize("name, body, attribute, index, value", INERTIAS)
def test_an_inertia_binding_reads_back_what_it_wrote_in_both_engines(tmp_path, name, body, attribute, index, value):
    """Read back to 1e-14 of the body's largest moment: MuJoCo compiles a fullinertia to principal moments and a
    rotation (mju_eig3, iterative: measured to 15 eps of the largest moment), read back as the tensor; the other
    entries unchanged as much, and both engines' bodies still the same."""
    location = SceneLocation("body", body, attribute, index)
    before = models(tmp_path, name)
    written = models(tmp_path, name, [(location, value)])
    width = 3 if attribute == "inertia" else 6
    for old, new in zip(before, written):
        rounding = 1e-14 * max(abs(new.read(SceneLocation("body", body, "fullinertia", i))) for i in range(3))
        assert new.read(location) == pytest.approx(value, rel=0, abs=rounding)
        for other in set(range(width)) - {index}:
            at = SceneLocation("body", body, attribute, other)
            assert new.read(at) == pytest.approx(old.read(at), rel=0, abs=rounding), other
    compare_scenes(*written, name)


@pytest.mark.parametrize("name, body, attribute, index, value", INERTIAS)
def test_both_engines_agree_after_an_inertia_binding(tmp_path, name, body, attribute, index, value):
    location = SceneLocation("body", body, attribute, index)
    mujoco, pinocchio = models(tmp_path, name, [(location, value)])
    for state in states(len(SCENES[name][2].coords), 2):
        errors = differences(quantities(mujoco, *state), quantities(pinocchio, *state))
        assert {q: e for q, e in errors.items() if not e <= RTOL} == {}


@pytest.mark.parametrize("attribute, index, value", [("inertia", 2, 3.5e-3), ("inertia", 0, -1e-3),
                                                     ("fullinertia", 3, 5e-3)])
def test_an_unphysical_inertia_is_refused_naming_the_body(tmp_path, attribute, index, value):
    """A + B < C, a negative moment, a product of inertia beyond the moments: ValueError naming the file and body."""
    location = SceneLocation("body", "bob", attribute, index)
    (tmp_path / "scene.xml").write_text(SPHERICAL)
    for Model in (MujocoModel, PinocchioModel):
        with pytest.raises(ValueError, match=r"scene.xml: body 'bob': principal moments .* not a rigid body's"):
            Model(tmp_path / "scene.xml", SCENES["spherical"][2], [(location, value)])


def test_several_writes_are_judged_together(tmp_path):
    """Raising all three moments of the spherical pendulum's bob tenfold passes through A + B < C on the way."""
    writes = [(SceneLocation("body", "bob", "inertia", i), 10 * x)
              for i, x in ((2, 2.5e-3), (0, 1e-3), (1, 2e-3))]
    for model in models(tmp_path, "spherical", writes):
        assert [model.read(location) for location, _ in writes] == pytest.approx([value for _, value in writes])


@pytest.mark.parametrize("Model", [MujocoModel, PinocchioModel])
def test_an_inertia_binding_of_a_fullinertia_body_s_principal_moments_is_refused(tmp_path, Model):
    """Written or read: MuJoCo's principal moments of a fullinertia are its own decomposition's, in its order."""
    (tmp_path / "scene.xml").write_text(SLIDE_HINGE)
    location = SceneLocation("body", "cart", "inertia", 0)
    with pytest.raises(ValueError, match="body 'cart'.* fullinertia.* bind fullinertia"):
        Model(tmp_path / "scene.xml", SCENES["slide_hinge"][2], [(location, 5e-3)])
    if Model is PinocchioModel:
        with pytest.raises(ValueError, match="bind fullinertia"):
            Model(tmp_path / "scene.xml", SCENES["slide_hinge"][2]).read(location)


def test_the_frames_of_a_body_s_joints_are_no_placeholders(tmp_path):
    """The massless frames between a body's joints (engines.scene.joint_frame) are marked in both engines' trees and
    are not the bodies whose placeholders MuJoCo's twin doubles: the spherical pendulum of two hinges has none (it
    reported 'bob/a', which MuJoCo has no body of)."""
    for model in models(tmp_path, "spherical"):
        assert [(body.name, body.frame) for body in model.tree()] == [("bob/a", True), ("bob", False)]
    folder = tmp_path / "spherical_pendulum"
    shutil.copytree(SPHERICAL_CASE, folder)
    case = Case(folder)
    assert case.placeholders() == {} and case.approximations_doubled() is case.model("mujoco")
    (folder / "scene.xml").write_text((folder / "scene.xml").read_text().replace(
        'diaginertia="2e-3 3e-3 1e-3"', 'diaginertia="1e-14 1e-14 1e-14"'))  # a point mass: a placeholder inertia
    placeholders = Case(folder).placeholders()
    assert placeholders == {"bob": (False, True)}
    assert Case(folder).approximations_doubled().m.body_inertia[1].tolist() == [2e-14] * 3


@pytest.mark.parametrize("name", SCENES)
def test_both_engines_linearisations_agree(tmp_path, name):
    """df/dq and df/dq' within the sum of both engines' error estimates (MuJoCo's differences; Pinocchio's analytic
    derivatives' rounding, or its differences through a composite joint), M to RTOL.  Measured: at most 0.57 of that
    sum (welded), 0.02 and below elsewhere."""
    mujoco, pinocchio = models(tmp_path, name)
    for state in states(len(SCENES[name][2].coords), 2):
        a, b = mujoco.linearisation(*state), pinocchio.linearisation(*state)
        assert relative(a.mass, b.mass) <= RTOL
        for field in ("force_q", "force_v"):
            assert np.max(np.abs(getattr(a, field) - getattr(b, field))) <= a.error + b.error, field


def test_pinocchio_s_analytic_derivatives_are_wrong_through_a_composite_joint(tmp_path):
    """Why Pinocchio's adapter differences RNEA on a scene with several joints on one body: computeRNEADerivatives
    (Pinocchio 4.1) gives the spherical pendulum's dtau/dq of the second hinge off by 1.58 N m/rad and its dtau/dv
    by 0.085 N m s (its differences and MuJoCo's agree within their estimated errors).  Fails once Pinocchio's are right: then the
    adapter can take them again."""
    _, pinocchio = models(tmp_path, "spherical")
    _, q, v = states(2, 1)[0]
    config, velocity, acc, _ = pinocchio._dynamics(0.0, q, v)
    analytic, differenced = pinocchio._rnea_derivatives(config, velocity, acc), pinocchio._rnea_differences(config, velocity, acc)
    assert np.max(np.abs(analytic[0] - differenced[0])) > 1.0
    assert np.max(np.abs(analytic[1] - differenced[1])) > 0.05  # dtau/dv too: 0.085 N m s


# -- Drake (the optional extra): welded bodies as the others, several joints on one body refused -------------------

@pytest.mark.parametrize("file", ["scene.xml", "scene.urdf"])
@pytest.mark.parametrize("write", [None, ("forearm", "fullinertia", 3, 1e-4), ("arm", "inertia", 1, 2.5e-3)])
def test_drake_models_the_welded_scene_as_mujoco(tmp_path, file, write):
    """Measured worst: 1.7e-15 (reactions); the bindings read back exactly."""
    drake_adapter = pytest.importorskip("engines.drake_adapter")
    writes = [] if write is None else [(SceneLocation("body", *write[:3]), write[3])]
    mujoco, _ = models(tmp_path, "welded", writes)
    gravity = [(SceneLocation("option", "gravity", index=2), -9.81)] if file == "scene.urdf" else []
    drake = drake_adapter.DrakeModel(tmp_path / file, SCENES["welded"][2], writes + gravity)
    compare_scenes(mujoco, drake, "welded")
    for state in states(2, 3):
        errors = differences(quantities(mujoco, *state), quantities(drake, *state))
        assert {q: e for q, e in errors.items() if not e <= RTOL} == {}
    for location, value in writes:
        assert drake.read(location) == pytest.approx(value, rel=1e-15)


def test_drake_refuses_several_joints_on_one_body(tmp_path):
    drake_adapter = pytest.importorskip("engines.drake_adapter")
    (tmp_path / "scene.xml").write_text(SPHERICAL)
    with pytest.raises(drake_adapter.Refused, match="body 'bob' has 2 joints: Drake's MJCF parser puts all but the last"):
        drake_adapter.DrakeModel(tmp_path / "scene.xml", SCENES["spherical"][2])


# -- a researcher's case of two files on a body with two joints ----------------------------------------------------

SPHERICAL_CASE = Path(__file__).resolve().parent / "scene_forms" / "spherical_pendulum"


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
@pytest.mark.parametrize("planted, status", [(None, 0), ("IZZ * np.sin(b)**2", 1)])
def test_a_spherical_pendulum_of_two_hinges_on_one_body_passes_dyncheck_run(tmp_path, capsys, planted, status):
    """scene.xml and equations.py only (tests/scene_forms/spherical_pendulum): green (51 rows, 8 s here); with the
    body's IZZ left out of M[a,a], red."""
    folder = tmp_path / "spherical_pendulum"
    shutil.copytree(SPHERICAL_CASE, folder)
    if planted:
        text = (folder / "equations.py").read_text()
        assert text.count(f" + {planted}") == 2
        (folder / "equations.py").write_text(text.replace(f" + {planted}", "", 1))
    assert main(["run", "--cases", str(tmp_path)]) == status, capsys.readouterr().out


def spherical_case_with_izz(tmp_path, binding):
    """tests/scene_forms/spherical_pendulum with its IZZ a parameter, bound by case.toml to `binding` of bob."""
    folder = tmp_path / "spherical_pendulum"
    shutil.copytree(SPHERICAL_CASE, folder)
    equations = folder / "equations.py"
    text = equations.read_text().replace("IXX, IYY, IZZ = 2e-3, 3e-3, 1e-3", "IXX, IYY = 2e-3, 3e-3")
    equations.write_text(text.replace('"g": 9.81}', '"g": 9.81, "IZZ": 1e-3}').replace("IZZ *", 'p["IZZ"] *')
                         .replace("- IZZ)", '- p["IZZ"])'))
    location = '{ element = "body", name = "bob", attribute = "%s", index = %d }' % binding
    (folder / "case.toml").write_text(f"[scene.bindings]\nIZZ = [{location}]\n")
    return folder


@pytest.mark.parametrize("binding, about", [
    (("inertia", 2), "principal moment of inertia of body 'bob' about its centre of mass, axis z"),
    (("fullinertia", 2), "inertia of body 'bob' about its centre of mass, izz in the body frame"),
])
def test_a_case_binds_a_parameter_to_a_body_s_inertia(tmp_path, binding, about):
    """A body's principal moment or an entry of its full inertia as a case's parameter (the schema's BINDABLE): its
    unit and meaning from the binding, checked against both engines on load, and an override written into both."""
    case = Case(spherical_case_with_izz(tmp_path, binding))
    izz = next(p for p in case.parameters if p.name == "IZZ")
    assert (izz.unit, izz.about) == ("kg m^2", about)
    location = SceneLocation("body", "bob", *binding)
    other = case.with_params(IZZ=1.5e-3)
    for source in ("mujoco", "pinocchio"):
        assert other.model(source).read(location) == pytest.approx(1.5e-3, rel=1e-15)
    # the ceiling: a scene's value 1e-12 off the case's is refused, fullinertia's read-back rounding notwithstanding
    scene = case.folder / "scene.xml"
    scene.write_text(scene.read_text().replace('diaginertia="2e-3 3e-3 1e-3"', 'diaginertia="2e-3 3e-3 1.000000000001e-3"'))
    with pytest.raises(ValueError, match=rf"scene.xml of case 'spherical_pendulum': body 'bob' {binding[0]}\[2\] is "):
        Case(case.folder).model("mujoco")
