"""The schema of case.toml, and what makes a case's numbers physical.

Three checks, in the order a case is loaded (dyncheck.case.folder.Case):
`validate(spec, file)` the parsed file's keys, types, units and cross-references;
`check_params(...)` the parameter values after overrides (positive masses, each parameter's bounds, the
case's constraints);
`check_values(...)` every number that may be an expression, evaluated at those parameters, and each
parameter's printed form (as the book's text shows it) against its value.
Each raises one ValueError naming the file, the field (a dotted path such as `integration.rtol`,
or `override m` for an override) and the value.
docs/case-file.md, the reference of the case file, is `markdown()`.
"""

import ast
import functools
import math
import operator
import re
from pathlib import Path

import numpy as np
import pint

from dyncheck.common import ceilings, expressions, words
from dyncheck.common.ceilings import LEAST_RTOL, MAX_STEPS
from dyncheck.results import measured
from dyncheck.common.expressions import evaluate
from dyncheck.common.messages import suggest

# -- the schema -----------------------------------------------------------------------------------
# A type is a string: "str", "int", "bool", "number" (a TOML integer or float), "expr" (a number,
# or an expression of the parameters and pi in quotes), "force" (a number, or an expression of t, the
# coordinates, their rates and the parameters: dyncheck.case.folder.AppliedForce), optionally with a condition: "int > 0",
# "number >= 0", "expr != 0"; or a tuple: ("list", item), ("pair", item) a list of two,
# ("one of", *values), ("map", item) a table whose keys are names (of parameters, joints, ...),
# ("table", {key: type}) a table of these keys, "key?" optional, or FREE.  What each key means is in
# MEANINGS below, its unit (where it has one) in KEY_UNITS.

FREE = ("free",)  # a table whose contents the module that reads it checks
RANGE = ("pair", "number")
FRAME = ("one of", "body", "world")
TOLERANCE = ("table", {"safety": "number > 0", "why": "str"})

SCHEMA = ("table", {
    "name": "str",
    "section?": "str",
    "title": "str",
    "summary": "str",
    "derivation": "str",
    "coords": ("list", "str"),
    "reactions": ("list", "str"),
    "coord_units": ("list", ("one of", "rad", "m")),
    "params": ("map", ("table", {"value": "number", "unit": "str", "about": "str", "printed?": "str",
                                 "minimum?": "number", "exclusive_minimum?": "number", "maximum?": "number",
                                 "exclusive_maximum?": "number"})),
    "constraints?": ("list", ("table", {"expression": "str", "strict?": "bool", "why": "str"})),
    "initial": ("table", {"q": ("list", "expr"), "v": ("list", "expr"), "t_end": "expr > 0"}),
    # physical limits past which a coordinate grows without bound (dyncheck/checks.py, runaway)
    "runaway?": ("list", ("table", {"when": "str", "coordinate": "str", "escape": "expr > 0", "why": "str"})),
    "sample": ("table", {
        "count": "int > 0", "seed": "int >= 0", "t": ("pair", "expr"),
        "q": ("list", ("pair", "expr")), "v": ("list", ("pair", "expr")),
        # random parameter sets of the "random parameters" check (dyncheck/checks.py)
        "params?": ("table", {"sets": "int > 0", "states": "int > 0", "seed": "int >= 0",
                              "ranges": ("map", ("pair", "expr"))}),
    }),
    "work_precision?": FREE,  # validated by dyncheck/work_precision.py
    # how long the case's own code may run, and in how much memory (dyncheck/isolation.py)
    "budget?": ("table", {"call?": "number > 0", "case?": "number > 0", "memory?": "number > 0"}),
    "integration": ("table", {"output_step": "expr > 0", "rtol": "expr > 0", "tight_rtol": "expr > 0",
                              "mujoco_step": "expr > 0"}),
    "tolerance": ("table", {"pointwise": ("table", {"value": "number > 0", "force_scale": "expr >= 0",
                                                    "moment_scale?": "expr >= 0", "why": "str"}),
                            "trajectory": TOLERANCE, "energy": TOLERANCE}),
    "report": ("table", {
        "modelling": "str",
        "stop?": "str",
        "values?": ("map", ("table", {"expression": "str", "unit": "str", "about": "str"})),
        "figures?": ("map", ("table", {"x": "str", "y": "str", "title": "str", "xlabel": "str", "ylabel": "str",
                                       "caption?": "str", "xlim?": RANGE, "ylim?": RANGE, "equal?": "bool"})),
    }),
    # what the case page's animation shows beside the motion (dyncheck/animation.py)
    "animation?": ("table", {"program?": ("one of", "beside", "ghost"),
                             "arrow?": ("table", {"force": ("list", "str"), "at": ("list", "str"), "about": "str"}),
                             "graph?": ("table", {"y": "str", "title": "str", "ylabel": "str", "ylim?": RANGE}),
                             "caption?": "str"}),
    "scene": ("table", {
        "coords": ("map", "str"),  # book coordinate -> hinge or slide joint
        "euler?": ("table", {"joint": "str", "coords": ("list", "str")}),  # ball joint in Euler angles
        "driven": ("map", ("table", {"angle?": "expr", "rate?": "expr", "acc?": "expr"})),
        "dependent?": ("list", "str"),  # joints that closed loops move (engines.loops), no coordinate's
        "applied?": ("map", ("list", "force")),
        "paths?": ("list", "str"),
        "reactions": ("map", ("table", {"body": "str", "sensor": "str", "axis": ("one of", 0, 1, 2),
                                        "frame": FRAME, "quantity?": ("one of", "force", "moment")})),
        "points?": ("map", ("table", {"body": "str", "frame": FRAME, "kind?": (
            "one of", "acceleration", "com acceleration", "angular velocity", "angular acceleration")})),
        "urdf_root_joint?": ("table", {"name": "str", "type": ("one of", "spherical")}),
        "bindings?": ("map", ("list", ("table", {
            "element": ("one of", "body", "joint", "option"), "name": "str", "attribute?": "str",
            "index?": "int", "scale?": "number", "depends?": ("list", "str")}))),
    }),
    "program?": ("table", {
        "figures?": ("map", ("table", {"expression": "str", "range": RANGE, "where": "str"})),
        "plots?": ("list", ("table", {"x": "str", "y": "str", "title": "str", "xlabel?": "str", "ylabel?": "str",
                                     "xlim?": RANGE, "ylim?": RANGE})),
        "outputs?": ("map", "str"),
    }),
    # right: {printed expression's key: the right expression}, checked against the reference (checks.right_sides)
    "findings?": ("list", ("table", {"id": "str", "title": "str", "where": "str", "effect?": "str",
                                     "sources": ("list", "str"), "quantities": ("list", "str"),
                                     "explanation": "str", "measured?": "str", "right?": ("map", "str")})),
    # numbers measured in the results, for the pages' prose (dyncheck/measured.py checks each kind's keys)
    "measured?": ("map", ("table", {"kind": ("one of", *measured.KINDS), "of?": "str",
                                    "run?": ("one of", *measured.RUNS), "against?": ("one of", *measured.RUNS),
                                    "mode?": "int > 0", "source?": ("one of", "reference", "mujoco", "pinocchio"),
                                    "check?": "str", "quantity?": "str", "sources?": "str"})),
    # data_checks divides by the formula's value
    "data?": ("list", ("table", {"name": "str", "printed": "expr", "formula": "expr != 0", "where": "str",
                                 "tolerance": "number >= 0", "relation?": ("one of", "equal", "at most")})),
    "stability?": FREE,  # validated by dyncheck/stability.py
    # cross-references validated by dyncheck/vibration.py
    "vibration?": ("table", {"why": "str", "overrides?": ("map", "expr"), "q": ("list", "expr"),
                             "v": ("list", "expr"), "solve": ("list", "str"), "amplitude": "number > 0",
                             "periods": "int > 0",
                             "campbell?": ("table", {"parameter": "str", "scale?": "str", "values": ("list", "expr"),
                                                     "why": "str"}),
                             "boundary?": ("list", ("table", {"parameter": "str", "scale?": "str",
                                                              "bracket": ("pair", "expr"),
                                                              "expected": "str", "why": "str"})),
                             "floquet?": ("table", {"why": "str", "period": "str", "q": ("list", "expr"),
                                                    "v": ("list", "expr"), "periods": "int > 0",
                                                    "amplitude": "number > 0"})}),
    # the student's page (dyncheck/student_page.py, which checks the expressions against the derivation)
    "course?": ("table", {"intro": "str", "steps": ("list", ("table", {
        "title": "str", "text": "str",
        "show?": ("list", ("table", {"expression?": "str", "label?": "str", "quantities?": ("list", "str"),
                                     "source?": ("one of", "book", "program", "reference", "mujoco", "pinocchio"),
                                     "symbols?": ("map", "str"), "checked?": "str"})),
        "figures?": ("list", ("table", {"figure": "str", "caption": "str"})),
        "vibration?": "bool"}))}),
})

SCALARS = {"str": ((str,), "a string"), "int": ((int,), "an integer"), "bool": ((bool,), "true or false"),
           "number": ((int, float), "a number"), "expr": ((int, float, str), "a number or an expression in quotes"),
           "force": ((int, float, str), "a number or an expression of t, the coordinates, their rates and the "
                                        "parameters, in quotes")}
CONDITIONS = {"> 0": (lambda x: x > 0, "must be > 0"), ">= 0": (lambda x: x >= 0, "must be >= 0"),
              "!= 0": (lambda x: x != 0, "must not be 0")}

# What a binding can set in the scene files (the engines' `_write` and `read`): element and
# attribute -> the number of components `index` may pick.  An option binding is gravity.
BINDABLE = {("body", "mass"): 1, ("body", "pos"): 3, ("body", "ipos"): 3, ("body", "inertia_about_origin"): 3,
            ("joint", "stiffness"): 1, ("joint", "damping"): 1, ("joint", "springref"): 1, ("option", None): 3}

# -- parameters ---------------------------------------------------------------------------------
# A parameter's unit (params.<name>.unit) is any SI unit that pint reads ("N s/m", "kg m^2", "rad/s"),
# coherent (no prefix, no factor: every value of a case is in SI), or "-" for a pure number.
UNIT_REGISTRY = pint.UnitRegistry()
DIMENSIONLESS = "-"
UNIT_TEXT = re.compile(r"(?:1\s*/\s*)?[A-Za-z_ ]+(?:(?:\^|\*\*)-?[1-9])?(?:\s*[*/ ]\s*[A-Za-z_]+(?:(?:\^|\*\*)-?[1-9])?)*")
# Quantities whose every value must be positive, in every case, by their dimension.  Whatever else a
# parameter must satisfy depends on the case (a length may be a body's size, > 0, or a position, of any
# sign): its bounds in [params] and the case's [[constraints]].
POSITIVE_UNITS = {"kg": "a mass", "N/m": "a stiffness", "kg m^2": "a moment of inertia"}
POSITIVE_DIMENSIONS = {UNIT_REGISTRY.Quantity(1.0, unit).dimensionality: what for unit, what in POSITIVE_UNITS.items()}


@functools.cache  # pint parses a unit in ~0.1 ms, and every parameter set drawn checks every parameter's unit
def si_dimension(unit):
    """The dimension of `unit`, a coherent SI unit or "-"; ValueError saying why it is not one."""
    if unit == DIMENSIONLESS:
        return UNIT_REGISTRY.Quantity(1.0).dimensionality
    if not unit.strip():
        raise ValueError(f"is empty; write '{DIMENSIONLESS}' for a pure number")
    if not UNIT_TEXT.fullmatch(unit):  # before pint's parser, which evaluates what it reads
        raise ValueError(f"is not a unit: write SI units with letters, spaces, / and ^ or ** and small integer "
                         f"powers, as in 'N s/m' or 'kg m^2', or '{DIMENSIONLESS}' for a pure number")
    try:
        base = UNIT_REGISTRY.Quantity(1.0, unit).to_base_units()
    except Exception as error:  # pint's parser fails in many ways (its errors, tokenize's, Python's)
        raise ValueError(f"is not a unit ({type(error).__name__}: {error}); write SI units as in 'N s/m' or "
                         f"'kg m^2', or '{DIMENSIONLESS}' for a pure number") from None
    if not math.isclose(base.magnitude, 1.0, rel_tol=1e-12):
        raise ValueError(f"is not a coherent SI unit: 1 {unit} = {base.magnitude:g} {base.units:~}; every value of a "
                         f"case is in SI, so give it in {base.units:~}")
    return base.dimensionality
# The bound keys of params.<name> (JSON Schema's words) and the relation each demands of the value.
BOUNDS = {"minimum": ">=", "exclusive_minimum": ">", "maximum": "<=", "exclusive_maximum": "<"}
RELATIONS = {">=": operator.ge, ">": operator.gt, "<=": operator.le, "<": operator.lt}


def without_zeros(value):
    """A number as the book's text extraction, which lost every digit 0, shows it: 0.0558 -> ".558", 2000 -> "2"."""
    return np.format_float_positional(float(value), trim="-").replace("0", "")


RESERVED_NAMES = ("index", "errata")  # the report's own pages: <name>.md of a case would replace them


def validate(spec, file, folder=None):
    """The parsed case file `spec` against the schema; ValueError names `file`, the field and the value.
    `folder`: the case's folder, to check too that it is named after the case and holds its derivation (None for a
    case rebuilt from saved results, whose folder may have moved)."""
    _walk(spec, SCHEMA, "", file)
    _cross_references(spec, file)
    if folder is not None:
        if spec["name"] != Path(folder).name:  # the command line finds a case by its folder, pages by its name
            raise _error(file, "name", spec["name"], f"is not the name of the case's folder, '{Path(folder).name}'")
        derivation_file(spec["derivation"], folder, file)
        module = spec.get("stability", {}).get("module")
        if isinstance(module, str):  # its own studies, loaded by dyncheck.studies.stability once the models are built
            path = own_file(folder, module, "stability.module", file)
            if not module.endswith(".py") or not path.is_file():  # refused by every command, `list` as `run`
                raise _error(file, "stability.module", module, f"is not a Python file of the case's folder ({path})")


def check_params(spec, params, overrides, file):
    """The parameter values (defaults and `overrides` applied): physical, or ValueError."""
    field = lambda p: f"override {p}" if p in overrides else f"params.{p}.value"
    for p, x in params.items():
        for relation, bound, reason in demands(spec["params"][p], p):
            if not RELATIONS[relation](x, bound):
                raise _error(file, field(p), x, f"must be {relation} {bound:g} ({reason})")
    _check_constraints(spec.get("constraints", []), params, overrides, file)


def _check_constraints(constraints, params, overrides, file):
    """Each constraint's expression >= 0 (> 0 if strict) at `params`, or ValueError naming it."""
    names = expressions.of_parameters(params)  # as dyncheck.case.folder.Case.value evaluates the file's numbers
    for i, constraint in enumerate(constraints):
        field, expression = f"constraints[{i}]", constraint["expression"]
        try:
            x = evaluate(expression, names)
        except ValueError as error:
            raise _error(file, f"{field}.expression", expression, f"cannot be evaluated: {error}") from None
        if isinstance(x, (bool, np.bool_)):  # a comparison would pass as 0 or 1, whatever it says
            raise _error(file, f"{field}.expression", expression, "is a comparison; a constraint is an expression "
                         "that must be >= 0 (> 0 with strict = true): write a >= b as a - b")
        strict = constraint.get("strict", False)
        if not (x > 0 if strict else x >= 0):  # also refuses a NaN
            involved = [p for p in dict.fromkeys(re.findall(r"[A-Za-z_]\w*", expression)) if p in params]
            values = ", ".join(f"{p} = {params[p]!r}" + (" (override)" if p in overrides else "") for p in involved)
            raise _error(file, field, expression, f"is {x:.4g} at {values or 'any parameters'}, not "
                         f"{'>' if strict else '>='} 0: {' '.join(constraint['why'].split())}"
                         + ("; set the others with the overrides (`dyncheck list` shows each case's constraints)"
                            if any(p in overrides for p in involved) else ""))


def check_values(spec, file, value):
    """Every number that may be an expression, evaluated by `value(x, field)` at the case's parameters, and
    each parameter's printed form against its value (after check_params: a value that is not physical is
    the first thing to say)."""
    for p, item in spec["params"].items():
        if "printed" in item and item["printed"] != without_zeros(item["value"]):
            raise _error(file, f"params.{p}.printed", item["printed"], f"is not params.{p}.value = {item['value']!r} "
                         f"as the book's text shows it, every digit 0 lost ('{without_zeros(item['value'])}')")
    values = {}
    for field, x, condition in _expressions(spec, SCHEMA, ""):
        values[field] = v = value(x, field)
        if not math.isfinite(v):
            raise _error(file, field, x, f"is {v}, not a finite number")
        if condition and not CONDITIONS[condition][0](v):
            raise _error(file, field, x, CONDITIONS[condition][1] + (f" (it is {v:g})" if isinstance(x, str) else ""))
    _check_integration(spec, values, file)
    _check_sizes(spec, values, file)
    for i, runaway in enumerate(spec.get("runaway", [])):  # true or false, it must evaluate (its why: Case.prose)
        value(runaway["when"], f"runaway[{i}].when")
    sample = spec["sample"]
    ranges = sample.get("params", {}).get("ranges", {})
    intervals = {"sample.t": sample["t"], **{f"sample.q[{i}]": x for i, x in enumerate(sample["q"])},
                 **{f"sample.v[{i}]": x for i, x in enumerate(sample["v"])},
                 **{f"sample.params.ranges.{p}": x for p, x in ranges.items()}}
    for field, bounds in intervals.items():
        lo, hi = values[f"{field}[0]"], values[f"{field}[1]"]
        if lo > hi:
            raise _error(file, field, bounds, f"is not an interval lo <= hi ({lo:g} > {hi:g})")
    # The random parameter sets must be physical too: an interval is within bounds when both its ends are.
    for p, bounds in ranges.items():
        for relation, bound, reason in demands(spec["params"][p], p):
            if not all(RELATIONS[relation](values[f"sample.params.ranges.{p}[{i}]"], bound) for i in (0, 1)):
                raise _error(file, f"sample.params.ranges.{p}", bounds,
                             f"leaves the physical values: {p} must be {relation} {bound:g} ({reason})")


def _check_integration(spec, values, file):
    """The runs' settings, each one that the integrators can honour and that makes its rows mean something."""
    setting = spec["integration"]
    shown = lambda key: (f"integration.{key} = {setting[key]!r}"
                         + (f" = {values['integration.' + key]:g}" if isinstance(setting[key], str) else ""))
    whole = lambda ratio: round(ratio) >= 1 and abs(ratio - round(ratio)) <= 1e-9 * ratio  # as simulate's grid
    if not whole(values["integration.output_step"] / values["integration.mujoco_step"]):
        raise _error(file, "integration.output_step", setting["output_step"],
                     f"is not a multiple of {shown('mujoco_step')}")
    if not whole(values["initial.t_end"] / values["integration.output_step"]):  # every run ends on an output
        raise _error(file, "initial.t_end", spec["initial"]["t_end"],
                     f"is not a whole number of output steps ({shown('output_step')})")
    for key in ("rtol", "tight_rtol"):
        if values[f"integration.{key}"] < LEAST_RTOL:
            raise _error(file, f"integration.{key}", setting[key],
                         f"is below {LEAST_RTOL:.3g}, 100 machine epsilons: scipy's integrators raise a smaller rtol "
                         "to that, so the run would not be the one its rows say (dyncheck.common.ceilings.LEAST_RTOL)")
    if values["integration.rtol"] > ceilings.RUN:
        raise _error(file, "integration.rtol", setting["rtol"],
                     f"is above {ceilings.RUN:g}: a run's error, about rtol of each quantity, would be beyond the "
                     "ceiling where an error estimate means anything, and every row judged by one inconclusive")
    if values["integration.tight_rtol"] >= values["integration.rtol"]:
        raise _error(file, "integration.tight_rtol", setting["tight_rtol"],
                     f"is not below integration.rtol = {setting['rtol']!r}: the tight twin must be tighter")


# How much work one case file may ask for, so that a run ends in minutes (dyncheck.run.simulate bounds
# each integration as it runs; these bound what is asked before anything runs).
MAX_STATES = 10_000  # random states of the pointwise check, and sets x states of the random parameters:
#                      four sources at ~0.25 ms each per state, 10 s
MAX_SETS = 1_000  # random parameter sets: each builds both engines' models, ~20 ms
MAX_OUTPUTS = 100_000  # rows of one run's output: a reactions and an energy evaluation each, ~0.2 ms, 20 s


def _check_sizes(spec, values, file):
    """The number of random states and sets, and of a run's outputs and MuJoCo's steps, within the bounds above."""
    sample, t_end = spec["sample"], values["initial.t_end"]
    sets = sample.get("params", {"sets": 0, "states": 0})
    limits = [("sample.count", sample["count"], sample["count"], MAX_STATES, "random states"),
              ("sample.params.sets", sets["sets"], sets["sets"], MAX_SETS, "random parameter sets"),
              ("sample.params.states", sets["states"], sets["sets"] * sets["states"], MAX_STATES,
               "random states over all parameter sets"),
              ("initial.t_end", spec["initial"]["t_end"], t_end / values["integration.output_step"], MAX_OUTPUTS,
               "output rows per run (t_end / integration.output_step)"),
              ("initial.t_end", spec["initial"]["t_end"], t_end / values["integration.mujoco_step"], MAX_STEPS,
               "MuJoCo steps per run (t_end / integration.mujoco_step)")]
    for field, x, amount, limit, what in limits:
        if amount > limit:
            raise _error(file, field, x, f"asks for {amount:.3g} {what}, more than the {limit:.0e} a run allows")


# -- the walk -----------------------------------------------------------------------------------

def _walk(x, kind, field, file):
    """x against `kind`; `field` is its dotted path."""
    if isinstance(kind, str):
        return _scalar(x, kind, field, file)
    tag, *rest = kind
    if tag == "one of":
        if not any(type(x) is type(option) and x == option for option in rest):  # True is not 1
            raise _error(file, field, x, "is not one of " + ", ".join(map(repr, rest)))
        return
    sequence = tag in ("list", "pair")
    if not isinstance(x, list if sequence else dict):
        raise _error(file, field, x, f"is {_type_name(x)}, not {_describe(kind)}")
    if tag == "pair" and len(x) != 2:
        raise _error(file, field, x, "is not a pair [lo, hi]")
    if sequence:
        for i, item in enumerate(x):
            _walk(item, rest[0], f"{field}[{i}]", file)
    elif tag == "map":
        for key, item in x.items():
            _walk(item, rest[0], _join(field, key), file)
    elif tag == "table":
        keys = {key.rstrip("?"): key for key in rest[0]}
        for key, item in x.items():
            if key not in keys:  # a typo must not pass for an absent optional key
                raise _error(file, _join(field, key), item, "is not a known key" + _hint(key, keys))
        for key, declared in keys.items():
            if key in x:
                _walk(x[key], rest[0][declared], _join(field, key), file)
            elif not declared.endswith("?"):
                raise ValueError(f"{file}: {_join(field, key)} is missing ({_describe(rest[0][declared])})")


def _scalar(x, kind, field, file):
    base, _, condition = kind.partition(" ")
    types, expected = SCALARS[base]
    if not isinstance(x, types) or (type(x) is bool and base != "bool"):
        raise _error(file, field, x, f"is {_type_name(x)}, not {expected}")
    if isinstance(x, float) and not math.isfinite(x):
        raise _error(file, field, x, "is not finite")
    if condition and base != "expr" and not CONDITIONS[condition][0](x):  # expressions: check_values
        raise _error(file, field, x, CONDITIONS[condition][1])


def _expressions(x, kind, field):
    """(field, value, condition) of every "expr" in x, which has passed `_walk`."""
    if isinstance(kind, str):
        base, _, condition = kind.partition(" ")
        if base == "expr":
            yield field, x, condition
    elif kind[0] in ("list", "pair"):
        for i, item in enumerate(x):
            yield from _expressions(item, kind[1], f"{field}[{i}]")
    elif kind[0] == "map":
        for key, item in x.items():
            yield from _expressions(item, kind[1], _join(field, key))
    elif kind[0] == "table":
        for key, declared in ((k.rstrip("?"), k) for k in kind[1]):
            if key in x:
                yield from _expressions(x[key], kind[1][declared], _join(field, key))


def _cross_references(spec, file):
    """What the types do not say: names that must refer to each other, lengths, units."""
    name, coords, params, scene = spec["name"], spec["coords"], spec["params"], spec["scene"]
    if not name.isidentifier():
        raise _error(file, "name", name, "is not an identifier (letters, digits and _, not starting with a digit)")
    if name in RESERVED_NAMES:
        raise _error(file, "name", name, f"is the name of a page of the report ({', '.join(RESERVED_NAMES)}); choose another")
    for key in ("coords", "reactions"):
        twice = [x for x in spec[key] if spec[key].count(x) > 1]
        if twice:
            raise _error(file, key, spec[key], f"names '{twice[0]}' twice")
    per_coordinate = {"coord_units": spec["coord_units"], "initial.q": spec["initial"]["q"],
                      "initial.v": spec["initial"]["v"], "sample.q": spec["sample"]["q"],
                      "sample.v": spec["sample"]["v"]}
    for field, values in per_coordinate.items():
        if len(values) != len(coords):
            raise _error(file, field, values, f"has length {len(values)}, not {len(coords)} "
                                              f"(one per coordinate: {', '.join(coords) or 'none'})")
    for p, item in params.items():
        try:
            si_dimension(item["unit"])
        except ValueError as why:
            raise _error(file, f"params.{p}.unit", item["unit"], str(why)) from None
        for key, relation in BOUNDS.items():  # overrides and ranges are checked later; the default here
            if key in item and not RELATIONS[relation](item["value"], item[key]):
                raise _error(file, f"params.{p}.{key}", item[key], f"excludes the default params.{p}.value = "
                             f"{item['value']!r}: {p} must be {relation} {item[key]:g}")

    euler = scene.get("euler", {}).get("coords", [])
    if "euler" in scene and len(euler) != 3:
        raise _error(file, "scene.euler.coords", euler, "does not name 3 coordinates (a ball joint's Euler angles)")
    if sorted([*scene["coords"], *euler]) != sorted(coords):
        raise _error(file, "scene.coords", scene["coords"],
                     f"(with scene.euler) does not give each of the coordinates ({', '.join(coords) or 'none'}) "
                     "exactly one joint")
    moments = [name for name, reaction in scene["reactions"].items() if reaction.get("quantity") == "moment"]
    if moments and "moment_scale" not in spec["tolerance"]["pointwise"]:
        raise _error(file, "tolerance.pointwise", spec["tolerance"]["pointwise"],
                     f"has no moment_scale, which the moment reaction '{moments[0]}' is judged against at least")
    if sorted(scene["reactions"]) != sorted(spec["reactions"]):
        raise _error(file, "scene.reactions", list(scene["reactions"]),
                     f"does not name the case's reactions ({', '.join(spec['reactions'])})")
    for p, locations in scene.get("bindings", {}).items():
        if p not in params:
            raise _error(file, f"scene.bindings.{p}", locations, "binds no parameter" + _hint(p, params))
    check_bindings(scene.get("bindings", {}), params, file)
    for p, bounds in spec["sample"].get("params", {}).get("ranges", {}).items():
        if p not in params:
            raise _error(file, f"sample.params.ranges.{p}", bounds, "is not a parameter's range" + _hint(p, params))
    ids = [finding["id"] for finding in spec.get("findings", [])]
    for i, finding_id in enumerate(ids):
        if finding_id in ids[:i]:
            raise _error(file, f"findings[{i}].id", finding_id, "is the id of an earlier finding")
    for i, finding in enumerate(spec.get("findings", [])):
        for source in finding["sources"]:
            if not _of_the_book(source):
                raise _error(file, f"findings[{i}].sources", source,
                             "is not the book's: a finding is an error of the book, its program, its figures or its "
                             "data ('book', 'program', or a comparison with one of them), never of an engine or the "
                             "reference")
    for i, runaway in enumerate(spec.get("runaway", [])):
        if runaway["coordinate"] not in coords:
            raise _error(file, f"runaway[{i}].coordinate", runaway["coordinate"], "is not a coordinate"
                         + _hint(runaway["coordinate"], coords))
        try:
            comparison = isinstance(ast.parse(runaway["when"].strip(), mode="eval").body, ast.Compare)
        except SyntaxError as error:
            raise _error(file, f"runaway[{i}].when", runaway["when"], f"cannot be parsed: {error.msg}") from None
        if not comparison:  # a number would hold wherever it is not 0
            raise _error(file, f"runaway[{i}].when", runaway["when"], "is not a comparison of the parameters, "
                         "such as k < m*Omega**2")
    _ceilings(spec, file)
    _course(spec, file)
    for key, figure in spec.get("program", {}).get("figures", {}).items():
        lo, hi = figure["range"]
        if not lo < hi:
            raise _error(file, f"program.figures.{key}.range", figure["range"], "is not an interval lo < hi")
    # What dyncheck.checks.runs.program_output_checks evaluates: arrays (a division by zero is then inf, not an error).
    engine = {**expressions.of_parameters({p: item["value"] for p, item in params.items()}),
              **{f"{body}_{axis}": np.ones(1) for body in scene.get("paths", []) for axis in "xyz"},
              **{name: np.ones(1) for name in spec["reactions"]}}
    for key, expression in spec.get("program", {}).get("outputs", {}).items():
        try:
            evaluate(expression, engine)
        except ValueError as error:
            raise _error(file, f"program.outputs.{key}", expression, f"cannot be evaluated from MuJoCo's values at "
                         f"the program's states: {error}") from None


def quantities(spec):
    """The quantities a case's rows may name, as the case file implies them: each coordinate, its rate and
    acceleration and its equation's residual, each reaction, point (a vector's name stands for its components),
    program output and finding's quantity, the energy, the drive power and the work-energy balance, and the book's
    printed Newton and Euler rows of the case's section (Book.printed_rows)."""
    coords = spec["coords"]
    names = {*coords, *(f"{c}_rate" for c in coords), *(f"{c}_acc" for c in coords), *(f"{c} residual" for c in coords),
             *spec["reactions"], *spec["scene"].get("points", {}), *spec.get("program", {}).get("outputs", {}),
             *(q for finding in spec.get("findings", []) for q in finding["quantities"]),
             "energy", "drive_power", "work-energy balance"}
    rows = {f"{law} {axis}{frame} ({spec.get('section', '')})" for law in ("Newton", "Euler") for axis in "XYZ"
            for frame in ("", "1", "2", "3")}
    return names | rows


def _course(spec, file):
    """The student's page names quantities the rows have, a label for each expression, and vibration results only
    where the case has them."""
    known = quantities(spec)
    for i, step in enumerate(spec.get("course", {}).get("steps", [])):
        for j, item in enumerate(step.get("show", [])):
            field = f"course.steps[{i}].show[{j}]"
            if "expression" not in item and "quantities" not in item:
                raise _error(file, field, item, "shows nothing: give an expression, quantities that check it, or both")
            if "expression" in item and "label" not in item:
                raise _error(file, field, item, "has an expression but no label (its left side in LaTeX)")
            for quantity in item.get("quantities", []):
                if quantity not in known:
                    raise _error(file, f"{field}.quantities", quantity, "is no quantity of this case"
                                 + _hint(quantity, sorted(known)))
        if step.get("vibration") and "vibration" not in spec:
            raise _error(file, f"course.steps[{i}].vibration", True, "shows vibration results, but the case has no "
                         "[vibration]")


# The package's own derivations, the one place outside a case's folder that its `derivation` may name.
REFERENCE = Path(__file__).resolve().parents[2] / "reference"


def own_file(folder, name, field, file):
    """The file `name` that the case file's `field` gives, as a path inside the case's `folder` (symbolic links
    and .. resolved): a case file names only files of its own folder, so that reading a case runs no code
    from elsewhere.  ValueError for a path that leaves it; whether the file is there is the caller's to say."""
    path = (Path(folder) / name).resolve()
    if not path.is_relative_to(Path(folder).resolve()):
        raise _error(file, field, name, f"is not a file of the case's folder {folder} (it is {path}): a case file "
                     "names only files of its own folder")
    return path


def derivation_file(derivation, folder, file):
    """The file of the case's equations, checked before anything is imported: a .py file in the case's
    `folder` (own_file), or `reference.<name>`, the package's own reference/<name>.py (never any other
    module: finding one would import its parent packages, and loading it runs whatever is installed)."""
    if derivation.endswith(".py"):
        path = own_file(folder, derivation, "derivation", file)
        where = "no file in the case folder"
    else:
        package, _, name = derivation.partition(".")
        if package != REFERENCE.name or not name.isidentifier():
            raise _error(file, "derivation", derivation, f"is neither a module of the package's {REFERENCE.name}/ "
                         f"({REFERENCE.name}.<name>) nor a path ending in .py of the case's folder")
        path, where = REFERENCE / f"{name}.py", f"no module of the package's {REFERENCE.name}/"
    if not path.is_file():
        raise _error(file, "derivation", derivation, f"names {where} (where the case's equations live)")
    return path


def _of_the_book(source):
    """Whether a finding's source is the book's: a source of the book, or a comparison of one with another."""
    return any(side.startswith(("book", "program")) for side in source.split(" vs "))


def _ceilings(spec, file):
    """Tolerances that would make their checks vacuous (dyncheck.common.ceilings)."""
    tolerance = spec["tolerance"]
    if tolerance["pointwise"]["value"] > ceilings.POINTWISE:
        raise _error(file, "tolerance.pointwise.value", tolerance["pointwise"]["value"],
                     f"is above the ceiling {ceilings.POINTWISE:g} of a pointwise comparison, above which it proves nothing")
    for check in ("trajectory", "energy"):
        if tolerance[check]["safety"] > ceilings.SAFETY:
            raise _error(file, f"tolerance.{check}.safety", tolerance[check]["safety"],
                         f"is above {ceilings.SAFETY:g}: a check that trusts its error estimate this little proves nothing")
    for i, item in enumerate(spec.get("data", [])):
        if item["tolerance"] > ceilings.DATA:
            raise _error(file, f"data[{i}].tolerance", item["tolerance"],
                         f"is above the ceiling {ceilings.DATA:g}: it could not tell a printing error from the printed rounding")


def check_bindings(bindings, params, file, elements=None):
    """[scene.bindings]: their types (also for a case of two files, whose case file dyncheck.case.derived.case_file
    derives from them before the whole is validated), each parameter bound somewhere, each location one that a
    binding can set, its index within the attribute's components; with `elements` ({"body": names, "joint":
    names} of the scene), each name one of the scene's."""
    _walk(bindings, SCHEMA[1]["scene"][1]["bindings?"], "scene.bindings", file)
    for p, locations in bindings.items():
        if not locations:
            raise _error(file, f"scene.bindings.{p}", locations, "binds the parameter to nothing: give its locations "
                         "in the scene, or leave it out")
        for i, location in enumerate(locations):
            field = f"scene.bindings.{p}[{i}]"
            _binding(location, field, params, file)
            names = (elements or {}).get(location["element"])
            if names is not None and location["name"] not in names:
                raise _error(file, f"{field}.name", location["name"], f"is no {location['element']} of the scene"
                             + _hint(location["name"], sorted(names)))


def _binding(location, field, params, file):
    element, attribute = location["element"], location.get("attribute")
    if (element, attribute) not in BINDABLE:
        bindable = [a for e, a in BINDABLE if e == element and a]
        raise _error(file, f"{field}.attribute", attribute, f"is not a bindable attribute of a {element}"
                     + (f"; those are {', '.join(bindable)}" if bindable else "; a binding of the option has none"))
    if element == "option" and location["name"] != "gravity":
        raise _error(file, f"{field}.name", location["name"], "is not 'gravity', the one option a binding sets")
    index, size = location.get("index", 0), BINDABLE[element, attribute]
    if not 0 <= index < size:
        raise _error(file, f"{field}.index", index, f"is not within 0..{size - 1} ({element} {attribute or 'gravity'})")
    for depend in location.get("depends", []):
        if depend not in params:
            raise _error(file, f"{field}.depends", location["depends"], f"names '{depend}', not a parameter"
                         + _hint(depend, params))


def demands(item, name):
    """What the value of parameter `name` (its table `item` in [params]) must satisfy beyond being finite:
    a list of (relation, bound, reason)."""
    unit = item["unit"]
    what = POSITIVE_DIMENSIONS.get(si_dimension(unit))
    demands = [(">", 0, f"{name} is {what}, in {unit}")] if what else []
    return demands + [(relation, item[key], f"params.{name}.{key}") for key, relation in BOUNDS.items() if key in item]


# -- messages -----------------------------------------------------------------------------------

def _error(file, field, value, problem):
    text = repr(value)
    return ValueError(f"{file}: {field} = {text if len(text) <= 80 else text[:77] + '...'} {problem}")


def _hint(word, choices):
    return suggest(word, choices) or f"; expected one of: {', '.join(choices)}"


def _join(field, key):
    return f"{field}.{key}" if field else key


def _type_name(x):
    names = {str: "a string", bool: "a boolean", int: "an integer", float: "a number", list: "an array",
             dict: "a table"}
    return names.get(type(x), "a date or time")


def _describe(kind):
    if isinstance(kind, str):
        base, _, condition = kind.partition(" ")
        return SCALARS[base][1] + (f", {condition}" if condition else "")
    return {"list": "an array", "pair": "a pair [lo, hi]", "map": "a table", "table": "a table",
            "free": "a table"}.get(kind[0], "one of " + ", ".join(map(repr, kind[1:])))


# -- the reference: docs/case-file.md ---------------------------------------------------------------
# What each key of SCHEMA means, by its dotted path: `<name>` stands for any key of a table whose keys
# are names, `[i]` for any item of an array.  A test demands one meaning per key, and no other.

ALONG_RUN = "an expression along the run (see Expressions)"
MEANINGS = {
    "name": "The case's name, an identifier; the reports and the JSON output call the case by it.",
    "section": "The book's section of the example, e.g. 1.8.3; a case of your own may have none.",
    "title": "The example's title in the reports.",
    "summary": "The example in a paragraph: the scene, its coordinates, what moves it; it opens the case's report.",
    "derivation": "Where the case's equations live: a path ending in .py of a file in the case's folder, or "
                  "`reference.<name>`, a module of the package's own `reference/` (the book's cases).  Nothing "
                  "else: a path that leaves the folder (.., an absolute path, a symbolic link to elsewhere) or any "
                  "other module is refused before anything is loaded.  It defines the sources `Book`, `Reference` "
                  "and, if the book prints a program, `Program`.",
    "coords": "The generalized coordinates, in the order of the book's equations; their rates are `<coord>_rate`.",
    "reactions": "The reactions (force or moment components) the derivation computes, by name; compared between "
                 "the sources.",
    "coord_units": "The unit of each coordinate, in the order of `coords`: rad (an angle) or m (a length).",
    "params": "The case's parameters, by name: the one source of its numbers, for the equations and both scene "
              "files alike.  `--set NAME=VALUE` overrides one.",
    "params.<name>.value": "Its default value.",
    "params.<name>.unit": "Its unit, one of the known units (see Parameters).",
    "params.<name>.about": "What it is and where the book gives it; shown in the report.",
    "params.<name>.printed": "The value as a program listing shows it in the book's text extraction, which lost "
                             "every digit 0: `\".558\"` for h = 0.0558.  It must be the value with every 0 removed; "
                             "the report shows both, and docs/book-numbers.md how each value was recovered.",
    "params.<name>.minimum": "Its value (default, override, random range) must be >= this.",
    "params.<name>.exclusive_minimum": "Its value (default, override, random range) must be > this.",
    "params.<name>.maximum": "Its value (default, override, random range) must be <= this.",
    "params.<name>.exclusive_maximum": "Its value (default, override, random range) must be < this.",
    "constraints": "What the parameters must satisfy together, beyond each one's bounds (see Constraints); `dyncheck list` shows each with its margin at the case's numbers.",
    "constraints[i].expression": "An expression of the parameters and pi that must be >= 0 (> 0 if strict).",
    "constraints[i].strict": "true: the expression must be > 0, not only >= 0.  Absent: false.",
    "constraints[i].why": "What the constraint means and why it holds; the error shows it.",
    "initial": "The initial conditions of the integrated runs.",
    "initial.q": "The coordinates at t = 0, one per coordinate.",
    "initial.v": "Their rates at t = 0, one per coordinate.",
    "initial.t_end": "The end of the runs, which start at t = 0: a whole number of `integration.output_step`s.",
    "runaway": "Where the case's physics runs away: conditions of the parameters under which a coordinate grows "
               "without bound, so that the runs past them are reported as `runaway`, not as `unstable` (see "
               "Runaway).",
    "runaway[i].when": "A comparison of the parameters and pi that holds where the physics runs away, e.g. "
                       "`k < m*(alpha_rate + beta_rate)**2`.",
    "runaway[i].coordinate": "The coordinate that grows without bound.",
    "runaway[i].escape": "Where a run has run away: where `when` holds, every run of the checks stops at the first "
                         "step that ends with the coordinate's magnitude beyond this.",
    "runaway[i].why": "The physical reason, shown in the rows; a number in it may be written `{= expression}` "
                      "or `{= expression :format}` (an expression of the parameters), computed at the run's "
                      "parameters.",
    "sample": "The random states of the pointwise check, at which every source is evaluated.",
    "sample.count": f"How many random states (at most {MAX_STATES}).",
    "sample.seed": "The seed of their random generator: two runs draw the same states.",
    "sample.t": "The interval of the random times.",
    "sample.q": "The interval of each coordinate's random values, one per coordinate.",
    "sample.v": "The interval of each coordinate's random rates, one per coordinate.",
    "sample.params": "Random parameter sets of the check \"random parameters\": reference and both engines must "
                     "agree at each.",
    "sample.params.sets": f"How many parameter sets (at most {MAX_SETS}).",
    "sample.params.states": f"Random states per set (sets times states at most {MAX_STATES}).",
    "sample.params.seed": "The seed of the sets' and their states' random generator.",
    "sample.params.ranges": "The parameters that vary, by name, each drawn uniformly from its interval; the "
                            "others keep their values.  Each interval must lie within the parameter's bounds; a "
                            "set that breaks a constraint is drawn again.",
    "work_precision": "The work-precision study of `dyncheck report` (methods, steps, tolerances, the solution "
                      "they are measured against) and the convergence checks (`convergence.omega`, the scene's "
                      "fastest frequency as an expression of the parameters, sets each method's step and horizon; "
                      "an optional `convergence.method_omega` table gives a method that integrates other "
                      "coordinates its own; where the motion outruns it, four times over, the horizon ends "
                      "before, and the row says where); validated by dyncheck/work_precision.py.",
    "budget": "How long a derivation of the case folder (code dyncheck does not control) may run, and in how much "
              "memory: a call, a run or a memory use past its budget is a failing row that says which function, at "
              "which state, after how long (docs/isolation.md).  The book's derivations in the package's own "
              "`reference` have none.",
    "budget.call": "One call of the derivation (an accelerations, an energy, ...).  Absent: 1000 times the slowest of "
                   "its calls at the initial state, at least 5 s; its import has 60 s.",
    "budget.case": "All the checks of the case, in a process of its own.  Absent: a million times that call's cost "
                   "(what the longest runs of a case take), at least 900 s.",
    "budget.memory": "The memory the case's process may map.  Absent: the machine's memory shared by the cases that "
                     "run at once.",
    "integration": "How the checks integrate the equations.",
    "integration.output_step": "The interval between a run's output rows; a multiple of mujoco_step.",
    "integration.rtol": "The relative and absolute tolerance of scipy's DOP853 for the runs of reference, book and "
                        "Pinocchio: from 100 machine epsilons (2.2e-14: scipy raises a smaller rtol to that) to "
                        f"{ceilings.RUN:g} (above it a run's error estimate means nothing).",
    "integration.tight_rtol": "The tolerance of the tight solution the runs are compared with; below rtol, and at "
                              "least 100 machine epsilons.",
    "integration.mujoco_step": "MuJoCo's fixed time step; an expression of the parameters may make it follow the scene's fastest motion (the longest step that divides an output_step of 1 ms with omega dt at most c: \"1e-3 / max(1, ceil(omega / c))\", omega written out in the parameters).",
    "tolerance": "The allowed errors of the checks, each with its argument.",
    "tolerance.pointwise": "The pointwise check: every source at the random states.",
    "tolerance.pointwise.value": f"The largest allowed relative error (at most {ceilings.POINTWISE:g}, above which "
                                 "a comparison proves nothing).",
    "tolerance.pointwise.force_scale": "The least scale a reaction is judged against (e.g. the weight m * g), so "
                                       "that a reaction that vanishes is not judged by rounding noise.",
    "tolerance.pointwise.moment_scale": "The least scale a moment reaction is judged against (e.g. the weight "
                                        "times a length); required when a reaction is a moment.",
    "tolerance.pointwise.why": "The argument for the value: rounding, modelling differences, margin.",
    "tolerance.trajectory": "The trajectory check: each integrated run against the tight solution.",
    "tolerance.trajectory.safety": f"The allowed error is this times the run's own error estimate (at most "
                                   f"{ceilings.SAFETY:g}).",
    "tolerance.trajectory.why": "The argument for the factor.",
    "tolerance.energy": "The work-energy balance check along each run.",
    "tolerance.energy.safety": f"The allowed residual is this times the balance's own error estimate (at most "
                               f"{ceilings.SAFETY:g}).",
    "tolerance.energy.why": "The argument for the factor.",
    "report": "What the case's report page says beside the checks.",
    "report.modelling": "How each source models the example: the book's equations, the reference's corrections, "
                        "the engines' scenes.",
    "report.stop": f"Where the book's program stops: {ALONG_RUN} that cuts the report's values and figures at the "
                   "first time it holds.",
    "report.values": "Values computed along every source's run, by name, shown side by side.",
    "report.values.<name>.expression": f"The value: {ALONG_RUN}, e.g. max(Rz) or first(nutation > 1).",
    "report.values.<name>.unit": "Its unit as shown (free text).",
    "report.values.<name>.about": "What it is.",
    "report.figures": "Figures drawn from every source's run, by name.",
    "report.figures.<name>.x": f"The abscissa: {ALONG_RUN}.",
    "report.figures.<name>.y": f"The ordinate: {ALONG_RUN}.",
    "report.figures.<name>.title": "The figure's title.",
    "report.figures.<name>.xlabel": "The x axis's label.",
    "report.figures.<name>.ylabel": "The y axis's label.",
    "report.figures.<name>.caption": "What the figure shows and what to see in it, under it on the page.  Absent: its title.",
    "report.figures.<name>.xlim": "The x axis's range.  Absent: the data's.",
    "report.figures.<name>.ylim": "The y axis's range.  Absent: the data's.",
    "report.figures.<name>.equal": "true: the same scale on both axes.",
    "animation": "What the case page's animation (a GIF of the motion in 3-D, or in its plane) shows beside the "
                 "motion; absent: the motion alone.",
    "animation.program": "The book's program's run (`program`) drawn `beside` the exact motion or as a `ghost` over it.",
    "animation.arrow": "A force drawn as an arrow at each frame, from the exact run; the largest is half the "
                       "scene's extent long.",
    "animation.arrow.force": f"Its three world components (x, y, z): {ALONG_RUN}.",
    "animation.arrow.at": f"The point it acts at (x, y, z, m): {ALONG_RUN}.",
    "animation.arrow.about": "What the arrow is, for the caption.",
    "animation.graph": "A quantity drawn beside the motion against time, growing with the frames, with its "
                       "largest value dashed.",
    "animation.graph.y": f"The quantity: {ALONG_RUN}.",
    "animation.graph.title": "The graph's title.",
    "animation.graph.ylabel": "Its axis's label, with the unit.",
    "animation.graph.ylim": "Its axis's range.  Absent: the data's.",
    "animation.caption": "What to see in the animation: the caption's last sentences, with measured numbers where it "
                         "says what the runs show (see Measured numbers in prose).",
    "scene": "How the scene files (scene.xml for MuJoCo, scene.urdf for Pinocchio) map to the case.",
    "scene.coords": "Each coordinate of a hinge or slide joint, by name: that joint's name in the scene files.",
    "scene.euler": "A ball joint whose orientation the book writes in Euler angles.",
    "scene.euler.joint": "The ball joint's name in the scene files.",
    "scene.euler.coords": "The three coordinates that are its Euler angles, in the order of the book's rotations.",
    "scene.driven": "Joints that a prescribed motion moves (they are not coordinates), by name in the scene files.",
    "scene.driven.<name>.angle": "Its position at t = 0.  Absent: 0.",
    "scene.driven.<name>.rate": "Its rate at t = 0.  Absent: 0.",
    "scene.driven.<name>.acc": "Its acceleration, constant.  Absent: 0.",
    "scene.dependent": "Joints that closed kinematic loops move (MJCF <connect> equalities, docs/own-case.md section "
                       "7): no coordinate's; each engine solves them from the coordinates at every state.  Absent: none.",
    "scene.applied": "Generalized forces on joints, by name in the scene files: one per degree of freedom of the "
                     "joint (a ball joint's: moments about its local axes), each a number or a law of t, the "
                     "coordinates, their rates (`<coordinate>_rate`) and the parameters, e.g. "
                     "`x = [\"F0 * cos(Omega * t)\"]`.  The engines apply it at every evaluation (MuJoCo at each "
                     "stage of its RK4 step); its work is in the work-energy balance.",
    "scene.paths": "Bodies whose centre of mass the runs trace: the columns <body>_x, <body>_y, <body>_z of the "
                   "run (see Expressions).",
    "scene.reactions": "Where the engines read each reaction of `reactions`, by its name.",
    "scene.reactions.<name>.body": "The body the force acts on.",
    "scene.reactions.<name>.sensor": "The MJCF force (or torque) sensor that measures it, or the name of a <connect> "
                                     "for the force of its loop on its body1 at the anchor (frame \"world\").",
    "scene.reactions.<name>.axis": "Its component: 0, 1 or 2 (x, y, z).",
    "scene.reactions.<name>.frame": "The frame of the component: the body's or the world's.",
    "scene.reactions.<name>.quantity": "A force (the default: read by a <force> sensor) or a moment about the "
                                       "body's origin (a <torque> sensor on a site there), of the parent on the "
                                       "body and what hangs from it.",
    "scene.points": "Kinematic vectors of a body compared between the sources, by name: the quantities "
                    "<name>_x, <name>_y, <name>_z.",
    "scene.points.<name>.body": "The body.",
    "scene.points.<name>.frame": "The frame of the components: the body's or the world's.",
    "scene.points.<name>.kind": "What vector: the acceleration of the body frame's origin, of the centre of mass, "
                                "the angular velocity or acceleration.  Absent: acceleration.",
    "scene.urdf_root_joint": "URDF has no ball joint: Pinocchio loads scene.urdf's root link on this joint.",
    "scene.urdf_root_joint.name": "The joint's name.",
    "scene.urdf_root_joint.type": "The joint's type.",
    "scene.bindings": "Where each parameter lives in the scene files, by its name: on load the engines' models "
                      "are checked against the parameter's value, and an override is written into them.",
    "scene.bindings.<name>[i].element": "The kind of element: a body, a joint, or the option (gravity).",
    "scene.bindings.<name>[i].name": "The element's name in the scene files; gravity for the option.",
    "scene.bindings.<name>[i].attribute": "The attribute: a body's " + ", ".join(
        a for e, a in BINDABLE if e == "body") + "; a joint's " + ", ".join(
        a for e, a in BINDABLE if e == "joint") + "; none for the option.",
    "scene.bindings.<name>[i].index": "The component of a vector attribute.  Absent: 0.",
    "scene.bindings.<name>[i].scale": "The attribute is the parameter times this (e.g. -1 for gravity along -z).  "
                                      "Absent: 1.",
    "scene.bindings.<name>[i].depends": "Other parameters the attribute depends on (an inertia about the origin "
                                        "on the mass and the centre of mass): it is rewritten after them when "
                                        "they change.",
    "program": "The book's printed program (`Program` of the derivation) and its figures.",
    "program.figures": "The ranges the book's figures show, by name: the program's run and the tight solution "
                       "must stay inside.",
    "program.figures.<name>.expression": f"What the figure shows: {ALONG_RUN}.",
    "program.figures.<name>.range": "The figure's axis range.",
    "program.figures.<name>.where": "Where the book shows the figure.",
    "program.outputs": "What the program writes out, by its column: an expression of MuJoCo's values at the "
                       "program's state on the same row (see Expressions), compared at up to 200 of its rows "
                       "(check `program`, `program vs mujoco at the program's states`), e.g. `h1x = \"-link1_x\"` "
                       "where the listing's x axis is the mirror of the scene's.",
    "program.plots": "The book's figures redrawn from the program's run and the tight solution.",
    "program.plots[i].x": f"The abscissa: {ALONG_RUN}.",
    "program.plots[i].y": f"The ordinate: {ALONG_RUN}.",
    "program.plots[i].title": "The plot's title.",
    "program.plots[i].xlabel": "The x axis's label in the book's words, with its unit.  Absent: `time [s]` for t, else x.",
    "program.plots[i].ylabel": "The y axis's label in the book's words, with its unit.  Absent: the title.",
    "program.plots[i].xlim": "The x axis's range (the book's).  Absent: the data's.",
    "program.plots[i].ylim": "The y axis's range (the book's).  Absent: the data's.",
    "findings": "Errors of the book that the checks establish: a failing check that a finding covers is "
                "reported as the finding, not as a failure.",
    "findings[i].id": "A unique id, e.g. 1.8.3-R.",
    "findings[i].title": "The error in a line; it may hold measured numbers (see Measured numbers in prose), so "
                         "that it stays true under `--set`.",
    "findings[i].where": "Where the book has it.",
    "findings[i].effect": "What it changes in the book's results, where the checks cannot compute that.",
    "findings[i].sources": "The comparisons it covers: book, program, or a comparison `X vs Y` with one of them; "
                           "never an engine's or the reference's alone.",
    "findings[i].quantities": "The quantities it covers.",
    "findings[i].explanation": "The evidence: what is printed, what is right, by how much.",
    "findings[i].measured": "What this run measures of it, in sentences whose numbers are measured in the results "
                            "(see Measured numbers in prose): shown on the case page and in the errata as this run's, "
                            "never marked as the book's numbers.",
    "measured": "Numbers measured in the saved results, by name, for the pages' prose (dyncheck/measured.py; see "
                "Measured numbers in prose).",
    "measured.<name>.kind": "What is measured: `span` (max - min of `of` along `run`), `rms` (its root mean square "
                            "about its mean), `start`, `end`, `change` (its value at the run's first output, last, "
                            "and the difference), `phase lag` (degrees by which `run`'s oscillation of `of` lags "
                            "`against`'s, at the latter's dominant frequency over its last two periods), `frequency` "
                            "(rad/s of the vibration analysis's oscillating mode `mode`), `error` (the error of the "
                            "row with `check`, `quantity` and `sources`), `program step` (the book's program's time "
                            "step, s).",
    "measured.<name>.of": f"What is measured along the run: {ALONG_RUN}.",
    "measured.<name>.run": "The run, named as the rows name it: `program` (the book's program), `book equations, "
                           "same integrator` (the book's equations stepped as its program steps them, with the "
                           "drives' work), `tight reference` (the exact motion), `reference`, `book`, `mujoco`, "
                           "`pinocchio`.",
    "measured.<name>.against": "The run a `phase lag` is taken against (named as `run`).",
    "measured.<name>.mode": "The oscillating mode of a `frequency`, 1 the slowest.",
    "measured.<name>.source": "Whose modes a `frequency` is: reference, mujoco or pinocchio.  Absent: reference.",
    "measured.<name>.check": "The check of an `error`'s row.",
    "measured.<name>.quantity": "The quantity of an `error`'s row.",
    "measured.<name>.sources": "The comparison of an `error`'s row, as the pages write it: `program vs tight "
                               "reference`.",
    "findings[i].right": "The right expression of a printed one the search of edits does not find, by its key in "
                         "the book's module's PRINTED, in that module's symbols; the run checks it against the "
                         "reference at the random states, and the errata typeset it beside the printed one.",
    "data": "The book's printed numbers against its own formulas.",
    "data[i].name": "The quantity's name in the report.",
    "data[i].printed": "The printed value.",
    "data[i].formula": "The value of the book's formula; the difference is relative to it.",
    "data[i].where": "Where the book prints them.",
    "data[i].tolerance": f"The allowed relative difference, e.g. half a unit of the last printed digit (at most "
                         f"{ceilings.DATA:g}).",
    "data[i].relation": "equal: printed = formula; at most: printed <= formula.  Absent: equal.",
    "stability": "The stability studies of `dyncheck report`, each in a sub-table named after it; `module` names "
                 "a .py file in the case's folder (not outside it) with the case's own studies.  Validated by dyncheck/stability.",
    "vibration": "Vibration analysis (dyncheck/vibration.py): an equilibrium found by Newton-Raphson, the equations "
                 "linearised about it by the derivation and by both engines, their frequencies, modes and stability, "
                 "each frequency checked in a run.  Rows with check `vibration`; the page's section \"Vibration "
                 "analysis\".",
    "course": "The student's page, `<case>_student.md` beside the case page (dyncheck/student_page.py, "
              "[student-pages.md](student-pages.md)): the book's procedure step by step in plain words, each result "
              "typeset from the expression the code evaluates and checked against the engines by the run's rows.",
    "course.intro": "The page's opening paragraph: what the example is and what it finds (Markdown, `$` maths).",
    "course.steps": "The steps, in the book's order.",
    "course.steps[i].title": "The step's heading.",
    "course.steps[i].text": "What the step does, in plain words, with inline `$...$` maths, `{= expression}` "
                            "numbers (see Numbers in prose) and `{~ expression}` numbers measured in the results "
                            "(see Measured numbers in prose).",
    "course.steps[i].show": "The results the step typesets, each with its check.",
    "course.steps[i].show[i].expression": "The expression the code evaluates: `book:KEY` (the derivation's "
                                          "Book.PRINTED), `program:KEY` (Program.PRINTED), `frames:KEY` (the "
                                          "derivation module's FRAMES, matrices of the angle `a`).  Absent: a check "
                                          "alone.",
    "course.steps[i].show[i].label": "The left side, in LaTeX, e.g. `{}_{B_3}\\mathbf{a}_E`.",
    "course.steps[i].show[i].quantities": "The quantities whose rows check it.  Absent: the expression's KEY (a "
                                          "vector's name stands for its components).",
    "course.steps[i].show[i].source": "Whose rows: those comparing this source with the engines or the exact "
                                      "motion.  Absent: book or program for their expressions, else reference.",
    "course.steps[i].show[i].symbols": "LaTeX for the expression's names here, e.g. `{ a = '\\alpha' }` for a "
                                       "frame's angle.",
    "course.steps[i].show[i].checked": "What the rows compare, in words, where it is not the expression itself.",
    "course.steps[i].figures": "Figures of the case page shown in this step, each with its caption.",
    "course.steps[i].figures[i].figure": "The figure's kind: `figures/<case>_<figure>.png` of the case page "
                                         "(scene, coordinates, program, modes, ...).",
    "course.steps[i].figures[i].caption": "What it shows and what to see in it, in plain words; what it shows of "
                                          "the runs in measured numbers (see Measured numbers in prose).",
    "course.steps[i].vibration": "Show the vibration analysis's equilibrium, frequencies and stability here.",
    "vibration.why": "What is linearised, and why about this state.",
    "vibration.overrides": "Parameters changed for the linearised scene, e.g. the arm at rest so that the disk's spin "
                           "makes a relative equilibrium, or no resisting moment.",
    "vibration.q": "The coordinates where Newton-Raphson starts (one per coordinate).",
    "vibration.v": "The rates where it starts (one per coordinate): a relative equilibrium's constant rates.",
    "vibration.solve": "The state variables Newton-Raphson solves for, coordinates or `<coord>_rate`; the others "
                       "stay as given.",
    "vibration.amplitude": "The largest coordinate displacement of each mode's run from the equilibrium: small enough "
                           f"that the frequency's nonlinear shift stays below {ceilings.MOTION:g} of it.",
    "vibration.periods": "How long each mode's run lasts, in periods of that mode.",
    "vibration.campbell": "The Campbell diagram of `dyncheck report`: the frequencies against a parameter (a spin rate).",
    "vibration.campbell.parameter": "The parameter swept.",
    "vibration.campbell.scale": "What `values` are multiples of (default 1): an expression of the parameters, such as "
                                "`sqrt(k/m)`, so that the sweep follows `--set`.  Evaluated in the linearised scene (with "
                                "`vibration.overrides`) where the study runs, not on load: where it has no value there "
                                "(a square root of a negative number), or one not > 0, the page says that there is "
                                "nothing to sweep.",
    "vibration.campbell.values": "Its values, in multiples of `scale`, in order: each equilibrium starts Newton-Raphson "
                                 "from the one before.  The page's own equilibrium's value joins them where it lies "
                                 "between two.",
    "vibration.campbell.why": "What the diagram shows.",
    "vibration.boundary": "Stability boundaries, each found from the eigenvalues (bisection on the parameter between the "
                          "bracket's stable and unstable ends, or where the equilibrium ceases) and confirmed by runs "
                          "either side.",
    "vibration.boundary[i].parameter": "The parameter whose value crosses the boundary.",
    "vibration.boundary[i].scale": "What `bracket` is in multiples of (default 1), as `vibration.campbell.scale`.",
    "vibration.boundary[i].bracket": "Two values of it, in multiples of `scale`, one on each side.  Where the "
                                     "equilibrium is stable at both ends, or unstable at both, the page says so, and "
                                     "what the formula `expected` gives.",
    "vibration.boundary[i].expected": "The boundary as a formula says it is (compared with the eigenvalues'): an "
                                      "expression of the parameters, evaluated where the study runs (it may have no "
                                      "value at other parameters, as a square root of a difference).",
    "vibration.boundary[i].why": "Where the formula comes from.",
    "vibration.floquet": "About a periodic motion, where the base's motion makes the equations periodic in t (no "
                         "equilibrium): the orbit by shooting Newton-Raphson on the derivation, each source's monodromy "
                         "matrix, its Floquet multipliers and the stability verdict, the largest multiplier checked by "
                         "stroboscopic runs.  At the case's own numbers (no overrides).",
    "vibration.floquet.why": "What the periodic motion is, and why the equations are periodic.",
    "vibration.floquet.period": "The period T of the equations, an expression of the parameters and pi, e.g. "
                                "`2*pi/abs(beta_rate)` (checked: the accelerations at t and t + T agree).  Evaluated by "
                                "the analysis, not on load: where it has no value, or one not > 0, at the run's "
                                "parameters (a disk at rest, beta_rate = 0), the analysis is not applicable and says why.",
    "vibration.floquet.q": "The coordinates where shooting starts, at t = 0 (one per coordinate).",
    "vibration.floquet.v": "The rates where it starts (one per coordinate).",
    "vibration.floquet.periods": "How long the stroboscopic runs last, in periods.",
    "vibration.floquet.amplitude": "The largest coordinate displacement of the runs from the orbit, along the "
                                   "eigenvector of the largest multiplier: small enough that its nonlinear shift "
                                   f"stays below {ceilings.MOTION:g} of it.",
}
# The unit of a key's numbers, where it has one.
KEY_UNITS = {
    **dict.fromkeys(["params.<name>.value", *(f"params.<name>.{key}" for key in BOUNDS), "sample.params.ranges"],
                    "params.<name>.unit"),
    **dict.fromkeys(["initial.q", "sample.q"], "coord_units"),
    "runaway[i].escape": "the coordinate's (coord_units)",
    **dict.fromkeys(["initial.v", "sample.v"], "coord_units per s"),
    **dict.fromkeys(["initial.t_end", "sample.t", "integration.output_step", "integration.mujoco_step"], "s"),
    **dict.fromkeys(["budget.call", "budget.case"], "s"),
    "budget.memory": "GB (10^9 bytes)",
    "tolerance.pointwise.force_scale": "N",
    "tolerance.pointwise.moment_scale": "N m",
    "scene.driven.<name>.angle": "rad or m (the joint's)",
    "scene.driven.<name>.rate": "rad/s or m/s",
    "scene.driven.<name>.acc": "rad/s^2 or m/s^2",
    "scene.applied": "N m or N (the joint's)",
    "vibration.q": "coord_units",
    "vibration.v": "coord_units per s",
    "vibration.amplitude": "coord_units",
    **dict.fromkeys(["vibration.campbell.scale", "vibration.boundary[i].scale", "vibration.boundary[i].expected"],
                    "the parameter's"),
    **dict.fromkeys(["vibration.campbell.values", "vibration.boundary[i].bracket"], "multiples of `scale`"),
    "vibration.floquet.period": "s",
    "vibration.floquet.q": "coord_units",
    "vibration.floquet.v": "coord_units per s",
    "vibration.floquet.amplitude": "coord_units",
}


def keys(kind=SCHEMA, path=""):
    """(dotted path, type, optional) of every key of the schema, each table's keys after it."""
    tag = kind[0] if isinstance(kind, tuple) else None
    if tag == "table":
        for declared, item in kind[1].items():
            key = _join(path, declared.rstrip("?"))
            yield key, item, declared.endswith("?")
            yield from keys(item, key)
    elif tag == "map":
        yield from keys(kind[1], f"{path}.<name>")
    elif tag == "list":
        yield from keys(kind[1], f"{path}[i]")


def _words(kind):
    """A type of the schema in words."""
    if isinstance(kind, str) or kind[0] == "one of":
        return _describe(kind)
    tag, *rest = kind
    return {"list": lambda: "an array, each item " + _words(rest[0]),
            "pair": lambda: "a pair [lo, hi], each " + _words(rest[0]),
            "map": lambda: "a table of names, each " + _words(rest[0]),
            "table": lambda: "a table (its keys below)",
            "free": lambda: "a table (see its meaning)"}[tag]()


def markdown():
    """docs/case-file.md: the case file's reference."""
    lines = ["# The case file", "",
             "Generated by `dyncheck.case.schema.markdown()` from `dyncheck.case.schema.SCHEMA` and `MEANINGS`; a test checks "
             "that it is current.", "",
             "Each case is a folder (in `cases/`, or in a folder of your own given with `--cases DIR`) with its "
             "`case.toml`, `scene.xml` (MJCF, for MuJoCo), `scene.urdf` (for Pinocchio) and, if it is not elsewhere, "
             "its derivation.  Loading checks the file in this order: its keys and types (a misspelt key is refused, "
             "not taken for an absent optional one), units and cross-references; then the parameters, overrides "
             "applied, against their bounds and the constraints; then every number that may be an expression, "
             "evaluated at those parameters.  A problem gives one error naming the file, the field (a dotted path "
             "as below, or `override NAME`) and the value, and exit code 2.", "",
             "## Keys", "",
             "`<name>` stands for any key of a table whose keys are names, `[i]` for any item of an array.  A number "
             "of type \"a number or an expression in quotes\" may be written as an expression of the parameters "
             "(see Expressions); its condition (such as `> 0`) holds for its value.", "",
             "| key | required | type | unit | meaning |", "|---|---|---|---|---|"]
    lines += [f"| `{key}` | {'no' if optional else 'yes'} | {_words(kind)} | {KEY_UNITS.get(key, '')} | "
              f"{MEANINGS[key]} |" for key, kind, optional in keys()]
    lines += ["", "## Parameters", "",
              "A parameter's `unit` is any coherent SI unit (no prefix, no factor: every value of a case is in "
              "SI) that the units library pint reads, such as `N s/m`, `N m s/rad`, `kg m^2`, `rad/s^2`, or "
              f"`{DIMENSIONLESS}` for a pure number; `g`, `N/mm` or `deg` are refused with the SI unit to use.", "",
              "A parameter of the dimension of " + ", ".join(f"`{unit}` ({what})" for unit, what in POSITIVE_UNITS.items())
              + " must be > 0 in every case.  Anything else a value must satisfy depends on the case and is "
              "written next to it, in JSON Schema's words:", ""]
    lines += [f"- `{key} = x`: the value must be {relation} x" for key, relation in BOUNDS.items()]
    lines += ["", "The default `value` must lie within its bounds; so must every override (`--set`) and both "
              "ends of the parameter's interval in `sample.params.ranges`.  For example "
              "`l = { value = 0.1, unit = \"m\", exclusive_minimum = 0.0, about = \"rod length\" }`.", "",
              "## Constraints", "",
              "What no bound of one parameter can say: each `[[constraints]]` entry's `expression`, an expression "
              "of the parameters and pi, must be >= 0, or > 0 with `strict = true`.  They are checked after "
              "overrides, and at every random parameter set (a set that breaks one is drawn again).  A comparison "
              "is refused (it would pass as 0 or 1): write a >= b as `a - b`.  The error names the file, "
              "`constraints[i]`, the expression, its value, the parameters in it (marked `(override)` where "
              "overridden) and the `why`.  For example:", "",
              "```toml", "[[constraints]]", "expression = \"Ixx - m*h**2\"", "strict = true",
              "why = \"the moment of inertia about the centre of mass across the axis must be > 0\"", "```", "",
              "## Runaway", "",
              "A physical runaway is not a numerical failure.  Where the case knows its physical limits, each "
              "`[[runaway]]` entry says when the parameters are past one (`when`), which coordinate then grows "
              "without bound and where a run has run away (`escape`), and why.  At parameters where no `when` "
              "holds, nothing changes: a run that blows up is `unstable`.  Where the first `when` that holds "
              "does, every run of the checks (reference, book, Pinocchio, MuJoCo, and their twins) stops at the "
              "first step beyond `escape`, and:", "",
              "- every source escaped: the runs' rows are `runaway` (a success, counted apart), with the `why` "
              "and when, which method and which step each source escaped;",
              "- some escaped and others did not: not the physics the case states.  The rows of a run that "
              "stayed within the bound to the end fail, those of the escaped runs are `unstable` (as are those of "
              "a run that blew up otherwise: a non-finite state, a budget);",
              "- none escaped before `initial.t_end` (a growth too slow to reach `escape`): the runs are compared "
              "as at any parameters.", "",
              "The conditions are checked on load: `when` must be a comparison, and it and every `{= expression}` "
              "in `why` must evaluate at the parameters.  For example:", "",
              "```toml", "[[runaway]]", "when = \"k < m*(alpha_rate + beta_rate)**2\"", "coordinate = \"l\"",
              "escape = 100.0",
              "why = \"the spin's pull m Omega^2 = {= m*(alpha_rate + beta_rate)**2 :.4g} N/m beats the spring k = "
              "{= k :g} N/m\"",
              "```", "",
              "## Numbers in prose", "",
              "A text that a page shows (`summary`, `report.modelling`, `tolerance.<name>.why`, a finding's "
              "`explanation` and `effect`, `runaway[i].why`, ...) may write a number as `{= expression}` or "
              "`{= expression :format}` (a Python format spec of a number, default `.3g`, its width and precision of at "
              "most 3 digits each): it is computed at the parameters "
              "of the run, so that the page stays true under `--set`.  For example `sqrt(k/m) = "
              "{= sqrt(k/m) :.0f} rad/s` reads `sqrt(k/m) = 100 rad/s` at the book's k = 2000 N/m and `50 rad/s` "
              "at k = 500.  Every such number is evaluated on load (a bad one is refused, exit 2).  A number "
              "measured in the results is written `{~ ...}` (see Measured numbers in prose); one measured once, "
              "at the book's numbers, belongs only in a finding's `explanation` or `effect`, which a page under "
              "overrides marks as the case file's account of the book's numbers.", "",
              "## Measured numbers in prose", "",
              "A number measured in the results, not computed from the parameters, is named in `[measured]` and "
              "written `{~ expression}` or `{~ expression :format}`: an expression of those names and the "
              "parameters, with a number's format spec (default `.3g`) or the name of a rule of `dyncheck/words.py` "
              "that chooses the words from the number, such as " + "; ".join(
                  f"`{name}`: " + ", ".join(f"{x:g} \"{rule(x)}\"" for x in words.EXAMPLES[name])
                  for name, rule in words.WORDS.items())
              + ".  The pages measure them from the saved results when they are rendered; a paragraph that needs "
              "one the run could not take (its run blew up, the book's program did not finish) says so instead, "
              "and why.  They may stand in the texts a page renders beside the results: the course's texts and "
              "figure captions, `animation.caption`, a finding's `title` and `measured`.  On load each `{~ ...}` "
              "must evaluate and each measure have the keys of its kind.  For example:", "",
              "```toml", "[measured]", "l_listing = { kind = \"span\", of = \"l\", run = \"program\" }",
              "l_exact = { kind = \"span\", of = \"l\", run = \"tight reference\" }",
              "psi_lag = { kind = \"phase lag\", of = \"psi\", run = \"program\", against = \"tight reference\" }",
              "```", "",
              "with `The listing's l spans {~ l_listing :.3g} m, {~ l_listing / l_exact :ratio} the exact motion's; "
              "its swing {~ psi_lag :lag} the exact one.`, which reads \"... 0.0427 m, 14 % larger than the exact "
              "motion's; its swing lags 85 degrees behind the exact one.\" at the book's numbers.", "",
              "## Expressions", "",
              "An expression is text in quotes, parsed and evaluated by `dyncheck.common.expressions` (never by Python's "
              "eval).  It may hold only numbers, names, unary + and -, the operators + - * / **, one comparison "
              "(< <= > >= == !=, not a chain) and calls of "
              + ", ".join(f"`{name}`" for name in expressions.CALLABLE) + ".  Every number is a float; an "
              f"exponent beyond +-{expressions.MAX_EXPONENT} is refused, and so is an expression longer than "
              f"{expressions.MAX_LENGTH} characters or nested deeper than {expressions.MAX_DEPTH} levels.", "",
              "The names depend on where the expression is:", "",
              "- the file's numbers of type \"a number or an expression in quotes\", `constraints[i].expression`, "
              "`runaway[i].when` and every `{= expression}` in prose: "
              "the parameters, `pi` and numpy's " + ", ".join(f"`{name}`" for name in expressions.FUNCTIONS) + ";",
              "- along a run (`report.stop`, `report.values`, `report.figures`, `program.figures`, `program.plots`, `animation.arrow`, `animation.graph`): "
              "the run's columns, arrays over its output times (each coordinate, its rate `<coord>_rate`, each "
              "reaction, `energy`, `work`, and `<body>_x`, `<body>_y`, `<body>_z` of each body of `scene.paths`), "
              "`t`, the parameters, `pi`, numpy's " + ", ".join(f"`{name}`" for name in expressions.FUNCTIONS)
              + ", and `first(condition)`, the first time the condition holds (NaN if never).  With a "
              "`report.stop`, every array ends where it first holds;",
              "- `program.outputs`: MuJoCo's values at the program's rows' states, arrays over those rows "
              "(`<body>_x`, `<body>_y`, `<body>_z` of each body of `scene.paths` and each reaction), the parameters, "
              "`pi` and numpy's " + ", ".join(f"`{name}`" for name in expressions.FUNCTIONS) + "."]
    return "\n".join(lines) + "\n"
