"""What the pages' figures and animation draw along a run, computed where the checks run the engines (the pages
import no engine): the traced bodies' paths and the scene's skeleton (`drawings`), and the animation's frames
(`frames`: when they are taken, and the skeleton at each from MuJoCo's forward kinematics, engines.render)."""

import math

import numpy as np

from dyncheck.results.values import Frames
from dyncheck.run.simulate import fastest_frequency


def with_paths(case, run):
    """`run` with the world coordinates of the case's traced bodies'
    centres of mass (<body>_x, _y, _z) as columns, for the case's figures and values
    (dyncheck.common.expressions.namespace): computed here, where the engines are, so that the report
    needs none."""
    if not case.scene.paths:
        return run
    positions = case.model("mujoco").paths_many(run.index.to_numpy(), run[list(case.coords)].to_numpy())  # (time, body, xyz)
    out = run.copy()
    for b, body in enumerate(case.scene.paths):
        for i, axis in enumerate("xyz"):
            out[f"{body}_{axis}"] = positions[:, b, i]
    out.attrs = dict(run.attrs)
    return out


def drawings(case, runs):
    """The scene at t = 0 for the report's scene figure, beside the animation's first frame: the world positions of
    the body origins; None when the tight reference blew up (nothing is drawn along it)."""
    if not runs["reference"].ok:
        return {"scene": None}
    tight = runs["reference"].twin
    _, origins, _ = case.model("mujoco").points(0.0, tight[list(case.coords)].to_numpy()[0])
    return {"scene": {"origins": origins}}


# When frames are taken: often enough for the fastest motion shown, no oftener than a slow motion needs.
FRAMES_PER_PERIOD = 8  # a period (or a turn) of the fastest motion shown takes at least 8 frames
SLOW_FRAMES = 100  # a slow motion: at most 100 frames ...
MIN_INTERVAL = 0.05  # ... at least 50 ms apart, which play about in real time
# A GIF stores each frame's change from the one before (about 2 to 5 kB at 64 colours): at most 500 frames
# keeps a GIF under about 2 MB.  A run that needs more is shown over its first 500 frames (the caption says so).
MAX_FRAMES = 500
def frame_rows(run, omega):
    """The rows of `run` (a DataFrame indexed by t) that are the animation's frames: evenly spaced, at least
    FRAMES_PER_PERIOD in a period 2 pi / omega of the fastest motion shown (`omega` in rad/s; 0 for none),
    else as a slow motion (at most SLOW_FRAMES, at least MIN_INTERVAL apart); the first MAX_FRAMES of them."""
    t = run.index.to_numpy()
    step = (t[-1] - t[0]) / max(len(t) - 1, 1)
    if not step:
        return np.arange(len(t))[:MAX_FRAMES]
    slow = max(math.ceil((len(t) - 1) / (SLOW_FRAMES - 1)), math.ceil(MIN_INTERVAL / step - 1e-9))
    fast = math.floor(2 * math.pi / (FRAMES_PER_PERIOD * omega) / step + 1e-9) if omega else slow
    return np.arange(0, len(t), max(min(slow, fast), 1))[:MAX_FRAMES]


def fastest_shown(case, runs):
    """The fastest motion the animation shows, rad/s: the case's fastest frequency (simulate.fastest_frequency)
    or the fastest turn of an angle along the runs ({label: run}), whichever is faster; 0 for neither."""
    angles = [c for c, unit in zip(case.coords, case.spec.get("coord_units", [])) if unit == "rad"]
    rates = [np.nanmax(np.abs(run[f"{c}_rate"].to_numpy())) for run in runs.values() for c in angles
             if f"{c}_rate" in run and len(run)]
    return max([fastest_frequency(case) or 0.0, *rates])


def at_times(run, times):
    """The rows of `run` nearest to `times` (a run that stopped earlier holds its last row)."""
    t = run.index.to_numpy()
    return np.clip(np.searchsorted(t, times - 1e-9), 0, len(t) - 1)


def animated_runs(case, runs, program):
    """{label: run} that the animation draws: "exact" (the tight reference solution) and, with
    `[animation] program`, "program" (the book's program's run)."""
    shown = {"exact": runs["reference"].twin}
    if case.spec.get("animation", {}).get("program") and program.get("listing") is not None:
        shown["program"] = program["listing"]
    return shown


def frames(case, runs, program):
    """{label: Frames} of every animated run, at the exact run's frame times, from MuJoCo's forward
    kinematics; {} where the reference's run failed (nothing to animate)."""
    if not runs["reference"].ok:
        return {}
    from engines.render import skeleton  # only here, where the checks run the engines
    model = case.model("mujoco")
    exact = runs["reference"].twin
    shown = animated_runs(case, runs, program)
    times = exact.index.to_numpy()[frame_rows(exact, fastest_shown(case, shown))]
    out = {}
    for label, run in shown.items():
        q = run[list(case.coords)].to_numpy()[at_times(run, times)]
        out[label] = Frames(times, *skeleton(model, times, q))
    return out
