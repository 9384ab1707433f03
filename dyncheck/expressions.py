"""Expressions in case files, evaluated along a run: report values, figures, stop tests, figure ranges."""

import numpy as np

FUNCTIONS = ("sin", "cos", "tan", "arctan", "sqrt", "abs", "max", "min", "pi")


def namespace(case, run):
    """What a case's expressions may use along `run` (a DataFrame indexed by t): its columns, t, the
    parameters, the traced bodies' centre-of-mass coordinates (<body>_x, _y, _z), numpy's
    functions and first(condition); up to the case's `stop` condition, if it has one."""
    model = case.model("mujoco")
    q = run[list(case.coords)].to_numpy()
    positions = np.array([model.points(t, qi)[0] for t, qi in zip(run.index, q)])
    t = run.index.to_numpy()
    names = {name: getattr(np, name) for name in FUNCTIONS}
    names.update(case.params)
    names.update({column: run[column].to_numpy() for column in run.columns})
    for b, body in enumerate(case.scene["paths"]):
        names.update({f"{body}_{axis}": positions[:, b, i] for i, axis in enumerate("xyz")})
    names["t"] = t
    stop = case.spec["report"].get("stop")
    if stop:  # the book's program stops here: cut every series after the first time it holds
        hit = evaluate(stop, names)
        end = int(np.argmax(hit)) + 1 if np.any(hit) else len(t)
        names = {k: (x[:end] if isinstance(x, np.ndarray) and x.shape[:1] == t.shape else x) for k, x in names.items()}
        t = names["t"]
    names["first"] = lambda condition: float(t[np.argmax(condition)]) if np.any(condition) else float("nan")
    return names


def evaluate(expression, names):
    with np.errstate(all="ignore"):
        return eval(expression, {"__builtins__": {}}, names)
