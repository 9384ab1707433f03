"""Case files against their schema: every bad input gives one clear error and exit code 2, never a traceback."""

import copy
import json
import re
import shutil
import tomllib
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import dyncheck
from dyncheck import cli
from dyncheck.case import folder as case_module
from dyncheck.case import meanings, schema
from dyncheck.case.folder import Case

DOCS = Path(__file__).resolve().parent.parent / "docs" / "case-file.md"


def test_every_case_file_validates():
    for name in dyncheck.case_names():
        file = case_module.CASES_DIR / name / "case.toml"
        schema.validate(tomllib.loads(file.read_text()), file, file.parent)
        dyncheck.load_case(name)


@pytest.fixture
def cases(tmp_path):
    """A copy of the cases folder, for the command line's `--cases`."""
    shutil.copytree(case_module.CASES_DIR, tmp_path / "cases")
    return tmp_path / "cases"


def edit(folder, file, old, new):
    text = (folder / file).read_text()
    assert old in text, old
    (folder / file).write_text(text.replace(old, new, 1))


# (case, text in case.toml, its replacement, what the message says after the file's name: a part or parts)
BAD_CASE_FILES = [
    ("spring_pendulum", "[tolerance.energy]", "[tollerance.energy]",
     ("tollerance = {'energy': {'safety': 10.0, 'why': ", "is not a known key (did you mean 'tolerance'?)")),
    ("spring_pendulum", "rtol = 1e-10", "rtoll = 1e-10",
     "integration.rtoll = 1e-10 is not a known key (did you mean 'rtol'?)"),
    ("spring_pendulum", "t_end = 3.0\n", "", "initial.t_end is missing (a number or an expression in quotes, > 0)"),
    ("spring_pendulum", "count = 100", 'count = "100"', "sample.count = '100' is a string, not an integer"),
    ("spring_pendulum", 'coords = ["psi", "l"]', 'coords = "psi, l"', "coords = 'psi, l' is a string, not an array"),
    ("spring_pendulum", 'unit = "kg"', 'unit = "g"',
     "params.m.unit = 'g' is not a coherent SI unit: 1 g = 0.001 kg; every value of a case is in SI, so give it in kg"),
    ("spring_pendulum", 'unit = "N/m"', 'unit = "N/mm"',
     "params.k.unit = 'N/mm' is not a coherent SI unit: 1 N/mm = 1000 kg / s ** 2"),
    ("spring_pendulum", "m = { value = 0.2,", "m = { value = 0.0,",
     "params.m.value = 0.0 must be > 0 (m is a mass, in kg)"),
    ("spring_pendulum", "m = { value = 0.2,", "m = { value = -1,",
     "params.m.value = -1.0 must be > 0 (m is a mass, in kg)"),
    ("spring_pendulum", "k = { value = 2000.0,", "k = { value = 0.0,",
     "params.k.value = 0.0 must be > 0 (k is a stiffness, in N/m)"),
    ("rotating_pendulum", "l = { value = 0.1,", "l = { value = -0.1,",
     "params.l.exclusive_minimum = 0.0 excludes the default params.l.value = -0.1: l must be > 0"),
    ("spinning_top", "Izz = { value = 0.002258,", "Izz = { value = 0.0023,",
     "constraints[1] = '2*(Ixx - m*h**2) - Izz + 1e-5' is -3.568e-05 at Ixx = 0.0029393, m = 0.582, h = 0.0558, "
     "Izz = 0.0023, not >= 0: the triangle inequality A + B >= C"),
    ("spinning_top", "Ixx = { value = 0.0029393,", "Ixx = { value = 0.0018,",
     "constraints[0] = 'Ixx - m*h**2' is -1.214e-05 at Ixx = 0.0018, m = 0.582, h = 0.0558, not > 0: the top's "
     "moment of inertia about its centre of mass"),
    ("spinning_top", 'printed = ".558"', 'printed = ".0558"', "params.h.printed = '.0558' is not params.h.value = "
     "0.0558 as the book's text shows it, every digit 0 lost ('.558')"),
    ("spring_pendulum", "a = { value = 0.05,", "a = { value = 0.06,", "params.a.printed = '.5' is not "
     "params.a.value = 0.06 as the book's text shows it, every digit 0 lost ('.6')"),
    ("spring_pendulum", "rtol = 1e-10", "rtol = inf", "integration.rtol = inf is not finite"),
    ("spring_pendulum", "output_step = 1e-3", "output_step = 0.0", "integration.output_step = 0.0 must be > 0"),
    ("spinning_top", 'applied = { tip = [0.0, 0.0, "Mz"] }', 'applied = { tip = [0.0, 0.0, ""] }',  # hypothesis found it
     "scene.applied.tip = [0.0, 0.0, '']: invalid syntax"),
    ("piston", "output_step = 1e-3", "output_step = 1.5e-4",
     "integration.output_step = 0.00015 is not a multiple of integration.mujoco_step = 0.0001"),
    ("spring_pendulum", "output_step = 1e-3", "output_step = 1.5e-4",  # a step that follows omega: its value too
     "integration.output_step = 0.00015 is not a multiple of integration.mujoco_step = '1e-3 / min(max(1, ceil(sqrt(k/m "
     "+ max(alpha_rate**2, (alpha_rate + beta_rate)**2)) / 10.5)), 166)' = 0.0001"),
    ("spring_pendulum", "tight_rtol = 1e-12", "tight_rtol = 1e-8",
     "integration.tight_rtol = 1e-08 is not below integration.rtol"),
    # runs the integrators cannot make as asked (dyncheck.common.ceilings.LEAST_RTOL), or whose rows would mean nothing
    ("spring_pendulum", "rtol = 1e-10\n", "rtol = 1e-300\n", "integration.rtol = 1e-300 is below 2.22e-14, 100 machine "
                                                             "epsilons: scipy's integrators raise a smaller rtol to that"),
    ("spring_pendulum", "tight_rtol = 1e-12", "tight_rtol = 1e-15", "integration.tight_rtol = 1e-15 is below 2.22e-14"),
    ("spring_pendulum", "tight_rtol = 1e-12", "tight_rtol = 0.0", "integration.tight_rtol = 0.0 must be > 0"),
    ("spring_pendulum", "rtol = 1e-10\n", "rtol = 0.01\n", "integration.rtol = 0.01 is above 0.001: a run's error"),
    ("spring_pendulum", "t_end = 3.0\n", "t_end = 3.0005\n",  # a traceback in simulate before
     "initial.t_end = 3.0005 is not a whole number of output steps (integration.output_step = 0.001)"),
    ("spring_pendulum", "t_end = 3.0\n", "t_end = 1e-4\n", "initial.t_end = 0.0001 is not a whole number of output steps"),
    ("spring_pendulum", "rtol = 1e-13", "rtol = 1e-15", "work_precision.solution.rtol = 1e-15 is below 2.22e-14"),
    ("spring_pendulum", "1e-11, 1e-12]", "1e-11, 1e-16]", "work_precision.sweep.reference.DOP853 = 1e-16 is below"),
    ("double_pendulum", "\nrtol = 1e-9", "\nrtol = 1e-16", "stability.lyapunov.rtol = 1e-16 is below 2.22e-14"),
    ("double_pendulum", "\ncheck_rtol = 1e-7", "\ncheck_rtol = 0.0", "stability.lyapunov.check_rtol = 0.0 is below"),
    ("spring_pendulum", 'q = ["pi/6", 0.0]', 'q = ["pi/6"]',
     "initial.q = ['pi/6'] has length 1, not 2 (one per coordinate: psi, l)"),
    ("spring_pendulum", 'q = ["pi/6", 0.0]', 'q = ["pi/sixth", 0.0]',
     "cannot evaluate 'pi/sixth': name 'sixth' is not defined (at initial.q[0])"),
    ("spring_pendulum", 'k = [{ element = "joint"', 'kk = [{ element = "joint"',
     ("scene.bindings.kk = [{'element': 'joint',", "binds no parameter (did you mean 'k'?)")),
    ("spring_pendulum", 'axis = 0, frame = "body"', 'axis = 3, frame = "body"',
     "scene.reactions.R.axis = 3 is not one of 0, 1, 2"),
    ("spring_pendulum", "\n[params]\n", '\n[params]\nmu = { value = 0.5, unit = "furlong", about = "x" }\n',
     "params.mu.unit = 'furlong' is not a coherent SI unit: 1 furlong = 201.168 m"),
    ("spring_pendulum", "\n[params]\n", '\n[params]\nmu = { value = 0.5, unit = "blorp", about = "x" }\n',
     "params.mu.unit = 'blorp' is not a unit"),
    ("spring_pendulum", "\n[params]\n", '\n[params]\nmu = { value = 0.5, unit = "", about = "x" }\n',
     "params.mu.unit = '' is empty; write '-' for a pure number"),
    ("spring_pendulum", "\n[params]\n", '\nname = "spring_pendulum"\n[params]\n',
     "not valid TOML: Cannot overwrite a value"),
    ("spring_pendulum", "\n[params]\n", "\n[params\n",
     "not valid TOML: Expected ']' at the end of a table declaration"),
    ("double_pendulum", "m1 = [0.05, 2.0]", "m1 = [0.0, 2.0]",
     "sample.params.ranges.m1 = [0.0, 2.0] leaves the physical values: m1 must be > 0 (m1 is a mass, in kg)"),
    # settings that would make a check vacuous (dyncheck/common/ceilings.py)
    ("spring_pendulum", 'sources = ["book"]', 'sources = ["mujoco"]',
     "findings[0].sources = 'mujoco' is not the book's: a finding is an error of the book"),
    ("spring_pendulum", 'sources = ["book"]', 'sources = ["reference vs mujoco"]',
     "findings[0].sources = 'reference vs mujoco' is not the book's"),
    ("spring_pendulum", "value = 1e-9", "value = 1e300",
     "tolerance.pointwise.value = 1e+300 is above the ceiling 1e-06 of a pointwise comparison"),
    ("spring_pendulum", "safety = 10.0", "safety = 1e300", "tolerance.trajectory.safety = 1e+300 is above 100"),
    ("spinning_top", "tolerance = 2e-5", "tolerance = 1.0", "data[0].tolerance = 1.0 is above the ceiling 0.05"),
    ("double_pendulum", "\neps0 = 1e-10", "\neps0 = nan", "cannot evaluate nan: nan is not finite (at stability.lyapunov.eps0)"),
    ("double_pendulum", "\ntol = 1e-3", "\ntol = 1e-12", "stability.lyapunov.tol = 1e-12 is not in (eps0 = 1e-10, 0.001]"),
]


@pytest.mark.parametrize("name, old, new, message", BAD_CASE_FILES)
def test_a_bad_case_file_exits_2_naming_file_field_and_value(cases, capsys, name, old, new, message):
    edit(cases / name, "case.toml", old, new)
    assert cli.main(["run", name, "--cases", str(cases)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"dyncheck: error: {cases / name / 'case.toml'}: ") and err.count("\n") == 1, err
    assert all(part in err for part in ((message,) if isinstance(message, str) else message)), err


BAD_COMMAND_LINES = [
    (["run", "spring_pendulum", "--set", "g=1e999"], "spring_pendulum/case.toml: override g = inf is not finite"),
    (["run", "spring_pendulum", "--set", "g=nan"], "spring_pendulum/case.toml: override g = 'nan' is not a number"),
    (["run", "spring_pendulum", "--set", "m=abc"], "spring_pendulum/case.toml: override m = 'abc' is not a number"),
    (["run", "spring_pendulum", "--set", "m=0"], "override m = 0.0 must be > 0 (m is a mass, in kg)"),
    (["run", "spring_pendulum", "--set", "g=-9.81"], "override g = -9.81 must be >= 0 (params.g.minimum)"),
    (["run", "rotating_pendulum", "--set", "l=-0.1"], "override l = -0.1 must be > 0 (params.l.exclusive_minimum)"),
    (["run", "spinning_top", "--set", "Ixx=0.0028"],
     "constraints[1] = '2*(Ixx - m*h**2) - Izz + 1e-5' is -0.0002723 at Ixx = 0.0028 (override), m = 0.582, "
     "h = 0.0558, Izz = 0.002258, not >= 0: the triangle inequality A + B >= C"),
    (["run", "spinning_top", "--set", "h=0.08"],
     "constraints[0] = 'Ixx - m*h**2' is -0.0007855 at Ixx = 0.0029393, m = 0.582, h = 0.08 (override), not > 0"),
    (["run", "spinning_top", "--set", "m=0.732478"],  # within the sampled m (0.2 to 1 kg), which draws Ixx with it
     "the triangle inequality A + B >= C of the top's moments of inertia about its centre of mass (A = B = Ixx - m "
     "h^2, C = Izz, kg m^2), to within the 1e-5 kg m^2 that scene.xml's armature can carry (A + B - C >= -1e-5); "
     "beyond, no rigid body has these inertias; set the others with the overrides (`dyncheck list` shows each "
     "case's constraints)"),
    (["run", "spring_pendulum", "--set", "mm=1"],
     "--set mm: no selected case has a parameter 'mm' (did you mean 'm'?)"),
    (["run", "spring_pendulm"], "unknown case 'spring_pendulm' (did you mean 'spring_pendulum'?); known cases: "),
    (["report", "xyz"], "unknown case 'xyz'; known cases: "),
]


@pytest.mark.parametrize("argv, message", BAD_COMMAND_LINES)
def test_a_bad_command_line_exits_2(capsys, argv, message):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("dyncheck: error: ") and message in err and err.count("\n") == 1, err


def test_the_book_s_unrealisable_inertias_load_and_the_scene_s_margin_is_the_limit():
    """The printed pair breaks A + B >= C by 3.7e-6 kg m^2 and loads; Izz may grow up to the 1e-5 that
    scene.xml's armature carries, and MuJoCo compiles it; beyond, the case refuses it, not MuJoCo."""
    top = dyncheck.load_case("spinning_top")
    a = top.params["Ixx"] - top.params["m"] * top.params["h"] ** 2
    dyncheck.load_case("spinning_top", Izz=2 * a + 0.99e-5).model("mujoco")
    with pytest.raises(ValueError, match="the triangle inequality"):
        dyncheck.load_case("spinning_top", Izz=2 * a + 1.01e-5)


# -- bounds, constraints and the derivation of a case file ----------------------------------------

L0 = 'l0 = { value = 0.1, unit = "m", exclusive_minimum = 0.0,'  # spring_pendulum's spring length


@pytest.mark.parametrize("key, bound, within, beyond, relation", [
    ("minimum", 0.05, 0.05, 0.04, ">="), ("exclusive_minimum", 0.05, 0.051, 0.05, ">"),
    ("maximum", 0.5, 0.5, 0.51, "<="), ("exclusive_maximum", 0.5, 0.49, 0.5, "<"),
])
def test_a_bound_refuses_an_override_beyond_it(cases, key, bound, within, beyond, relation):
    edit(cases / "spring_pendulum", "case.toml", L0, f'l0 = {{ value = 0.1, unit = "m", {key} = {bound},')
    Case(cases / "spring_pendulum", {"l0": within})
    with pytest.raises(ValueError) as error:
        Case(cases / "spring_pendulum", {"l0": beyond})
    assert str(error.value) == (f"{cases / 'spring_pendulum' / 'case.toml'}: override l0 = {beyond!r} must be "
                                f"{relation} {bound:g} (params.l0.{key})")


def test_a_bound_refuses_a_random_range_beyond_it(cases):
    edit(cases / "spring_pendulum", "case.toml", "l0 = [0.1, 0.3]", "l0 = [0.0, 0.3]")
    with pytest.raises(ValueError, match=re.escape("sample.params.ranges.l0 = [0.0, 0.3] leaves the physical "
                                                   "values: l0 must be > 0 (params.l0.exclusive_minimum)")):
        Case(cases / "spring_pendulum")


@pytest.mark.parametrize("bound, message", [
    ("maximum = 0.05", "params.l0.maximum = 0.05 excludes the default params.l0.value = 0.1: l0 must be <= 0.05"),
    ("exclusive_minimum = 0.1", "params.l0.exclusive_minimum = 0.1 excludes the default params.l0.value = 0.1: "
                                "l0 must be > 0.1"),
])
def test_a_bound_that_excludes_the_default_is_refused(cases, bound, message):
    edit(cases / "spring_pendulum", "case.toml", L0, f'l0 = {{ value = 0.1, unit = "m", {bound},')
    with pytest.raises(ValueError, match=re.escape(message)):
        Case(cases / "spring_pendulum")


def with_constraint(folder, expression, strict=False):
    """The case in `folder` with one [[constraints]] entry appended."""
    text = (folder / "case.toml").read_text()
    (folder / "case.toml").write_text(text + f'\n[[constraints]]\nexpression = "{expression}"\n'
                                      + ("strict = true\n" if strict else "") + 'why = "the spring is long"\n')


def test_a_constraint_refuses_an_override_naming_it_its_value_and_its_parameters(cases):
    with_constraint(cases / "spring_pendulum", "l0 - 2*r")  # l0 = 0.1, r = 0.1: -0.1
    with pytest.raises(ValueError) as error:
        Case(cases / "spring_pendulum", {"l0": 0.15})
    assert str(error.value) == (f"{cases / 'spring_pendulum' / 'case.toml'}: constraints[0] = 'l0 - 2*r' is "
                                "-0.05 at l0 = 0.15 (override), r = 0.1, not >= 0: the spring is long; set the "
                                "others with the overrides (`dyncheck list` shows each case's constraints)")
    Case(cases / "spring_pendulum", {"l0": 0.2})


@pytest.mark.parametrize("strict", [False, True])
def test_a_strict_constraint_refuses_zero(cases, strict):
    with_constraint(cases / "spring_pendulum", "l0 - 0.1", strict)  # exactly 0 at the default l0 = 0.1
    if not strict:
        Case(cases / "spring_pendulum")
        return
    with pytest.raises(ValueError, match=re.escape("constraints[0] = 'l0 - 0.1' is 0 at l0 = 0.1, not > 0: the "
                                                   "spring is long")):
        Case(cases / "spring_pendulum")


@pytest.mark.parametrize("expression, message", [
    ("l0 - l00", "constraints[0].expression = 'l0 - l00' cannot be evaluated: name 'l00' is not defined "
                 "(did you mean 'l0'?)"),
    ("l0 -", "constraints[0].expression = 'l0 -' cannot be evaluated: invalid syntax"),
    ("l0 / (r - 0.1)", "constraints[0].expression = 'l0 / (r - 0.1)' cannot be evaluated: float division by zero"),
    ("l0 > r", "constraints[0].expression = 'l0 > r' is a comparison"),
])
def test_a_bad_constraint_gives_a_clean_error(cases, capsys, expression, message):
    with_constraint(cases / "spring_pendulum", expression)
    assert cli.main(["run", "spring_pendulum", "--cases", str(cases)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"dyncheck: error: {cases / 'spring_pendulum' / 'case.toml'}: {message}"), err


@pytest.mark.parametrize("derivation, message", [
    ("reference.spring_pendulm", "derivation = 'reference.spring_pendulm' names no module of the package's reference/"),
    ("nowhere.spring_pendulum", "derivation = 'nowhere.spring_pendulum' is neither a module of the package's "
                                "reference/"),
    ("reference.spring_pendulum.x", "derivation = 'reference.spring_pendulum.x' is neither a module of the package's "
                                    "reference/"),
    ("equations.py", "derivation = 'equations.py' names no file in the case folder"),
    ("reference/spring_pendulum", "derivation = 'reference/spring_pendulum' is neither a module of the package's "
                                  "reference/"),
])
def test_a_derivation_that_is_not_there_is_refused(cases, derivation, message):
    edit(cases / "spring_pendulum", "case.toml", 'derivation = "reference.spring_pendulum"',
         f'derivation = "{derivation}"')
    with pytest.raises(ValueError, match=re.escape(message)):
        Case(cases / "spring_pendulum")


def test_a_derivation_may_be_a_file_in_the_case_folder(cases):
    edit(cases / "spring_pendulum", "case.toml", 'derivation = "reference.spring_pendulum"',
         'derivation = "equations.py"')
    (cases / "spring_pendulum" / "equations.py").write_text("")
    schema.validate(tomllib.loads((cases / "spring_pendulum" / "case.toml").read_text()),
                    cases / "spring_pendulum" / "case.toml", cases / "spring_pendulum")


def test_the_schema_names_no_case():
    """Everything about one case is in its folder: the schema knows no case by name."""
    text = Path(schema.__file__).read_text()
    assert not [name for name in dyncheck.case_names() if name in text]


def test_every_key_has_a_meaning():
    keys = {key for key, _, _ in meanings.keys()}
    assert not keys - set(meanings.MEANINGS), f"keys without a meaning in meanings.MEANINGS: {keys - set(meanings.MEANINGS)}"
    assert not set(meanings.MEANINGS) - keys, f"meanings of no key: {set(meanings.MEANINGS) - keys}"
    assert set(meanings.KEY_UNITS) <= keys, f"units of no key: {set(meanings.KEY_UNITS) - keys}"


def test_the_case_file_reference_is_current():
    assert DOCS.read_text() == meanings.markdown(), \
        "regenerate: python -c 'import dyncheck.case.meanings as s; print(s.markdown(), end=\"\")' > docs/case-file.md"


def test_without_its_urdf_pinocchio_reads_the_mjcf(cases):
    """A hand-written scene.urdf is a second model of the scene; without one, Pinocchio reads scene.xml."""
    (cases / "double_pendulum" / "scene.urdf").unlink()
    case = Case(cases / "double_pendulum")
    assert case.pinocchio_scene.name == "scene.xml" and case.model("pinocchio").path.endswith("scene.xml")


@pytest.mark.parametrize("scene, text, message", [
    ("scene.xml", None, "scene.xml: no such scene file (case 'double_pendulum' needs it for mujoco)"),
    ("scene.xml", "<mujoco><worldbody><body", "scene.xml: XML parse error"),
    ("scene.urdf", "<robot name='x'><link", "scene.urdf: not well-formed XML: unclosed token: line 1"),
])
def test_a_scene_file_that_fails_to_load_exits_2(cases, capsys, scene, text, message):
    path = cases / "double_pendulum" / scene
    if text is None:
        path.unlink()
    else:
        path.write_text(text)
    assert cli.main(["run", "double_pendulum", "--cases", str(cases)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"dyncheck: error: {path}") and message in err and err.count("\n") == 1, err


# -- property: whatever is wrong with a case file, loading it gives a ValueError naming the file ----------

def toml(spec):
    """spec as TOML text: every table inline (tomllib has no writer)."""
    key = lambda k: k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k, ensure_ascii=False)

    def value(x):
        if isinstance(x, bool):
            return "true" if x else "false"
        if isinstance(x, (int, float)):
            return repr(x)  # inf, nan and 1e-05 are TOML too
        if isinstance(x, str):
            return json.dumps(x, ensure_ascii=False)
        if isinstance(x, list):
            return "[" + ", ".join(map(value, x)) + "]"
        return "{" + ", ".join(f"{key(k)} = {value(v)}" for k, v in x.items()) + "}"
    return "".join(f"{key(k)} = {value(v)}\n" for k, v in spec.items())


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    """A copy of every case folder, scene files included, and its parsed case file."""
    root = tmp_path_factory.mktemp("cases")
    out = {}
    for name in dyncheck.case_names():
        shutil.copytree(case_module.CASES_DIR / name, root / name)
        out[name] = (root / name, tomllib.loads((root / name / "case.toml").read_text()))
    return out


def test_the_toml_writer_round_trips(folders):
    for folder, spec in folders.values():
        (folder / "case.toml").write_text(toml(spec))
        assert tomllib.loads((folder / "case.toml").read_text()) == spec
        Case(folder)


TEXT = st.text(st.characters(blacklist_categories=("Cs", "Cc")), max_size=8)
SCALARS = st.one_of(st.booleans(), st.integers(-10, 1000), st.floats(), TEXT)
VALUES = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=3)
                      | st.dictionaries(TEXT.filter(bool), inner, max_size=3), max_leaves=6)


def places(x, path=()):
    """The path of every value inside x, its tables' keys and its arrays' items."""
    items = x.items() if isinstance(x, dict) else enumerate(x) if isinstance(x, list) else ()
    for k, item in items:
        yield path + (k,)
        yield from places(item, path + (k,))


def mutate(spec, data):
    """spec with one value deleted, replaced by a random one, or its key renamed."""
    spec = copy.deepcopy(spec)
    path = data.draw(st.sampled_from(list(places(spec))))
    parent = spec
    for k in path[:-1]:
        parent = parent[k]
    k = path[-1]
    action = data.draw(st.sampled_from(["delete", "replace", "rename"]))
    if action == "delete":
        del parent[k]
    elif action == "rename" and isinstance(parent, dict):
        new = data.draw(st.one_of(TEXT.filter(bool), st.just(k + "s"), st.just(k[:-1] or "_")))
        parent[new] = parent.pop(k)
    else:
        parent[k] = data.draw(VALUES)
    return spec


@settings(max_examples=150, deadline=None)
@given(name=st.sampled_from(dyncheck.case_names()), data=st.data())
def test_a_mutated_case_file_loads_or_gives_a_value_error_naming_it(folders, name, data):
    folder, spec = folders[name]
    for _ in range(data.draw(st.integers(1, 3))):
        spec = mutate(spec, data)
    (folder / "case.toml").write_text(toml(spec))
    try:
        case = Case(folder)
    except ValueError as error:
        assert str(error).startswith(f"{folder / 'case.toml'}: "), error
        return
    # What loads can be used: the numbers the checks read all evaluate.
    case.initial, case.sample_states(), case.integration, case.scene


GARBLE = st.sampled_from(["truncate", "insert", "delete", "bytes"])


@settings(max_examples=100, deadline=None)
@given(name=st.sampled_from(dyncheck.case_names()), how=GARBLE, data=st.data())
def test_malformed_toml_gives_a_value_error_naming_the_file(folders, name, how, data):
    folder, _ = folders[name]
    text = (case_module.CASES_DIR / name / "case.toml").read_bytes()
    at = data.draw(st.integers(0, len(text)))
    if how == "truncate":
        text = text[:at]
    elif how == "insert":
        text = text[:at] + data.draw(st.binary(min_size=1, max_size=4)) + text[at:]
    elif how == "delete":
        text = text[:at] + text[at + data.draw(st.integers(1, 40)):]
    else:
        text = data.draw(st.binary(max_size=200))
    (folder / "case.toml").write_bytes(text)
    try:
        Case(folder)
    except ValueError as error:
        assert str(error).startswith(f"{folder / 'case.toml'}: "), error


# Some drawn values are allowed and degenerate (a mass or inertia orders of magnitude from the others): MuJoCo
# compiles them, saying its mass matrix is singular to its precision.  This test asks only that they load or give
# a ValueError.
@pytest.mark.filterwarnings("ignore:Inertia matrix is too close to singular:UserWarning")
@settings(max_examples=80, deadline=None)
@given(name=st.sampled_from(dyncheck.case_names()), data=st.data())
def test_random_overrides_load_or_give_a_clean_error(name, data):
    """Any `--set NAME=VALUE` (odd numbers, huge ones, text) loads every model of the case or gives
    a ValueError (exit 2) with a message; never another exception."""
    from dyncheck.cli import select_cases
    key = data.draw(st.sampled_from(list(dyncheck.load_case(name).defaults) + ["zz"]))
    value = data.draw(st.one_of(st.floats(), st.floats(-10.0, 10.0), st.text(max_size=6)))
    try:
        select_cases([name], [f"{key}={value}"])
    except ValueError as error:
        assert str(error).strip()
