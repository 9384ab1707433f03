"""Random parameter sets are physical in the scene too: the constraints a scene's bindings imply (a positive mass,
principal moments about the centre of mass that a rigid body has) are drawn within, and a set the engines still
cannot load is a failing row that says why, never a traceback."""

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
