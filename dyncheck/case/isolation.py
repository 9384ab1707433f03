"""Code dyncheck does not control, bounded: a researcher's derivation may exit, hang, allocate without bound or end
its process.  Every call into it runs under `guarded_call`, which records what runs (the file, the function, the
state, since when) and turns its exit (SystemExit), an overrun of its time budget or a MemoryError into a
DerivationError naming all of that: the checks make of it a failing row, as of any error of a model.  What a
process cannot survive (os._exit, a signal, a hang in compiled code) is seen from outside: each case runs in a
forked process of its own (`run_each`), within a memory cap and a time budget, and the console command itself runs
under `supervised`, so that foreign code can never end dyncheck with an exit code of its choosing.
docs/isolation.md says what a user sees."""

import ctypes
import faulthandler
import hashlib
import hmac
import importlib.util
import mmap
import os
import pickle
import resource
import signal
import struct
import sys
import threading
import time
import traceback
from dataclasses import dataclass
from multiprocessing import connection, get_all_start_methods, get_context
from pathlib import Path

import numpy as np

MAX_SHOWN = 16  # coordinates a record keeps of a state (a message shows no more)
LABEL_BYTES = 2048
# The record's layout, in one page shared with the forked process that reads it: a header of doubles
# (active, t, started, coordinates n, the call's budget, the state's q and v), the function's name and the label
# (what runs), then the end: whether it was reached, the exit code, whether loading, and the supervisor's token.
HEADER = 5 + 2 * MAX_SHOWN
NAME_AT, LABEL_AT, DONE_AT = 8 * HEADER, 8 * HEADER + 64, 8 * HEADER + 64 + LABEL_BYTES
TOKEN_AT, TOKEN_BYTES = DONE_AT + 16, 16
# The defaults of a case's budget (Case.budget).  A call of a derivation costs microseconds to milliseconds (a
# generated 7-dof inverse dynamics: 2-6 ms); 1000 of them is no honest call's time, and 5 s is a floor that
# no machine's load reaches.  The checks of a case make at most about a million evaluations of it (the six book
# cases' runs together: 640,000 DOP853 evaluations), so a million calls' cost bounds a case, with 900 s as its floor
# (the book's slowest case takes 7 s, a 7-dof arm 3 minutes).  An import may compile or lambdify for seconds.
CALL_FLOOR, CALLS_PER_BUDGET = 5.0, 1000
CASE_FLOOR, CALLS_PER_CASE = 900.0, 10**6
IMPORT_BUDGET = 60.0
TICK = 0.05  # s between two looks of the watchdog: a call is stopped within this of its budget
OVERRUN_SIGNAL = signal.SIGUSR2  # the watchdog's to the main thread (SIGALRM is the user's, and pytest's)
# A call that outlives its budget by this much did not stop when its watchdog told it to (it ignores or swallows
# the signal, or hangs in compiled code, or its process is stopped): the process watching it kills it.  The
# watchdog stops an honest call within TICK (0.05 s) of its budget; 20 ticks leave room for a loaded machine.
GRACE = 1.0
POLL = 0.1  # s between two looks of a watching process at its children (the records, their exits)
PR_SET_PDEATHSIG = 1  # prctl(2): the signal a process gets when the one that forked it dies


class DerivationError(Exception):
    """Foreign code that exited, overran its time budget or ran out of memory, said with where and when."""


class CallTimeout(BaseException):
    """Raised into foreign code past its budget: a BaseException, so that its own `except Exception` lets it out."""


@dataclass(frozen=True)
class Budget:
    """How long one call of a case's own code may run (s), how long its whole case (s, in its own process), and
    how much memory that process may map (bytes); docs/isolation.md argues the defaults."""
    call: float
    case: float
    memory: int | None  # None: the machine's, shared (dyncheck.cli)


class Record:
    """What foreign code runs now, in memory that a forked process shares with the one that forked it: written at
    every call (about 0.7 us), read by the parent when the child dies.  `done(code)` marks a normal end."""

    def __init__(self):
        self._memory = mmap.mmap(-1, TOKEN_AT + TOKEN_BYTES)  # anonymous and shared: a forked child writes, its parent reads
        self._doubles = np.frombuffer(self._memory, dtype=float, count=HEADER)
        self._name = self._label = None

    def enter(self, label, name, args, budget):
        if label != self._label:
            self._write(LABEL_AT, LABEL_BYTES, label)
            self._label = label
        if name != self._name:
            self._write(NAME_AT, 64, name)
            self._name = name
        d = self._doubles
        d[1], d[2], d[3], d[4] = np.nan, time.monotonic(), 0, budget
        if _at_a_state(args):
            t, q, v = args[:3]
            n = min(len(q), MAX_SHOWN)
            d[1], d[3] = float(t), n
            d[5:5 + n], d[5 + MAX_SHOWN:5 + MAX_SHOWN + n] = q[:n], v[:n]
        d[0] = 1.0

    def leave(self):
        self._doubles[0] = 0.0

    def _write(self, at, size, text):
        data = text.encode()[:size - 2]
        self._memory[at:at + 2 + len(data)] = struct.pack("<H", len(data)) + data

    def _read(self, at):
        (size,) = struct.unpack("<H", self._memory[at:at + 2])
        return self._memory[at + 2:at + 2 + size].decode(errors="replace")

    def done(self, code, token):
        """Marks a normal end with its exit code, signed with the token that the supervising process gave (`seal`):
        a record that foreign code marks done without it is no end."""
        self._memory[TOKEN_AT:TOKEN_AT + TOKEN_BYTES] = token
        self._memory[DONE_AT:DONE_AT + 9] = struct.pack("<?q", True, code)

    def seal(self):
        """A new token for `done`, kept by the caller (the supervisor, which hands it to its child alone)."""
        self._memory[DONE_AT:DONE_AT + 9] = struct.pack("<?q", False, 0)
        self._memory[TOKEN_AT:TOKEN_AT + TOKEN_BYTES] = bytes(TOKEN_BYTES)
        return os.urandom(TOKEN_BYTES)

    @property
    def loading(self):
        """Whether the process is loading cases (bad input ends it with exit 2), rather than running them."""
        return self._memory[DONE_AT + 9] == 1

    @loading.setter
    def loading(self, value):
        self._memory[DONE_AT + 9] = int(value)

    def code(self, token):
        """The exit code that `done` recorded with `token`, or None where the process ended otherwise."""
        finished, code = struct.unpack("<?q", self._memory[DONE_AT:DONE_AT + 9])
        signed = hmac.compare_digest(bytes(self._memory[TOKEN_AT:TOKEN_AT + TOKEN_BYTES]), token)
        return code if finished and signed else None

    def overran(self):
        """Where the running call has outlived its budget by GRACE (its watchdog did not stop it), why the process
        running it is killed, in words; else None."""
        d = self._doubles
        if d[0] == 1.0 and time.monotonic() > d[2] + d[4] + GRACE:
            return f"{self.describe()}: killed, {past(self._read(NAME_AT), d[4])}, which it did not stop at when told"
        return None

    def describe(self):
        """The call that was running, in words ("equations.py: accelerations at t = 0.1 s, q = [...], v = [...],
        after 2.5 s"), or None where none was."""
        d = self._doubles
        if d[0] != 1.0:
            return None
        return in_words(self._read(LABEL_AT), self._read(NAME_AT), d[1], d[5:5 + int(d[3])],
                        d[5 + MAX_SHOWN:5 + MAX_SHOWN + int(d[3])], time.monotonic() - d[2])


def in_words(label, name, t, q, v, elapsed):
    state = "" if np.isnan(t) else (f" at t = {t:.6g} s, q = [{', '.join(f'{x:.6g}' for x in q)}], "
                                     f"v = [{', '.join(f'{x:.6g}' for x in v)}]")
    return f"{label}: {name}{state}, after {elapsed:.3g} s"


RECORD = Record()  # this process's; a forked child given its own (run_each) writes there


class _Watchdog:
    """A thread that sends OVERRUN_SIGNAL to the main thread when the call running there has outrun its deadline
    (and every second after, should the call swallow the CallTimeout): the signal ends a sleep or a Python loop."""

    def __init__(self):
        self.deadline = None  # the running call's, time.monotonic(); None between calls
        self.pid = os.getpid()
        self.main = threading.main_thread().ident
        signal.signal(OVERRUN_SIGNAL, _overrun)
        threading.Thread(target=self._watch, daemon=True, name="dyncheck-watchdog").start()

    def _watch(self):
        last = 0.0
        while True:
            time.sleep(TICK)
            deadline, now = self.deadline, time.monotonic()
            if deadline is not None and now > deadline and now - last > 1.0:
                last = now
                signal.pthread_kill(self.main, OVERRUN_SIGNAL)


_WATCHDOG = None


def _overrun(signum, frame):
    if _WATCHDOG is not None and _WATCHDOG.deadline is not None and time.monotonic() > _WATCHDOG.deadline:
        raise CallTimeout


def _watchdog():
    """This process's watchdog (a forked child has none of its parent's threads: it starts its own), or None off
    the main thread, where no signal handler can be set (a Dask worker's threads): their calls have no deadline."""
    global _WATCHDOG
    if threading.current_thread() is not threading.main_thread():
        return None
    if _WATCHDOG is None or _WATCHDOG.pid != os.getpid():
        _WATCHDOG = _Watchdog()
    return _WATCHDOG


def past(name, budget):
    """An overrun call's budget in words, and what sets it: an import's is fixed, a call's is the case's."""
    if name == "import":
        return f"past the {budget:g} s an import may take"
    return f"past its budget of {budget:g} s for one call (case.toml's [budget] call sets it)"


def guarded_call(label, name, budget, function, *args):
    """function(*args), foreign code: recorded, within `budget` s, its exit or overrun a DerivationError."""
    watchdog = _watchdog()
    RECORD.enter(label, name, args, budget)
    start, pid = time.monotonic(), os.getpid()
    if watchdog is not None:
        watchdog.deadline = start + budget
    where = lambda: in_words(label, name, *(_state(args) + (time.monotonic() - start,)))
    try:
        try:
            # copies of the arrays: code that writes into its arguments (q[0] %= 2 pi) changes no state of the checks
            return function(*(a.copy() if isinstance(a, np.ndarray) else a for a in args))
        finally:
            if os.getpid() != pid:  # a copy of this process that the code forked: it must not run dyncheck on
                os._exit(0)
            if watchdog is not None:
                watchdog.deadline = None
            RECORD.leave()
    except SystemExit as error:
        raise DerivationError(f"{where()}: it ended the process (sys.exit({error.code!r}))") from None
    except CallTimeout:
        raise DerivationError(f"{where()}: stopped, {past(name, budget)}") from None
    except MemoryError:
        raise DerivationError(f"{where()}: it ran out of memory (the case's cap, which case.toml's [budget] memory sets)") from None


def _at_a_state(args):
    """Whether a call's arguments begin with a state, (t, q, v, ...), as the model interface's do."""
    return len(args) >= 3 and np.ndim(args[1]) == 1 and np.ndim(args[2]) == 1


def _state(args):
    if _at_a_state(args):
        return float(args[0]), np.asarray(args[1], dtype=float), np.asarray(args[2], dtype=float)
    return np.nan, (), ()


class Guarded:
    """A module or model of foreign code whose functions each run under guarded_call, within `budget` s a call
    (which Case sets from their measured cost once it has one); its other attributes (classes among them) as
    they are."""

    def __init__(self, target, label, budget):
        self._target, self.label, self.budget = target, label, budget
        self.cost = 0.0  # s, of one call, once measured (Case._derived)
        self.__doc__ = getattr(target, "__doc__", None)  # the module's, which a derived case's title is read from

    def __getattr__(self, name):
        attribute = getattr(self._target, name)
        if name.startswith("_") or not callable(attribute) or isinstance(attribute, type):
            return attribute
        method = lambda *args: guarded_call(self.label, name, self.budget, attribute, *args)
        self.__dict__[name] = method  # looked up once
        return method


# -- whole processes --------------------------------------------------------------------------------------------

def each_forked(items, work, workers, budget_of):
    """run_each where processes can be forked; elsewhere work(item) for each item in this process, one after
    another, as (index, ("result", value)) (an exception is raised as it is)."""
    if "fork" in get_all_start_methods():
        return run_each(items, work, workers, budget_of)
    return ((index, ("result", work(item))) for index, item in enumerate(items))


def run_each(items, work, workers, budget_of):
    """work(item) for each item, each in a forked process of its own, `workers` at a time, in the order given:
    yields (index, ("result", value)), or (index, ("lost", why)) where the process died, overran its case budget
    (budget_of(item).case s: it is killed) or raised, or (index, ("interrupted", None)) where it was interrupted
    (a KeyboardInterrupt raised by code there: the item did not finish, the others run on).  Each process maps
    at most budget_of(item).memory bytes and ignores Ctrl-C (the terminal sends it to the whole group): this one
    stops them all (KeyboardInterrupt)."""
    context = get_context("fork")
    waiting, running = list(enumerate(items)), {}  # connection -> (index, process, record, deadline, budget)
    try:
        while waiting or running:
            while waiting and len(running) < workers:
                index, item = waiting.pop(0)
                budget = budget_of(item)
                record = Record()
                receive, send = context.Pipe(duplex=False)
                process = context.Process(target=_child, args=(work, item, send, record, budget.memory, os.getpid()),
                                          daemon=True)
                process.start()
                send.close()
                running[receive] = (index, process, record, time.monotonic() + budget.case, budget)
            ready = connection.wait(list(running) + [p.sentinel for _, p, _, _, _ in running.values()], timeout=POLL)
            for receive, (index, process, record, deadline, budget) in list(running.items()):
                outcome = None
                if receive in ready or process.sentinel in ready:
                    try:
                        outcome = receive.recv()
                    except (EOFError, OSError, pickle.UnpicklingError):
                        process.join()
                        outcome = ("lost", _death(process.exitcode, record))
                elif time.monotonic() > deadline:
                    running_call = record.describe()
                    process.kill()
                    outcome = ("lost", f"stopped after its budget of {budget.case:g} s for the whole case "
                                       "(case.toml's [budget] case sets it)"
                                       + (f", during {running_call}" if running_call else ""))
                elif (overrun := record.overran()) is not None:
                    process.kill()
                    outcome = ("lost", overrun)
                if outcome is not None:
                    process.join()
                    receive.close()
                    del running[receive]
                    yield index, outcome
    finally:
        for receive, (_, process, _, _, _) in running.items():
            process.kill()
            process.join()
            receive.close()


def machine_memory():
    """The machine's physical memory, bytes."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def _death(code, record):
    """A process's end (its exit code, negative for a signal, as multiprocessing gives it) and its last call."""
    how = (f"killed by signal {signal.Signals(-code).name}" if code < 0 else f"exit code {code}")
    call = record.describe()
    return f"its process ended ({how})" + (f" during {call}" if call else "")


def _die_with_parent(parent):
    """This forked process is killed when `parent` dies (Linux's prctl; elsewhere the parent kills it), so that no
    case runs on, orphaned, after foreign code killed the process that watches it."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # it died before the request: none will come
        os._exit(1)


def _child(work, item, send, record, memory, parent):
    global RECORD
    RECORD = record
    _die_with_parent(parent)
    faulthandler.disable()  # a crash is the case's row, not a dump of this process's threads (pytest enables it)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    try:
        outcome = ("result", work(item))
    except KeyboardInterrupt:  # raised by code, since this process ignores Ctrl-C: an interruption all the same
        outcome = ("interrupted", None)
    except DerivationError as error:
        outcome = ("lost", str(error))
    except Exception as error:  # the checks stopped where no row could hold the error: the case's one row says it
        outcome = ("lost", f"{type(error).__name__}: {error}")
    try:
        send.send(outcome)
    except MemoryError:
        send.send(("lost", "its results did not fit in the case's memory cap (case.toml's [budget] memory sets it)"))
    except (TypeError, AttributeError, pickle.PicklingError) as error:  # a value that cannot travel between processes
        send.send(("lost", f"its results could not be sent back from its process: {type(error).__name__}: {error}"))
    send.close()
    os._exit(0)


def supervised(main):
    """main() in a forked process, its exit code passed on only where main returned it (the record signed with a
    token that only this process and main's own frame hold): a process ended by foreign code (os._exit, a signal, a
    forged record) gives exit 2 where it was loading a case, else 1, with a line saying what ran.  A call of that
    process that outlives its budget is killed (its watchdog did not stop it); a stop (SIGSTOP) is resumed."""
    context = get_context("fork")
    RECORD.leave()
    token = RECORD.seal()
    process = context.Process(target=_main_child, args=(main, RECORD, token, os.getpid()))
    process.start()
    # The child gets Ctrl-C too (the terminal sends it to the group), and says it was interrupted; a SIGTERM sent to
    # this process alone (a CI job's time-out) is passed on, and ends this one as it would have.
    terminated = []
    previous = (signal.signal(signal.SIGINT, signal.SIG_IGN),
                signal.signal(signal.SIGTERM, lambda *_: (terminated.append(True), process.terminate())))
    try:
        status, overrun = _watch(process.pid)
    finally:
        signal.signal(signal.SIGINT, previous[0])
        signal.signal(signal.SIGTERM, previous[1])
    code, recorded = os.waitstatus_to_exitcode(status), RECORD.code(token)
    if recorded is not None and recorded == code:
        return code
    if terminated:
        return 128 + signal.SIGTERM
    ended = overrun or _death(code, RECORD)
    print(f"dyncheck: error: {ended}: a case's own code ended dyncheck", file=sys.stderr)
    return 2 if RECORD.loading else 1


def _watch(pid):
    """Waits for the child `pid` to end, resuming it where something stopped it and killing it where its running
    call overran (RECORD): its wait status, and the overrun call in words (or None)."""
    overrun = None
    while True:
        try:
            done, status = os.waitpid(pid, os.WNOHANG | os.WUNTRACED)
        except InterruptedError:
            continue
        if done and os.WIFSTOPPED(status):
            os.kill(pid, signal.SIGCONT)
        elif done:
            return status, overrun
        elif overrun is None and (overrun := RECORD.overran()) is not None:
            os.kill(pid, signal.SIGKILL)
        time.sleep(POLL)


def _main_child(main, record, token, parent):
    _die_with_parent(parent)
    # The cap of the cases' processes holds here too, for what runs outside them (a derivation's import, the
    # studies): the machine's memory, which no run that it can hold needs more than.
    memory = machine_memory()
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    try:
        code = main()
    except SystemExit as error:  # argparse's --help and usage errors
        code = error.code if isinstance(error.code, int) else (0 if error.code is None else 2)
    except KeyboardInterrupt:  # wherever Ctrl-C lands that main does not expect it
        print("dyncheck: interrupted", file=sys.stderr)
        code = 130
    except Exception:  # dyncheck's own error (a case's is caught where it runs): said so, not blamed on the case
        traceback.print_exc()
        print("dyncheck: internal error: the traceback above is dyncheck's own, not the case's", file=sys.stderr)
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    record.done(code, token)
    os._exit(code)


# -- a case's own Python file ------------------------------------------------------------------------

def load_file(path, what):
    """The Python file at `path` as a module, loaded once per content of the file (an edited file is
    loaded again: a researcher fixing a derivation between two runs in one process gets the fix);
    `what` names it in the ValueError of a file that cannot be loaded."""
    path = Path(path).resolve()
    try:
        code = path.read_bytes()
    except OSError as error:
        raise ValueError(f"{what}: cannot read {path}: {error.strerror or error}") from None
    name = f"dyncheck_file_{hashlib.sha256(code).hexdigest()[:16]}_{abs(hash(str(path))):x}"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:  # foreign code: bounded in time, its exit an error (isolation)
            guarded(what, lambda: guarded_call(str(path), "import", IMPORT_BUDGET,
                                                         spec.loader.exec_module, module))
        except BaseException:
            del sys.modules[name]
            raise
    return sys.modules[name]


def guarded(what, call):
    """call(), with whatever a case's own code raises (or its sys.exit) as a ValueError naming `what`:
    bad input, exit 2, never a traceback or a silent exit."""
    try:
        return call()
    except (ValueError, DerivationError) as error:
        raise ValueError(f"{what}: {error}") from None
    except (Exception, SystemExit) as error:
        raise ValueError(f"{what}: {type(error).__name__}: {error}") from None


def call_cost(call, first):
    """The cost of a call, s: the least of up to COST_CALLS more calls, within COST_TIME, after the first (which
    took `first` s and pays for numpy's first use of each function it calls)."""
    least, spent = first, first
    for _ in range(COST_CALLS):
        if spent > COST_TIME:
            break
        start = time.perf_counter()
        call()
        took = time.perf_counter() - start
        least, spent = min(least, took), spent + took
    return least


# The calls that measure a derivation's cost: the least of 10 is within a few per cent of its steady cost, and 0.05 s
# bounds what a slow derivation (a generated 7-dof arm, 2-6 ms a call) spends on it.
COST_CALLS, COST_TIME = 10, 0.05
