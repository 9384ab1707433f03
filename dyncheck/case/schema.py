"""The schema of case.toml, and what makes a case's numbers physical.

Three checks, in the order a case is loaded (dyncheck.case.folder.Case):
`validate(spec, file)` the parsed file's keys, types, units and cross-references;
`check_params(...)` the parameter values after overrides (positive masses, each parameter's bounds, the
case's constraints);
`check_values(...)` every number that may be an expression, evaluated at those parameters, and each
parameter's printed form (as the book's text shows it) against its value.
Each raises one ValueError naming the file, the field (a dotted path such as `integration.rtol`,
or `override m` for an override) and the value.
docs/case-file.md, the reference of the case file, is `dyncheck.case.meanings.markdown()`.
"""

import ast
import math
import operator
import re
from pathlib import Path

import numpy as np

from dyncheck.case.files import derivation_file, own_file
from dyncheck.case.units import POSITIVE_DIMENSIONS, si_dimension
from dyncheck.common import ceilings, expressions
from dyncheck.common.ceilings import LEAST_RTOL, MAX_STEPS
from dyncheck.common.expressions import evaluate
from dyncheck.common.messages import field_error, hint
from dyncheck.results import measured

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
    # physical limits past which a coordinate grows without bound (dyncheck/checks/, runaway)
    "runaway?": ("list", ("table", {"when": "str", "coordinate": "str", "escape": "expr > 0", "why": "str"})),
    "sample": ("table", {
        "count": "int > 0", "budget?": "number >= 0", "seed": "int >= 0", "t": ("pair", "expr"),
        "q": ("list", ("pair", "expr")), "v": ("list", ("pair", "expr")),
        # random parameter sets of the "random parameters" check (dyncheck/checks/)
        "params?": ("table", {"sets": "int > 0", "states": "int > 0", "seed": "int >= 0",
                              "ranges": ("map", ("pair", "expr"))}),
    }),
    "work_precision?": FREE,  # validated by dyncheck/studies/work_precision.py
    # how long the case's own code may run, and in how much memory (dyncheck/case/isolation.py)
    "budget?": ("table", {"call?": "number > 0", "case?": "number > 0", "memory?": "number > 0", "run?": "number > 0"}),
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
    # what the case page's animation shows beside the motion (dyncheck/pages/animation.py)
    "animation?": ("table", {"program?": ("one of", "beside", "ghost"),
                             "arrow?": ("table", {"force": ("list", "str"), "at": ("list", "str"), "about": "str"}),
                             "graph?": ("table", {"y": "str", "title": "str", "ylabel": "str", "ylim?": RANGE}),
                             "caption?": "str"}),
    "scene": ("table", {
        "coords?": ("map", "str"),  # book coordinate -> hinge or slide joint
        "joints?": ("map", "str"),  # or: hinge or slide joint -> affine expression of the coordinates
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
    # numbers measured in the results, for the pages' prose (dyncheck/results/measured.py checks each kind's keys)
    "measured?": ("map", ("table", {"kind": ("one of", *measured.KINDS), "of?": "str",
                                    "run?": ("one of", *measured.RUNS), "against?": ("one of", *measured.RUNS),
                                    "mode?": "int > 0", "source?": ("one of", "reference", "mujoco", "pinocchio"),
                                    "check?": "str", "quantity?": "str", "sources?": "str"})),
    # data_checks divides by the formula's value
    "data?": ("list", ("table", {"name": "str", "printed": "expr", "formula": "expr != 0", "where": "str",
                                 "tolerance": "number >= 0", "relation?": ("one of", "equal", "at most")})),
    "stability?": FREE,  # validated by dyncheck/studies/stability/
    # cross-references validated by dyncheck/checks/vibration.py
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
    # the student's page (dyncheck/pages/student_page.py, which checks the expressions against the derivation)
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
# attribute -> the number of components `index` may pick.  An option binding is gravity.  A body's inertia is its
# principal moments about the centre of mass (MJCF diaginertia, in the inertial frame); its fullinertia the tensor
# about the centre of mass in the body frame, ixx iyy izz ixy ixz iyz (engines.bindings.FULL_INERTIA).
BINDABLE = {("body", "mass"): 1, ("body", "pos"): 3, ("body", "ipos"): 3, ("body", "inertia_about_origin"): 3,
            ("body", "inertia"): 3, ("body", "fullinertia"): 6,
            ("joint", "stiffness"): 1, ("joint", "damping"): 1, ("joint", "springref"): 1, ("option", None): 3}

# -- parameters ---------------------------------------------------------------------------------
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
            raise field_error(file, "name", spec["name"], f"is not the name of the case's folder, '{Path(folder).name}'")
        derivation_file(spec["derivation"], folder, file)
        module = spec.get("stability", {}).get("module")
        if isinstance(module, str):  # its own studies, loaded by dyncheck.studies.stability once the models are built
            path = own_file(folder, module, "stability.module", file)
            if not module.endswith(".py") or not path.is_file():  # refused by every command, `list` as `run`
                raise field_error(file, "stability.module", module, f"is not a Python file of the case's folder ({path})")


def check_params(spec, params, overrides, file):
    """The parameter values (defaults and `overrides` applied): physical, or ValueError."""
    field = lambda p: f"override {p}" if p in overrides else f"params.{p}.value"
    for p, x in params.items():
        for relation, bound, reason in demands(spec["params"][p], p):
            if not RELATIONS[relation](x, bound):
                raise field_error(file, field(p), x, f"must be {relation} {bound:g} ({reason})")
    _check_constraints(spec.get("constraints", []), params, overrides, file)


def _check_constraints(constraints, params, overrides, file):
    """Each constraint's expression >= 0 (> 0 if strict) at `params`, or ValueError naming it."""
    names = expressions.of_parameters(params)  # as dyncheck.case.folder.Case.value evaluates the file's numbers
    for i, constraint in enumerate(constraints):
        field, expression = f"constraints[{i}]", constraint["expression"]
        try:
            x = evaluate(expression, names)
        except ValueError as error:
            raise field_error(file, f"{field}.expression", expression, f"cannot be evaluated: {error}") from None
        if isinstance(x, (bool, np.bool_)):  # a comparison would pass as 0 or 1, whatever it says
            raise field_error(file, f"{field}.expression", expression, "is a comparison; a constraint is an expression "
                         "that must be >= 0 (> 0 with strict = true): write a >= b as a - b")
        strict = constraint.get("strict", False)
        if not (x > 0 if strict else x >= 0):  # also refuses a NaN
            involved = [p for p in dict.fromkeys(re.findall(r"[A-Za-z_]\w*", expression)) if p in params]
            values = ", ".join(f"{p} = {params[p]!r}" + (" (override)" if p in overrides else "") for p in involved)
            raise field_error(file, field, expression, f"is {x:.4g} at {values or 'any parameters'}, not "
                         f"{'>' if strict else '>='} 0: {' '.join(constraint['why'].split())}"
                         + ("; set the others with the overrides (`dyncheck list` shows each case's constraints)"
                            if any(p in overrides for p in involved) else ""))


def check_values(spec, file, value):
    """Every number that may be an expression, evaluated by `value(x, field)` at the case's parameters, and
    each parameter's printed form against its value (after check_params: a value that is not physical is
    the first thing to say)."""
    for p, item in spec["params"].items():
        if "printed" in item and item["printed"] != without_zeros(item["value"]):
            raise field_error(file, f"params.{p}.printed", item["printed"], f"is not params.{p}.value = {item['value']!r} "
                         f"as the book's text shows it, every digit 0 lost ('{without_zeros(item['value'])}')")
    values = {}
    for field, x, condition in _expressions(spec, SCHEMA, ""):
        values[field] = v = value(x, field)
        if not math.isfinite(v):
            raise field_error(file, field, x, f"is {v}, not a finite number")
        if condition and not CONDITIONS[condition][0](v):
            raise field_error(file, field, x, CONDITIONS[condition][1] + (f" (it is {v:g})" if isinstance(x, str) else ""))
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
            raise field_error(file, field, bounds, f"is not an interval lo <= hi ({lo:g} > {hi:g})")
    # The random parameter sets must be physical too: an interval is within bounds when both its ends are.
    for p, bounds in ranges.items():
        for relation, bound, reason in demands(spec["params"][p], p):
            if not all(RELATIONS[relation](values[f"sample.params.ranges.{p}[{i}]"], bound) for i in (0, 1)):
                raise field_error(file, f"sample.params.ranges.{p}", bounds,
                             f"leaves the physical values: {p} must be {relation} {bound:g} ({reason})")


def _check_integration(spec, values, file):
    """The runs' settings, each one that the integrators can honour and that makes its rows mean something."""
    setting = spec["integration"]
    shown = lambda key: (f"integration.{key} = {setting[key]!r}"
                         + (f" = {values['integration.' + key]:g}" if isinstance(setting[key], str) else ""))
    whole = lambda ratio: round(ratio) >= 1 and abs(ratio - round(ratio)) <= 1e-9 * ratio  # as simulate's grid
    if not whole(values["integration.output_step"] / values["integration.mujoco_step"]):
        raise field_error(file, "integration.output_step", setting["output_step"],
                     f"is not a multiple of {shown('mujoco_step')}")
    if not whole(values["initial.t_end"] / values["integration.output_step"]):  # every run ends on an output
        raise field_error(file, "initial.t_end", spec["initial"]["t_end"],
                     f"is not a whole number of output steps ({shown('output_step')})")
    for key in ("rtol", "tight_rtol"):
        if values[f"integration.{key}"] < LEAST_RTOL:
            raise field_error(file, f"integration.{key}", setting[key],
                         f"is below {LEAST_RTOL:.3g}, 100 machine epsilons: scipy's integrators raise a smaller rtol "
                         "to that, so the run would not be the one its rows say (dyncheck.common.ceilings.LEAST_RTOL)")
    if values["integration.rtol"] > ceilings.RUN:
        raise field_error(file, "integration.rtol", setting["rtol"],
                     f"is above {ceilings.RUN:g}: a run's error, about rtol of each quantity, would be beyond the "
                     "ceiling where an error estimate means anything, and every row judged by one inconclusive")
    if values["integration.tight_rtol"] >= values["integration.rtol"]:
        raise field_error(file, "integration.tight_rtol", setting["tight_rtol"],
                     f"is not below integration.rtol = {setting['rtol']!r}: the tight twin must be tighter")


# How much work one case file may ask for, so that a run ends in minutes (dyncheck.run.simulate bounds
# each integration as it runs; these bound what is asked before anything runs).
# The most random states a [sample] budget gives (Case.sample_count): 4 times a case of two files' 256, so that a
# region of 5 % of the state space holds about 50 of them, at a quarter of a second of evaluations (0.25 s, its
# budget) where a state costs 0.24 ms or less.
MAX_ADAPTIVE_STATES = 1024
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
            raise field_error(file, field, x, f"asks for {amount:.3g} {what}, more than the {limit:.0e} a run allows")


# -- the walk -----------------------------------------------------------------------------------

def _walk(x, kind, field, file):
    """x against `kind`; `field` is its dotted path."""
    if isinstance(kind, str):
        return _scalar(x, kind, field, file)
    tag, *rest = kind
    if tag == "one of":
        if not any(type(x) is type(option) and x == option for option in rest):  # True is not 1
            raise field_error(file, field, x, "is not one of " + ", ".join(map(repr, rest)))
        return
    sequence = tag in ("list", "pair")
    if not isinstance(x, list if sequence else dict):
        raise field_error(file, field, x, f"is {_type_name(x)}, not {kind_in_words(kind)}")
    if tag == "pair" and len(x) != 2:
        raise field_error(file, field, x, "is not a pair [lo, hi]")
    if sequence:
        for i, item in enumerate(x):
            _walk(item, rest[0], f"{field}[{i}]", file)
    elif tag == "map":
        for key, item in x.items():
            _walk(item, rest[0], joined(field, key), file)
    elif tag == "table":
        keys = {key.rstrip("?"): key for key in rest[0]}
        for key, item in x.items():
            if key not in keys:  # a typo must not pass for an absent optional key
                raise field_error(file, joined(field, key), item, "is not a known key" + hint(key, keys))
        for key, declared in keys.items():
            if key in x:
                _walk(x[key], rest[0][declared], joined(field, key), file)
            elif not declared.endswith("?"):
                raise ValueError(f"{file}: {joined(field, key)} is missing ({kind_in_words(rest[0][declared])})")


def _scalar(x, kind, field, file):
    base, _, condition = kind.partition(" ")
    types, expected = SCALARS[base]
    if not isinstance(x, types) or (type(x) is bool and base != "bool"):
        raise field_error(file, field, x, f"is {_type_name(x)}, not {expected}")
    if isinstance(x, float) and not math.isfinite(x):
        raise field_error(file, field, x, "is not finite")
    if condition and base != "expr" and not CONDITIONS[condition][0](x):  # expressions: check_values
        raise field_error(file, field, x, CONDITIONS[condition][1])


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
            yield from _expressions(item, kind[1], joined(field, key))
    elif kind[0] == "table":
        for key, declared in ((k.rstrip("?"), k) for k in kind[1]):
            if key in x:
                yield from _expressions(x[key], kind[1][declared], joined(field, key))


def _cross_references(spec, file):
    """What the types do not say: names that must refer to each other, lengths, units."""
    name, coords, params, scene = spec["name"], spec["coords"], spec["params"], spec["scene"]
    if not name.isidentifier():
        raise field_error(file, "name", name, "is not an identifier (letters, digits and _, not starting with a digit)")
    if name in RESERVED_NAMES:
        raise field_error(file, "name", name, f"is the name of a page of the report ({', '.join(RESERVED_NAMES)}); choose another")
    for key in ("coords", "reactions"):
        twice = [x for x in spec[key] if spec[key].count(x) > 1]
        if twice:
            raise field_error(file, key, spec[key], f"names '{twice[0]}' twice")
    per_coordinate = {"coord_units": spec["coord_units"], "initial.q": spec["initial"]["q"],
                      "initial.v": spec["initial"]["v"], "sample.q": spec["sample"]["q"],
                      "sample.v": spec["sample"]["v"]}
    for field, values in per_coordinate.items():
        if len(values) != len(coords):
            raise field_error(file, field, values, f"has length {len(values)}, not {len(coords)} "
                                              f"(one per coordinate: {', '.join(coords) or 'none'})")
    for p, item in params.items():
        try:
            si_dimension(item["unit"])
        except ValueError as why:
            raise field_error(file, f"params.{p}.unit", item["unit"], str(why)) from None
        for key, relation in BOUNDS.items():  # overrides and ranges are checked later; the default here
            if key in item and not RELATIONS[relation](item["value"], item[key]):
                raise field_error(file, f"params.{p}.{key}", item[key], f"excludes the default params.{p}.value = "
                             f"{item['value']!r}: {p} must be {relation} {item[key]:g}")

    euler = scene.get("euler", {}).get("coords", [])
    if "euler" in scene and len(euler) != 3:
        raise field_error(file, "scene.euler.coords", euler, "does not name 3 coordinates (a ball joint's Euler angles)")
    if "joints" in scene and scene.get("coords"):
        raise field_error(file, "scene.coords", scene["coords"], "is given with scene.joints, which gives every "
                          "joint as a function of the coordinates: give one of the two")
    if "joints" not in scene and sorted([*scene.get("coords", {}), *euler]) != sorted(coords):
        raise field_error(file, "scene.coords", scene.get("coords", {}),
                     f"(with scene.euler) does not give each of the coordinates ({', '.join(coords) or 'none'}) "
                     "exactly one joint")
    moments = [name for name, reaction in scene["reactions"].items() if reaction.get("quantity") == "moment"]
    if moments and "moment_scale" not in spec["tolerance"]["pointwise"]:
        raise field_error(file, "tolerance.pointwise", spec["tolerance"]["pointwise"],
                     f"has no moment_scale, which the moment reaction '{moments[0]}' is judged against at least")
    if sorted(scene["reactions"]) != sorted(spec["reactions"]):
        raise field_error(file, "scene.reactions", list(scene["reactions"]),
                     f"does not name the case's reactions ({', '.join(spec['reactions'])})")
    for p, locations in scene.get("bindings", {}).items():
        if p not in params:
            raise field_error(file, f"scene.bindings.{p}", locations, "binds no parameter" + hint(p, params))
    check_bindings(scene.get("bindings", {}), params, file)
    for p, bounds in spec["sample"].get("params", {}).get("ranges", {}).items():
        if p not in params:
            raise field_error(file, f"sample.params.ranges.{p}", bounds, "is not a parameter's range" + hint(p, params))
    ids = [finding["id"] for finding in spec.get("findings", [])]
    for i, finding_id in enumerate(ids):
        if finding_id in ids[:i]:
            raise field_error(file, f"findings[{i}].id", finding_id, "is the id of an earlier finding")
    for i, finding in enumerate(spec.get("findings", [])):
        for source in finding["sources"]:
            if not _of_the_book(source):
                raise field_error(file, f"findings[{i}].sources", source,
                             "is not the book's: a finding is an error of the book, its program, its figures or its "
                             "data ('book', 'program', or a comparison with one of them), never of an engine or the "
                             "reference")
    for i, runaway in enumerate(spec.get("runaway", [])):
        if runaway["coordinate"] not in coords:
            raise field_error(file, f"runaway[{i}].coordinate", runaway["coordinate"], "is not a coordinate"
                         + hint(runaway["coordinate"], coords))
        try:
            comparison = isinstance(ast.parse(runaway["when"].strip(), mode="eval").body, ast.Compare)
        except SyntaxError as error:
            raise field_error(file, f"runaway[{i}].when", runaway["when"], f"cannot be parsed: {error.msg}") from None
        if not comparison:  # a number would hold wherever it is not 0
            raise field_error(file, f"runaway[{i}].when", runaway["when"], "is not a comparison of the parameters, "
                         "such as k < m*Omega**2")
    _ceilings(spec, file)
    _course(spec, file)
    for key, figure in spec.get("program", {}).get("figures", {}).items():
        lo, hi = figure["range"]
        if not lo < hi:
            raise field_error(file, f"program.figures.{key}.range", figure["range"], "is not an interval lo < hi")
    # What dyncheck.checks.runs.program_output_checks evaluates: arrays (a division by zero is then inf, not an error).
    engine = {**expressions.of_parameters({p: item["value"] for p, item in params.items()}),
              **{f"{body}_{axis}": np.ones(1) for body in scene.get("paths", []) for axis in "xyz"},
              **{name: np.ones(1) for name in spec["reactions"]}}
    for key, expression in spec.get("program", {}).get("outputs", {}).items():
        try:
            evaluate(expression, engine)
        except ValueError as error:
            raise field_error(file, f"program.outputs.{key}", expression, f"cannot be evaluated from MuJoCo's values at "
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
                raise field_error(file, field, item, "shows nothing: give an expression, quantities that check it, or both")
            if "expression" in item and "label" not in item:
                raise field_error(file, field, item, "has an expression but no label (its left side in LaTeX)")
            for quantity in item.get("quantities", []):
                if quantity not in known:
                    raise field_error(file, f"{field}.quantities", quantity, "is no quantity of this case"
                                 + hint(quantity, sorted(known)))
        if step.get("vibration") and "vibration" not in spec:
            raise field_error(file, f"course.steps[{i}].vibration", True, "shows vibration results, but the case has no "
                         "[vibration]")


def _of_the_book(source):
    """Whether a finding's source is the book's: a source of the book, or a comparison of one with another."""
    return any(side.startswith(("book", "program")) for side in source.split(" vs "))


def _ceilings(spec, file):
    """Tolerances that would make their checks vacuous (dyncheck.common.ceilings)."""
    tolerance = spec["tolerance"]
    if tolerance["pointwise"]["value"] > ceilings.POINTWISE:
        raise field_error(file, "tolerance.pointwise.value", tolerance["pointwise"]["value"],
                     f"is above the ceiling {ceilings.POINTWISE:g} of a pointwise comparison, above which it proves nothing")
    for check in ("trajectory", "energy"):
        if tolerance[check]["safety"] > ceilings.SAFETY:
            raise field_error(file, f"tolerance.{check}.safety", tolerance[check]["safety"],
                         f"is above {ceilings.SAFETY:g}: a check that trusts its error estimate this little proves nothing")
    for i, item in enumerate(spec.get("data", [])):
        if item["tolerance"] > ceilings.DATA:
            raise field_error(file, f"data[{i}].tolerance", item["tolerance"],
                         f"is above the ceiling {ceilings.DATA:g}: it could not tell a printing error from the printed rounding")


def check_bindings(bindings, params, file, elements=None):
    """[scene.bindings]: their types (also for a case of two files, whose case file dyncheck.case.derived.case_file
    derives from them before the whole is validated), each parameter bound somewhere, each location one that a
    binding can set, its index within the attribute's components; with `elements` ({"body": names, "joint":
    names} of the scene), each name one of the scene's."""
    _walk(bindings, SCHEMA[1]["scene"][1]["bindings?"], "scene.bindings", file)
    for p, locations in bindings.items():
        if not locations:
            raise field_error(file, f"scene.bindings.{p}", locations, "binds the parameter to nothing: give its locations "
                         "in the scene, or leave it out")
        for i, location in enumerate(locations):
            field = f"scene.bindings.{p}[{i}]"
            _binding(location, field, params, file)
            names = (elements or {}).get(location["element"])
            if names is not None and location["name"] not in names:
                raise field_error(file, f"{field}.name", location["name"], f"is no {location['element']} of the scene"
                             + hint(location["name"], sorted(names)))
    # one scene number set by two parameters would follow whichever is written last: an override of one moves both
    seen = {}
    for p, locations in bindings.items():
        for i, location in enumerate(locations):
            key = (location["element"], location.get("name"), location.get("attribute"), location.get("index", 0))
            if key in seen and seen[key] != p:
                raise field_error(file, f"scene.bindings.{p}[{i}]", location, f"is also bound by {seen[key]}: one scene "
                                  "number can follow one parameter")
            seen[key] = p


def _binding(location, field, params, file):
    element, attribute = location["element"], location.get("attribute")
    if (element, attribute) not in BINDABLE:
        bindable = [a for e, a in BINDABLE if e == element and a]
        raise field_error(file, f"{field}.attribute", attribute, f"is not a bindable attribute of a {element}"
                     + (f"; those are {', '.join(bindable)}" if bindable else "; a binding of the option has none"))
    if element == "option" and location["name"] != "gravity":
        raise field_error(file, f"{field}.name", location["name"], "is not 'gravity', the one option a binding sets")
    index, size = location.get("index", 0), BINDABLE[element, attribute]
    if not 0 <= index < size:
        raise field_error(file, f"{field}.index", index, f"is not within 0..{size - 1} ({element} {attribute or 'gravity'})")
    for depend in location.get("depends", []):
        if depend not in params:
            raise field_error(file, f"{field}.depends", location["depends"], f"names '{depend}', not a parameter"
                         + hint(depend, params))


def demands(item, name):
    """What the value of parameter `name` (its table `item` in [params]) must satisfy beyond being finite:
    a list of (relation, bound, reason)."""
    unit = item["unit"]
    what = POSITIVE_DIMENSIONS.get(si_dimension(unit))
    demands = [(">", 0, f"{name} is {what}, in {unit}")] if what else []
    return demands + [(relation, item[key], f"params.{name}.{key}") for key, relation in BOUNDS.items() if key in item]


# -- messages -----------------------------------------------------------------------------------

def joined(field, key):
    return f"{field}.{key}" if field else key


def _type_name(x):
    names = {str: "a string", bool: "a boolean", int: "an integer", float: "a number", list: "an array",
             dict: "a table"}
    return names.get(type(x), "a date or time")


def kind_in_words(kind):
    if isinstance(kind, str):
        base, _, condition = kind.partition(" ")
        return SCALARS[base][1] + (f", {condition}" if condition else "")
    return {"list": "an array", "pair": "a pair [lo, hi]", "map": "a table", "table": "a table",
            "free": "a table"}.get(kind[0], "one of " + ", ".join(map(repr, kind[1:])))
