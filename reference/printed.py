"""The book's printed formulas as Python expressions: a `Book` declares them in `PRINTED` and
evaluates them here, so that the strings dyncheck searches for edits are the code that runs."""

import functools


@functools.cache
def _compiled(expression):
    """Each string is compiled once: an integrator evaluates it at every step."""
    return compile(expression, "<printed>", "eval")


def evaluate(printed, names, keys=None):
    """{key: value} of the printed expressions `keys` (default: all) with the symbols `names`."""
    return {key: eval(_compiled(printed[key]), {"__builtins__": {}}, names) for key in (keys or printed)}
