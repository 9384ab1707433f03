import shutil
from pathlib import Path

import pytest

import dyncheck
from dyncheck.checks import run_case
from dyncheck.report import write_reports

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="session")
def results():
    """Every check of every case with default parameters, run once for the whole session."""
    return {name: run_case(dyncheck.load_case(name)) for name in dyncheck.case_names()}


@pytest.fixture(scope="session")
def example_results():
    """Every check of every case in examples/, run once for the whole session."""
    examples = ROOT / "examples"
    return {name: run_case(dyncheck.load_case(name, examples)) for name in dyncheck.case_names(examples)}


@pytest.fixture(scope="session")
def rendered(results, example_results, tmp_path_factory):
    """Both report trees as `dyncheck report` lays them out (reports/ and reports/examples/, beside a copy of
    docs/ so that the pages' links resolve), written once from this session's runs: every page, figure and
    animation the code under test draws.  The studies (`dyncheck report` runs them, `dyncheck run` does not)
    are not among them; their figures pass dyncheck.style.save's checks whenever they are drawn."""
    root = tmp_path_factory.mktemp("rendered")
    shutil.copytree(ROOT / "docs", root / "docs")
    write_reports(list(results.values()), root / "reports")  # first: it replaces the folder the examples go into
    write_reports(list(example_results.values()), root / "reports" / "examples")
    return root
