"""Throughput of each source and the harness's overhead over the bare engine loop, measured side by side.

Each ratio compares two timings taken in the same run on the same machine: the harness's way of
doing a thing against the engine doing the same thing with nothing around it.  Times are the
median of `repeat` runs.
"""

import copy
import statistics
import time

import mujoco
import mujoco.rollout
import numpy as np
import pandas as pd
import pinocchio as pin


def _median_time(run, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def bench_case(case, steps=2000, repeat=5):
    """Rows: source, what, count, median seconds, rate per second, and the ratio to its bare loop."""
    q0, v0, _ = case.initial
    dt = case.integration["mujoco_step"]
    sample = case.sample_states()
    rows = []

    mj = case.model("mujoco")
    m = copy.copy(mj.m)
    m.dof_armature[:] = mj.armature
    m.opt.timestep, m.opt.integrator = dt, mujoco.mjtIntegrator.mjINT_RK4
    d = mujoco.MjData(m)
    mj._set_state(0.0, q0, v0, d)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, state0, spec)

    def bare_step():
        mujoco.mj_setState(m, d, state0, spec)
        mujoco.mj_step(m, d, nstep=steps)

    bare = _median_time(bare_step, repeat)
    rollout = _median_time(lambda: mujoco.rollout.rollout(m, d, state0[None], nstep=steps), repeat)
    harness = _median_time(lambda: mj.step(q0, v0, steps * dt, dt, "RK4"), repeat)
    rows += [("mujoco", "mj_step(nstep), RK4", steps, bare, 1.0),
             ("mujoco", "mujoco.rollout, RK4", steps, rollout, rollout / bare),
             ("mujoco", "harness MujocoModel.step (rollout + book coordinates)", steps, harness, harness / bare)]

    pn = case.model("pinocchio")
    configs = [(pn._configuration(t, q), pn._velocity(t, q, v)) for t, q, v in sample]
    zeros = np.zeros(pn.m.nv)
    bare_aba = _median_time(lambda: [pin.aba(pn.m, pn.d, c, w, zeros) for c, w in configs], repeat)
    harness_acc = _median_time(lambda: [pn.accelerations(t, q, v) for t, q, v in sample], repeat)
    rows += [("pinocchio", "pin.aba loop", len(sample), bare_aba, 1.0),
             ("pinocchio", "harness PinocchioModel.accelerations", len(sample), harness_acc, harness_acc / bare_aba)]

    for source in ("reference", "book"):
        model = case.model(source)
        elapsed = _median_time(lambda: [model.accelerations(t, q, v) for t, q, v in sample], repeat)
        rows.append((source, "accelerations loop", len(sample), elapsed, float("nan")))
    frame = pd.DataFrame(rows, columns=["source", "what", "count", "median s", "ratio to bare"])
    frame.insert(0, "case", case.name)
    frame["per second"] = frame["count"] / frame["median s"]
    return frame
