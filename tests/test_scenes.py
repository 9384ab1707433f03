"""Every element and attribute of a scene file is modelled by both engines and compared, refused on
load, or without effect (engines.scene.RULES): the reproductions of issue 10 and a walk of the rules."""

import importlib
import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np
import pytest

import dyncheck
from dyncheck import cli
from dyncheck.case.folder import Case
from engines import scene

DOCS = Path(__file__).resolve().parent.parent / "docs" / "scene-elements.md"
MJCF_SCHEMA = Path(mujoco.__file__).parent / "doc" / "XMLschema.rst"
FILES = {"MJCF": "scene.xml", "URDF": "scene.urdf"}


def mutated(tmp_path, case, file, old, new):
    """A copy of a case whose scene `file` has every `old` replaced by `new`."""
    folder = tmp_path / case
    shutil.copytree(dyncheck.case.folder.CASES_DIR / case, folder)
    text = (folder / file).read_text()
    assert old in text, (case, file, old)
    (folder / file).write_text(text.replace(old, new))
    return Case(folder)


def load_both(case):
    case.model("pinocchio")
    case.model("mujoco")


# rotating_pendulum: alpha and beta prescribed (armature 1e12), psi free about X3, a force sensor at D.
PSI_MJCF = '<joint name="psi" type="hinge" axis="1 0 0"/>'
PSI_URDF = '<joint name="psi" type="continuous">'
OPTION = 'timestep="2.5e-4"/>'
SITE = '<site name="D"/>'
PLUGIN = ('<sensor>', '<extension><plugin plugin="mujoco.pid"><instance name="p"/></plugin></extension>'
          '<actuator><plugin plugin="mujoco.pid" instance="p" joint="psi"/></actuator><sensor>', "<plugin>")
FLEX = ('<worldbody>', '<worldbody><flexcomp name="rope" type="grid" count="3 1 1" spacing="0.1 0.1 0.1" dim="1"'
        ' pos="0 0 2"/>', "<flex>")

# For each refused rule, a minimal change of rotating_pendulum's scene that the loader must refuse, and
# what the message shows.
REFUSALS = {
    ("MJCF", "option", "density"): ('<option ', '<option density="1.2" ', '<option density="1.2">'),
    ("MJCF", "option", "viscosity"): ('<option ', '<option viscosity="1e-5" ', '<option viscosity="1e-05">'),
    ("MJCF", "option-flag", "gravity"): (OPTION, OPTION[:-2] + '><flag gravity="disable"/></option>',
                                         '<flag gravity="disable">'),
    ("MJCF", "option-flag", "spring"): (OPTION, OPTION[:-2] + '><flag spring="disable"/></option>',
                                        '<flag spring="disable">'),
    ("MJCF", "option-flag", "sensor"): (OPTION, OPTION[:-2] + '><flag sensor="disable"/></option>',
                                        '<flag sensor="disable">'),
    ("MJCF", "option-flag", "sleep"): (OPTION, OPTION[:-2] + '><flag sleep="enable"/></option>',
                                       '<flag sleep="enable">'),
    ("MJCF", "option-flag", "invdiscrete"): (OPTION, OPTION[:-2] + '><flag invdiscrete="enable"/></option>',
                                             '<flag invdiscrete="enable">'),
    ("MJCF", "body", "gravcomp"): ('<body name="pendulum" ', '<body name="pendulum" gravcomp="1" ',
                                   "body 'pendulum' <body gravcomp=\"1\">"),
    ("MJCF", "body", "mocap"): ('<worldbody>', '<worldbody><body name="target" mocap="true"/>', '<body mocap="true">'),
    ("MJCF", "body-joint", "name"): (PSI_MJCF, PSI_MJCF + '<joint name="extra" type="hinge" axis="0 1 0"/>',
                                     "joint 'extra' <joint name=\"extra\">"),
    ("MJCF", "body-joint", "pos"): (PSI_MJCF, PSI_MJCF[:-2] + ' pos="0 0 0.01"/>', '<joint pos="0 0 0.01">'),
    ("MJCF", "body-joint", "springyield"): (PSI_MJCF, PSI_MJCF[:-2] + ' springyield="0.1"/>',
                                            '<joint springyield="'),
    ("MJCF", "body-joint", "ref"): (PSI_MJCF, PSI_MJCF[:-2] + ' ref="0.2"/>', '<joint ref="'),
    ("MJCF", "body-joint", "damping"): (PSI_MJCF, PSI_MJCF[:-2] + ' damping="0.1 0.2"/>', '<joint damping="0.2 0">'),
    ("MJCF", "body-joint", "frictionloss"): (PSI_MJCF, PSI_MJCF[:-2] + ' frictionloss="0.1"/>',
                                             '<joint frictionloss="0.1">'),
    ("MJCF", "body-joint", "limited"): (PSI_MJCF, PSI_MJCF[:-2] + ' limited="true" range="-1 1"/>',
                                        '<joint limited="1">'),
    ("MJCF", "body-joint", "armature"): (PSI_MJCF, PSI_MJCF[:-2] + ' armature="0.01"/>', '<joint armature="0.01">'),
    ("MJCF", "body-freejoint", "*"): ('<worldbody>', '<worldbody><body name="ball" pos="0 0 1"><freejoint name="f"/>'
                                      '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>', "<freejoint>"),
    ("MJCF", "body-geom", "contype"): ('<worldbody>', '<worldbody><geom type="plane" size="1 1 0.1"/>',
                                      '<geom contype="1">'),
    ("MJCF", "body-geom", "conaffinity"): (
        '<worldbody>', '<worldbody><geom type="plane" size="1 1 0.1" contype="0" conaffinity="1"/>',
        '<geom conaffinity="1">'),
    ("MJCF", "body-flexcomp", "*"): FLEX,
    ("MJCF", "deformable-flex", "*"): FLEX,
    ("MJCF", "flex", "*"): FLEX,
    ("MJCF", "flexcomp", "*"): FLEX,
    ("MJCF", "body-plugin", "*"): PLUGIN,
    ("MJCF", "geom-plugin", "*"): PLUGIN,
    ("MJCF", "plugin", "*"): PLUGIN,
    ("MJCF", "instance", "*"): PLUGIN,
    ("MJCF", "extension", "*"): PLUGIN,
    ("MJCF", "contact-pair", "*"): ('<sensor>', '<contact><pair geom1="a" geom2="b"/></contact><sensor>', "<pair>"),
    ("MJCF", "body-site", "quat"): (SITE, '<site name="D" euler="0 0 0.1"/>', "<site quat="),
    ("MJCF", "equality", "*"): ('<sensor>', '<equality><joint joint1="psi"/></equality><sensor>', "equality '0' <joint>"),
    ("MJCF", "tendon", "*"): ('<sensor>', '<tendon><fixed><joint joint="psi" coef="1"/></fixed></tendon><sensor>',
                              "<tendon>"),
    ("MJCF", "spatial", "*"): ('<sensor>', '<tendon><spatial><site site="D"/><site site="O"/></spatial></tendon>'
                               '<sensor>', "<tendon>"),
    ("MJCF", "fixed", "*"): ('<sensor>', '<tendon><fixed><joint joint="psi" coef="1"/></fixed></tendon><sensor>',
                             "<tendon>"),
    ("MJCF", "actuator", "*"): ('<sensor>', '<actuator><motor joint="psi"/></actuator><sensor>', "<actuator>"),
    ("MJCF", "sensor", "cutoff"): ('site="D"/>', 'site="D" cutoff="0.5"/>', '<force cutoff="0.5">'),
    ("MJCF", "sensor", "nsample"): ('site="D"/>', 'site="D" nsample="2"/>', '<force nsample="2">'),
    ("URDF", "joint", "name"): ('</robot>', '<link name="extra"><inertial><mass value="0.1"/><inertia ixx="1e-3"'
                                ' ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link><joint name="extra"'
                                ' type="continuous"><parent link="pendulum"/><child link="extra"/></joint></robot>',
                                "joint 'extra' <joint name=\"extra\">"),
    ("URDF", "joint/limit", "lower"): (PSI_URDF, '<joint name="psi" type="revolute"><limit lower="-0.1"'
                                       ' upper="1e300" effort="0" velocity="0"/>', "<limit lower=\"-0.1\">"),
    ("URDF", "joint/limit", "upper"): (PSI_URDF, '<joint name="psi" type="revolute"><limit lower="-1e300"'
                                       ' upper="0.1" effort="0" velocity="0"/>', "<limit upper=\"0.1\">"),
    ("URDF", "joint/dynamics", "friction"): (PSI_URDF, PSI_URDF + '<dynamics friction="0.1"/>',
                                             "joint 'psi' <dynamics friction=\"0.1\">"),
    ("URDF", "joint/mimic", "*"): (PSI_URDF, PSI_URDF + '<mimic joint="beta"/>', "joint 'psi' <mimic>"),
}
# What some mutations need besides: geoms for a pair or a contact, a second site for a tendon.
GEOM = '<geom size="0.01"/>'
NEEDS = {("MJCF", "contact-pair", "*"): (SITE, SITE + '<geom name="a" size="0.01" contype="0" conaffinity="0"/>'
                                         '<geom name="b" size="0.01" contype="0" conaffinity="0"/>'),
         ("MJCF", "spatial", "*"): ("<worldbody>", '<worldbody><site name="O"/>'),
         ("MJCF", "body-geom", "contype"): (SITE, SITE + GEOM),
         ("MJCF", "body-geom", "conaffinity"): (SITE, SITE + GEOM)}


def refused_rules():
    return [(r.file, r.element, r.attribute) for r in scene.RULES if r.status == scene.REFUSED]


# Rules about moment reactions, which the book's cases have none of, and about what Pinocchio's MJCF reader
# misreads (the book's cases have a scene.urdf): mutated in these test modules.
ELSEWHERE = {("MJCF", "body-site", "pos"): ("test_mechanisms", "test_a_moment_read_about_another_point_is_refused"),
             ("MJCF", "sensor-torque", "site"): ("test_mechanisms", "test_a_moment_read_by_a_force_sensor_is_refused"),
             ("MJCF", "body-frame", "*"): ("test_own_scenes", "test_a_frame_read_by_pinocchio_is_refused_by_name")}


def test_every_refused_rule_has_a_mutation_here():
    """and the other mutations refuse values of compared attributes that cannot be compared."""
    assert all(hasattr(importlib.import_module(module), test) for module, test in ELSEWHERE.values())
    options = {key for key in refused_rules() if key[1] in ("option", "option-flag")}  # tests/test_scene_options.py
    assert set(refused_rules()) <= set(REFUSALS) | set(ELSEWHERE) | options
    assert {scene.rule(*key).status for key in set(REFUSALS) - set(refused_rules())} == {scene.COMPARED}


@pytest.mark.parametrize("key", sorted(REFUSALS))
# The FLEX mutations give MuJoCo a rope that nothing holds, which it compiles with this warning before dyncheck
# refuses the element: expected here.
@pytest.mark.filterwarnings("ignore:flex 'rope' is not rigid and has no equality constraints:UserWarning")
def test_each_refused_element_is_refused_on_load_naming_file_element_and_attribute(tmp_path, key):
    file, element, attribute = key
    old, new, shown = REFUSALS[key]
    folder = tmp_path / "rotating_pendulum"
    shutil.copytree(dyncheck.case.folder.CASES_DIR / "rotating_pendulum", folder)
    path = folder / FILES[file]
    text = path.read_text()
    assert old in text, key
    text = text.replace(old, new, 1)
    if key in NEEDS:
        text = text.replace(*NEEDS[key], 1)
    path.write_text(text)
    with pytest.raises(ValueError, match="is not modelled by dyncheck") as error:
        Case(folder).model("mujoco" if file == "MJCF" else "pinocchio")
    message = str(error.value)
    assert FILES[file] in message and shown in message, message
    assert "\n" not in message


# For each compared attribute, a change of rotating_pendulum's scene in one file only: refused once both
# engines are loaded, naming both files and what differs.
COMPARED = {
    ("MJCF", "option", "gravity"): ("scene.xml", 'gravity="0 0 -9.81"', 'gravity="0.5 0 -9.81"', "gravity"),
    ("MJCF", "body", "name"): ("scene.xml", '"pendulum"', '"bob"', "'bob'"),
    ("MJCF", "body", "pos"): ("scene.xml", 'pos="0 0.1 0.2"', 'pos="0.01 0.1 0.2"', "body 'pendulum' position"),
    ("MJCF", "body", "euler"): ("scene.xml", 'pos="0 0.1 0.2"', 'pos="0 0.1 0.2" euler="0 0 0.1"',
                                "body 'pendulum' rotation"),
    # a body welded to the pendulum in the MJCF only: its 0.1 kg joins the pendulum's
    ("MJCF", "body", "(joints)"): ("scene.xml", SITE, SITE + '<body name="extra"><inertial pos="0 0 0" mass="0.1"'
                                   ' diaginertia="1e-3 1e-3 1e-3"/></body>', "body 'pendulum' mass"),
    ("MJCF", "body-inertial", "*"): ("scene.xml", '<inertial pos="0 0 -0.1"', '<inertial pos="0.05 0 -0.1"',
                                     "body 'pendulum' centre of mass"),
    ("MJCF", "body-joint", "type"): ("scene.xml", 'name="psi" type="hinge"', 'name="psi" type="slide"',
                                     "body 'pendulum' joint_type is 'slide' in scene.xml and 'hinge'"),
    ("MJCF", "body-joint", "axis"): ("scene.xml", PSI_MJCF, PSI_MJCF.replace("1 0 0", "0 1 0"), "body 'pendulum' axis"),
    ("MJCF", "body-joint", "stiffness"): ("scene.xml", PSI_MJCF, PSI_MJCF[:-2] + ' stiffness="0.1"/>',
                                          "body 'pendulum' stiffness"),
    ("MJCF", "body-joint", "springdamper"): ("scene.xml", PSI_MJCF, PSI_MJCF[:-2] + ' springdamper="1 0.5"/>',
                                             "body 'pendulum' stiffness"),
    ("MJCF", "body-joint", "springref"): ("scene.xml", PSI_MJCF, PSI_MJCF[:-2] + ' springref="0.3"/>',
                                          "body 'pendulum' springref"),
    ("MJCF", "body-joint", "damping"): ("scene.xml", PSI_MJCF, PSI_MJCF[:-2] + ' damping="0.1"/>',
                                        "body 'pendulum' damping"),
    ("URDF", "joint/dynamics", "damping"): ("scene.urdf", PSI_URDF, PSI_URDF + '<dynamics damping="0.1"/>',
                                            "body 'pendulum' damping"),
    ("MJCF", "sensor-force", "site"): ("scene.xml", '<force name="rod_on_particle"', '<torque name="rod_on_particle"',
                                       "is a <torque> sensor"),
    ("URDF", "link", "name"): ("scene.urdf", '"pendulum"', '"bob"', "'pendulum'"),
    ("URDF", "link/inertial/origin", "xyz"): ("scene.urdf", '<origin xyz="0 0 -0.1"/>',
                                              '<origin xyz="0.05 0 -0.1"/>', "body 'pendulum' centre of mass"),
    ("URDF", "link/inertial/origin", "rpy"): ("scene.urdf", '<origin xyz="0 0 0.0558"/>',
                                              '<origin xyz="0 0 0.0558" rpy="0.2 0 0"/>',
                                              "body 'top' inertia", "spinning_top"),
    ("URDF", "link/inertial/mass", "value"): ("scene.urdf", '<link name="disk"/>', '<link name="disk"><inertial>'
                                              '<mass value="0.3"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0"'
                                              ' izz="0"/></inertial></link>', "body 'disk' mass"),
    ("URDF", "link/inertial/inertia", "*"): ("scene.urdf", 'ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"',
                                             'ixx="1e-3" ixy="1e-4" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"',
                                             "body 'pendulum' inertia about the centre of mass"),
    ("URDF", "joint", "type"): ("scene.urdf", PSI_URDF, '<joint name="psi" type="floating">',
                                "<joint type=\"floating\">"),
    ("URDF", "joint/origin", "*"): ("scene.urdf", '<origin xyz="0 0.1 0.2"/>', '<origin xyz="0 0.1 0.2" rpy="0 0 0.1"/>',
                                    "body 'pendulum' rotation"),
    ("URDF", "joint/axis", "xyz"): ("scene.urdf", '<axis xyz="1 0 0"/>', '<axis xyz="1 0.01 0"/>',
                                    "body 'pendulum' axis"),
    ("URDF", "joint/parent", "link"): ("scene.urdf", '<parent link="disk"/><child link="pendulum"/>',
                                       '<parent link="arm"/><child link="pendulum"/>', "body 'pendulum' parent"),
    ("URDF", "joint/child", "link"): ("scene.urdf", '<parent link="arm"/><child link="disk"/>',
                                      '<parent link="arm"/><child link="pendulum"/>', "scene.urdf"),
}


# A loop's <connect>, which the book's cases have none of: compared in tests/test_loops.py.
LOOPS = {("MJCF", "equality-connect", "*"): "test_a_loop_left_open_in_the_urdf_is_refused"}


def test_every_compared_rule_has_a_mutation_here():
    import test_loops
    assert all(hasattr(test_loops, test) for test in LOOPS.values())
    compared = {(r.file, r.element, r.attribute) for r in scene.RULES if r.status == scene.COMPARED}
    orientations = {("MJCF", "body", a) for a in ("quat", "axisangle", "xyaxes", "zaxis")}  # as euler
    assert set(COMPARED) | orientations | {("MJCF", "body-joint", "name"), ("URDF", "joint", "name")} | \
        {key for key in ELSEWHERE if scene.rule(*key).status == scene.COMPARED} | set(LOOPS) == compared


@pytest.mark.parametrize("key", sorted(COMPARED))
def test_a_compared_attribute_changed_in_one_file_is_refused(tmp_path, key):
    file, old, new, shown, *case_name = COMPARED[key]  # rotating_pendulum unless named
    case = mutated(tmp_path, *(case_name or ["rotating_pendulum"]), file, old, new)
    with pytest.raises(ValueError) as error:
        load_both(case)
    message = str(error.value)
    assert file in message and shown in message, message
    assert "\n" not in message


def test_the_same_rotations_written_in_both_files_are_accepted(tmp_path):
    """The top's inertia frame and the pendulum's body turned about their Z by the same angle in both
    files (MJCF quat, URDF rpy): the loaders' roundings stay inside the comparison's tolerance."""
    half = 0.15
    quat = f'quat="{float(np.cos(half))!r} 0 0 {float(np.sin(half))!r}"'
    for name, xml_old, urdf_old in (
            ("spinning_top", '<inertial pos="0 0 0.0558"', '<origin xyz="0 0 0.0558"'),
            ("rotating_pendulum", '<body name="pendulum" pos="0 0.1 0.2"', '<origin xyz="0 0.1 0.2"')):
        folder = tmp_path / name
        shutil.copytree(dyncheck.case.folder.CASES_DIR / name, folder)
        for file, old, new in (("scene.xml", xml_old, f"{xml_old} {quat}"),
                               ("scene.urdf", urdf_old, f'{urdf_old} rpy="0 0 {2 * half!r}"')):
            text = (folder / file).read_text()
            assert text.count(old) == 1, (name, file)
            (folder / file).write_text(text.replace(old, new))
        load_both(Case(folder))


# -- the reproductions of issue 10, one by one --------------------------------------------------------
@pytest.mark.parametrize("case_name, file, old, new, shown", [
    ("rotating_pendulum", "scene.urdf", PSI_URDF, PSI_URDF + '<dynamics damping="0.1"/>', "body 'pendulum' damping"),
    ("rotating_pendulum", "scene.urdf", PSI_URDF, PSI_URDF + '<dynamics friction="0.1"/>', "<dynamics friction"),
    ("spring_pendulum", "scene.urdf", 'lower="-1e300" upper="1e300"', 'lower="-0.01" upper="0.01"', "<limit lower"),
    ("rotating_pendulum", "scene.xml", 'gravity="0 0 -9.81"', 'gravity="0.5 0 -9.81"', "gravity"),
    ("rotating_pendulum", "scene.xml", '<inertial pos="0 0 -0.1"', '<inertial pos="0.05 0 -0.1"', "centre of mass"),
    ("rotating_pendulum", "scene.xml", SITE, SITE + '<body name="stray" pos="0 0 -0.2"><inertial pos="0 0 0"'
     ' mass="0.05" diaginertia="1e-5 1e-5 1e-5"/></body>', "body 'pendulum' mass"),  # welded: its mass joins
    ("spinning_top", "scene.xml", '<inertial pos="0 0 0.0558"', '<inertial pos="0 0 0.0558" quat="0.99 0.14 0 0"',
     "body 'top' inertia"),
    ("spinning_top", "scene.xml", 'diaginertia="0.00113716152 0.00113716152 0.002268"',
     'fullinertia="0.00113716152 0.00113716152 0.002268 1e-4 0 0"', "body 'top' inertia"),
    ("spinning_top", "scene.urdf", '<origin xyz="0 0 0.0558"/>', '<origin xyz="0 0 0.0558" rpy="0.2 0 0"/>',
     "body 'top' inertia"),
    ("rotating_pendulum", "scene.xml", PSI_MJCF, PSI_MJCF + '<joint name="extra" type="hinge" axis="0 1 0"/>',
     "joint 'extra'"),
    ("rotating_pendulum", "scene.xml", '<force name="rod_on_particle"', '<torque name="rod_on_particle"',
     "is a <torque> sensor"),
    ("rotating_pendulum", "scene.xml", PSI_MJCF, PSI_MJCF[:-2] + ' stiffness="0.1" springref="0.3"/>',
     "body 'pendulum' stiffness"),
])
def test_issue_10_scenes_that_passed_or_failed_as_engine_disagreements_are_bad_input(
        tmp_path, case_name, file, old, new, shown):
    case = mutated(tmp_path, case_name, file, old, new)
    with pytest.raises(ValueError) as error:
        load_both(case)
    assert file in str(error.value) and shown in str(error.value), str(error.value)


def test_the_command_line_refuses_a_scene_the_other_file_contradicts(tmp_path, monkeypatch, capsys):
    """Exit 2 before any check runs: `run` loads every model up front, and the comparison with them."""
    mutated(tmp_path, "rotating_pendulum", "scene.xml", 'gravity="0 0 -9.81"', 'gravity="0.5 0 -9.81"')
    monkeypatch.setattr(cli, "run_case", lambda case, localise=True, quick=False: pytest.fail("ran a case with a bad scene"))
    assert cli.main(["run", "rotating_pendulum", "--cases", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dyncheck: error: ") and "scene.xml and scene.urdf" in err and "gravity" in err


# -- the rules themselves ------------------------------------------------------------------------------
def mjcf_reference():
    """(element anchor, attribute) of every attribute in MuJoCo's XML reference shipped with the wheel."""
    anchors = re.findall(r"grid-item::\s*\n\s*:ref:`[^<]+<([^>]+)>`", MJCF_SCHEMA.read_text())
    return sorted({tuple(anchor.rsplit("-", 1)) for anchor in anchors})


def test_every_attribute_of_mujocos_reference_has_a_rule():
    listed = mjcf_reference()
    assert len(listed) > 1000  # the reference was read
    assert [pair for pair in listed if not _has_rule("MJCF", *pair)] == []


def _has_rule(file, element, attribute):
    try:
        scene.rule(file, element, attribute)
        return True
    except KeyError:
        return False


@pytest.mark.parametrize("name", dyncheck.case_names())
def test_every_urdf_element_and_attribute_of_the_cases_has_a_rule(name):
    root = ET.parse(dyncheck.case.folder.CASES_DIR / name / "scene.urdf").getroot()

    def walk(element, path):
        for child in element:
            here = f"{path}/{child.tag}" if path else child.tag
            for attribute in child.attrib:
                assert _has_rule("URDF", here, attribute), (here, attribute)
            walk(child, here)
    walk(root, "")


def test_the_docs_table_is_current():
    assert DOCS.read_text() == scene.markdown(), "regenerate: python -c 'import engines.scene as s; print(s.markdown(), end=\"\")' > docs/scene-elements.md"
