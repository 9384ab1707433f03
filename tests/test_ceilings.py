"""Every tolerance has a ceiling: a comparison too loose to prove anything is never a pass."""

import shutil

import pytest

from dyncheck.case import folder as case_module
from dyncheck.checks.runs import run_sources, trajectory
from dyncheck.common import ceilings
from dyncheck.results.values import row


@pytest.mark.parametrize("error", [0.0, 0.5, 2.0])
def test_a_row_whose_tolerance_is_above_its_ceiling_is_inconclusive_whatever_its_error(error):
    r = row("trajectory", "psi", ("mujoco", "tight reference"), error, 21.0, "MuJoCo RK4", ceiling=ceilings.RUN)
    assert r.status == "inconclusive"
    assert "above the ceiling 1e-03" in r.detail and r.detail.endswith("MuJoCo RK4")


def test_a_row_at_its_ceiling_is_judged():
    assert row("energy", "drift", ("mujoco",), 2e-3, 1e-3, ceiling=1e-3).status == "fail"
    assert row("energy", "drift", ("mujoco",), 5e-4, 1e-3, ceiling=1e-3).status == "pass"


@pytest.mark.full
def test_a_mujoco_step_too_coarse_to_prove_anything_is_not_a_pass(tmp_path):
    """The issue's six-second reproduction: at 0.1 s steps MuJoCo is tens of per cent off the motion, and
    its own error estimate is as large: the comparison proves nothing, so it must not pass."""
    folder = tmp_path / "rotating_pendulum"
    shutil.copytree(case_module.CASES_DIR / "rotating_pendulum", folder)
    text = (folder / "case.toml").read_text()
    step = next(line for line in text.splitlines() if line.startswith("mujoco_step = "))  # it follows omega
    for old, new in (("output_step = 1e-3", "output_step = 0.1"), (step, "mujoco_step = 0.1")):
        assert old in text
        text = text.replace(old, new, 1)
    (folder / "case.toml").write_text(text)
    case = case_module.Case(folder)
    rows = [r for r in trajectory(case, run_sources(case)) if r.comparison == "mujoco vs tight reference"]
    assert rows and max(r.error for r in rows) > 0.1  # the run is far off, as the issue measured
    assert not any(r.status == "pass" for r in rows), rows
    assert {r.status for r in rows} <= {"inconclusive", "fail"}


def test_the_book_s_listing_runs_are_judged_at_a_figure_s_resolution(results):
    """'program vs tight reference' once passed with tolerances of 2 to 42 (relative): its rows are now
    judged at LISTING, and the listings that stray are registered findings."""
    rows = [(name, r) for name, res in results.items() for r in res.rows if r.comparison == "program vs tight reference"]
    assert rows and all(r.tolerance == ceilings.LISTING for _, r in rows)
    strayed = {name for name, r in rows if r.error > ceilings.LISTING}
    assert strayed == {"spring_pendulum", "double_pendulum", "spinning_top"}
    assert all(r.status == "finding" for _, r in rows if r.error > ceilings.LISTING)


def test_no_row_of_the_book_s_cases_passes_above_its_ceiling(results):
    rows = [r for res in results.values() for r in res.rows if r.tolerance is not None]
    assert rows and all(r.tolerance <= r.ceiling for r in rows if r.status == "pass")
    assert not [r for r in rows if r.status == "inconclusive"]
