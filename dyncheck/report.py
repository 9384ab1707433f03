"""Markdown reports with figures: reports/<case>.md per case and reports/index.md.

The new report is built whole in a folder beside the old one and swapped in with one atomic
rename, so a failed, interrupted or killed run leaves the previous report intact.
"""

import ctypes
import errno
import fcntl
import json
import os
import re
import shutil
import sys
from contextlib import contextmanager
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from dyncheck.checks import ENGINES, energy_residual, findings_of, state_columns  # noqa: E402
from dyncheck.cli import OK_STATUSES, format_rows, to_json  # noqa: E402
from dyncheck.expressions import evaluate, namespace  # noqa: E402
from dyncheck import stability, work_precision  # noqa: E402

STYLE = {  # source -> line style, so that coinciding curves stay visible
    "tight reference": dict(color="black", lw=2.6, alpha=0.35),
    "book": dict(color="tab:red", lw=1.0, ls="--"),
    "pinocchio": dict(color="tab:blue", lw=1.0, ls=":"),
    "mujoco": dict(color="tab:green", lw=1.0, ls="-."),
    "reference": dict(color="tab:orange", lw=1.0, ls=(0, (1, 3))),
}


def write_reports(results, out):
    """Write the pages of `results` into the folder `out`, keeping what it holds of other cases, and
    return the files written (relative to `out`).

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
            written = []
            for res in results:
                written += write_case_page(res, tree)
                written.append(write_summary(res, tree))
            cases = summaries(tree, out)
            written += [write_index(tree, cases), write_errata(tree, cases)]
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


def write_summary(res, tmp):
    """data/<case>.json: the case's results (the schema of `dyncheck run --json`) for the index."""
    rows = res["rows"]
    studies = res.get("studies")
    sweep = studies["work_precision"] if studies else None
    summary = {**to_json([res])["cases"][0], "title": res["case"].title, "status": status_of(rows),
               "worst_engine_error": worst_engine_error(rows), "random": random_tried(res),
               "cheapest": None if sweep is None or sweep.empty else  # for the index: level -> method
               {f"{r['level']:.0e}": r["cheapest"] for _, r in work_precision.cheapest(sweep).iterrows()}}
    rel = f"data/{res['case'].name}.json"
    (tmp / rel).write_text(json.dumps(summary, indent=1) + "\n")
    return rel


# -- figures ------------------------------------------------------------------------

def trajectories(res):
    """{label: DataFrame} of the book's run for every source, the tight reference first."""
    runs = res["runs"]
    out = {"tight reference": runs["reference"][1]}
    out.update({s: runs[s][0] for s in ("book", "pinocchio", "mujoco") if isinstance(runs[s], tuple)})
    return out


def figure_scene(res, path):
    case = res["case"]
    model = case.model("mujoco")
    tight = trajectories(res)["tight reference"]
    q = tight[list(case.coords)].to_numpy()
    paths = np.array([model.points(t, qi)[0] for t, qi in zip(tight.index, q)])  # (time, body, xyz)
    _, origins, parents = model.points(0.0, q[0])
    planar = np.ptp(paths[..., 2]) < 1e-12 and np.ptp(origins[:, 2]) < 1e-12
    fig = plt.figure(figsize=(6.4, 5.2))
    ax = fig.add_subplot(projection=None if planar else "3d")
    dims = 2 if planar else 3
    chain = np.vstack([np.zeros(3), origins])  # body 0 is the world origin
    for i, parent in enumerate(parents):
        seg = chain[[parent, i + 1], :dims].T
        ax.plot(*seg, color="0.3", lw=2)
    ax.scatter(*chain[:, :dims].T, color="0.3", s=12)
    body_ids = [model.body_id(name) for name in case.scene["paths"]]
    for b, name in enumerate(case.scene["paths"]):
        arm = np.vstack([origins[body_ids[b] - 1], paths[0, b]])  # body origin to its point mass
        ax.plot(*arm[:, :dims].T, color="0.3", lw=2)
        ax.plot(*paths[:, b, :dims].T, lw=0.6, label=f"{name} (tight reference, 0-{tight.index[-1]:g} s)")
        ax.scatter(*paths[0, b, :dims], s=40, marker="o", zorder=5)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if planar:
        ax.set_aspect("equal")
    else:
        ax.set_zlabel("z [m]")
    ax.set_title(f"{case.section} {case.title}\nthe scene at t = 0 (grey) and the path in space", fontsize=9)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_series(res, columns, ylabel, title, path, log_error=False):
    """Columns over time from every source, overlaid; with log_error, |source - tight reference|."""
    runs = trajectories(res)
    tight = runs["tight reference"]
    fig, axes = plt.subplots(len(columns), 1, figsize=(7.5, 2.3 * len(columns)), sharex=True, squeeze=False)
    for ax, column in zip(axes[:, 0], columns):
        for label, run in runs.items():
            if log_error:
                if label == "tight reference":
                    continue
                ax.semilogy(run.index, (run[column] - tight[column]).abs() + 1e-300, label=label,
                            **{**STYLE[label], "ls": "-", "lw": 0.8, "alpha": 0.8})
            else:
                ax.plot(run.index, run[column], label=label, **STYLE[label])
        ax.set_ylabel(ylabel(column), fontsize=8)
        ax.grid(alpha=0.3)
        if log_error:
            ax.set_ylim(bottom=1e-16)
    axes[0, 0].legend(fontsize=7, ncol=4, loc="lower left", bbox_to_anchor=(0, 1.0), frameon=False)
    fig.suptitle(title, fontsize=9)
    axes[-1, 0].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_energy(res, path):
    case = res["case"]
    runs = trajectories(res)
    driven = case.driven
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 5.2), sharex=True)
    tight = runs["tight reference"]
    top.plot(tight.index, tight["energy"] - tight["energy"].iloc[0], label="E(t) - E(0)", **STYLE["tight reference"])
    if driven:
        top.plot(tight.index, tight["work"], label="W(t), work of the prescribed motions", color="tab:purple", lw=1)
    top.set_ylabel("[J]")
    top.set_title("energy balance" + (": E(t) - E(0) = W(t)" if driven else ": E(t) = E(0)")
                  + " (tight reference)", fontsize=9)
    top.legend(fontsize=7, loc="upper right", framealpha=0.9)
    top.grid(alpha=0.3)
    for label, run in runs.items():
        bottom.semilogy(run.index, energy_residual(run).abs() + 1e-300, label=label,
                        **{**STYLE[label], "ls": "-", "lw": 0.8})
    bottom.set_ylim(bottom=1e-16)
    bottom.set_ylabel("|E(t) - E(0) - W(t)| [J]", fontsize=8)
    bottom.set_xlabel("t [s]")
    bottom.legend(fontsize=7, ncol=4, loc="lower left", bbox_to_anchor=(0, 1.0), frameon=False)
    bottom.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_pointwise(res, path):
    """Per random state, each source's deviation from `reference`, relative to the quantity's scale."""
    values = res["sample"]["values"]
    quantities = list(values["reference"])
    fig, axes = plt.subplots(1, len(quantities), figsize=(2.3 * len(quantities), 3.2), sharey=True)
    for ax, quantity in zip(np.atleast_1d(axes), quantities):
        ref = values["reference"][quantity]
        scale = np.max(np.abs(ref)) or 1.0
        for i, source in enumerate(("book", "mujoco", "pinocchio")):
            dev = np.abs(values[source][quantity] - ref) / scale
            ax.semilogy(np.full(len(dev), i) + np.linspace(-0.25, 0.25, len(dev)), dev + 1e-18, ".",
                        ms=3, color=STYLE[source]["color"])
        ax.axhline(1e-9, color="k", lw=0.8, ls="--")
        ax.set_xticks(range(3), ["book", "mujoco", "pinocchio"], rotation=45, fontsize=7)
        ax.set_title(quantity, fontsize=8)
        ax.set_ylim(1e-18, 10)
    np.atleast_1d(axes)[0].set_ylabel("|source - reference| / max |reference|", fontsize=8)
    fig.suptitle(f"pointwise, {len(res['sample']['states'])} random states (dashed: tolerance)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def report_namespaces(res):
    """{source: namespace} along each source's run, for a case's own figures and values."""
    return {label: namespace(res["case"], run) for label, run in trajectories(res).items()}


def figure_extra(res, spaces, item, path):
    """One of a case's own figures: y against x for every source, overlaid."""
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for label, names in spaces.items():
        x, y = (evaluate(item[k], names) for k in ("x", "y"))
        ax.plot(x, y, label=label, **STYLE[label])
    ax.set_xlabel(item["xlabel"])
    ax.set_ylabel(item["ylabel"])
    if item.get("ylim"):
        ax.set_ylim(*item["ylim"])
    if item.get("equal"):
        ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=4, loc="lower left", bbox_to_anchor=(0, 1.0), frameon=False)
    fig.suptitle(item["title"], fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_program(res, path):
    """The book's program figures: left from the listing's run, right from the corrected equations."""
    case, runs = res["case"], res["program"]
    plots = case.spec["program"]["plots"]
    sides = (("listing", runs["listing"], "tab:red"),
             ("corrected", runs["tight"], "black"))
    fig, axes = plt.subplots(len(plots), 2, figsize=(9.0, 2.8 * len(plots)), squeeze=False)
    for row, item in enumerate(plots):
        for col, (label, run, color) in enumerate(sides):
            names = namespace(case, run)
            ax = axes[row, col]
            ax.plot(evaluate(item["x"], names), evaluate(item["y"], names), color=color, lw=0.8)
            for key, setter in (("xlim", ax.set_xlim), ("ylim", ax.set_ylim)):
                if key in item:
                    setter(*item[key])
            ax.set_title(f"{item['title']}: {label}", fontsize=8)
            ax.set_xlabel("t [s]" if item["x"] == "t" else item["x"], fontsize=8)
            ax.grid(alpha=0.3)
    program = case.model("program")
    fig.suptitle(f"{case.section}: the book's figures from its program ({program.integrator}, dt = {program.dt:.3g} s)"
                 " and from the corrected equations; axes as the book's", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def values_table(res, spaces):
    """A case's named results (e.g. the least friction coefficient), computed for every source."""
    rows = []
    for key, item in res["case"].spec["report"].get("values", {}).items():
        row = {"result": item["about"], "unit": item["unit"]}
        for label, names in spaces.items():
            value = float(evaluate(item["expression"], names))
            row[label] = "not reached" if np.isnan(value) else f"{value:.4g}"
        rows.append(row)
    return markdown_table(pd.DataFrame(rows))


# -- pages --------------------------------------------------------------------------

def status_of(rows):
    return "PASS" if all(r["status"] in OK_STATUSES for r in rows) else "FAIL"


def worst_engine_error(rows):
    """Largest pointwise error among reference, MuJoCo and Pinocchio."""
    errors = [r["error"] for r in rows if r["check"] == "pointwise"
              and all(s in ENGINES for s in r["sources"].split(" vs "))]
    return max(errors, default=float("nan"))


def random_tried(res):
    """What the random pointwise checks tried: states at the case's parameters, parameter sets and
    states at each, their seeds, and whether reference and both engines agreed at all of them."""
    case, rows = res["case"], res["rows"]
    sample, params = case.spec["sample"], case.spec["sample"].get("params", {})
    engine_rows = [r for r in rows if r["check"] in ("pointwise", "random parameters")
                   and all(s in ENGINES for s in r["sources"].split(" vs "))]
    return {"states": sample["count"], "seed": sample["seed"], "parameter_sets": params.get("sets", 0),
            "states_per_set": params.get("states", 0), "parameter_seed": params.get("seed"),
            "agreed": all(r["status"] == "pass" for r in engine_rows)}


def random_sentence(tried):
    text = f"{tried['states']} random states at these parameters (seed {tried['seed']})"
    if tried["parameter_sets"]:
        text += (f" and {tried['parameter_sets']} random parameter sets (seed {tried['parameter_seed']}) over the"
                 f" ranges of the case file, {tried['states_per_set']} states each")
    return text


def markdown_table(frame):
    return frame.to_markdown(index=False)


def summary_table(rows):
    """One line per (check, comparison): how many quantities, their statuses, the worst error/tolerance."""
    frame = pd.DataFrame(rows)
    out = []
    for (check, sources), group in frame.groupby(["check", "sources"], sort=False):
        judged = group.dropna(subset=["error", "tolerance"])
        with np.errstate(divide="ignore", invalid="ignore"):  # a zero tolerance: any error is infinitely over
            ratios = np.where(judged["error"] > 0, judged["error"] / judged["tolerance"], 0.0)
        worst = judged.iloc[int(np.argmax(ratios))] if len(judged) else None
        out.append({"check": check, "comparison": sources, "quantities": len(group),
                    "status": ", ".join(f"{n} {s}" for s, n in group["status"].value_counts().items()),
                    "worst": "-" if worst is None else f"{worst['quantity']}: {worst['error']:.2e} / {worst['tolerance']:.2e}"})
    return pd.DataFrame(out)


def scene_table(case):
    """The joints of the engine models: what is free, what is prescribed, what is applied."""
    scene = case.scene
    rows = [{"joint": joint, "role": f"prescribed: {angle:g} + {rate:.6g} t" + (f" + {acc / 2:g} t^2" if acc else "")}
            for joint, (angle, rate, acc) in scene["driven"].items()]
    rows += [{"joint": joint, "role": "free: the book's " + ", ".join(case.coords[i] for i in idx)
              + (" (ball joint, in the book's Euler angles)" if kind == "euler" else "")}
             for kind, joint, idx in scene["layout"]]
    rows += [{"joint": joint, "role": f"applied generalized force {list(force)} (joint frame)"}
             for joint, force in scene["applied"].items()]
    return markdown_table(pd.DataFrame(rows))


def write_case_page(res, tmp):
    case, rows = res["case"], res["rows"]
    name = case.name
    coord_unit = dict(zip(case.coords, case.spec["coord_units"]))
    plots = {  # figure -> how to draw it; the coordinate plots only where there are coordinates
        "scene": lambda path: figure_scene(res, path),
        "coordinates": lambda path: figure_series(res, state_columns(case)[::2], lambda c: f"{c} [{coord_unit[c]}]",
                                                  "coordinates over time, every source overlaid", path),
        "errors": lambda path: figure_series(res, state_columns(case), lambda c: f"|{c} error|",
                                             "error against the tight reference solution", path, log_error=True),
        "energy": lambda path: figure_energy(res, path),
        "reactions": lambda path: figure_series(res, list(case.reaction_names), lambda c: f"{c} [N]",
                                                "reactions over time, every source", path),
        "pointwise": lambda path: figure_pointwise(res, path),
    }
    if not case.coords:
        del plots["coordinates"], plots["errors"]
    if res["program"] and case.spec.get("program", {}).get("plots"):
        plots["program"] = lambda path: figure_program(res, path)
    along_runs = isinstance(res["runs"]["reference"], tuple)
    if not along_runs:  # the reference run blew up (see the unstable rows): nothing to draw along it
        plots = {kind: draw for kind, draw in plots.items() if kind in ("pointwise", "program")}
    extras = case.spec["report"].get("figures", {}) if along_runs else {}
    values = case.spec["report"].get("values") if along_runs else None
    spaces = report_namespaces(res) if extras or values else {}
    for key, item in extras.items():
        plots[key] = lambda path, item=item: figure_extra(res, spaces, item, path)
    figures = {}
    for kind, draw in plots.items():
        figures[kind] = f"figures/{name}_{kind}.png"
        draw(tmp / figures[kind])
    units = case.units

    params = pd.DataFrame([{"parameter": k, "value": f"{v:.10g}", "unit": units[k],
                            "meaning": case.spec["params"][k]["about"]
                            + (" (overridden)" if k in case.overrides else "")}
                           for k, v in case.params.items()])
    q0, v0, t_end = case.initial
    counts = pd.Series([r["status"] for r in rows]).value_counts()
    table = format_rows(rows)
    table["finding"] = [r["finding"] or "" for r in rows]
    findings = findings_of(res)
    runs = res["runs"]
    cost = pd.DataFrame([{"source": s, "method": run.attrs["method"],
                          "setting": f"dt = {run.attrs['dt']:g} s" if run.attrs["dt"] else f"rtol = {run.attrs['rtol']:g}",
                          "wall time [s]": f"{run.attrs['wall']:.3f}", "evaluations": run.attrs["evaluations"]}
                         for s in ("reference", "book", "pinocchio", "mujoco") if isinstance(runs[s], tuple)
                         for run in runs[s]])
    lines = [
        f"# {case.section} {case.title}",
        "",
        f"**{status_of(rows)}**: " + ", ".join(f"{n} {s}" for s, n in counts.items())
        + f"; worst pointwise error among reference, MuJoCo and Pinocchio: {worst_engine_error(rows):.1e}"
        + f" (tolerance {case.tolerance['pointwise']['value']:g}). [All cases](index.md), [errata](errata.md)"
        + (f"  \nParameters overridden: {case.overrides}" if case.overrides else ""),
        "",
        "## The scene",
        "",
        " ".join(case.spec["summary"].split()),
        "",
        f"![scene]({figures['scene']})" if "scene" in figures else "",
        "",
        "## Parameters",
        "",
        markdown_table(params),
        "",
        f"Initial conditions (the book's): {_state(case.coords, q0, v0)}; horizon {t_end:g} s.",
        "",
        "## How each source models it",
        "",
        "\n\n".join(" ".join(p.split()) for p in case.spec["report"]["modelling"].strip().split("\n\n")),
        "",
        "Joints of `scene.xml` (MuJoCo) and `scene.urdf` (Pinocchio), the same in both:",
        "",
        scene_table(case),
        "",
        *(["## Results", "", "Computed along each source's run of the book's initial conditions.", "",
           values_table(res, spaces), ""] if values else []),
        "## Checks",
        "",
        f"Random states tried: {random_sentence(random_tried(res))}.",
        "",
        "Errors are relative: pointwise to the largest magnitude of the quantity over the random states,"
        " trajectories to the largest magnitude of the coordinate over the run, energy to the largest"
        " |E| or |W|.  `finding` marks a disagreement explained by a registered error of the book.",
        "",
        "In short, the worst row of each comparison (error over its tolerance):",
        "",
        markdown_table(summary_table(rows)),
        "",
        f"<details><summary>All {len(rows)} checks</summary>",
        "",
        markdown_table(table),
        "",
        "</details>",
        "",
    ]
    if findings:
        lines += ["## Findings: where the book is wrong", ""]
        for f in findings:
            spec = next(x for x in case.findings if x["id"] == f["id"])
            lines += [f"### {f['id']}: {f['title']}", "",
                      f"*Where:* {spec['where']}.  *Largest relative error:* {f['error']:.3g}"
                      f" (quantities {', '.join(f['quantity'])}; comparisons: {', '.join(f['sources'])};"
                      f" {f['established']})."
                      + (f"  {f['effect']}" if f["effect"] else ""), "",
                      f"*Localised automatically* (edits of the printed expression searched until one agrees"
                      f" with the engines): {f['localised']}.", "", f["explanation"], ""]
    sections, study_files = study_sections(res, tmp)
    lines += sections + [
        "## Figures",
        "",
        *[f"![{kind}]({path})\n" for kind, path in figures.items() if kind != "scene"],
        "## Tolerances and why",
        "",
    ]
    for kind, tol in case.tolerance.items():
        value = f"{tol['value']:g}" if "value" in tol else f"safety factor {tol['safety']:g}"
        lines += [f"- **{kind}** ({value}): " + " ".join(tol["why"].split())]
    lines += ["", "## Cost of the runs", "", markdown_table(cost), "",
              f"All checks of this case took {res['wall']:.1f} s.", ""]
    page = f"{name}.md"
    (tmp / page).write_text("\n".join(lines))
    return [page] + list(figures.values()) + study_files


def study_sections(res, tmp):
    """The page's speed-against-accuracy, convergence and stability sections, and the files they use.
    res["studies"] is None when `dyncheck report --no-studies` left them out."""
    case, studies = res["case"], res.get("studies")
    convergence = [r for r in res["rows"] if r["check"] == "convergence"]
    lines, files = ["## Speed against accuracy", ""], []
    if studies is None:
        lines += ["Not run this time (`dyncheck report --no-studies`).", ""]
    elif studies["work_precision"].empty:
        lines += [work_precision.NO_SWEEP, ""]
    else:
        frame = studies["work_precision"]
        csv, chart = f"data/{case.name}_work_precision.csv", f"figures/{case.name}_work_precision.png"
        work_precision.write_csv(frame, tmp / csv)
        work_precision.figure(frame, case, tmp / chart)
        files += [csv, chart]
        reference = frame.attrs["reference"]
        unstable = frame[frame["status"] == "unstable"]
        best = work_precision.cheapest(frame)
        best["level"] = best["level"].map(lambda x: f"{x:.0e}")
        for column in ("wall", "runner_up_wall", "error"):
            best[column] = best[column].map(lambda x: "-" if pd.isna(x) else f"{x:.3g}")
        lines += [f"Every method from the book's initial conditions over {reference['t_end']:g} s, against the"
                  f" reference solution: {reference['label']}.  Error is the largest deviation of any"
                  " coordinate or rate, relative to its largest magnitude; the rows behind the chart are in"
                  f" [{csv}]({csv}).  {work_precision.COST_NOTE}", "",
                  f"![work-precision]({chart})", "",
                  "Which method is cheapest at each accuracy level (relative trajectory error):", "",
                  markdown_table(best.rename(columns={"wall": "wall [s]", "runner_up": "runner-up",
                                                      "runner_up_wall": "runner-up wall [s]"})), ""]
        if len(unstable):
            lines += ["Unstable (blew up; not drawn): " + "; ".join(
                f"{work_precision.point_label(r)}: {r['detail']}" for _, r in unstable.iterrows()) + ".", ""]
    lines += ["## Convergence", ""]
    if convergence:
        lines += ["Observed order of each fixed-step method, from runs at h, h/2, h/4 (checks; tolerance from"
                  " the next term of the error expansion, see the case file):", "",
                  markdown_table(pd.DataFrame([{"method": r["quantity"], "source": r["sources"],
                                                "|observed - expected|": f"{r['error']:.3f}" if r["error"] is not None else "-",
                                                "tolerance": f"{r['tolerance']:.3f}" if r["tolerance"] is not None else "-",
                                                "status": r["status"], "detail": r["detail"]} for r in convergence])), ""]
    else:
        lines += [work_precision.NO_SWEEP if not case.coords else "No fixed-step method is checked for this case.", ""]
    if studies and studies["stability"]:
        lines += ["## Stability: where methods fail", ""]
        for result in studies["stability"]:
            chart = f"figures/{case.name}_{result['study']}.png"
            stability.figure(result, tmp / chart)
            files.append(chart)
            lines += [f"### {result['title']}", "", *[f"- {sentence}" for sentence in result["findings"]], "",
                      f"![{result['study']}]({chart})", "",
                      f"*How:* {result['why']} (this study took {result['wall']:.0f} s.)", "",
                      f"<details><summary>The numbers ({len(result['table'])} rows)</summary>", "",
                      markdown_table(result["table"]), "", "</details>", ""]
    return lines, files


def _state(coords, q, v):
    return ", ".join(f"{c} = {x:.6g}" for c, x in zip(coords, q)) + ", " + \
        ", ".join(f"{c}' = {x:.6g}" for c, x in zip(coords, v))


SUMMARY_KEYS = {"case", "section", "params", "checks", "findings", "title", "status", "worst_engine_error",
                "random", "cheapest"}  # what write_summary writes


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


def write_errata(tmp, cases):
    """errata.md: every finding of every case in one table, then each in full."""
    table = [{"finding": f"[{f['id']}](#{f['id'].replace('.', '').lower()})", "case": f"[{c['case']}]({c['case']}.md)",
              "where": f["where"], "what": f["title"], "largest relative error": f"{f['error']:.3g}",
              "localised edit": f["localised"]}
             for c in cases for f in c["findings"]]
    lines = ["# Errata: where the book is wrong", "",
             "Each finding is a disagreement between the book and the engines that an error of the book"
             " explains.  It is registered in its case file and checked on every run: if the book's"
             " version ever agrees with the engines, the run fails.  [All cases](index.md)", "",
             markdown_table(pd.DataFrame(table)) if table else "No findings.", ""]
    for c in cases:
        for f in c["findings"]:
            lines += [f"## {f['id']}", "", f"**{f['title']}** ([{c['case']}]({c['case']}.md), {c['section']})", "",
                      f"- *Where:* {f['where']}",
                      f"- *Quantities:* {', '.join(f['quantity'])}; largest relative error {f['error']:.3g}",
                      f"- *How established:* {f['established']}",
                      *([f"- *Effect:* {f['effect']}"] if f["effect"] else []),
                      f"- *Localised edit:* {f['localised']}", "",
                      f["explanation"], ""]
    programs = [c for c in cases if (tmp / f"figures/{c['case']}_program.png").exists()]
    if programs:
        lines += ["## The book's programs: its figures redrawn", "",
                  "Each figure the book draws from a program, from a line-by-line transcription of that"
                  " program (left) and from the corrected equations integrated tightly (right), on the"
                  " book's axes.", ""]
        lines += [f"### {c['section']} ([{c['case']}]({c['case']}.md))\n\n![program](figures/{c['case']}_program.png)\n"
                  for c in programs]
    (tmp / "errata.md").write_text("\n".join(lines))
    return "errata.md"


def speed_table(cases):
    """Index lines: for each case with a work-precision sweep, the cheapest method at each accuracy."""
    rows = [{"case": f"[{c['case']}]({c['case']}.md#speed-against-accuracy)", **c["cheapest"]}
            for c in cases if c.get("cheapest")]
    if not rows:
        return []
    return ["The cheapest method (least wall time) that reaches each relative trajectory error, from each"
            " case's work-precision sweep (details, charts and the stability studies on the case pages):", "",
            markdown_table(pd.DataFrame(rows).fillna("-")), ""]


def write_index(tmp, cases):
    """index.md over `cases` (the summaries)."""
    rows = []
    for case in cases:
        counts = pd.Series([c["status"] for c in case["checks"]]).value_counts()
        rows.append({
            "case": f"[{case['case']}]({case['case']}.md)", "section": case["section"], "title": case["title"],
            "status": case["status"], "checks": ", ".join(f"{n} {s}" for s, n in counts.items()),
            "worst engine error": f"{case['worst_engine_error']:.1e}",
            "findings": ", ".join(f"{f['id']} ({f['error']:.2g})" for f in case["findings"]) or "none"})
    tried = [c["random"] for c in cases]
    states = sum(t["states"] + t["parameter_sets"] * t["states_per_set"] for t in tried)
    disagreed = [c["case"] for c in cases if not c["random"]["agreed"]]
    lines = ["# dyncheck reports", "",
             "The worked examples of I. F. Santos, *Dynamics of Machines*, ch. 1, checked against MuJoCo"
             " and Pinocchio.  *Worst engine error* is the largest pointwise relative error among"
             " `reference`, MuJoCo and Pinocchio (accelerations, reactions, energy, drive power);"
             " a finding is an error of the book, with the largest relative error it causes: all of them"
             " are in the [errata](errata.md).", "",
             markdown_table(pd.DataFrame(rows)), "",
             *speed_table(cases),
             f"The last run tried {sum(t['parameter_sets'] for t in tried)} random parameter sets besides the book's"
             f" and {states} random states in all ({len(cases)} cases; seeds on each case page): reference, MuJoCo"
             " and Pinocchio " + (f"disagreed in {', '.join(disagreed)}." if disagreed else
                                  "agreed at every one of them within the pointwise tolerance."), ""]
    (tmp / "index.md").write_text("\n".join(lines))
    return "index.md"
