"""The qualitative words a page chooses from a number, each by a rule written here beside its thresholds, so
that a sentence cannot say "twice" of 1.03 or "agrees" of a deviation of 2.  The prose of a case file asks for
them by name (`{~ expression :ratio}`, dyncheck.results.measured); the student's page for its checks (`agreement`)."""

import math
import re

# A number's format spec in prose (Python's: [[fill]align][sign][z][#][0][width][grouping][.precision][type]), its
# width and precision of at most 3 digits each: a double holds 17 significant digits and a page's line is under
# 200 characters, so 999 already writes nothing but padding and noise, while format() would build whatever is
# asked (width 99999999999: a MemoryError; precision 999999999: a 1 GB string, 73 s).
FORMAT_SPEC = re.compile(r"(?:.?[<>=^])?[-+ ]?z?#?0?(?P<width>[0-9]*)[,_]?(?:\.(?P<precision>[0-9]+))?[eEfFgGn%]?")


def is_format(spec):
    """Whether `spec` is a format spec a prose number may have (FORMAT_SPEC)."""
    form = FORMAT_SPEC.fullmatch(spec)
    return bool(form) and len(form["width"]) <= 3 and len(form["precision"] or "") <= 3


# A ratio reads "about twice" (or "about half") within 5 % of 2 (of 1/2): what a reader takes "about" to allow, and
# far from 1.5, where "twice" would overstate by a third.  Within 0.5 % of 1 two measured sizes are "the same": below
# what a printed figure shows (1 % of its axis, dyncheck.common.ceilings.LISTING).
TWICE = (1.9, 2.1)
HALF = (0.475, 0.525)
SAME = (0.995, 1.005)


def percent(fraction):
    """A fraction as a page writes a percentage: "14 %", "0.7 %"."""
    share = 100 * abs(fraction)
    return f"{share:.0f} %" if share >= 1 else f"{share:.1g} %"


def share(error):
    """A relative error as a share of the quantity's largest value: "95 %", or "3.2e-03" below 1 %."""
    return percent(error) if error >= 0.01 else f"{error:.1e}"


def ratio(r):
    """A ratio of two sizes, A / B, as the words that stand between them in "A is ... B": "the same as",
    "14 % larger than", "about twice", "3.1 times", "14 % smaller than", "about half", "30 % of"."""
    if not (math.isfinite(r) and r > 0):
        raise ValueError(f"a ratio of two sizes is a positive number, not {r}")
    if SAME[0] <= r <= SAME[1]:
        return "the same as"
    if TWICE[0] <= r <= TWICE[1]:
        return "about twice"
    if HALF[0] <= r <= HALF[1]:
        return "about half"
    if r > 2:
        return f"{r:.2g} times"
    if r > 1:
        return f"{percent(r - 1)} larger than"
    if r > 0.5:
        return f"{percent(1 - r)} smaller than"
    return f"{percent(r)} of"


def gains(change):
    """The verb of an energy's change by its sign: "gains", "loses" (0: "keeps")."""
    if not math.isfinite(change):
        raise ValueError(f"a change is a finite number, not {change}")
    return "gains" if change > 0 else "loses" if change < 0 else "keeps"


# Two oscillations are "in step" while their phases differ by at most 5 degrees: a 70th of a period, under the
# width of a printed curve's line at the figures' scale.
IN_STEP = 5.0  # degrees


def lag(degrees):
    """A phase lag of A behind B, in degrees within (-180, 180], as the words between them in "A ... B":
    "lags 59 degrees behind", "runs 12 degrees ahead of", "stays in step (within 2 degrees) with"."""
    if not math.isfinite(degrees):
        raise ValueError(f"a phase lag is a finite number, not {degrees}")
    if abs(degrees) <= IN_STEP:
        return f"stays in step (within {max(abs(degrees), 1):.0f} degrees) with"
    return f"lags {degrees:.0f} degrees behind" if degrees > 0 else f"runs {-degrees:.0f} degrees ahead of"


def agreement(checks):
    """How checks read from their relative errors, each check (whom, error, whether the error is within its
    tolerance): "agrees with MuJoCo to 3e-15 and Pinocchio exactly", "differs from the exact motion by 95 %".  A
    deviation beyond its tolerance never agrees."""
    agree = [f"{whom} exactly" if error == 0 else f"{whom} to {error:.0e}" for whom, error, within in checks if within]
    differ = [f"{whom} by {share(error)}" for whom, error, within in checks if not within]
    return " and ".join(([f"agrees with {' and '.join(agree)}"] if agree else [])
                        + ([f"differs from {' and '.join(differ)}"] if differ else []))


WORDS = {"ratio": ratio, "gains": gains, "lag": lag}  # the rules a case file's prose may name after its `:`
EXAMPLES = {"ratio": (1.003, 1.14, 2.02, 3.1, 0.86, 0.49, 0.3), "gains": (1.85, -0.04), "lag": (85.2, -12.4, 1.6)}
