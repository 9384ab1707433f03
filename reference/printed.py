"""The book's printed formulas as Python expressions: a `Book` declares them in `PRINTED` and
evaluates them here, so that the strings dyncheck searches for edits are the code that runs."""

import functools

import numpy as np


@functools.cache
def _compiled(expression):
    """Each string is compiled once: an integrator evaluates it at every step."""
    return compile(expression, "<printed>", "eval")


def evaluate(printed, names, keys=None):
    """{key: value} of the printed expressions `keys` (default: all) with the symbols `names`."""
    return {key: eval(_compiled(printed[key]), {"__builtins__": {}}, names) for key in (keys or printed)}


def function(expression, arguments, names):
    """The printed expression as a Python function of the symbols `arguments`, its other symbols bound
    to `names`: where a model evaluates it at every step, rebuilding the names costs more than it."""
    return eval(f"lambda {', '.join(arguments)}: {expression}", {"__builtins__": {}, **names})


def floats(q, v):
    """A state's coordinates and rates as one list of Python floats, for `Functions`: arithmetic and math's functions
    cost less on them than on numpy's scalars, and an array's tolist makes them at once."""
    return np.asarray(q, dtype=float).tolist() + np.asarray(v, dtype=float).tolist()


class Functions:
    """The expressions of a table of printed ones as `function`s of `arguments`, the other symbols bound to
    `names`: compiled once per expression, and looked up in the table at each use, so that the table stays
    the code that runs (an edit of it takes effect)."""

    def __init__(self, table, arguments, names):
        self.table, self.arguments, self.names = table, tuple(arguments), names
        self._made = {}

    def __getitem__(self, key):
        expression = self.table[key]
        if expression not in self._made:
            self._made[expression] = function(expression, self.arguments, self.names)
        return self._made[expression]
