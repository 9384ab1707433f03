"""Pieces of the vibration analysis, each in seconds (the default `pytest`; tests/test_vibration.py runs the whole
analysis of every case): the amplitude of its runs (settled_amplitude), halved while its nonlinear shift would take the rows'
tolerance near their ceiling and no further than HALVINGS; the shooting's failure as NoOrbit (a singular Jacobian, a
stall), and its continuation from the book's orbit."""

import math
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.integrate

import dyncheck
from dyncheck.checks import floquet, linear, vibration
from dyncheck.common import ceilings
from dyncheck.pages import vibration_page
from dyncheck.results.values import Status


class _Run:  # a run's measured exponent, as a Motion gives it
    def __init__(self, exponent, ok=True):
        self.exponent, self.ok = exponent, ok


@pytest.mark.parametrize("power, halvings", [(2, 2), (1, 4)])
def test_the_amplitude_is_halved_until_its_shift_is_a_tenth_of_the_ceiling(power, halvings):
    # A shift of 1.5e-5 |lambda| at the case's amplitude, quadratic or linear in it: 10 x the shift must come within
    # a tenth of the ceiling 1e-4, i.e. the shift within 1e-6: two halvings (9.4e-7) or four (9.4e-7).  Each
    # amplitude is run once: a halving's run at twice its amplitude is the last one's.
    size, asked = 50.0, []
    exponent = lambda a: 1.5e-5 * size * (a / 1e-3) ** power / (2**power - 1)  # run(2a) - run(a): 1.5e-5 size at 1e-3
    run = lambda a: asked.append(a) or _Run(exponent(a))
    amplitude, runs, shift = linear.settled_amplitude(1e-3, size, run, lambda at, doubled: doubled.exponent - at.exponent)
    assert amplitude == 1e-3 / 2**halvings and asked == [2e-3] + [1e-3 / 2**k for k in range(halvings + 1)]
    assert [r.exponent for r in runs] == [exponent(amplitude), exponent(2 * amplitude)]
    assert linear.SAFETY * shift <= ceilings.MOTION / 10 * size < linear.SAFETY * 2**power * shift


def test_a_failed_or_hopeless_run_is_not_halved_forever():
    failed = lambda a: _Run(None, ok=a < 2e-3)  # the run at twice the amplitude fails
    assert linear.settled_amplitude(1e-3, 1.0, failed, None)[::2] == (1e-3, math.inf)
    asked = []
    hopeless = lambda a: asked.append(a) or _Run(1.0 if a > 1.5e-3 else 0.0)  # a shift no halving removes
    shift_of = lambda at, doubled: 1.0
    assert linear.settled_amplitude(1e-3, 1.0, hopeless, shift_of)[0] == 1e-3 / 2**linear.HALVINGS
    assert len(asked) == linear.HALVINGS + 2


def test_a_singular_shooting_jacobian_is_no_orbit_not_a_traceback(monkeypatch):
    # Phi(T) - I singular (a multiplier at 1): rotating_pendulum --set l=0.05 --set alpha_rate=-5 raised LinAlgError
    # out of `dyncheck run`; it is NoOrbit, which the Floquet analysis turns into its row
    case = dyncheck.load_case("rotating_pendulum")
    table = floquet.floquet_settings(case)
    period = floquet.period_of(case, table)
    monkeypatch.setattr(floquet, "transition", lambda samples, *args: (np.eye(2)[None], None))
    guess = np.concatenate([table["q"], table["v"]]) + 0.1  # off the orbit: Newton must step
    with pytest.raises(floquet.NoOrbit, match=r"Phi\(T\) - I is singular at psi = "):
        floquet.periodic_orbit(case, "reference", guess, period)


def test_a_shooting_whose_steps_do_nothing_stops_after_stall_iterations(monkeypatch):
    # A monodromy matrix the samples do not resolve gave the spring pendulum at m = 1e-4 kg steps of nothing: its
    # |x(T) - x(0)| stayed at 31 for all 50 iterations (137 s).  Here Phi(T) is huge, so each step is ~1e-12
    case = dyncheck.load_case("rotating_pendulum")
    table = floquet.floquet_settings(case)
    period = floquet.period_of(case, table)
    monkeypatch.setattr(floquet, "transition", lambda samples, *args: (1e12 * np.eye(2)[None], None))
    runs = []
    orbit_run = floquet.orbit_run
    monkeypatch.setattr(floquet, "orbit_run", lambda *args: runs.append(args[-1]) or orbit_run(*args))
    guess = np.concatenate([table["q"], table["v"]]) + 0.1
    with pytest.raises(floquet.NoOrbit, match=r"stalled: \|x\(T\) - x\(0\)\| stayed at .* for 5 iterations"):
        floquet.periodic_orbit(case, "reference", guess, period)
    assert runs.count(case.integration["tight_rtol"]) == floquet.STALL + 1


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_an_orbit_that_shooting_misses_from_the_guess_is_continued_from_the_book_s():
    # At 4 times the book's arm rate Newton-Raphson from the case file's guess stalls at |x(T) - x(0)| = 1.7 (and
    # the row said no orbit existed); continued from the book's orbit it converges, to the orbit that
    # scipy.optimize.root finds on phi_T(x) - x from the same continuation (psi = 0.648, psi' = 0)
    case = dyncheck.load_case("rotating_pendulum", alpha_rate=3.14)
    table = floquet.floquet_settings(case)
    (states, _, residual, error), continued = floquet.continued_orbit(
        case, np.concatenate([table["q"], table["v"]]), floquet.period_of(case, table))
    assert continued > 0 and residual <= error
    assert states[0] == pytest.approx([0.648064, 0.0], abs=1e-6)


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_each_step_of_the_continuation_shoots_at_its_own_period(monkeypatch):
    # The disk's rate sets the period (2 pi / |beta'|): shot at the case's period, the book's orbit "converged" at
    # T = 10.47 s on the book's 8 s system, and the continuation then failed (found in review)
    case = dyncheck.load_case("rotating_pendulum", alpha_rate=3.14, beta_rate=0.6)
    periods = []
    periodic_orbit = floquet.periodic_orbit
    monkeypatch.setattr(floquet, "periodic_orbit",
                        lambda at, source, start, period, *rest: periods.append((dict(at.overrides), period))
                        or periodic_orbit(at, source, start, period, *rest))
    analysis = floquet.floquet(case)
    assert analysis.continued > 0 and analysis.monodromy
    assert periods[1] == ({"alpha_rate": pytest.approx(math.pi / 4), "beta_rate": pytest.approx(math.pi / 4)},
                          pytest.approx(8.0))
    assert all(period == pytest.approx(2 * math.pi / at["beta_rate"]) for at, period in periods[1:])


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_the_eigensolver_s_rounding_is_measured_not_bounded_by_the_matrix_s_norm():
    # At 2.3 times the book's disk rate the spring-mass pendulum's mode shapes agree to 5e-11 in all three sources,
    # but eps |A| (the stiffness over a mass, 6,200 1/s^2, where the shapes' coordinates are 1/74 of their rates)
    # put their tolerances at 4.8e-6, above the ceilings of 3e-6: six rows were inconclusive.  Measured, the
    # rounding leaves them passing, each tolerance still 1,000 times the sources' disagreement
    case = dyncheck.load_case("spring_pendulum", beta_rate=58.41)
    shapes = [r for r in vibration.analyse(case).rows if r.quantity.startswith("mode shape")]
    assert len(shapes) == 6 and all(r.status == Status.PASS for r in shapes)
    assert all(1e3 * r.error < r.tolerance < r.ceiling for r in shapes)


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_the_samples_of_a_are_doubled_while_the_monodromy_s_estimate_is_the_interpolation_s(monkeypatch):
    # The estimate is the twin's, from every other sample: off the book's numbers (arm and disk at -5 and -2.8 rad/s)
    # A's harmonics reached past the twin's resolution, and every Floquet row was inconclusive from 64 samples whose
    # Phi(T) agreed with 128's to 6e-12.  Here the book's orbit sampled 4 times: the estimate's share of the rows'
    # ceiling is 0.76 (the Floquet rows inconclusive); from 8, 6e-5; from 16, 8e-8, the twin's integration error,
    # which more samples do not lower
    case = dyncheck.load_case("rotating_pendulum")
    table = floquet.floquet_settings(case)
    period = floquet.period_of(case, table)
    states = floquet.periodic_orbit(case, "reference", np.concatenate([table["q"], table["v"]]), period)[0]
    share = lambda monodromy: max(2 * linear.SAFETY * np.max(m.errors) / np.max(np.abs(m.matrix))
                                  for m in monodromy.values())
    rows = []
    resolved, monodromy = floquet.resolved_monodromy(case, states[::16], period, rows)
    assert len(resolved) == 17 and not rows
    assert resolved == pytest.approx(states[::4], rel=0, abs=1e-15)  # the orbit's run again, with more outputs
    assert share(monodromy) <= ceilings.POINTWISE / 10
    # at the case's 64 samples nothing is doubled; with a 100 times lower ceiling the estimate stays above its share,
    # and the samples are doubled once: 128 do not halve it, and the doubling stops
    assert len(floquet.resolved_monodromy(case, states, period, rows)[0]) == len(states)
    monkeypatch.setattr(ceilings, "POINTWISE", ceilings.POINTWISE / 100)
    assert len(floquet.resolved_monodromy(case, states, period, rows)[0]) == 2 * len(states) - 1


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_an_orbit_shooting_misses_but_mujoco_finds_is_shot_from_mujoco_s(monkeypatch):
    # The arm and disk at -3.77 and 3.55 rad/s (tests/test_vibration.py analyses its orbit): the derivation's
    # Newton-Raphson from the guess ran off, and so did the continuation; MuJoCo's converged (on AVX-512 kernels), and
    # the row failed the derivation for lacking an orbit it has.  Here the derivation's own shooting from the guess is
    # made to fail at the book's numbers
    case = dyncheck.load_case("rotating_pendulum")
    periodic_orbit = floquet.periodic_orbit
    table = floquet.floquet_settings(case)
    guess = np.concatenate([table["q"], table["v"]])

    def missing_from_the_guess(at, source, start, *rest):
        if source == "reference" and np.array_equal(start, guess):
            raise floquet.NoOrbit("planted")
        return periodic_orbit(at, source, start, *rest)

    monkeypatch.setattr(floquet, "periodic_orbit", missing_from_the_guess)
    analysis = floquet.floquet(case)
    assert analysis.seeded and analysis.monodromy and all(r.status == Status.PASS for r in analysis.rows)
    assert "from MuJoCo's orbit" in "\n".join(vibration_page.floquet_lines(SimpleNamespace(floquet=analysis), case))


@pytest.mark.parametrize("lam", [1j, -0.3 + 2j, 5.366j])
def test_dop853_s_error_on_a_linear_motion_is_its_stability_function_s(lam):
    # A mode's DOP853 run at its step cap (a twentieth of the period) moves lambda by 6.1e-12 of |lambda|; the
    # rows allowed nothing for it, and a spring pendulum's mode off by 6.3e-12 failed at 5.0e-12 (pytest -m slow)
    step, steps = 2 * math.pi / lam.imag / linear.STEPS_PER_PERIOD, 200
    rates = lambda t, y: [lam.real * y[0] - lam.imag * y[1], lam.imag * y[0] + lam.real * y[1]]  # z' = lambda z
    solver = scipy.integrate.DOP853(rates, 0.0, [1.0, 0.0], steps * step, first_step=step, max_step=step, rtol=1e-3, atol=1e-3)
    while solver.status == "running":
        solver.step()
    assert solver.t == pytest.approx(steps * step, rel=1e-12)
    z = complex(*solver.y)
    turns = round((lam.imag * solver.t - np.angle(z)) / (2 * math.pi))  # the phase's whole turns, which log drops
    measured = abs(complex(np.log(abs(z)), np.angle(z) + 2 * math.pi * turns) / solver.t - lam)
    assert measured == pytest.approx(linear.dop853_exponent_error(lam, step), rel=1e-3)
    assert 5e-12 < measured / abs(lam) < 8e-12


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
@pytest.mark.parametrize("overrides", [{"m1": 0.05, "m2": 2.0}, {"m1": 0.0533416, "l1": 0.0789191, "m2": 0.713027}])
def test_newton_finds_the_hanging_state_where_the_mass_matrix_is_nearly_singular(overrides):
    # A light inner mass makes M's condition 1,000: q'' = M^-1 f is far from linear near the hanging state, and
    # Newton-Raphson on it did not converge (the first) or went to theta2 = 5 pi (the second, where every source
    # agreed that the pendulum was unstable, exit 0).  On the forces M q'' (over M's diagonal) it converges from the
    # guess in 3 iterations
    vib = vibration.analyse(dyncheck.load_case("double_pendulum", **overrides))
    assert vib.equilibrium.q == pytest.approx([0.0, 0.0], abs=1e-12) and vib.equilibrium.iterations <= 4
    assert vib.modes["reference"].verdict == "marginally stable"
    assert all(r.status == Status.PASS for r in vib.rows)


def test_a_boundary_formula_that_is_no_number_at_the_parameters_is_no_bad_input():
    """The top's existence boundary takes the square root of (Ixx - Izz) m g h: with its centre of mass below the
    tip (h < 0) it is no number, which says there is no boundary, not that the case file is bad (`--set h=-0.03`
    exited 2 blaming the file); a formula naming something that is not a parameter still is bad input."""
    case = dyncheck.load_case("spinning_top", h=-0.03)  # loading validates
    case.spec["vibration"]["boundary"][0]["expected"] = "2*sqrt(m*g*hh)"
    with pytest.raises(ValueError, match=r"vibration\.boundary\[0\]\.expected = '2\*sqrt\(m\*g\*hh\)' names hh, "
                                         "not a parameter"):
        linear.validate(case)


def test_a_degenerate_equilibrium_is_found_and_its_linearisations_compared_within_their_rounding():
    """The rotating pendulum under g = 0 balances at psi = -pi/2, where psi'' and its slope both vanish while the
    centrifugal terms that cancel there do not.  Newton stopped there with |psi''| 8e-24 but did not call it
    converged (a tolerance relative to the zero Jacobian there), and the row failed the derivation for lacking the
    equilibrium MuJoCo has: its tolerance is relative to the largest Jacobian met on the way now."""
    case = dyncheck.load_case("rotating_pendulum", g=0.0)
    table, scene = linear.settings(case), linear.linearised(case)
    eq = linear.equilibrium(scene.model("reference"), 0.0, table["q"], table["v"], table["solve"], case.coords,
                               scene.model("pinocchio").mass_matrix)
    assert abs(eq.q[0] + math.pi / 2) < 1e-4  # psi'' ~ d^3 there: within rounding of the terms at d = 6e-5 rad
    # A's entries there are 1e-8 of the terms they sum: Pinocchio's A, 2e-14 off the derivation's, once failed
    # with an error estimate relative to its RNEA derivatives' own entries (1e-23); its measured noise allows it
    ours = linear.derivation_linear(scene.model("reference"), "reference", eq)
    theirs = linear.engine_linear(scene.model("pinocchio"), "pinocchio", eq)
    n = ours.n
    assert np.max(np.abs(ours.state_matrix[n:] - theirs.state_matrix[n:])) <= linear.SAFETY * (ours.error
                                                                                                  + theirs.error)
