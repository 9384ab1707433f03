"""Work-precision and convergence: what each integrator and engine pays for its accuracy.

`sweep(case)` runs every method over a tolerance or step sweep against one named reference
solution and returns tidy rows; `figure` draws them log-log, `cheapest` says which method reaches
each accuracy level first.  `convergence(case)` gives the observed order of every fixed-step
method as check rows.  Both read the case file's [work_precision] table.
"""

import math
import time
from collections import Counter

import numpy as np
import pandas as pd

from dyncheck import cache, ceilings
from dyncheck.ceilings import ROUNDING_FLOOR
from dyncheck.messages import plural
from dyncheck.results import Status, heading, no_number, row
from dyncheck.schema import MAX_OUTPUTS
from dyncheck.simulate import (FIXED_METHODS, LEAST_RTOL, MAX_STEPS, METHODS, MUJOCO_METHODS, SCIPY_METHODS, Unstable,
                               energy_residual, fastest_frequency, simulate, state_columns)
from dyncheck.style import METHOD_COLOUR, SWEEP_STYLE, legend_below, log_range, panels, save, title
from dyncheck.vibration import jacobian, scales_of

COLUMNS = ["case", "source", "method", "setting", "value", "error", "energy_error", "cpu", "cpu_min", "cpu_max",
           "repeats", "evaluations", "steps", "status", "resolved", "detail"]
# A timed run's cost is its CPU time (simulate's attrs["cpu"]): the wall time it takes on an idle core, which
# other processes' load leaves out (three busy processes on this 2-core machine stretched wall times 2.6x and
# their spreads 5-15x, CPU times by 4-11%).  CPU times still differ from run to run: the pages and their CSV
# leave them out (a report made twice is the same), and the timing files (write_csv(..., timing=True),
# figure(..., cost="cpu")) carry them.
TIMING_COLUMNS = ["cpu", "cpu_min", "cpu_max", "repeats"]
COSTS = {"evaluations": "right-hand-side evaluations", "cpu": "CPU time [s], median (bars: fastest to slowest)"}
COST_WORDS = {"evaluations": "right-hand-side evaluations", "cpu": "CPU time (the fastest of repeated runs)"}
NO_SWEEP = ("Nothing to integrate: every motion of this scene is prescribed (no free coordinate), so it "
            "has no work-precision chart and no convergence check.")
EVALUATIONS_NOTE = ("Cost is counted in right-hand-side evaluations (MuJoCo's RK4: 4 a step, its Euler: 1), "
                    "which compare the methods whatever steps them.")
CPU_NOTE = ("MuJoCo steps in C (its rollout) and every other method in Python around its right-hand side, so "
            "across engines CPU time measures the harness as much as the method.")
# A point whose error is within this factor of the reference solution's verified accuracy cannot be
# told apart from the reference's own error: it is drawn hollow and never counts as reaching a level.
RESOLUTION = 10.0
LEVELS = (1e-2, 1e-4, 1e-6, 1e-8, 1e-10)
EXPECTED_ORDER = {name: method.order for name, method in METHODS.items() if method.order}  # the fixed steps
ENGINES = ("pinocchio", "mujoco")  # a sweep's engine sources, named in its chart's legend
GLYPHS = {"o": "\u25cb", "s": "\u25a1", "^": "\u25b3", "-": "\u2014", "--": "- -", ":": "\u00b7\u00b7\u00b7"}  # legend title
SWEEP_METHODS = {"reference": SCIPY_METHODS + FIXED_METHODS, "pinocchio": SCIPY_METHODS, "mujoco": MUJOCO_METHODS}
KEYS = ("t_end", "output_step", "repeat", "repeat_under", "why", "solution", "sweep", "convergence")
CONVERGENCE_KEYS = ("omega", "omega_t", "omega_h", "why")
OPTIONAL_KEYS = ("method_omega",)
MAX_REPEAT = 100  # timed repetitions of a quick run (under repeat_under seconds in all)
# Timed runs of the points that decide which method is cheapest in CPU time (cheapest()), which ranks the
# points by their fastest run.  What slows a run (caches, the other core's work, the host's other tenants)
# only adds time, and on this machine it added it to most runs of a point now and then, even idle and in CPU
# time: between three idle regenerations of the sweeps a point's median moved by up to 2.1x (1.7x at the 90th
# percentile), its fastest run by 4% (median), 9% (90th percentile), 13% (95th).  Interquartile ranges and
# median absolute deviations of five runs named ties 1.7x apart and left 5 of 20 cells unreproduced.
DECIDING_REPEATS = 5
# Two fastest runs closer than this fraction of the faster cannot be told apart: each moves by up to ~10%
# between regenerations (above), and their ratio with both.
REPRODUCIBILITY = 0.20


# -- the case file's [work_precision] table ---------------------------------------------------------

def settings(case):
    """The case's [work_precision] table, checked (ValueError names the file and the field); None
    for a case without one (nothing to integrate)."""
    spec = case.spec.get("work_precision")
    if spec is None:
        return None

    def fail(field, why):
        raise ValueError(f"{case.origin}: work_precision.{field} {why}")

    def positive(field, x):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not 0 < x < math.inf:
            fail(field, f"= {x!r} must be a positive finite number")
        return float(x)

    def within(field, x, count, limit, what):  # the bounds of a run's size (schema.MAX_OUTPUTS, simulate.MAX_STEPS)
        if count > limit:
            fail(field, f"= {x:g} asks for {count:.3g} {what}, more than the {limit:.0e} a run allows")

    def multiple(field, step, of):
        if abs(of / step - round(of / step)) > 1e-9 * of / step:
            fail(field, f"= {step:g} must divide {of:g} s (outputs and horizons fall on steps)")

    def honoured(field, rtol):  # scipy raises a smaller rtol to LEAST_RTOL: the point would not be the one it says
        if rtol < LEAST_RTOL:
            fail(field, f"= {rtol:g} is below {LEAST_RTOL:.3g}, the least rtol scipy's integrators honour "
                        "(dyncheck.simulate.LEAST_RTOL)")
        return rtol

    for table, keys, field in ((spec, KEYS, ""), (spec.get("convergence", {}), CONVERGENCE_KEYS, "convergence.")):
        for key in (set(keys) ^ set(table)) - set(OPTIONAL_KEYS):
            fail(field + key, "is missing" if key in keys else
                 f"is not a known key; expected {', '.join(keys + OPTIONAL_KEYS)}")
    out = {key: positive(key, spec[key]) for key in ("t_end", "output_step", "repeat_under")}
    if not isinstance(spec["repeat"], int) or not 1 <= spec["repeat"] <= MAX_REPEAT:
        fail("repeat", f"= {spec['repeat']!r} must be an integer from 1 to {MAX_REPEAT}")
    out["repeat"] = spec["repeat"]
    multiple("output_step", out["output_step"], out["t_end"])
    within("output_step", out["output_step"], out["t_end"] / out["output_step"], MAX_OUTPUTS, "output rows per run")
    out["solution"] = {key: positive(f"solution.{key}", spec["solution"].get(key)) for key in ("rtol", "max_step")}
    honoured("solution.rtol", out["solution"]["rtol"])
    within("solution.max_step", out["solution"]["max_step"], out["t_end"] / out["solution"]["max_step"], MAX_STEPS,
           "steps")
    out["sweep"] = {}
    for source, methods in spec["sweep"].items():
        if source not in SWEEP_METHODS:
            fail(f"sweep.{source}", f"is not a source of the sweep ({', '.join(SWEEP_METHODS)})")
        for method, values in methods.items():
            field = f"sweep.{source}.{method}"
            if method not in SWEEP_METHODS[source]:
                fail(field, f"is not a method of the sweep; {source} runs {', '.join(SWEEP_METHODS[source])}")
            values = [positive(field, x) for x in values]
            if method in SCIPY_METHODS:
                values = [honoured(field, rtol) for rtol in values]
            else:
                for dt in values:
                    multiple(field, dt, out["output_step"])
                    within(field, dt, out["t_end"] / dt, MAX_STEPS, "steps")
            out["sweep"].setdefault(source, {})[method] = values
    # The convergence runs are set in units of the scene's fastest frequency omega (an expression of
    # the parameters), so that they stay in the asymptotic range, and as cheap, when a parameter is
    # overridden: step h = omega_h / omega, horizon the whole number of steps nearest omega_t / omega.
    # A method that integrates other coordinates may see another fastest motion (`method_omega`: MuJoCo's
    # quaternions turn with the body's angular velocity, where the Euler angles see its nutation).
    conv = spec["convergence"]
    omega_t = positive("convergence.omega_t", conv["omega_t"])
    method_omega = conv.get("method_omega", {})
    if not isinstance(method_omega, dict) or set(method_omega) - set(conv["omega_h"]):
        fail("convergence.method_omega", f"= {method_omega!r} must be a table of methods of convergence.omega_h")
    out["convergence"] = {"steps": {}}
    for method, omega_h in conv["omega_h"].items():
        if method not in EXPECTED_ORDER:
            fail(f"convergence.omega_h.{method}", f"is not a fixed-step method ({', '.join(EXPECTED_ORDER)})")
        positive(f"convergence.omega_h.{method}", omega_h)
        within(f"convergence.omega_h.{method}", omega_h, 4 * omega_t / omega_h, MAX_STEPS, "steps (at h/4)")
        field = f"convergence.method_omega.{method}" if method in method_omega else "convergence.omega"
        omega = case.value(method_omega.get(method, conv["omega"]), f"work_precision.{field}")
        if not omega > 0:  # parameters may leave nothing to converge (g = 0): convergence() says so in a row
            out["convergence"]["steps"][method] = (None, None, omega)
            continue
        h = omega_h / omega
        out["convergence"]["steps"][method] = (h, max(1, round(omega_t / omega_h)) * h, omega)
    return out


def plan(case):
    """The sweep's points: (source, method, "rtol" | "dt", value), in the order sweep() runs them."""
    wp = settings(case)
    if wp is None:
        return []
    return [(source, method, "rtol" if method in SCIPY_METHODS else "dt", value)
            for source, methods in wp["sweep"].items() for method, values in methods.items() for value in values]


# -- the reference solution ----------------------------------------------------------------------

def _dop853(case, t_end, output_step, rtol, max_step):
    """`reference` by DOP853 at rtol = atol with its step capped at `max_step`.  The cap matters:
    uncapped, DOP853 at 1e-13 takes a few long steps whose error its estimate misses (measured 1e-12
    to 3e-11 against Radau at 1e-13; capped at about half its mean step, 5e-14 to 1e-12)."""
    return cache.solution(case, "reference", case.initial[:2], t_end, "DOP853", rtol=rtol, max_step=max_step,
                          output_step=output_step, work=case.driven, omega=fastest_frequency(case))


def trajectory_error(run, reference, columns):
    """Largest state error over the run, each coordinate relative to its largest magnitude in the
    reference (as dyncheck.checks.trajectory)."""
    return max(float((run[c] - reference[c]).abs().max() / reference[c].abs().max()) for c in columns)


def reference_solution(case):
    """The sweep's reference solution, its label and its verified accuracy.

    The solution is DOP853 at the case's rtol with its step capped at `max_step`; the verification
    is the same at twice the cap, 2^8 times the local error of an 8th-order method, so their
    distance is the verification's own error and bounds the solution's (the case file records a
    one-off comparison with Radau at the same tolerance, a method of another family), but not below
    the rounding floor of a run."""
    wp = settings(case)
    rtol, max_step = wp["solution"]["rtol"], wp["solution"]["max_step"]
    solution = _dop853(case, wp["t_end"], wp["output_step"], rtol, max_step)
    verification = _dop853(case, wp["t_end"], wp["output_step"], rtol, 2 * max_step)
    distance = trajectory_error(verification, solution, state_columns(case))
    # Below a thousand ulps the distance is luck: rounding along the run is that large.
    accuracy = max(distance, ROUNDING_FLOOR)
    label = (f"DOP853, rtol = atol = {rtol:g}, steps <= {max_step:g} s; verified to {accuracy:.1e} "
             f"by the same with steps <= {2 * max_step:g} s" + ("" if distance >= ROUNDING_FLOOR else
                                                              f" ({distance:.1e} away; rounding floor)"))
    return solution, label, accuracy


# -- the sweep -------------------------------------------------------------------------------------

def _progress(progress, text):
    if progress is not None:
        progress(text)


def energy_error(run, scale=None):
    """max |E(t) - E(0) - W(t)| of `run` relative to `scale` (by default the run's own largest |E| or |W|);
    NaN for a run without energy or work (a derivation that defines no energy or drive_power)."""
    if "energy" not in run or "work" not in run:
        return np.nan
    scale = scale or max(run["energy"].abs().max(), run["work"].abs().max())
    return float(energy_residual(run).abs().max() / scale)


def sweep(case, progress=None):
    """Every method of the case's sweep against the reference solution: a DataFrame of COLUMNS, one row
    per point of plan(case), with the reference solution's label and accuracy in .attrs["reference"].

    error: max over time and state coordinates of |x - x_ref| / max |x_ref| (per coordinate);
    energy_error: max |E(t) - E(0) - W(t)| / max(|E_ref|, |W_ref|), the energy drift of a closed scene
    or the work-energy balance of a driven one (energy_error); cpu, cpu_min, cpu_max: median, least and most
    of the CPU times of `repeats` timed runs (`repeat` when one run takes under `repeat_under` seconds in all, else one; DECIDING_REPEATS
    for a point that decides the CPU-time table of cheapest()); evaluations: right-hand sides (MuJoCo: 1 or 4 per step);
    steps: fixed steps (NaN for scipy, which does not report them).  A run that blows up is a row
    with status "unstable", NaN errors and the time and step in `detail`.  resolved: whether the error
    is above RESOLUTION times the reference's verified accuracy.  An empty frame for a case with
    nothing to integrate (NO_SWEEP)."""
    wp = settings(case)
    if wp is None:
        return pd.DataFrame(columns=COLUMNS)
    reference, label, accuracy = reference_solution(case)
    columns = state_columns(case)
    # A derivation without energy() gives its runs none: their energy error is NaN, and the engines' runs
    # are judged against their own energy and work.
    scale = max(reference["energy"].abs().max(), reference["work"].abs().max()) \
        if {"energy", "work"} <= set(reference) else None
    q0, v0, _ = case.initial

    def timed(source, method, setting, value):  # one run of a point and the time it took in all
        start = time.perf_counter()
        run = simulate(case.model(source), (q0, v0), wp["t_end"], method, output_step=wp["output_step"],
                       work=case.driven, omega=fastest_frequency(case), **{setting: value})
        return run, time.perf_counter() - start

    rows, times, quick = [], {}, []  # times: row -> the CPU times of its runs; quick: rows to repeat at will
    for source, method, setting, value in plan(case):
        point = {"case": case.name, "source": source, "method": method, "setting": setting, "value": value}
        try:
            run, took = timed(source, method, setting, value)
        except Unstable as failure:
            rows.append({**point, "error": np.nan, "energy_error": np.nan, "evaluations": np.nan,
                         "steps": failure.step, "status": "unstable", "resolved": False,
                         "detail": f"unstable at t = {failure.t:.4g} s"
                                   + (f", step {failure.step}" if failure.step is not None else "") + f": {failure.why}"})
            _progress(progress, f"{case.name} {source} {method} {setting}={value:g}: unstable")
            continue
        error = trajectory_error(run, reference, columns)
        times[len(rows)] = [run.attrs["cpu"]]
        # Repeat only runs that are quick in all (integration, energy and work on the grid, for MuJoCo the
        # drive power at every step): timer noise matters there, and it bounds the cost.
        if took < wp["repeat_under"]:
            quick.append(len(rows))
        rows.append({**point, "error": error, "energy_error": energy_error(run, scale),
                     "evaluations": run.attrs["evaluations"], "steps": run.attrs.get("steps", np.nan), "status": "ok",
                     "resolved": bool(error > RESOLUTION * accuracy), "detail": ""})
        _progress(progress, f"{case.name} {source} {method} {setting}={value:g}: {error:.1e}")

    def frame():
        timing = pd.DataFrame([{"cpu": float(np.median(w)), "cpu_min": min(w), "cpu_max": max(w),
                                "repeats": len(w)}
                               for w in times.values()], index=list(times), columns=TIMING_COLUMNS)
        out = pd.DataFrame(rows).join(timing).reindex(columns=COLUMNS)
        out["repeats"] = out["repeats"].fillna(0).astype(int)  # an unstable point's: none timed to the end
        out.attrs["reference"] = {"label": label, "accuracy": accuracy, "t_end": wp["t_end"]}
        return out

    def again(points):  # one more timed run of each point, in the sweep's order
        for i in points:
            times[i].append(timed(*(rows[i][key] for key in ("source", "method", "setting", "value")))[0].attrs["cpu"])

    # More runs go round the points, not back to back, so that a change of the machine's load during the
    # sweep falls on every point alike (runs back to back share one load and understate the spread): the
    # quick points up to `repeat` runs, for the chart's bars; then the points that decide the CPU-time
    # table (at each level the cheapest, those tied with it and the runner-up) up to DECIDING_REPEATS
    # runs whatever they cost, for a claim that one is faster than another.
    for _ in range(wp["repeat"] - 1):
        again(quick)
    while True:
        table = cheapest(frame(), cost="cpu")
        named = {label for labels in table["points"] for label in labels} | set(table["runner_up"])
        deciding = [i for i in times if point_label(rows[i]) in named
                    and len(times[i]) < max(wp["repeat"], DECIDING_REPEATS)]
        if not deciding:
            return frame()
        again(deciding)


def write_csv(frame, path, timing=False):
    """The tidy rows, with the reference solution named in a comment line above the header: without the
    CPU times, or (timing) the points' keys with only their CPU times."""
    keys = ["case", "source", "method", "setting", "value"]
    columns = keys + TIMING_COLUMNS if timing else [c for c in frame.columns if c not in TIMING_COLUMNS]
    with open(path, "w") as f:
        if "reference" in frame.attrs:
            f.write(f"# {frame.attrs['reference']['label']}\n")
        frame[columns].to_csv(f, index=False)


# -- which method is cheapest ----------------------------------------------------------------------

def point_label(r):
    """E.g. "reference DOP853, rtol = 1e-08", "mujoco:RK4, dt = 0.005 s"."""
    name = r["method"] if r["method"].startswith(r["source"] + ":") else f"{r['source']} {r['method']}"
    return f"{name}, {r['setting']} = {r['value']:g}" + (" s" if r["setting"] == "dt" else "")


TIE_WORDS = {"evaluations": "tie: equal counts", "cpu": f"tie: fastest runs within {REPRODUCIBILITY:.0%}"}


def tie_in_words(points, cost):
    """"A", or for several points "A or B (tie ...)", the points of one method and setting from several
    sources named once: "reference and pinocchio LSODA, rtol = 0.0001"."""
    names = []
    for _, same in points.groupby(["method", "setting", "value"], sort=False):
        label, source = point_label(same.iloc[0]), same["source"].iloc[0]
        names.append(" and ".join(same["source"]) + label[len(source):] if label.startswith(source + " ") else label)
    return names[0] if len(points) == 1 else f"{' or '.join(names)} ({TIE_WORDS[cost]})"


def cheapest(frame, cost="evaluations", levels=LEVELS):
    """For each accuracy level (relative trajectory error), the (source, method) that reaches it at the least
    `cost` (a column: "evaluations" or "cpu"), those that cannot be told from it, and the runner-up, the
    cheapest of the rest: a DataFrame with level, cheapest (in words: "A", or "A or B (tie ...)"), points and
    methods (the labels and method names of the cheapest and the tied, in the sweep's order), <cost> and error
    (of the cheapest; in CPU time its fastest run), runner_up, runner_up_<cost>.  Each (source, method) stands
    by its point of fewest evaluations that reaches the level: a count, the same in every run, and within one
    method CPU time follows it.  Evaluations are counts: a tie is an equal count.  CPU times rank by each
    point's fastest run (see DECIDING_REPEATS): one method is ahead of another only when its fastest run is
    faster by more than REPRODUCIBILITY of its own, else they tie.  Only resolved points count; a level below
    RESOLUTION times the reference's accuracy cannot be decided and says so, a level nobody reaches says
    "none reached"."""
    floor = RESOLUTION * frame.attrs.get("reference", {}).get("accuracy", 0.0)
    ok = frame[(frame["status"] == "ok") & frame["resolved"]]
    ranked = "cpu_min" if cost == "cpu" else cost
    out = []
    for level in levels:
        entry = {"level": level, "cheapest": "none reached", "points": (), "methods": (), cost: np.nan,
                 "error": np.nan, "runner_up": "", f"runner_up_{cost}": np.nan}
        if level < floor:
            entry["cheapest"] = f"not resolvable: below {floor:.1g}, {RESOLUTION:g}x the reference's accuracy"
        else:
            # each (source, method)'s point that reaches the level, cheapest first; stable sorts (ties in the
            # sweep's order) so that equal counts pick the same points every time
            reached = ok[ok["error"] <= level].sort_values("evaluations", kind="stable") \
                .drop_duplicates(["source", "method"]).sort_values(ranked, kind="stable")
            if len(reached):
                best, others = reached.iloc[0], reached.iloc[1:]
                tied = (others[ranked] <= (1 + REPRODUCIBILITY) * best[ranked] if cost == "cpu"
                        else others[ranked] == best[ranked])
                winners = pd.concat([reached.iloc[:1], others[tied]]).sort_index()
                entry.update({"cheapest": tie_in_words(winners, cost),
                              "points": tuple(point_label(r) for _, r in winners.iterrows()),
                              "methods": tuple(winners["method"]), cost: best[ranked], "error": best["error"]})
                rest = others[~tied]
                if len(rest):
                    entry.update({"runner_up": point_label(rest.iloc[0]), f"runner_up_{cost}": rest.iloc[0][ranked]})
        out.append(entry)
    return pd.DataFrame(out)


def in_short(sweeps, cost="evaluations"):
    """A sentence on which methods are cheapest in `cost` over the sweeps of several cases ({case: frame}): at
    how many of the accuracy levels they reach each method is the cheapest (cheapest(): methods tied count
    each), e.g. "counted in right-hand-side evaluations, the cheapest method at each of the 19 accuracy levels
    (1e-02 to 1e-10) that the 4 integrated cases reach is an adaptive one: LSODA at 15 of them, ..."."""
    cells = [set(methods) for frame in sweeps.values() if not frame.empty
             for methods in cheapest(frame, cost)["methods"] if methods]
    wins = Counter(method for methods in cells for method in methods)
    ranked = [f"{method} at {wins[method]}" for method in sorted(wins, key=lambda m: (-wins[m], m))]
    if not ranked:
        return f"counted in {COST_WORDS[cost]}, no method reaches any of the accuracy levels {LEVELS[0]:.0e} to {LEVELS[-1]:.0e}"
    ranked[0] += " of them"
    kind = ("an adaptive one: " if set(wins) <= set(SCIPY_METHODS) else
            "a fixed-step one: " if not set(wins) & set(SCIPY_METHODS) else "")
    integrated = sum(not frame.empty for frame in sweeps.values())
    ties = sum(len(methods) > 1 for methods in cells)
    return (f"counted in {COST_WORDS[cost]}, the cheapest method at each of the {len(cells)} accuracy levels"
            f" ({LEVELS[0]:.0e} to {LEVELS[-1]:.0e}) that the {plural(integrated, 'integrated case')} reach is {kind}"
            + (", ".join(ranked[:-1]) + " and " if len(ranked) > 1 else "") + ranked[-1]
            + (f"; {plural(ties, 'level')} {'is a tie' if ties == 1 else 'are ties'} between methods"
               f" ({TIE_WORDS[cost]}), counted for each" if ties else ""))


def read_csv(path, timing=None):
    """A sweep as write_csv wrote it, with the CPU times of its `timing` twin when given (the reference's
    label and accuracy are not restored: below its resolution a level reads "none reached")."""
    frame = pd.read_csv(path, comment="#")
    if timing is not None:
        frame = frame.merge(pd.read_csv(timing, comment="#"), on=["case", "source", "method", "setting", "value"])
    return frame


# -- the chart ---------------------------------------------------------------------------------

def figure(frame, case, path, cost="evaluations"):
    """Error against cost, log-log: trajectory error (top) and energy error (bottom) against `cost`
    (COSTS: right-hand-side evaluations, or the CPU time with bars from the fastest to the slowest
    repeat); hollow markers for points the reference cannot resolve; the unresolvable band shaded.
    Returns the caption."""
    ref = frame.attrs.get("reference", {})
    floor = RESOLUTION * ref.get("accuracy", 0.0)
    ok = frame[frame["status"] == "ok"]
    fig, axes = panels(2, 1, 7.4, sharex=True)
    axes = axes[:, 0]
    drawn = {}  # label -> errors by step or tolerance, to name a line that hides another
    for (source, method), points in ok.groupby(["source", "method"], sort=False):
        points = points.sort_values("value", ascending=False)  # along the sweep: loose to tight
        style = dict(color=METHOD_COLOUR[method], ms=5, lw=1.1, **SWEEP_STYLE[source])
        label = f"{method} ({source})" if source in ENGINES or method in SCIPY_METHODS else method
        errors = points.set_index("value")["error"]
        same = [other for other, e in drawn.items() if e.index.equals(errors.index) and np.array_equal(e, errors)]
        drawn[label] = errors
        label += f", same as {same[0]}" if same else ""
        for ax, y in zip(axes, ("error", "energy_error")):
            ax.plot(points[cost], points[y], mfc="none", label=label if ax is axes[0] else None, **style)
            solid = points[points["resolved"]]
            ax.plot(solid[cost], solid[y], ls="none", marker=style["marker"], color=style["color"], ms=5)
            if cost == "cpu":
                spread = [points["cpu"] - points["cpu_min"], points["cpu_max"] - points["cpu"]]
                ax.errorbar(points["cpu"], points[y], xerr=spread, ls="none", color=style["color"], lw=0.7)
    for ax in axes:
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="major")
    axes[0].axhspan(1e-300, floor, color="0.85", zorder=0)
    axes[0].axhline(floor, color="0.5", lw=0.8)
    axes[0].set_ylim(*log_range([ok["error"], [floor]]))
    if ok["energy_error"].notna().any():
        axes[1].set_ylim(*log_range([ok["energy_error"]]))
    axes[0].set_ylabel("trajectory error [1]\nmax |x - x_ref| / max |x_ref|")
    axes[1].set_ylabel("energy error [1]\nmax |E - E(0) - W| / max(|E|, |W|)")
    axes[1].set_xlabel(COSTS[cost])
    solution = "tight solution" if "derivation" in set(frame["source"]) else "reference solution"
    sources = ", ".join(f"{GLYPHS[SWEEP_STYLE[s]['marker']]} {GLYPHS[SWEEP_STYLE[s]['ls']]} {s}"
                        for s in SWEEP_STYLE if s in set(frame["source"]))
    legend_below(fig, ncol=2, title=f"colour: method; marker and line: source ({sources})")
    fig.suptitle(title(heading(case.spec), f"error against {'CPU time' if cost == 'cpu' else 'cost'} over "
                                           f"{ref.get('t_end', 0):g} s"))
    save(fig, path)
    unstable = frame[frame["status"] == "unstable"]
    notes = "; ".join(f"{point_label(r)} ({r['detail'].split(':')[0]})" for _, r in unstable.iterrows())
    reached = cheapest(frame, cost)
    reached = reached[reached[cost].notna()]
    best = "" if reached.empty else (f" The cheapest to reach {reached['level'].iloc[-1]:.0e}, the tightest level any"
                                     f" method reaches: {reached['cheapest'].iloc[-1]}.")
    return (f"Each method's error against its {COSTS[cost].split(',')[0]}, from loose to tight settings (colour: method;"
            f" marker and line style: source): the trajectory's relative error (top) and the energy balance's (bottom),"
            f" against the {solution} ({ref.get('label', '')})."
            f" Lower left is better. Hollow markers and the shaded band: within {RESOLUTION:g}x of the {solution}'s"
            " accuracy, where the error cannot be told." + best
            + (" The derivation defines no energy or drive power: its own methods have no energy error."
               if ok["energy_error"].isna().any() else "")
            + (f" Unstable (not drawn): {notes}." if notes else ""))


# -- convergence ----------------------------------------------------------------------------------

class NoFrequency(ValueError):
    """The parameters give the scene no frequency (omega = 0: two pendulums without gravity), so the convergence
    study has no steps: not applicable where nothing moves (released from rest), a failure where something does."""


def convergence(case):
    """The observed order of every fixed-step method of the case file's [work_precision.convergence]:
    check rows (check "convergence", quantity the method, error |observed - expected order|).

    Observed order: runs at h, h/2, h/4 from the book's initial conditions over a short horizon T,
    p = log2(D1 / D2) with D1 = |x_h - x_h/2|, D2 = |x_h/2 - x_h/4|, each the largest difference
    over the trajectory (at 50 or more of the coarsest run's steps) and the state coordinates,
    relative to the coordinate's largest magnitude (rates: the largest of the rates of its unit).  Over the trajectory, not at the final state: the error of one
    instant can pass near zero and bend the ratio (measured: RK4 on the book's chaotic example shows 5.05
    at the final state and 3.89 over the trajectory, 4.00 and 3.94 at halved steps).

    Tolerance, from the error expansion x_h - x = h^p e_p + h^(p+1) e_(p+1) + ...:
    D1 / D2 = 2^p (1 + c rho h) / (1 + c rho h / 2), c = (1 - 2^-(p+1)) / (1 - 2^-p) <= 1.5, with
    rho = |e_(p+1) / e_p|, so the observed order is off by about c rho h / (2 ln 2) <= 1.1 rho h.
    The next term carries one more factor of the fastest frequency omega of the scene than the
    leading one, and where the error accumulates over the horizon (the Eulers' growing amplitude)
    one more factor omega T, so rho <= omega (1 + omega T) and the allowed deviation is
    omega h (1 + omega T), omega from the case file (measured over the four cases: 0.02 to 0.45 of
    it, halving with h as the expansion says).  Steps are chosen to keep it at most 0.25: an order
    off by one fails fourfold.  Differences at rounding level would make p meaningless, so a setup
    whose D2 is under ROUNDING_FLOOR raises instead of reporting.

    The argument needs omega to bound the motion's frequency.  Where the reference's motion outruns it
    (`motion_frequency`: more than OUTRUN omega), the horizon ends before, and the row says where: a top with
    Izz = Ixx / 4 under g = 1 m/s^2 passes 0.003 rad from its Euler angles' singularity 0.24 s in, where the
    frequency of its Euler-angle equations passes 600 rad/s against the case's 11.5, and RK4 at the
    case's step blew up; before 0.198 s it shows order 3.92."""
    wp = settings(case)
    if wp is None:
        return []
    q0, v0, _ = case.initial
    columns = state_columns(case)
    units = dict(zip(case.coords, case.spec["coord_units"]))
    steps = wp["convergence"]["steps"]
    if any(omega == 0 for _, _, omega in steps.values()):
        raise NoFrequency("the case's fastest frequency omega (work_precision.convergence.omega) is 0 at these "
                          "parameters, and the study's steps h = omega_h / omega follow from it")
    for method, (_, _, omega) in steps.items():
        if not omega > 0:
            raise ValueError(f"{case.origin}: work_precision.convergence: omega = {omega!r} for {method} must be a "
                             "positive number (the fastest frequency it integrates, with these parameters)")
    times, frequency = motion_frequency(case, max(t_end for _, t_end, _ in steps.values()))
    rows = []
    for method, (h, t_end, omega) in steps.items():
        source = "mujoco" if method in MUJOCO_METHODS else "reference"
        outrun = (times <= t_end) & (frequency > OUTRUN * omega)
        cut = ""
        if outrun.any():
            first = times[np.argmax(outrun)]
            cut = (f"; the horizon ends before {first:.3g} s, where the motion's frequency passes {OUTRUN:g} omega "
                   f"(to {frequency[times <= t_end].max():.3g} rad/s within {t_end:.3g} s)")
            t_end = math.floor(first / h) * h
            if t_end < MIN_STEPS * h:
                rows.append(no_number("convergence", method, (source,), f"not measured: within {MIN_STEPS} steps of "
                                      f"h = {h:.3g} s{cut}", Status.INCONCLUSIVE))
                continue
        model = case.model(source)
        # Compare at least 50 instants on the coarsest run's steps, not every one of them: each output costs
        # a frame row; the states are all these runs give (no reactions, no energy).
        n = round(t_end / h)
        every = max(k for k in range(1, n // 50 + 1) if n % k == 0)
        try:
            runs = [simulate(model, (q0, v0), t_end, method, dt=h / 2**i, output_step=every * h,
                             work=False, quantities=())[columns] for i in range(3)]
        except Unstable as failure:
            rows.append(no_number("convergence", method, (source,), failure))
            continue
        scale = runs[2].abs().max()
        # Rates of one unit share one scale, the largest of them: a rate that stays near zero over the short
        # horizon (a top's nutation rate beside its spin) would otherwise be judged by its own size, where it
        # carries only the leak of the whole angular velocity's error through the coordinate map.
        for unit in set(units.values()):
            rates = [f"{name}_rate" for name, its in units.items() if its == unit]
            scale[rates] = scale[rates].max()
        d1, d2 = ((runs[i] - runs[i + 1]).abs().max().div(scale).max() for i in range(2))
        if not d2 > ROUNDING_FLOOR:
            raise ValueError(f"{case.origin}: work_precision.convergence.omega_h.{method} gives h = {h:g} s: the runs at "
                             f"h/2 and h/4 differ by {d2:.1e}, within rounding ({ROUNDING_FLOOR:.1e}); choose a larger step")
        observed = math.log2(d1 / d2)
        expected = EXPECTED_ORDER[method]
        rows.append(row("convergence", method, (source,), abs(observed - expected), omega * h * (1 + omega * t_end),
                        f"observed order {observed:.3f} (expected {expected}) from dt = {h:g}, {h / 2:g}, "
                        f"{h / 4:g} s over {t_end:g} s; differences {d1:.2e}, {d2:.2e}; allowed "
                        f"omega h (1 + omega T) with omega = {omega:g} rad/s{cut}", ceiling=ceilings.CONVERGENCE))
    return rows


# The argument above needs omega to bound the motion's frequency.  Measured as the spectral radius of the
# state Jacobian along the reference's motion, the book's cases reach 0.68 to 1.15 of the case's omega, and the
# two pendulums' chaotic swings 2.6 of it for instants, where the orders are observed as the argument says.  A top
# passing 0.003 rad from its Euler angles' singularity (Izz = Ixx / 4, g = 1 m/s^2) passes 50 times its
# omega there, and RK4 at the case's step blew up: the horizon ends where the motion passes OUTRUN omega.
OUTRUN = 4.0
MIN_STEPS = 20  # the fewest steps of h a convergence run's horizon may hold
MOTION_POINTS = 50  # the instants of the reference's motion whose frequency is measured


def motion_frequency(case, t_end):
    """The reference's motion from the book's start over [0, t_end] (DOP853 at the case's rtol): MOTION_POINTS + 1
    times, and at each the spectral radius of the state Jacobian [[0, I], [dq''/dq, dq''/dq']] (the vibration
    analysis's differences): the local frequency, from rest or not, which a coordinate singularity makes large.
    Zero where the run fails (the convergence runs then say how)."""
    q0, v0, _ = case.initial
    model = case.model("reference")
    n = len(q0)
    try:
        run = simulate(model, (q0, v0), t_end, "DOP853", rtol=case.integration["rtol"],
                       output_step=t_end / MOTION_POINTS, work=False, omega=fastest_frequency(case), quantities=())
    except Unstable:
        return np.array([0.0]), np.array([0.0])
    states = run[state_columns(case)].to_numpy()[:, np.r_[0:2 * n:2, 1:2 * n:2]]  # (q, q') per instant
    radius = []
    with np.errstate(all="ignore"):
        for t, x in zip(run.index, states):
            acc = lambda y: np.asarray(model.accelerations(t, y[:n], y[n:]), dtype=float)
            state_matrix = np.block([[np.zeros((n, n)), np.eye(n)], [jacobian(acc, x, scales_of(x))[0]]])
            radius.append(np.max(np.abs(np.linalg.eigvals(state_matrix))) if np.all(np.isfinite(state_matrix))
                          else np.inf)
    return run.index.to_numpy(), np.array(radius)
