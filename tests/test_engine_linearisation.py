"""The engines' own linearisations (engines.coordinates.Linearisation, ball_joint_linearisation): against differences of
each engine's own accelerations, MuJoCo's against Pinocchio's, the sleeping top's eigenvalues against the theory,
and what they refuse."""

import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from dyncheck.case.folder import load_case
from dyncheck.checks import linear
from engines import coordinates

ROOT = Path(__file__).resolve().parent.parent
# a stiff spring (k = 4929 N/m, a light bob under g = 1): RNEA's rounding is of its own entries, not the spring's
STIFF = {"k": 4929.0, "m": 0.05, "g": 1.0}
CASES = [("double_pendulum", ROOT / "cases", {}), ("spring_pendulum", ROOT / "cases", {}),
         ("spring_pendulum", ROOT / "cases", STIFF), ("spinning_top", ROOT / "cases", {}),
         ("forced_cart_pendulum", ROOT / "examples", {})]
ENGINES = ("mujoco", "pinocchio")
EPS = np.finfo(float).eps


def states(case):
    """The book's initial state and two of the pointwise check's random ones (off equilibrium: the springs
    stretched, the drives turning); the top's second with a nutation in (0.3, 2.5), where |J^-1| <= 3.4."""
    (t, q, v), (random, other) = (0.0, *case.initial[:2]), case.sample_states()[:2]
    if "nutation" in case.coords:
        other[1][case.coords.index("nutation")] = np.random.default_rng(15).uniform(0.3, 2.5)
    return [(t, q, v), random, other]


def accelerations_jacobian(model, t, q, v):
    """d(q'')/d(q, q') (n, 2n) of a model's own `accelerations`, by dyncheck.checks.vibration's extrapolated differences (the
    derivation's linearisation), and their largest error estimate."""
    x = np.concatenate([q, v])
    jacobian, errors = linear.jacobian(lambda y: np.asarray(model.accelerations(t, *np.split(y, 2)), dtype=float),
                                          x, linear.scales_of(x))
    return jacobian, float(np.max(errors))


@pytest.fixture(scope="module", params=CASES, ids=[name + ("-stiff" if overrides else "") for name, _, overrides in CASES])
def case(request):
    name, folder, overrides = request.param
    return load_case(name, folder, **overrides)


@pytest.mark.parametrize("engine", ENGINES)
def test_linearisation_matches_the_engines_own_accelerations(case, engine):
    """M^-1 [force_q, force_v] is the derivative of the engine's own accelerations, to the two error estimates: the
    linearisation's, through M^-1 (an entry of M^-1 E sums |M^-1|_inf entries of E), and the differences'; and
    its mass matrix is `mass_matrix`, bit for bit (the same matrix through the same map)."""
    model = case.model(engine)
    for t, q, v in states(case):
        linear = model.linearisation(t, q, v)
        assert np.array_equal(linear.mass, model.mass_matrix(t, q, v))
        inverse_mass = np.linalg.inv(linear.mass)
        state_matrix = inverse_mass @ np.hstack([linear.force_q, linear.force_v])
        differences, difference_error = accelerations_jacobian(model, t, q, v)
        tolerance = np.linalg.norm(inverse_mass, np.inf) * linear.error + difference_error
        assert np.max(np.abs(state_matrix - differences)) <= tolerance, (case.name, engine, t, q, v)
        # the estimates are honest, but not vacuous: far below the entries
        assert tolerance <= 1e-8 * max(1.0, np.max(np.abs(differences))), (case.name, engine, tolerance)


def test_a_stiff_spring_is_no_scale_of_pinocchio_s_rounding():
    """The springs' -k join Pinocchio's RNEA derivatives in one rounding: 1e3 eps of k on every entry put 2e-6 on the
    stiff spring pendulum's angle row (its entries about 10) and left its mode rows inconclusive."""
    case = load_case("spring_pendulum", **STIFF)
    for t, q, v in states(case):
        assert case.model("pinocchio").linearisation(t, q, v).error < 0.1 * 1e3 * EPS * STIFF["k"]


def test_mujoco_agrees_with_pinocchio(case):
    """MuJoCo's differences and Pinocchio's analytic derivatives agree to their error estimates, once MuJoCo's
    placeholder masses and inertias (which the URDF's zeros lack) are allowed for: the scene with them doubled
    (case.approximations_doubled) moves MuJoCo's linearisation by their effect, measured with its own error."""
    twin = case.approximations_doubled()
    for t, q, v in states(case):
        mujoco, pinocchio, doubled = (model.linearisation(t, q, v)
                                      for model in (case.model("mujoco"), case.model("pinocchio"), twin))
        difference = lambda a, b: max(np.max(np.abs(a.force_q - b.force_q)), np.max(np.abs(a.force_v - b.force_v)))
        tolerance = difference(doubled, mujoco) + doubled.error + mujoco.error + pinocchio.error
        assert difference(mujoco, pinocchio) <= tolerance, (case.name, t, q, v)
        # MuJoCo's placeholder inertias (1e-14 kg m^2) against the largest entry: the pointwise check's 1e-9 bounds it
        assert np.max(np.abs(mujoco.mass - pinocchio.mass)) <= 1e-9 * np.max(np.abs(pinocchio.mass))
        assert "mjd_inverseFD" in mujoco.method and "analytic" in pinocchio.method


@pytest.fixture(scope="module")
def forced_by_a_law_of_the_state(tmp_path_factory):
    """The forced cart-pendulum pushed also by a law of its state, -3 sin(x) - 0.5 x theta' (its engines only: its
    derivation's push is the example's)."""
    folder = tmp_path_factory.mktemp("cases") / "forced_cart_pendulum"
    shutil.copytree(ROOT / "examples" / "forced_cart_pendulum", folder)
    toml = folder / "case.toml"
    toml.write_text(toml.read_text().replace('x = ["F0 * cos(Omega * t)"]',
                                             'x = ["F0 * cos(Omega * t) - 3 * sin(x) - 0.5 * x * theta_rate"]'))
    return load_case(folder.name, folder.parent)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_law_of_the_state_is_differenced(forced_by_a_law_of_the_state, engine):
    """A push that depends on the state enters force_q and force_v by its own differences: the linearisation
    still matches the engine's accelerations; its error holds the law's; a law of time only adds none."""
    case = forced_by_a_law_of_the_state
    model = case.model(engine)
    for t, q, v in states(case):
        linear = model.linearisation(t, q, v)
        inverse_mass = np.linalg.inv(linear.mass)
        differences, difference_error = accelerations_jacobian(model, t, q, v)
        tolerance = np.linalg.norm(inverse_mass, np.inf) * linear.error + difference_error
        assert np.max(np.abs(inverse_mass @ np.hstack([linear.force_q, linear.force_v]) - differences)) <= tolerance
    t, q, v = states(case)[1]
    law = coordinates.applied_derivatives(model.forces, model.m.nv, t, q, v)
    assert law[0][0] == pytest.approx([-3 * np.cos(q[0]) - 0.5 * v[1], 0.0], abs=law[2])
    assert law[1][0] == pytest.approx([0.0, -0.5 * q[0]], abs=law[2])
    time_only = load_case("forced_cart_pendulum", ROOT / "examples").model(engine)
    assert coordinates.applied_derivatives(time_only.forces, time_only.m.nv, t, q, v)[2] == 0.0


def sleeping_top_eigenvalues(case, spin):
    """The nonzero eigenvalues of the sleeping top about its tip at `spin` S, seen in the top's own axes: in the
    world, i [Izz S +- sqrt(Izz^2 S^2 - 4 Ixx m g h)] / (2 Ixx) and their conjugates (Ixx about the tip); a tilt
    that stands still in the world turns at -S in the body's axes, so the body sees each shifted by -i S (its
    conjugate by +i S).  The real parts, and so stability, are the same."""
    Ixx, Izz, m, g, h = (case.value(name) for name in ("Ixx", "Izz", "m", "g", "h"))
    root = np.sqrt(complex(Izz**2 * spin**2 - 4 * Ixx * m * g * h))
    world = 1j * (Izz * spin + np.array([root, -root])) / (2 * Ixx)
    return np.concatenate([world - 1j * spin, np.conj(world - 1j * spin)])


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("above", [1.5, 0.7])
def test_sleeping_top_eigenvalues(engine, above):
    """Above the least spin S_c = 2 sqrt(Ixx m g h) / Izz the sleeping top's eigenvalues are imaginary, below it
    a pair has a positive real part.  Each nonzero eigenvalue to first order in the error of A: its condition
    number (|y| |x| / |y^H x|, left and right eigenvectors) times |dA|_2 <= |dA|_F <= 6 error, with a factor 10
    for the second order; the spin's double zero is a Jordan block (dtheta_z' = dw_z, dw_z' = 0), whose
    eigenvalues move by the square root of the error."""
    case = load_case("spinning_top")
    Ixx, Izz, m, g, h = (case.value(name) for name in ("Ixx", "Izz", "m", "g", "h"))
    spin = above * 2 * np.sqrt(Ixx * m * g * h) / Izz
    matrix, error = case.model(engine).ball_joint_linearisation(np.array([1.0, 0.0, 0.0, 0.0]), [0.0, 0.0, spin])
    values, left, right = scipy.linalg.eig(matrix, left=True, right=True)
    zeros = np.argsort(np.abs(values))[:2]
    assert np.all(np.abs(values[zeros]) <= 10 * np.sqrt(6 * error))
    for expected in sleeping_top_eigenvalues(case, spin):
        i = np.argmin(np.abs(values - expected))
        condition = 1 / abs(np.vdot(left[:, i], right[:, i]))  # scipy's eigenvectors have unit norm
        assert abs(values[i] - expected) <= 10 * condition * 6 * error, (engine, above, values[i], expected)
    assert (np.max(values.real) > 1.0) == (above < 1)
    assert error <= 1e-9 * np.max(np.abs(matrix))


@pytest.mark.parametrize("engine", ENGINES)
def test_loops_are_refused(engine):
    """The slider-crank's coordinates' equations hold its loop's forces: no linearisation of the open tree."""
    case = load_case("slider_crank", ROOT / "examples")
    t, q, v = case.sample_states()[0]
    with pytest.raises(ValueError, match=r"scene\.xml: linearisation of a scene with closed loops"):
        case.model(engine).linearisation(t, q, v)


@pytest.mark.parametrize("engine", ENGINES)
def test_ball_joint_linearisation_needs_a_lone_ball_joint(engine):
    case = load_case("double_pendulum")
    with pytest.raises(ValueError, match="ball_joint_linearisation needs a scene whose only joint is a ball joint"):
        case.model(engine).ball_joint_linearisation(np.array([1.0, 0.0, 0.0, 0.0]), [0.0, 0.0, 1.0])
