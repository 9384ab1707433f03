"""Progress on stderr: a bar on a terminal, plain lines in a log (a redirect, CI, nohup); stdout the same either way."""

import io
import re
import sys
from dataclasses import replace

import pandas as pd
import pytest

from dyncheck import cli
from dyncheck.common import progress
from dyncheck.pages import report
from dyncheck.studies import campbell, stability, work_precision
from test_ci_contract import toy


@pytest.fixture
def quick_report(monkeypatch):
    """`dyncheck report piston` with a toy result (with a run, so that it gets studies), studies that take two steps
    each and no pages: what is left is the command's progress and its output."""
    monkeypatch.setattr(cli, "run_case", lambda case, localise=True, quick=False: replace(toy("piston"), runs={"reference": None}))

    def steps(result):
        def study(case, progress=None):
            progress("first run")
            progress("second run")
            return result
        return study
    monkeypatch.setattr(work_precision, "sweep", steps(pd.DataFrame(columns=work_precision.COLUMNS)))
    monkeypatch.setattr(stability, "studies", steps([]))
    monkeypatch.setattr(campbell, "sweep", steps(None))
    def pages(results, out, animations=True, case_written=None):
        for result in results:
            case_written(result.name)
        return []
    monkeypatch.setattr(report, "write_reports", pages)
    monkeypatch.delenv("GITHUB_ACTIONS", raising=False)


class Terminal(io.StringIO):
    def isatty(self):
        return True


def report_piston(tmp_path, capsys, monkeypatch, terminal):
    """stdout and what reached stderr of `dyncheck report piston`, with stderr a terminal or not."""
    stderr = Terminal() if terminal else sys.stderr
    monkeypatch.setattr(sys, "stderr", stderr)
    assert cli.main(["report", "piston", "--out", str(tmp_path / "out")]) == 1  # the toy has failing rows
    captured = capsys.readouterr()
    return captured.out, stderr.getvalue() if terminal else captured.err


def test_a_redirected_report_says_each_case_and_stage_on_stderr(quick_report, tmp_path, capsys, monkeypatch):
    out, err = report_piston(tmp_path, capsys, monkeypatch, terminal=False)
    pages = f"pages to {tmp_path / 'out'}/"
    assert re.sub(r"\d+\.\d s\)", "T)", err).splitlines() == [
        "dyncheck: checks ...",
        "dyncheck: checks: piston done, FAIL (T)",
        "dyncheck: checks done (1/1 cases, T)",
        "dyncheck: studies ...",
        "dyncheck: studies: piston done (T)",
        "dyncheck: studies done (1/1 cases, T)",
        f"dyncheck: {pages} ...",
        f"dyncheck: {pages}: piston written (T)",
        f"dyncheck: {pages} done (1/1 cases, T)"]
    assert "dyncheck: checks" not in out and "studies and pages: wrote 0 files" in out


def test_on_a_terminal_the_same_report_draws_bars_and_prints_no_lines(quick_report, tmp_path, capsys, monkeypatch):
    redirected, _ = report_piston(tmp_path, capsys, monkeypatch, terminal=False)
    out, err = report_piston(tmp_path, capsys, monkeypatch, terminal=True)
    assert "\rchecks: " in err and "\rstudies: " in err  # the bars
    assert not [line for line in re.split(r"[\r\n]", err) if line.startswith("dyncheck: ")]
    seconds = re.compile(r"\d+\.\d s|\(\d+ s\)")
    assert seconds.sub("", out) == seconds.sub("", redirected)  # stdout's rows and summary as they were


def test_steps_without_a_milestone_get_a_line_once_quiet_has_passed(monkeypatch, capsys):
    with progress.Progress("sweep", total=3) as bar:
        bar.step("DOP853 rtol=1e-06")
    assert len(capsys.readouterr().err.splitlines()) == 2  # its start and end: a minute has not passed
    monkeypatch.setattr(progress, "QUIET", 0.0)
    with progress.Progress("sweep", total=3) as bar:
        bar.step("DOP853 rtol=1e-06")
    assert re.fullmatch(r"dyncheck: sweep: 1/3 runs, DOP853 rtol=1e-06 \(\d+\.\d s\)",
                        capsys.readouterr().err.splitlines()[1])


def test_a_stage_left_by_an_exception_has_no_closing_line(capsys):
    with pytest.raises(KeyboardInterrupt):
        with progress.Progress("checks", total=2, unit="case") as bar:
            bar.step()
            raise KeyboardInterrupt
    assert capsys.readouterr().err == "dyncheck: checks ...\n"
