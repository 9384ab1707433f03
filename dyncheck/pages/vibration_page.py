"""The page's "Vibration analysis" section: the equilibrium, the linearised equations typeset, the table of
frequencies from every source and every run, the modes and the Campbell diagram drawn.  Drawn from saved
results only (dyncheck.checks.vibration computes them)."""

import math

import numpy as np
import pandas as pd

from dyncheck.studies.campbell import Sweep  # and with it its classes registered for loading saved results (report --from)
from dyncheck.common.messages import ENGINE_NAMES
from dyncheck.results.values import OWN_WORDS, heading
from dyncheck.checks.vibration import MATRIX_NAMES
from dyncheck.checks.linear import SAFETY, match
from dyncheck.common.style import SOURCE_STYLE, embed, leave_out, legend_below, panels, save, title
from dyncheck.pages.figures import quantity_label

NAMES = {"reference": "reference", **ENGINE_NAMES}
HATCH = {"reference": "", "mujoco": "//", "pinocchio": ".."}  # grey-safe: a source is a hatch as well as a colour


def source_name(source, case):
    """A source as the page names it: the derivation of a researcher's case is "derivation"."""
    return OWN_WORDS.get(source, source) if case.one_derivation and source == "reference" else NAMES[source]


ROUNDING = 1e-12  # entries below this fraction of the largest shown are rounding noise of the derivatives: 0


def latex_matrix(symbol, matrix, largest):
    """$$ symbol = [ ... ] $$, six significant digits, for GitHub's Markdown maths; entries below ROUNDING times
    `largest` written as 0."""
    rows = r" \\ ".join(" & ".join(_number(x if abs(x) > ROUNDING * largest else 0.0) for x in line)
                         for line in matrix)
    return f"$$\\mathbf{{{symbol}}} = \\begin{{bmatrix}} {rows} \\end{{bmatrix}}$$"


def _number(x):
    if x == 0:
        return "0"
    mantissa, exponent = f"{x:.6e}".split("e")
    exponent = int(exponent)
    if -3 <= exponent <= 4:
        return f"{x:.6g}"
    return f"{float(mantissa):.6g} \\cdot 10^{{{exponent}}}"


def section(result, case, tmp):
    """The section's lines and the files it wrote; none for a case without [vibration]."""
    vib = result.vibration
    if vib is None:
        return [], []
    lines = ["## Vibration analysis", "", " ".join(case.prose(vib.why, "vibration.why").split()), ""]
    if vib.overrides:
        lines += ["Linearised with " + ", ".join(f"{name} = {value:.6g} {case.units[name]}"
                                                for name, value in vib.overrides.items())
                  + " (the case's other numbers as above).", ""]
    if vib.equilibrium is None or not vib.modes:
        return lines + [f"No analysis: {vib.failure}", ""], []
    eq = vib.equilibrium
    coords = case.coords
    lines += [f"**Equilibrium** (Newton-Raphson, {eq.iterations} iterations, accelerations left "
              f"{eq.residual:.1e} of the balancing terms): "
              + ", ".join(f"{c} = {equilibrium_value(x)}" for c, x in zip(coords, eq.q)) + "; "
              + ", ".join(f"{c}' = {equilibrium_value(x)}" for c, x in zip(coords, eq.v)) + ".", ""]
    lines += linear_equations(vib, case)
    lines += frequency_lines(vib, case)
    files = []
    if vib.modes["reference"].oscillating():
        chart = f"figures/{case.name}_modes.png"
        figure_modes(vib, case, tmp / chart)
        files.append(chart)
        lines += embed(chart, "mode shapes",
                       "The mode shapes: each mode's coordinate displacements, scaled so that the largest is 1, from "
                       "each source's linearisation (bars side by side: colour and hatch per source).  Coinciding bars "
                       "are the check: the rows `mode shape` above give the largest difference.")
    else:  # every eigenvalue real: nothing oscillates, no shape to draw
        lines += ["No mode oscillates about this equilibrium (every eigenvalue of A is real): no mode shapes to draw.",
                  ""]
    lines += floquet_lines(vib, case)
    sweep = (result.studies or {}).get("vibration")
    if sweep is not None:
        chart = f"figures/{case.name}_campbell.png"
        figure_campbell(sweep, case, tmp / chart)
        files.append(chart)
        lines += sweep_lines(sweep, case, chart)
    return lines, files


def linear_equations(vib, case):
    """The linearised equations typeset: M, K, D, G, N (Pinocchio's, analytic; the zero ones named) and the
    derivation's A."""
    coords = ", ".join(case.coords)
    lines = []
    pin = vib.linear.get("pinocchio")
    if pin is not None:
        matrices = pin.matrices()
        largest = max(np.max(np.abs(m)) for m in matrices.values())
        zero = [name for name, m in matrices.items() if np.max(np.abs(m)) <= ROUNDING * largest]
        shown = [name for name in matrices if name not in zero]
        lines += [f"**Linearised equations** M q'' + (D + G) q' + (K + N) q = 0 in ({coords}), from Pinocchio's "
                  "analytic derivatives (SI units; MuJoCo's and the derivation's agree to the rows `vibration` "
                  "above):", "",
                  *[latex_matrix(name, matrices[name], largest) + "\n" for name in shown],
                  ("Zero here: " + ", ".join(f"{n} ({MATRIX_NAMES[n]})" for n in zero) + "." if zero else ""), ""]
    ref = vib.linear["reference"]
    lines += [f"The {source_name('reference', case)}'s first-order form z' = A z, z = ({coords}, and their rates), "
              f"by central differences of its accelerations (error estimate {ref.error:.1e}):", "",
              latex_matrix("A", ref.state_matrix, np.max(np.abs(ref.state_matrix))), ""]
    return lines


def frequency_lines(vib, case):
    """The table of frequencies, damping ratios and the runs' frequencies, and the verdicts."""
    ref = vib.modes["reference"]
    n = len(case.coords)
    runs = {}
    for motion in vib.motions:
        runs.setdefault((motion.mode, motion.source), motion)  # the first: at the amplitude, MuJoCo at its step
    table = []
    for k, i in enumerate(ref.oscillating()):
        lam = ref.eigenvalues[i]
        entry = {"mode": k + 1}
        nearest = {source: match(ref, modes)[i] for source, modes in vib.modes.items()}
        for source, modes in vib.modes.items():
            entry[f"{source_name(source, case)} [rad/s]"] = f"{modes.eigenvalues[nearest[source]].imag:.10g}"
        entry["[Hz]"] = f"{lam.imag / (2 * math.pi):.6g}"
        entry["damping ratio"] = (f"{-lam.real / abs(lam):.3g}" if abs(lam.real) > SAFETY * ref.bounds[i] else "0")
        for source in vib.modes:
            motion = runs.get((nearest[source], source))
            entry[f"run: {source_name(source, case)}"] = ("-" if motion is None else
                                                          f"{motion.frequency:.10g}" if motion.ok else "unstable")
        shape = ref.shape(i, n)
        entry["shape"] = ", ".join(f"{c} {_shape_entry(x)}" for c, x in zip(case.coords, shape))
        table.append(entry)
    # each mode's amplitude, the case's or halved (vibration.settled_amplitude): one number where they agree
    amplitudes = {k + 1: runs[(i, "reference")].amplitude for k, i in enumerate(ref.oscillating())
                  if (i, "reference") in runs}
    amplitude = (f"{next(iter(amplitudes.values())):g}" if len(set(amplitudes.values())) == 1 else
                 ", ".join(f"{a:g} (mode {k})" for k, a in amplitudes.items()))
    runs_words = (f"the frequency of the modal coordinate in a run from the equilibrium displaced along the mode by "
                  f"{amplitude} in its largest coordinate, MuJoCo by its RK4, the others by DOP853" if amplitudes else
                  "none: no mode oscillates" if not ref.oscillating() else
                  "none: the equilibrium is unstable, and every run leaves it")
    lines = [f"**Natural frequencies** (imaginary parts of the eigenvalues of A; the runs: {runs_words}):", "",
             pd.DataFrame(table).to_markdown(index=False, disable_numparse=True), "",
             stability_line("**Stability**", vib.modes, case, VERDICT_WORDS), ""]
    return lines


def stability_line(title, by_source, case, words):
    """The verdicts of `by_source` ({source: its Modes or Monodromy}): one, with its meaning in `words`, where every
    source gives it; else each source's."""
    verdicts = {source_name(s, case): m.verdict for s, m in by_source.items()}
    if len(set(verdicts.values())) == 1:
        verdict = next(iter(verdicts.values()))
        return f"{title}: {verdict} by every source.  {words[verdict]}"
    return f"{title}: " + "; ".join(f"{s}: {v}" for s, v in verdicts.items()) + "."


VERDICT_WORDS = {
    "marginally stable": "Every eigenvalue lies on the imaginary axis within its error bound: small motions "
                         "neither grow nor decay in the linear equations, and the nonlinear terms decide.",
    "asymptotically stable": "Every eigenvalue has a negative real part beyond its error bound: small motions decay.",
    "unstable": "An eigenvalue has a positive real part beyond its error bound: small motions grow.",
}


def equilibrium_value(x):
    """A state variable of the equilibrium: zero where Newton-Raphson left it within rounding of zero."""
    return "0" if abs(x) < 1e-12 else f"{x:.10g}"


def _degrees(x):
    """The phase of x in whole degrees, without a sign on zero."""
    return f"{round(math.degrees(np.angle(x))) + 0:d}"


def _shape_entry(x):
    return f"{x.real:.4g}" if abs(x.imag) <= 1e-9 else f"{abs(x):.4g}∠{_degrees(x)}°"


def figure_modes(vib, case, path):
    """One panel per oscillating mode: each coordinate's displacement in each source's mode shape."""
    ref = vib.modes["reference"]
    n = len(case.coords)
    modes = ref.oscillating()
    cols = min(3, len(modes))
    rows = -(-len(modes) // cols)
    fig, axes = panels(rows, cols, 1.0 + 2.4 * rows, sharey=True)
    width = 0.8 / len(vib.modes)
    for ax, (k, i) in zip(axes.flat, enumerate(modes)):
        lam = ref.eigenvalues[i]
        shapes = {source: modes_s.shape(match(ref, modes_s)[i], n) for source, modes_s in vib.modes.items()}
        # A gyroscopic mode moves its coordinates out of phase: its bars are magnitudes, each phase written over it.
        complex_ = any(np.max(np.abs(shape.imag)) > 1e-9 for shape in shapes.values())
        for s, (source, shape) in enumerate(shapes.items()):
            style = SOURCE_STYLE[source]
            x = np.arange(n) + (s - (len(shapes) - 1) / 2) * width
            ax.bar(x, np.abs(shape) if complex_ else shape.real, width, color=style["color"], alpha=0.8,
                   hatch=HATCH[source], edgecolor="black", linewidth=0.5, label=source_name(source, case))
        if complex_:
            for c, value in enumerate(shapes["reference"]):
                ax.text(c, abs(value) + 0.03, f"{_degrees(value)}°", ha="center", fontsize=8)
        ax.axhline(0.0, color="black", lw=0.6)
        ax.set_xticks(range(n), [quantity_label(c) for c in case.coords])  # typeset: short enough for 9 to a panel
        ax.set_ylim((0.0, 1.2) if complex_ else (-1.15, 1.15))
        ax.set_title(f"mode {k + 1}: {lam.imag:.4g} rad/s")
        ax.grid(False, axis="x")
    leave_out(axes, len(modes))
    fig.supylabel("|displacement| [1] (largest = 1), phase" if complex_ else "displacement [1] (largest = 1)", fontsize=9)
    fig.suptitle(title(heading(case.spec), "mode shapes about the equilibrium"))
    legend_below(fig)
    save(fig, path)


def sweep_lines(sweep: Sweep, case, chart):
    """The Campbell diagram and the stability boundary in words; no figure where the sweep found nothing to draw."""
    lines = [f"### Campbell diagram: frequencies against {sweep.parameter}", "",
             " ".join(case.prose(sweep.why, "vibration.campbell.why").split()), ""]
    if len(sweep.data):
        lines += embed(chart, "Campbell diagram", campbell_caption(sweep))
    else:
        lines += ["No diagram at these parameters: the sweep has no equilibrium to draw (below).", ""]
    for sentence in sweep.findings:
        lines += [f"- {sentence}"]
    return lines + [""]


def campbell_caption(sweep: Sweep):
    at = lambda x: f"{sweep.parameter} = {x:.5g} {sweep.unit}"
    return (f"The Campbell diagram: the equilibrium's state at each {sweep.parameter} (top: how it moves with it), each "
            "oscillating mode's frequency (middle) and the largest real part of the eigenvalues (bottom), from the "
            "derivation (line) and both engines (markers); a positive real part is an unstable equilibrium."
            + (f"  Dashed: the stability boundary from the eigenvalues, {at(sweep.boundary)}: the equilibrium is stable "
               f"{'above' if sweep.stable_above else 'below'} it, unstable or gone "
               f"{'below' if sweep.stable_above else 'above'}." if sweep.boundary is not None else "")
            + (f"  Dotted: the equilibrium analysed above, {at(sweep.analysed)}." if sweep.analysed is not None else "")
            + "".join(f"  Circles: where modes {a.modes[0]} and {a.modes[1]} come closest, {at(a.value)}, "
                      f"{a.gap:.2g} rad/s apart ({'a veering' if a.veers else 'a crossing'})." for a in sweep.approaches))


def figure_campbell(sweep: Sweep, case, path):
    """Frequencies and the largest real part against the swept parameter, every source; the boundary, the
    analysed equilibrium and the closest approaches marked."""
    data = sweep.data
    fig, axes = panels(3, 1, 6.6, sharex=True, height_ratios=[1.6, 3, 1.4])
    branch, top, bottom = axes[:, 0]
    axes = [branch, branch.twinx()] if len(sweep.branch_units) == 2 else [branch]
    for ax, (name, unit), style in zip(axes, sweep.branch_units.items(), ("-", "--")):
        ax.plot(sweep.branch["value"], sweep.branch[name], color="black", ls=style, marker=".",
                label=f"{name} [{unit}]")
        ax.set_ylabel(f"{name} [{unit}]")
    branch.set_title("the equilibrium (derivation)")
    markers = {"reference": None, "mujoco": "^", "pinocchio": "s"}
    for source, group in data.groupby("source", sort=False):
        style = SOURCE_STYLE[source]
        for mode, curve in group.groupby("mode"):
            top.plot(curve["value"], curve["frequency"], color=style["color"], ls="-" if source == "reference" else "none",
                     marker=markers[source], ms=4, mfc="none", label=source_name(source, case) if mode == 1 else None)
        real = group.groupby("value")["largest_real"].first()
        bottom.plot(real.index, real.to_numpy(), color=style["color"], ls="-" if source == "reference" else "none",
                    marker=markers[source], ms=4, mfc="none")
    for a in sweep.approaches:
        top.plot([a.value, a.value], a.frequencies, color="black", ls="none", marker="o", ms=7, mfc="none",
                 label="closest approach of two modes")
    marks = [(sweep.boundary, "--", f"stability boundary, {sweep.parameter} = {sweep.boundary:.5g} {sweep.unit}"
              if sweep.boundary is not None else None),
             (sweep.analysed, ":", f"the equilibrium analysed above, {sweep.parameter} = {sweep.analysed:.4g} {sweep.unit}"
              if sweep.analysed is not None else None)]
    for value, style, label in marks:
        if value is not None:
            for ax in (branch, top, bottom):
                ax.axvline(value, color="black", ls=style, lw=0.8, label=label if ax is top else None)
    bottom.axhline(0.0, color="black", lw=0.6)
    top.set_ylabel("frequency [rad/s]")
    bottom.set_ylabel("largest Re λ [1/s]")
    bottom.set_xlabel(f"{sweep.parameter} [{sweep.unit}]")
    fig.suptitle(title(heading(case.spec), "Campbell diagram"))
    legend_below(fig, ncol=2)
    save(fig, path)


def floquet_lines(vib, case):
    """The subsection on the book's periodic motion: the period, the orbit, each source's Floquet multipliers (their
    magnitude, angle and exponent), the verdict and the stroboscopic runs; none for a case without
    [vibration.floquet]."""
    floquet = vib.floquet
    if floquet is None:
        return []
    lines = ["### About the book's periodic motion (Floquet)", "",
             " ".join(case.prose(floquet.why, "vibration.floquet.why").split()), ""]
    if not floquet.monodromy:
        return lines + [f"No analysis: {floquet.failure}", ""]
    n = len(case.coords)
    units = dict(zip(case.coords, case.spec["coord_units"]))
    coordinates = floquet.orbit[:-1, :n]  # equally spaced over one period
    amplitude = np.max(np.abs(coordinates - coordinates.mean(axis=0)), axis=0)
    lines += [f"**Period** T = {floquet.period:.10g} s: the equations repeat after it (the row `period T`).  **The "
              f"periodic orbit**, by shooting Newton-Raphson on the {source_name('reference', case)} "
              f"({floquet.iterations} iterations"
              + (f", continued from the book's orbit in {floquet.continued} steps of the overridden parameters"
                 if floquet.continued else "")
              + (", from MuJoCo's orbit: from the guess, and continued from the book's orbit, it found none"
                 if floquet.seeded else "")
              + f", |x(T) - x(0)| left {floquet.residual:.1e} of the state's scale, "
              f"within the run's own error estimate {floquet.residual_error:.1e}), starts at "
              + ", ".join(f"{c} = {equilibrium_value(x)}" for c, x in zip(case.coords, floquet.orbit[0, :n])) + "; "
              + ", ".join(f"{c}' = {equilibrium_value(x)}" for c, x in zip(case.coords, floquet.orbit[0, n:]))
              + "; its amplitude (the largest |q - mean| over the period): "
              + ", ".join(f"{c} {x:.4g} {units[c]}" for c, x in zip(case.coords, amplitude)) + ".", ""]
    reference = floquet.monodromy["reference"]
    table = []
    for label, r in enumerate(reference.distinct(), start=1):
        for source, monodromy in floquet.monodromy.items():
            mu = monodromy.multipliers[match(reference, monodromy)[r]]
            exponent = np.log(mu) / floquet.period
            table.append({"multiplier": label, "source": source_name(source, case), "modulus": f"{abs(mu):.12g}",
                          "angle [deg]": f"{math.degrees(np.angle(mu)):.8g}", "Re log(mu)/T [1/s]": f"{exponent.real:.3g}",
                          "Im log(mu)/T [rad/s]": f"{exponent.imag:.8g}"})
    words = {"marginally stable": "Every multiplier lies on the unit circle within its error bound: small motions about "
                                  "the periodic one neither grow nor decay from period to period in the linear "
                                  "equations, and the nonlinear terms decide.",
             "asymptotically stable": "Every multiplier lies inside the unit circle beyond its error bound: small "
                                      "motions about the periodic one decay.",
             "unstable": "A multiplier lies outside the unit circle beyond its error bound: small motions about the "
                         "periodic one grow."}
    lines += [f"**Floquet multipliers**, the eigenvalues of the monodromy matrix Phi(T) (one of each complex pair), "
              "from each source's own linearisation along the orbit; the exponent log(mu)/T's imaginary part is a "
              f"frequency known only up to multiples of 2 pi / T = {2 * math.pi / floquet.period:.6g} rad/s:", "",
              pd.DataFrame(table).to_markdown(index=False, disable_numparse=True), "",
              stability_line("**Stability (Floquet)**", floquet.monodromy, case, words), ""]
    runs = [m for m in floquet.motions[:3] if m.ok]
    if runs:
        mu = reference.multipliers[reference.largest()]
        lines += [f"**By motion**: each source's run from the orbit displaced by {runs[0].amplitude:g} along its "
                  f"eigenvector of the largest multiplier (|mu| {abs(mu):.10g} at {math.degrees(np.angle(mu)):.8g}°), "
                  "sampled once per period: the measured multiplier, " + "; ".join(
                      f"{source_name(m.source, case)} |mu| {abs(np.exp(m.exponent * floquet.period)):.10g} at "
                      f"{math.degrees(m.frequency * floquet.period):.8g}°" for m in runs)
                  + " (the rows `largest Floquet multiplier, stroboscopic run`).", ""]
    return lines


def summary(vib):
    """The analysis in short, for data/<case>.json and the index: None without `[vibration]`."""
    if vib is None:
        return None
    ref = vib.modes.get("reference")
    floquet = vib.floquet.monodromy.get("reference") if vib.floquet is not None else None
    return {"frequencies": None if ref is None else [float(ref.eigenvalues[i].imag) for i in ref.oscillating()],
            "verdict": None if ref is None else ref.verdict,
            "relative": vib.equilibrium is not None and bool(np.any(vib.equilibrium.v != 0)),
            "overridden": {name: float(value) for name, value in vib.overrides.items()},
            "multipliers": None if floquet is None else [float(math.degrees(np.angle(floquet.multipliers[i])))
                                                         for i in range(len(floquet.multipliers))
                                                         if floquet.multipliers[i].imag > floquet.bounds[i]],
            "floquet_verdict": None if floquet is None else floquet.verdict}


def index_lines(cases, book):
    """The index's table of the vibration analyses (the summaries' `vibration`), or nothing; `book`: the index of
    the book's examples (else a folder of one's own cases)."""
    rows = []
    for case in cases:
        vib = case.get("vibration")
        if not vib:
            continue
        about = ", ".join(f"{name} = {value:.4g}" for name, value in vib["overridden"].items())
        rows.append({"case": f"[{case['case']}]({case['case']}.md)",
                     "linearised about": ("a steady motion (relative equilibrium)" if vib["relative"] else
                                          "rest (equilibrium)") + (f", with {about}" if about else ""),
                     "frequencies [rad/s]": "-" if vib["frequencies"] is None else
                     ", ".join(f"{w:.6g}" for w in vib["frequencies"]) or "none",
                     "stability": vib["verdict"] or "no equilibrium",
                     "periodic motion: multipliers' angles [deg], stability": "-" if vib["multipliers"] is None else
                     ", ".join(f"{a:.5g}" for a in vib["multipliers"]) + f"; {vib['floquet_verdict']}"})
    if not rows:
        return []
    step, motions = ("the book's step 16; ", "the book's own periodic motions") if book else ("", "periodic motions")
    periodic = any(case["vibration"]["multipliers"] for case in cases if case.get("vibration"))
    return [f"Vibration analysis ({step}the section \"Vibration analysis\" of each page): the natural frequencies"
            " about each equilibrium, from the derivation's eigenvalues (MuJoCo's, Pinocchio's and runs in each agree,"
            " row by row on the page)" + (f", and about {motions} the Floquet multipliers:" if periodic else ":"), "",
            pd.DataFrame(rows).to_markdown(index=False, disable_numparse=True), ""]
