"""Numbers measured in a case's saved results, for the prose of its pages.

A case file's `[measured]` table names each number and says how it is measured (its `kind`, and the run,
the expression along it, the mode or the row it is taken from).  A text of the pages may then write
`{~ expression}` or `{~ expression :format}`: an expression (dyncheck.common.expressions) of those names and the
parameters, written with a number's format spec (default `.3g`) or in the words of a rule of dyncheck.common.words
(`:ratio`, `:gains`, `:lag`), so that a sentence says "14 % larger than" of 1.14 and "about twice" only of 1.9
to 2.1.  The numbers are measured from the CaseResult when the page is rendered (the pages render saved
results only); where one cannot be (its run blew up, the book's program did not finish), the paragraph that
holds it says so instead of guessing.  `check` refuses, on load, what could not be evaluated.
"""

import math
import re
from dataclasses import dataclass, replace

import numpy as np

from dyncheck.common import expressions, words

MEASURED_NUMBER = re.compile(r"\{~([^{}]*)\}")
# What each kind measures, and the keys it needs beside `kind`.
KINDS = {
    "span": ("of", "run"),  # max - min of the expression along the run
    "rms": ("of", "run"),  # its root mean square about its mean
    "start": ("of", "run"),  # its value at the run's first output
    "end": ("of", "run"),  # and at its last
    "change": ("of", "run"),  # end - start
    "phase lag": ("of", "run", "against"),  # degrees by which `run`'s oscillation lags `against`'s (phase_lag)
    "frequency": ("mode",),  # rad/s of the vibration analysis's mode (1: the slowest), of `source` (the reference)
    "error": ("check", "quantity", "sources"),  # the error of the row with this check, quantity and comparison
    "program step": (),  # the time step of the book's program, s
}
OPTIONAL = {"frequency": ("source",)}
# The runs a measure may be taken along, named as the rows name them.
RUNS = ("program", "book equations, same integrator", "tight reference", "reference", "book", "mujoco", "pinocchio")
PROGRAM_RUNS = {"program": "listing", "book equations, same integrator": "same integrator"}  # CaseResult.program's
# The texts that may hold measured numbers: those a page renders with the results beside it.
FIELDS = re.compile(r"course\.intro|course\.steps\[\d+\]\.(text|figures\[\d+\]\.caption)|animation\.caption"
                    r"|findings\[\d+\]\.(title|measured)")


@dataclass(frozen=True)
class Unavailable:
    """A measure that this run could not take, and why."""
    why: str


def check(case):
    """The case's [measured] table and every `{~ ...}` of its texts, against what a result of the case holds;
    ValueError naming the file, the field and the value."""
    table = case.spec.get("measured", {})
    columns = set(along_names(case))
    for name, item in table.items():
        field = f"measured.{name}"
        kind = item["kind"]
        needed, allowed = KINDS[kind], {"kind", *KINDS[kind], *OPTIONAL.get(kind, ())}
        for key in needed:
            if key not in item:
                raise _error(case, field, item, f"has no `{key}`, which a measure of kind '{kind}' needs")
        for key in set(item) - allowed:
            raise _error(case, f"{field}.{key}", item[key], f"is not a key of a measure of kind '{kind}' (it has "
                         + (", ".join(f"`{k}`" for k in needed) or "no other keys") + ")")
        for key in ("run", "against"):
            if item.get(key) in PROGRAM_RUNS and not case.has_program:
                raise _error(case, f"{field}.{key}", item[key], "is a run of the book's program, which this case has not")
        if kind == "program step" and not case.has_program:
            raise _error(case, field, item, "measures the book's program, which this case has not")
        if "of" in item:
            try:
                unknown = expressions.names(item["of"]) - columns
            except ValueError as error:
                raise _error(case, f"{field}.of", item["of"], f"cannot be parsed: {error}") from None
            if unknown:
                raise _error(case, f"{field}.of", item["of"], f"names {', '.join(sorted(unknown))}, not a column of "
                             "the runs or a parameter")
    names = {**expressions.of_parameters(case.params), **dict.fromkeys(table, 1.0)}
    for field, text in texts(case.spec):
        if not FIELDS.fullmatch(field):
            raise _error(case, field, text, "holds a measured number `{~ ...}`, which only the texts a page renders "
                         "beside the results may: course texts and figure captions, animation.caption, a finding's "
                         "title and measured")
        for match in MEASURED_NUMBER.finditer(text):
            expression, spec = split(match[1])
            try:
                expressions.evaluate(expression, names)
            except ValueError as error:
                raise _error(case, field, match[0], f"cannot be evaluated from the measures ([measured]: "
                             f"{', '.join(table) or 'none'}) and the parameters: {error}") from None
            if spec not in words.WORDS and not words.is_format(spec):
                raise _error(case, field, match[0], f"{spec!r} is neither a number's format spec nor one of the "
                             f"words {', '.join(words.WORDS)} (dyncheck.common.words)")


def texts(spec, holding=MEASURED_NUMBER, path=""):
    """(field, text) of every text of a case file that `holding` finds in (a measured number, by default; None:
    every text), the field a dotted path such as `findings[2].measured`."""
    if isinstance(spec, dict):
        for key, value in spec.items():
            yield from texts(value, holding, f"{path}.{key}" if path else key)
    elif isinstance(spec, list):
        for i, value in enumerate(spec):
            yield from texts(value, holding, f"{path}[{i}]")
    elif isinstance(spec, str) and (holding is None or holding.search(spec)):
        yield path, spec


def along_names(case):
    """The names an expression along a run may use: the runs' columns, t and the parameters."""
    paths = [f"{body}_{axis}" for body in case.spec["scene"].get("paths", []) for axis in "xyz"]
    return [*case.coords, *(f"{c}_rate" for c in case.coords), *case.spec["reactions"], "energy", "work", "t",
            *paths, *expressions.of_parameters(case.params)]


def split(inside):
    """The expression and the format of `{~ expression :format}`."""
    expression, colon, spec = inside.rpartition(":")
    return (expression.strip(), spec.strip()) if colon else (inside.strip(), ".3g")


def _error(case, field, value, problem):
    text = repr(value)
    return ValueError(f"{case.origin}: {field} = {text if len(text) <= 80 else text[:77] + '...'} {problem}")


# -- measuring -------------------------------------------------------------------------------------

def parameters(result):
    """The parameters of a result's run: the case file's values with its overrides."""
    return {**{name: float(p["value"]) for name, p in result.spec["params"].items()}, **result.overrides}


def values(result):
    """{name: its value, or Unavailable} of every measure of the result's case."""
    return {name: measure(result, item) for name, item in result.spec.get("measured", {}).items()}


# What a kind of measure makes of an expression's values along a run.
REDUCTIONS = {"span": np.ptp, "rms": np.std, "start": lambda x: x[0], "end": lambda x: x[-1],
              "change": lambda x: x[-1] - x[0]}


def measure(result, item):
    """One measure of `[measured]` (its table `item`) taken from the result: a float, or Unavailable."""
    kind = item["kind"]
    if kind == "frequency":
        return frequency(result, item["mode"], item.get("source", "reference"))
    if kind == "error":
        return row_error(result, item["check"], item["quantity"], item["sources"])
    if kind == "program step":
        return result.program["dt"] if result.program else Unavailable(program_failure(result))
    series = [of(result, item["of"], item[key]) for key in ("run", "against") if key in item]
    missing = [s for s in series if isinstance(s, Unavailable)]
    if missing:
        return missing[0]
    (t, x), *other = series
    if kind == "phase lag":
        return phase_lag(t, x, *other[0])
    return float(REDUCTIONS[kind](x))


def of(result, expression, run):
    """(t, the expression's values) along a run of the result, or Unavailable."""
    frame = run_frame(result, run)
    if isinstance(frame, Unavailable):
        return frame
    names = expressions.along(parameters(result), result.spec["report"].get("stop"), frame)
    try:  # a column this run lacks: a derivation without energy, the listing's run without work
        x = np.broadcast_to(np.asarray(expressions.evaluate(expression, names), dtype=float), names["t"].shape)
    except ValueError as error:
        return Unavailable(f"{expression} along the {words_of(run)}: {error}")
    if not np.all(np.isfinite(x)):
        return Unavailable(f"{expression} is not finite along the {words_of(run)}")
    return names["t"], x


def run_frame(result, run):
    """The run named as the rows name it (RUNS), or Unavailable saying why this result has none."""
    if run in PROGRAM_RUNS:
        return result.program[PROGRAM_RUNS[run]] if result.program else Unavailable(program_failure(result))
    source, twin = ("reference", True) if run == "tight reference" else (run, False)
    outcome = result.runs.get(source)
    if outcome is None:
        return Unavailable(f"this result has no {source} run")
    if not outcome.ok:
        return Unavailable(f"the {words_of(run)} did not reach its end ({outcome.failure})")
    return outcome.twin if twin else outcome.run


def words_of(run):
    return {"program": "book's program's run", "tight reference": "exact motion"}.get(run, f"{run}'s run")


def program_failure(result):
    """Why a result has no run of the book's program: its rows say."""
    why = next((r.detail for r in result.rows if r.check == "program" and r.sources == ("program run",)), None)
    return f"the book's program did not run to its end ({why})" if why else "the book's program did not run"


def frequency(result, mode, source):
    """The natural frequency (rad/s) of the vibration analysis's oscillating mode number `mode` (1: the slowest)."""
    vib = result.vibration
    if vib is None or vib.equilibrium is None or source not in vib.modes:
        return Unavailable("no vibration analysis" + (f": {vib.failure}" if vib is not None and vib.failure else ""))
    modes = vib.modes[source]
    oscillating = modes.oscillating()
    if mode > len(oscillating):
        return Unavailable(f"the equilibrium has {len(oscillating)} oscillating modes, not {mode}")
    return float(modes.eigenvalues[oscillating[mode - 1]].imag)


def row_error(result, check_, quantity, sources):
    row = next((r for r in result.rows if (r.check, r.quantity, r.comparison) == (check_, quantity, sources)), None)
    if row is None:
        return Unavailable(f"no row {check_} {quantity} ({sources})")
    return Unavailable(f"row {check_} {quantity} ({sources}): {row.detail}") if row.error is None else row.error


# The phase is taken over the last whole periods of the oscillation, at most this many: a drift that builds up over
# the run shows at its end, and more periods average the slower modulations of a motion that is not one sine.
PERIODS = 2
PADDING = 16  # the spectrum zero-padded this many times, so that its peak finds the period to about 1 / (16 N) of it


def phase_lag(t, x, s, y):
    """Degrees (within (-180, 180]) by which the oscillation x(t) lags y(s) at y's dominant frequency, over the last
    PERIODS whole periods of it within both runs (y interpolated to x's times: the book's program may end a step
    before the exact motion); Unavailable where either does not oscillate."""
    common = (t >= s[0]) & (t <= s[-1])
    t, x = t[common], x[common]
    y = np.interp(t, s, y)
    y0 = y - y.mean()
    if np.ptp(y0) == 0 or np.ptp(x) == 0:
        return Unavailable("one of the two runs does not oscillate")
    dt = (t[-1] - t[0]) / (len(t) - 1)
    spectrum = np.abs(np.fft.rfft(y0, PADDING * len(t)))
    frequencies = np.fft.rfftfreq(PADDING * len(t), dt)
    peak = 1 + int(np.argmax(spectrum[1:]))  # not the mean
    period = 1 / frequencies[peak]
    whole = min(PERIODS, math.floor((t[-1] - t[0]) / period))
    if whole < 1:
        return Unavailable(f"the run is shorter than the oscillation's period ({period:.3g} s)")
    window = t >= t[-1] - whole * period
    turn = np.exp(-2j * np.pi * frequencies[peak] * t[window])
    phase = lambda z: np.angle(np.sum((z[window] - z[window].mean()) * turn))
    lag = math.degrees(phase(y) - phase(x))
    return float(-((-lag + 180) % 360 - 180))  # within (-180, 180]


# -- writing ---------------------------------------------------------------------------------------

def fill(result, text, measures=None):
    """`text` with each `{~ expression :format}` written from the result's measures; a paragraph (text between
    blank lines) that needs one the run could not take says so, and why, instead."""
    if not MEASURED_NUMBER.search(text):
        return text
    measures = values(result) if measures is None else measures
    names = {**expressions.of_parameters(parameters(result)), **measures}

    def paragraph(part):
        missing = {measures[n].why: n for match in MEASURED_NUMBER.finditer(part)
                   for n in expressions.names(split(match[1])[0]) if isinstance(measures.get(n), Unavailable)}
        try:
            if missing:
                raise ValueError("; ".join(missing))
            return MEASURED_NUMBER.sub(lambda match: written(match[1], names), part)
        except ValueError as why:  # a measure the run could not take, or words no number of it has (a ratio of 0)
            return f"(Not measured in this run: {why}.)"
    return "\n\n".join(paragraph(part) for part in text.split("\n\n"))


def written(inside, names):
    expression, spec = split(inside)
    value = float(expressions.evaluate(expression, names))
    return words.WORDS[spec](value) if spec in words.WORDS else format(value, spec)


def finding(result, found):
    """A finding of the result with its title and measured text written from the result's measures."""
    measures = values(result) if MEASURED_NUMBER.search(found.title + found.measured) else {}
    return replace(found, title=fill(result, found.title, measures),
                   measured=fill(result, found.measured, measures))
