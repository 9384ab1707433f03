"""A researcher's MJCF read alike by both engines, or refused in words (issue 34): angles under MJCF's default
<compiler angle="degree">, a <frame>, a body Pinocchio's reader finds no inertia of, a URDF fixed joint."""

import math
import shutil

import pytest

import dyncheck
from dyncheck.case.folder import Case
from dyncheck.cli import main
from test_scene_options import edit, tutorial

THETA = '<joint name="theta" type="hinge" axis="0 -1 0"/>'
BOB = '<inertial pos="0 0 -0.5" mass="0.3" diaginertia="1e-14 1e-14 1e-14"/>'


def with_hinge_spring(folder, rest='p["theta0"]', rest_value=math.radians(30)):
    """The tutorial's cart-pendulum with a spring of 0.7 N m/rad on theta, relaxed at 30 degrees (the file's
    springref="30", in MJCF's default degrees); its derivation's spring relaxed at `rest`."""
    case = tutorial(folder, damper=False)
    edit(case / "scene.xml", THETA, THETA.replace("/>", ' stiffness="0.7" springref="30"/>'))
    edit(case / "equations.py", '"g": 9.81}', f'"g": 9.81, "kt": 0.7, "theta0": {rest_value!r}}}')
    edit(case / "equations.py", "-m * g * l * np.sin(theta)]", f'-m * g * l * np.sin(theta) - p["kt"] * (theta - {rest})]')
    edit(case / "equations.py", "- m * g * l * np.cos(theta)\n",
         f'- m * g * l * np.cos(theta) + 0.5 * p["kt"] * (theta - {rest})**2\n')
    return case


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_hinge_spring_relaxed_at_30_degrees_passes_dyncheck_run(tmp_path, capsys):
    """Was refused: the Pinocchio side read springref="30" as 30 rad, MuJoCo as 30 degrees."""
    with_hinge_spring(tmp_path)
    assert main(["run", "--cases", str(tmp_path)]) == 0, capsys.readouterr()


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_derivation_whose_hinge_spring_is_relaxed_at_0_fails(tmp_path, capsys):
    """The spring's rest position acts in both engines: a derivation without it fails against each."""
    with_hinge_spring(tmp_path, rest="0.0")
    assert main(["run", "--cases", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "theta_acc (derivation vs mujoco): fail" in out and "theta_acc (derivation vs pinocchio): fail" in out, out


def test_a_springref_set_in_rad_reaches_both_engines_of_a_degree_scene(tmp_path):
    """--set theta0=0.6 (rad): MuJoCo's spec holds degrees, the Pinocchio side rad."""
    case = Case(with_hinge_spring(tmp_path), {"theta0": 0.6})
    for source in ("mujoco", "pinocchio"):  # each read back against the case on load (Case._verify)
        assert case.model(source).tree()[-1].springref == pytest.approx(0.6, rel=1e-15), source


@pytest.mark.parametrize("old, new", [
    ('<body name="bob">', '<body name="bob" euler="0 0 30">'),
    ('<body name="bob">', '<body name="bob" axisangle="0 0 1 30">'),
    (BOB, '<inertial pos="0 0 -0.5" euler="10 20 30" mass="0.3" diaginertia="1e-3 2e-3 3e-3"/>'),
    (BOB, '<inertial pos="0 0 -0.5" axisangle="1 0 0 30" mass="0.3" diaginertia="1e-3 2e-3 3e-3"/>'),
    ('<option', '<default><default class="spring"><joint stiffness="0.7" springref="30"/></default></default><option'),
])
def test_angles_in_degrees_are_read_alike_by_both_engines(tmp_path, old, new):
    """Orientations and a class's springref under <compiler angle="degree"> (MJCF's default): both engines' bodies
    compared on load (dyncheck.case.folder.compare_scenes), rotations, inertias and springs."""
    case = with_hinge_spring(tmp_path)
    if "class" in new:  # the joint's spring from the class instead
        edit(case / "scene.xml", 'stiffness="0.7" springref="30"/>', 'class="spring"/>')
    edit(case / "scene.xml", old, new)
    loaded = Case(case)
    loaded.model("mujoco")
    assert loaded.model("pinocchio").tree()[-1].springref == pytest.approx(math.radians(30), rel=1e-15)


def test_a_frame_read_by_pinocchio_is_refused_by_name(tmp_path):
    """Pinocchio's MJCF reader (4.1) drops the bodies inside a <frame>: the case said "no joint named 'theta'"."""
    case = tutorial(tmp_path, damper=False)
    text = (case / "scene.xml").read_text()
    (case / "scene.xml").write_text(text.replace('<body name="bob">', '<frame name="hanger" pos="0 0 0">'
                                                 '<body name="bob">').replace("</body>\n    </body>",
                                                                               "</body></frame>\n    </body>"))
    with pytest.raises(ValueError) as error:
        Case(case).model("pinocchio")
    message = str(error.value)
    assert message.startswith(f"{case / 'scene.xml'}: frame 'hanger' <frame> is not modelled by dyncheck"), message
    assert "drops the bodies inside it" in message and "no joint named" not in message


def test_a_body_pinocchio_finds_no_inertia_of_is_named_in_words(tmp_path):
    """A ground body with a geom and no <inertial> under <compiler inertiafromgeom="false">: Pinocchio's
    reader said only its C++ source file, function and "Cannot get inertia from geom and no inertia was found"."""
    case = tutorial(tmp_path, damper=False)
    text = (case / "scene.xml").read_text().replace('<option', '<compiler inertiafromgeom="false"/><option')
    text = text.replace('<body name="cart">', '<body name="rail"><geom type="box" size="1 0.01 0.01"/>'
                        '<body name="cart">').replace("</worldbody>", "</body></worldbody>")
    (case / "scene.xml").write_text(text)
    with pytest.raises(ValueError) as error:
        Case(case).model("pinocchio")
    message = str(error.value)
    assert message.startswith(f"{case / 'scene.xml'}: body 'rail' has a geom and no <inertial>"), message
    assert "inertiafromgeom" in message and ".cpp" not in message and "\n" not in message


def test_a_urdf_fixed_joint_welds_its_link_and_its_mass_is_compared(tmp_path):
    """Was refused for its type (issue 37): a fixed joint welds its link to its parent, whose mass it joins; a
    massless tip loads, a tip of 0.1 kg that the MJCF has not is refused by the scene comparison, naming the mass."""
    folder = tmp_path / "rotating_pendulum"
    shutil.copytree(dyncheck.case.folder.CASES_DIR / "rotating_pendulum", folder)
    weld = '<joint name="weld" type="fixed"><parent link="pendulum"/><child link="tip"/></joint></robot>'
    text = (folder / "scene.urdf").read_text()
    edit(folder / "scene.urdf", "</robot>", '<link name="tip"/>' + weld)
    loaded = Case(folder)
    loaded.model("mujoco")
    loaded.model("pinocchio")
    (folder / "scene.urdf").write_text(text.replace("</robot>", '<link name="tip"><inertial><mass value="0.1"/>'
                                                    '<inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/>'
                                                    '</inertial></link>' + weld))
    loaded = Case(folder)
    loaded.model("mujoco")
    with pytest.raises(ValueError) as error:
        loaded.model("pinocchio")
    assert "body 'pendulum' mass is " in str(error.value), error.value
