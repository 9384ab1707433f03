"""Work-precision: what each integrator and engine pays for its accuracy.

`sweep(case)` runs every method over a tolerance or step sweep against one named reference
solution and returns tidy rows; `figure` draws them log-log, `cheapest` says which method reaches
each accuracy level first.  It reads the case file's [work_precision] table (dyncheck.checks.convergence.settings,
which the convergence orders share).
"""

import time
from collections import Counter

import numpy as np
import pandas as pd

from dyncheck.checks.convergence import settings
from dyncheck.common.ceilings import ROUNDING_FLOOR
from dyncheck.common.messages import plural
from dyncheck.common.style import METHOD_COLOUR, SWEEP_STYLE, legend_below, log_range, panels, save, title
from dyncheck.results.values import Status, heading
from dyncheck.run import cache
from dyncheck.run.simulate import SCIPY_METHODS, Unstable, energy_residual, fastest_frequency, simulate, state_columns

COLUMNS = ["case", "source", "method", "setting", "value", "error", "energy_error", "cpu", "cpu_min", "cpu_max",
           "repeats", "evaluations", "steps", "status", "resolved", "detail"]
# A timed run's cost is its CPU time (simulate's attrs["cpu"]): the wall time it takes on an idle core, which
# other processes' load leaves out (three busy processes on this 2-core machine stretched wall times 2.6x and
# their spreads 5-15x, CPU times by 4-11%).  CPU times still differ from run to run: the pages and their CSV
# leave them out (a report made twice is the same), and the timing files (write_csv(..., timing=True),
# figure(..., cost="cpu")) carry them.
TIMING_COLUMNS = ["cpu", "cpu_min", "cpu_max", "repeats"]
UNFINISHED = (str(Status.UNSTABLE), str(Status.SPENT))  # a point's run that blew up or ran out of its wall time
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
ENGINES = ("pinocchio", "mujoco")  # a sweep's engine sources, named in its chart's legend
GLYPHS = {"o": "\u25cb", "s": "\u25a1", "^": "\u25b3", "-": "\u2014", "--": "- -", ":": "\u00b7\u00b7\u00b7"}  # legend title
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
    reference (as dyncheck.checks.runs.trajectory)."""
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
    with status "unstable" (or "budget spent", where it ran out of its wall time), NaN errors and the time and step in
    `detail`.  resolved: whether the error
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
                         "steps": failure.step, "status": str(failure.status), "resolved": False,
                         "detail": f"{failure.status} at t = {failure.t:.4g} s"
                                   + (f", step {failure.step}" if failure.step is not None else "") + f": {failure.why}"})
            _progress(progress, f"{case.name} {source} {method} {setting}={value:g}: {failure.status}")
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
    unstable = frame[frame["status"].isin(UNFINISHED)]
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
