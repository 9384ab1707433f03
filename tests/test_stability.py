"""Stability studies (dyncheck/studies/stability/, and the cases' own studies.py): theory, the measured limits against it, blow-ups as data.

Fast by default (a few seconds each): each test runs one study on a reduced set of its numbers.
`pytest -m slow` runs every study of every case as the report does and draws the figures.
"""

import math
import re
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

import dyncheck
from dyncheck.checks.horizon import agreement_horizon, benettin
from dyncheck.common import style
from dyncheck.run import simulate
from dyncheck.run.simulate import Unstable
from dyncheck.studies import stability
from dyncheck.studies.stability import common, long_runs


def settings(case, study, **changes):
    out = stability.settings_of(case, study)
    out.update(changes)
    return out


# -- linear stability theory ------------------------------------------------------------------

def test_linear_limits_of_the_schemes():
    """On x'' = -omega^2 x: semi-implicit Euler stable to omega h = 2, RK4 to 2 sqrt(2) (imaginary
    axis), explicit Euler never; over a finite horizon the limits move up by the growth allowed."""
    omega = 100.0
    assert common.spectral_radius("semi-implicit Euler", 1.999) == 1.0
    assert common.spectral_radius("semi-implicit Euler", 2.001) > 1.0
    assert common.spectral_radius("RK4", 2 * math.sqrt(2) - 1e-6) < 1.0 < common.spectral_radius("RK4", 2.83)
    assert np.all(common.spectral_radius("explicit Euler", np.geomspace(1e-6, 3, 20)) > 1.0)
    # Long horizon: the sharp limits; explicit Euler h = 2 ln(G) / (omega^2 span) for small omega h.
    span, growth = 1e4 / omega, 10.0
    assert common.limit_step("semi-implicit Euler", omega, span, growth) * omega == pytest.approx(2.0, rel=1e-4)
    assert common.limit_step("mujoco:implicitfast", omega, span, growth) * omega == pytest.approx(2.0, rel=1e-4)
    assert common.limit_step("RK4", omega, span, growth) * omega == pytest.approx(2 * math.sqrt(2), rel=1e-3)
    h = common.limit_step("explicit Euler", omega, span, growth)
    assert h == pytest.approx(2 * math.log(growth) / (omega**2 * span), rel=1e-3)


def test_spring_softened_by_the_spin_and_k_crit():
    """The relative equilibrium's fast frequency is sqrt(k/m - Omega^2 sin^2 psi*) for a stiff spring, and
    no stable equilibrium exists below k_crit = m Omega^2."""
    case = dyncheck.load_case("spring_pendulum")
    p = case.params
    omega = p["alpha_rate"] + p["beta_rate"]
    psi, _, _, fast = stability.case_module(case).spring_linearisation(case, 1e5)
    assert fast == pytest.approx(math.sqrt(1e5 / p["m"] - omega**2 * math.sin(psi) ** 2), rel=1e-6)
    k_crit = p["m"] * omega**2
    assert stability.case_module(case).spring_linearisation(case, 0.99 * k_crit) is None
    assert stability.case_module(case).spring_linearisation(case, 1.05 * k_crit)[1] > 10 * p["l0"]  # out at l -> infinity


# -- 1. spring pendulum --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def stiff_spring():
    """The step study at k = 1e5 N/m (and one k below k_crit) for semi-implicit Euler, RK4 and MuJoCo's Euler."""
    case = dyncheck.load_case("spring_pendulum")
    s = settings(case, "stable_step", k_scale=1.0, k=[100.0, 1e5], methods=["semi-implicit Euler", "RK4", "mujoco:Euler"])
    start = time.perf_counter()
    result = stability.case_module(case).stable_step(case, s)
    return result, s, time.perf_counter() - start


@pytest.mark.full
def test_semi_implicit_euler_blows_up_at_2_over_omega_within_the_bisection(stiff_spring):
    result, s, wall = stiff_spring
    data = result.data
    for method in ("semi-implicit Euler", "mujoco:Euler", "RK4"):
        row = data[(data["k"] == 1e5) & (data["method"] == method)].iloc[0]
        assert row["status"] == "measured"
        limit = common.SHARP[method] / row["omega_fast"]
        assert row["h_limit"] == pytest.approx(limit)
        # The theory (with the horizon's hair) lies in the bracket [no blow-up, blow-up], which is as
        # narrow as the bisection's resolution (plus one step of the grid T / integer).
        grid = row["h_blowup"] ** 2 / s["horizon"]
        assert row["h_no_blowup"] <= row["h_theory"] * (1 + 1e-9) + grid
        assert row["h_blowup"] >= row["h_theory"] * (1 - 1e-9) - grid
        assert row["h_blowup"] / row["h_no_blowup"] <= 1 + s["resolution"] + 2 * grid / row["h_blowup"]
        assert row["h_blowup"] == pytest.approx(limit, rel=s["resolution"] + 0.02)
        # and the largest stable step (growth at most 10) agrees with the theory too
        assert row["ratio"] == pytest.approx(1.0, abs=s["resolution"] + 0.02)
    assert wall < 20


@pytest.mark.full  # its fixture runs the 6 s step study
def test_below_k_crit_the_exact_solution_runs_away_too(stiff_spring):
    result, _, _ = stiff_spring
    data = result.data
    soft = data[data["k"] == 100.0]
    assert set(soft["status"]) == {"physical runaway"}
    exact = soft[soft["method"] == "exact (DOP853)"].iloc[0]
    assert 0 < exact["t_fail"] < 1.0
    for _, row in soft[soft["method"] != "exact (DOP853)"].iterrows():
        assert row["t_fail"] == pytest.approx(exact["t_fail"], abs=0.05)  # together with the physics
    crit = result.series["crit"]
    assert crit["lo"] < crit["hi"] and abs(crit["hi"] / crit["theory"] - 1) < 0.02
    assert any("k_crit = 159.9 N/m" in f for f in result.findings)


@pytest.mark.parametrize("overrides", [{}, {"m": 0.5}, {"alpha_rate": 6.0}])
def test_the_stiffnesses_of_the_step_study_follow_k_crit(overrides):
    """The case file gives them in multiples of k_crit = m Omega^2 (its k_scale): under --set m=0.5 fixed ones of
    150, 170, 200 N/m "around k_crit" were all below its 400 N/m."""
    case = dyncheck.load_case("spring_pendulum", **overrides)
    p = case.params
    k_crit = p["m"] * (p["alpha_rate"] + p["beta_rate"]) ** 2
    s = stability.case_module(case).in_newtons_per_metre(stability.settings_of(case, "stable_step"))
    below, above = [k for k in s["k"] if k < k_crit], [k for k in s["k"] if k > k_crit]
    assert min(s["k"]) < 0.1 * k_crit and max(s["k"]) > 100 * k_crit and len(below) >= 3 and len(above) >= 3
    assert max(below) / k_crit == pytest.approx(0.94, rel=5e-3) and min(above) / k_crit == pytest.approx(1.06, rel=5e-3)
    assert all(float(f"{k:.3g}") == k for k in s["k"])  # 3000 N/m in the tables, not 2997.89
    assert s["k_fit"] > k_crit and s["k_stiff"] > s["k_fit"]


def test_a_blown_up_run_is_recorded_with_time_and_step():
    """Beyond the limit: the generic scheme stops at the physical bound, MuJoCo's run at its reset or at
    the bound; `attempt` turns both into data."""
    case = dyncheck.load_case("spring_pendulum", k=1e5)
    for method in ("semi-implicit Euler", "mujoco:RK4"):
        out, fail = simulate.attempt(lambda: common.run_fixed(case, "book", method, 0.01, 0.5,
                                                                  bound=100.0, index=1))
        assert out is None and fail["status"] == "unstable"
        assert 0 < fail["t"] <= 0.5 and fail["step"] > 0 and fail["why"]
        assert "unstable at t = " in simulate.describe(fail)
    with pytest.raises(Unstable):  # outside `attempt` it is the simulator's own exception
        common.run_fixed(case, "book", "RK4", 0.01, 0.5, bound=100.0, index=1)


# -- 2. double pendulum --------------------------------------------------------------------------

def test_agreement_horizon_is_finite_positive_and_cheap():
    case = dyncheck.load_case("double_pendulum")
    start = time.perf_counter()
    horizon, details = agreement_horizon(case)
    assert time.perf_counter() - start < 4.0  # < 2 s on an idle machine
    assert math.isfinite(horizon) and horizon > 0
    assert details["within"] == (horizon >= case.initial[2])
    assert details["amplification"] > 1 and details["eps0"] * details["amplification"] < details["tol"]
    assert "agreement horizon" in details["sentence"]
    # A case without [stability.lyapunov] sets no limit.
    horizon, details = agreement_horizon(dyncheck.load_case("piston"))
    assert horizon == math.inf and details["within"]


@pytest.mark.full
def test_lyapunov_exponent_tells_chaos_from_regular_motion():
    case = dyncheck.load_case("double_pendulum")
    chaotic = np.array([math.pi / 2, math.pi / 2])
    t, logs = benettin(case, chaotic, np.zeros(2), 8.0, 0.1, 1e-8, 1e-9)
    assert 5.0 < logs[-1] / t[-1] < 11.0  # ~7.6 1/s over 30 s
    q0, v0, _ = case.initial
    t, logs = benettin(case, q0, v0, 8.0, 0.1, 1e-8, 1e-9)
    assert logs[-1] / t[-1] < 1.5  # regular: ln(stretch) stays ~6


def test_energy_drift_records_a_blow_up_as_data_and_shows_no_nan():
    case = dyncheck.load_case("double_pendulum")
    s = settings(case, "energy_drift", methods=["explicit Euler", "semi-implicit Euler", "mujoco:Euler"],
                 dt=0.02, horizon=2.0, output_step=0.02)
    result = long_runs.energy_drift(case, s)
    data = result.data.set_index("method")
    assert data.loc["explicit Euler", "status"] == "unstable"  # NaN at this step
    assert 0 < data.loc["explicit Euler", "t_fail"] <= 2.0 and data.loc["explicit Euler", "step_fail"] > 0
    assert data.loc["semi-implicit Euler", "status"] == "ran"
    text = result.table.to_string().lower()
    assert "nan" not in text and "unstable at t = " in text
    assert any("explicit Euler: unstable at t = " in f for f in result.findings)
    # MuJoCo's Euler is the textbook semi-implicit Euler
    assert any("mujoco:Euler = semi-implicit Euler" in f for f in result.findings)


@pytest.mark.parametrize("overrides, horizon, over_the_top", [({}, 60.0, True), ({"m2": 0.5, "l2": 0.3}, 60.0, False)])
def test_the_energy_drifts_words_follow_its_numbers(overrides, horizon, over_the_top):
    """The swing's energy is one computed number in the findings and the caption (the case file's text said 0.10 J
    where the caption said 0.11 J at m2 = 0.5 kg); "can go over the top" only where the energy gained exceeds what
    the masses over the top hold (at m2 = 0.5 kg, l2 = 0.3 m explicit Euler gains 13 swing energies of the 34 it
    takes, and was said to exceed them)."""
    case = dyncheck.load_case("double_pendulum", **overrides)
    result = long_runs.energy_drift(case, settings(case, "energy_drift", methods=["explicit Euler"], horizon=horizon))
    swing = long_runs.swing_words(result.series["swing"])
    caption = long_runs.figure_energy_drift(result, Path(tempfile.mkdtemp()) / "drift.png", "double pendulum")
    assert swing in result.findings[0] and swing in caption and not re.search(r"\d J\b", result.why)
    row = result.data.set_index("method").loc["explicit Euler"]
    top = next(f for f in result.findings if f.startswith("explicit Euler:"))
    assert row["drift_T"] > 1.0 and ("so it can go over the top" in top) == over_the_top
    assert ("so it cannot yet go over the top" in top) != over_the_top


# -- 3. spinning top -------------------------------------------------------------------------------

def test_euler_angle_error_grows_toward_zero_nutation_while_engines_stay_exact():
    case = dyncheck.load_case("spinning_top")
    s = settings(case, "euler_singularity", nutation=[1e-1, 1e-3, 1e-5, 1e-7], miss=[])
    result = stability.case_module(case).euler_singularity(case, s)
    data = result.data
    ref = data[data["source"] == "reference (Euler angles)"].set_index("nutation")["error"]
    assert ref[1e-1] < 1e-14 and ref[1e-5] > 1e-10 and ref[1e-7] > 1e-5
    assert np.all(np.diff(ref.to_numpy()) > 0)  # grows as the nutation falls
    engines = data[data["source"].str.contains("quaternion")]["error"]
    assert engines.max() < 1e-14


@pytest.mark.full
def test_sleeping_threshold_agrees_with_the_criterion_within_its_resolution():
    case = dyncheck.load_case("spinning_top")
    result = stability.case_module(case).sleeping_top(case, settings(case, "sleeping_top"))
    s = result.series
    p = case.params
    criterion = 2 * math.sqrt(p["Ixx"] * p["m"] * p["g"] * p["h"]) / p["Izz"]
    assert s["criterion"] == pytest.approx(criterion)
    resolution, bound = result.settings["resolution"], result.settings["bound"]
    assert s["hi"] - s["lo"] <= resolution * criterion * 1.001
    # The first integrals' threshold for this bound and horizon lies in MuJoCo's bracket ...
    assert s["lo"] <= s["finite"] <= s["hi"]
    # ... and the bracket within the bisection's resolution of the criterion, once the bound's own shift
    # (the falling top only wobbles out to 2 sqrt(1 - s^2 / s_c^2): s_c sqrt(1 - bound^2 / 4)) is allowed.
    assert s["lo"] <= criterion * (1 + resolution)
    assert s["hi"] >= criterion * math.sqrt(1 - bound**2 / 4) * (1 - resolution)


# -- dispatch and validation ------------------------------------------------------------------------

def test_studies_follow_the_case_file():
    assert stability.studies(dyncheck.load_case("piston")) == []
    case = dyncheck.load_case("spinning_top")
    case.spec["stability"] = {"why": "x", "sleeping": {"why": "typo"}}
    with pytest.raises(ValueError, match="stability.sleeping is not a known study"):
        stability.studies(case)
    case.spec["stability"] = {"module": "studies.py", "sleeping_top": {"why": "no numbers"}}
    with pytest.raises(ValueError, match="stability.sleeping_top lacks"):
        stability.validate(case)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["spring_pendulum", "double_pendulum", "spinning_top"])
def test_every_study_runs_in_budget_and_draws(name, tmp_path):
    case = dyncheck.load_case(name)
    start = time.perf_counter()
    results = stability.studies(case)
    assert time.perf_counter() - start < 90
    assert results
    for result in results:
        assert result.findings and not result.data.empty
        assert "nan" not in result.table.to_string().lower()
        path = tmp_path / f"{name}_{result.study}.png"
        stability.figure(case, result, path)
        assert path.stat().st_size > 10_000


def test_a_study_with_nothing_to_measure_says_why_and_draws_nothing(tmp_path):
    """A top whose centre of mass is below its tip (--set h=-0.03) needs no spin to stand upright: its
    least-spin study raised a math domain error out of `report`; it is now not applicable, says why on the
    page, and draws no figure.  Its passages through the upright need the upright spin-stabilised."""
    case = dyncheck.load_case("spinning_top", h=-0.03)
    top = stability.case_module(case)
    with pytest.raises(common.NotApplicable, match="no least spin to find"):
        top.sleeping_top(case, settings(case, "sleeping_top"))
    with pytest.raises(common.NotApplicable, match="the top falls rather than swing through the vertical"):
        top._passages(dyncheck.load_case("spinning_top", g=100.0), settings(case, "euler_singularity"), None)
    result = common.not_applicable(case, "sleeping_top", settings(case, "sleeping_top"), "because")
    assert result.findings == ("Not applicable at these parameters: because",) and result.table.empty
    assert stability.figure(case, result, tmp_path / "top.png") is None and not any(tmp_path.iterdir())


def test_the_euler_singularity_study_without_passages_draws_its_one_panel(tmp_path):
    """--set Ixx=0.0105 (within its sampled range) lifts the upright top's least spin above the passages' spin:
    they are not applicable, and the study's figure, drawn with its one other panel, had its title run off the
    figure's edge, which took the whole report down (a helper's sweep of `report --set`)."""
    case = dyncheck.load_case("spinning_top", Ixx=0.0105063)
    result = stability.case_module(case).euler_singularity(case, settings(case, "euler_singularity"))
    assert any(f.startswith("No passage through the upright: at the passages' spin 43.98 rad/s the upright is "
                            "unstable") for f in result.findings)
    assert stability.figure(case, result, tmp_path / "singularity.png") and (tmp_path / "singularity.png").is_file()


def test_the_euler_singularity_figure_keeps_its_axes_to_what_an_error_can_be(monkeypatch, tmp_path):
    """Its lower axis, an axis direction's error, ends a decade above pi rad (it ran to 1e9), and what the
    figure draws is in its legend: machine epsilon's line (its label was printed over the markers) and the
    grey nutation of the right axis."""
    case = dyncheck.load_case("spinning_top")
    top = stability.case_module(case)
    t = np.linspace(0.0, 0.5, 50)
    rows = pd.DataFrame([{"source": source, "nutation": n, "error": e * n ** -2}
                         for source, e in (("reference (Euler angles)", 1e-18), ("mujoco (quaternion)", 1e-30))
                         for n in (1e-1, 1e-4, 1e-8)])
    passes = [{"status": "ok", "closest": 1e-6, "t": t, "nutation": 1e-6 + t, "error_mj": np.full(50, 1e-14),
               "dop853": {"status": "ok", "error": np.full(50, 1e-11)}, "rk4": {"fail": {"t": 0.118}}}]
    drawn = {}
    monkeypatch.setattr(top, "save", lambda fig, path: drawn.update(fig=fig))
    top.figure_euler_singularity(SimpleNamespace(series={"rows": rows, "passes": passes}), tmp_path / "x.png", "1.10")
    errors, passage = drawn["fig"].axes[1], drawn["fig"].axes[2]
    assert np.pi < errors.get_ylim()[1] <= 10
    legend = [text.get_text() for text in drawn["fig"].legends[0].get_texts()]
    assert "machine epsilon, 2.2e-16" in legend and "MuJoCo (quaternion)" in legend
    assert any(label.startswith("nutation of the closest passage") for label in legend)
    assert not [text.get_text() for ax in drawn["fig"].axes for text in ax.texts]  # no text over the data
    style.pyplot().close(drawn["fig"])
