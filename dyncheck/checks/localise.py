"""Localise an error of the book: the smallest edit of its printed expression that makes it agree.

A `Book` that prints a quantity as a formula declares it in `PRINTED` ({quantity: Python expression})
and evaluates it through `symbols(t, q, v)`, so the string searched here is the code that runs.
The search edits the expression's syntax tree: each additive term negated, doubled, halved or
dropped; each sin swapped for cos and back; each term of a bracketed sum moved out of the product
the bracket is in (a bracket closed too late); each matrix product's operands swapped and each
transpose toggled; each symbol set to zero everywhere.  Single edits first, then pairs; an edit
explains the finding when the edited expression agrees with the engines to the pointwise tolerance.
"""

import ast

import numpy as np


def _additive_terms(node):
    """The operands of a chain of + and - (each with its sign), or None."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
        left = _additive_terms(node.left) or [(node.left, 1)]
        return left + [(node.right, 1 if isinstance(node.op, ast.Add) else -1)]
    return None


def _sites(tree):
    """Every (node, kind) an edit can act on."""
    sites = []
    for node in ast.walk(tree):
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
            sites += [(node.right, "term")]
            if not (isinstance(node.left, ast.BinOp) and isinstance(node.left.op, (ast.Add, ast.Sub))):
                sites += [(node.left, "term")]
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("sin", "cos"):
            sites.append((node, "trig"))
        elif isinstance(node, ast.BinOp) and isinstance(node.op, ast.MatMult):
            sites += [(node, "product"), (node.left, "transpose"), (node.right, "transpose")]
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult) and _additive_terms(node.left):
            sites += [(node, f"bracket {i}") for i in range(len(_additive_terms(node.left)))]
    return sites


class _Edit(ast.NodeTransformer):
    def __init__(self, target, kind, how):
        self.target, self.kind, self.how = target, kind, how

    def visit(self, node):
        if node is not self.target:
            return self.generic_visit(node)
        if self.kind == "term":
            factor = {"negate": -1.0, "double": 2.0, "halve": 0.5, "drop": 0.0}[self.how]
            return ast.BinOp(ast.Constant(factor), ast.Mult(), node)
        if self.kind == "trig":
            swapped = ast.Call(ast.Name({"sin": "cos", "cos": "sin"}[node.func.id], ast.Load()), node.args, [])
            return swapped
        if self.kind == "product":
            return ast.BinOp(node.right, ast.MatMult(), node.left)
        if self.kind.startswith("bracket"):  # (A + B) * C -> A + B * C: a bracket closed too late
            terms = _additive_terms(node.left)
            i = int(self.kind.split()[1])
            (moved, sign), rest = terms[i], terms[:i] + terms[i + 1:]
            inner = rest[0][0] if rest[0][1] > 0 else ast.UnaryOp(ast.USub(), rest[0][0])
            for term, s in rest[1:]:
                inner = ast.BinOp(inner, ast.Add() if s > 0 else ast.Sub(), term)
            product = ast.BinOp(inner, ast.Mult(), node.right)
            return ast.BinOp(moved if sign > 0 else ast.UnaryOp(ast.USub(), moved), ast.Add(), product)
        if isinstance(node, ast.Attribute) and node.attr == "T":  # transpose: toggle
            return node.value
        return ast.Attribute(node, "T", ast.Load())


def _zero_symbol(tree, name):
    class Zero(ast.NodeTransformer):
        def visit_Name(self, node):
            return ast.Constant(0.0) if node.id == name else node
    return Zero().visit(tree)


def edits(expression):
    """(description, edited expression) for every single edit of `expression`."""
    out = []
    tree = ast.parse(expression, mode="eval")
    parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
    terms = {node for node, kind in _sites(tree) if kind == "term"}
    for index, (node, kind) in enumerate(_sites(tree)):
        text = ast.unparse(node)
        if kind == "trig":  # name the term the sine or cosine sits in
            term = node
            while term in parents and term not in terms:
                term = parents[term]
            text = f"{text}` in `{ast.unparse(term)}"
        hows = {"term": ("negate", "double", "halve", "drop"), "trig": ("swap",),
                "product": ("swap",), "transpose": ("toggle",)}.get(kind, ("move",))
        for how in hows:
            fresh = ast.parse(expression, mode="eval")
            target = _sites(fresh)[index][0]
            edited = ast.fix_missing_locations(_Edit(target, kind, how).visit(fresh))
            label = {"negate": f"sign of `{text}`", "double": f"`{text}` x 2", "halve": f"`{text}` / 2",
                     "drop": f"drop `{text}`", "swap": f"swap sin/cos in `{text}`" if kind == "trig"
                     else f"swap the factors of `{text}`", "toggle": f"transpose `{text}`",
                     "move": f"close the bracket before `{ast.unparse(node.right)}` so that it leaves out"
                             f" `{ast.unparse((_additive_terms(node.left) or [(node, 1)])[int(kind.split()[-1])][0])}`"
                             if kind.startswith("bracket") else ""}[how]
            out.append((label, ast.unparse(edited)))
    called = {n.func.id for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
    names = sorted({n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} - called)
    for name in names:
        out.append((f"`{name}` = 0 everywhere", ast.unparse(_zero_symbol(ast.parse(expression, mode="eval"), name))))
    return out


def values_at(expression, namespaces):
    """A printed expression (or an edit of it: the book module's own code) at each of `namespaces`, as
    one array; no builtins reach it."""
    code = compile(expression, "<printed>", "eval")
    with np.errstate(all="ignore"):
        return np.array([np.asarray(eval(code, {"__builtins__": {}}, names), dtype=float) for names in namespaces])


def _error(expression, namespaces, target, tolerance):
    """Largest deviation from the target relative to the target's largest magnitude."""
    try:
        values = values_at(expression, namespaces)
    except (ArithmeticError, TypeError, ValueError):
        return np.inf
    scale = np.max(np.abs(target)) or 1.0
    error = float(np.max(np.abs(values - target)) / scale)
    return error if np.isfinite(error) else np.inf


def localise(expression, namespaces, target, tolerance):
    """The single edits, or failing those the pairs, that make `expression` agree with `target`.

    Returns (edits that work, each as (description, error, edited expression)), how many were tried,
    and the error of the printed expression itself.
    """
    printed = _error(expression, namespaces, target, tolerance)
    singles = edits(expression)
    found = [(label, err, text) for label, text in singles
             if (err := _error(text, namespaces, target, tolerance)) <= tolerance]
    tried = len(singles)
    if not found:
        seen = set()
        for first, text in singles:
            for second, text2 in edits(text):
                tried += 1
                if frozenset((first, second)) in seen:
                    continue
                seen.add(frozenset((first, second)))
                if (err := _error(text2, namespaces, target, tolerance)) <= tolerance:
                    found.append((f"{first}, and {second}", err, text2))
    return found, tried, printed
