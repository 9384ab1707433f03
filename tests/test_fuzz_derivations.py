"""A researcher's derivation as hostile code (issue 34), beside tests/test_fuzz.py's hostile case files: modules
that exit, raise, loop, sleep, allocate, kill their process or return what is not a vector of numbers, in a
region of the state space few random states fall into; and derivations wrong only in a region of 5 % of it.
Each must give a failing row that says what happened, within its budget: never exit 0, never a traceback, never a
hang.  DYNCHECK_FUZZ_EXAMPLES raises the number of random regions (the long form: `pytest -m slow`)."""

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import dyncheck
from dyncheck.checks.pointwise import pointwise, validate_placeholders
from dyncheck.cli import exit_code, run_cases

GUIDE = Path(__file__).resolve().parent.parent / "docs" / "own-case.md"
FILES = {}  # the guide's first scene.xml and equations.py, as written (before its planted error)
for name, text in re.findall(r"```(?:xml|python) file=cart_pendulum/(\S+)\n(.*?)```", GUIDE.read_text(), re.S):
    FILES.setdefault(name, text)
CALL_BUDGET = 0.1  # s: a case.toml [budget] call, so that a looping derivation costs the test seconds, not minutes


def make_case(folder, equations, toml=""):
    """The guide's cart-pendulum in `folder`/cart_pendulum with `equations` for its equations.py."""
    case = folder / "cart_pendulum"
    case.mkdir(parents=True)
    (case / "scene.xml").write_text(FILES["scene.xml"])
    (case / "equations.py").write_text(equations)
    if toml:
        (case / "case.toml").write_text(toml)
    return folder


def misbehaving(action, where="abs(q[1]) > 2.5", function="accelerations"):
    """The guide's correct equations, with `action` done by `function` where `where` holds (theta beyond 2.5 rad:
    a few random states, and no state of the runs, which stay within 0.5 rad)."""
    source = FILES["equations.py"]
    head = f"def {function}("
    start = source.index(head)
    body = source.index(":\n", start) + 2
    guard = textwrap.indent(f"if {where}:\n" + textwrap.indent(action, "    ") + "\n", "    ")
    return "import os, sys, time, signal, ctypes\n" + source[:body] + guard + source[body:]


BUDGETED = f"[budget]\ncall = {CALL_BUDGET}\n"

# (name, what the derivation does in its region, the words its failing row must hold)
MISCHIEF = [
    ("sys.exit(0)", "sys.exit(0)", "it ended the process (sys.exit(0))"),
    ("raise SystemExit", "raise SystemExit", "it ended the process (sys.exit(None))"),
    ("os._exit(0)", "os._exit(0)", "its process ended (exit code 0) during cart_pendulum/equations.py: accelerations"),
    ("SIGKILL", "os.kill(os.getpid(), signal.SIGKILL)", "killed by signal SIGKILL"),
    ("segfault", "ctypes.string_at(0)", "killed by signal SIGSEGV"),
    ("loop", "while True: pass", f"past its budget of {CALL_BUDGET:g} s for one call"),
    ("sleep", "time.sleep(1e6)", f"past its budget of {CALL_BUDGET:g} s for one call"),
    ("swallowed time-out", "while True:\n    try:\n        time.sleep(1e6)\n    except BaseException:\n        pass",
     f"killed, past its budget of {CALL_BUDGET:g} s for one call"),  # it outlives every CallTimeout: killed
    ("ignored time-out", "signal.signal(signal.SIGUSR2, signal.SIG_IGN)\nwhile True: pass",
     f"killed, past its budget of {CALL_BUDGET:g} s for one call"),
    ("stopped", "os.kill(os.getpid(), signal.SIGSTOP)", f"killed, past its budget of {CALL_BUDGET:g} s for one call"),
    ("40 GB", "x = np.ones(5 * 10**9)", "it ran out of memory"),
    ("raise", "raise KeyError('theta')", "KeyError: 'theta'"),
    ("NaN", "return np.array([np.nan, 0.0])", "is nan at random state"),
    ("wrong shape", "return np.zeros(3)", "not real numbers of shape (2,)"),
]


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
@pytest.mark.parametrize("name, action, said", MISCHIEF, ids=[m[0] for m in MISCHIEF])
def test_a_derivation_misbehaving_in_a_small_region_fails_saying_what_it_did(name, action, said, tmp_path):
    folder = make_case(tmp_path, misbehaving(action), BUDGETED)
    case = dyncheck.load_case("cart_pendulum", folder)
    start = time.perf_counter()
    results, interrupted = run_cases([case], localise=False)
    elapsed = time.perf_counter() - start
    assert interrupted is None and exit_code(results) == 1
    failing = [r for r in results[0].rows if not r.status.ok]
    assert any(said in (r.detail or "") for r in failing), [r.detail for r in failing][:5]
    assert elapsed < 60, f"{name}: {elapsed:.0f} s"


def test_the_state_of_a_misbehaving_call_is_in_its_row(tmp_path):
    folder = make_case(tmp_path, misbehaving("os._exit(3)"))
    results, _ = run_cases([dyncheck.load_case("cart_pendulum", folder)], localise=False)
    (row,) = results[0].rows
    assert re.search(r"accelerations at t = \S+ s, q = \[\S+, -?2\.[5-9]\d*\], v = \[", row.detail), row.detail


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_derivation_that_exits_at_import_or_on_load_is_bad_input_for_the_command(tmp_path):
    """Through the console command, whose supervisor sees the process end: exit 2 while loading, never 0."""
    for where, source in (("import", "import os\nos._exit(0)\n" + FILES["equations.py"]),
                          ("load", misbehaving("os._exit(0)", where="True"))):
        folder = make_case(tmp_path / where, source)
        for command in ("run", "list"):
            done = subprocess.run(["dyncheck", command, "--cases", str(folder)], capture_output=True, text=True,
                                  timeout=120)
            assert done.returncode == 2, (where, command, done.stdout[-500:], done.stderr[-500:])
            assert "a case's own code ended dyncheck" in done.stderr and "Traceback" not in done.stderr


def command(folder, timeout=120):
    return subprocess.run(["dyncheck", "run", "--cases", str(folder)], capture_output=True, text=True,
                          timeout=timeout)


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_forged_end_is_no_end(tmp_path):
    """Code that marks dyncheck's record done (with a token of its own making) and ends the process with 0 ends
    dyncheck with exit 2: only the supervisor's token signs an end."""
    forger = ("import os, sys\nsys.modules['dyncheck.case.isolation'].RECORD.done(0, bytes(16))\nos._exit(0)\n"
              + FILES["equations.py"])
    done = command(make_case(tmp_path, forger))
    assert done.returncode == 2, done.stderr[-500:]
    assert "a case's own code ended dyncheck" in done.stderr and "Traceback" not in done.stderr


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_derivation_that_changes_the_current_folder_does_not_move_the_files_written(tmp_path):
    """Relative paths of the command line are the caller's: taken from the current folder before a case's code runs
    (here an import that moves to another folder, and a call that moves again in the case's process)."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    mover = f"import os\nos.chdir({str(elsewhere)!r})\n" + misbehaving(f"os.chdir({str(elsewhere)!r})", where="True")
    make_case(tmp_path / "cases", mover)
    done = subprocess.run(["dyncheck", "run", "--cases", "cases", "--json", "out.json", "--junit", "out.xml"],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-500:]
    assert (tmp_path / "out.json").is_file() and (tmp_path / "out.xml").is_file()
    assert list(elsewhere.iterdir()) == []


@pytest.mark.parametrize("action, code, said", [
    # a stopped parent is resumed by the supervisor: the run ends with the derivation's NaN, once
    ("os.kill(os.getppid(), signal.SIGSTOP)\nreturn np.array([np.nan, 0.0])", 1, "dyncheck: FAIL"),
    # a copy of the case's process that the code forks does not run dyncheck on: its summary is printed once
    ("os.fork()\nreturn np.array([np.nan, 0.0])", 1, "dyncheck: FAIL"),
    # the watching process killed: the command says so, and no case's process lives on
    ("os.write(os.open(os.environ['DYNCHECK_TEST_PID'], os.O_WRONLY | os.O_CREAT | os.O_APPEND),"
     " b'%d\\n' % os.getpid())\nos.kill(os.getppid(), signal.SIGKILL)",
     1, "killed by signal SIGKILL")], ids=["stops its parent", "forks", "kills its parent"])
@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_derivation_acting_on_processes_ends_the_run_as_one_run(action, code, said, tmp_path, monkeypatch):
    pid_file = tmp_path / "pid"
    monkeypatch.setenv("DYNCHECK_TEST_PID", str(pid_file))
    done = command(make_case(tmp_path / "case", misbehaving(action), BUDGETED))
    assert done.returncode == code, done.stderr[-500:]
    assert (done.stdout + done.stderr).count(said) == 1, (done.stdout[-500:], done.stderr[-500:])
    assert "Traceback" not in done.stderr
    if pid_file.exists():
        assert not any(alive(int(pid), within=5) for pid in pid_file.read_text().split())  # each process it ran in


def alive(pid, within):
    """Whether process `pid` still runs after `within` s (a zombie, dead but not yet reaped, does not)."""
    stat = Path(f"/proc/{pid}/stat")
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            if stat.read_text().rsplit(")", 1)[1].split()[0] in "ZX":
                return False
        except (FileNotFoundError, ProcessLookupError):
            return False
        time.sleep(0.1)
    return True


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_ctrl_c_during_a_run_exits_130_without_a_traceback(tmp_path):
    folder = make_case(tmp_path, misbehaving("time.sleep(1e6)", where="True"), "[budget]\ncall = 100\n")
    process = subprocess.Popen(["dyncheck", "run", "--cases", str(folder)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, start_new_session=True)
    time.sleep(4)  # loading (about 2 s), then the first call, which sleeps
    os.killpg(process.pid, signal.SIGINT)  # as a terminal sends it: to the whole group
    out, err = process.communicate(timeout=60)
    assert process.returncode == 130, err[-500:]
    assert "Traceback" not in err and "interrupted" in err


# -- wrong only in a region of 5 % of the state space ------------------------------------------------

def regions(case, count, seed):
    """`count` random regions of at most 5 % of the case's state space: an interval of one of t, x, theta, their
    rates (times within the horizon), or a box over two of them whose sides multiply to 5 % of their ranges."""
    sample = case.spec["sample"]
    names = ["t", "q[0]", "q[1]", "v[0]", "v[1]"]
    box = [(0.0, case.initial[2])] + [tuple(case.value(x) for x in pair) for pair in sample["q"] + sample["v"]]
    rng = np.random.default_rng(seed)
    for _ in range(count):
        axes = rng.choice(len(names), size=rng.integers(1, 3), replace=False)
        share = 0.05 ** (1 / len(axes))
        condition = []
        for axis in axes:
            lo, hi = box[axis]
            width = share * (hi - lo)
            start = rng.uniform(lo, hi - width)
            condition.append(f"{start!r} <= {names[axis]} <= {start + width!r}")
        yield " and ".join(condition)


WRONG = ["return np.array([np.nan, 0.0])", "return -accelerations_right(t, q, v, p)",
         "return accelerations_right(t, q, v, p) + np.array([0.0, 1e-3])"]


def region_variant(where, wrong):
    source = FILES["equations.py"].replace("def accelerations(", "def accelerations_right(")
    return source + (f"\n\ndef accelerations(t, q, v, p):\n    if {where}:\n        {wrong}\n"
                     f"    return accelerations_right(t, q, v, p)\n")


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
@pytest.mark.parametrize("count", [int(os.environ.get("DYNCHECK_FUZZ_EXAMPLES", "20"))])
def test_a_derivation_wrong_only_in_a_region_of_5_percent_fails(count, tmp_path):
    right = dyncheck.load_case("cart_pendulum", make_case(tmp_path / "right", FILES["equations.py"]))
    missed = []
    for i, where in enumerate(regions(right, count, seed=34)):
        folder = make_case(tmp_path / f"region{i}", region_variant(where, WRONG[i % len(WRONG)]))
        rows, _ = pointwise(dyncheck.load_case("cart_pendulum", folder))
        if all(r.status.ok for r in rows):
            missed.append(where)
    assert not missed, f"{len(missed)} of {count} regions passed: {missed}"


def test_the_regions_test_can_fail(tmp_path):
    """A region between two neighbouring states' theta holds no state: there the same wrong derivation passes, so
    the failures above mean the states reached the regions."""
    # budget 0: the case file's count of states, the same in all three (a measured cost picks the count otherwise)
    fixed = "[sample]\nbudget = 0\n"
    right = dyncheck.load_case("cart_pendulum", make_case(tmp_path / "right", FILES["equations.py"], fixed))
    theta = np.sort([q[1] for _, q, _ in right.sample_states()])
    gap = np.argmax(np.diff(theta))
    where = f"{theta[gap]!r} < q[1] < {theta[gap + 1]!r}"
    folder = make_case(tmp_path / "gap", region_variant(where, WRONG[0]), fixed)
    rows, _ = pointwise(dyncheck.load_case("cart_pendulum", folder))
    assert all(r.status.ok for r in rows)
    folder = make_case(tmp_path / "state", region_variant(f"{theta[gap]!r} <= q[1] < {theta[gap + 1]!r}", WRONG[0]),
                       fixed)
    rows, _ = pointwise(dyncheck.load_case("cart_pendulum", folder))
    assert not all(r.status.ok for r in rows)  # the same region with one state in it


@pytest.mark.parametrize("override", [{"k": "-1"}, {"k": "2_0"}, {"l": "1e-7"}], ids=["bound", "not a number", "light"])
def test_a_message_about_a_case_of_two_files_names_its_folder_not_a_case_toml(override, tmp_path):
    folder = make_case(tmp_path, FILES["equations.py"])
    with pytest.raises(ValueError) as refused:
        validate_placeholders(dyncheck.load_case("cart_pendulum", folder, **override))
    assert str(refused.value).startswith(f"{folder / 'cart_pendulum'}: override "), str(refused.value)


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_derivation_writing_into_its_arguments_changes_no_state_of_the_checks(tmp_path):
    """The guide's correct equations, which zero q, v and t's arrays after computing their answer: they pass."""
    source = FILES["equations.py"].replace("def accelerations(", "def _accelerations(")
    source += ("\n\ndef accelerations(t, q, v, p):\n    answer = _accelerations(t, q, v, p)\n"
               "    q[...] = 0.0\n    v[...] = 0.0\n    return answer\n")
    results, _ = run_cases([dyncheck.load_case("cart_pendulum", make_case(tmp_path, source))], localise=False)
    assert exit_code(results) == 0, [r.detail for r in results[0].rows if not r.status.ok][:3]


def test_a_derivation_file_of_another_name_is_named_as_it_is(tmp_path):
    folder = make_case(tmp_path, "")
    (folder / "cart_pendulum" / "equations.py").unlink()
    (folder / "cart_pendulum" / "lagrange.py").write_text(misbehaving("raise KeyError('m')", where="True"))
    (folder / "cart_pendulum" / "case.toml").write_text('derivation = "lagrange.py"\n')
    with pytest.raises(ValueError, match=r"cart_pendulum/lagrange\.py: at the initial state .*KeyError"):
        dyncheck.load_case("cart_pendulum", folder)
