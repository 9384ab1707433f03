import pytest

import dyncheck
from dyncheck.checks import run_case


@pytest.fixture(scope="session")
def results():
    """Every check of both cases with default parameters, run once for the whole session (~25 s)."""
    return {name: run_case(dyncheck.load_case(name)) for name in ("spring_pendulum", "double_pendulum")}
