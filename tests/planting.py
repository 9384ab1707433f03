"""Planted errors: single-term mutations of a derivation's source, for measuring how often dyncheck's
localisation names the term a wrong equation lacks (tests/test_planted_errors.py).

A term is an operand of a + or - chain, or a whole expression that is a product or a negation (an
entry of a mass matrix, a force side written as one product).  The kinds of error planted, each in
one place of the functions that compute the accelerations:
  drop     a term of a chain is left out
  flip     a term's sign is flipped
  sin-cos  a call of sin becomes cos, or cos sin
  factor2  a term is doubled or halved
"""

import ast
import random
from dataclasses import dataclass

KINDS = ("drop", "flip", "sin-cos", "factor2")
ARITHMETIC = (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.Mod, ast.FloorDiv)


@dataclass(frozen=True)
class Mutant:
    """A derivation with one planted error."""
    source: str  # the whole module, mutated
    function: str  # where: "forces", "Book.accelerations"
    line: int
    kind: str  # one of KINDS
    term: str  # the term (or call) as written
    change: str  # what it became

    def __str__(self):
        return f"{self.function}, line {self.line}: {self.kind} {self.term!r} -> {self.change!r}"


def functions(tree, names):
    """The function definitions of `tree` named in `names`, as "function" or "Class.method"."""
    found = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            found[node.name] = node
        elif isinstance(node, ast.ClassDef):
            found.update({f"{node.name}.{item.name}": item for item in node.body if isinstance(item, ast.FunctionDef)})
    missing = [name for name in names if name not in found]
    if missing:
        raise ValueError(f"no function {', '.join(missing)} in the module; it has {', '.join(found)}")
    return [(name, found[name]) for name in names]


def parents(function):
    return {child: node for node in ast.walk(function) for child in ast.iter_child_nodes(node)}


def is_chain(node):
    return isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub))


def is_term(node, parent):
    """An operand of a + or - chain (not the chain's own left part, which holds the operands before),
    or a product or negation that is no part of a larger arithmetic expression."""
    if is_chain(parent):
        return not (node is parent.left and is_chain(node))
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub) or \
            isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)):
        return not (isinstance(parent, ast.UnaryOp) or isinstance(parent, ast.BinOp) and isinstance(parent.op, ARITHMETIC))
    return False


def trig_name(node):
    """"sin" or "cos" for a call of sin or cos (np.sin, math.cos, sin), else None."""
    if not isinstance(node, ast.Call):
        return None
    name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", None)
    return name if name in ("sin", "cos") else None


def sites(source, names):
    """Every (function, index, kind) where an error can be planted in the functions `names`; index
    counts the nodes of the function in ast.walk's order, the same in every parse of `source`."""
    out = []
    for name, function in functions(ast.parse(source), names):
        up = parents(function)
        for index, node in enumerate(ast.walk(function)):
            if node in up and isinstance(node, ast.expr) and is_term(node, up[node]):
                kinds = ["flip", "factor2"] + (["drop"] if is_chain(up[node]) else [])
                out += [(name, index, kind) for kind in kinds]
            if trig_name(node):
                out.append((name, index, "sin-cos"))
    return out


def plant(source, names, site, rng):
    """The Mutant of `source` with the error of `site` (from `sites`); rng chooses x2 or /2."""
    name, index, kind = site
    tree = ast.parse(source)
    function = dict(functions(tree, names))[name]
    up = parents(function)
    node = next(node for i, node in enumerate(ast.walk(function)) if i == index)
    parent, term = up.get(node), ast.unparse(node)
    if kind == "sin-cos":
        new = "cos" if trig_name(node) == "sin" else "sin"
        if isinstance(node.func, ast.Attribute):
            node.func.attr = new
        else:
            node.func.id = new
        changed = node
    elif kind == "drop":
        # the chain without the term: a - b without b is a, without a it is -b
        kept = parent.left if node is parent.right else parent.right
        changed = kept if node is parent.right or isinstance(parent.op, ast.Add) else ast.UnaryOp(ast.USub(), kept)
        replace(up, parent, changed)
    elif kind == "flip":
        if is_chain(parent) and node is parent.right:
            parent.op = ast.Sub() if isinstance(parent.op, ast.Add) else ast.Add()
            changed = parent
        else:
            changed = node.operand if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub) \
                else ast.UnaryOp(ast.USub(), node)
            replace(up, node, changed)
    elif kind == "factor2":
        two = ast.Constant(2)
        changed = ast.BinOp(two, ast.Mult(), node) if rng.random() < 0.5 else ast.BinOp(node, ast.Div(), two)
        replace(up, node, changed)
    else:
        raise ValueError(f"kind {kind!r}: not one of {', '.join(KINDS)}")
    return Mutant(ast.unparse(ast.fix_missing_locations(tree)), name, node.lineno, kind, term, ast.unparse(changed))


def replace(up, old, new):
    """Put `new` where `old` is in its parent."""
    parent = up[old]
    for field, value in ast.iter_fields(parent):
        if value is old:
            setattr(parent, field, new)
            return
        if isinstance(value, list) and any(item is old for item in value):
            value[[item is old for item in value].index(True)] = new
            return
    raise ValueError(f"{ast.unparse(old)!r} not found in its parent")


def mutants(source, names, per_kind, seed):
    """Up to `per_kind` Mutants of each kind, their sites chosen at random (seeded) in the functions
    `names` of `source`."""
    rng = random.Random(seed)
    every = sites(source, names)
    chosen = []
    for kind in KINDS:
        of_kind = [site for site in every if site[2] == kind]
        chosen += rng.sample(of_kind, min(per_kind, len(of_kind)))
    return [plant(source, names, site, rng) for site in chosen]
