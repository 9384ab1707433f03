"""Every <option> attribute and <flag> of the installed MuJoCo is classified in engines.scene.RULES (issue 34):
walked from MuJoCo's own lists, so that a new version's option or flag fails here until it is; each one without
effect leaves MuJoCo's numbers bit for bit, each refused one is refused on load (in a scene with a loop, those
refused with a loop)."""

import re
import shutil
from pathlib import Path

import mujoco
import numpy as np
import pytest

from dyncheck.case.folder import Case
from dyncheck.checks.pointwise import evaluate
from dyncheck.cli import main
from engines import scene
from engines.mujoco_scene import OPTION_ATTRIBUTES, options_set
from test_own_case_doc import steps

ROOT = Path(__file__).resolve().parent.parent
XML_REFERENCE = Path(mujoco.__file__).parent / "doc" / "XMLreference.rst"
SLIDER_CRANK = ROOT / "examples" / "slider_crank"
DEFAULT = mujoco.MjModel.from_xml_string("<mujoco/>").opt
FLAG_BITS = {"disable": mujoco.mjtDisableBit, "enable": mujoco.mjtEnableBit}  # what setting a flag so does


def installed_options():
    """{<option> attribute: MjOption field} of the installed MuJoCo, its flags aside."""
    fields = [f for f in dir(mujoco.MjOption) if not f.startswith("_") and f not in ("disableflags", "enableflags")]
    return {OPTION_ATTRIBUTES.get(field, field): field for field in fields}


def installed_flags():
    """{<flag> attribute: the value other than its default, "disable" or "enable"} of the installed MuJoCo."""
    prefixes = {"disable": "mjDSBL_", "enable": "mjENBL_"}
    return {name[len(prefixes[value]):].lower(): value for value, bits in FLAG_BITS.items()
            for name in bits.__members__ if name.startswith(prefixes[value])}


def own_rule(element, attribute):
    return [r for r in scene.RULES if (r.file, r.element, r.attribute) == ("MJCF", element, attribute)]


def test_every_option_and_flag_of_the_installed_mujoco_has_its_own_rule():
    options, flags = installed_options(), installed_flags()
    assert len(options) > 20 and len(flags) > 20 and "damper" in flags  # MuJoCo's lists were read
    assert [a for a in options if len(own_rule("option", a)) != 1] == []
    assert [f for f in flags if len(own_rule("option-flag", f)) != 1] == []
    # no rule for what MuJoCo lacks, and no "*" that would classify a new one unread
    assert {r.attribute for r in scene.RULES if r.element == "option"} == set(options)
    assert {r.attribute for r in scene.RULES if r.element == "option-flag"} == set(flags)
    # the names are MJCF's: each is an anchor of MuJoCo's XML reference
    anchors = set(re.findall(r"^\.\. _(option-[a-z_]+(?:-[a-z_]+)?):", XML_REFERENCE.read_text(), re.M))
    assert {f"option-{a}" for a in options} | {f"option-flag-{f}" for f in flags} == anchors - {"option-flag"}


def test_the_adapter_finds_every_option_and_flag_set_otherwise_than_its_default():
    """engines.mujoco_scene.options_set, which the load judges, sees each one (walked from MuJoCo's lists)."""
    model = mujoco.MjModel.from_xml_string("<mujoco/>")
    for attribute, field in installed_options().items():
        opt = mujoco.MjModel.from_xml_string("<mujoco/>").opt
        setattr(opt, field, other_number(field))
        assert [(e, a) for e, a, _ in options_set(opt)] == [("option", attribute)], attribute
    for flag, value in installed_flags().items():
        opt = model.opt
        bit = getattr(FLAG_BITS[value], ("mjDSBL_" if value == "disable" else "mjENBL_") + flag.upper())
        field = value + "flags"
        setattr(opt, field, int(bit))
        assert list(options_set(opt)) == [("option-flag", flag, value)], flag
        setattr(opt, field, 0)


# An <option> value other than the default, in MJCF's words, for every attribute (the enumerations by name).
NAMED = {"integrator": "discrete", "cone": "elliptic", "jacobian": "sparse", "solver": "CG"}


def other_number(field):
    """A value of MjOption's `field` other than its default (an enumeration's another member)."""
    default = np.asarray(getattr(DEFAULT, field))
    if default.dtype.kind == "f":
        return np.where(default != 0, default / 2, 0.25).tolist()
    return int(default) - 1 if default > 0 else int(default) + 1


def other_value(attribute):
    if attribute in NAMED:
        return NAMED[attribute]
    return " ".join(f"{x:g}" for x in np.atleast_1d(other_number(installed_options()[attribute])))


def with_option(source, attributes="", flag=""):
    """source's scene.xml text with <option gravity ...> given further attributes and a <flag>."""
    text = source.read_text()
    option = re.search(r"<option ([^/>]*)/>", text)
    return text.replace(option.group(0), f"<option {option.group(1)} {attributes}>{flag}</option>", 1)


def tutorial(folder, damper=True):
    """docs/own-case.md's cart-pendulum in `folder`/cart_pendulum, with a damper on the cart (c = 0.7 N s/m)."""
    case = folder / "cart_pendulum"
    for kind, path, text in steps():
        if kind == "file" and not (folder / path).exists():
            (folder / path).parent.mkdir(parents=True, exist_ok=True)
            (folder / path).write_text(text)
    if damper:
        edit(case / "scene.xml", 'stiffness="20"', 'stiffness="20" damping="0.7"')
        edit(case / "equations.py", '"g": 9.81}', '"g": 9.81, "c": 0.7}')
        edit(case / "equations.py", "- k * x,", '- k * x - p["c"] * x_rate,')
    return case


def edit(path, old, new):
    text = path.read_text()
    assert text.count(old) == 1, (path, old)
    path.write_text(text.replace(old, new))


def mujoco_numbers(folder):
    """MuJoCo's evaluations at ten random states, its linearisation at one, and an RK4 and an Euler run."""
    case = Case(folder)
    states = case.sample_states()[:10]
    numbers = evaluate(case, "mujoco", states)
    model = case.model("mujoco")
    linearisation = model.linearisation(*states[0])
    numbers.update(force_q=linearisation.force_q, force_v=linearisation.force_v)
    q0, v0, _ = case.initial
    for integrator in ("RK4", "Euler"):
        run = model.step(q0, v0, 0.2, 1e-3, integrator)
        numbers[integrator] = np.hstack([run["q"], run["v"]])
    return numbers


def without_effect_here(rule):
    """In a scene without loops: the rules without effect, and those refused only with a loop."""
    return rule.status == scene.NO_EFFECT or rule.with_loops


@pytest.fixture(scope="module")
def cart(tmp_path_factory):
    folder = tutorial(tmp_path_factory.mktemp("cart"))
    return folder, mujoco_numbers(folder)


@pytest.mark.parametrize("element, attribute", [
    (r.element, r.attribute) for r in scene.RULES if r.element in ("option", "option-flag") and without_effect_here(r)])
def test_an_option_or_flag_without_effect_leaves_every_number_of_mujoco_bit_for_bit(cart, element, attribute):
    """On the tutorial's cart-pendulum with a damper: its evaluations, linearisation and Euler and RK4 runs
    (the harness sets the integrator and the step of every run, and evaluates under Euler)."""
    folder, expected = cart
    scene_file = folder / "scene.xml"
    original = scene_file.read_text()
    try:
        if element == "option":
            scene_file.write_text(with_option(scene_file, f'{attribute}="{other_value(attribute)}"'))
        else:
            scene_file.write_text(with_option(scene_file, flag=f'<flag {attribute}="{installed_flags()[attribute]}"/>'))
        numbers = mujoco_numbers(folder)
    finally:
        scene_file.write_text(original)
    assert {k: float(np.max(np.abs(numbers[k] - expected[k]))) for k in expected
            if not np.array_equal(numbers[k], expected[k])} == {}


def refused_options():
    return [r for r in scene.RULES if r.element in ("option", "option-flag") and r.status == scene.REFUSED]


def set_in(source, rule):
    """The scene file `source` with the rule's option or flag set otherwise than its default."""
    if rule.element == "option":
        return with_option(source, f'{rule.attribute}="{other_value(rule.attribute)}"')
    extra = ' integrator="discrete"' if rule.attribute == "ipc" else ""  # MuJoCo compiles ipc with it only
    return with_option(source, extra, f'<flag {rule.attribute}="{installed_flags()[rule.attribute]}"/>')


@pytest.mark.parametrize("rule", refused_options(), ids=lambda r: f"{r.element}-{r.attribute}")
def test_a_refused_option_or_flag_is_refused_on_load(tmp_path, rule):
    """In the slider-crank (examples/): those refused with a loop too.  One line naming the file, the element,
    the attribute and its value."""
    folder = tmp_path / "slider_crank"
    shutil.copytree(SLIDER_CRANK, folder, ignore=shutil.ignore_patterns("__pycache__"))
    (folder / "scene.xml").write_text(set_in(SLIDER_CRANK / "scene.xml", rule))
    with pytest.raises(ValueError) as error:
        Case(folder).model("mujoco")
    value = other_value(rule.attribute) if rule.element == "option" else installed_flags()[rule.attribute]
    tag = "option" if rule.element == "option" else "flag"
    assert str(error.value).startswith(f"{folder / 'scene.xml'}: <option> <{tag} {rule.attribute}=\"{value}\"> is "
                                       f"not modelled by dyncheck ({rule.why}); "), str(error.value)
    assert "\n" not in str(error.value)


def test_the_damper_flag_that_told_a_right_derivation_to_add_a_damper_is_refused(tmp_path, capsys):
    """Issue 34's reproduction: MuJoCo applied <flag damper="disable">, the Pinocchio side and the derivation
    did not, and the run told the derivation to add + c x'.  Now exit 2 before any check."""
    case = tutorial(tmp_path)
    (case / "scene.xml").write_text(with_option(case / "scene.xml", flag='<flag damper="disable"/>'))
    assert main(["run", "--cases", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "scene.xml: <option> <flag damper=\"disable\"> is not modelled by dyncheck" in err, err


def test_a_flag_of_a_newer_mujoco_than_the_table_is_refused_as_unclassified(tmp_path, monkeypatch):
    monkeypatch.setattr(scene, "RULES", [r for r in scene.RULES if r.attribute != "fwdinv"])
    case = tutorial(tmp_path)
    (case / "scene.xml").write_text(with_option(case / "scene.xml", flag='<flag fwdinv="enable"/>'))
    with pytest.raises(ValueError, match=r'<flag fwdinv="enable"> is not modelled by dyncheck \(not yet classified'):
        Case(case).model("mujoco")


SOLVER_TOLERANCE = 1e-8
"""Of a run's largest value: MuJoCo's constraint solver stops at its tolerance (1e-8, of its cost and gradient),
so that what changes the solver's path but not its solution (its start, the Jacobian's storage) moves a loop's
run by that at most.  Measured on the slider-crank's 0.2 s runs: 1.3e-10 (warmstart), 1.2e-12 (jacobian)."""


@pytest.fixture(scope="module")
def slider_crank(tmp_path_factory):
    folder = tmp_path_factory.mktemp("loop") / "slider_crank"
    shutil.copytree(SLIDER_CRANK, folder, ignore=shutil.ignore_patterns("__pycache__"))
    return folder, mujoco_numbers_of_a_loop(folder)


def mujoco_numbers_of_a_loop(folder):
    """`mujoco_numbers` without the linearisation, which a scene with loops does not have."""
    case = Case(folder)
    numbers = evaluate(case, "mujoco", case.sample_states()[:10])
    q0, v0, _ = case.initial
    for integrator in ("RK4", "Euler"):
        run = case.model("mujoco").step(q0, v0, 0.2, 1e-3, integrator)
        numbers["run " + integrator] = np.hstack([run["q"], run["v"]])
    return numbers


@pytest.mark.parametrize("element, attribute", [
    (r.element, r.attribute) for r in scene.RULES if r.element in ("option", "option-flag") and r.status == scene.NO_EFFECT])
def test_an_option_or_flag_without_effect_leaves_a_loop_s_evaluations_bit_for_bit(slider_crank, element, attribute):
    """The slider-crank's (examples/): MuJoCo's rigid loop at ten states (the discrete integrator changed them,
    before the harness evaluated under Euler), and its runs to the constraint solver's tolerance."""
    folder, expected = slider_crank
    scene_file = folder / "scene.xml"
    original = scene_file.read_text()
    try:
        if element == "option":
            scene_file.write_text(with_option(scene_file, f'{attribute}="{other_value(attribute)}"'))
        else:
            scene_file.write_text(with_option(scene_file, flag=f'<flag {attribute}="{installed_flags()[attribute]}"/>'))
        numbers = mujoco_numbers_of_a_loop(folder)
    finally:
        scene_file.write_text(original)
    runs = [k for k in expected if k.startswith("run ")]
    assert {k: float(np.max(np.abs(numbers[k] - expected[k]))) for k in expected
            if k not in runs and not np.array_equal(numbers[k], expected[k])} == {}
    for k in runs:
        assert np.max(np.abs(numbers[k] - expected[k])) <= SOLVER_TOLERANCE * np.max(np.abs(expected[k])), k
