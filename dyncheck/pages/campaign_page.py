"""The campaign's summary page (campaign_<case>.md), its maps' heat maps, and its timing (campaign_<case>_timing.md):
drawn from the campaign's tables alone, the same bytes from the same results."""

from pathlib import Path

import matplotlib.colors as colors
import numpy as np
import pandas as pd

from dyncheck.checks.pointwise import ENGINES
from dyncheck.common.style import embed, panels, save, title
from dyncheck.results.values import Status, heading

AGREEING = {f"{a} vs {b}" for i, a in enumerate(ENGINES) for b in ENGINES[i + 1:]}  # must agree everywhere
FAILED = tuple(str(status) for status in Status if not status.ok)


def named(table, row):
    """The set's parameters in words, as the pages name a set."""
    return ", ".join(f"{p} = {row[p]:.4g}" for p in table)


def state_of(case, row):
    """The state of a row (its two sources differ most there) in words."""
    if row.get("state", -1) < 0:
        return "-"
    return ", ".join([f"t = {row['state_t']:.4g} s"] + [f"{c} = {row[f'state_{c}']:.4g}" for c in case.coords]
                     + [f"{c}' = {row[f'state_{c}_rate']:.4g}" for c in case.coords])


def page(case, plan, table, drawn_maps, figures):
    """The summary page's lines.  `drawn_maps`: {name: (Map, x label, y label, cells)}; `figures`: the folder."""
    params = list(case.params)
    sets = table["set"].nunique()
    lines = [f"# Campaign: {heading(case.spec)}", "",
             f"{sets} random parameter sets (seed {case.spec['sample']['params']['seed']}, uniform over the case file's "
             f"[sample.params] ranges, physical by rejection"
             + (f"; fixed: {case.overrides_text()}" if case.overrides else "") + f"), {plan.chunks[0].states if plan.chunks else 0} "
             f"random states each; {plan.missing} sets could not be drawn.  At each set every source is compared "
             "pointwise (accelerations, reactions, energy, drive power), the book's printed rows and program where "
             "there are, and every registered finding re-measured.  Sets per minute per core: "
             f"[campaign_{case.name}_timing.md](campaign_{case.name}_timing.md).", ""]
    lines += worst_disagreement(case, table, params)
    lines += by_comparison(table, params)
    lines += findings(case, table, params)
    lines += failures(table, params)
    for name, (spec, xlabel, ylabel, cells) in drawn_maps.items():
        path = Path(figures) / f"campaign_{case.name}_{name}.png"
        caption = draw_map(case, spec, xlabel, ylabel, cells, path)
        lines += [f"## Map: {spec.title}", ""] + embed(Path(path.parent.name) / path.name, spec.title, caption)
        lines += map_summary(spec, cells)
    return lines


def worst_disagreement(case, table, params):
    agreeing = table[table["comparison"].isin(AGREEING) & table["error"].notna()]
    if agreeing.empty:
        return ["## Worst disagreement between sources", "", "No comparison of two sources had a number.", ""]
    worst = agreeing.loc[agreeing["error"].idxmax()]
    above = agreeing[agreeing["error"] > agreeing["tolerance"]]
    return ["## Worst disagreement between sources", "",
            f"Among {', '.join(sorted(AGREEING))} (the sources that must agree everywhere): "
            f"**{worst['error']:.3g}** in {worst['quantity']} ({worst['comparison']}, {worst['check']}; tolerance "
            f"{worst['tolerance']:.3g}), at set {worst['set']}: {named(params, worst)}; at the state "
            f"{state_of(case, worst)}.  {len(above)} of their {len(agreeing)} rows are above their tolerance.", ""]


def by_comparison(table, params):
    """The worst row of each comparison over the sets."""
    measured = table[table["error"].notna()]
    rows = []
    for (check, comparison), group in measured.groupby(["check", "comparison"], sort=True):
        worst = group.loc[group["error"].idxmax()]
        rows.append({"check": check, "comparison": comparison, "worst error": f"{worst['error']:.3g}",
                     "quantity": worst["quantity"], "tolerance": f"{worst['tolerance']:.3g}",
                     "rows above tolerance": f"{int((group['error'] > group['tolerance']).sum())} of {len(group)}",
                     "at set": f"{worst['set']}: {named(params, worst)}"})
    return ["## Every comparison", "", "Its worst row over the sets.", "",
            pd.DataFrame(rows).to_markdown(index=False) if rows else "none", ""]


def findings(case, table, params):
    """Each registered finding's size over the parameter space: its largest row at each set."""
    lines = ["## The findings over the parameter space", "",
             "A finding's size at a set is the largest error of the rows it explains there; it shows where that is "
             "above the tolerance.  Findings of runs, figures and data are measured by `dyncheck run` only.", ""]
    rows = []
    for finding in case.findings:
        mine = table[(table["finding"] == finding["id"]) & table["error"].notna()]
        if mine.empty:
            rows.append({"finding": finding["id"], "sets": "0", "min": "-", "median": "-", "max": "-",
                         "shows at": "-", "largest at": "not pointwise: not measured here"})
            continue
        size = mine.loc[mine.groupby("set")["error"].idxmax()]
        shows = int(size["set"].isin(mine.loc[mine["status"] == "finding", "set"]).sum())
        largest = size.loc[size["error"].idxmax()]
        rows.append({"finding": finding["id"], "sets": str(len(size)), "min": f"{size['error'].min():.3g}",
                     "median": f"{size['error'].median():.3g}", "max": f"{size['error'].max():.3g}",
                     "shows at": f"{shows} sets", "largest at": f"{largest['quantity']}, set {largest['set']}: "
                                                                 f"{named(params, largest)}"})
    return lines + [pd.DataFrame(rows).to_markdown(index=False) if rows else "The case registers no finding.", ""]


def failures(table, params):
    """The sets where a source failed (no number) or a row failed that no finding explains."""
    failed = table[table["status"].isin(FAILED)]
    lines = ["## Failures", ""]
    if failed.empty:
        return lines + ["None: every row at every set passes or is a registered finding.", ""]
    rows = [{"set": r["set"], "check": r["check"], "comparison": r["comparison"], "quantity": r["quantity"],
             "status": r["status"], "error": "-" if pd.isna(r["error"]) else f"{r['error']:.3g}",
             "why": r["reason"] or "-", "parameters": named(params, r)}
            for _, r in failed.sort_values(["set", "check", "comparison", "quantity"]).head(50).iterrows()]
    return lines + [f"{len(failed)} rows at {failed['set'].nunique()} sets; the first 50:", "",
                    pd.DataFrame(rows).to_markdown(index=False), ""]


def draw_map(case, spec, xlabel, ylabel, cells, path):
    """The map as two heat maps (the measured value; measured over the closed form); returns the caption."""
    xs, ys = np.sort(cells["x"].unique()), np.sort(cells["y"].unique())
    grid = lambda column: cells.pivot(index="y", columns="x", values=column).reindex(index=ys, columns=xs).to_numpy()
    value, ratio = grid("value"), grid("value") / grid("theory")
    fig, axes = panels(1, 2, 3.6)
    for ax, data, label, norm in ((axes[0, 0], value, spec.value, colors.LogNorm() if spec.log[0] else None),
                                  (axes[0, 1], ratio, "measured / closed form", None)):
        shown = ax.pcolormesh(edges(xs, spec.log[0]), edges(ys, spec.log[1]), np.ma.masked_invalid(data),
                              shading="flat", norm=norm if np.isfinite(data).any() else None, cmap="viridis")
        fig.colorbar(shown, ax=ax, label=label, shrink=0.9)
        if spec.boundary is not None:
            ends = edges(xs, spec.log[0])[[0, -1]]
            dense = np.geomspace(*ends, 200) if spec.log[0] else np.linspace(*ends, 200)
            ax.plot(dense, spec.boundary(case, dense), color="red", lw=1.5, ls="--")  # seen on blank and dark
            ax.set_ylim(edges(ys, spec.log[1])[[0, -1]])
        ax.set_xscale("log" if spec.log[0] else "linear")
        ax.set_yscale("log" if spec.log[1] else "linear")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.grid(False)
    fig.suptitle(title(heading(case.spec), f"{spec.title}, {len(xs)} x {len(ys)}"))
    save(fig, path)
    return (f"{spec.title}: left the {spec.value} measured at each cell of the grid (blank: none, the table says "
            f"why), right the measured value over the closed form, the {spec.theory}"
            + (" (red dashed: the closed-form boundary beyond which the physics runs away)." if spec.boundary else "."))


def edges(centres, log):
    """Cell edges around grid centres (half-way, geometrically on a log axis)."""
    c = np.log(centres) if log else np.asarray(centres, dtype=float)
    step = np.diff(c)
    inner = c[:-1] + step / 2
    out = np.r_[c[0] - step[0] / 2, inner, c[-1] + step[-1] / 2] if len(c) > 1 else np.r_[c[0] - 0.5, c[0] + 0.5]
    return np.exp(out) if log else out


def map_summary(spec, cells):
    measured = cells[cells["value"].notna()]
    ratio = (measured["value"] / measured["theory"]).dropna()
    lines = [f"{len(measured)} of {len(cells)} cells measured"
             + (f"; measured over the closed form {ratio.min():.3g} to {ratio.max():.3g} (median {ratio.median():.3g})"
                if len(ratio) else "") + "."]
    counts = cells["status"].str.split(":").str[0].value_counts().sort_index()
    lines.append("Cells by status: " + ", ".join(f"{status} {count}" for status, count in counts.items()) + ".")
    return [" ".join(lines), ""]


def timing(case, table, wall, workers, computed):
    """The timing file's lines: sets per minute per core from the sets' own times, and this run's wall time."""
    per_set = table.groupby("set")["seconds"].first()
    lines = [f"# Campaign timing: {heading(case.spec)}", "",
             f"- {len(per_set)} sets; {per_set.sum():.1f} s of work in all: "
             f"**{60 * len(per_set) / per_set.sum():.1f} sets/min/core** (median {per_set.median() * 1e3:.0f} ms a set)"
             if per_set.sum() > 0 else "- no sets"]
    if computed and wall > 0:
        lines.append(f"- this run: {computed} sets in {wall:.1f} s on {workers} worker{'s' * (workers != 1)}: "
                     f"{60 * computed / wall:.1f} sets/min, {60 * computed / wall / workers:.1f} sets/min/core")
    return lines + [""]


def write(case, plan, table, drawn_maps, wall, workers, computed):
    """The page and the timing file in the plan's folder; their paths."""
    out = plan.out
    (out / "figures").mkdir(parents=True, exist_ok=True)
    path = out / f"campaign_{case.name}.md"
    path.write_text("\n".join(page(case, plan, table, drawn_maps, out / "figures")))
    timing_path = out / f"campaign_{case.name}_timing.md"
    timing_path.write_text("\n".join(timing(case, table, wall, workers, computed)))
    return path, timing_path

