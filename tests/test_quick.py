"""`dyncheck run --quick`: the checks at states alone, the rows `run` has of them, the same verdict on them; a wrong
equation still named with its term; what it leaves out said in its table, its summary line and its JSON."""

import json
import subprocess
import sys

import pytest

import planting
from dyncheck import cli
from dyncheck.case.folder import Case
from dyncheck.checks.runs import QUICK_LEAVES_OUT, run_case

import chain
from test_ci_contract import validate


@pytest.mark.full  # a whole run, if a short one
def test_its_rows_are_runs_rows_at_the_states(tmp_path):
    """run_case(quick=True) gives the rows of run_case that are not of the runs along time, equal, in their order,
    and the same localisation of a wrong equation; no runs.  The full run's horizon is cut (Case.with_horizon),
    which no check at the states depends on; its count of states is the case file's (budget 0), not what a measured
    cost fits, which the two Cases would measure apart."""
    folder = chain.write(tmp_path / "chain2", 2, planted="np.array([0.0, 0.4 * np.sin(q[0])])")
    (folder / "case.toml").write_text("[sample]\nbudget = 0\n")
    case = Case(folder)
    quick, full = run_case(case, quick=True), run_case(case.with_horizon(0.5))
    assert {r.check for r in full.rows} & set(QUICK_LEAVES_OUT)  # it has rows to leave out
    assert quick.rows == tuple(r for r in full.rows if r.check not in QUICK_LEAVES_OUT)
    assert quick.localisations == full.localisations and quick.localisations
    assert quick.runs == {} and quick.drawings == {}


def mutant_of_the_tutorial(tutorial):
    """docs/own-case.md's case with a term dropped from its force side (tests/planting.py)."""
    source = (tutorial / "equations.py").read_text()
    mutant = next(m for m in planting.mutants(source, ("forces",), per_kind=1, seed=13) if m.kind == "drop")
    (tutorial / "equations.py").write_text(mutant.source)
    return mutant


def test_a_planted_error_fails_with_its_equation_named(tutorial, capsys):
    mutant = mutant_of_the_tutorial(tutorial)
    assert (mutant.function, mutant.term) == ("forces", "k * x")  # the spring's force left out of the x equation
    assert cli.main(["run", "--quick", "--cases", str(tutorial.parent), "cart_pendulum"]) == 1
    out = capsys.readouterr().out
    wrong = out[out.index("cart_pendulum: where the derivation is wrong:"):].splitlines()
    assert wrong[1].startswith("  the derivation's equation x: add - k x to its force side f"), wrong[:3]
    assert "dyncheck: FAIL (quick tier): 1 of 1 case;" in out


def test_a_right_derivation_passes_and_the_files_hold_its_rows(tutorial, tmp_path, capsys):
    json_file, junit = tmp_path / "run.json", tmp_path / "run.xml"
    assert cli.main(["run", "--quick", "--cases", str(tutorial.parent), "cart_pendulum", "--json", str(json_file),
                     "--junit", str(junit)]) == 0
    out = capsys.readouterr().out
    assert "cart_pendulum: quick tier, the checks at states alone: left out every run along time, the rows of " \
           f"{', '.join(QUICK_LEAVES_OUT)}" in out
    assert "dyncheck: PASS (quick tier): 1 case;" in out
    document = json.loads(json_file.read_text())
    validate(document)  # docs/results.schema.json
    assert document["quick"] == list(QUICK_LEAVES_OUT) and document["status"] == "pass"
    checks = {row["check"] for row in document["cases"][0]["checks"]}
    assert checks and not checks & set(QUICK_LEAVES_OUT)
    assert junit.read_text().count("<testcase ") == len(document["cases"][0]["checks"])


def test_without_quick_the_json_says_nothing_of_it():
    assert "quick" not in cli.to_json([], None)


def test_saving_results_for_pages_is_refused(tutorial, tmp_path, capsys):
    assert cli.main(["run", "--quick", "--cases", str(tutorial.parent), "--results", str(tmp_path / "saved")]) == 2
    assert "--results" in capsys.readouterr().err and not (tmp_path / "saved").exists()


def test_it_imports_none_of_what_only_runs_along_time_need(tutorial):
    """Its start-up is most of its time: it imports neither pandas nor scipy.integrate, scipy.optimize, scipy.stats
    nor pint (seconds between them), in its own process or the case's (-X importtime reports both)."""
    code = ("import sys\nfrom dyncheck.cli import main\n"
            f"sys.exit(main(['run', '--quick', '--cases', {str(tutorial.parent)!r}]))\n")
    done = subprocess.run([sys.executable, "-X", "importtime", "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout[-2000:]
    imported = {line.rpartition("|")[2].strip() for line in done.stderr.splitlines() if line.startswith("import time:")}
    assert "dyncheck.checks.runs" in imported and "mujoco" in imported  # the imports are reported
    heavy = {"pandas", "scipy.integrate", "scipy.optimize", "scipy.stats", "pint"}
    assert not heavy & imported, heavy & imported
