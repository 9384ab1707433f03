"""The schema of case.toml, and what makes a case's numbers physical.

Three checks, in the order a case is loaded (dyncheck.case.Case):
`validate(spec, file)` the parsed file's keys, types, units and cross-references;
`check_params(...)` the parameter values after overrides (positive masses, a realisable top, ...);
`check_values(...)` every number that may be an expression, evaluated at those parameters.
Each raises one ValueError naming the file, the field (a dotted path such as `integration.rtol`,
or `override m` for an override) and the value.
"""

import difflib
import importlib.util
import math

from dyncheck import ceilings

# -- the schema -----------------------------------------------------------------------------------
# A type is a string: "str", "int", "bool", "number" (a TOML integer or float), "expr" (a number,
# or an expression of the parameters and pi in quotes), optionally with a condition: "int > 0",
# "number >= 0", "expr != 0"; or a tuple: ("list", item), ("pair", item) a list of two,
# ("one of", *values), ("map", item) a table whose keys are names (of parameters, joints, ...),
# ("table", {key: type}) a table of these keys, "key?" optional, or FREE.

FREE = ("free",)  # a table whose contents the module that reads it checks
RANGE = ("pair", "number")
FRAME = ("one of", "body", "world")
TOLERANCE = ("table", {"safety": "number > 0", "why": "str"})

SCHEMA = ("table", {
    "name": "str",
    "section": "str",
    "title": "str",
    "summary": "str",
    "coords": ("list", "str"),
    "reactions": ("list", "str"),
    "coord_units": ("list", ("one of", "rad", "m")),
    "params": ("map", ("table", {"value": "number", "unit": "str", "about": "str"})),
    "initial": ("table", {"q": ("list", "expr"), "v": ("list", "expr"), "t_end": "expr > 0"}),
    "sample": ("table", {
        "count": "int > 0", "seed": "int >= 0", "t": ("pair", "expr"),
        "q": ("list", ("pair", "expr")), "v": ("list", ("pair", "expr")),
        # random parameter sets of the "random parameters" check (dyncheck/checks.py)
        "params?": ("table", {"sets": "int > 0", "states": "int > 0", "seed": "int >= 0",
                              "ranges": ("map", ("pair", "expr"))}),
    }),
    "work_precision?": FREE,  # validated by dyncheck/work_precision.py
    "integration": ("table", {"output_step": "expr > 0", "rtol": "expr > 0", "tight_rtol": "expr > 0",
                              "mujoco_step": "expr > 0"}),
    "tolerance": ("table", {"pointwise": ("table", {"value": "number > 0", "force_scale": "expr >= 0", "why": "str"}),
                            "trajectory": TOLERANCE, "energy": TOLERANCE}),
    "report": ("table", {
        "modelling": "str",
        "stop?": "str",
        "values?": ("map", ("table", {"expression": "str", "unit": "str", "about": "str"})),
        "figures?": ("map", ("table", {"x": "str", "y": "str", "title": "str", "xlabel": "str", "ylabel": "str",
                                       "xlim?": RANGE, "ylim?": RANGE, "equal?": "bool"})),
    }),
    "scene": ("table", {
        "coords": ("map", "str"),  # book coordinate -> hinge or slide joint
        "euler?": ("table", {"joint": "str", "coords": ("list", "str")}),  # ball joint in Euler angles
        "driven": ("map", ("table", {"angle?": "expr", "rate?": "expr", "acc?": "expr"})),
        "applied?": ("map", ("list", "expr")),
        "paths?": ("list", "str"),
        "reactions": ("map", ("table", {"body": "str", "sensor": "str", "axis": ("one of", 0, 1, 2),
                                        "frame": FRAME})),
        "points?": ("map", ("table", {"body": "str", "frame": FRAME, "kind?": (
            "one of", "acceleration", "com acceleration", "angular velocity", "angular acceleration")})),
        "urdf_root_joint?": ("table", {"name": "str", "type": ("one of", "spherical")}),
        "bindings?": ("map", ("list", ("table", {
            "element": ("one of", "body", "joint", "option"), "name": "str", "attribute?": "str",
            "index?": "int", "scale?": "number", "depends?": ("list", "str")}))),
    }),
    "program?": ("table", {
        "figures?": ("map", ("table", {"expression": "str", "range": RANGE, "where": "str"})),
        "plots?": ("list", ("table", {"x": "str", "y": "str", "title": "str", "xlim?": RANGE, "ylim?": RANGE})),
    }),
    "findings?": ("list", ("table", {"id": "str", "title": "str", "where": "str", "effect?": "str",
                                     "sources": ("list", "str"), "quantities": ("list", "str"),
                                     "explanation": "str"})),
    # data_checks divides by the formula's value
    "data?": ("list", ("table", {"name": "str", "printed": "expr", "formula": "expr != 0", "where": "str",
                                 "tolerance": "number >= 0", "relation?": ("one of", "equal", "at most")})),
    "stability?": FREE,  # validated by dyncheck/stability.py
})

SCALARS = {"str": ((str,), "a string"), "int": ((int,), "an integer"), "bool": ((bool,), "true or false"),
           "number": ((int, float), "a number"), "expr": ((int, float, str), "a number or an expression in quotes")}
CONDITIONS = {"> 0": (lambda x: x > 0, "must be > 0"), ">= 0": (lambda x: x >= 0, "must be >= 0"),
              "!= 0": (lambda x: x != 0, "must not be 0")}

# What a binding can set in the scene files (the engines' `_write` and `read`): element and
# attribute -> the number of components `index` may pick.  An option binding is gravity.
BINDABLE = {("body", "mass"): 1, ("body", "pos"): 3, ("body", "ipos"): 3, ("body", "inertia_about_origin"): 3,
            ("joint", "stiffness"): 1, ("option", None): 3}

# -- parameters ---------------------------------------------------------------------------------
# The unit of each parameter name the cases use, in every case.
UNITS = {"m": "kg", "m1": "kg", "m2": "kg", "k": "N/m", "Ixx": "kg m^2", "Izz": "kg m^2", "Mz": "N m",
         "g": "m/s^2", "L_acc": "m/s^2", "L_rate": "m/s", "theta_acc": "rad/s^2",
         **dict.fromkeys(("a", "b", "c", "r", "h", "l", "l0", "l1", "l2", "L0", "thickness"), "m"),
         **dict.fromkeys(("alpha0", "beta0", "psi", "theta0"), "rad"),
         **dict.fromkeys(("alpha_rate", "beta_rate", "theta_rate"), "rad/s")}
# Units whose every value must be positive.
POSITIVE_UNITS = {"kg": "a mass", "N/m": "a stiffness", "kg m^2": "a moment of inertia"}
# Lengths are sizes of bodies (> 0) or positions of hinges and centres of mass (any sign, or zero:
# the disk's hinge may sit on its axis, the top's centre of mass below its tip).  The same name
# may be either (r: a hinge's radius on the 1.8 disks, the top's disk radius), hence per case.
SIZES = {"double_pendulum": {"l1", "l2"}, "piston": {"L0"}, "rotating_particle": {"l"},
         "rotating_pendulum": {"l"}, "spring_pendulum": {"l0"}, "spinning_top": {"r", "thickness"}}
# A rigid body's moments of inertia about its centre of mass satisfy A + B >= C.  For the top,
# A = B = Ixx - m h^2, C = Izz.  The book's printed pair breaks it by 3.7e-6 kg m^2 (finding
# 1.10-data); scene.xml carries up to 1e-5 kg m^2 of it by its armature identity (see there), so
# that much is allowed and MuJoCo's compiler never has to refuse an override.
TOP_SLACK = 1e-5  # kg m^2


def validate(spec, file):
    """The parsed case file `spec` against the schema; ValueError names `file`, the field and the value."""
    _walk(spec, SCHEMA, "", file)
    _cross_references(spec, file)


def check_params(spec, params, overrides, file):
    """The parameter values (defaults and `overrides` applied): physical, or ValueError."""
    field = lambda p: f"override {p}" if p in overrides else f"params.{p}.value"
    for p, x in params.items():
        demand = _demand(spec["name"], p, spec["params"][p]["unit"])
        if demand and not demand[0](x):
            raise _error(file, field(p), x, demand[1])
    if {"Ixx", "Izz", "m", "h"} <= set(params):  # the top: Ixx (= Iyy) and Izz about its tip
        named = lambda *names: ", ".join(f"{p} = {params[p]!r}" + (" (override)" if p in overrides else "")
                                         for p in names)
        a, c = params["Ixx"] - params["m"] * params["h"] * params["h"], params["Izz"]
        if a <= 0:
            raise ValueError(f"{file}: {named('Ixx', 'm', 'h')} give the top a moment of inertia about its centre "
                             f"of mass A = Ixx - m h^2 = {a:.4g} kg m^2, not > 0; no rigid body has it")
        if 2 * a - c < -TOP_SLACK:
            raise ValueError(f"{file}: {named('Ixx', 'Izz', 'm', 'h')} break the triangle inequality A + B >= C "
                             f"of the top's moments of inertia about its centre of mass (A = B = Ixx - m h^2 = "
                             f"{a:.4g}, C = Izz): A + B - C = {2 * a - c:.3g} kg m^2, beyond the -{TOP_SLACK:g} "
                             "that the scene can carry; no rigid body has these inertias")


def check_values(spec, file, value):
    """Every number that may be an expression, evaluated by `value(x, field)` at the case's parameters."""
    values = {}
    for field, x, condition in _expressions(spec, SCHEMA, ""):
        values[field] = v = value(x, field)
        if not math.isfinite(v):
            raise _error(file, field, x, f"is {v}, not a finite number")
        if condition and not CONDITIONS[condition][0](v):
            raise _error(file, field, x, CONDITIONS[condition][1] + (f" (it is {v:g})" if isinstance(x, str) else ""))
    setting = spec["integration"]
    steps = values["integration.output_step"] / values["integration.mujoco_step"]
    if round(steps) < 1 or abs(steps - round(steps)) > 1e-9 * steps:
        raise _error(file, "integration.output_step", setting["output_step"],
                     f"is not a multiple of integration.mujoco_step = {setting['mujoco_step']!r}")
    if values["integration.tight_rtol"] >= values["integration.rtol"]:
        raise _error(file, "integration.tight_rtol", setting["tight_rtol"],
                     f"is not below integration.rtol = {setting['rtol']!r}: the tight twin must be tighter")
    _check_sizes(spec, values, file)
    sample = spec["sample"]
    ranges = sample.get("params", {}).get("ranges", {})
    intervals = {"sample.t": sample["t"], **{f"sample.q[{i}]": x for i, x in enumerate(sample["q"])},
                 **{f"sample.v[{i}]": x for i, x in enumerate(sample["v"])},
                 **{f"sample.params.ranges.{p}": x for p, x in ranges.items()}}
    for field, bounds in intervals.items():
        lo, hi = values[f"{field}[0]"], values[f"{field}[1]"]
        if lo > hi:
            raise _error(file, field, bounds, f"is not an interval lo <= hi ({lo:g} > {hi:g})")
    for p, bounds in ranges.items():  # the random parameter sets must be physical too
        demand = _demand(spec["name"], p, spec["params"][p]["unit"])
        if demand and not all(demand[0](values[f"sample.params.ranges.{p}[{i}]"]) for i in (0, 1)):
            raise _error(file, f"sample.params.ranges.{p}", bounds, f"leaves the physical values: {p} " + demand[1])


# How much work one case file may ask for, so that a run ends in minutes (dyncheck.simulate bounds
# each integration as it runs; these bound what is asked before anything runs).
MAX_STATES = 10_000  # random states of the pointwise check, and sets x states of the random parameters:
#                      four sources at ~0.25 ms each per state, 10 s
MAX_SETS = 1_000  # random parameter sets: each builds both engines' models, ~20 ms
MAX_OUTPUTS = 100_000  # rows of one run's output: a reactions and an energy evaluation each, ~0.2 ms, 20 s


def _check_sizes(spec, values, file):
    """The number of random states and sets, and of a run's outputs and MuJoCo's steps, within the bounds above."""
    from dyncheck.simulate import MAX_STEPS  # here, not at the top: it loads scipy and pandas
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
    if not name.isidentifier() or importlib.util.find_spec(f"reference.{name}") is None:
        raise _error(file, "name", name, "names no module in reference/ (the case's equations)")
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
        unit, known = item["unit"], sorted(set(UNITS.values()))
        if p in UNITS and unit != UNITS[p]:
            raise _error(file, f"params.{p}.unit", unit, f"is not the unit of {p}, {UNITS[p]!r}")
        if unit not in known:
            raise _error(file, f"params.{p}.unit", unit, "is not a known unit" + _hint(unit, known))

    euler = scene.get("euler", {}).get("coords", [])
    if "euler" in scene and len(euler) != 3:
        raise _error(file, "scene.euler.coords", euler, "does not name 3 coordinates (a ball joint's Euler angles)")
    if sorted([*scene["coords"], *euler]) != sorted(coords):
        raise _error(file, "scene.coords", scene["coords"],
                     f"(with scene.euler) does not give each of the coordinates ({', '.join(coords) or 'none'}) "
                     "exactly one joint")
    if sorted(scene["reactions"]) != sorted(spec["reactions"]):
        raise _error(file, "scene.reactions", list(scene["reactions"]),
                     f"does not name the case's reactions ({', '.join(spec['reactions'])})")
    for p, locations in scene.get("bindings", {}).items():
        if p not in params:
            raise _error(file, f"scene.bindings.{p}", locations, "binds no parameter" + _hint(p, params))
        for i, location in enumerate(locations):
            _binding(location, f"scene.bindings.{p}[{i}]", params, file)
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
    _ceilings(spec, file)
    for key, figure in spec.get("program", {}).get("figures", {}).items():
        lo, hi = figure["range"]
        if not lo < hi:
            raise _error(file, f"program.figures.{key}.range", figure["range"], "is not an interval lo < hi")


def _of_the_book(source):
    """Whether a finding's source is the book's: a source of the book, or a comparison of one with another."""
    return any(side.startswith(("book", "program")) for side in source.split(" vs "))


def _ceilings(spec, file):
    """Tolerances that would make their checks vacuous (dyncheck.ceilings)."""
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


def _demand(case, name, unit):
    """What a parameter's value must satisfy beyond being finite: (test, text), or None."""
    if unit in POSITIVE_UNITS:
        return (lambda x: x > 0), f"must be > 0 ({name} is {POSITIVE_UNITS[unit]}, in {unit})"
    if name in SIZES.get(case, ()):
        return (lambda x: x > 0), f"must be > 0 ({name} is a length, in m)"
    if name == "g":
        return (lambda x: x >= 0), "must be >= 0 (g is the magnitude of gravity; the scene gives its direction)"
    return None


# -- messages -----------------------------------------------------------------------------------

def _error(file, field, value, problem):
    text = repr(value)
    return ValueError(f"{file}: {field} = {text if len(text) <= 80 else text[:77] + '...'} {problem}")


def suggest(word, choices):
    """" (did you mean 'x'?)" for the choice closest to a misspelt word, or ""."""
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


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
