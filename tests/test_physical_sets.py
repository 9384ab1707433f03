"""Random parameter sets are physical in the scene too: the constraints a scene's bindings imply (a positive mass,
principal moments about the centre of mass that a rigid body has) are drawn within, and a set the engines still
cannot load is a failing row that says why, never a traceback."""

import pytest

from dyncheck.case.folder import Case
from dyncheck.checks import pointwise
from dyncheck.cli import main
from dyncheck.results.values import Status
from test_planted_errors import tutorial_subject


def cart_with_bound_inertia(tmp_path):
    """The tutorial's cart-pendulum with the cart's moment about z through its origin bound to a parameter Iz =
    2.5e-3 kg m^2, its other two 1e-3 and 2e-3: drawn between half and twice its value, Iz above 3e-3 breaks
    A + B >= C, and MuJoCo's compiler refuses it."""
    folder = tutorial_subject(tmp_path).folder
    scene = folder / "scene.xml"
    scene.write_text(scene.read_text().replace('diaginertia="1e-3 1e-3 1e-3"', 'diaginertia="1e-3 2e-3 2.5e-3"'))
    equations = folder / "equations.py"
    equations.write_text(equations.read_text().replace('"g": 9.81}', '"g": 9.81, "Iz": 2.5e-3}'))
    (folder / "case.toml").write_text('[scene.bindings]\nIz = [{ element = "body", name = "cart", attribute = '
                                      '"inertia_about_origin", index = 2 }]\n')
    return folder


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_sets_that_break_a_body_s_triangle_inequality_are_not_drawn(tmp_path, capsys):
    """Before: `dyncheck run` raised MuJoCo's 'inertia must satisfy A + B >= C' out of the run."""
    folder = cart_with_bound_inertia(tmp_path)
    case = Case(folder)
    sets, missing = pointwise.parameter_sets(case)
    assert missing == 0 and sets and all(s["Iz"] <= 3e-3 for s in sets)
    assert "A + B >= C" in pointwise.scene_breaks(case, {"Iz": 3.5e-3})
    assert pointwise.scene_breaks(case, {"Iz": 2.9e-3}) is None
    assert main(["run", "--cases", str(folder.parent)]) == 0, capsys.readouterr().out[-2000:]


def test_a_set_the_engines_cannot_load_is_a_failing_row_naming_it(tmp_path, monkeypatch):
    case = Case(cart_with_bound_inertia(tmp_path))
    monkeypatch.setattr(pointwise, "scene_breaks", lambda case, drawn: None)  # as if the constraints missed it
    failing = [r for r in pointwise.random_parameters(case) if r.status == Status.FAIL]
    assert failing and all(r.error is None for r in failing)
    assert "the scene cannot be loaded there: ValueError: " in failing[0].detail
    assert "inertia must satisfy A + B >= C" in failing[0].detail and "Iz = " in failing[0].detail


def cart_with_a_welded_lamp(tmp_path, binding):
    """The tutorial's cart-pendulum with a lamp welded on the cart (no joint: not in MuJoCo's tree of moving bodies,
    its inertia merged into the cart's) whose moments about its centre of mass are 1e-3, 2e-3 and J = 2.5e-3 kg m^2,
    J bound by `binding` (its attribute, index): above 3e-3, A + B >= C breaks."""
    folder = tutorial_subject(tmp_path).folder
    scene = folder / "scene.xml"
    inertia = "fullinertia" if binding[0] == "fullinertia" else "diaginertia"
    moments = "1e-3 2e-3 2.5e-3" + (" 0 0 0" if inertia == "fullinertia" else "")
    lamp = (f'<body name="lamp" pos="0 0 0.1"><inertial pos="0 0 0.05" mass="0.2" {inertia}="{moments}"/></body>\n'
            '      <body name="bob">')
    text = scene.read_text()
    assert text.count('<body name="bob">') == 1
    scene.write_text(text.replace('<body name="bob">', lamp))
    equations = folder / "equations.py"
    equations.write_text(equations.read_text().replace('"g": 9.81}', '"g": 9.81, "J": 2.5e-3}'))
    (folder / "case.toml").write_text('[scene.bindings]\nJ = [{ element = "body", name = "lamp", attribute = '
                                      '"%s", index = %d }]\n' % binding)
    return folder


@pytest.mark.parametrize("binding", [("inertia", 2), ("fullinertia", 2)])
def test_sets_that_break_a_welded_body_s_bound_inertia_are_not_drawn(tmp_path, binding):
    """A welded body's principal moment or full inertia bound: its current values read from MuJoCo's model (before,
    a KeyError of the tree, which has no welded body), the triangle inequality judged on them."""
    case = Case(cart_with_a_welded_lamp(tmp_path, binding))
    assert "lamp" not in {body.name for body in case.model("mujoco").tree()}
    assert "body 'lamp': principal moments" in pointwise.scene_breaks(case, {"J": 3.5e-3})
    assert pointwise.scene_breaks(case, {"J": 2.9e-3}) is None
    sets, missing = pointwise.parameter_sets(case)
    assert missing == 0 and sets and all(s["J"] <= 3e-3 for s in sets)
    with pytest.raises(ValueError, match="body 'lamp': principal moments"):  # what the draw keeps out
        case.with_params(J=3.5e-3).model("mujoco")


def test_a_bound_off_diagonal_entry_can_break_a_body(tmp_path):
    """Entries of a full inertia: an off-diagonal 1e-3 (on 1e-3, 2e-3, 2.5e-3) leaves a principal moment of 3.8e-4,
    still a body; 1.5e-3, a negative one."""
    folder = cart_with_a_welded_lamp(tmp_path, ("fullinertia", 2))
    toml = folder / "case.toml"
    toml.write_text(toml.read_text() + 'mu = [{ element = "body", name = "lamp", attribute = "fullinertia", '
                                       'index = 3 }]\n')
    equations = folder / "equations.py"
    equations.write_text(equations.read_text().replace('"J": 2.5e-3}', '"J": 2.5e-3, "mu": 1e-9}'))
    scene = folder / "scene.xml"
    scene.write_text(scene.read_text().replace("2.5e-3 0 0 0", "2.5e-3 1e-9 0 0"))
    case = Case(folder)
    assert pointwise.scene_breaks(case, {"mu": 1e-3}) is None
    assert "body 'lamp': principal moments of inertia about its centre of mass -" in pointwise.scene_breaks(
        case, {"mu": 1.5e-3})
