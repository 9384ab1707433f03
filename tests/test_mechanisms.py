"""Mechanisms beyond the book's (issue 14): viscous joint damping, springs' rest positions and applied forces
that are laws of time and state, on the forced cart-pendulum of examples/.  The example runs green; each
mismatch planted in one place (a derivation without a damper or without the push, a damper or a rest position
only in one scene file, an engine that drops its dampers, a law that does not evaluate) is refused on load or
fails with a reason, never passed."""

import shutil
from pathlib import Path

import pytest

from dyncheck.cli import main

pytestmark = pytest.mark.full  # runs of the cases' engines, seconds each: `pytest -m full`

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "forced_cart_pendulum"

# The example's scene for Pinocchio's URDF reader: a second model, compared with scene.xml on load.  A URDF has
# no springs (the case's binding of k writes it); its dampers are <dynamics damping>.
URDF = """<robot name="forced_cart_pendulum">
  <link name="world"/>
  <link name="cart"><inertial><mass value="1"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <link name="bob"><inertial><origin xyz="0 0 -0.5"/><mass value="0.3"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="x" type="prismatic"><parent link="world"/><child link="cart"/><axis xyz="1 0 0"/>
    <limit lower="-1e300" upper="1e300" effort="0" velocity="0"/>{x}</joint>
  <joint name="theta" type="revolute"><parent link="cart"/><child link="bob"/><axis xyz="0 -1 0"/>
    <limit lower="-1e300" upper="1e300" effort="0" velocity="0"/>{theta}</joint>
</robot>
"""


def example(tmp_path, edits=(), urdf=None, source=EXAMPLE):
    """The example `source` in tmp_path/cases without its studies, with `edits` (file, old, new) applied, and a
    scene.urdf if given."""
    folder = tmp_path / "cases" / source.name
    shutil.copytree(source, folder, ignore=shutil.ignore_patterns("studies.py", "__pycache__"))
    toml = folder / "case.toml"
    toml.write_text(toml.read_text().split("[stability")[0])  # the checks only: the studies are the report's
    for file, old, new in edits:
        text = (folder / file).read_text()
        assert text.count(old) == 1, (file, old)
        (folder / file).write_text(text.replace(old, new))
    if urdf is not None:
        (folder / "scene.urdf").write_text(urdf)
    return folder.parent


def run(cases, capsys):
    status = main(["run", "--cases", str(cases)])
    out, err = capsys.readouterr()
    return status, out, err


def test_the_forced_damped_example_passes_against_both_engines(tmp_path, capsys):
    status, out, _ = run(example(tmp_path), capsys)
    assert status == 0, out
    assert "work-energy balance" in out and "not applicable" not in out


def test_its_urdf_twin_with_the_same_dampers_passes(tmp_path, capsys):
    """Pinocchio on a hand-written URDF: the dampers from <dynamics damping>, checked against the MJCF's."""
    urdf = URDF.format(x='<dynamics damping="0.6"/>', theta='<dynamics damping="0.1"/>')
    status, out, _ = run(example(tmp_path, urdf=urdf), capsys)
    assert status == 0, out


def test_a_derivation_without_the_cart_s_damper_is_named(tmp_path, capsys):
    status, out, _ = run(example(tmp_path, [("equations.py", ' - p["c"] * x_rate + push', " + push")]), capsys)
    assert status == 1
    assert "the derivation's equation x: add - c x' to its force side f" in out


def test_a_derivation_without_the_push_is_named(tmp_path, capsys):
    """The case file's laws of time and state are candidate terms of the fit, in its own words."""
    status, out, _ = run(example(tmp_path, [("equations.py", " - p[\"c\"] * x_rate + push", ' - p["c"] * x_rate')]),
                         capsys)
    assert status == 1
    assert "the derivation's equation x: add + (F0 * cos(Omega * t)) to its force side f" in out
    assert "the derivation's equation theta:" not in out


@pytest.mark.parametrize("theta, shown", [("", "body 'bob' damping"),
                                          ('<dynamics damping="0.2"/>', "body 'bob' damping")])
def test_a_damper_only_in_one_scene_file_is_refused(tmp_path, capsys, theta, shown):
    """The hinge's damper is no parameter of the derivation (ct is dropped), so no binding writes it: the URDF's
    (none, or another) against the MJCF's 0.1 is refused before any work."""
    edits = [("equations.py", '"ct": 0.1, ', ""), ("equations.py", ' - p["ct"] * theta_rate**2', ""),
             ("equations.py", ' - p["ct"] * theta_rate', "")]
    status, _, err = run(example(tmp_path, edits, URDF.format(x="", theta=theta)), capsys)
    assert status == 2
    assert "scene.urdf" in err and shown in err


def test_a_spring_rest_position_only_in_the_mjcf_is_refused(tmp_path, capsys):
    """A springref no parameter binds: the URDF has none, so the two scenes disagree, on load."""
    edits = [("scene.xml", 'stiffness="20" damping="0.6"', 'stiffness="20" springref="0.03" damping="0.6"')]
    status, _, err = run(example(tmp_path, edits, URDF.format(x="", theta="")), capsys)
    assert status == 2
    assert "body 'cart' springref" in err


def test_a_spring_rest_position_is_bound_and_followed(tmp_path, capsys):
    """x0 binds to the springref, and --set moves it in the scene and the derivation alike."""
    edits = [("scene.xml", 'stiffness="20" damping="0.6"', 'stiffness="20" springref="0.03" damping="0.6"'),
             ("equations.py", '"F0": 0.05,', '"F0": 0.05, "x0": 0.03,'),
             ("equations.py", "- k * x - p[", '- k * (x - p["x0"]) - p['),
             ("equations.py", "0.5 * k * x**2", '0.5 * k * (x - p["x0"])**2')]
    cases = example(tmp_path, edits)
    assert main(["run", "--cases", str(cases), "--set", "x0=-0.02"]) == 0
    assert "x0 = -0.02 m" in capsys.readouterr().out


def test_an_engine_that_drops_its_dampers_is_refused(tmp_path, capsys, monkeypatch):
    """Were the Pinocchio side to lose the dampers it reads from the MJCF, the two engines' models of one file
    would disagree on load."""
    from engines import pinocchio_scene
    read = pinocchio_scene.joint_values
    monkeypatch.setattr(pinocchio_scene, "joint_values", lambda *args: {**read(*args), "damping": {}})
    status, _, err = run(example(tmp_path), capsys)
    assert status == 2
    assert "damping" in err


@pytest.mark.parametrize("law, shown", [('x = ["F0 * cos(Omega * tt)"]', "name 'tt' is not defined"),
                                        ('x = ["F0 * cos(Omega * t)", "1.0"]', "joint 'x' has 1 degree of freedom")])
def test_a_force_law_that_does_not_fit_is_refused(tmp_path, capsys, law, shown):
    """A name the law does not know, or two components on a slide's one degree of freedom."""
    status, _, err = run(example(tmp_path, [("case.toml", 'x = ["F0 * cos(Omega * t)"]', law)]), capsys)
    assert status == 2
    assert "scene.applied" in err and shown in err


def test_a_forcing_parameter_needs_its_unit(tmp_path, capsys):
    status, _, err = run(example(tmp_path, [("case.toml", '[params.Omega]\nunit = "rad/s"\n', "")]), capsys)
    assert status == 2
    assert "PARAMS['Omega'] is used by case.toml's [scene.applied]" in err


# The bob's reactions: the pin's force and the hinge's moment on it, read by a <force> and a <torque> sensor at
# its origin, in its frame; the derivation's from the bob's Newton equation m a_G = F + m g, and r x F.
SENSORS = [("scene.xml", '        <inertial pos="0 0 -0.5" mass="0.3" diaginertia="1e-14 1e-14 1e-14"/>\n',
            '        <inertial pos="0 0 -0.5" mass="0.3" diaginertia="1e-14 1e-14 1e-14"/>\n'
            '        <site name="hinge"/>\n'),
           ("scene.xml", "  </worldbody>\n", '  </worldbody>\n  <sensor>\n    <force name="pin" site="hinge"/>\n'
            '    <torque name="hinge" site="hinge"/>\n  </sensor>\n'),
           ("equations.py", "def drive_power(t, q, v, p):", '''def reactions(t, q, v, p):
    x, theta = q
    x_rate, theta_rate = v
    m, l, g = p["m"], p["l"], p["g"]
    x_acc, theta_acc = accelerations(t, q, v, p)
    fx = m * (x_acc + l * np.cos(theta) * theta_acc - l * np.sin(theta) * theta_rate**2)
    fz = m * (l * np.sin(theta) * theta_acc + l * np.cos(theta) * theta_rate**2 + g)
    return {"pin_x": np.cos(theta) * fx + np.sin(theta) * fz, "pin_z": -np.sin(theta) * fx + np.cos(theta) * fz,
            "hinge_x": 0.0, "hinge_y": -l * np.cos(theta) * fx - l * np.sin(theta) * fz, "hinge_z": 0.0}


def drive_power(t, q, v, p):''')]


def test_reaction_moments_agree_with_both_engines(tmp_path, capsys):
    status, out, _ = run(example(tmp_path, SENSORS), capsys)
    assert status == 0, out
    assert "hinge_y" in out and "pin_z" in out


def test_a_reaction_moment_of_the_wrong_sign_fails(tmp_path, capsys):
    flipped = SENSORS + [("equations.py", '"hinge_y": -l * np.cos(theta)', '"hinge_y": l * np.cos(theta)')]
    status, out, _ = run(example(tmp_path, flipped), capsys)
    assert status == 1
    assert "pointwise hinge_y (derivation vs mujoco): fail" in out
    assert "pointwise hinge_y (mujoco vs pinocchio)" not in out  # the engines agree with each other


def test_a_moment_read_about_another_point_is_refused(tmp_path, capsys):
    """The torque sensor's moment is about its site, Pinocchio's about the joint: a site off the body's origin
    would compare two moments about two points."""
    edits = [(file, old, new.replace('<site name="hinge"/>', '<site name="hinge" pos="0 0 -0.1"/>'))
             for file, old, new in SENSORS]
    status, _, err = run(example(tmp_path, edits), capsys)
    assert status == 2
    assert '<site pos="0 0 -0.1">' in err


def test_a_moment_read_by_a_force_sensor_is_refused(tmp_path, capsys):
    """A case file that calls a reaction a moment must name a torque sensor for it."""
    edits = SENSORS + [("case.toml", "[params.F0]", '[scene.reactions]\nhinge_y = { body = "bob", sensor = "pin", '
                                                      'axis = 1, frame = "body", quantity = "moment" }\n\n[params.F0]')]
    status, _, err = run(example(tmp_path, edits), capsys)
    assert status == 2
    assert "sensor 'pin' of reaction 'hinge_y' is a <force> sensor: a moment reaction reads a <torque> sensor" in err


def test_a_wrong_energy_is_named_while_the_equations_hold(tmp_path, capsys):
    """energy() is fitted as an equation is: its difference from the engines' over the random states and sets."""
    status, out, _ = run(example(tmp_path, [("equations.py", "return kinetic + 0.5 * k * x**2", "return kinetic + k * x**2")]),
                         capsys)
    assert status == 1
    assert "the derivation's energy: add - k / 2 x^2 to it to agree with the engines" in out
    assert "the derivation's equation" not in out
