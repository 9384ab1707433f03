"""The Campbell diagram and the stability boundaries of `[vibration]`, a study of `dyncheck report`: the
frequencies of the equilibrium against a parameter, where two of them come closest (a veering or a crossing), and
each `[[vibration.boundary]]` found from the eigenvalues, compared with its formula and confirmed by runs either
side.  The sweep and the brackets are multiples of their table's `scale`, an expression of the parameters (a
spring's sqrt(k/m)), so that they follow `--set`; where they have nothing to show at the parameters the
study says so in a sentence.  `sweep(case)` returns a `Sweep`; dyncheck.pages.vibration_page draws it."""

import math
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import minimize_scalar

from dyncheck.checks.linear import (ENGINES, RUNS_PER_PERIOD, SAFETY, NoEquilibrium, along, derivation_linear,
                                    engine_linear, equilibrium, linearised, modal, settings, state_names)
from dyncheck.results import store
from dyncheck.run.simulate import Unstable, simulate


@store.register
@dataclass(frozen=True)
class Approach:
    """Where two neighbouring frequencies of the sweep come closest (the derivation's, the search refined)."""
    modes: tuple  # (k, k + 1), numbered by frequency from 1
    value: float  # the swept parameter there
    frequencies: tuple  # (lower, upper) [rad/s]
    resolution: float  # the least gap the search can tell from zero there [rad/s]

    @property
    def gap(self):
        return self.frequencies[1] - self.frequencies[0]

    @property
    def veers(self):
        """A gap the search resolves is a veering (the modes couple); else they cross."""
        return self.gap > SAFETY * self.resolution


@store.register
@dataclass(frozen=True)
class Sweep:
    """The frequencies against a parameter, and where the equilibrium stops being stable."""
    parameter: str
    unit: str
    why: str
    data: pd.DataFrame  # source, value, mode (1, 2, ... by frequency), frequency [rad/s], largest_real [1/s]
    branch: pd.DataFrame  # value, and the equilibrium's solved state variables there: how it moves with the parameter
    branch_units: dict  # {state variable: unit}
    boundary: float | None  # the swept parameter's boundary, where [vibration.boundary] has one in it
    stable_above: bool | None  # whether the equilibrium is stable above `boundary` (else below it)
    analysed: float | None  # the swept parameter at the page's own equilibrium ([vibration]), where the sweep holds it
    approaches: tuple  # of Approach: each pair of neighbouring modes' closest approach inside the sweep
    findings: tuple  # sentences with the numbers
    wall: float


def sweep(case, progress=None):
    """The `[vibration.campbell]` sweep and the `[vibration.boundary]` search; None without them."""
    table = settings(case)
    if table is None or "campbell" not in table:
        return None
    start = time.perf_counter()
    scene = linearised(case)
    campbell = table["campbell"]
    parameter = campbell["parameter"]
    if progress:
        progress(f"{case.name}: Campbell diagram over {parameter}")
    names = state_names(case.coords)
    analysed = held_value(scene, table, parameter)
    values, nothing = swept_values(scene, campbell, analysed)
    records, branch, missing, findings = [], [], [], []
    equilibria = {}  # value -> the equilibrium there, to continue from
    guess = (table["q"], table["v"])
    for value in values:
        point, eq, reference = equilibrium_at(scene, table, parameter, value, guess)
        if eq is None:
            missing.append(value)
            continue
        guess = equilibria[value] = (eq.q, eq.v)
        # an angle as the page shows it, in (-pi, pi]: Newton-Raphson may land a whole turn away
        shown = lambda name, x: float(np.angle(np.exp(1j * x))) if unit(case, name) == "rad" else float(x)
        branch.append({"value": value, **{name: shown(name, eq.state[names.index(name)]) for name in table["solve"]}})
        each = {"reference": reference, **{source: modal(engine_linear(point.model(source), source, eq))
                                           for source in ENGINES}}
        for source, modes in each.items():
            for k, frequency in enumerate(frequencies(modes)):
                records.append({"source": source, "value": value, "mode": k + 1, "frequency": frequency,
                                "largest_real": largest_real(modes)})
    data = pd.DataFrame(records, columns=["source", "value", "mode", "frequency", "largest_real"])
    if nothing:
        findings.append(nothing)
    if missing:
        findings.append(f"No equilibrium near the last one at {parameter} = "
                        + ", ".join(f"{x:.4g}" for x in missing) + f" {unit(case, parameter)}: not drawn.")
    approaches = closest_approaches(scene, table, parameter, data, equilibria)
    findings += [along_the_sweep(data, parameter, unit(case, parameter))] if len(data) else []
    findings += [approach_words(a, parameter, unit(case, parameter)) for a in approaches]
    boundaries = {}
    for settings_ in table.get("boundary", []):
        found, sentences = boundary_search(case, scene, table, settings_, progress)
        if found is not None:
            boundaries[settings_["parameter"]] = found
        findings += sentences
    boundary, stable_above = boundaries.get(parameter, (None, None))
    return Sweep(parameter, unit(case, parameter), campbell["why"], data, pd.DataFrame(branch),
                 {name: unit(case, name) for name in table["solve"]}, boundary, stable_above,
                 analysed if analysed in equilibria else None, tuple(approaches), tuple(findings),
                 time.perf_counter() - start)


def held_value(scene, table, name):
    """The swept parameter, or the state variable Newton-Raphson holds, at the page's own equilibrium."""
    if name in scene.params:
        return float(scene.params[name])
    return float(np.concatenate([table["q"], table["v"]])[state_names(scene.coords).index(name)])


def scale_of(scene, item, field):
    """(the item's `scale` at these parameters, None) or (None, why it has none: not a number, or not > 0)."""
    scale = item.get("scale", 1.0)
    try:
        value = scene.value(scale, f"{field}.scale")
    except ValueError:  # not finite: a square root of a negative number, a division by zero
        return None, "has no value here"
    return (value, None) if value > 0 else (None, f"is {value:g} here, not positive")


def swept_values(scene, campbell, analysed):
    """The sweep's values at these parameters, multiples of its scale, with the page's own equilibrium's value
    among them where it lies inside; and None, or the sentence saying why there is nothing to sweep."""
    scale, why = scale_of(scene, campbell, "vibration.campbell")
    if scale is None:
        return [], (f"Nothing to sweep at these parameters: the values are multiples of `{campbell['scale']}`, which "
                    f"{why}.")
    values = [scale * scene.value(x, "vibration.campbell.values") for x in campbell["values"]]
    for i in range(len(values) - 1):  # continuation goes from each value to the next: `analysed` goes in between
        if min(values[i], values[i + 1]) < analysed < max(values[i], values[i + 1]):
            values.insert(i + 1, analysed)
            break
    return values, None


def vary(scene, name, value, q, v):
    """(scene, q, v) with `name` set to `value`: a parameter of the scene, or a state variable Newton-Raphson holds
    (the top's spin rate)."""
    if name in scene.params:
        return scene.with_params(**{name: value}), q, v
    x = np.concatenate([q, v])
    x[state_names(scene.coords).index(name)] = value
    n = len(q)
    return scene, x[:n], x[n:]


def equilibrium_at(scene, table, name, value, guess):
    """(scene, equilibrium, the derivation's modes there) with `name` at `value`, starting Newton-Raphson from
    `guess` (q, v); (scene, None, None) where there is no equilibrium."""
    scene, q, v = vary(scene, name, value, *guess)
    try:
        eq = equilibrium(scene.model("reference"), 0.0, q, v, table["solve"], scene.coords,
                         scene.model("pinocchio").mass_matrix)
    except NoEquilibrium:
        return scene, None, None
    return scene, eq, modal(derivation_linear(scene.model("reference"), "reference", eq))


def frequencies(modes):
    """The oscillating modes' frequencies, in increasing order: mode 1 the slowest."""
    return sorted(float(modes.eigenvalues[i].imag) for i in modes.oscillating())


def largest_real(modes):
    """The largest real part of the eigenvalues, those within their bounds taken as 0."""
    real = np.where(np.abs(modes.eigenvalues.real) > SAFETY * modes.bounds, modes.eigenvalues.real, 0.0)
    return float(np.max(real))


def stable(modes):
    """Whether an equilibrium's modes (None: there is none) say it is stable."""
    return modes is not None and modes.verdict != "unstable"


def unit(case, name):
    """The unit of a parameter or a state variable."""
    if name in case.units:
        return case.units[name]
    coord = name.removesuffix("_rate")
    base = dict(zip(case.coords, case.spec["coord_units"]))[coord]
    return f"{base}/s" if name.endswith("_rate") else base


# -- where two frequencies come closest ------------------------------------------------------------

APPROACH_RESOLUTION = 1e-4  # the search's width, relative to the two grid intervals around the least gap


def closest_approaches(scene, table, parameter, data, equilibria):
    """For each pair of neighbouring modes of the derivation whose gap is least inside the sweep (not at an end),
    that least gap, refined between the grid's neighbours of the least by a bounded Brent search on the
    derivation's frequencies, each equilibrium continued from the grid's there."""
    reference = data[data["source"] == "reference"].pivot(index="value", columns="mode", values="frequency")
    out = []
    for k in reference.columns[:-1]:
        pair = reference[[k, k + 1]].dropna()
        if len(pair) < 3:
            continue
        x = pair.index.to_numpy()
        gap = (pair[k + 1] - pair[k]).to_numpy()
        i = int(np.argmin(gap))
        if i in (0, len(x) - 1):  # least at an end: the two do not come closest inside the sweep
            continue
        guess = equilibria[x[i]]

        def gap_at(value):
            _, eq, modes = equilibrium_at(scene, table, parameter, value, guess)
            found = frequencies(modes) if eq is not None else []
            return found[k] - found[k - 1] if len(found) > k else math.inf

        low, high = sorted((x[i - 1], x[i + 1]))
        width = APPROACH_RESOLUTION * (high - low)
        best = minimize_scalar(gap_at, bounds=(low, high), method="bounded", options={"xatol": width})
        _, eq, modes = equilibrium_at(scene, table, parameter, best.x, guess)
        found = frequencies(modes)
        # a crossing's gap falls to zero like |slope| |value - crossing|: the search cannot tell it from zero below
        # the steepest slope of the gap on the grid there times the search's width
        slope = max(abs(gap[i - 1] - gap[i]) / abs(x[i - 1] - x[i]), abs(gap[i + 1] - gap[i]) / abs(x[i + 1] - x[i]))
        out.append(Approach((k, k + 1), float(best.x), (found[k - 1], found[k]), slope * width))
    return out


def approach_words(approach, parameter, unit_):
    k, j = approach.modes
    low, high = approach.frequencies
    said = (f"Modes {k} and {j} come closest at {parameter} = {approach.value:.4g} {unit_}: {low:.4g} and {high:.4g} "
            f"rad/s, {approach.gap:.2g} rad/s apart ({approach.gap / (0.5 * (low + high)):.1%} of their mean)")
    if approach.veers:
        return said + (f", a gap well beyond the least the search resolves ({approach.resolution:.1g} rad/s): they "
                       "veer apart instead of crossing, the two modes coupled there.")
    return said + f", within the least gap the search resolves ({approach.resolution:.1g} rad/s): they cross."


def along_the_sweep(data, parameter, unit_):
    """The derivation's frequencies along the sweep in a sentence: each mode's first and last, and its least and
    largest where they lie inside."""
    reference = data[data["source"] == "reference"]
    words = []
    for mode, curve in reference.groupby("mode"):
        x, f = curve["value"].to_numpy(), curve["frequency"].to_numpy()
        text = (f"mode {mode} from {f[0]:.4g} rad/s at {parameter} = {x[0]:.4g} to {f[-1]:.4g} rad/s at "
                f"{x[-1]:.4g} {unit_}")
        inside = [f"{what} {f[i]:.4g} rad/s at {x[i]:.4g}" for what, i in (("least", np.argmin(f)),
                                                                              ("largest", np.argmax(f)))
                  if 0 < i < len(f) - 1]
        words.append(text + (f" ({', '.join(inside)} {unit_})" if inside else ""))
    return "Frequencies along the sweep (the derivation's, at its values): " + "; ".join(words) + "."


# -- the stability boundaries -----------------------------------------------------------------------

BOUNDARY_RESOLUTION = 1e-6  # the bisection's relative width: far below any formula's difference worth naming
GROWN = 10.0  # a run whose displacement grows beyond this many times its start's has left the equilibrium
EITHER_SIDE = 0.02  # the runs either side of the boundary, this far from it (relative)


def boundary_search(case, scene, table, settings_, progress):
    """Bisection on the parameter between the bracket's stable and unstable ends (unstable: no equilibrium
    near the last stable one, or an eigenvalue with a positive real part), each equilibrium from the last
    stable one; then the derivation's runs from the stable side's equilibrium, displaced along its slowest
    mode, with the parameter either side of the boundary.  Returns ((boundary, stable above it), sentences), or
    (None, sentences) where the bracket holds none."""
    parameter = settings_["parameter"]
    unit_ = unit(case, parameter)
    if progress:
        progress(f"{case.name}: stability boundary in {parameter}")
    scale, why = scale_of(scene, settings_, "vibration.boundary")
    if scale is None:
        return None, [f"No search for a stability boundary in {parameter} at these parameters: its bracket is in "
                      f"multiples of `{settings_['scale']}`, which {why}."]
    ends = [scale * scene.value(x, "vibration.boundary.bracket") for x in settings_["bracket"]]
    try:
        expected = scene.value(settings_["expected"], "vibration.boundary.expected")
    except ValueError:  # a formula of the parameters (validate) with no value at these: it says there is no boundary
        expected = None
    guess = (table["q"], table["v"])
    states = [equilibrium_at(scene, table, parameter, x, guess)[1:] for x in ends]
    holds = [stable(modes) for _, modes in states]
    if holds[0] == holds[1]:
        inside = expected is not None and min(ends) < expected < max(ends)
        formula = (f"the formula `{settings_['expected']}` has no value at these parameters (it says there is no "
                   "boundary)" if expected is None else
                   f"the formula `{settings_['expected']}` gives {expected:.6g} {unit_}, "
                   + ("inside the bracket: the eigenvalues do not bear it out" if inside else "outside the bracket"))
        return None, [f"No stability boundary in {parameter} between {min(ends):.6g} and {max(ends):.6g} {unit_} (the "
                      f"bracket): the equilibrium is {'stable' if holds[0] else 'unstable or absent'} at both ends; "
                      f"{formula}."]
    good, bad = (0, 1) if holds[0] else (1, 0)
    x_good, x_bad, eq_good = ends[good], ends[bad], states[good][0]
    while abs(x_bad - x_good) > BOUNDARY_RESOLUTION * abs(x_good):
        mid = 0.5 * (x_good + x_bad)
        _, eq, modes = equilibrium_at(scene, table, parameter, mid, (eq_good.q, eq_good.v))
        if stable(modes):
            x_good, eq_good = mid, eq
        else:
            x_bad = mid
    boundary = 0.5 * (x_good + x_bad)
    compared = ("has no value at these parameters: it gives no boundary here" if expected is None else
                f"gives {expected:.7g}: {(boundary / expected - 1):+.1e} relative")
    stable_above = x_good > x_bad
    sentences = [f"Boundary from the eigenvalues: {parameter} = {boundary:.7g} {unit_} (bisection to "
                 f"{BOUNDARY_RESOLUTION:.0e}), the equilibrium stable {'above' if stable_above else 'below'} it; "
                 f"the formula `{settings_['expected']}` {compared}.  "
                 + " ".join(scene.prose(settings_["why"], "vibration.boundary.why").split())]
    sentences += [either_side(case, scene, table, parameter, boundary, side, stable_above) for side in (+1, -1)]
    return (boundary, stable_above), sentences


def either_side(case, scene, table, parameter, boundary, side, stable_above):
    """A sentence on the derivation's run with the parameter at boundary (1 + side EITHER_SIDE): started at the
    stable side's equilibrium displaced by the amplitude along its slowest mode, over `periods` of that mode;
    its largest displacement over the start's says whether the motion stays near the equilibrium."""
    unit_ = unit(case, parameter)
    stable_value = boundary * (1 + EITHER_SIDE if stable_above else 1 - EITHER_SIDE)
    value = boundary * (1 + side * EITHER_SIDE)
    _, eq, modes = equilibrium_at(scene, table, parameter, stable_value, (table["q"], table["v"]))
    if eq is None:
        return f"No run at {parameter} = {value:.5g} {unit_}: no equilibrium on the stable side to start from."
    slowest = modes.oscillating()[0]
    n = len(eq.q)
    period = 2 * math.pi / modes.eigenvalues[slowest].imag
    amplitude = table["amplitude"]
    start = eq.state + amplitude * along(modes.right[:, slowest], n)
    run_scene, q0, v0 = vary(scene, parameter, value, start[:n], start[n:])
    start = np.concatenate([q0, v0])
    model = run_scene.model("reference")
    t_end = table["periods"] * period
    output_step = t_end / (table["periods"] * RUNS_PER_PERIOD)
    try:
        with np.errstate(all="ignore"):
            run = simulate(model, (start[:n], start[n:]), t_end, "DOP853", rtol=case.integration["rtol"],
                           output_step=output_step, work=False, max_step=period / 20, omega=2 * math.pi / period,
                           quantities=())
        # the coordinates at rest in the equilibrium: a cyclic one's angle drifts at a changed rate, and stays one
        resting = eq.v == 0
        q = (run[list(case.coords)].to_numpy() - (eq.q + np.outer(run.index.to_numpy(), eq.v)))[:, resting]
        grown = float(np.max(np.abs(q)) / amplitude)
        ended = f"its displacement reaches {grown:.3g} times the start's"
    except (Unstable, ArithmeticError) as error:
        grown, ended = math.inf, f"it blew up ({error})"
    stays = grown < GROWN  # a stable mode's linear motion stays at its start's size
    expect_stable = (value > boundary) == stable_above
    agree = "as the eigenvalues say" if stays == expect_stable else "AGAINST the eigenvalues"
    return (f"Run at {parameter} = {value:.5g} {unit_} ({side * EITHER_SIDE:+.0%} of the boundary), from the equilibrium "
            f"at {stable_value:.5g} {unit_} displaced by {amplitude:g} along its slowest mode, over {t_end:.3g} s: "
            f"{ended} (beyond {GROWN:g} counts as leaving): {'stays near' if stays else 'leaves'} the equilibrium, "
            f"{agree}.")
