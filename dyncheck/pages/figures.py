"""The case page's figures, drawn from the saved results: the scene, the runs' series and their errors, the
energy balance, the pointwise comparisons, the case file's own figures, the book's program beside the exact
motion."""

import re
import textwrap

import numpy as np

from dyncheck.common.expressions import evaluate, namespace
from dyncheck.common.messages import ENGINE_NAMES
from dyncheck.common.style import (TEXT_HEIGHT, TEXT_WIDTH, along, leave_out, legend_below, log_range, panels,
                                   pyplot, save, thin, title)
from dyncheck.common.style import SOURCE_STYLE as STYLE
from dyncheck.pages import typeset
from dyncheck.results.values import heading
from dyncheck.run.simulate import energy_residual


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
    """The scene at t = 0, every body as the animation draws it (its first frame: engines.render.skeleton), and the
    path of each traced point mass along the tight run; returns the caption."""
    tight = trajectories(result)["tight reference"]
    origins = result.drawings["scene"]["origins"]
    skeleton = result.drawings["animation"]["exact"]  # its first frame is t = 0
    paths = np.array([tight[[f"{body}_{axis}" for axis in "xyz"]].to_numpy() for body in case.scene.paths])
    paths = paths.reshape(len(case.scene.paths), len(tight), 3).transpose(1, 0, 2)  # (time, body, xyz)
    paths = thin(paths)
    drawn = np.concatenate([paths.reshape(-1, 3), origins, skeleton.dots[0], skeleton.segments[0].reshape(-1, 3),
                            skeleton.rims[0].reshape(-1, 3)])
    flat = [i for i in range(3) if np.ptp(drawn[:, i]) < 1e-12]  # a planar scene: drawn in its plane
    used = [i for i in range(3) if i != flat[-1]] if flat else [0, 1, 2]
    fig = pyplot().figure(figsize=(TEXT_WIDTH, 4.6))
    ax = fig.add_subplot(projection=None if flat else "3d")
    pick = lambda xyz: np.asarray(xyz)[..., used].T
    for segment in skeleton.segments[0]:
        ax.plot(*pick(segment), color="0.3", lw=2)
    for ring in skeleton.rims[0]:
        ax.plot(*pick(ring), color="tab:green", lw=1.2)
    ax.scatter(*pick(np.vstack([np.zeros(3), origins])), color="0.3", s=12)  # the world's origin, the bodies'
    sizes = 40 * (skeleton.masses / skeleton.masses.max()) ** (2 / 3) + 10 if len(skeleton.masses) else []
    ax.scatter(*pick(skeleton.dots[0]), color="0.1", s=sizes, zorder=4)
    lines = ("-", "--", ":", "-.")  # one per body's path: told apart in grey
    for b, name in enumerate(case.scene.paths):
        ax.plot(*pick(paths[:, b]), lw=0.8, ls=lines[b % len(lines)], label=f"path of {name}")
        ax.scatter(*pick(paths[0, b]), s=40, marker="o", zorder=5)
    labels = [f"{axis} [m]" for axis in "xyz"]
    ax.set_xlabel(labels[used[0]])
    ax.set_ylabel(labels[used[1]])
    if flat:
        ax.set_aspect("equal")
    else:
        ax.set_zlabel("z [m]")
    ax.set_title(titled(case, "the scene at t = 0" + (" and the path in space" if case.scene.paths else "")))
    legend_below(fig)
    save(fig, path)
    moving = ", ".join(case.scene.paths)
    rings = "; a green ring, the disk of a rigid body's largest principal moment" if skeleton.rims.shape[1] else ""
    return ("The bodies at t = 0: grey lines from each body's origin (small dots) to what hangs on it and to its "
            f"centre of mass (large dots, by mass){rings}"
            + (f"; the path of {moving} over 0-{tight.index[-1]:g} s"
               f" ({named(words, 'tight reference')}); axes in metres, {'the plane of motion' if flat else 'in space'}."
               if moving else "; axes in metres."))


FULL_LABEL_ROWS = 5  # rows of panels whose y labels fit on one line beside them: "|theta_1' error| [rad/s]"


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
        # a label longer than a panel of many rows is tall: its unit under it
        ax.set_ylabel(ylabel(column).replace(" [", "\n[", 1) if rows > FULL_LABEL_ROWS else ylabel(column))
    leave_out(axes, len(columns), "t [s]")
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
    return "N m" if case.scene.reactions[name].quantity == "moment" else "N"


POINT_SOURCES = ("book", "mujoco", "pinocchio")  # the sources whose deviation from the reference is drawn


def figure_pointwise(result, case, path, *, words):
    """Per random state, each source's deviation from `reference`, relative to the quantity's scale, in a
    grid of at most four panels across; returns the caption."""
    values = result.sample["values"]
    quantities = list(values["reference"])
    tolerance = case.tolerance["pointwise"]["value"]
    # absent: its evaluation failed; named as the reference (a researcher's derivation is both): no deviation
    drawn = [s for s in POINT_SOURCES if s in values and named(words, s) != named(words, "reference")]
    deviations = {}
    for quantity in quantities:
        ref = values["reference"][quantity]
        scale = np.max(np.abs(ref)) or 1.0
        deviations[quantity] = {source: np.abs(values[source][quantity] - ref) / scale for source in drawn}
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
        ax.set_xlim(-0.6, len(drawn) - 0.4)
        ax.set_ylim(low, high)
        ax.set_title(quantity_label(quantity), fontsize=8)
    leave_out(axes, len(quantities))
    reference = named(words, "reference")
    fig.supylabel(f"relative deviation from the {reference} [1]" if rows > 1 else "relative deviation [1]", fontsize=9)
    fig.suptitle(titled(case, f"pointwise, {len(result.sample['states'])} random states"))
    legend_below(fig, ncol=4)
    save(fig, path)
    worst = {source: max((d[source].max(), q) for q, d in deviations.items()) for source in drawn}
    return (f"Each source's deviation from the {reference} at each of the {len(result.sample['states'])} random"
            f" states, |source - {reference}| / max |{reference}| over the states, one panel per quantity (marker and colour per"
            f" source; exact agreement on the bottom edge); dashed: the tolerance {tolerance:g}. The largest: "
            + ", ".join(f"{named(words, s)} {w[0]:.1e} ({w[1]})" for s, w in worst.items()) + ".")


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


