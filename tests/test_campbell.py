"""The Campbell diagram and the stability boundaries (dyncheck/studies/campbell.py) follow the parameters: the sweep and the
brackets are multiples of their scale, the boundary is found inside its bracket, two modes' closest approach is
found and judged, and where there is nothing to show the page says so in a sentence.  At `--set k=500` the spring
pendulum's sweep once ran 0-100 rad/s past sqrt(k/m) = 50 rad/s (an l axis to 1e7 m, no boundary line), its bracket
[90, 110] held no boundary, and its text named the veering at the book's 65 rad/s.

Fast by default (one bisection, a few seconds); `pytest -m full` runs whole sweeps and draws them."""

import math
import subprocess
import sys
from pathlib import Path

import pytest

import dyncheck
from dyncheck.checks import linear
from dyncheck.pages import vibration_page
from dyncheck.studies import campbell


def spring(**overrides):
    case = dyncheck.load_case("spring_pendulum", **overrides)
    return case, linear.settings(case), linear.linearised(case)


@pytest.mark.parametrize("k", [500.0, 2000.0, 5000.0])
def test_the_spring_pendulums_sweep_ends_just_below_sqrt_k_over_m(k):
    case, table, scene = spring(k=k)
    omega = math.sqrt(k / case.params["m"])
    analysed = campbell.held_value(scene, table, "beta_rate")
    values, nothing = campbell.swept_values(scene, table["campbell"], analysed)
    assert nothing is None and values[0] == 0.0
    assert 0.99 * omega < max(values) < omega  # up to the runaway, not past it
    assert values == sorted(values) and analysed in values  # the page's own equilibrium among them
    brackets = {b["parameter"]: [scene.value(b["scale"]) * x for x in b["bracket"]] for b in table["boundary"]}
    assert brackets["beta_rate"][0] < omega < brackets["beta_rate"][1]
    k_crit = case.params["m"] * scene.params["beta_rate"] ** 2
    assert brackets["k"][0] < k_crit < brackets["k"][1]


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_at_k_500_the_boundary_is_found_inside_its_bracket_and_confirmed_by_runs():
    case, table, scene = spring(k=500.0)
    (boundary, stable_above), sentences = campbell.boundary_search(case, scene, table, table["boundary"][0], None)
    assert boundary == pytest.approx(50.0, rel=1e-5) and not stable_above
    # 1.9e-6 above sqrt(k/m): a hair beyond it the equations still hold an equilibrium, 67 km out with the rod tilted
    # just past the horizontal (sin psi < sqrt(k/m) / Omega keeps the spring's stiffness ahead of the pull), which
    # Newton-Raphson finds from the last one
    assert sentences[0].startswith(f"Boundary from the eigenvalues: beta_rate = {boundary:.7g} rad/s")
    assert "stable below it" in sentences[0] and "k = 500 N/m" in sentences[0]
    assert [("leaves" in s, "as the eigenvalues say" in s) for s in sentences[1:]] == [(True, True), (False, True)]


def test_a_bracket_without_the_boundary_says_where_it_looked_and_what_the_formula_gives():
    case, table, scene = spring(k=500.0)
    below = {**table["boundary"][0], "bracket": [0.5, 0.8]}  # 25 to 40 rad/s: stable at both ends
    found, sentences = campbell.boundary_search(case, scene, table, below, None)
    assert found is None
    assert sentences == ["No stability boundary in beta_rate between 25 and 40 rad/s (the bracket): the equilibrium is "
                         "stable at both ends; the formula `sqrt(k/m)` gives 50 rad/s, outside the bracket."]


def test_a_scale_with_no_value_at_the_parameters_is_a_sentence_not_a_sweep():
    case, table, scene = spring()
    for scale, why in (("sqrt(g - 2*k)", "has no value here"), ("g - k", "is -1990.18 here, not positive")):
        values, nothing = campbell.swept_values(scene, {**table["campbell"], "scale": scale}, 0.0)
        assert values == [] and nothing == (f"Nothing to sweep at these parameters: the values are multiples of "
                                            f"`{scale}`, which {why}.")
        found, sentences = campbell.boundary_search(case, scene, table, {**table["boundary"][0], "scale": scale}, None)
        assert found is None and sentences[0].startswith("No search for a stability boundary in beta_rate")


def test_an_empty_sweep_draws_no_figure_and_says_so():
    case = dyncheck.load_case("spring_pendulum")
    empty = campbell.Sweep("beta_rate", "rad/s", "Why.", campbell.pd.DataFrame(), campbell.pd.DataFrame(), {},
                           None, None, None, (), ("Nothing to sweep at these parameters: ...",), 0.0)
    lines = vibration_page.sweep_lines(empty, case, "figures/x.png")
    assert not any("![" in line for line in lines)
    assert "No diagram at these parameters" in " ".join(lines) and "- Nothing to sweep at these parameters: ..." in lines


@pytest.mark.full  # whole sweeps: about 10 s each
@pytest.mark.parametrize("k, veering", [(500.0, (30.0, 35.0)), (2000.0, (62.0, 67.0)), (5000.0, (95.0, 110.0))])
def test_the_campbell_diagram_follows_k(k, veering, tmp_path):
    case = dyncheck.load_case("spring_pendulum", k=k)
    omega = math.sqrt(k / case.params["m"])
    sweep = campbell.sweep(case)
    assert sweep.data["value"].max() < omega and not any("No equilibrium" in f for f in sweep.findings)
    assert sweep.boundary == pytest.approx(omega, rel=1e-5) and sweep.stable_above is False
    assert sweep.branch["l"].abs().max() < 100 * (case.params["r"] + case.params["l0"])  # no far-out equilibria
    (approach,) = sweep.approaches
    assert approach.modes == (1, 2) and veering[0] < approach.value < veering[1] and approach.veers
    assert any(f.startswith(f"Modes 1 and 2 come closest at beta_rate = {approach.value:.4g} rad/s") and
               "veer apart" in f for f in sweep.findings)
    assert sweep.analysed == pytest.approx(case.params["alpha_rate"] + case.params["beta_rate"])
    vibration_page.figure_campbell(sweep, case, tmp_path / "campbell.png")  # raises where a text runs off the edge
    caption = vibration_page.campbell_caption(sweep)
    assert f"beta_rate = {omega:.5g} rad/s: the equilibrium is stable below it" in caption


@pytest.mark.full
def test_the_tops_sweep_starts_above_its_least_spin_at_other_parameters():
    case = dyncheck.load_case("spinning_top", m=0.3)
    sweep = campbell.sweep(case)
    least = sweep.boundary
    p = case.params
    assert least == pytest.approx(2 * math.sqrt((p["Ixx"] - p["Izz"]) * math.cos(math.pi / 6) * p["m"] * p["g"] * p["h"])
                                  / p["Izz"], rel=1e-5)
    assert sweep.stable_above and least < sweep.data["value"].min() < 1.1 * least
    assert not any("No equilibrium" in f for f in sweep.findings)
    # with its centre of mass below the tip every spin has a steady precession: the sweep shows it, no boundary
    below = campbell.sweep(dyncheck.load_case("spinning_top", h=-0.02))
    assert below.boundary is None and len(below.data)
    assert any(f.startswith("No stability boundary in spin_rate") and "has no value at these parameters" in f
               for f in below.findings)


def test_a_scale_is_checked_for_its_names_on_load_and_evaluated_where_the_study_runs():
    """Like a boundary's formula, a scale may have no value at some parameters (the study then says so); one that
    names what is no parameter is refused, naming the field."""
    case = dyncheck.load_case("spring_pendulum")
    case.spec["vibration"]["campbell"]["scale"] = "sqrt(g - 2*k)"  # no value at the book's numbers
    linear.validate(case)
    case.spec["vibration"]["boundary"][1]["scale"] = "m*Omega**2"
    with pytest.raises(ValueError, match=r"vibration\.boundary\[1\]\.scale = 'm\*Omega\*\*2' names Omega, not a "
                                         "parameter"):
        linear.validate(case)


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_the_pages_load_a_saved_sweep_without_running_anything():
    """`dyncheck report --from` imports the pages alone: the Sweep's classes must be registered by them (a saved
    Campbell diagram was 'not registered with dyncheck.results.store' once it had a module of its own)."""
    code = ("import dyncheck.pages.report, dyncheck.results.store as store; "
            "assert {'Sweep', 'Approach'} <= set(store._registry), sorted(store._registry)")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=Path(__file__).resolve().parent.parent)


def test_saved_results_load_in_python_alone(results, tmp_path):
    """docs/results.md's `dyncheck.results.values.load_results(Path(DIR))`, in a process that imports nothing else: the
    classes a saved result holds (its runs, its vibration analysis) are registered by load_result itself."""
    from dyncheck.results.values import save_results
    save_results([results["double_pendulum"]], tmp_path)
    code = (f"from pathlib import Path; from dyncheck.results.values import load_results; "
            f"assert load_results(Path({str(tmp_path)!r}))[0].vibration is not None")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=Path(__file__).resolve().parent.parent)
