import pytest

import dyncheck
from dyncheck.checks import run_case


@pytest.fixture(scope="session")
def results():
    """Every check of every case with default parameters, run once for the whole session."""
    return {name: run_case(dyncheck.load_case(name)) for name in dyncheck.case_names()}
