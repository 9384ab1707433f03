"""The book's printed formulas as Python expressions: a `Book` declares them in `PRINTED` and
evaluates them here, so that the strings dyncheck searches for edits are the code that runs."""


def evaluate(printed, names, keys=None):
    """{key: value} of the printed expressions `keys` (default: all) with the symbols `names`."""
    return {key: eval(printed[key], {"__builtins__": {}}, names) for key in (keys or printed)}
