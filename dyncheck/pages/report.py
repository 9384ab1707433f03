"""Markdown reports with figures: reports/<case>.md per case, reports/index.md and errata.md, rendered
from results alone (dyncheck.results.values.CaseResult): no engine is imported here, nothing is computed
but what the pages show.  The results are saved in the report's results/ folder, and the pages are
rendered from what was saved, so that `dyncheck report --from reports/results` renders them again.

The new report is built whole in a folder beside the old one and swapped in with one atomic
rename, so a failed, interrupted or killed run leaves the previous report intact.
"""

import ctypes
import errno
import fcntl
import json
import math
import os
import re
import shutil
import sys
import textwrap
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pandas as pd

from dyncheck.pages import animation, student_page, typeset, vibration_page
from dyncheck.common import expressions
from dyncheck.results import measured
from dyncheck.studies import stability, work_precision
from dyncheck.case.folder import CASES_DIR, Case
from dyncheck.common.expressions import evaluate, namespace
from dyncheck.common.messages import ENGINE_NAMES, plural, statuses_in_words
from dyncheck.results.values import (OWN_WORDS, RESULTS_VERSION, Status, case_json, consequences, format_rows, heading,
                              inside_or_outside, load_result, reason, save_results)
from dyncheck.run.simulate import energy_residual, state_columns
from dyncheck.common.style import SOURCE_STYLE as STYLE
from dyncheck.common.style import TEXT_HEIGHT, TEXT_WIDTH, along, embed, legend_below, log_range, panels, pyplot, save, thin, title

ENGINES = ("reference", "mujoco", "pinocchio")  # the sources that must agree everywhere


def write_reports(results, out, animations=True):
    """Write the pages of `results` into the folder `out`, keeping what it holds of other cases, and
    return the files written (relative to `out`); `animations`: with each case's GIF.

    The new tree is a copy of `out` with this run's files written over it, and its index and errata
    are made from the summaries it holds; it is built beside `out` and exchanged with it in one
    rename, so a reader sees the previous report or the new one, never a mix.  Writers into one
    folder take turns (`locked`), each building on the last one's report."""
    out = Path(out).resolve()  # through a symbolic link: the link stays, the folder it names is replaced
    with locked(out):
        remove_stale_trees(out)
        tree = out.parent / f"{temp_prefix(out)}{os.getpid()}"
        try:
            tree.mkdir()
            if out.is_dir():  # `.tmp-*`: what killed runs of earlier versions left inside `out`
                shutil.copytree(out, tree, dirs_exist_ok=True, ignore=shutil.ignore_patterns(".tmp-*"))
            (tree / "figures").mkdir(exist_ok=True)
            (tree / "data").mkdir(exist_ok=True)
            save_results(results, tree / "results")
            written = [f"results/{result.name}" for result in results]
            # The pages from the results as saved: what `report --from` renders from them.
            for result in (load_result(tree / "results" / result.name) for result in results):
                case = Case(result.folder, result.overrides, result.spec)
                if result.runs:
                    written += write_case_page(result, case, tree, animations)
                    written += student_page.write(result, case, tree)  # after the case page: it shows its figures
                else:  # its checks did not finish (dyncheck.checks.runs.unfinished)
                    written.append(write_unfinished_page(result, case, tree))
                written.append(write_summary(result, case, tree))
            cases = summaries(tree, out)
            written.append(write_index(tree, cases))
            written += write_index_timing(tree, cases)
            if not all(c["one_derivation"] for c in cases):  # the book's errata; a researcher's case has no book
                written.append(write_errata(tree, cases))
            swap(tree, out)
        finally:  # this run's tree after a failure, or the previous report after the swap
            if tree.exists():
                shutil.rmtree(tree)
    return written


def temp_prefix(out):
    return f".{out.name}.tmp-"


@contextmanager
def locked(out):
    """Hold the lock on `out` (flock on a file beside it, released by the system if we are killed).
    A second writer waits its turn rather than fail: the first one's wait is seconds, and both
    reports then land, the second built on the first."""
    with open(out.parent / f".{out.name}.lock", "a+") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.seek(0)
            print(f"dyncheck: waiting for {lock.read().strip() or 'another writer'}, which is writing {out}",
                  file=sys.stderr)
            fcntl.flock(lock, fcntl.LOCK_EX)
        lock.truncate(0)
        lock.write(f"dyncheck pid {os.getpid()}\n")
        lock.flush()
        yield


def remove_stale_trees(out):
    """Trees beside `out` that killed writers left; only called under the lock, so no live writer has
    one.  A writer killed between the two renames of `swap` left the previous report aside: put back."""
    for path in sorted(out.parent.iterdir()):
        if path.name.startswith(temp_prefix(out)):
            if path.name.endswith(PREVIOUS) and not out.exists():
                path.rename(out)
            else:
                shutil.rmtree(path)


PREVIOUS = "-previous"  # the name's end of the previous report while `swap` cannot exchange
RENAME_EXCHANGE = 2  # <linux/fs.h>
AT_FDCWD = -100  # <fcntl.h>: paths relative to the working directory


def swap(new, out):
    """Put the tree `new` at `out` and the previous one, if any, at `new`."""
    if not out.exists():
        os.rename(new, out)
    elif not exchange(new, out):
        # No atomic exchange here (not Linux, or a file system without it): `out` is missing for a
        # moment between the two renames, but it is never a mix of two reports.
        previous = new.with_name(new.name + PREVIOUS)
        os.rename(out, previous)
        os.rename(new, out)
        os.rename(previous, new)


def exchange(a, b):
    """Exchange two paths in one atomic step (Linux's renameat2 with RENAME_EXCHANGE, which
    Python's os does not offer); False where the system cannot."""
    renameat2 = getattr(ctypes.CDLL(None, use_errno=True), "renameat2", None)
    if renameat2 is None:
        return False
    if renameat2(AT_FDCWD, os.fsencode(a), AT_FDCWD, os.fsencode(b), RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS):  # the file system or kernel lacks it
        return False
    raise OSError(code, os.strerror(code), os.fsdecode(b))


def write_summary(result, case, tmp):
    """data/<case>.json: the case's results (the schema of `dyncheck run --json`) for the index."""
    rows = result.rows
    sweep = sweep_in_words(result.studies["work_precision"], case) if result.studies else None
    worst = worst_engine_error(rows)
    summary = {"version": RESULTS_VERSION, **case_json(result), "title": case.title,
               "overridden": case.overrides_text(),  # in words, for the index and errata
               "one_derivation": case.one_derivation,  # the index's words: a researcher's or the book's
               "worst_engine_error": worst if math.isfinite(worst) else None,  # JSON has no NaN
               "random": random_tried(result, case),
               "cheapest": None if sweep is None or sweep.empty else  # for the index: level -> method
               {f"{r['level']:.0e}": r["cheapest"] for _, r in work_precision.cheapest(sweep).iterrows()},
               "vibration": vibration_page.summary(result.vibration),
               "typeset": [{"finding": f.id, **typeset_pair(pair)} for f in result.findings for pair in f.pairs]}
    rel = f"data/{case.name}.json"
    (tmp / rel).write_text(json.dumps(summary, indent=1) + "\n")
    return rel


# -- figures ------------------------------------------------------------------------

def trajectories(result):
    """{label: DataFrame} of the book's run for every source, the tight reference first."""
    runs = result.runs
    out = {"tight reference": runs["reference"].twin}
    out.update({s: runs[s].run for s in ("book", "pinocchio", "mujoco") if runs[s].ok})
    return out


def titled(case, what):
    return title(heading(case.spec), what)


def named(words, source):
    """A source as the case's pages name it (OWN_WORDS for a case of one derivation; the engines by name)."""
    return words.get(source, ENGINE_NAMES.get(source, source))


# A rate or an acceleration primed, as the pages' prose writes them (psi'', l'').
PRIMES = (("_acc", "''"), ("_rate", "'"), ("_dot", "'"))


def quantity_label(name):
    """A quantity as a figure names it, in the page's words: its symbol typeset (typeset.symbol, drawn by
    matplotlib's mathtext), a rate or an acceleration primed, a vector's component after it (theta1_acc ->
    theta_1'', omega3_dot_x -> omega_3' x, a_D_x -> a_D x); a word stays words (energy, drive power,
    precession'')."""
    base, paren, note = name.partition(" (")  # "psi (dependent)"
    base, component = re.fullmatch(r"(.+?)(?:_([xyz]))?", base).groups()
    prime = next((mark for suffix, mark in PRIMES if base.endswith(suffix)), "")
    base = next((base[:-len(suffix)] for suffix, _ in PRIMES if base.endswith(suffix)), base)
    head = re.match(r"[A-Za-z]*", base)[0]
    if head in typeset.GREEK or len(head) == 1 or re.fullmatch(r"[A-Z][xyz]{1,2}", base):
        shown = f"${typeset.symbol(base)}{prime}$"
    else:
        shown = base.replace("_", " ") + prime
    return shown + (f" {component}" if component else "") + (f" ({note}" if paren else "")


def figure_scene(result, case, path, *, words):
    """The scene at t = 0 and the path of each point mass along the tight run; returns the caption."""
    tight = trajectories(result)["tight reference"]
    scene = result.drawings["scene"]
    origins, parents = scene["origins"], scene["parents"]
    paths = np.array([tight[[f"{body}_{axis}" for axis in "xyz"]].to_numpy() for body in case.scene["paths"]])
    paths = paths.reshape(len(case.scene["paths"]), len(tight), 3).transpose(1, 0, 2)  # (time, body, xyz)
    paths = thin(paths)
    planar = np.ptp(np.concatenate([paths[..., 2].ravel(), origins[:, 2]])) < 1e-12
    fig = pyplot().figure(figsize=(TEXT_WIDTH, 4.6))
    ax = fig.add_subplot(projection=None if planar else "3d")
    dims = 2 if planar else 3
    chain = np.vstack([np.zeros(3), origins])  # body 0 is the world origin
    for i, parent in enumerate(parents):
        seg = chain[[parent, i + 1], :dims].T
        ax.plot(*seg, color="0.3", lw=2)
    ax.scatter(*chain[:, :dims].T, color="0.3", s=12)
    lines = ("-", "--", ":", "-.")  # one per body's path: told apart in grey
    for b, name in enumerate(case.scene["paths"]):
        arm = np.vstack([origins[scene["path_origins"][b]], paths[0, b]])  # body origin to its point mass
        ax.plot(*arm[:, :dims].T, color="0.3", lw=2)
        ax.plot(*paths[:, b, :dims].T, lw=0.8, ls=lines[b % len(lines)], label=f"path of {name}")
        ax.scatter(*paths[0, b, :dims], s=40, marker="o", zorder=5)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if planar:
        ax.set_aspect("equal")
    else:
        ax.set_zlabel("z [m]")
    ax.set_title(titled(case, "the scene at t = 0 and the path in space"))
    legend_below(fig)
    save(fig, path)
    moving = ", ".join(case.scene["paths"])
    return ("The bodies and joints at t = 0 (grey lines, the dots their origins)"
            + (f" and the path of {moving} over 0-{tight.index[-1]:g} s"
               f" ({named(words, 'tight reference')}); axes in metres, {'the plane of motion' if planar else 'in space'}."
               if moving else "; axes in metres."))


def figure_series(result, case, columns, ylabel, what, path, *, words, log_error=False):
    """Columns over time from every source, overlaid, a panel each (two columns of panels beyond three);
    with log_error, |source - tight reference| on log axes whose range follows the data.  `words`: the
    sources' names as the case's pages say them.  Returns each source's largest departure from the tight
    reference, {source: (departure, column)}, for the caption."""
    runs = trajectories(result)
    tight = runs["tight reference"]
    cols = 1 if len(columns) <= 3 else 2
    rows = -(-len(columns) // cols)
    fig, axes = panels(rows, cols, min(TEXT_HEIGHT - 0.5, 1.0 + 1.75 * rows), sharex=True)
    worst = {}
    for ax, column in zip(axes.flat, columns):
        errors = {label: (run[column] - tight[column]).abs() for label, run in runs.items() if label != "tight reference"}
        for label, error in errors.items():
            if error.max() > worst.get(label, (-1.0, None))[0]:
                worst[label] = (error.max(), column)
        if log_error:
            errors = {label: thin(error) for label, error in errors.items()}
            low, high = log_range(list(errors.values()))
            for label, error in errors.items():
                ax.semilogy(error.index, np.maximum(error, low), label=named(words, label), **along(label, len(error)))
            ax.set_ylim(low, high)
        else:
            for label, run in runs.items():
                run = thin(run[column])
                ax.plot(run.index, run, label=named(words, label), **along(label, len(run)))
        ax.set_ylabel(ylabel(column))
    for ax in axes.flat[len(columns):]:
        ax.set_axis_off()
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(titled(case, what))
    legend_below(fig, ncol=5)
    save(fig, path)
    return worst


def departures(worst, unit, words):
    """"book 0.12 rad (psi), MuJoCo 3e-09 rad (psi)": each source's largest departure in words."""
    return ", ".join(f"{named(words, source)} {error:.2g} {unit(column)} ({column})"
                     for source, (error, column) in worst.items())


def figure_energy(result, case, path, *, words):
    """The energy balance along the run (top) and each source's miss of it (bottom); returns the caption."""
    # A derivation may define no energy: its runs have none, and the balance drawn is the first engine's.
    runs = {label: thin(run) for label, run in trajectories(result).items() if {"energy", "work"} <= set(run)}
    driven = any(run["work"].abs().max() > 0 for run in runs.values())  # from the results: no scene file read
    fig, axes = panels(2, 1, 5.0, sharex=True)
    top, bottom = axes[:, 0]
    shown = next(iter(runs), None)
    if shown is None:
        top.text(0.5, 0.5, "no run has an energy: the derivation defines none\nand the engines' runs failed",
                 ha="center", transform=top.transAxes)
    else:
        balance = runs[shown]
        top.plot(balance.index, balance["energy"] - balance["energy"].iloc[0], label="E(t) - E(0)",
                 **{**STYLE[shown], "marker": None})
        if driven:
            top.plot(balance.index, balance["work"], label="W(t), work of the drives, forces and dampers",
                     color="tab:purple", lw=1, ls="--")
        top.set_title("energy balance" + (": E(t) - E(0) = W(t)" if driven else ": E(t) = E(0)")
                      + f" ({named(words, shown)})")
        top.legend(loc="lower left", bbox_to_anchor=(0, 1.12), ncol=2, frameon=False)
    top.set_ylabel("energy [J]")
    misses = {label: energy_residual(run).abs() for label, run in trajectories(result).items() if label in runs}
    low, high = log_range(list(misses.values()))
    for label, miss in misses.items():
        miss = thin(miss)
        bottom.semilogy(miss.index, np.maximum(miss, low), label=named(words, label), **along(label, len(miss)))
    bottom.set_ylim(low, high)
    bottom.set_ylabel("|E(t) - E(0) - W(t)| [J]")
    bottom.set_xlabel("t [s]")
    fig.suptitle(titled(case, "energy along the run"))
    legend_below(fig, *bottom.get_legend_handles_labels(), ncol=5)
    save(fig, path)
    if shown is None:
        return "No energy: the derivation defines none and the engines' runs failed."
    return (f"Top: the change of the total energy E(t) - E(0) ({named(words, shown)}'s run)"
            + (", and the work W(t) done on the system, which it must equal" if driven else ", which must stay 0")
            + ". Bottom: how far each source's run misses that balance, in joules; the largest miss: "
            + ", ".join(f"{named(words, label)} {miss.max():.2g} J" for label, miss in misses.items()) + ".")


def state_unit(case, column):
    """The unit of a state column: its coordinate's, per second for a rate."""
    units = dict(zip(case.coords, case.spec["coord_units"]))
    return units[column[:-len("_rate")]] + "/s" if column.endswith("_rate") else units[column]


def reaction_unit(case, name):
    return "N m" if case.scene["reactions"][name].get("quantity") == "moment" else "N"


POINT_SOURCES = ("book", "mujoco", "pinocchio")  # the sources whose deviation from the reference is drawn


def figure_pointwise(result, case, path, *, words):
    """Per random state, each source's deviation from `reference`, relative to the quantity's scale, in a
    grid of at most four panels across; returns the caption."""
    values = result.sample["values"]
    quantities = list(values["reference"])
    tolerance = case.tolerance["pointwise"]["value"]
    deviations = {}
    for quantity in quantities:
        ref = values["reference"][quantity]
        scale = np.max(np.abs(ref)) or 1.0
        deviations[quantity] = {source: np.abs(values[source][quantity] - ref) / scale
                                for source in POINT_SOURCES if source in values}  # absent: its evaluation failed
    low, high = log_range([d for by_source in deviations.values() for d in by_source.values()] + [[tolerance]])
    cols = min(4, len(quantities))
    rows = -(-len(quantities) // cols)
    fig, axes = panels(rows, cols, min(TEXT_HEIGHT - 0.5, 1.4 + 1.25 * rows), sharex=True, sharey=True)
    for ax, quantity in zip(axes.flat, quantities):
        for i, (source, dev) in enumerate(deviations[quantity].items()):
            style = STYLE[source]
            ax.semilogy(np.full(len(dev), i) + np.linspace(-0.3, 0.3, len(dev)), np.maximum(dev, low), ls="none",
                        marker=style["marker"], ms=3, mfc=style.get("mfc"), color=style["color"],
                        label=named(words, source))
        ax.axhline(tolerance, color="k", lw=0.8, ls="--", label=f"tolerance {tolerance:g}")
        ax.set_xticks([])
        ax.set_xlim(-0.6, len(POINT_SOURCES) - 0.4)
        ax.set_ylim(low, high)
        ax.set_title(quantity_label(quantity), fontsize=8)
    for ax in axes.flat[len(quantities):]:
        ax.set_axis_off()
    fig.supylabel("relative deviation from the reference [1]" if rows > 1 else "relative deviation [1]", fontsize=9)
    fig.suptitle(titled(case, f"pointwise, {len(result.sample['states'])} random states"))
    legend_below(fig, ncol=4)
    save(fig, path)
    worst = {source: max(((d[source].max(), q) for q, d in deviations.items() if source in d), default=None)
             for source in POINT_SOURCES}
    return (f"Each source's deviation from the reference at each of the {len(result.sample['states'])} random"
            " states, |source - reference| / max |reference| over the states, one panel per quantity (marker and colour per"
            f" source; exact agreement on the bottom edge); dashed: the tolerance {tolerance:g}. The largest: "
            + ", ".join(f"{named(words, s)} {w[0]:.1e} ({w[1]})" for s, w in worst.items() if w is not None) + ".")


def report_namespaces(result, case):
    """{source: namespace} along each source's run, for a case's own figures and values."""
    return {label: namespace(case, run) for label, run in trajectories(result).items()}


def figure_extra(spaces, case, item, path, *, words):
    """One of a case's own figures: y against x for every source, overlaid; returns the caption."""
    fig, axes = panels(1, 1, 4.0)
    ax = axes[0, 0]
    for label, names in spaces.items():
        x, y = (thin(np.asarray(evaluate(item[k], names), dtype=float)) for k in ("x", "y"))
        ax.plot(x, y, label=named(words, label), **along(label, len(x)))
    ax.set_xlabel(item["xlabel"])
    ax.set_ylabel(item["ylabel"])
    if item.get("ylim"):
        ax.set_ylim(*item["ylim"])
    if item.get("equal"):
        ax.set_aspect("equal", adjustable="datalim")
    fig.suptitle(titled(case, item["title"]))
    legend_below(fig, ncol=5)
    save(fig, path)
    return item.get("caption", item["title"]) + " Every source's run overlaid (line style, marker and colour per source)."


PART = 0.05  # a program's run has left the exact motion where it is off by this fraction of that motion's range


def figure_program(result, case, path):
    """The book's program figures: left from the listing's run, right from the reference's equations
    integrated tightly (the exact motion, or the corrected one where the listing's formulas are wrong);
    returns the caption."""
    runs = result.program
    plots = case.spec["program"]["plots"]
    right = ("corrected equations (the reference's), integrated tightly" if listing_formulas_wrong(result)
             else "exact motion (the reference's equations, integrated tightly)")
    sides = (("the book's program", runs["listing"], "tab:red", "--"),
             (textwrap.fill(right, 34), runs["tight"], "black", "-"))
    fig, axes = panels(len(plots), 2, min(TEXT_HEIGHT - 0.4, 0.9 + 2.0 * len(plots)))
    for row, item in enumerate(plots):
        for col, (label, run, color, line) in enumerate(sides):
            names = namespace(case, run)
            ax = axes[row, col]
            x, y = evaluate(item["x"], names), evaluate(item["y"], names)
            ax.plot(x, y, color=color, ls=line, lw=0.9)
            book_axes(ax, item, x, y)
            ax.set_title(item["title"], fontsize=8)
            ax.set_xlabel(plot_label(item, "x"), fontsize=8)
            ax.set_ylabel(plot_label(item, "y"), fontsize=8)
    for ax, (label, *_) in zip(axes[0], sides):
        ax.set_title(f"{label}\n{ax.get_title()}", fontsize=8)
    fig.suptitle(titled(case, f"the book's figures, from its program ({runs['integrator']}, dt = {runs['dt']:.3g} s)"
                              " and from the equations"))
    save(fig, path)
    return (f"The book's figures redrawn: left from a line-by-line transcription of its program ({runs['integrator']},"
            f" dt = {runs['dt']:.3g} s, red dashed), right from the {right} (black); the dashed grey frame is the"
            f" book's printed axes. {program_parting(result, case, plots)}")


def plot_label(item, axis):
    """A program plot's axis label (program.plots[i].xlabel, ylabel; see dyncheck.case.schema for the defaults)."""
    default = ("time [s]" if item["x"] == "t" else item["x"]) if axis == "x" else item["title"]
    return item.get(f"{axis}label", default)


def listing_formulas_wrong(result):
    """Whether a registered finding says the listing's formulas are wrong (not only its integrator): a
    program row with a finding other than the listing against the tight reference."""
    return any(r.check == "program" and r.finding and r.comparison != "program vs tight reference" for r in result.rows)


def program_parting(result, case, plots):
    """In words, when the program's run leaves the exact motion in its first plot against time."""
    item = next((item for item in plots if item["x"] == "t"), None)
    if item is None:
        return ""
    listing, tight = (namespace(case, result.program[key]) for key in ("listing", "tight"))
    t, y = (np.asarray(evaluate(item[k], listing), dtype=float) for k in ("x", "y"))
    t_exact, y_exact = (np.asarray(evaluate(item[k], tight), dtype=float) for k in ("x", "y"))
    apart = np.abs(y - np.interp(t, t_exact, y_exact)) > PART * np.ptp(y_exact)
    what = plot_label(item, "y")
    if not apart.any():
        return f"In {what} the program stays within {PART:.0%} of the exact motion's range over its {t[-1]:g} s."
    return (f"In {what} the program leaves the exact motion (by more than {PART:.0%} of its range) after"
            f" {t[np.argmax(apart)]:.3g} s.")


def book_axes(ax, item, x, y):
    """The book's printed axes (the plot's xlim, ylim) as a dashed frame, and the view wide enough for
    the frame and for the data wherever it goes (under other parameters it may leave the book's axes)."""
    x, y = (np.asarray(v, dtype=float) for v in (x, y))
    shown = np.isfinite(x) & np.isfinite(y)  # a run that blew up is drawn up to where it went
    (x0, x1), (y0, y1) = (item.get(key, (v[shown].min(), v[shown].max())) for key, v in (("xlim", x), ("ylim", y)))
    if "xlim" in item or "ylim" in item:
        ax.add_patch(pyplot().Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ls="--", lw=0.8, color="0.4", zorder=0))
    for v, low, high, setter in ((x, x0, x1, ax.set_xlim), (y, y0, y1, ax.set_ylim)):
        low, high = min(low, v[shown].min()), max(high, v[shown].max())
        setter(low - 0.04 * (high - low), high + 0.04 * (high - low))


def values_table(case, spaces):
    """A case's named results (e.g. the least friction coefficient), computed for every source."""
    rows = []
    for key, item in case.spec["report"].get("values", {}).items():
        row = {"result": item["about"], "unit": item["unit"]}
        for label, names in spaces.items():
            value = float(evaluate(item["expression"], names))
            row[label] = "not reached" if np.isnan(value) else f"{value:.4g}"
        rows.append(row)
    return markdown_table(pd.DataFrame(rows))


# -- pages --------------------------------------------------------------------------

def size(error, spec=".3g"):
    """A finding's largest error, or why there is none (its rows compare with what the book printed, not applicable
    under overrides)."""
    return "none: not applicable with these parameters" if error is None else format(error, spec)


def worst_engine_error(rows):
    """Largest pointwise error among reference, MuJoCo and Pinocchio."""
    errors = [r.error for r in rows if r.check == "pointwise" and set(r.sources) <= set(ENGINES)]
    return max(errors, default=float("nan"))


def random_tried(result, case):
    """What the random pointwise checks tried: states at the case's parameters, parameter sets and
    states at each, their seeds, and whether reference and both engines agreed at all of them (None where they
    were not compared: the case's checks did not finish)."""
    sample, params = case.spec["sample"], case.spec["sample"].get("params", {})
    engine_rows = [r for r in result.rows if r.check in ("pointwise", "random parameters")
                   and set(r.sources) <= set(ENGINES)]
    return {"states": sample["count"], "seed": sample["seed"], "parameter_sets": params.get("sets", 0),
            "states_per_set": params.get("states", 0), "parameter_seed": params.get("seed"),
            "agreed": all(r.status == Status.PASS for r in engine_rows) if engine_rows else None}


def random_sentence(tried):
    text = f"{plural(tried['states'], 'random state')} at these parameters (seed {tried['seed']})"
    if tried["parameter_sets"]:
        text += (f" and {plural(tried['parameter_sets'], 'random parameter set')} (seed {tried['parameter_seed']})"
                 f" over the ranges of the case file, {plural(tried['states_per_set'], 'state')} each")
    return text


def markdown_table(frame):
    """The frame as a Markdown table: text as written ("0.0200" stays, tabulate would print 0.02), numbers
    as tabulate writes them (6 significant digits), nothing (an empty text, None, NaN) as "-", a | in a
    cell escaped (it would end the cell), and the columns of numbers aligned right."""
    cells = frame.map(lambda x: "-" if x is None or x == "" or (isinstance(x, float) and math.isnan(x)) else
                      format(x, "g") if isinstance(x, float) else str(x).replace("|", "\\|"))
    numeric = [any(map(is_number, cells[column])) and all(is_number(x) or x == "-" for x in cells[column])
               for column in cells]
    cells.columns = [str(column).replace("|", "\\|") for column in cells.columns]
    return cells.to_markdown(index=False, disable_numparse=True,
                             colalign=["right" if n else "left" for n in numeric] or None)


def is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def summary_table(rows):
    """One line per (check, comparison): how many quantities, their statuses, the worst error/tolerance."""
    frame = pd.DataFrame([{"check": r.check, "sources": r.comparison, "quantity": r.quantity, "status": str(r.status),
                           "error": np.nan if r.error is None else r.error,
                           "tolerance": np.nan if r.tolerance is None else r.tolerance, "row": r} for r in rows])
    out = []
    for (check, sources), group in frame.groupby(["check", "sources"], sort=False):
        judged = group.dropna(subset=["error", "tolerance"])
        with np.errstate(divide="ignore", invalid="ignore"):  # a zero tolerance: any error is infinitely over
            ratios = np.where(judged["error"] > 0, judged["error"] / judged["tolerance"], 0.0)
        worst = judged.iloc[int(np.argmax(ratios))] if len(judged) else None
        out.append({"check": check, "comparison": sources, "quantities": len(group),
                    "status": statuses_in_words(group["status"].value_counts()),
                    "worst": "-" if worst is None else f"{worst['quantity']}: " + (
                        inside_or_outside(worst["row"]) if worst["row"].yes_or_no
                        else f"{worst['error']:.2e} / {worst['tolerance']:.2e}")})
    return pd.DataFrame(out)


def not_passed(rows):
    """Page lines naming every row that neither passed nor is a finding or not applicable, and why: a
    failure's error against its tolerance, an integration's blow-up or a physical runaway (when, which
    method, which step)."""
    shown = [r for r in rows if r.status not in (Status.PASS, Status.FINDING, Status.NOT_APPLICABLE)]
    if not shown:
        return []
    why = {}  # one line per status and reason: a runaway or a blow-up stops every row of a run alike
    for r in shown:
        why.setdefault((r.status, reason(r) or r.detail), []).append(f"{r.check} {r.quantity} ({r.comparison})")
    return ["Rows that did not pass, and why:", "",
            *[f"- {'; '.join(names)}: **{status}**: {text}" for (status, text), names in why.items()], ""]


def not_checked(rows):
    """Page lines naming the `not applicable` rows that have nothing to compare (a derivation without
    energy), and why; those under overrides show their comparison in the table."""
    why = {}
    for r in rows:
        if r.status == Status.NOT_APPLICABLE and r.error is None:
            why.setdefault(r.detail, []).append(f"{r.check} {r.quantity} ({r.comparison})")
    return [line for text, names in why.items() for line in (f"Not applicable: {'; '.join(names)}: {text}.", "")]


def scene_table(case):
    """The joints of the engine models: what is free, what is prescribed, what is applied."""
    scene = case.scene
    rows = [{"joint": joint, "role": f"prescribed: {law_of_time(*law)}"} for joint, law in scene["driven"].items()]
    whose = "the coordinate " if case.one_derivation else "the book's "
    rows += [{"joint": joint, "role": "free: " + whose + ", ".join(case.coords[i] for i in idx)
              + (" (ball joint, in Euler angles)" if kind == "euler" else "")}
             for kind, joint, idx in scene["layout"]]
    rows += [{"joint": joint, "role": "dependent: each engine solves it from the coordinates, closing the loop"}
             for joint in scene["dependent"]]
    written = lambda x: f"{case.value(x):g}" if not isinstance(x, str) or not {"t", *case.coords} & \
        {n.removesuffix("_rate") for n in expressions.names(x)} else x  # a number, or the law of t and the state
    rows += [{"joint": joint, "role": "applied generalized force (" + ", ".join(map(written, force.components))
              + ") (joint frame)"} for joint, force in scene["applied"].items()]
    return markdown_table(pd.DataFrame(rows))


def write_case_page(result, case, tmp, animations=True):
    rows = result.rows
    name = case.name
    words = OWN_WORDS if case.one_derivation else {}
    unit = lambda column: state_unit(case, column)
    force = lambda column: reaction_unit(case, column)
    tight = named(words, "tight reference")
    run_of = initial_words(case)

    def coordinates(path):
        worst = figure_series(result, case, case.coords, lambda c: f"{quantity_label(c)} [{unit(c)}]", "coordinates over time",
                              path, words=words)
        return (f"Each coordinate along the run of {run_of}, every source overlaid (line style, marker and"
                f" colour per source). Largest departure from the {tight}: {departures(worst, unit, words)}.")

    def errors(path):
        worst = figure_series(result, case, state_columns(case), lambda c: f"|{quantity_label(c)} error| [{unit(c)}]",
                              f"error against the {tight}", path, words=words, log_error=True)
        return (f"How far each source's run of {run_of} is from the {tight} ({result.runs['reference'].twin.attrs['method']},"
                " a tighter tolerance), each coordinate and rate on a log scale that follows the data; exact"
                f" agreement lies on the bottom edge. Largest: {departures(worst, unit, words)}.")

    def reactions(path):
        worst = figure_series(result, case, list(case.reaction_names), lambda c: f"{quantity_label(c)} [{force(c)}]",
                              "reactions over time", path, words=words)
        return (f"Each reaction along the run of {run_of}, every source overlaid. Largest departure from the"
                f" {tight}: {departures(worst, force, words)}.")

    plots = {  # figure -> how to draw it, returning its caption; the coordinate plots only where there are coordinates
        "scene": lambda path: figure_scene(result, case, path, words=words),
        "coordinates": coordinates,
        "errors": errors,
        "energy": lambda path: figure_energy(result, case, path, words=words),
        "reactions": reactions,
        "pointwise": lambda path: figure_pointwise(result, case, path, words=words),
    }
    if "reference" not in result.sample["values"]:  # nothing to measure the deviations from
        del plots["pointwise"]
    if not case.coords:
        del plots["coordinates"], plots["errors"]
    if not case.reaction_names:
        del plots["reactions"]
    if result.program.get("listing") is not None and case.spec.get("program", {}).get("plots"):
        plots["program"] = lambda path: figure_program(result, case, path)
    along_runs = result.runs["reference"].ok
    if not along_runs:  # the reference run blew up or ran away (rows say when): nothing to draw along it
        plots = {kind: draw for kind, draw in plots.items() if kind in ("pointwise", "program")}
    extras = case.spec["report"].get("figures", {}) if along_runs else {}
    values = case.spec["report"].get("values") if along_runs else None
    spaces = report_namespaces(result, case) if extras or values else {}
    for key, item in extras.items():
        plots[key] = lambda path, item=item: figure_extra(spaces, case, item, path, words=words)
    figures, captions = {}, {}
    for kind, draw in plots.items():
        figures[kind] = f"figures/{name}_{kind}.png"
        captions[kind] = draw(tmp / figures[kind])

    counts = pd.Series([str(r.status) for r in rows]).value_counts()
    table = format_rows(rows)
    table["finding"] = [r.finding or "" for r in rows]
    findings = result.findings
    runs = result.runs
    cost = cost_table(runs, case.one_derivation).drop(columns="wall time [s]")
    lines = [
        f"# {heading(case.spec)}",
        "",
        f"**{result.status}**: " + statuses_in_words(counts)
        + f"; worst pointwise error among {'MuJoCo and Pinocchio' if case.one_derivation else 'reference, MuJoCo and Pinocchio'}"
        f": {worst_engine_error(rows):.1e}"
        + f" (tolerance {case.tolerance['pointwise']['value']:g}). [All cases](index.md)"
        + ("" if case.one_derivation else ", [errata](errata.md)")
        + (f"  \nParameters overridden (`--set`): {case.overrides_text()}; the book's figures and printed data"
           " do not apply to them" if case.overrides else ""),
        "",
        *([f"For students: [the book's procedure step by step]({student_page.page_name(case)}).", ""]
          if "course" in case.spec else []),
        "## The scene",
        "",
        " ".join(case.prose(case.spec["summary"], "summary").split()),
        "",
        *(embed(figures["scene"], "scene", captions["scene"]) if "scene" in figures else ["", ""]),
        "## Parameters",
        "",
        *parameters_table(case, tmp),
        initial_conditions(case),
        "",
        "## How each source models it",
        "",
        "\n\n".join(" ".join(p.split()) for p in case.prose(case.spec["report"]["modelling"], "report.modelling")
                    .strip().split("\n\n")),
        "",
        "Joints of `scene.xml`, which MuJoCo and Pinocchio both read:" if case.pinocchio_scene.name == "scene.xml"
        else f"Joints of `scene.xml` (MuJoCo) and `{case.pinocchio_scene.name}` (Pinocchio), the same in both:",
        "",
        scene_table(case),
        "",
        *(["## Results", "", f"Computed along each source's run of {initial_words(case)}.", "",
           values_table(case, spaces), ""] if values else []),
        "## Checks",
        "",
        f"Random states tried: {random_sentence(random_tried(result, case))}.",
        "",
        "Errors are relative: pointwise to the largest magnitude of the quantity over the random states,"
        " trajectories to the largest magnitude of the coordinate over the run, energy to the largest"
        " |E| or |W|." + ("" if case.one_derivation else
                          "  `finding` marks a disagreement explained by a registered error of the book."),
        "",
        "In short, the worst row of each comparison (error over its tolerance):",
        "",
        markdown_table(summary_table(rows)),
        "",
        *not_passed(rows),
        *not_checked(rows),
        *wrong_equations(result),
        f"<details><summary>All {len(rows)} checks</summary>",
        "",
        markdown_table(table),
        "",
        "</details>",
        "",
    ]
    if findings:
        lines += ["## Findings: where the book is wrong", ""]
        for f in (measured.finding(result, f) for f in findings):
            lines += [f"### {f.id}: {f.title}", "",
                      f"*Where:* {f.where}.  *Largest relative error:* {size(f.error)}"
                      f" (quantities {', '.join(f.quantities)}; comparisons: {', '.join(f.sources)};"
                      f" {f.established})."
                      + (f"  {f.effect}" if f.effect else ""), "",
                      *([f"*Measured in this run:* {f.measured}", ""] if f.measured else []),
                      f"*Localised automatically* (edits of the printed expression searched until one agrees"
                      f" with the engines): {f.localised}.", "", f.explanation, ""]
    vibration_lines, vibration_files = vibration_page.section(result, case, tmp)
    animation_lines, animation_files = animation.section(result, case, tmp, animations)
    sections, study_files = study_sections(result, case, tmp)
    study_files += vibration_files + animation_files
    lines += animation_lines + vibration_lines + sections + [
        "## Figures",
        "",
        *[line for kind, path in figures.items() if kind != "scene" for line in embed(path, kind, captions[kind])],
        "## Tolerances and why",
        "",
    ]
    for kind, tol in case.tolerance.items():
        value = f"{tol['value']:g}" if "value" in tol else f"safety factor {tol['safety']:g}"
        lines += [f"- **{kind}** ({value}): " + " ".join(case.prose(tol["why"], f"tolerance.{kind}.why").split())]
    lines += ["", "## Cost of the runs", "", markdown_table(cost), "",
              f"Wall times, which differ from run to run, are on the [timing page]({timing_page_name(case)}).", ""]
    page = f"{name}.md"
    (tmp / page).write_text("\n".join(lines))
    return [page] + list(figures.values()) + study_files + write_timing_page(result, case, tmp)


def write_unfinished_page(result, case, tmp):
    """The page of a case whose checks did not finish (its process died or overran its budget): its one row says
    why, and there is nothing else to show."""
    (row,) = result.rows
    page = f"{case.name}.md"
    (tmp / page).write_text("\n".join([
        f"# {heading(case.spec)}", "", f"**{result.status}**: {row.detail}. [All cases](index.md)", "",
        "Nothing else was checked: the rows, runs and figures of this case are those of a run that finishes "
        "(docs/isolation.md).", ""]))
    return page


def cost_table(runs, one_derivation):
    """Each source's run of the initial state and its twin: method, setting, wall time, right-hand-side
    evaluations.  A case of one derivation names them in its own words: its run and twin (the book's)
    and the tight solution (the reference's twin; the reference's run repeats the book's)."""
    shown = ([("derivation", runs["book"].run), ("derivation", runs["book"].twin),
              ("tight solution", runs["reference"].twin)] if runs["book"].ok else []) if one_derivation else \
        [(s, run) for s in ("reference", "book") if runs[s].ok for run in (runs[s].run, runs[s].twin)]
    shown += [(s, run) for s in ("pinocchio", "mujoco") if runs[s].ok for run in (runs[s].run, runs[s].twin)]
    return pd.DataFrame([{"source": s, "method": run.attrs["method"],
                          "setting": f"dt = {run.attrs['dt']:g} s" if run.attrs["dt"] else f"rtol = {run.attrs['rtol']:g}",
                          "wall time [s]": f"{run.attrs['wall']:.3f}", "evaluations": run.attrs["evaluations"]}
                         for s, run in shown], columns=["source", "method", "setting", "wall time [s]", "evaluations"])


def sweep_in_words(sweep, case):
    """The work-precision sweep with its sources named as the case's pages name them (OWN_WORDS for a case
    of one derivation), for its tables and charts."""
    if not case.one_derivation:
        return sweep
    shown = sweep.assign(source=sweep["source"].map(lambda s: OWN_WORDS.get(s, s)))
    shown.attrs = sweep.attrs
    return shown


def initial_words(case):
    return "the initial state" if case.one_derivation else "the book's initial conditions"


def timing_page_name(case):
    return f"{case.name}_timing.md"


def write_timing_page(result, case, tmp):
    """<case>_timing.md and its chart and CSV: every time of the run, apart from the case page because times
    differ from run to run (the page stays the same when nothing else changed)."""
    studies = result.studies
    lines = [f"# {heading(case.spec)}: times", "",
             f"Times of this run on this machine, which differ from run to run; [the case page]({case.name}.md).",
             "", f"All checks of this case took {result.wall:.1f} s.", "",
             f"## The runs of {initial_words(case)}", "",
             markdown_table(cost_table(result.runs, case.one_derivation)), ""]
    files = [timing_page_name(case)]
    if studies and not studies["work_precision"].empty:
        frame = sweep_in_words(studies["work_precision"], case)
        missing = set(work_precision.TIMING_COLUMNS) - set(frame.columns)
        if missing:  # results saved before the column was measured: nothing to rank by
            raise ValueError(f"{case.name}: the saved work-precision sweep lacks {', '.join(sorted(missing))} (saved"
                             " by an earlier dyncheck); make the results again with `dyncheck report`")
        csv, chart = (f"data/{case.name}_work_precision_timing.csv",
                      f"figures/{case.name}_work_precision_timing.png")
        work_precision.write_csv(frame, tmp / csv, timing=True)
        cpu_caption = work_precision.figure(frame, case, tmp / chart, cost="cpu")
        files += [csv, chart]
        best = work_precision.cheapest(frame, cost="cpu")
        labels = {work_precision.point_label(r): r for _, r in frame.iterrows()}

        def cpu_times(label):
            r = labels.get(label)
            return "-" if r is None or pd.isna(r["cpu"]) else \
                f"{r['cpu_min']:.3g} (median {r['cpu']:.3g}, slowest {r['cpu_max']:.3g}; {r['repeats']:g} run{'s' * (r['repeats'] > 1)})"
        table = pd.DataFrame({"level": best["level"].map(lambda x: f"{x:.0e}"),
                              "fewest evaluations": work_precision.cheapest(frame)["cheapest"],
                              "least CPU time": best["cheapest"],
                              "CPU [s]: fastest (median, slowest)": best["points"].map(
                                  lambda points: "; ".join(map(cpu_times, points)) or "-"),
                              "runner-up in CPU time": best["runner_up"],
                              "runner-up CPU [s]": best["runner_up"].map(cpu_times)})
        lines += ["## Speed against accuracy in CPU time", "",
                  f"The work-precision sweep of [the case page]({case.name}.md#speed-against-accuracy) against CPU"
                  " time: the integration alone, the median of repeated runs (quick runs are repeated, as the"
                  " case file's `work_precision.repeat` says), the bars from the fastest to the slowest.  "
                  + CPU_TIME + "  " + work_precision.CPU_NOTE, "",
                  *embed(chart, "work-precision, CPU time", cpu_caption),
                  "Which method reaches each accuracy level (relative trajectory error) in the least CPU time, beside"
                  " the fewest evaluations (the case page's ranking).  " + CPU_TIES, "",
                  markdown_table(table), "", f"The rows behind the chart: [{csv}]({csv}).", ""]
    if studies and studies["stability"]:
        lines += ["## Stability studies", "", markdown_table(pd.DataFrame(
            [{"study": s.title, "wall time [s]": f"{s.wall:.1f}"} for s in studies["stability"]])), ""]
    (tmp / files[0]).write_text("\n".join(lines))
    return files


def wrong_equations(result):
    """The page's account of where the derivation's equations are wrong (dyncheck.checks.residuals): each with the
    terms that explain it, and how many failing rows are its consequences."""
    if not result.localisations:
        return []
    follow = consequences(result)
    return ["### Where the derivation is wrong", "",
            "Each equation whose residual M_engine (q''_derivation - q''_engine) fails against MuJoCo, and each"
            " reaction that fails while the equations hold, fitted over the random states and parameter sets by a"
            " few terms in the derivation's own symbols:", "",
            *[f"- {loc}" for loc in result.localisations], "",
            *([f"Other failing rows, which compare quantities computed from these equations (accelerations, runs,"
               f" energy): {len(follow)}, consequences, not further errors.", ""] if follow else [])]


def study_sections(result, case, tmp):
    """The page's speed-against-accuracy, convergence and stability sections, and the files they use.
    result.studies is None when `dyncheck report --no-studies` left them out."""
    studies = result.studies
    convergence = [r for r in result.rows if r.check == "convergence"]
    lines, files = ["## Speed against accuracy", ""], []
    if studies is None:
        lines += ["Not run this time (`dyncheck report --no-studies`).", ""]
    elif studies["work_precision"].empty:
        lines += [work_precision.NO_SWEEP, ""]
    else:
        frame = sweep_in_words(studies["work_precision"], case)
        csv, chart = f"data/{case.name}_work_precision.csv", f"figures/{case.name}_work_precision.png"
        work_precision.write_csv(frame, tmp / csv)
        caption = work_precision.figure(frame, case, tmp / chart)
        files += [csv, chart]
        reference = frame.attrs["reference"]
        unstable = frame[frame["status"] == "unstable"]
        best = work_precision.cheapest(frame).drop(columns=["points", "methods"])
        best["level"] = best["level"].map(lambda x: f"{x:.0e}")
        for column in ("evaluations", "runner_up_evaluations"):
            best[column] = best[column].map(lambda x: "-" if pd.isna(x) else f"{x:.0f}")
        best["error"] = best["error"].map(lambda x: "-" if pd.isna(x) else f"{x:.3g}")
        solution = ("the tight solution: the derivation" if case.one_derivation else
                    "the reference solution: the reference's equations")
        lines += [f"Every method from {initial_words(case)} over {reference['t_end']:g} s, against"
                  f" {solution} by {reference['label']}.  Error is the largest deviation of any"
                  " coordinate or rate, relative to its largest magnitude; the rows behind the chart are in"
                  f" [{csv}]({csv}).  {work_precision.EVALUATIONS_NOTE}", "",
                  *embed(chart, "work-precision", caption),
                  "Which method is cheapest (fewest evaluations) at each accuracy level (relative trajectory"
                  f" error); in CPU time on the [timing page]({timing_page_name(case)}):", "",
                  markdown_table(best.rename(columns={"runner_up": "runner-up",
                                                      "runner_up_evaluations": "runner-up evaluations"})), ""]
        if len(unstable):
            lines += ["Unstable (blew up; not drawn): " + "; ".join(
                f"{work_precision.point_label(r)}: {r['detail']}" for _, r in unstable.iterrows()) + ".", ""]
    if convergence:
        lines += ["## Convergence", "",
                  "Observed order of each fixed-step method, from runs at h, h/2, h/4 (checks; tolerance from"
                  " the next term of the error expansion, see the case file):", "",
                  markdown_table(pd.DataFrame([{"method": r.quantity, "source": r.comparison,
                                                "|observed - expected|": "-" if r.error is None else f"{r.error:.3f}",
                                                "tolerance": "-" if r.tolerance is None else f"{r.tolerance:.3f}",
                                                "status": str(r.status), "detail": r.detail} for r in convergence])),
                  ""]
    elif case.coords:  # without coordinates the speed section has said that nothing is integrated
        lines += ["## Convergence", "", "No fixed-step method is checked for this case.", ""]
    if studies and studies["stability"]:
        lines += ["## Stability: where methods fail", ""]
        for study in studies["stability"]:
            lines += [f"### {study.title}", "", *[f"- {sentence}" for sentence in study.findings], ""]
            chart = f"figures/{case.name}_{study.study}.png"
            caption = stability.figure(case, study, tmp / chart)
            if caption is None:  # not applicable at these parameters: nothing measured, nothing drawn
                lines += [f"*How, where it applies:* {study.why}", ""]
                continue
            if not (tmp / chart).is_file():  # a case's own figure function that drew nothing
                raise ValueError(f"{case.origin}: stability study {study.study}: its figure function wrote no {chart}")
            files.append(chart)
            lines += [*embed(chart, study.study, caption),
                      f"*How:* {study.why}", "",
                      f"<details><summary>The numbers ({plural(len(study.table), 'row')})</summary>", "",
                      markdown_table(study.table), "", "</details>", ""]
    return lines, files


def parameters_table(case, tree):
    """The page's table of parameters, and where the book's program gives one, what the listing shows; `tree`: the
    folder the page is written in, from which the link to docs/book-numbers.md goes."""
    printed = any(p.printed for p in case.parameters)
    table = pd.DataFrame([{"parameter": p.name, "value": f"{p.value:.10g}", "unit": p.unit, "allowed": p.allowed,
                           **({"as printed": as_printed(p)} if printed else {}),
                           "meaning": p.about + (" (overridden)" if p.name in case.overrides else "")}
                          for p in case.parameters])
    # ../docs from the book's report trees, top-level folders of the checkout (reports/, reports-NAME=VALUE/); from
    # an --out elsewhere, the way to this checkout's docs
    book_numbers = Path(os.path.relpath(CASES_DIR.parent / "docs" / "book-numbers.md", tree)).as_posix()
    return [markdown_table(table), "",
            *(["*As printed*: the value in the book's program listing as the book's text extraction shows it.  The"
               " extraction lost every digit 0; each value was read back by replaying the listing for every way of"
               " restoring the zeros and keeping the one that lands inside the book's figures ([the book's"
               f" numbers]({book_numbers}), example by example).", ""] if printed else [])]


def as_printed(parameter):
    """A parameter's value as the book's listing shows it and as read, for the parameters table."""
    if parameter.printed is None:
        return "-"
    read = f"{parameter.default:.10g}"
    return f"printed `{parameter.printed}`" + ("" if parameter.printed == read else
                                                f", read {read} (digits 0 lost in extraction)")


def initial_conditions(case):
    """The page's line on the initial state and the horizon; a scene with no free coordinate starts where its
    prescribed motions put it, and the line gives their laws instead."""
    q0, v0, t_end = case.initial
    state = _state(case.coords, q0, v0) if case.coords else "none, every joint moves as prescribed: " + ", ".join(
        f"{joint} = {law_of_time(*law)}" for joint, law in case.scene["driven"].items())
    label = "Initial conditions" if case.one_derivation else "Initial conditions (the book's)"
    return f"{label}: {state}; horizon {t_end:g} s."


def _state(coords, q, v):
    return ", ".join(f"{c} = {x:.6g}" for c, x in zip(coords, q)) + ", " + \
        ", ".join(f"{c}' = {x:.6g}" for c, x in zip(coords, v))


def law_of_time(angle, rate, acc):
    """A prescribed motion angle + rate t + acc t^2/2 with its zero terms left out: "0.8 + 0.3 t - 0.05 t^2"."""
    terms = [f"{coefficient:.6g}{power}" for coefficient, power in ((angle, ""), (rate, " t"), (acc / 2, " t^2"))
             if coefficient]
    return " + ".join(terms).replace("+ -", "- ") or "0"


SUMMARY_KEYS = {"case", "section", "params", "checks", "findings", "title", "status", "worst_engine_error",
                "random", "cheapest", "one_derivation"}  # what write_summary writes


def summaries(tree, out):
    """The summary of every case in `tree`'s data/, in book order.  A file there that write_summary
    did not write (foreign, broken, of another version) is skipped with a warning naming it in `out`."""
    cases = []
    for path in sorted((tree / "data").glob("*.json")):
        try:
            summary = json.loads(path.read_text())
        except (ValueError, RecursionError):  # not JSON, not UTF-8, or nested too deeply
            summary = None
        if isinstance(summary, dict) and SUMMARY_KEYS <= summary.keys() and summary["case"] == path.stem:
            cases.append(summary)
        else:
            print(f"dyncheck: warning: {out / 'data' / path.name} is not a case summary that dyncheck report"
                  " wrote; left out of the index", file=sys.stderr)
    return sorted(cases, key=lambda c: section_key(str(c["section"])))


def section_key(section):
    """Book order for any section string: numbers as numbers ("1.9" before "1.10"), the rest as
    text ("1.7" before "1.7a", all of them before "new")."""
    parts = re.split(r"([0-9]+)", section)  # the numbers at the odd places
    return [(0, int(part)) if i % 2 else (1, part) for i, part in enumerate(parts)]


def with_overrides(summary):
    """", with k = 500 N/m (book: 2000)" for a case run with overrides, else nothing."""
    return f", with {summary['overridden']}" if summary.get("overridden") else ""


def typeset_pair(pair):
    """A finding's Pair as the errata show it: both sides in LaTeX, what differs boxed, and their origins."""
    printed, right = typeset.marked(pair.printed, pair.right, pair.symbols)
    lhs = typeset.latex(pair.lhs, pair.symbols) + " = " if pair.lhs else ""
    return {"printed": lhs + printed, "right": lhs + right, "printed_from": pair.printed_from,
            "right_from": pair.right_from}


def errata_pairs(pairs):
    """The lines of a finding's typeset pairs: "As printed" and "Right", each a display formula."""
    lines = []
    for pair in pairs:
        lines += [f"*As printed* ({pair['printed_from']}):", "", "$$", pair["printed"], "$$", "",
                  f"*Right* ({pair['right_from']}):", "", "$$", pair["right"], "$$", ""]
    return lines


def write_errata(tmp, cases):
    """errata.md: every finding of every case in one table, then each in full."""
    table = [{"finding": f"[{f['id']}](#{f['id'].replace('.', '').lower()})",
              "case": f"[{c['case']}]({c['case']}.md)" + with_overrides(c),
              "where": f["where"], "what": f["title"], "largest relative error": size(f["error"]),
              "localised edit": f["localised"]}
             for c in cases for f in c["findings"]]
    lines = ["# Errata: where the book is wrong", "",
             "Each finding is a disagreement between the book and the engines that an error of the book"
             " explains.  It is registered in its case file and checked on every run: if the book's"
             " version ever agrees with the engines, the run fails.  [All cases](index.md)", "",
             markdown_table(pd.DataFrame(table)) if table else "No findings.", ""]
    for c in cases:
        for f in c["findings"]:
            lines += [f"## {f['id']}", "",
                      f"**{f['title']}** ([{c['case']}]({c['case']}.md), {c['section']}{with_overrides(c)})", "",
                      f"- *Where:* {f['where']}",
                      f"- *Quantities:* {', '.join(f['quantity'])}; largest relative error {size(f['error'])}",
                      f"- *How established:* {f['established']}",
                      *([f"- *Effect:* {f['effect']}"] if f["effect"] else []),
                      *([f"- *Measured in this run:* {f['measured']}"] if f.get("measured") else []),
                      f"- *Localised edit:* {f['localised']}", "",
                      *errata_pairs([pair for pair in c.get("typeset", []) if pair["finding"] == f["id"]]),
                      f["explanation"], ""]
    programs = [c for c in cases if (tmp / f"figures/{c['case']}_program.png").exists()]
    if programs:
        lines += ["## The book's programs: its figures redrawn", "",
                  "Each figure the book draws from a program, from a line-by-line transcription of that"
                  " program (left) and from the reference's equations integrated tightly (right), on the"
                  " book's axes.", ""]
        for c in programs:
            lines += [f"### {c['section']} ([{c['case']}]({c['case']}.md))", "",
                      *embed(f"figures/{c['case']}_program.png", "program",
                             f"The book's figures of {c['section']} redrawn from its program (left, red dashed) and from"
                             " the reference's equations integrated tightly (right, black), each panel titled as the"
                             " book's; the dashed grey frame is the book's printed axes. The case page says when the"
                             " program leaves that motion.")]
    (tmp / "errata.md").write_text("\n".join(lines))
    return "errata.md"


def speed_table(tmp, cases):
    """Index lines: for each case with a work-precision sweep, the cheapest method at each accuracy, and in
    short which methods are cheapest (in CPU time: index_timing.md)."""
    rows = [{"case": f"[{c['case']}]({c['case']}.md#speed-against-accuracy)", **c["cheapest"]}
            for c in cases if c.get("cheapest")]
    if not rows:
        return []
    return ["The cheapest method (fewest right-hand-side evaluations) that reaches each relative trajectory error, from each"
            " case's work-precision sweep (details, charts and the stability studies on the case pages):", "",
            markdown_table(pd.DataFrame(rows).fillna("-")), "",
            f"In short, {work_precision.in_short(sweeps(tmp, cases))}.  In CPU time, which differs from run to run:"
            f" [{INDEX_TIMING}]({INDEX_TIMING}).", ""]


INDEX_TIMING = "index_timing.md"
CPU_TIME = ("A run's CPU time is the wall time it takes on an idle core: other processes' load on the machine,"
            " which stretches wall times by factors, leaves it out.")
CPU_TIES = ("Each point ranks by its fastest run: what slows a run only adds time, and on a shared machine it adds it"
            " to most runs now and then, while the fastest run of a point moves by about 10% between regenerations."
            f"  A method is the cheapest only when its fastest run is faster than every other method's by more than"
            f" {work_precision.REPRODUCIBILITY:.0%}; else the methods that cannot be told apart are named together.  The"
            f" runs that decide it are {work_precision.DECIDING_REPEATS} of each point, taken in turns with the other"
            " points' runs.")


def sweeps(tmp, cases, timing=False):
    """{case: its work-precision sweep as data/ holds it} for the cases with one (and their CPU times: timing).
    A timing file without every CPU-time column (an earlier version's) is left out with a warning naming it."""
    def csv(case, suffix):
        return tmp / "data" / f"{case}_work_precision{suffix}.csv"
    out = {}
    for case in (c["case"] for c in cases if c.get("cheapest")):
        frame = work_precision.read_csv(csv(case, ""), csv(case, "_timing") if timing else None)
        if timing and not set(work_precision.TIMING_COLUMNS) <= set(frame.columns):
            print(f"dyncheck: warning: data/{csv(case, '_timing').name} lacks CPU-time columns"
                  f" ({', '.join(sorted(set(work_precision.TIMING_COLUMNS) - set(frame.columns)))}; an earlier"
                  f" version's): left out of {INDEX_TIMING}", file=sys.stderr)
            continue
        out[case] = frame
    return out


def write_index_timing(tmp, cases):
    """index_timing.md: the index's speed table and sentence in CPU time, apart from the index because CPU
    times differ from run to run; [] and none (an earlier one removed) when no case has a sweep."""
    timed = sweeps(tmp, cases, timing=True)
    if not timed:
        (tmp / INDEX_TIMING).unlink(missing_ok=True)
        return []
    rows = [{"case": f"[{case}]({case}_timing.md)",
             **{f"{r['level']:.0e}": r["cheapest"] for _, r in work_precision.cheapest(frame, cost="cpu").iterrows()}}
            for case, frame in timed.items()]
    lines = ["# dyncheck reports: times", "",
             "Times of the last report on this machine, which differ from run to run; [the index](index.md).", "",
             "The cheapest method in CPU time that reaches each relative trajectory error, from each case's"
             " work-precision sweep (its timing page has the times).  " + CPU_TIME + "  " + CPU_TIES, "",
             markdown_table(pd.DataFrame(rows).fillna("-")), "",
             f"In short, {work_precision.in_short(timed, cost='cpu')}.", ""]
    (tmp / INDEX_TIMING).write_text("\n".join(lines))
    return [INDEX_TIMING]


def write_index(tmp, cases):
    """index.md over `cases` (the summaries)."""
    rows = []
    for case in cases:
        counts = pd.Series([c["status"] for c in case["checks"]]).value_counts()
        rows.append({
            "case": f"[{case['case']}]({case['case']}.md)" + (f" ([step by step]({case['case']}_student.md))" if
                                                                (tmp / f"{case['case']}_student.md").is_file() else ""),
            "section": case["section"],
            "title": case["title"] + with_overrides(case),
            "status": case["status"].upper(), "checks": statuses_in_words(counts),
            "worst engine error": "-" if case["worst_engine_error"] is None else f"{case['worst_engine_error']:.1e}",
            "findings": ", ".join(f"{f['id']} ({size(f['error'], '.2g')})" for f in case["findings"]) or "none"})
    compared = [c for c in cases if c["random"]["agreed"] is not None]
    tried = [c["random"] for c in compared]
    states = sum(t["states"] + t["parameter_sets"] * t["states_per_set"] for t in tried)
    disagreed = [c["case"] for c in compared if not c["random"]["agreed"]]
    not_compared = [c["case"] for c in cases if c["random"]["agreed"] is None]
    book = not any(c["one_derivation"] for c in cases)  # the book's examples, or (also) researchers' own cases
    derivations = "`reference`" if book else "the derivations"
    lines = ["# dyncheck reports", "",
             ("The worked examples of I. F. Santos, *Dynamics of Machines*, ch. 1, checked against MuJoCo"
              " and Pinocchio." if book else "Each case's derivation checked against MuJoCo and Pinocchio.")
             + f"  *Worst engine error* is the largest pointwise relative error among {derivations}, MuJoCo and"
             " Pinocchio (accelerations, reactions, energy, drive power)"
             + ("; a finding is an error of the book, with the largest relative error it causes: all of them"
                " are in the [errata](errata.md)." if any(c["findings"] for c in cases) else "."), "",
             markdown_table(pd.DataFrame(rows)), "",
             *speed_table(tmp, cases),
             *vibration_page.index_lines(cases, book),
             f"The last run tried {plural(sum(t['parameter_sets'] for t in tried), 'random parameter set')} besides"
             f" {'the book' if book else 'each case'}'s and {plural(states, 'random state')} in all"
             f" ({plural(len(compared), 'case')};"
             f" seeds on each case page): {derivations}, MuJoCo and Pinocchio "
             + (f"disagreed in {', '.join(disagreed)}." if disagreed else
                "agreed at every one of them within the pointwise tolerance.")
             + (f"  Not compared: {', '.join(not_compared)}, whose checks did not finish." if not_compared else ""),
             ""]
    (tmp / "index.md").write_text("\n".join(lines))
    return "index.md"
