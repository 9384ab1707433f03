"""Vibration analysis (dyncheck/checks/vibration.py, the book's step 16): equilibria by Newton-Raphson, the
linearisation of the derivation and of both engines, frequencies against closed forms and against runs,
the stability boundaries against their formulas and runs either side; a wrong term fails, a bad table is
refused naming its field."""

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

import dyncheck
from dyncheck.checks import floquet, linear, vibration
from dyncheck.common import ceilings, derivatives
from dyncheck.pages import vibration_page
from dyncheck.results.values import Status
from dyncheck.studies import campbell

pytestmark = pytest.mark.full  # runs of the cases' engines, seconds each: `pytest -m full`

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def double_pendulum_closed_form(p):
    """The hanging double pendulum's frequencies, theta2 measured from arm 1: sqrt of the eigenvalues of (K, M)."""
    m1, m2, l1, l2, g = (p[k] for k in ("m1", "m2", "l1", "l2", "g"))
    mass = np.array([[m1 * l1**2 + m2 * (l1 + l2) ** 2, m2 * l2 * (l1 + l2)], [m2 * l2 * (l1 + l2), m2 * l2**2]])
    stiffness = g * np.array([[(m1 + m2) * l1 + m2 * l2, m2 * l2], [m2 * l2, m2 * l2]])
    return np.sqrt(scipy.linalg.eigh(stiffness, mass, eigvals_only=True))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_double_pendulums_frequencies_are_the_closed_forms_at_random_parameters(seed):
    rng = np.random.default_rng(seed)
    case = dyncheck.load_case("double_pendulum", m1=rng.uniform(0.01, 1), m2=rng.uniform(0.01, 1),
                              l1=rng.uniform(0.05, 1), l2=rng.uniform(0.05, 1), g=rng.uniform(1, 20))
    table = linear.settings(case)
    eq = linear.equilibrium(case.model("reference"), 0.0, table["q"], table["v"], table["solve"], case.coords)
    assert np.max(np.abs(eq.q)) < 1e-12
    expected = double_pendulum_closed_form(case.params)
    for source in ("reference", "mujoco", "pinocchio"):
        model = case.model(source)
        equations = (linear.derivation_linear(model, source, eq) if source == "reference"
                  else linear.engine_linear(model, source, eq))
        modes = linear.modal(equations)
        found = [modes.eigenvalues[i].imag for i in modes.oscillating()]
        # the eigenvalues' own bounds are ~1e-10 of them; the engines' placeholders ~1e-11
        np.testing.assert_allclose(found, expected, rtol=1e-8)
        assert modes.verdict == "marginally stable"


@pytest.fixture(scope="module")
def analysed():
    """The analysis of the book's cases that have one, at their numbers."""
    return {name: vibration.analyse(dyncheck.load_case(name))
            for name in ("double_pendulum", "rotating_pendulum", "spring_pendulum", "spinning_top")}


def test_every_comparison_passes_at_the_books_numbers(analysed):
    for name, vib in analysed.items():
        assert vib.rows and all(r.status == Status.PASS for r in vib.rows), (name, [r for r in vib.rows
                                                                                  if r.status != Status.PASS])
        sources = {s for r in vib.rows for s in r.sources}
        assert sources == {"reference", "mujoco", "pinocchio"}, name
        # every oscillating mode's eigenvalue is checked by a run in each source
        modes = len(vib.modes["reference"].oscillating())
        assert sum("by motion" in r.quantity for r in vib.rows) == 3 * modes, name


def test_the_tops_steady_precession_is_the_slow_root_of_the_x2_row(analysed):
    vib = analysed["spinning_top"]
    p = dyncheck.load_case("spinning_top").params
    n, s = vib.equilibrium.q[1], vib.equilibrium.v[2]
    a, b, c = (p["Izz"] - p["Ixx"]) * math.cos(n), p["Izz"] * s, -p["m"] * p["g"] * p["h"]
    roots = np.roots([a, b, c])
    slow = roots[np.argmin(np.abs(roots))]
    assert vib.equilibrium.v[0] == pytest.approx(slow, rel=1e-12)


def test_the_spring_pendulums_runaway_boundary_comes_out_of_the_eigenvalues():
    case = dyncheck.load_case("spring_pendulum")
    sweep = campbell.sweep(case)
    scene = linear.linearised(case)
    omega = scene.params["beta_rate"]
    assert sweep.boundary == pytest.approx(math.sqrt(scene.params["k"] / scene.params["m"]), rel=2e-6)
    k_crit = [f for f in sweep.findings if f.startswith("Boundary from the eigenvalues: k =")]
    assert k_crit and f"{scene.params['m'] * omega**2:.7g}" in k_crit[0]
    either = [f for f in sweep.findings if f.startswith("Run at")]
    assert len(either) == 4 and all("as the eigenvalues say" in f for f in either)
    assert sum("leaves the equilibrium" in f for f in either) == 2


def test_a_soft_spring_finds_only_the_unstable_equilibrium_through_the_hinge():
    case = dyncheck.load_case("spring_pendulum", k=100.0)  # below m Omega^2 = 160 N/m: the spin wins
    vib = vibration.analyse(case)
    assert vib.equilibrium.q[1] + case.params["l0"] < 0  # the particle beyond the hinge, held by the pull
    assert {m.verdict for m in vib.modes.values()} == {"unstable"}
    about_equilibrium = [r for r in vib.rows if r not in vib.floquet.rows]
    assert all(r.status == Status.PASS for r in about_equilibrium[:-1])
    last = about_equilibrium[-1]
    assert last.status == Status.NOT_APPLICABLE and "unstable equilibrium" in last.detail
    # its page says that no mode was run (it raised a TypeError, formatting the amplitude of no run)
    assert "the runs: none: the equilibrium is unstable, and every run leaves it" in \
        vibration_page.frequency_lines(vib, case)[0]


def test_no_equilibrium_in_either_is_not_applicable(monkeypatch):
    monkeypatch.setattr(derivatives, "NEWTON_ITERATIONS", 0)  # Newton-Raphson gives up at once, in every source
    vib = vibration.analyse(dyncheck.load_case("double_pendulum"))
    assert [r.status for r in vib.rows] == [Status.NOT_APPLICABLE] and "finds none from the guess in either" in vib.rows[0].detail


def test_a_mujoco_run_whose_twin_failed_is_no_number_naming_the_twin(monkeypatch):
    # Without its twin at twice the step MuJoCo's step error is unknown: its row says so rather than allow none.
    case = dyncheck.load_case("double_pendulum")
    twin_step = linear.MUJOCO_TWIN * case.integration["mujoco_step"]
    real = linear.mode_run

    def twin_fails(case, model, source, eq, modes, i, amplitude, periods, method, dt=None):
        if dt == twin_step:
            return linear.Motion(source, i, amplitude, None, None, "mujoco:RK4: unstable at t = 0.1 s (step 500)")
        return real(case, model, source, eq, modes, i, amplitude, periods, method, dt)

    monkeypatch.setattr(vibration, "mode_run", twin_fails)
    rows = [r for r in vibration.analyse(case).rows if "by motion" in r.quantity]
    mujoco = [r for r in rows if r.sources == ("mujoco",)]
    assert len(mujoco) == 2 and all(r.status == Status.UNSTABLE and "its twin at twice the step failed" in r.detail
                                    for r in mujoco)
    assert all(r.status == Status.PASS for r in rows if r.sources != ("mujoco",))


def edited_case(tmp_path, folder, *edits):
    """The case `folder` copied into tmp_path, each edit (file, old, new) made where `old` stands once, and loaded."""
    copy = tmp_path / folder.name
    shutil.copytree(folder, copy, ignore=shutil.ignore_patterns("__pycache__"))
    for file, old, new in edits:
        text = (copy / file).read_text()
        assert text.count(old) == 1, (file, old)
        (copy / file).write_text(text.replace(old, new))
    return dyncheck.load_case(folder.name, tmp_path)


def planted(tmp_path, old, new):
    """The forced cart-pendulum example with one edit of its equations."""
    return edited_case(tmp_path, EXAMPLES / "forced_cart_pendulum", ("equations.py", old, new))


def test_the_damped_example_is_asymptotically_stable_and_checked(tmp_path):
    vib = vibration.analyse(edited_case(tmp_path, EXAMPLES / "forced_cart_pendulum"))
    assert all(r.status == Status.PASS for r in vib.rows)
    assert {m.verdict for m in vib.modes.values()} == {"asymptotically stable"}
    assert any(r.quantity == "D (damping)" and r.sources == ("reference", "pinocchio") for r in vib.rows)


def test_a_wrong_damper_in_the_derivation_fails_its_linearisation(tmp_path):
    vib = vibration.analyse(planted(tmp_path, '- p["ct"] * theta_rate])', '- 1.01 * p["ct"] * theta_rate])'))
    failed = {r.quantity for r in vib.rows if r.status == Status.FAIL and "reference" in r.sources}
    assert {"A = d(q', q'')/d(q, q')", "D (damping)"} <= failed
    assert any(q.startswith("frequency mode") for q in failed)
    # the engines agree with each other and with their own runs
    assert all(r.status == Status.PASS for r in vib.rows if "reference" not in r.sources)


def test_a_derivation_without_the_engines_equilibrium_fails(tmp_path):
    vib = vibration.analyse(planted(tmp_path, "-m * g * l * np.sin(theta)", "-m * g * l * (np.sin(theta) + 100)"))
    assert [r.status for r in vib.rows] == [Status.FAIL] and "MuJoCo has one" in vib.rows[0].detail


@pytest.mark.parametrize("edit, message", [
    (("solve = [\"x\", \"theta\"]", "solve = [\"x\", \"phi\"]"), "vibration.solve names 'phi'"),
    (("q = [0.01, 0.1]", "q = [0.01]"), "vibration.q has 1 entries"),
    (("overrides = { F0 = 0.0 }", "overrides = { F1 = 0.0 }"), "vibration.overrides: no parameter 'F1'"),
    (("periods = 10", "periods = 0"), "periods"),
])
def test_a_bad_vibration_table_is_refused_naming_its_field(tmp_path, edit, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace("[", r"\[")):
        linear.validate(edited_case(tmp_path, EXAMPLES / "forced_cart_pendulum", ("case.toml", *edit)))


@pytest.mark.parametrize("name, override", [("spring_pendulum", {"m": 0.9})])
def test_a_lighter_bob_gives_conclusive_vibration_rows(name, override):
    # At the case's amplitude the stroboscopic rows' tolerance was 1.7e-4, above the ceiling 1e-4 (the nonlinear
    # shift); the amplitude halved (settled_amplitude), every vibration row passes.
    rows = vibration.analyse(dyncheck.load_case(name, **override)).rows
    assert rows and all(r.status is Status.PASS for r in rows if r.error is not None), \
        [(r.quantity, r.sources, str(r.status)) for r in rows if r.status is not Status.PASS]


def test_newton_finds_the_heavy_double_pendulums_equilibrium():
    # m2 = 80 m1: the linear model's first steps went many turns away and stalled at theta1 = -187 rad (|q''| 47);
    # a step of at most a radian reaches the hanging equilibrium
    vib = vibration.analyse(dyncheck.load_case("double_pendulum", m2=3.7))
    assert vib.equilibrium is not None and np.max(np.abs(vib.equilibrium.q)) < 1e-12
    assert all(r.status is Status.PASS for r in vib.rows), [(r.quantity, str(r.status)) for r in vib.rows]


def test_a_small_multiplier_beside_a_large_one_is_judged_by_its_condition():
    # Drawn by `pytest -m slow` (tests/test_whole_runs.py): an unstable orbit (psi = -146.04 rad, psi' = -0.62), its
    # multipliers 0.017 and 59.  The small one's Floquet rows were inconclusive (ceiling 1e-6 of |mu|, tolerance
    # 8e-6); its ceiling is now its change under a term of 1e-6 of every entry of Phi(T), as an eigenvalue's of A
    case = dyncheck.load_case("rotating_pendulum", beta_rate=3.553239637656647, m=0.7608564989312635,
                              a=0.016549572222525136, c=0.010889868082228252, g=1.0, b=0.9954854367992794,
                              l=0.4876207142464939, h=0.016549572222525136, alpha_rate=-3.7657084985644085, beta0=-1.9,
                              alpha0=-3.116409447015411, r=0.19198205169631802)
    period = floquet.period_of(case, floquet.floquet_settings(case))
    states = floquet.periodic_orbit(case, "reference", np.array([-146.0356, -0.6217]), period)[0]
    assert states[0] == pytest.approx([-146.0355951, -0.62170769], abs=1e-6)
    rows = []
    _, monodromy = floquet.resolved_monodromy(case, states, period, rows)
    assert sorted(abs(monodromy["reference"].multipliers)) == pytest.approx([0.01695534, 58.978468], rel=1e-6)
    rows = floquet.floquet_rows(monodromy, case.tolerance["pointwise"]["value"])
    small = [r for r in rows if r.quantity == "Floquet multiplier 1"]
    assert len(small) == 3 and all(r.ceiling > r.tolerance > ceilings.POINTWISE for r in small)  # once inconclusive
    assert all(r.status == Status.PASS for r in rows), [r for r in rows if r.status != Status.PASS]


def test_mujoco_s_stroboscopic_run_allows_for_its_approximations():
    # A spring held just above its runaway (k = 165 N/m, k_crit = m Omega^2 = 160): the drift of the disk's prescribed
    # rate through MuJoCo's armature moved its measured |mu| by 2.7e-7, the rest of its allowance 5e-9 (a random
    # --set sweep: the row failed).  Its run with the approximations doubled measures the effect: 2.58e-7
    analysis = floquet.floquet(dyncheck.load_case("spring_pendulum", k=165.0))
    mujoco = [r for r in analysis.rows if r.quantity.startswith("largest Floquet") and r.sources == ("mujoco",)]
    assert len(analysis.motions) == 6 and mujoco and mujoco[0].status == Status.PASS
    assert 1e-7 < mujoco[0].error < mujoco[0].tolerance < ceilings.MOTION
