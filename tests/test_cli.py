"""The command line: exit codes, the table, JSON and reports."""

import json
from dataclasses import replace

import pandas as pd
import pytest

import dyncheck
from dyncheck import cli
from dyncheck.results.values import RESULTS_VERSION, Status
from dyncheck.studies import stability, work_precision
from dyncheck.studies.stability import long_runs


@pytest.fixture
def canned(monkeypatch, results):
    """`run_case` answering from the session's results, and no studies (minutes; their page is
    tested below), so CLI tests cost no simulation."""
    monkeypatch.setattr(cli, "run_case", lambda case, localise=True, quick=False: results[case.name])
    monkeypatch.setattr(cli, "study_case", lambda case: {
        "work_precision": pd.DataFrame(columns=work_precision.COLUMNS), "stability": []})


def test_list_names_both_cases(capsys):
    assert cli.main(["list"]) == 0
    out = capsys.readouterr().out
    assert "spring_pendulum" in out and "double_pendulum" in out and "1.8.3" in out


def test_list_shows_each_parameter_with_its_unit_bounds_and_sampled_range(capsys):
    assert cli.main(["list", "spring_pendulum"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "== spring_pendulum: 1.8.3 " in lines[1] and not any("== piston" in line for line in lines)
    header = next(line for line in lines if line.startswith("parameter"))
    assert header.split() == ["parameter", "value", "unit", "allowed", "sampled", "about"]
    k = next(line for line in lines if line.startswith("k "))
    assert k.split()[:5] == ["k", "2000", "N/m", ">", "0"]  # the value and what it must satisfy: k > 0
    assert all(len(line) <= 100 for line in lines)


def test_list_shows_the_constraints_that_couple_the_parameters(capsys):
    """`--set m=0.73` alone, within m's sampled range, breaks the top's triangle inequality: list says so ahead."""
    assert cli.main(["list", "spinning_top"]) == 0
    lines = capsys.readouterr().out.splitlines()
    constraint = next(line for line in lines if line.startswith("2*(Ixx - m*h**2) - Izz + 1e-5 >= 0"))
    assert constraint.split(">= 0")[1].split()[0] == "6.32e-06" and all(len(line) <= 100 for line in lines)


def test_list_shows_the_sampled_interval_apart_from_the_allowed_one(capsys):
    assert cli.main(["list", "piston"]) == 0
    m = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("m "))
    assert m.split()[:7] == ["m", "2", "kg", ">", "0", "0.1", "to"]  # allowed m > 0, drawn from 0.1 to 5 kg


def test_run_exits_0_and_writes_the_json_of_the_design(canned, tmp_path, capsys):
    path = tmp_path / "out.json"
    assert cli.main(["run", "spring_pendulum", "double_pendulum", "--json", str(path)]) == 0
    assert "finding" in capsys.readouterr().out
    data = json.loads(path.read_text())
    spring = next(c for c in data["cases"] if c["case"] == "spring_pendulum")
    assert data["version"] == RESULTS_VERSION
    assert set(spring) == {"case", "section", "status", "counts", "params", "overrides", "checks", "findings",
                           "localisations"}
    assert set(spring["checks"][0]) == {"check", "quantity", "sources", "error", "tolerance", "ceiling", "status", "finding",
                                       "detail", "reason"}
    finding = next(f for f in spring["findings"] if f["id"] == "1.8.3-R")
    assert {"id", "title", "quantity", "sources", "error", "explanation"} <= set(finding)
    assert finding["error"] > 0.1
    assert finding["localised"].startswith("R: `L * psi_rate * Omega * cos(psi)` x 2")


def test_run_exits_1_when_a_check_fails(monkeypatch, results):
    def failing(case, localise=True, quick=False):
        res = results[case.name]
        return replace(res, rows=(replace(res.rows[0], status=Status.FAIL),) + res.rows[1:])
    monkeypatch.setattr(cli, "run_case", failing)
    assert cli.main(["run", "double_pendulum"]) == 1


@pytest.mark.parametrize("argv, message", [
    (["run", "pendulum"], "unknown case 'pendulum'"),
    (["run", "double_pendulum", "--set", "k=3"], "no selected case has a parameter 'k'"),
    (["run", "spring_pendulum", "--set", "k"], "expected NAME=VALUE"),
    (["run", "spring_pendulum", "--set", "k=soft"], "'soft' is not a number"),
    (["report", "spring_pendulum", "--set", "m=inf"], "override m = 'inf' is not a number"),
    (["report", "spring_pendulum", "--set", "m=1e400"], "override m = inf is not finite"),
])
def test_bad_input_exits_2_with_a_message(argv, message, capsys):
    assert cli.main(argv) == 2
    assert message in capsys.readouterr().err


def test_overrides_reach_the_run(monkeypatch, results, tmp_path):
    def run_case(case, localise=True, quick=False):  # in a worker process: a case without the override fails the run there
        assert case.params["g"] == 3.5 and case.overrides == {"g": 3.5}, case.name
        return results[case.name]
    monkeypatch.setattr(cli, "run_case", run_case)
    path = tmp_path / "out.json"
    assert cli.main(["run", "--set", "g=3.5", "--json", str(path)]) == 0
    assert [c["case"] for c in json.loads(path.read_text())["cases"]] == dyncheck.case_names()


def test_report_writes_pages_figures_and_index(canned, tmp_path):
    assert cli.main(["report", "--out", str(tmp_path)]) == 0
    index = (tmp_path / "index.md").read_text()
    assert "[spring_pendulum](spring_pendulum.md)" in index and "PASS" in index
    page = (tmp_path / "spring_pendulum.md").read_text()
    for link in [line.split("(")[1].rstrip(")") for line in page.splitlines() if line.startswith("![")]:
        assert (tmp_path / link).stat().st_size > 10_000, link
    assert "1.8.3-R" in page and not list(tmp_path.glob(".tmp-*"))
    errata = (tmp_path / "errata.md").read_text()
    for finding in ("1.7-eq1.24", "1.8.3-R", "1.8.3-listing-ldd", "1.8.3-listing-R", "1.9-figure", "1.10-R"):
        assert f"## {finding}" in errata, finding
    for link in [line.split("(")[1].rstrip(")") for line in errata.splitlines() if line.startswith("![")]:
        assert (tmp_path / link).stat().st_size > 10_000, link


def test_a_scene_that_disagrees_with_its_case_exits_2(monkeypatch, tmp_path, capsys):
    import shutil

    from dyncheck.case import folder as case_module
    shutil.copytree(case_module.CASES_DIR, tmp_path / "cases")
    scene = tmp_path / "cases" / "double_pendulum" / "scene.xml"
    scene.write_text(scene.read_text().replace('mass="0.46"', 'mass="0.5"'))
    assert cli.main(["run", "double_pendulum", "--cases", str(tmp_path / "cases")]) == 2
    assert "scene.xml of case 'double_pendulum': body 'link2' mass is 0.5" in capsys.readouterr().err


@pytest.mark.full
def test_bench_prints_throughput_and_ratios(capsys):
    assert cli.main(["bench", "double_pendulum"]) == 0
    out = capsys.readouterr().out
    assert "mj_step(nstep), RK4" in out and "pin.aba loop" in out and "ratio to bare" in out


def test_a_failed_report_leaves_the_previous_one_intact(canned, monkeypatch, tmp_path):
    from dyncheck.pages import case_page
    assert cli.main(["report", "double_pendulum", "--out", str(tmp_path)]) == 0
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}

    def broken(*args, **_):
        args[-1].write_text("half a figure")
        raise RuntimeError("disk full")
    monkeypatch.setattr(case_page, "figure_energy", broken)
    with pytest.raises(RuntimeError, match="disk full"):
        cli.main(["report", "double_pendulum", "--out", str(tmp_path)])
    after = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    assert after == before  # nothing half-written, no temporary folder left behind


def test_the_page_shows_the_studies(monkeypatch, results, tmp_path):
    """Work-precision chart, CSV, cheapest table, convergence table and a stability study on the page
    (a small sweep and a short study: the real ones take minutes)."""
    def small_studies(case):
        case.spec["work_precision"].update(t_end=0.5, output_step=0.01, repeat=1, solution={"rtol": 1e-11, "max_step": 0.01},
                                           sweep={"reference": {"DOP853": [1e-5, 1e-8], "RK4": [1e-2]},
                                                  "mujoco": {"mujoco:RK4": [1e-2, 5e-3]}})
        drift = {**stability.settings_of(case, "energy_drift"), "methods": ["explicit Euler", "semi-implicit Euler"],
                 "dt": 0.02, "horizon": 2.0, "output_step": 0.02}
        return {"work_precision": work_precision.sweep(case), "stability": [long_runs.energy_drift(case, drift)]}
    monkeypatch.setattr(cli, "run_case", lambda case, localise=True, quick=False: results[case.name])
    monkeypatch.setattr(cli, "study_case", small_studies)
    assert cli.main(["report", "double_pendulum", "--out", str(tmp_path)]) == 0
    page = (tmp_path / "double_pendulum.md").read_text()
    for heading in ("## Speed against accuracy", "## Convergence", "## Stability: where methods fail"):
        assert heading in page
    assert "Which method is cheapest" in page and "observed order" in page and "unstable at t = " in page
    index = (tmp_path / "index.md").read_text()
    assert "The cheapest method" in index and "1e-04" in index  # the index's speed table
    rows = pd.read_csv(tmp_path / "data" / "double_pendulum_work_precision.csv", comment="#")
    assert set(rows["method"]) == {"DOP853", "RK4", "mujoco:RK4"} and (rows["error"] > 0).all()
    for link in [line.split("(")[1].rstrip(")") for line in page.splitlines() if line.startswith("![")]:
        assert (tmp_path / link).stat().st_size > 10_000, link


def test_no_cases_folder_exits_2_saying_where_it_looked(tmp_path, capsys):
    """A non-editable install copies the code but not cases/: say so, never run nothing and pass."""
    (tmp_path / "empty").mkdir()
    assert cli.main(["run", "--cases", str(tmp_path / "missing")]) == 2
    assert "no such folder" in capsys.readouterr().err
    assert cli.main(["run", "--cases", str(tmp_path / "empty")]) == 2 and cli.main(["list", "--cases", str(tmp_path / "empty")]) == 2
    assert "no cases in" in capsys.readouterr().err
