import shutil
from pathlib import Path

import pytest
from hypothesis import settings

import dyncheck
from dyncheck.cli import run_cases
from dyncheck.pages.report import write_reports

ROOT = Path(__file__).resolve().parent.parent
# No test here is about speed (docs/speed.md: speed is benchmarked), and a worker per core makes an example's time
# the machine's load: hypothesis's deadline (200 ms an example) off for all, as the slow property tests had it.
settings.register_profile("dyncheck", deadline=None)
settings.load_profile("dyncheck")
WHOLE_RUNS = {"results", "example_results", "rendered"}  # the session fixtures that run every case


@pytest.hookimpl(tryfirst=True)  # before xdist's, which reads the group into the test's id
def pytest_collection_modifyitems(items):
    """A test that takes a whole run of every case is `full`: the default run leaves it to `pytest -m full`.
    Under pytest-xdist (`-n`: pyproject.toml) such tests share one worker (`--dist loadgroup`), where the session
    fixtures run once; every other test goes to whichever worker is free."""
    for item in items:
        if WHOLE_RUNS & set(item.fixturenames):
            item.add_marker(pytest.mark.full)
            item.add_marker(pytest.mark.xdist_group("whole_runs"))


@pytest.fixture(scope="session")
def results():
    """Every check of every case with default parameters, run once for the whole session (in parallel, as
    `dyncheck run` runs them)."""
    return whole_run(ROOT / "cases")


@pytest.fixture(scope="session")
def example_results():
    """Every check of every case in examples/, run once for the whole session."""
    return whole_run(ROOT / "examples")


def whole_run(folder):
    cases = [dyncheck.load_case(name, folder) for name in dyncheck.case_names(folder)]
    results, interrupted = run_cases(cases)
    assert interrupted is None
    return {result.name: result for result in results}


@pytest.fixture(scope="session")
def rendered(results, example_results, tmp_path_factory):
    """Both report trees as `dyncheck report` lays them out (reports/ and reports/examples/, beside a copy of
    docs/ so that the pages' links resolve), written once from this session's runs: every page, figure and
    animation the code under test draws.  The studies (`dyncheck report` runs them, `dyncheck run` does not)
    are not among them; their figures pass dyncheck.common.style.save's checks whenever they are drawn."""
    root = tmp_path_factory.mktemp("rendered")
    shutil.copytree(ROOT / "docs", root / "docs")
    write_reports(list(results.values()), root / "reports")  # first: it replaces the folder the examples go into
    write_reports(list(example_results.values()), root / "reports" / "examples")
    return root


@pytest.fixture
def tutorial(tmp_path):
    """docs/own-case.md's two-file case (scene.xml and a plain equations.py, no case.toml) in
    tmp_path/cases/cart_pendulum, as the guide writes it."""
    from test_own_case_doc import steps
    for kind, path, text in steps():
        if kind == "file" and path.startswith("cart_pendulum/"):
            (tmp_path / "cases" / path).parent.mkdir(parents=True, exist_ok=True)
            (tmp_path / "cases" / path).write_text(text)
    return tmp_path / "cases" / "cart_pendulum"
