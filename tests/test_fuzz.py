"""Adversarial fuzzing (issue 10): mutated scene files, hostile `--set` values and hostile expressions in
case files.  Each input must load or be refused with a ValueError (exit 2); never another exception, and a
scene mutation that changes what engines.scene compares or refuses must not load silently.

DYNCHECK_FUZZ_EXAMPLES raises every test's max_examples for an offline campaign; DYNCHECK_FUZZ_LOG names a
file to which each input's outcome class is appended (one line: fuzzer, class, input)."""

import contextlib
import io
import math
import os
import shutil
import signal
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import dyncheck
from dyncheck.case.folder import CASES_DIR, SOURCES, Case
import dyncheck.cli

N = int(os.environ.get("DYNCHECK_FUZZ_EXAMPLES", "0"))
LOG = os.environ.get("DYNCHECK_FUZZ_LOG")
CAMPAIGN = bool(N and LOG)  # count every outcome instead of stopping at the first failure
HANG = 60  # seconds: an input that takes longer is a hang


def examples(default):
    return settings(max_examples=N or default, deadline=None, derandomize=not N,
                    suppress_health_check=list(HealthCheck))


def record(fuzzer, outcome, what):
    if LOG:
        with open(LOG, "a") as f:
            f.write(f"{fuzzer}\t{outcome}\t{what!r}\n")


class Hang(Exception):
    pass


def bounded(fn, *args):
    def alarm(*_):
        raise Hang()
    old = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(HANG)
    try:
        return fn(*args)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


# -- values ---------------------------------------------------------------------------------------
NUMBERS = st.one_of(st.sampled_from([0.0, -0.0, -1.0, 1.0, 1e300, -1e300, 1e-300, math.nan, math.inf, -math.inf,
                                     1e-12, 2.0, 0.5]),
                    st.floats(allow_nan=True, allow_infinity=True))
TEXT = st.one_of(st.sampled_from(["", " ", "abc", "true", "false", "auto", "disable", "enable", "1 2", "1,2,3",
                                  "0x10", "1e", "--1", "nan nan nan", "\u0661", "１", "1\u00a02", "&amp;", "∞"]),
                 st.text(max_size=8))


def vector(n):
    return st.lists(NUMBERS, min_size=n, max_size=n).map(lambda xs: " ".join(repr(x) for x in xs))


VALUES = st.one_of(NUMBERS.map(repr), vector(2), vector(3), vector(4), vector(6), TEXT)

# -- scene mutations ------------------------------------------------------------------------------
SCENE_CASES = ["rotating_pendulum", "spring_pendulum", "double_pendulum", "spinning_top"]
# (path from the root, attribute): refused by engines.scene.RULES on any value but the default
MJCF_REFUSED = [("option", "density"), ("option", "viscosity"), ("option/flag", "gravity"), ("option/flag", "spring"),
                ("option/flag", "sensor"), ("option/flag", "sleep"), ("option/flag", "invdiscrete"),
                (".//body", "gravcomp"), (".//body", "mocap"), (".//joint", "pos"), (".//joint", "springref"),
                (".//joint", "springyield"), (".//joint", "ref"), (".//joint", "damping"),
                (".//joint", "frictionloss"), (".//joint", "limited"), (".//joint", "armature"),
                (".//site", "quat"), (".//site", "euler"), ("sensor/force", "cutoff"), ("sensor/force", "nsample")]
MJCF_COMPARED = [("option", "gravity"), (".//body", "name"), (".//body", "pos"), (".//body", "quat"),
                 (".//body", "axisangle"), (".//body", "xyaxes"), (".//body", "zaxis"), (".//body", "euler"),
                 (".//inertial", "mass"), (".//inertial", "pos"), (".//inertial", "diaginertia"),
                 (".//inertial", "fullinertia"), (".//inertial", "quat"), (".//joint", "name"), (".//joint", "type"),
                 (".//joint", "axis"), (".//joint", "stiffness"), (".//joint", "springdamper"),
                 ("sensor/force", "site"), ("compiler", "settotalmass"), ("compiler", "angle"),
                 ("compiler", "eulerseq"), ("compiler", "boundmass"), ("compiler", "boundinertia"),
                 ("compiler", "inertiafromgeom"), ("compiler", "balanceinertia"), ("compiler", "autolimits")]
MJCF_OTHER = [("option", "timestep"), ("option", "integrator"), ("option", "wind"), ("option", "magnetic"),
              ("option/flag", "contact"), ("option/flag", "energy"), ("size", "memory"), (".//joint", "range"),
              (".//joint", "group"), (".//body", "childclass"), (".//site", "pos"), ("mujoco", "model"),
              (".//joint", "bogus"), ("option", "bogus")]
URDF_REFUSED = [("joint/limit", "lower"), ("joint/limit", "upper"), ("joint/dynamics", "damping"),
                ("joint/dynamics", "friction"), ("joint/mimic", "joint"), ("joint/mimic", "multiplier")]
URDF_COMPARED = [("link", "name"), ("link/inertial/origin", "xyz"), ("link/inertial/origin", "rpy"),
                 ("link/inertial/mass", "value"), *[("link/inertial/inertia", i) for i in
                                                    ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")],
                 ("joint", "name"), ("joint", "type"), ("joint/origin", "xyz"), ("joint/origin", "rpy"),
                 ("joint/axis", "xyz"), ("joint/parent", "link"), ("joint/child", "link")]
URDF_OTHER = [("joint/limit", "effort"), ("joint/limit", "velocity"), ("robot", "name"), ("link", "bogus"),
              ("joint", "bogus")]
MJCF_STRAY = [  # (parent path, element text)
    (".", '<tendon><fixed name="t"><joint joint="{j}" coef="1"/></fixed></tendon>'),
    (".", '<equality><joint joint1="{j}"/></equality>'), (".", '<actuator><motor joint="{j}"/></actuator>'),
    (".", '<contact><pair geom1="g1" geom2="g2"/></contact>'), (".", '<contact><exclude body1="{b}" body2="{b}"/></contact>'),
    (".", '<visual><global fovy="30"/></visual>'), (".", '<size memory="1M"/>'), (".", '<statistic extent="2"/>'),
    (".", '<custom><numeric name="n" data="1 2"/></custom>'), (".", '<keyframe><key time="1"/></keyframe>'),
    (".", '<asset><material name="mat" rgba="1 0 0 1"/></asset>'), (".", '<default><joint damping="1"/></default>'),
    (".", '<default><geom contype="1" conaffinity="1"/></default>'), (".", '<compiler settotalmass="5"/>'),
    (".", '<bogus/>'), (".", '<extension><plugin plugin="mujoco.elasticity.cable"/></extension>'),
    (".//body", '<freejoint/>'), (".//body", '<joint name="extra" type="hinge"/>'),
    (".//body", '<geom name="g1" type="sphere" size="0.01" mass="0"/>'),
    (".//body", '<geom name="g2" type="sphere" size="0.01" mass="0" contype="1" conaffinity="1"/>'),
    (".//body", '<geom type="sphere" size="0.01" contype="0" conaffinity="0" mass="1"/>'),
    (".//body", '<geom type="sphere" size="0.01" contype="0" conaffinity="0"/>'),
    (".//body", '<site name="s2"/>'), (".//body", '<camera name="c"/>'), (".//body", '<light name="l"/>'),
    (".//body", '<body name="welded"><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>'),
    (".//body", '<body name="extra"><joint name="{j}2"/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>'),
    (".//body", '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>'), (".//body", '<bogus/>'),
    (".//body", '<plugin plugin="mujoco.pid"/>'), ("worldbody", '<body name="free"><freejoint/><geom size="1" contype="0" conaffinity="0"/></body>'),
    ("worldbody", '<geom type="plane" size="1 1 1"/>'),
    ("sensor", '<force site="{s}" cutoff="1"/>'), ("sensor", '<jointpos joint="{j}"/>'),
]
URDF_STRAY = [
    ("joint", '<mimic joint="{j}"/>'), ("joint", '<dynamics damping="1"/>'), ("joint", '<dynamics damping="0" friction="0"/>'),
    ("joint", '<limit lower="-1" upper="1" effort="0" velocity="0"/>'), ("joint", '<calibration rising="0"/>'),
    ("joint", '<safety_controller k_velocity="1"/>'), ("joint", '<bogus/>'),
    ("link", '<visual><geometry><sphere radius="1"/></geometry></visual>'),
    ("link", '<collision><geometry><box size="1 1 1"/></geometry></collision>'),
    ("link", '<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>'),
    ("link", '<bogus/>'), (".", '<material name="m"><color rgba="1 0 0 1"/></material>'),
    (".", '<transmission name="t"><type>x</type></transmission>'), (".", '<gazebo reference="x"/>'),
    (".", '<link name="stray"/>'), (".", '<joint name="stray" type="fixed"><parent link="world"/><child link="stray"/></joint>'),
    (".", '<joint name="stray" type="floating"><parent link="world"/><child link="stray"/></joint>'),
    (".", '<link name="stray"/><joint name="stray" type="fixed"><parent link="world"/><child link="stray"/></joint>'),
    (".", '<bogus/>'),
]


def _targets(root, path):
    """Elements at `path`, creating the leaf (e.g. option/flag) if it is missing."""
    found = root.findall(path) if path != "." else [root]
    if path == "mujoco" or path == "robot":
        return [root]
    if found:
        return found
    if "//" in path:
        return []
    parent = root
    for tag in path.split("/"):
        child = parent.find(tag)
        parent = child if child is not None else ET.SubElement(parent, tag)
    return [parent]


def mutate_scene(folder, kind, file, pick, value, data_index):
    """Apply a mutation to folder's scene file; return a description (or None if it found no target)."""
    path = folder / ("scene.xml" if file == "MJCF" else "scene.urdf")
    root = ET.parse(path).getroot()
    if kind == "stray":
        table = MJCF_STRAY if file == "MJCF" else URDF_STRAY
        parent_path, text = table[pick % len(table)]
        joint = root.find(".//joint").get("name") if root.find(".//joint") is not None else "tip"
        body = root.find(".//body").get("name") if file == "MJCF" else "x"
        site = root.find(".//site").get("name") if root.find(".//site") is not None else "x"
        text = text.format(j=joint, b=body, s=site)
        parents = _targets(root, parent_path)
        if not parents:
            return None
        parent = parents[data_index % len(parents)]
        for child in ET.fromstring(f"<x>{text}</x>"):
            parent.append(child)
        what = f"{path.name}: add {text} to <{parent.tag} {parent.attrib.get('name', '')}>"
    else:
        table = {("MJCF", "refused"): MJCF_REFUSED, ("MJCF", "compared"): MJCF_COMPARED,
                 ("MJCF", "other"): MJCF_OTHER, ("URDF", "refused"): URDF_REFUSED,
                 ("URDF", "compared"): URDF_COMPARED, ("URDF", "other"): URDF_OTHER}[file, kind]
        element_path, attribute = table[pick % len(table)]
        if file == "URDF" and element_path.startswith(("joint/", "link/")) and element_path.count("/") >= 1:
            targets = _targets(root, element_path) if root.findall(element_path) else []
            if not targets:  # create it under a joint or link
                owner_tag, *rest = element_path.split("/")
                owners = root.findall(owner_tag)
                if not owners:
                    return None
                owner = owners[data_index % len(owners)]
                node = owner
                for tag in rest:
                    nxt = node.find(tag)
                    node = nxt if nxt is not None else ET.SubElement(node, tag)
                targets = [node]
        else:
            targets = _targets(root, element_path)
        if not targets:
            return None
        target = targets[data_index % len(targets)]
        old = target.get(attribute)
        if old is not None and _same(old, value):
            return None  # not a change
        target.set(attribute, value)
        what = f"{path.name}: <{target.tag} {target.attrib.get('name', '')}> {attribute}={value!r} (was {old!r})"
    path.write_text(ET.tostring(root, encoding="unicode"))
    return what


def _same(a, b):
    try:
        return np.array_equal(np.array(a.split(), dtype=float), np.array(b.split(), dtype=float), equal_nan=True)
    except ValueError:
        return a.strip() == b.strip()


_BASELINE = {}


def baseline(name):
    if name not in _BASELINE:
        case = Case(CASES_DIR / name)
        states = case.sample_states()[:3]
        models = {s: case.model(s) for s in SOURCES}
        _BASELINE[name] = (states, {s: _quantities(models[s], states) for s in ("reference", "mujoco", "pinocchio")},
                           {s: models[s] for s in ("mujoco", "pinocchio")})
    return _BASELINE[name]


def _flat(x):
    if isinstance(x, dict):
        return np.concatenate([_flat(x[k]) for k in sorted(x)]) if x else np.zeros(0)
    return np.ravel(np.asarray(x, dtype=float))


def _quantities(model, states):
    """What the pointwise check compares, at `states`: accelerations, reactions, energy and drive power."""
    return np.concatenate([np.concatenate([_flat(model.accelerations(t, q, v)), _flat(model.reactions(t, q, v)),
                                           _flat(model.energy(t, q, v)), _flat(model.drive_power(t, q, v))])
                           for t, q, v in states])


def _tree(model):
    return np.concatenate([np.ravel(model.gravity)] + [np.concatenate(
        [b.axis, b.position, np.ravel(b.rotation), [b.mass], b.com, np.ravel(b.inertia), b.stiffness])
        for b in model.tree()])


def scene_outcome(name, kind, file, pick, value, index):
    """(class, description) of one scene mutation."""
    states, expected, base_models = baseline(name)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / name
        shutil.copytree(CASES_DIR / name, folder)
        what = mutate_scene(folder, kind, file, pick, value, index)
        if what is None:
            return "no mutation", None
        try:
            def load():
                case = Case(folder)
                return case, [case.model(s) for s in SOURCES]
            case, _ = bounded(load)
        except ValueError:
            return "refused", what
        except Hang:
            return "hang", what
        except Exception as error:  # noqa: BLE001 - any other exception is the finding
            return "traceback", f"{what}: {type(error).__name__}: {error}"
        engine = "mujoco" if file == "MJCF" else "pinocchio"
        try:
            got = bounded(_quantities, case.model(engine), states)
        except (ArithmeticError, ValueError):  # the pointwise check fails on it
            return "caught by checks", what
        except Hang:
            return "hang", what
        except Exception as error:  # noqa: BLE001
            return "traceback", f"{what} (evaluating): {type(error).__name__}: {error}"
        ref = expected["reference"]
        if not np.all(np.isfinite(got)) or np.max(np.abs(got - ref)) > 1e-6 * max(1.0, np.max(np.abs(ref))):
            return "caught by checks", what
        # the engines agree with the reference: did the mutation change what the scene models?
        a, b = _tree(case.model(engine)), _tree(base_models[engine])
        if a.shape != b.shape or np.max(np.abs(a - b)) > 1e-9 * max(1.0, np.max(np.abs(b))):
            return "silent pass", what
        if kind in ("refused", "compared"):
            return "loaded (value equivalent to the file's)", what
        return "loaded", what


@pytest.fixture(autouse=True, scope="module")
def _quiet_mujoco():
    import mujoco
    mujoco.set_mju_user_warning(lambda message: None)


@examples(60)
@given(name=st.sampled_from(SCENE_CASES), kind=st.sampled_from(["refused", "compared", "other", "stray"]),
       file=st.sampled_from(["MJCF", "URDF"]), pick=st.integers(0, 1000), value=VALUES, index=st.integers(0, 10))
@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_mutated_scene_file_is_refused_or_loads_what_the_checks_compare(name, kind, file, pick, value, index):
    outcome, what = scene_outcome(name, kind, file, pick, value, index)
    record("scene", outcome, what)
    assert CAMPAIGN or outcome not in ("traceback", "hang", "silent pass"), what


# -- `--set` values -------------------------------------------------------------------------------
HOSTILE = st.one_of(st.text(max_size=20), st.text(alphabet=st.characters(codec="utf-8"), max_size=20),
                    st.sampled_from(["", "=", "==1", " 1 ", "1_000", "0x1p3", "1e400", "-1e400", "nan", "-inf",
                                     "infinity", "\x00", "1\x00", "\u0661", "１", "٫5", "1e-400", "1" * 400,
                                     "9" * 5000, "0.2\n", "\t0.3", "+0.1", "-0.2", "0", "1e300", "1/3", "pi",
                                     "m", "'", "\"", "\\", "$(rm -rf /)", "\ud800".encode("utf-8", "surrogatepass")
                                     .decode("utf-8", "surrogateescape")]),
                    st.floats().map(repr), st.floats(0.01, 10.0).map(repr))


def set_outcome(value, monkeypatch):
    monkeypatch.setattr(dyncheck.cli, "run_cases", lambda cases, localise=True, quick=False: ([], None))
    monkeypatch.setattr(dyncheck.cli, "print_results", lambda *a, **k: None)
    try:
        code = bounded(dyncheck.cli.main, ["run", "piston", "--set", f"m={value}"])
    except Hang:
        return "hang"
    except SystemExit as exit:  # argparse
        return "refused" if exit.code == 2 else f"traceback (exit {exit.code})"
    except Exception as error:  # noqa: BLE001
        return f"traceback ({type(error).__name__}: {error})"
    return {0: "loaded", 2: "refused"}.get(code, f"traceback (exit {code})")


@examples(40)
@given(value=HOSTILE)
def test_any_set_value_runs_or_exits_2(value):
    # a StringIO, not capsys: a terminal's stderr writes surrogates (argv's undecodable bytes) escaped,
    # pytest's capture would refuse them
    with pytest.MonkeyPatch.context() as monkeypatch, contextlib.redirect_stderr(io.StringIO()), \
            contextlib.redirect_stdout(io.StringIO()):
        outcome = set_outcome(value, monkeypatch)
    record("set", outcome.split(" ")[0], value)
    assert CAMPAIGN or outcome in ("loaded", "refused"), (value, outcome)


# -- expressions in a case file -------------------------------------------------------------------
EXPRESSION_TOKENS = ["1", "0", "2.5", "1e308", "1e-320", "m", "l", "g", "pi", "+", "-", "*", "/", "**", "%", "//",
                     "(", ")", ",", ".", "[", "]", "{", "}", "'", "\"", "lambda", ":", "__class__", "__import__",
                     "sin", "cos", "sqrt", "exp", "abs", "max", "not", "and", "if", "else", "==", "<", " ", "\u0661",
                     "j", "1j", "True", "None", "...", "@", "~", "<<", "9" * 30, ";", "\n", "#", "=", ":="]
EXPRESSIONS = st.one_of(st.lists(st.sampled_from(EXPRESSION_TOKENS), max_size=30).map("".join), st.text(max_size=20))
_CASE = {}


@examples(100)
@given(text=EXPRESSIONS)
def test_any_expression_in_a_case_file_is_a_number_or_a_value_error(text):
    case = _CASE.setdefault("c", dyncheck.load_case("spring_pendulum"))
    try:
        number = bounded(case.value, text)
    except ValueError:
        record("expression", "refused", text)
        return
    except Hang:
        record("expression", "hang", text)
        assert CAMPAIGN, text
        return
    except Exception:
        record("expression", "traceback", text)
        if not CAMPAIGN:
            raise
        return
    record("expression", "loaded", text)
    assert isinstance(number, float) and math.isfinite(number), (text, number)


@pytest.mark.parametrize("value", ["inf", "-inf", "nan"])
def test_a_non_finite_compared_value_is_refused(value):
    """Found by the campaign: stiffness="inf" on a prescribed joint (alpha) of scene.xml loaded, since
    compare_scenes' tolerance scaled with the inf and `inf > inf` is false."""
    assert scene_outcome("rotating_pendulum", "compared", "MJCF", MJCF_COMPARED.index((".//joint", "stiffness")),
                         value, 0)[0] == "refused"


def edited_case(tmp_path, name, old, new):
    """Case `name` copied into tmp_path with `old` in its scene.xml replaced by `new` (not yet built)."""
    folder = tmp_path / name
    shutil.copytree(CASES_DIR / name, folder)
    text = (folder / "scene.xml").read_text()
    assert old in text
    (folder / "scene.xml").write_text(text.replace(old, new, 1))
    return Case(folder)


def test_a_placeholder_s_centre_of_mass_far_from_its_body_is_refused(tmp_path):
    """Found by the campaign: a 1e-12 kg placeholder's centre of mass moved to (2, 2, 2) m loaded, as centres
    of mass are compared only on real bodies, though it carried 1.2e-11 kg m^2 about its origin."""
    case = edited_case(tmp_path, "rotating_pendulum", '<inertial pos="0 0 0" mass="1e-12"',
                       '<inertial pos="2 2 2" mass="1e-12"')
    case.model("pinocchio")
    with pytest.raises(ValueError, match="placeholder of 1e-12 kg whose centre of mass"):
        case.model("mujoco")


def test_a_non_finite_rotation_of_a_reaction_site_is_refused(tmp_path):
    """Found by the campaign: quat="0 inf 0 0" on the top's reaction site loaded (NaN > eps is false)."""
    case = edited_case(tmp_path, "spinning_top", '<site name="O"', '<site name="O" quat="0 inf 0 0"')
    with pytest.raises(ValueError, match="quat"):
        case.model("mujoco")


def test_a_nan_in_the_mjcf_is_refused(tmp_path):
    """Found by the campaign: MuJoCo compiles a placeholder's inertial pos="nan nan nan" to a finite centre of
    mass (with a warning) and the scene loaded."""
    case = edited_case(tmp_path, "rotating_pendulum", '<inertial pos="0 0 0" mass="1e-12"',
                       '<inertial pos="nan nan nan" mass="1e-12"')
    with pytest.raises(ValueError, match="holds a NaN"):
        case.model("mujoco")


def test_a_control_character_in_the_mjcf_is_refused(tmp_path):
    """Found by the campaign: MuJoCo's parser accepts a control character in an attribute, which XML forbids."""
    case = edited_case(tmp_path, "double_pendulum", 'model="double_pendulum"', 'model="x\x0by"')
    with pytest.raises(ValueError, match="not well-formed XML"):
        case.model("mujoco")
