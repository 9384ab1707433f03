"""The command line and the files it writes, under bad paths, Ctrl-C, failures and concurrent writers."""

import json
import math
from dataclasses import replace
import multiprocessing
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from dyncheck import cli
from dyncheck.case import folder as case_module
from dyncheck.case.folder import Case
from dyncheck.pages import case_page, report

PISTON_FILES = {"piston.md", "piston_timing.md", "piston_student.md", "index.md", "errata.md", "data/piston.json",
                *(f"figures/piston_{kind}.{suffix}" for kind in ("scene", "energy", "reactions", "pointwise")
                  for suffix in ("png", "pdf")),
                "figures/piston_animation.gif", "results/piston/value.json", "results/piston/arrays.npz"}


@pytest.fixture
def canned(monkeypatch, results):
    """`run_case` answering from the session's results, without studies (see tests/test_cli.py)."""
    monkeypatch.setattr(cli, "run_case", lambda case, localise=True, quick=False: replace(results[case.name], overrides=dict(case.overrides)))


@pytest.fixture
def quick_figures(monkeypatch):
    """Figures as a few bytes: these tests are about which files land where, not what they draw."""
    def quick(*args, **kwargs):
        path = args[-1]  # a PNG and its PDF twin, as dyncheck.common.style.save writes them
        path.write_bytes(b"figure")
        path.with_suffix(".pdf").write_bytes(b"figure")
    for name in ("figure_scene", "figure_energy", "figure_pointwise"):
        monkeypatch.setattr(case_page, name, lambda *args, **kwargs: quick(*args) or "A caption.")
    monkeypatch.setattr(case_page, "figure_series", lambda *args, **kwargs: quick(*args) or {})  # no departures


def result(results, name):
    """The session's results of case `name`, as the report takes them without studies."""
    return results[name]


def main_interrupted(argv):
    """cli.main, failing the test (not ending the session) if Ctrl-C escapes it."""
    try:
        return cli.main(argv)
    except KeyboardInterrupt:
        pytest.fail("Ctrl-C escaped dyncheck as a traceback")


def files(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


# -- outputs that cannot be written: exit 2 before any work --------------------------

@pytest.fixture
def no_run(monkeypatch):
    monkeypatch.setattr(cli, "run_case", lambda case, localise=True, quick=False: pytest.fail("ran a case before checking the output"))


@pytest.mark.parametrize("option, where, why", [
    ("--json", "{tmp}", "is not a regular file"),  # a folder
    ("--json", "/dev/null", "is not a regular file"),  # replacing it would replace the device
    ("--json", "{tmp}/a_file/x.json", "a_file is a file, not a folder"),
    ("--json", "/proc/x.json", "cannot write in /proc"),
    ("--json", "/sys/x.json", "cannot write in /sys: Permission denied"),  # read-only even for root
    ("--out", "{tmp}/a_file", "is not a folder"),
    ("--out", "{tmp}/a_file/out", "a_file is a file, not a folder"),
    ("--out", "/proc/x", "cannot write in /proc"),
    ("--out", "/sys/x", "cannot write in /sys: Permission denied"),
    ("--out", "{tmp}/src", "holds files but no report"),  # the report replaces the folder: not a source tree
])
def test_an_output_that_cannot_be_written_exits_2_before_any_work(option, where, why, no_run, tmp_path, capsys):
    (tmp_path / "a_file").write_text("")
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "main.py").write_text("")
    path = where.format(tmp=tmp_path)
    command = "run" if option == "--json" else "report"
    assert cli.main([command, "piston", option, path]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"dyncheck: error: {option} {path}: ") and why in err, err
    assert len(err.splitlines()) == 1


def test_run_json_replaces_the_previous_file_whole_or_not_at_all(canned, monkeypatch, tmp_path, capsys):
    path = tmp_path / "out.json"
    path.write_text('{"cases": []}\n')

    def full_disk(fd):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "fsync", full_disk)
    assert cli.main(["run", "piston", "--json", str(path)]) == 2
    assert f"dyncheck: error: --json {path}: cannot write it: No space left on device" in capsys.readouterr().err
    assert path.read_text() == '{"cases": []}\n' and os.listdir(tmp_path) == ["out.json"]


# -- repeated names and foreign digits -----------------------------------------------

def test_a_case_named_twice_runs_once(monkeypatch, results, capsys, tmp_path):
    ran = tmp_path / "ran"  # each case runs in a process of its own: it says so in a file

    def run_case(case, localise=True, quick=False):
        with open(ran, "a") as f:
            f.write(case.name + "\n")
        return results[case.name]
    monkeypatch.setattr(cli, "run_case", run_case)
    assert cli.main(["run", "piston", "piston"]) == 0
    assert ran.read_text() == "piston\n" and capsys.readouterr().out.count("== piston") == 1


@pytest.mark.parametrize("sets, message", [
    (["m=1", "m=2"], "--set m: given twice (m=1 and m=2)"),
    (["m=١٢"], "override m = '١٢' is not a number (a decimal in ASCII digits"),  # float() reads it as 12.0
    (["m=１"], "override m = '１' is not a number"),  # fullwidth 1
    (["m=2_0"], "override m = '2_0' is not a number"),  # float() reads it as 20.0
    (["m=1e1_0"], "override m = '1e1_0' is not a number"),
    (["m=infinity"], "override m = 'infinity' is not a number"),
])
def test_a_repeated_or_non_numeric_set_exits_2(sets, message, no_run, capsys):
    argv = ["run", "piston"] + [arg for s in sets for arg in ("--set", s)]
    assert cli.main(argv) == 2
    assert message in capsys.readouterr().err


# -- Ctrl-C ------------------------------------------------------------------------------

def test_ctrl_c_during_run_prints_what_finished_and_exits_130(monkeypatch, results, tmp_path, capsys):
    def interrupted_on_the_second(case, localise=True, quick=False):
        if case.name != "piston":
            raise KeyboardInterrupt
        return results[case.name]
    monkeypatch.setattr(cli, "run_case", interrupted_on_the_second)
    path = tmp_path / "out.json"
    assert main_interrupted(["run", "piston", "rotating_particle", "spinning_top", "--json", str(path)]) == 130
    out, err = capsys.readouterr()
    assert "piston: " in out and "rotating_particle: " not in out
    assert "interrupted during case rotating_particle; above are the 1 cases that finished" in err
    data = json.loads(path.read_text())
    assert [c["case"] for c in data["cases"]] == ["piston"]
    assert data["incomplete"] == "interrupted (Ctrl-C) during case rotating_particle"


@pytest.mark.parametrize("command", ["run", "list"])
def test_ctrl_c_while_a_derivation_is_imported_exits_130_in_one_line(tutorial, command):
    """Ctrl-C while the cases load (here: a derivation's import sends it), in a process of its own as at a terminal."""
    equations = tutorial / "equations.py"
    equations.write_text("import os, signal\nos.kill(os.getpid(), signal.SIGINT)\n" + equations.read_text())
    done = subprocess.run([sys.executable, "-m", "dyncheck.cli", command, "--cases", str(tutorial.parent)],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONPATH": str(Path(cli.__file__).resolve().parent.parent)})
    assert (done.returncode, done.stderr) == (130, "dyncheck: interrupted\n"), done.stderr


@pytest.mark.parametrize("delay", [0.2, 0.4])
def test_ctrl_c_while_the_command_starts_exits_130_in_one_line(delay):
    """Ctrl-C while the command imports its modules (numpy, SciPy, the engines: most of a second; 0.2 s lands in
    them on any machine), as at a terminal.  The console command is `dyncheck.__main__:entry`."""
    started = subprocess.Popen([sys.executable, "-m", "dyncheck", "run", "piston"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "PYTHONPATH": str(Path(cli.__file__).resolve().parent.parent)})
    time.sleep(delay)
    started.send_signal(signal.SIGINT)
    _, err = started.communicate(timeout=120)
    assert (started.returncode, err) == (130, "dyncheck: interrupted\n"), err


def test_ctrl_c_during_report_leaves_it_unchanged_and_exits_130(monkeypatch, tmp_path, capsys):
    def interrupted(case, localise=True, quick=False):
        raise KeyboardInterrupt
    monkeypatch.setattr(cli, "run_case", interrupted)
    assert main_interrupted(["report", "piston", "--out", str(tmp_path / "out")]) == 130
    assert "interrupted during case piston" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


# -- the report's sections and its data folder ----------------------------------------------

@pytest.mark.parametrize("section, position", [("1.7a", 0), ("new", -1)])
def test_a_section_of_any_form_is_sorted_and_reported(section, position, results, quick_figures, tmp_path):
    """The index sorts sections naturally ("1.9" before "1.10"), text after numbers."""
    folder = tmp_path / "piston"
    shutil.copytree(case_module.CASES_DIR / "piston", folder)
    toml = folder / "case.toml"
    toml.write_text(toml.read_text().replace('section = "1.7"', f'section = "{section}"', 1))
    res = replace(results["piston"], folder=str(folder), spec=Case(folder).spec)
    out = tmp_path / "out"
    shutil.copytree(case_module.CASES_DIR.parent / "reports" / "data", out / "data",
                    ignore=shutil.ignore_patterns("piston.json"))  # the other five cases, 1.8.1 to 1.10
    report.write_reports([res], out)
    index = (out / "index.md").read_text()
    table = index.split("\n\n")[2]  # after the title and the introduction
    sections = [line.split("|")[2].strip() for line in table.splitlines()[2:]]
    assert sections[position] == section and len(sections) == 6
    assert [s for s in sections if s != section] == ["1.8.1", "1.8.2", "1.8.3", "1.9", "1.10"]


def test_a_foreign_json_in_data_is_left_out_with_a_warning(results, quick_figures, tmp_path, capsys):
    out = tmp_path / "out"
    (out / "data").mkdir(parents=True)
    (out / "index.md").write_text("")
    (out / "data" / "broken.json").write_text('{"case": ')
    (out / "data" / "notes.json").write_text('{"author": "someone else"}')
    report.write_reports([result(results, "piston")], out)
    err = capsys.readouterr().err
    for name in ("broken.json", "notes.json"):
        assert f"dyncheck: warning: {out / 'data' / name} is not a case summary" in err
        assert (out / "data" / name).exists()  # not ours to delete
    assert "[piston](piston.md)" in (out / "index.md").read_text()


# -- the swap, the lock, and what killed runs leave --------------------------------------------

def test_a_report_written_twice_holds_the_same_files_and_nothing_else(results, monkeypatch, tmp_path):
    """The same files as a report written file by file, nothing beside them but the lock; the second
    time through the two-rename swap of systems without an atomic exchange, with the same result."""
    out = tmp_path / "out"
    report.write_reports([result(results, "piston")], out)
    first = files(out)
    assert set(first) == PISTON_FILES
    monkeypatch.setattr(report, "exchange", lambda a, b: False)
    report.write_reports([result(results, "piston")], out)
    assert files(out) == first
    assert sorted(os.listdir(tmp_path)) == [".out.lock", "out"]


def test_nothing_reaches_the_folder_before_the_swap(canned, quick_figures, monkeypatch, tmp_path):
    """A failure or a kill at the last step, with every new file written, leaves the previous report
    byte for byte: the new one comes in as a whole or not at all (a duplicated case name moved
    files in until it failed part-way, before)."""
    out = tmp_path / "out"
    assert cli.main(["report", "rotating_particle", "--out", str(out)]) == 0
    before = files(out)

    def killed(new, out):
        assert files(out) == before and set(files(new)) > set(before)  # everything new is built beside
        raise RuntimeError("killed")
    monkeypatch.setattr(report, "swap", killed)
    with pytest.raises(RuntimeError, match="killed"):
        cli.main(["report", "piston", "piston", "--set", "m=3", "--out", str(out)])
    assert files(out) == before and sorted(os.listdir(tmp_path)) == [".out.lock", "out"]


def test_a_duplicated_case_name_writes_one_report(canned, quick_figures, tmp_path):
    out = tmp_path / "out"
    assert cli.main(["report", "piston", "piston", "--set", "m=3", "--out", str(out)]) == 0
    assert set(files(out)) == PISTON_FILES and "Parameters overridden (`--set`): m = 3 kg (book: " in (out / "piston.md").read_text()


def test_a_report_with_overrides_goes_beside_the_book_s_pages(canned, quick_figures, monkeypatch, tmp_path):
    """Without --out, `report --set` writes to a folder named after the overrides, never over reports/."""
    monkeypatch.chdir(tmp_path)
    assert cli.main(["report", "piston", "--set", "m=3", "--no-studies"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".")) == ["reports-m=3"]
    index = (tmp_path / "reports-m=3" / "index.md").read_text()
    assert "m = 3" in index


def test_stale_trees_of_killed_runs_are_removed(results, quick_figures, tmp_path):
    out = tmp_path / "out"
    (out / ".tmp-abc123" / "figures").mkdir(parents=True)  # what earlier versions left inside
    (out / "index.md").write_text("")
    (tmp_path / ".out.tmp-999999" / "figures").mkdir(parents=True)
    (tmp_path / "keep.tmp-1").mkdir()  # not ours
    report.write_reports([result(results, "piston")], out)
    assert sorted(os.listdir(tmp_path)) == [".out.lock", "keep.tmp-1", "out"]
    assert set(files(out)) == PISTON_FILES


def test_a_run_killed_between_the_two_renames_gets_its_report_back(results, quick_figures, tmp_path):
    """Where the system cannot exchange two folders, `swap` moves the previous report aside first."""
    out = tmp_path / "out"
    report.write_reports([result(results, "piston")], out)
    previous = files(out)
    out.rename(tmp_path / f".out.tmp-999999{report.PREVIOUS}")
    report.write_reports([result(results, "rotating_particle")], out)
    assert {k: v for k, v in files(out).items() if "piston" in k} == {k: v for k, v in previous.items() if "piston" in k}
    assert "[piston](piston.md)" in (out / "index.md").read_text()


def slowly(summaries):
    def slow(tree, out):
        cases = summaries(tree, out)
        time.sleep(0.5)  # the other writer reads the summaries too before this one moves its index in
        return cases
    return slow


def test_concurrent_writers_take_turns_and_both_cases_land(results, quick_figures, monkeypatch, tmp_path, capfd):
    monkeypatch.setattr(report, "summaries", slowly(report.summaries))
    out = tmp_path / "out"
    fork = multiprocessing.get_context("fork")
    writers = [fork.Process(target=report.write_reports, args=([result(results, name)], out))
               for name in ("piston", "rotating_particle")]
    for writer in writers:
        writer.start()
    for writer in writers:
        writer.join(timeout=60)
    assert [w.exitcode for w in writers] == [0, 0]
    index = (out / "index.md").read_text()
    assert "[piston](piston.md)" in index and "[rotating_particle](rotating_particle.md)" in index
    assert "dyncheck: waiting for dyncheck pid " in capfd.readouterr().err


def test_the_index_counts_no_state_of_a_case_whose_checks_did_not_finish(results, quick_figures, tmp_path):
    """An unfinished case compared nothing: the index says so, and neither counts its states nor calls it a
    disagreement."""
    from dyncheck.checks.runs import unfinished
    lost = unfinished(case_module.load_case("spinning_top"), "killed by signal SIGKILL")
    report.write_reports([results["piston"], lost], tmp_path / "out", animations=False)
    index = (tmp_path / "out" / "index.md").read_text()
    assert "Not compared: spinning_top, whose checks did not finish." in index
    assert "disagreed" not in index and "(1 case;" in index


def test_a_result_that_cannot_leave_its_process_is_lost_saying_so():
    """A study's result holding a read-only mapping (the spinning top's case.params) could not be pickled back from
    its forked process: the item is lost with the reason, not a traceback and a bare exit code."""
    from types import MappingProxyType
    from dyncheck.case import isolation
    budget = isolation.Budget(math.inf, 60.0, isolation.machine_memory() // 2)
    ((index, (kind, why)),) = list(isolation.run_each([1], lambda item: MappingProxyType({"m": item}), 1,
                                                      lambda item: budget))
    assert (index, kind) == (0, "lost") and "could not be sent back" in why and "mappingproxy" in why, why
