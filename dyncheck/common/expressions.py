"""Expressions in case files: the numbers of case.toml that are expressions of the parameters
(dyncheck.case.folder.Case.value), and those evaluated along a run: report values, figures, stop tests,
figure ranges.

No expression reaches Python's eval, which a case file escapes through attributes
(`().__class__.__base__.__subclasses__()`) and hangs with a power of huge integers (`9**9**9`).
`evaluate` parses it and walks its syntax tree node by node from a whitelist: numbers, names of the
namespace, unary + -, + - * / **, one comparison (not a chain), and calls of the functions below.
Every number is a float, so a power overflows at once instead of building a huge integer.
"""

import ast
import functools
import operator

import numpy as np

from dyncheck.common.messages import suggest

FUNCTIONS = ("sin", "cos", "tan", "arctan", "sqrt", "exp", "abs", "ceil", "max", "min")  # numpy's, by these names
CALLABLE = FUNCTIONS + ("first",)  # and first(condition), see `namespace`
# The case files' longest expression has 53 characters and the deepest syntax tree 8 levels (ast's
# nodes, operators included); these bounds leave room for any formula of a page, and keep the parse
# and the walk far inside Python's recursion limit of 1000.
MAX_LENGTH = 1000  # characters
MAX_DEPTH = 100  # levels of the syntax tree
# 2.0**1024 is beyond the largest float: a larger exponent overflows, or underflows to 0, for every
# base but those within a factor 2 of 1, which no formula here raises so high.
MAX_EXPONENT = 1024


def _extreme(reduce, pairwise):
    """max(x) / min(x): over an array (along a run); max(a, b, ...): of its arguments, element by element."""
    return lambda *args: reduce(args[0]) if len(args) == 1 else functools.reduce(pairwise, args)


# numpy's, by these names; max and min as in Python (numpy's max(a, b) takes b for an axis)
NUMPY = {**{name: getattr(np, name) for name in FUNCTIONS}, "max": _extreme(np.max, np.maximum),
         "min": _extreme(np.min, np.minimum)}


def of_parameters(params):
    """What a case-file number may use: the parameters, pi and numpy's functions."""
    return {**NUMPY, "pi": np.pi, **params}


def namespace(case, run):
    """What a case's expressions may use along `run` (a DataFrame indexed by t): its columns (among them
    the traced bodies' centre-of-mass coordinates <body>_x, _y, _z, see dyncheck.checks.runs.with_paths),
    t, the parameters, numpy's functions, pi and first(condition); up to the case's `stop` condition,
    if it has one."""
    return along(case.params, case.spec["report"].get("stop"), run)


def along(params, stop, run):
    """`namespace` of a run at the parameters `params`, cut where the expression `stop` (or None) first holds."""
    t = run.index.to_numpy()
    names = of_parameters(params)
    names.update({column: run[column].to_numpy() for column in run.columns})
    names["t"] = t
    if stop:  # the book's program stops here: cut every series after the first time it holds
        hit = evaluate(stop, names)
        end = int(np.argmax(hit)) + 1 if np.any(hit) else len(t)
        names = {k: (x[:end] if isinstance(x, np.ndarray) and x.shape[:1] == t.shape else x) for k, x in names.items()}
        t = names["t"]
    names["first"] = lambda condition: float(t[np.argmax(condition)]) if np.any(condition) else float("nan")
    return names


def evaluate(expression, names):
    """The value of `expression` (a string) with the names `names` (numbers, numpy arrays, the
    functions of CALLABLE); ValueError says why it cannot be evaluated."""
    try:
        with np.errstate(all="ignore"):  # along a run, a NaN or inf is a value of the series
            return _parse(expression)(names)
    except (ArithmeticError, TypeError) as error:  # ZeroDivisionError, a call with the wrong arguments
        raise ValueError(str(error)) from None


def names(expression):
    """The names `expression` uses (not its functions); ValueError if it is not allowed."""
    _parse(expression)
    tree = ast.parse(expression.strip(), mode="eval")
    called = {node.func.id for node in ast.walk(tree) if isinstance(node, ast.Call)}
    return {node.id for node in ast.walk(tree) if isinstance(node, ast.Name)} - called


@functools.cache  # some expressions are evaluated once per run
def _parse(expression):
    """`expression` as a function of the namespace, or ValueError if it is not allowed."""
    if len(expression) > MAX_LENGTH:
        raise ValueError(f"longer than {MAX_LENGTH} characters")
    try:
        tree = ast.parse(expression.strip(), mode="eval")  # eval strips blanks too
    except SyntaxError as error:
        raise ValueError(error.msg) from None
    except RecursionError:
        raise ValueError(f"nested deeper than {MAX_DEPTH} levels") from None
    depth, level = 0, [tree]
    while level:  # breadth first, without recursion
        depth += 1
        if depth > MAX_DEPTH:
            raise ValueError(f"nested deeper than {MAX_DEPTH} levels")
        level = [child for node in level for child in ast.iter_child_nodes(node)]
    return _compile(tree.body)


def _power(base, exponent):
    """base ** exponent, for an exponent within +-MAX_EXPONENT and a real result."""
    if np.any(np.abs(exponent) > MAX_EXPONENT):
        raise ValueError(f"the exponent {np.max(np.abs(exponent)):g} is beyond +-{MAX_EXPONENT}")
    try:
        result = base ** exponent
    except OverflowError:  # only Python floats raise it; numpy's overflow to inf
        raise ValueError(f"the power {exponent:g} of {base:g} overflows") from None
    if isinstance(result, complex):  # a Python float's fractional power of a negative number
        raise ValueError(f"the power {exponent:g} of {base:g} is not a real number")
    return result


UNARY = {ast.UAdd: operator.pos, ast.USub: operator.neg}
BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
          ast.Pow: _power}
COMPARISONS = {ast.Lt: operator.lt, ast.LtE: operator.le, ast.Gt: operator.gt, ast.GtE: operator.ge,
               ast.Eq: operator.eq, ast.NotEq: operator.ne}


def _compile(node):
    """A function of the namespace that evaluates `node`, or ValueError if `node` is not allowed."""
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):  # not bool, complex, str
        try:
            number = float(node.value)
        except OverflowError:
            raise ValueError(f"an integer of {len(str(node.value))} digits is beyond the largest float") from None
        return lambda names: number
    if isinstance(node, ast.Name):
        return lambda names: _lookup(node.id, names)
    if isinstance(node, ast.UnaryOp) and type(node.op) in UNARY:
        unary, operand = UNARY[type(node.op)], _compile(node.operand)
        return lambda names: unary(operand(names))
    if isinstance(node, ast.BinOp) and type(node.op) in BINARY:
        binary, left, right = BINARY[type(node.op)], _compile(node.left), _compile(node.right)
        return lambda names: binary(left(names), right(names))
    if isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in COMPARISONS:
        compare, left, right = COMPARISONS[type(node.ops[0])], _compile(node.left), _compile(node.comparators[0])
        return lambda names: compare(left(names), right(names))
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in CALLABLE \
            and not node.keywords:
        arguments = [_compile(argument) for argument in node.args]
        return lambda names: _lookup(node.func.id, names)(*(argument(names) for argument in arguments))
    text = ast.unparse(node)
    raise ValueError(f"`{text if len(text) <= 40 else text[:37] + '...'}` is not allowed; an expression has "
                     f"only numbers, names, + - * / **, one comparison and calls of {', '.join(CALLABLE)}")


def _lookup(name, names):
    if name not in names:
        raise ValueError(f"name '{name}' is not defined{suggest(name, names)}")
    return names[name]
