"""Typeset the expressions the code evaluates as LaTeX, for the pages' Markdown maths ($...$, $$...$$).

`latex(expression, symbols)` turns one of our expression strings (a reference module's `PRINTED`, an
edit that dyncheck.checks.localise found, a case file's formula) into LaTeX by walking its Python syntax tree,
node by node from a whitelist as dyncheck.common.expressions does (nothing is evaluated), in the order the
expression is written: no computer algebra reorders the book's terms.  `marked(printed, right)`
typesets two versions of one expression with what differs between them in \\boxed{} (a frame, which
prints in grey).

A name is typeset by the symbol table `symbols` ({name: LaTeX}; a reference module declares its own
as `LATEX` beside `PRINTED`), else by `symbol`'s defaults: greek names (psi -> \\psi, Omega ->
\\Omega), a rate or an acceleration by its suffix (psi_rate -> \\dot{\\psi}, l_acc -> \\ddot{l}), a
trailing number or an underscore as a subscript (l0 -> l_0, a_E -> a_{E}), moments of inertia
(Ixx -> I_{xx}).  A table's entry for a function may hold `{}`, where its arguments go
("TzT": "T_z({})^T").
"""

import ast
import difflib
import re
from collections.abc import Mapping

GREEK = {"alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa", "lambda", "mu",
         "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi", "omega", "varphi", "vartheta",
         "Gamma", "Delta", "Theta", "Lambda", "Xi", "Pi", "Sigma", "Upsilon", "Phi", "Psi", "Omega"}
FUNCTIONS = {"sin": r"\sin", "cos": r"\cos", "tan": r"\tan", "arctan": r"\arctan", "exp": r"\exp",
             "log": r"\ln", "max": r"\max", "min": r"\min"}
SPECIAL = ("sqrt", "abs", "array")  # typeset by their own layout: \sqrt{}, |...|, a column or a matrix
COMPARISONS = {ast.Lt: "<", ast.LtE: r"\le", ast.Gt: ">", ast.GtE: r"\ge", ast.Eq: "=", ast.NotEq: r"\ne"}
SUFFIXES = {"_rate": r"\dot", "_acc": r"\ddot"}  # psi_rate: the rate of psi

# Binding strength, as Python's: a weaker operand of a stronger operator is bracketed.
SUM, PRODUCT, SIGN, POWER, ATOM = 1, 2, 3, 4, 5


def symbol(name, symbols=None):
    """The LaTeX of the name `name`: the table's, else the defaults of the module's docstring."""
    if symbols and name in symbols:
        return symbols[name]
    for suffix, accent in SUFFIXES.items():
        if name.endswith(suffix) and len(name) > len(suffix):
            return f"{accent}{{{symbol(name[:-len(suffix)], symbols)}}}"
    if name in GREEK:
        return "\\" + name
    if name == "lo":  # the listings' l_o, the spring's natural length
        return "l_0"
    if match := re.fullmatch(r"([A-Za-z]+?)(\d+)", name):
        return f"{symbol(match[1], symbols)}_{{{match[2]}}}"
    if match := re.fullmatch(r"([A-Za-z]\w*?)_(\w+)", name):
        sub = match[2] if len(match[2]) == 1 else rf"\mathrm{{{match[2]}}}"
        return f"{symbol(match[1], symbols)}_{{{sub}}}"
    if match := re.fullmatch(r"([A-Z])([xyz]{1,2})", name):  # Ixx, Tz
        return f"{match[1]}_{{{match[2]}}}"
    return name if len(name) == 1 else rf"\mathit{{{name}}}"


def number(value):
    """A number as written: 2.0 -> 2, 5e-05 -> 5 \\cdot 10^{-5}."""
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        value = int(value)
    text = repr(value)
    if "e" in text:
        mantissa, exponent = text.split("e")
        power = f"10^{{{int(exponent)}}}"
        return power if mantissa in ("1", "1.0") else f"{mantissa} \\cdot {power}"
    return text


def latex(expression: str, symbols: Mapping[str, str] | None = None) -> str:
    """`expression` (Python syntax) as LaTeX; ValueError naming what it cannot typeset."""
    return _Typesetter(symbols).text(_parse(expression))


def marked(printed: str, right: str, symbols: Mapping[str, str] | None = None) -> tuple[str, str]:
    """`printed` and `right` as LaTeX, each with the parts that differ from the other in \\boxed{}.

    The two syntax trees are walked together: the terms of a sum, and the factors of a product, are
    aligned as sequences, so that a term added or dropped is boxed alone and a changed factor is boxed
    where it changed; nodes of different kinds are boxed whole.
    """
    a, b = _parse(printed), _parse(right)
    boxes = set()
    _compare(a, b, boxes)
    return _Typesetter(symbols, boxes).text(a), _Typesetter(symbols, boxes).text(b)


def _parse(expression):
    try:
        return ast.parse(expression.strip(), mode="eval").body
    except SyntaxError as error:
        raise ValueError(f"cannot typeset `{expression}`: {error.msg}") from None


# -- the walk of one tree ----------------------------------------------------------------------------
def _terms(node):
    """A chain of + and - as [(sign, term)], sign +1 or -1; the brackets of a term are kept."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
        return _terms(node.left) + [(1 if isinstance(node.op, ast.Add) else -1, node.right)]
    return [(1, node)]


def _factors(node):
    """A chain of * and @ as its factors, in order (a product needs no brackets to be regrouped)."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.MatMult)):
        return _factors(node.left) + _factors(node.right)
    return [node]


def _is_sum(node):
    return isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub))


def _is_product(node):
    return isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.MatMult))


def _refuse(node, why=""):
    text = ast.unparse(node)
    text = text if len(text) <= 40 else text[:37] + "..."
    raise ValueError(f"cannot typeset `{text}`{why}: an expression has only numbers, names, + - * / @ **, .T, "
                     f"comparisons, calls of functions and array([...])")


class _Typesetter:
    def __init__(self, symbols=None, boxes=frozenset()):
        self.symbols, self.boxes = symbols or {}, boxes

    def text(self, node):
        return self.typeset(node)[0]

    def typeset(self, node):
        """(LaTeX, binding strength) of `node`, boxed if it is among `boxes`."""
        text, strength = self._plain(node)
        if id(node) in self.boxes:
            return rf"\boxed{{{text}}}", ATOM
        return text, strength

    def bracketed(self, node, weakest):
        """`node`'s LaTeX, in brackets if it binds more weakly than `weakest`."""
        text, strength = self.typeset(node)
        return rf"\left({text}\right)" if strength < weakest else text

    def _plain(self, node):
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            return number(node.value), ATOM
        if isinstance(node, ast.Name):
            return symbol(node.id, self.symbols), ATOM
        if _is_sum(node):
            return self._sum(node), SUM
        if _is_product(node):
            return self._product(node), PRODUCT
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
            numerator, denominator = self.text(node.left), self.text(node.right)
            if isinstance(node.left, ast.UnaryOp) and isinstance(node.left.op, ast.USub) \
                    and id(node.left) not in self.boxes:  # -k/m: the sign before the fraction
                return rf"-\frac{{{self.bracketed(node.left.operand, PRODUCT)}}}{{{denominator}}}", SIGN
            return rf"\frac{{{numerator}}}{{{denominator}}}", ATOM
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
            return self._power(node), POWER
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            sign = "-" if isinstance(node.op, ast.USub) else "+"
            return sign + self.bracketed(node.operand, PRODUCT), SIGN
        if isinstance(node, ast.Compare) and all(type(op) in COMPARISONS for op in node.ops):  # a <= x <= b too
            return " ".join([self.text(node.left)] + [f"{COMPARISONS[type(op)]} {self.text(value)}"
                                                      for op, value in zip(node.ops, node.comparators)]), 0
        if isinstance(node, ast.Attribute) and node.attr == "T":  # a transpose
            return f"{{{self.bracketed(node.value, ATOM)}}}^T", POWER
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and not node.keywords:
            return self._call(node), ATOM
        _refuse(node)

    def _sum(self, node):
        out = []
        for i, (sign, term) in enumerate(_terms(node)):
            text = self.text(term) if not _is_sum(term) else rf"\left({self.text(term)}\right)"
            if isinstance(term, ast.UnaryOp) and i and id(term) not in self.boxes:
                text = rf"\left({text}\right)"  # a + (-b)
            if ("signed", id(term)) in self.boxes:  # the term and its sign differ from the other's
                out.append(rf"\boxed{{{'-' if sign < 0 else '+' if i else ''} {text}}}")
                continue
            out.append(text if not i else f"{'+' if sign > 0 else '-'} {text}")
        return " ".join(out)

    def _product(self, node):
        factors = _factors(node)
        out = []
        for i, factor in enumerate(factors):
            text, strength = self.typeset(factor)
            if strength < PRODUCT or (i and strength == SIGN):
                text = rf"\left({text}\right)"  # a (b + c), a (-b); a leading sign stays: -m (...)
            if i and (text[0].isdigit() or (out and out[-1][-1:].isdigit() and text[:1].isdigit())):
                out.append(r"\cdot")
            out.append(text)
        return " ".join(out)

    def _power(self, node):
        exponent = self.text(node.right)
        exponent = exponent if len(exponent) == 1 else f"{{{exponent}}}"
        base = node.left
        if isinstance(base, ast.Call) and isinstance(base.func, ast.Name) and base.func.id in FUNCTIONS \
                and base.func.id not in self.symbols and len(base.args) == 1 and id(base) not in self.boxes:
            return f"{FUNCTIONS[base.func.id]}^{exponent} {self._argument(base.args[0])}"  # sin^2 psi
        text, strength = self.typeset(base)
        if strength < ATOM or isinstance(base, ast.Call) and getattr(base.func, "id", None) in FUNCTIONS:
            text = rf"\left({text}\right)"
        elif "^" in text:
            text = f"{{{text}}}"
        return f"{text}^{exponent}"

    def _argument(self, node):
        """A function's single argument: a name or a number bare (\\sin\\psi), anything else bracketed."""
        text = self.text(node)
        bare = isinstance(node, (ast.Name, ast.Constant)) or id(node) in self.boxes
        return text if bare else rf"\left({text}\right)"

    def _call(self, node):
        name, args = node.func.id, node.args
        if name in self.symbols and "{}" in self.symbols[name]:
            return self.symbols[name].replace("{}", ", ".join(self.text(a) for a in args))
        if name == "array" and len(args) == 1 and isinstance(args[0], (ast.List, ast.Tuple)):
            return self._matrix(args[0])
        if name == "sqrt" and len(args) == 1:
            return rf"\sqrt{{{self.text(args[0])}}}"
        if name == "abs" and len(args) == 1:
            return rf"\left|{self.text(args[0])}\right|"
        if name in FUNCTIONS and name not in self.symbols:
            if len(args) == 1:
                return f"{FUNCTIONS[name]} {self._argument(args[0])}"
            return rf"{FUNCTIONS[name]}\left({', '.join(self.text(a) for a in args)}\right)"
        if name in SPECIAL or not args:
            _refuse(node, f" ({name} takes one argument here)" if name in SPECIAL else "")
        return rf"{symbol(name, self.symbols)}\left({', '.join(self.text(a) for a in args)}\right)"

    def _matrix(self, rows):
        """array([a, b, c]) as a column, array([[a, b], [c, d]]) as a matrix."""
        lines = []
        for row in rows.elts:
            cells = row.elts if isinstance(row, (ast.List, ast.Tuple)) else [row]
            lines.append(" & ".join(self.text(cell) for cell in cells))
        return r"\begin{bmatrix} " + r" \\ ".join(lines) + r" \end{bmatrix}"


# -- the walk of two trees ---------------------------------------------------------------------------
def _key(node):
    return ast.dump(node, annotate_fields=False)


def _shape(node):
    """What kind of node: a sum, a product, a call of which function, ...; pairs of one shape are compared
    inside, pairs of different shapes boxed whole."""
    if _is_sum(node):
        return "sum"
    if _is_product(node):
        return "product"
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
        return f"call {node.func.id} {len(node.args)}"
    if isinstance(node, ast.BinOp):
        return type(node.op).__name__
    if isinstance(node, ast.UnaryOp):
        return type(node.op).__name__
    return type(node).__name__


def _align(a, b, key):
    """Pairs (x, y) of two sequences in order, x or y None where one has an item the other lacks:
    equal items first (difflib), then, inside each differing stretch, items of the same shape."""
    pairs = []
    matcher = difflib.SequenceMatcher(None, [key(x) for x in a], [key(y) for y in b], autojunk=False)
    for tag, i1, i2, j1, j2 in matcher.get_opcodes():
        if tag == "equal":
            pairs += list(zip(a[i1:i2], b[j1:j2]))
            continue
        left, right = a[i1:i2], b[j1:j2]
        shapes = difflib.SequenceMatcher(None, [_shape(_unsigned(x)) for x in left],
                                         [_shape(_unsigned(y)) for y in right], autojunk=False)
        for tag2, k1, k2, l1, l2 in shapes.get_opcodes():
            if tag2 == "equal" or (tag2 == "replace" and k2 - k1 == l2 - l1):
                pairs += list(zip(left[k1:k2], right[l1:l2]))
            else:
                pairs += [(x, None) for x in left[k1:k2]] + [(None, y) for y in right[l1:l2]]
    return pairs


def _unsigned(item):
    return item[1] if isinstance(item, tuple) else item


def _compare(a, b, boxes):
    """Add to `boxes` the ids of the nodes of `a` and `b` that differ, as deep down as they still match."""
    if _key(a) == _key(b):
        return
    if _shape(a) != _shape(b):
        boxes.update((id(a), id(b)))
        return
    if _is_sum(a):
        for x, y in _align(_terms(a), _terms(b), lambda item: (item[0], _key(item[1]))):
            if x is None or y is None:
                boxes.add(id((x or y)[1]))
            elif x[0] != y[0]:  # the same term with the other sign: the sign and the term
                boxes.update((("signed", id(x[1])), ("signed", id(y[1]))))
            else:
                _compare(x[1], y[1], boxes)
        return
    if _is_product(a):
        for x, y in _align(_factors(a), _factors(b), _key):
            if x is None or y is None:
                boxes.add(id(x or y))
            else:
                _compare(x, y, boxes)
        return
    children_a, children_b = _children(a), _children(b)
    if len(children_a) != len(children_b) or not children_a:
        boxes.update((id(a), id(b)))
        return
    for x, y in zip(children_a, children_b):
        _compare(x, y, boxes)


def _children(node):
    """The operands of a node whose kind both trees share (a call's arguments, an array's cells)."""
    if isinstance(node, ast.BinOp):
        return [node.left, node.right]
    if isinstance(node, ast.UnaryOp):
        return [node.operand]
    if isinstance(node, ast.Call):
        if len(node.args) == 1 and isinstance(node.args[0], (ast.List, ast.Tuple)):  # array([...])
            return _cells(node.args[0])
        return list(node.args)
    if isinstance(node, ast.Attribute):
        return [node.value]
    if isinstance(node, ast.Compare):
        return [node.left, *node.comparators]
    return []


def _cells(rows):
    return [cell for row in rows.elts for cell in (row.elts if isinstance(row, (ast.List, ast.Tuple)) else [row])]
