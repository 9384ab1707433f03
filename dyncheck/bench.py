"""`dyncheck bench`: throughput of each source on a case's scene, and the harness's overhead over the
bare engine doing the same work, timed side by side in the same run.

Each row: source, what, count (steps, states or right-hand-side evaluations), the median wall time of
`repeat` runs, the rate per second, and the ratio of its time per item (seconds / count) to that of
the row named in `against` (its bare loop; a bare row itself has ratio 1), with BOUND beside it and
"EXCEEDED" where the ratio is beyond it.  The rows of a comparison
are timed in turns, so that a change of the machine's load falls on both alike.  The bare loops are
engines/bench.py's (`MujocoLoops`, `pinocchio_steps`, `pinocchio_rhs`): only engines/ calls the engines.

MuJoCo, the scene as `MujocoModel.step` steps it (armature back, RK4 at the case's step, the same
constant generalized forces) from the case's initial state:
  - "mj_step(nstep), RK4": one call stepping `steps` steps: the bare loop.
  - "rollout, RK4": `mujoco.rollout` of the same steps.
  - "harness step": `MujocoModel.step`, which is rollout plus a copy of the model, the book's
    coordinates of every step (vectorised, the top's Euler angles and rates too) and the drift of
    the driven rates; against mj_step, and against rollout, the engine call it makes.
  - batched: rollout of 64 starts (the case's, its coordinates shifted by k mrad or mm) in one call,
    on one thread and on two, against 64 calls of one start each.
  - where something does work: `drive_powers` over the states of a run (the work integral of a
    MuJoCo run needs the power at every step) against `drive_power` state by state.
Pinocchio:
  - "harness accelerations" at the pointwise check's states, as the pointwise and random-parameter
    checks ask for them (`PinocchioModel.accelerations_many`, all the states in one call), against
    "pin.<engine> loop": the engine step alone (`PinocchioModel.engine_dynamics`: the generalized forces,
    then ABA when nothing is prescribed, else RNEA with the prescribed accelerations and, if anything is
    free, CRBA's free block solved; the work any Pinocchio user does for the scene) on the same states
    already in Pinocchio's configuration.  The harness does more: the question is asked in the book's
    coordinates.  Their conversions (cos and sin of each angle, the prescribed motions at t, the top's
    quaternions and angular velocities, its Euler-angle accelerations back) are made in numpy over all
    the states, a few tenths of a microsecond each, against an engine step of 1.5-3 us on these
    few-joint scenes (ABA); the engine step goes state by state, as in the bare loop, and its answers
    are gathered into one array.  State by state, `accelerations` costs 1.5-4 times the bare loop, the
    top's ~18 times (its conversions on one state's Python floats, ~10 us).
  - "DOP853, harness simulate": `simulate(pinocchio, "DOP853")`, whose right-hand side asks the
    harness for the accelerations and the drive power (one engine step per state, remembered),
    against "DOP853, bare pin.<engine> rhs": `solve_ivp` with the same method, tolerances, span
    and output times over a right-hand side written for Pinocchio alone, in its own state: the
    joints' positions and rates, made a configuration by `pin.integrate` from the neutral one, or
    the top's quaternion and angular velocity (q' = q (w, 0) / 2).  This is the overhead that
    matters for a run.  The harness integrates the top in the same state (its `native`
    coordinates, dyncheck.run.simulate) and converts to the Euler angles at the outputs only, so both
    take the same steps.
Reference and book: the accelerations state by state; and where a source's accelerations, as
written, take many states as columns (closed forms in numpy), one call over 10000 states against
the loop.  The numerical Newton-Euler references (chains of frames, linear
solves) take one state at a time: vectorising them would mean writing their equations twice.
"""

import contextlib
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

from dyncheck.checks.runs import run_case
from dyncheck.run import cache
from dyncheck.run.simulate import simulate
from engines.bench import MujocoLoops, pinocchio_rhs, pinocchio_steps

BOUND = 1.5  # the most a harness row may cost per item over its bare loop (issue 17): "EXCEEDED" beyond
BATCH = 64  # initial conditions in the batched rollouts
SPAN = 0.5  # s of integration in the scipy pair


def _timed(run):
    """`run` made to return its wall time."""
    def timed():
        start = time.perf_counter()
        run()
        return time.perf_counter() - start
    return timed


def _measure(source, entries, repeat):
    """Rows (source, what, count, median seconds, against) of entries (what, count, run, against); each
    run returns its wall time.  The runs take turns, so that a change of the machine's load falls on
    a row and its bare row alike."""
    times = [[] for _ in entries]
    for _ in range(repeat):
        for (_, _, run, _), out in zip(entries, times):
            out.append(run())
    return [(source, what, count, statistics.median(t), against)
            for (what, count, _, against), t in zip(entries, times)]


def bench_table(cases, run_all=None):
    """`dyncheck bench`'s table of `cases`: their throughput rows (bench_case) and, with `run_all` (the command line's
    run_cases), their whole runs (bench_runs).  A case whose applied forces vary, or whose coordinates are a map of
    the joints, has no throughput rows (no bare loop evaluates a law of the state or maps the coordinates:
    engines.bench), which a line under the table says; its whole runs are timed."""
    frames, varying, mapped = [], [], []
    for case in cases:
        if case.model("mujoco").varying:
            varying.append(case.name)
        elif case.scene.coordinate_map:
            mapped.append(case.name)
        else:
            frames.append(bench_case(case))
    if run_all is not None:
        frames.append(bench_runs(cases, run_all))
    untimed = "; ".join(f"no throughput rows of {', '.join(names)}: {why}, which no bare engine loop {does} (--runs "
                        "times its whole runs)" for names, why, does in (
                            (varying, "its applied forces vary", "evaluates"),
                            (mapped, "its coordinates are a map of the joints (scene.joints)", "maps")) if names)
    if not frames:
        return untimed
    table = pd.concat(frames, ignore_index=True)
    table["ratio to bare"] = table["ratio to bare"].map(lambda x: "-" if pd.isna(x) else f"{x:.3g}")  # no bare loop
    return "\n".join(filter(None, (table.to_string(index=False, float_format=lambda x: f"{x:.3g}"), untimed)))


def bench_case(case, steps=2000, repeat=5):
    """Rows: source, what, count, median seconds, per second, the ratio per item to the bare row
    `against` (1 for a bare row itself)."""
    rows = _mujoco_rows(case, steps, repeat) + _pinocchio_rows(case, repeat) + _equation_rows(case, repeat)
    frame = pd.DataFrame(rows, columns=["source", "what", "count", "median s", "against"])
    frame.insert(0, "case", case.name)
    return _table(frame)


def _table(frame, bound=BOUND):
    """The rows with their rate, their ratio to the row they are measured against, and `bound` on it (None: the
    ratio is a measurement, not held to a bound)."""
    frame["per second"] = frame["count"] / frame["median s"]
    keys = list(zip(frame["case"], frame["source"]))
    cost = {(c, s, w): t / n for (c, s), w, n, t in zip(keys, frame["what"], frame["count"], frame["median s"])}
    bare = {(c, s, a) for (c, s), a in zip(keys, frame["against"])}
    frame["ratio to bare"] = [cost[c, s, w] / cost[c, s, a] if a else (1.0 if (c, s, w) in bare else np.nan)
                              for (c, s), w, a in zip(keys, frame["what"], frame["against"])]
    compared = (frame["against"] != "") & (bound is not None)
    frame["bound"] = np.where(compared, f"{bound:g}" if bound else "", "")
    frame["mark"] = np.where(compared & (frame["ratio to bare"] > (bound or np.inf)), "EXCEEDED", "")
    return frame[["case", "source", "what", "count", "median s", "per second", "ratio to bare", "bound", "mark",
                  "against"]]


def bench_runs(cases, run_all, repeat=3):
    """Whole runs side by side (`dyncheck bench --runs`), in the table of bench_case: each case's checks
    (`run_case`, without the findings' localisation, as `dyncheck run` runs them) with an empty cache of tight
    solutions against with the cache that run left; the command `dyncheck run --quick` of the case against
    `dyncheck run` of it, each in a process of its own as a terminal starts it (its imports and the case's loading
    included), with that cache; and all the cases one after another in this process against `run_all` (the command
    line's run_cases), one process per core.  Minutes: a whole run per row and repeat."""
    rows = []
    with tempfile.TemporaryDirectory() as folder, _cache_in(folder):
        for case in cases:
            def cold():
                shutil.rmtree(cache.folder(), ignore_errors=True)
                return _timed(lambda: run_case(case, localise=False))()
            computed = "run_case, tight solutions computed (empty cache)"
            full = "dyncheck run, the command"
            rows += [(case.name,) + r for r in _measure("harness", [
                (computed, 1, cold, ""),
                ("run_case, tight solutions from the cache", 1, _timed(lambda: run_case(case, localise=False)),
                 computed),
                (full, 1, _timed(lambda: _command(case)), ""),
                ("dyncheck run --quick, the command", 1, _timed(lambda: _command(case, "--quick")), full)], repeat)]
    was, cache.enabled = cache.enabled, False
    try:
        one = f"{len(cases)} cases in one process"
        rows += [("all",) + r for r in _measure("harness", [
            (one, len(cases), _timed(lambda: run_all(cases, False, workers=1)), ""),
            (f"{len(cases)} cases, one process per core ({os.cpu_count()})", len(cases),
             _timed(lambda: run_all(cases, False)), one)], repeat)]
    finally:
        cache.enabled = was
    return _table(pd.DataFrame(rows, columns=["case", "source", "what", "count", "median s", "against"]), bound=None)


def _command(case, *options):
    """`dyncheck run` of `case` (its folder, its overrides) with `options`, in a process of its own running this
    checkout's dyncheck; RuntimeError where it does not give a verdict (exit 0 or 1)."""
    checkout = str(Path(__file__).resolve().parents[1])
    overrides = [f"--set={name}={value!r}" for name, value in case.overrides.items()]
    done = subprocess.run([sys.executable, "-m", "dyncheck", "run", case.name, "--cases", str(case.folder.parent),
                           *overrides, *options], capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, (
                              checkout, os.environ.get("PYTHONPATH"))))})
    if done.returncode not in (0, 1):
        raise RuntimeError(f"dyncheck run {case.name} {' '.join(options)}: exit {done.returncode}: "
                           f"{done.stderr.strip()[-500:]}")


@contextlib.contextmanager
def _cache_in(folder):
    """The cache of tight solutions in `folder` meanwhile."""
    before = os.environ.get("DYNCHECK_CACHE")
    os.environ["DYNCHECK_CACHE"] = folder
    try:
        yield
    finally:
        if before is None:
            del os.environ["DYNCHECK_CACHE"]
        else:
            os.environ["DYNCHECK_CACHE"] = before


def _mujoco_rows(case, steps, repeat):
    mj = case.model("mujoco")
    q0, v0, _ = case.initial
    dt = case.integration["mujoco_step"]
    bare = MujocoLoops(mj, q0, v0, dt, "RK4")
    step, roll, harness = "mj_step(nstep), RK4", "rollout, RK4", "harness step"
    rows = _measure("mujoco", [(step, steps, _timed(lambda: bare.mj_step(steps)), ""),
                               (roll, steps, _timed(lambda: bare.rollout(steps)), step),
                               (harness, steps, _timed(lambda: mj.step(q0, v0, steps * dt, dt, "RK4")), step)],
                    repeat)
    rows.append(rows[-1][:-1] + (roll,))  # the harness step against rollout too

    starts = np.array([bare.engine_start(q0 + 1e-3 * k, v0) for k in range(BATCH)])
    nstep = steps // 8
    loop = f"{BATCH} rollouts of 1 start"
    rows += _measure("mujoco", [
        (loop, BATCH * nstep, _timed(lambda: [bare.rollout(nstep, s[None]) for s in starts]), ""),
        (f"rollout of {BATCH} starts", BATCH * nstep, _timed(lambda: bare.rollout(nstep, starts)), loop),
        (f"rollout of {BATCH} starts, 2 threads", BATCH * nstep,
         _timed(lambda: bare.rollout(nstep, starts, threads=2)), loop)],
        repeat)

    if case.driven:
        run = mj.step(q0, v0, steps * dt, dt, "RK4")
        states = list(zip(run["t"], run["q"], run["v"]))
        single = "harness drive_power per state"
        rows += _measure("mujoco", [
            (single, len(states), _timed(lambda: [mj.drive_power(*s) for s in states]), ""),
            ("harness drive_powers, one call", len(states),
             _timed(lambda: mj.drive_powers(run["t"], run["q"], run["v"])), single)], repeat)
    return rows


def _pinocchio_rows(case, repeat):
    pn = case.model("pinocchio")
    sample = case.sample_states() * 10
    engine_states = [pn.engine_state(t, q, v) for t, q, v in sample]
    columns = [np.array(column) for column in zip(*sample)]  # t (N,), q and v (N, n)
    bare = f"pin.{pn.algorithm} loop"
    rows = _measure("pinocchio", [
        (bare, len(sample), _timed(lambda: pinocchio_steps(pn, engine_states)), ""),
        ("harness accelerations", len(sample), _timed(lambda: pn.accelerations_many(*columns)), bare)], repeat)

    q0, v0, t_end = case.initial
    span, setting = min(SPAN, t_end), case.integration
    grid = np.linspace(0.0, span, int(round(span / setting["output_step"])) + 1)
    rhs, y0 = pinocchio_rhs(pn, q0, v0, work=case.driven)
    evaluations = {}

    def bare_run():
        start = time.perf_counter()
        solution = solve_ivp(rhs, (0.0, span), y0, method="DOP853", t_eval=grid, rtol=setting["rtol"],
                             atol=setting["rtol"])
        evaluations["bare"] = solution.nfev
        return time.perf_counter() - start

    def harness_run():
        run = simulate(pn, (q0, v0), span, "DOP853", rtol=setting["rtol"], output_step=setting["output_step"],
                       work=case.driven)
        evaluations["harness"] = run.attrs["evaluations"]
        return run.attrs["wall"]  # the integration, not the reactions and energy at the output times

    bare = f"DOP853, bare pin.{pn.algorithm} rhs"
    timed = _measure("pinocchio", [(bare, 0, bare_run, ""), ("DOP853, harness simulate", 0, harness_run, bare)],
                     repeat)
    return rows + [row[:2] + (evaluations[key],) + row[3:] for row, key in zip(timed, ("bare", "harness"))]


def _equation_rows(case, repeat):
    """The reference and the book: state by state, and many states as columns where the code allows."""
    sample = case.sample_states()
    many = sample * 100
    columns = (np.array([t for t, _, _ in many]), np.array([q for _, q, _ in many]).T,
               np.array([v for _, _, v in many]).T)
    rows = []
    for source in ("reference", "book"):
        model = case.model(source)
        loop = "accelerations per state"
        entries = [(loop, len(sample), _timed(lambda: [model.accelerations(t, q, v) for t, q, v in sample]), "")]
        if case.coords and _takes_columns(model, many, columns):
            entries.append((f"accelerations, {len(many)} in one call", len(many),
                            _timed(lambda: model.accelerations(*columns)), loop))
        rows += _measure(source, entries, repeat)
    return rows


def _takes_columns(model, states, columns):
    """Whether `model.accelerations` of states given as columns equals its state-by-state values."""
    try:
        with np.errstate(all="raise"):
            at_once = np.asarray(model.accelerations(*columns), dtype=float)
    except (ValueError, TypeError, IndexError, FloatingPointError):
        return False
    one_by_one = np.array([model.accelerations(t, q, v) for t, q, v in states[:100]]).T
    return at_once.shape == (len(one_by_one), len(states)) and np.allclose(
        at_once[:, :100], one_by_one, rtol=1e-12, atol=1e-12 * np.max(np.abs(one_by_one)))
