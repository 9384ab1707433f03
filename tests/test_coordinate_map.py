"""A derivation in coordinates of its own over the scene's joints (dyncheck.case.coordinate_map): a chain's equations in
absolute angles over its relative hinges, as a symbolic package or a textbook writes them, runs from two files with a
JOINTS map, is compared with both engines in its own coordinates, and an error planted in it is named in its own
equations and symbols.  A map that is no map is refused, naming the file and the entry."""

import numpy as np
import pytest

import chain
from dyncheck import cli
from dyncheck.case import coordinate_map
from dyncheck.case.folder import Case
from dyncheck.case.scene import PLACEHOLDER_INERTIA
from dyncheck.checks import pointwise, residuals
from dyncheck.checks.runs import run_case
from dyncheck.results.values import Status

def absolute_chain(folder, n, planted="", joints=None):
    """The chain's case folder with its derivation in absolute angles phi_k (tests/chain.py) and the map JOINTS."""
    return chain.write(folder, n, planted, absolute=True, joints=joints)


def test_the_map_is_affine_and_exact():
    m = coordinate_map.parse({"a": "phi1", "b": "phi2 - phi1 + pi / 2", "c": "-2 * phi3"}, ("phi1", "phi2", "phi3"),
                             {}, "JOINTS")
    assert m.matrix.tolist() == [[1, 0, 0], [-1, 1, 0], [0, 0, -2]] and m.offset.tolist() == [0, np.pi / 2, 0]
    q, v = np.array([0.3, -1.2, 2.0]), np.array([1.0, 2.0, 3.0])
    back = m.case_state(*m.joint_state(q, v))
    assert np.allclose(back[0], q, rtol=0, atol=4e-16) and np.allclose(back[1], v, rtol=0, atol=4e-16)


@pytest.mark.parametrize("joints, said", [
    ({"a": "phi1 * phi2", "b": "phi2"}, "JOINTS.a = 'phi1 * phi2': is not affine in the coordinates"),
    ({"a": "sin(phi1)", "b": "phi2"}, "JOINTS.a = 'sin(phi1)': is not affine"),
    ({"a": "phi1 + phi2", "b": "2 * phi1 + 2 * phi2"}, "the joints do not determine the coordinates"),
    ({"a": "phi1", "b": "psi"}, "JOINTS.b = 'psi': names 'psi', which is no coordinate"),
    ({"a": "phi1"}, "gives 1 joints (a) for 2 coordinates"),
    ({"a": "phi1", "b": "phi2 +"}, "JOINTS.b = 'phi2 +'")])
def test_a_map_that_is_no_map_is_refused(joints, said):
    with pytest.raises(ValueError) as error:
        coordinate_map.parse(joints, ("phi1", "phi2"), {}, "JOINTS")
    assert said in str(error.value), str(error.value)


@pytest.mark.parametrize("joints, said", [
    ({"theta1": "phi1", "theta3": "phi2 - phi1"}, "JOINTS['theta3'] is no hinge or slide"),
    ({"theta1": "phi1"}, "JOINTS leaves joints of"),
    ({"theta1": "phi1", "theta2": "phi1 * phi2"}, "JOINTS.theta2 = 'phi1 * phi2': is not affine")])
def test_a_two_file_case_with_a_bad_map_exits_2_naming_the_entry(tmp_path, capsys, joints, said):
    folder = absolute_chain(tmp_path / "cases" / "absolute", 2, joints=joints)
    assert cli.main(["run", "absolute", "--cases", str(folder.parent), "--quick"]) == 2
    err = capsys.readouterr().err
    assert "equations.py" in err and said in err, err


@pytest.mark.parametrize("n", [2, 3])
def test_a_chain_in_absolute_angles_passes(tmp_path, n):
    """Both engines, mapped, give the derivation's M and q'' in its absolute angles, to rounding (M = A^T M_joints A
    and q'' = A^{-1} q''_joints, exact for a constant A), and every row of its run passes."""
    case = Case(absolute_chain(tmp_path / f"absolute{n}", n))
    assert case.coords == tuple(f"phi{k + 1}" for k in range(n)) and case.scene.coords == tuple(
        f"theta{k + 1}" for k in range(n))
    rng = np.random.default_rng(3)
    q, v = rng.uniform(-np.pi, np.pi, n), rng.uniform(-5, 5, n)
    reference = case.model("reference")
    for source in ("mujoco", "pinocchio"):
        model = case.model(source)
        mass = np.asarray(reference.mass_matrix(0.0, q, v))
        # rounding of each side's M (a few eps of its largest entry) and the scene's placeholder inertias (n bodies
        # of PLACEHOLDER_INERTIA, which the derivation has not), through A^T . A
        allowed = (64 * np.finfo(float).eps * np.max(np.abs(mass))
                   + n * PLACEHOLDER_INERTIA * case.scene.coordinate_map.error_factor)
        assert np.max(np.abs(model.mass_matrix(0.0, q, v) - mass)) <= allowed
        acc = np.asarray(reference.accelerations(0.0, q, v))
        assert np.max(np.abs(model.accelerations(0.0, q, v) - acc)) <= 1e-12 * max(1.0, np.max(np.abs(acc)))
    result = run_case(case, localise=False)
    failing = [(r.check, r.quantity, r.sources, r.detail) for r in result.rows
               if r.status not in (Status.PASS, Status.NOT_APPLICABLE)]
    assert not failing, failing


def test_an_error_in_absolute_angles_is_named_in_them(tmp_path):
    """Half the second mass's weight moment about the shoulder left out of the phi1 equation: named in phi1's
    equation, as a term in phi's own symbols (sin(phi2)), not in the joints' theta."""
    planted = '0.5 * p["m2"] * p["g"] * LENGTHS[0] * np.sin(q[1]) * (np.arange(len(q)) == 0)'
    case = Case(absolute_chain(tmp_path / "planted", 2, planted))
    _, sample = pointwise.pointwise(case)
    rows, found = residuals.equation_rows(case, sample)
    failing = {(r.quantity, r.sources[0]) for r in rows if r.status == Status.FAIL}
    assert failing == {("phi1 residual", "reference"), ("f[phi1]", "reference")}, failing
    localisations = residuals.localise(case, rows, found, pointwise.parameter_sets(case)[0])
    assert [(loc.equation, loc.exact) for loc in localisations] == [("phi1", True)], localisations
    assert "sin(phi2)" in localisations[0].text and "theta" not in localisations[0].text, localisations[0].text


def test_the_mapped_linearisation_is_the_derivation_s_in_its_coordinates(tmp_path):
    """Both engines' linearisations, mapped (A^T K A, A^T C A), against the derivation's own equations differenced in
    its absolute angles at a state off equilibrium, at fixed accelerations a (the linearisation's: d(f - M a)/dq and
    df/dq'): central differences at h = 1e-6 are off by h^2 f''' ~ 1e-12 and by rounding eps |f| / h ~ 1e-9 of f's
    size, so 1e-7 of the largest entry tells a wrong map (an entry off by O(1))."""
    case = Case(absolute_chain(tmp_path / "absolute3", 3))
    reference = case.model("reference")
    q, v, h = np.array([0.3, -0.2, 0.5]), np.array([0.4, 0.1, -0.3]), 1e-6
    a = np.asarray(reference.accelerations(0.0, q, v))
    f = lambda q, v: np.asarray(reference.mass_matrix(0.0, q, v) @ (reference.accelerations(0.0, q, v) - a))
    columns = lambda x, g: np.column_stack([(g(x + h * e) - g(x - h * e)) / (2 * h) for e in np.eye(3)])
    force_q, force_v = columns(q, lambda x: f(x, v)), columns(v, lambda x: f(q, x))
    for source in ("mujoco", "pinocchio"):
        lin = case.model(source).linearisation(0.0, q, v)
        for mine, theirs in ((lin.force_q, force_q), (lin.force_v, force_v)):
            assert np.max(np.abs(mine - theirs)) <= 1e-7 * np.max(np.abs(theirs)), (source, mine, theirs)
        assert np.allclose(lin.mass, reference.mass_matrix(0.0, q, v), rtol=0, atol=1e-12)


def test_the_map_may_be_a_case_toml_s_scene_joints(tmp_path, capsys):
    """The map in a case.toml beside the files, `[scene.joints]` instead of JOINTS: the same case, and a wrong entry
    there named as case.toml's."""
    folder = absolute_chain(tmp_path / "cases" / "absolute", 2)
    equations = folder / "equations.py"
    equations.write_text("\n".join(line for line in equations.read_text().splitlines() if not line.startswith("JOINTS")))
    (folder / "case.toml").write_text('[scene.joints]\ntheta1 = "phi1"\ntheta2 = "phi2 - phi1"\n')
    case = Case(folder)
    assert case.scene.coordinate_map.matrix.tolist() == [[1, 0], [-1, 1]]
    assert cli.main(["run", "absolute", "--cases", str(folder.parent), "--quick"]) == 0
    (folder / "case.toml").write_text('[scene.joints]\ntheta1 = "phi1"\ntheta2 = "phi2 * phi1"\n')
    assert cli.main(["run", "absolute", "--cases", str(folder.parent), "--quick"]) == 2
    err = capsys.readouterr().err
    assert "case.toml: scene.joints.theta2 = 'phi2 * phi1': is not affine" in err, err
