"""Straight-line code traced from a function of floats, for the models that evaluate one at every integrator stage.

`compiled(function, arguments)` runs `function` once on tracer values: each + - * / (unary minus, ** with a constant
exponent, `sin`, `cos` of this module) on a traced value writes one assignment of Python source, the same operation
on the same operands; an operation on constants alone (parameters) is done then and there by Python, the very float
operation the plain function does at every call.  The source (one function of `arguments`, returning the traced
results in their tuples and lists) is compiled once.  Equal operations on equal operands are done once, and
results that nothing uses are not computed (but for / ** sin cos, which may raise).

Zeros are folded, which makes the code half as long (the chain's matrices, axes and offsets are mostly zeros):
x * 0 is a zero and x + 0, x - 0 are x, but for the sign of a zero result, where x is finite; x * 1, x / 1 are x.
So the code gives the plain function's floats, bit for bit but for the sign of a zero (which only the sign of later
zeros depends on: +0.0 == -0.0, and dividing by either raises), where every x it multiplied by zero is finite.  It
checks that (an infinity or NaN there would make a NaN of the plain function's product) and otherwise returns
`function`'s own result, as it does where an operation raises.

A function the tracer cannot follow (a branch or a comparison on a traced value, an operation it does not know,
a constant that is not a finite float or int) raises at trace time, and `compiled` returns `function` itself.
"""

import math


class Untraceable(Exception):
    """The traced function does something the straight-line code cannot repeat."""


class _Tape:
    """The assignments written so far, (name, expression, the names it reads, whether it may raise); the values
    multiplied by a zero (`guarded`); and the zero of the trace."""

    def __init__(self):
        self.lines, self.made, self.guarded = [], {}, set()
        self.zero = Value(self, "0.0")

    def emit(self, expression, operands, may_raise=False):
        if expression not in self.made:  # the same operation on the same operands: the same float
            name = f"x{len(self.lines)}"
            self.lines.append((name, expression, [x.name for x in operands if _traced(x)], may_raise))
            self.made[expression] = Value(self, name)
        return self.made[expression]


def _traced(x):
    return isinstance(x, Value) and x is not x.tape.zero


def _atom(x):
    """A traced value's name, or a constant's exact literal."""
    if isinstance(x, Value):
        return x.name
    if type(x) not in (float, int) or not math.isfinite(x):
        raise Untraceable(f"a constant {x!r} of type {type(x).__name__}")
    return repr(x) if x >= 0 and math.copysign(1.0, x) > 0 else f"({x!r})"


def _is(x, constant):
    """x is the constant (a zero: of either sign, or the trace's zero)."""
    return (isinstance(x, Value) and constant == 0 and x is x.tape.zero) or (type(x) in (float, int) and x == constant)


def _binary(a, operator, b):
    tape = a.tape if isinstance(a, Value) else b.tape
    if operator == "*" and (_is(a, 0) or _is(b, 0)):
        for x in (a, b):  # a zero where the other factor is finite, which the code checks
            if _traced(x):
                tape.guarded.add(x.name)
            else:
                _atom(x)  # a constant factor must be a finite float or int, as anywhere else
        return tape.zero
    if (operator in "+-" and _is(b, 0)) or (operator in "*/" and _is(b, 1)):
        return a
    if operator in "+*" and _is(a, 0 if operator == "+" else 1):
        return b
    if operator == "-" and _is(a, 0):
        return -b
    return tape.emit(f"{_atom(a)} {operator} {_atom(b)}", (a, b), may_raise=operator == "/")


class Value:
    """A float the traced function computes, named in the straight-line code."""

    __array_ufunc__ = None  # numpy's scalars and arrays leave their operators to ours (which refuse them)

    def __init__(self, tape, name):
        self.tape, self.name = tape, name

    def __add__(self, other): return _binary(self, "+", other)
    def __radd__(self, other): return _binary(other, "+", self)
    def __sub__(self, other): return _binary(self, "-", other)
    def __rsub__(self, other): return _binary(other, "-", self)
    def __mul__(self, other): return _binary(self, "*", other)
    def __rmul__(self, other): return _binary(other, "*", self)
    def __truediv__(self, other): return _binary(self, "/", other)
    def __rtruediv__(self, other): return _binary(other, "/", self)

    def __neg__(self):
        return self if self is self.tape.zero else self.tape.emit(f"-{self.name}", (self,))

    def __pow__(self, exponent):
        if isinstance(exponent, Value):
            raise Untraceable("a traced exponent")
        return self.tape.emit(f"{self.name} ** {_atom(exponent)}", (self,), may_raise=True)

    def _refuse(self, *_):
        raise Untraceable("a branch, comparison or conversion of a traced value")

    __bool__ = __float__ = __int__ = __index__ = __eq__ = __ne__ = __lt__ = __le__ = __gt__ = __ge__ = _refuse
    __rpow__ = __floordiv__ = __rfloordiv__ = __mod__ = __rmod__ = __abs__ = __round__ = _refuse
    __hash__ = None


def sin(x):
    """math.sin, or its traced call."""
    return x.tape.emit(f"sin({x.name})", (x,), may_raise=True) if isinstance(x, Value) else math.sin(x)


def cos(x):
    """math.cos, or its traced call."""
    return x.tape.emit(f"cos({x.name})", (x,), may_raise=True) if isinstance(x, Value) else math.cos(x)


def _literal(result, used):
    """The source of the traced function's result (tuples and lists of values), noting the names it reads."""
    if isinstance(result, (tuple, list)):
        items = "".join(f"{_literal(x, used)}, " for x in result)
        return f"({items})" if isinstance(result, tuple) else f"[{items}]"
    if _traced(result):
        used.add(result.name)
    return _atom(result)


def compiled(function, arguments):
    """`function` of the floats named `arguments` as straight-line code, or `function` itself where it cannot be
    traced (see the module's docstring)."""
    tape = _Tape()
    try:
        used = set()
        result = _literal(function(*(Value(tape, name) for name in arguments)), used)
    except Exception:  # noqa: BLE001  (whatever the trace stumbles on, the plain function does what it always did)
        return function
    used |= tape.guarded
    body = []
    for name, expression, operands, may_raise in reversed(tape.lines):
        if name in used or may_raise:
            body.append(f"        {name} = {expression}\n")
            used.update(operands)
    call = f"({', '.join(arguments)})"
    check = f"    if not isfinite({' + '.join(sorted(tape.guarded))}):\n        return plain{call}\n" if tape.guarded else ""
    source = (f"def traced{call}:\n    try:\n{''.join(reversed(body))}        pass\n"
              f"    except (ArithmeticError, ValueError):\n        return plain{call}\n{check}    return {result}\n")
    namespace = {"__builtins__": {}, "sin": math.sin, "cos": math.cos, "isfinite": math.isfinite, "plain": function,
                 "ArithmeticError": ArithmeticError, "ValueError": ValueError}
    exec(compile(source, "<straight-line code>", "exec"), namespace)
    return namespace["traced"]
