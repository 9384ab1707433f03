"""A case from two files: a researcher's scene.xml (MJCF) and equations.py, a plain module that imports
nothing from dyncheck.  `Equations` puts the module behind the model interface; `case_file` derives the
case file that the module and the scene imply (coordinates, units, bindings, time scales, tolerances),
over which a case.toml, where there is one, says more.  docs/own-case.md is the guide."""

import math

import numpy as np

from dyncheck.case.coordinate_map import parse
from dyncheck.case.start import displaced, initial_q, unsettled
from dyncheck.common import expressions
from dyncheck.common.messages import WithBlock, suggest

EQUATIONS = "equations.py"
SCENE = "scene.xml"
OPTIONAL = ("drive_power", "mass_matrix", "forces", "energy", "dependent")  # Equations' only where the module has them
# A parameter binds to a scene number equal to it, or to minus it where a sign is a direction (a position,
# gravity), to within the decimal text's rounding: the MJCF's text and the module's float of one number.
MATCH_RTOL = 4 * np.finfo(float).eps
SIGNED = {"pos", "ipos", None}  # the attributes (None: gravity) a parameter may bind to with scale -1
UNITS = {"mass": "kg", "pos": "m", "ipos": "m", "inertia_about_origin": "kg m^2", "inertia": "kg m^2",
         "fullinertia": "kg m^2", None: "m/s^2",
         ("stiffness", "slide"): "N/m", ("stiffness", "hinge"): "N m/rad",
         ("damping", "slide"): "N s/m", ("damping", "hinge"): "N m s/rad",
         ("springref", "slide"): "m", ("springref", "hinge"): "rad"}
JOINT_ATTRIBUTES = ("stiffness", "damping", "springref")  # whose unit depends on the joint's kind
ABOUT = {"mass": "mass of body '{name}'", "pos": "position of body '{name}' in its parent, component {index}",
         "ipos": "centre of mass of body '{name}', component {index}", None: "gravity, component {index}",
         "inertia_about_origin": "moment of inertia of body '{name}' about its origin, axis {index}",
         "inertia": "principal moment of inertia of body '{name}' about its centre of mass, axis {index}",
         "fullinertia": "inertia of body '{name}' about its centre of mass, i{index} in the body frame",
         "stiffness": "stiffness of joint '{name}'", "damping": "viscous damping of joint '{name}'",
         "springref": "rest position of joint '{name}''s spring"}
AXES = "xyz"


def component(location):
    """The name of a location's component (engines.bindings.SceneLocation) in ABOUT: an axis, or a fullinertia's
    entry (xx ... yz)."""
    from engines.bindings import FULL_INERTIA  # here, not above: rendering saved results imports no engine module
    index = location.index
    return "".join(AXES[i] for i in FULL_INERTIA[index]) if location.attribute == "fullinertia" else AXES[index]

DIVISORS = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)  # of an output step into MuJoCo's steps: 1-2-5 steps
# States of the pointwise check: a region of 5 % of the state space holds about 13 of 256 evenly spread states
# (Case.sample_states), where a derivation wrong only there must fail; 256 evaluations of the slowest
# derivations known (a generated 7-dof inverse dynamics, 2-6 ms each) take about a second.
SAMPLE_COUNT = 256
# and more where a state's evaluations are cheap (Case.sample_count): as many as fit a quarter of a second, a fraction
# of the run's own few seconds (with both engines' evaluations: the tutorial's 0.17 ms a state, 1024; the forced
# cart-pendulum's 0.33 ms, 512; the slider-crank's loop, 2 ms, 256)
SAMPLE_BUDGET = 0.25  # s


def is_plain(module):
    """Whether a derivation is a plain module (COORDS, PARAMS, accelerations or inverse_dynamics) rather than
    classes."""
    return hasattr(module, "COORDS") and (callable(getattr(module, "accelerations", None)) or by_inverse_dynamics(module))


def by_inverse_dynamics(module):
    """Whether a plain module gives its equations as inverse dynamics, inverse_dynamics(t, q, v, a, p): the
    generalised forces tau = M a - f that the accelerations a need (the form generated code comes in), and no
    accelerations of its own."""
    return callable(getattr(module, "inverse_dynamics", None)) and not callable(getattr(module, "accelerations", None))


# numpy's kinds of real numbers: float, signed and unsigned integer.  Not bool, nor complex (numpy would drop the
# imaginary part, even a nonzero one, with only a warning), nor str ("1.0" read as 1.0), nor object.
REAL_KINDS = "fiu"


def real(values, shape, function):
    """What a module's `function` returned, as a float array of `shape`; ValueError saying which function
    returned what otherwise.  On every right-hand side: one dtype and one shape test of the array numpy makes."""
    try:
        array = np.asarray(values)
    except ValueError as error:  # a ragged list
        raise ValueError(f"{function} returned {values!r:.80}: {error}") from None
    if array.dtype.kind not in REAL_KINDS or array.shape != shape:
        raise ValueError(f"{function} returned {values!r:.80} (numpy dtype {array.dtype}, shape {array.shape}), not "
                         f"real numbers of shape {shape}")
    return array.astype(float, copy=False)


class Equations:
    """A plain equations module at one parameter set, behind the model interface (docs/model-interface.md):
    each function f(t, q, v, p) becomes a method f(t, q, v); those of OPTIONAL only where the module has them
    (mass_matrix(q, p) and a closed loop's dependent(q, v, p) become mass_matrix(t, q, v), dependent(t, q, v)).
    What each returns must be real numbers of its shape (`real`): ValueError naming the function otherwise."""

    def __init__(self, module, params, reaction_names):
        self.coords, self.reaction_names = tuple(module.COORDS), tuple(reaction_names)
        self._module, self._p = module, params
        self._vector, self._matrix = (len(self.coords),), (len(self.coords),) * 2
        for name in OPTIONAL:
            if callable(getattr(module, name, None)):
                setattr(self, name, getattr(self, "_" + name))
        if by_inverse_dynamics(module):  # q'' = M^-1 f, M and f from it (where the module gives no M or f of its own)
            self.accelerations = lambda t, q, v: np.linalg.solve(*self._by_inverse_dynamics(t, q, v))
            if not hasattr(self, "mass_matrix"):
                self.mass_matrix = lambda t, q, v: self._by_inverse_dynamics(t, q, v)[0]
            if not hasattr(self, "forces"):
                self.forces = lambda t, q, v: self._by_inverse_dynamics(t, q, v)[1]

    def accelerations(self, t, q, v):
        return real(self._module.accelerations(t, q, v, self._p), self._vector, "accelerations(t, q, v, p)")

    def _inverse_dynamics(self, t, q, v, a):
        return real(self._module.inverse_dynamics(t, q, v, a, self._p), self._vector, "inverse_dynamics(t, q, v, a, p)")

    def _by_inverse_dynamics(self, t, q, v):
        """(M, f) of M q'' = f from the module's inverse dynamics tau(a) = M a - f, which is linear in a: f = -tau(0),
        and M's column j = (tau(s e_j) + f) / s, with s a power of two that makes |M s| at least |f|, so that the
        difference keeps M's digits (a stiff spring's f is 1e9 times M): M to a few eps of |M|, in n + 1 calls (2n + 1
        where f outweighs M)."""
        n = len(self.coords)
        f = -self._inverse_dynamics(t, q, v, np.zeros(n))
        columns = lambda s: np.column_stack([(self._inverse_dynamics(t, q, v, s * e) + f) / s for e in np.eye(n)])
        mass = columns(1.0)
        ratio = np.max(np.abs(f)) / np.max(np.abs(mass)) if np.max(np.abs(mass)) > 0 else 0.0
        if np.isfinite(ratio) and ratio > 1:
            mass = columns(2.0 ** math.ceil(math.log2(ratio)))
        return mass, f

    def reactions(self, t, q, v):
        if not self.reaction_names:
            return {}
        return {name: float(real(value, (), f"reactions(t, q, v, p)['{name}']"))
                for name, value in dict(self._module.reactions(t, q, v, self._p)).items()}

    def _energy(self, t, q, v):
        return float(real(self._module.energy(t, q, v, self._p), (), "energy(t, q, v, p)"))

    def _drive_power(self, t, q, v):
        return float(real(self._module.drive_power(t, q, v, self._p), (), "drive_power(t, q, v, p)"))

    def _mass_matrix(self, t, q, v):
        return real(self._module.mass_matrix(q, self._p), self._matrix, "mass_matrix(q, p)")

    def _dependent(self, t, q, v):
        positions, rates = self._module.dependent(q, v, self._p)
        return dict(positions), dict(rates)

    def _forces(self, t, q, v):
        return real(self._module.forces(t, q, v, self._p), self._vector, "forces(t, q, v, p)")


class Checked:
    """A class of a case's own code, each answer checked as a plain module's are (`real`): a complex q'' (numpy would
    drop even a nonzero imaginary part, with only a warning), a string or a wrong shape fails its row, naming the
    method, instead of being read as a number.  Its methods that this does not check (printed_rows, dependent) and
    its attributes are the class's own."""

    def __init__(self, model, n):
        self._model = model
        shapes = {"accelerations": (n,), "forces": (n,), "mass_matrix": (n, n), "energy": (), "drive_power": ()}
        for name, shape in shapes.items():
            if callable(getattr(model, name, None)):
                setattr(self, name, self._checking(getattr(model, name), name, shape))
        for name, shape in (("reactions", ()), ("point_accelerations", (3,))):
            if callable(getattr(model, name, None)):
                setattr(self, name, self._checking_each(getattr(model, name), name, shape))

    @staticmethod
    def _checking(method, name, shape):
        if shape == ():
            return lambda t, q, v: float(real(method(t, q, v), shape, f"{name}(t, q, v)"))
        return lambda t, q, v: real(method(t, q, v), shape, f"{name}(t, q, v)")

    @staticmethod
    def _checking_each(method, name, shape):
        as_value = float if shape == () else lambda array: array
        return lambda t, q, v: {key: as_value(real(value, shape, f"{name}(t, q, v)[{key!r}]"))
                                for key, value in dict(method(t, q, v)).items()}

    def __getattr__(self, name):
        return getattr(self._model, name)


def module_values(module, file):
    """COORDS and PARAMS of a plain module, checked: ValueError naming the file and the name."""
    coords, params = getattr(module, "COORDS", None), getattr(module, "PARAMS", None)
    if not (isinstance(coords, (list, tuple)) and coords and all(isinstance(c, str) and c.isidentifier() for c in coords)):
        raise ValueError(f"{file}: COORDS = {coords!r} is not a list of coordinate names (identifiers)")
    if len(set(coords)) != len(coords):
        raise ValueError(f"{file}: COORDS = {list(coords)!r} names a coordinate twice")
    if not isinstance(params, dict) or not all(isinstance(k, str) and k.isidentifier() for k in params):
        raise ValueError(f"{file}: PARAMS = {params!r} is not a dict of parameter names (identifiers) to values")
    for name, value in params.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ValueError(f"{file}: PARAMS['{name}'] = {value!r} is not a finite number (SI units)")
    for name in OPTIONAL + ("accelerations", "inverse_dynamics", "reactions"):
        if hasattr(module, name) and not callable(getattr(module, name)):
            raise ValueError(f"{file}: {name} is not a function")
    return tuple(coords), {name: float(value) for name, value in params.items()}


def declared_units(module, params, file):
    """The module's UNITS, {parameter: unit}: optional, the units of some parameters, which tell a mass from a length
    of the same value; ValueError naming the file and the entry where it names no parameter or no unit of a scene
    number."""
    declared = getattr(module, "UNITS", {})
    known = sorted(set(UNITS.values()))
    if not isinstance(declared, dict):
        raise ValueError(f"{file}: UNITS = {declared!r:.80} is not a dict of parameter names to units")
    for name, unit in declared.items():
        if name not in params:
            raise ValueError(f"{file}: UNITS[{name!r}] names no parameter of PARAMS")
        if unit not in known:
            raise ValueError(f"{file}: UNITS[{name!r}] = {unit!r:.40} is not a unit of a scene number: one of "
                             + ", ".join(known))
    return dict(declared)


def coordinate_joints(coords, scene, file):
    """{coordinate: joint}: by name, or, where no coordinate is named after a joint, the scene's hinges and
    slides in the file's order when there are as many as coordinates.  In a scene with closed loops the
    coordinates name some of the joints, the independent ones: the loops close the others (case.toml's [scene] dependent)."""
    scalar = [j for j in scene.joints if j.kind in ("hinge", "slide")]
    other = [j for j in scene.joints if j.kind not in ("hinge", "slide")]
    if other:
        raise ValueError(f"{scene.path}: joint '{other[0].name}' is a {other[0].kind} joint; a case without a "
                         "case.toml takes hinges and slides only (a ball joint's Euler angles go in case.toml's "
                         "[scene.euler], docs/case-file.md)")
    names = [j.name for j in scalar]
    if set(coords) == set(names):
        return {c: c for c in coords}
    if not set(coords) & set(names) and len(coords) == len(names):
        return dict(zip(coords, names))
    missing = [c for c in coords if c not in names]
    if not missing and scene.loops:  # the engines check that the loops leave as many degrees of freedom
        return {c: c for c in coords}
    if not missing:  # fewer coordinates than joints, no loop: the others would sit locked
        others = [n for n in names if n not in coords]
        raise ValueError(f"{file}: COORDS {list(coords)} leave joints of {scene.path} without a coordinate "
                         f"({', '.join(others)}); every hinge and slide is a coordinate, unless a closed loop "
                         "(an <equality> <connect>) moves it")
    raise ValueError(f"{file}: COORDS {list(coords)} do not match the joints of {scene.path} ({', '.join(names)}): "
                     f"coordinate '{missing[0]}' is no joint{suggest(missing[0], names)}; name each coordinate after "
                     "its joint, or give as many coordinates as hinges and slides, in the file's order")


def mapped_joints(module, coords, params, scene, file, given):
    """The module's JOINTS (or a case.toml's `[scene.joints]`, `given`), {joint: expression of COORDS}, in the
    scene's order, and each coordinate's unit: optional, each hinge and slide of the scene as an affine function of
    the coordinates (dyncheck.case.coordinate_map), where the derivation's coordinates are not the joints' (absolute
    angles over a chain's relative hinges); (None, None) without it.  ValueError naming the file and the entry."""
    declared = getattr(module, "JOINTS", None) if given is None else given
    if declared is None:
        return None, None
    named = f"{file}: JOINTS" if given is None else f"{file.parent / 'case.toml'}: scene.joints"
    names = [j.name for j in scene.joints if j.kind in ("hinge", "slide")]
    if not (isinstance(declared, dict) and all(isinstance(x, (str, int, float)) for x in declared.values())):
        raise ValueError(f"{named} = {declared!r:.80} is not a dict of the scene's joints to expressions of "
                         "COORDS (\"phi2 - phi1\")")
    for joint in declared:
        if joint not in names:
            raise ValueError(f"{named}[{joint!r}] is no hinge or slide of {scene.path} ({', '.join(names)})"
                             + suggest(str(joint), names))
    if [n for n in names if n not in declared] or len(scene.joints) > len(names):
        others = [j.name for j in scene.joints if j.name not in declared]
        raise ValueError(f"{named} leaves joints of {scene.path} without a position ({', '.join(others)}): "
                         "a map of the coordinates gives every joint, and takes hinges and slides only")
    mapped = {joint: str(declared[joint]) for joint in names}
    parse(mapped, coords, params, named)  # refused here, in the file's words, not at the case's load
    kinds = {j.name: j.kind for j in scene.joints}
    units = []  # each coordinate's: rad where it moves hinges, m where it moves slides
    for c in coords:
        moved = {kinds[joint] for joint, x in mapped.items() if c in expressions.names(x)}
        if len(moved) > 1:
            raise ValueError(f"{named} moves both hinges and slides by coordinate '{c}': an angle and a length are "
                             "not one coordinate")
        units.append("rad" if moved == {"hinge"} else "m")
    return mapped, units


def applied_parameters(params, given, file):
    """The parameters that case.toml's [scene.applied] forces use: they reach the engines through those
    forces, not the scene, so they bind to no scene number; each needs its unit in case.toml's [params]."""
    try:
        used = {name for force in given.get("scene", {}).get("applied", {}).values() for x in force
                if isinstance(x, str) for name in expressions.names(x)}
    except ValueError as error:
        raise ValueError(f"{file}: case.toml's scene.applied: {error}") from None
    for p in used & set(params):
        if not isinstance(given.get("params", {}).get(p, {}).get("unit"), str):
            raise ValueError(f"{file}: PARAMS['{p}'] is used by case.toml's [scene.applied] forces, not by the scene: "
                             f"say its unit in case.toml, [params.{p}] unit = \"N\" (or what it is)")
    return used & set(params)


def bindings(params, scene, joints_kind, file, given, declared=None):
    """{parameter: [binding table]}, {parameter: unit} and {parameter: the location of its first binding}: each
    parameter bound where `given` (a case.toml's [scene.bindings]) says, or else to the one scene number equal to it
    (or to minus it for a position or gravity) whose unit is the one `declared` ({parameter: unit}, the module's
    UNITS, where it gives one).  Every parameter that matches no number or several is refused in one message, with a
    [scene.bindings] block to complete."""
    from engines.bindings import SceneLocation  # here, not above: rendering saved results imports no engine module
    found, units, places, unbound, ambiguous = {}, {}, {}, [], {}
    unit = lambda location: UNITS[(location.attribute, joints_kind.get(location.name))
                                  if location.attribute in JOINT_ATTRIBUTES else location.attribute]
    declared = declared or {}
    for name, value in params.items():
        if name in given:
            found[name], places[name] = given[name], SceneLocation.of(given[name][0])
            units[name] = unit(places[name])
            continue
        matches = [(v.location, scale)
                   for v in scene.values for scale in ((1.0, -1.0) if v.location.attribute in SIGNED else (1.0,))
                   if value != 0 and abs(v.value - scale * value) <= MATCH_RTOL * abs(value)
                   and declared.get(name, unit(v.location)) == unit(v.location)]
        if len(matches) == 1:
            found[name], units[name], places[name] = [binding_table(*matches[0])], unit(matches[0][0]), matches[0][0]
        elif matches:
            ambiguous[name] = matches
        else:
            unbound.append(name)
    if unbound or ambiguous:
        raise binding_refusal(file, scene, params, unbound, ambiguous, unit, declared)
    return found, units, places


def binding_table(location, scale):
    """A [scene.bindings] table: the parameter times `scale` at `location` (an engines.bindings.SceneLocation)."""
    return {**location.table(), **({"scale": scale} if scale != 1.0 else {})}


def binding_refusal(file, scene, params, unbound, ambiguous, unit, declared):
    """The refusal of the parameters that bind to no scene number or to several (`ambiguous`: {parameter:
    [(location, scale)]}): each named on one line, and a [scene.bindings] block for a case.toml beside the module, a
    line a parameter (the first of several candidates, the others in its comment; where there is none, a commented
    template)."""
    where = lambda location, scale: f"{location.text()}{' x -1' if scale < 0 else ''} ({unit(location)})"
    as_toml = lambda match: "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in binding_table(*match).items()) + " }"
    unit_of = lambda name: f" in {declared[name]}" if name in declared else ""
    problems = [f"PARAMS['{name}'] = {params[name]!r} matches {len(found)} numbers{unit_of(name)}: "
                + ", ".join(where(*match) for match in found) for name, found in ambiguous.items()]
    problems += [f"PARAMS['{name}'] = {params[name]!r} is no number{unit_of(name)} of the scene (a body's mass, "
                 "position, centre of mass or principal inertia about it, a joint's stiffness, damping or spring rest "
                 "position, gravity)"
                 for name in unbound]
    verb = "does not bind" if len(problems) == 1 else "do not each bind"
    message = (f"{file}: {len(problems)} of PARAMS' values {verb} to one number of {scene.path}, so the "
               f"engines cannot follow them: {'; '.join(problems)}.  Write a case.toml beside it with the table below "
               "(docs/own-case.md), keeping the location each parameter means (the others are in its comment); or "
               "give the scene numbers that tell them apart, or the module a UNITS = {name: unit}")
    block = ["[scene.bindings]"]
    block += [f"{name} = [{as_toml(found[0])}]  # or: " + "; ".join(as_toml(match) for match in found[1:])
              for name, found in ambiguous.items()]
    block += [f'# {name} = [{{ element = "body", name = "...", attribute = "mass" }}]  # no number of the scene is '
              f"{params[name]!r}: write where it goes" for name in unbound]
    return WithBlock(message, "\n".join(block))


def nice(x):
    """x rounded down to 1, 2 or 5 times a power of ten: steps and horizons that read well."""
    power = 10.0 ** math.floor(math.log10(x))
    return next(m * power for m in (5, 2, 1) if m * power <= x * (1 + 1e-12))


def frequency(module, coords, params, q0, v0):
    """The case's fastest frequency, rad/s, from the derivation's own linearisation at the initial state:
    the square root of the largest |eigenvalue| of d q''/d q (central differences); at least 1 rad/s, so
    that a scene with no restoring force (a free slide) still gets a horizon of seconds."""
    h, n = 1e-6, len(coords)
    equations = Equations(module, params, ())
    jacobian = np.empty((n, n))
    for j in range(n):
        step = np.eye(n)[j] * h
        plus, minus = (equations.accelerations(0.0, q, v0) for q in (q0 + step, q0 - step))
        jacobian[:, j] = (plus - minus) / (2 * h)
    largest = float(np.max(np.abs(np.linalg.eigvals(jacobian)))) if np.all(np.isfinite(jacobian)) else 1.0
    return max(math.sqrt(largest), 1.0)


def reaction_sensors(names, scene, file):
    """[scene.reactions] for reactions named <sensor>_<x|y|z> after a force sensor (a force) or a torque sensor (a
    moment about the body's origin): that sensor's component, in its body's frame; or named <loop>_<x|y|z> after
    a <connect>: its force on its body1 at the anchor, in world axes (engines.loops)."""
    out = {}
    sensors = {**{s: (body, "force") for s, body in scene.force_sensors.items()},
               **{s: (body, "moment") for s, body in scene.torque_sensors.items()},
               **{loop: (body, "loop") for loop, body in scene.loops.items()}}
    for name in names:
        sensor, _, axis = name.rpartition("_")
        if sensor not in sensors or axis not in AXES:
            raise ValueError(f"{file}: reaction '{name}' is not named <sensor>_<x|y|z> after a <force> or <torque> "
                             f"sensor or a <connect> of {scene.path} ({', '.join(sensors) or 'none'}); name it so, or "
                             "say which sensor it reads in a case.toml [scene.reactions] (docs/case-file.md)")
        body, quantity = sensors[sensor]
        out[name] = {"body": body, "sensor": sensor, "axis": AXES.index(axis),
                     **({"frame": "world", "quantity": "force"} if quantity == "loop" else
                        {"frame": "body", "quantity": quantity})}
    return out


def case_file(folder, module, scene, given, overrides=None):
    """The case file that `module` (a plain equations module) and `scene` (engines.mjcf.SceneFile) imply,
    with `given` (a case.toml's tables, or {}) over it: what a case file says, it says.  Its time scales
    (horizon, steps, the studies' settings) come from the fastest frequency at the parameters with `overrides`
    (a stiffer spring: a faster motion, shorter steps); its parameters' values stay the module's."""
    where = given.get("derivation", EQUATIONS)  # a case.toml may name another .py file of the folder
    file = folder / where
    coords, params = module_values(module, file)
    mapped, units = mapped_joints(module, coords, params, scene, file, given.get("scene", {}).get("joints"))
    joints = {} if mapped else coordinate_joints(coords, scene, file)
    dependent = [] if mapped else [j.name for j in scene.joints if j.name not in joints.values()]  # closed by loops
    kinds = {j.name: j.kind for j in scene.joints}
    units = units or ["rad" if kinds[joints[c]] == "hinge" else "m" for c in coords]
    given_bindings = given.get("scene", {}).get("bindings", {})
    forcing = applied_parameters(params, given, file) - set(given_bindings)
    bound, param_units, places = bindings({p: x for p, x in params.items() if p not in forcing}, scene, kinds,
                                          file, given_bindings, declared_units(module, params, file))
    for p in forcing:
        param_units[p] = given["params"][p]["unit"]
    length = max(scene.length, 0.1)
    at_params = {**params, **numbers(overrides or {}, params)}
    start, equilibrium = (None, None) if "q" in given.get("initial", {}) else \
        initial_q(Equations(module, at_params, ()), units, length)
    initial = {"q": None if start is None else start.tolist(), "v": [0.0] * len(coords), **given.get("initial", {})}
    number = lambda x: float(expressions.evaluate(x, expressions.of_parameters(params)) if isinstance(x, str) else x)
    try:
        q0, v0 = (np.array([number(x) for x in initial[key]]) for key in ("q", "v"))
    except (TypeError, ValueError) as error:
        raise ValueError(f"{file}: case.toml's initial state {initial}: {error}") from None
    if q0.shape != (len(coords),) or v0.shape != (len(coords),):
        raise ValueError(f"{file}: case.toml's initial q and v must have one value per coordinate ({', '.join(coords)})")
    try:
        with np.errstate(all="ignore"):
            omega = frequency(module, coords, at_params, q0, v0)
            reactions = sorted(module.reactions(0.0, q0, v0, params)) if hasattr(module, "reactions") else []
    except Exception as error:  # the derivation's own error, as the checks would report it: refused here
        raise ValueError(f"{file}: at the initial state q = {q0.tolist()}, v = {v0.tolist()}: "
                         f"{type(error).__name__}: {error}") from None
    period = 2 * math.pi / omega
    output_step = nice(period / 100)
    t_end = round(math.ceil(3 * period / output_step) * output_step, 12)  # three periods, on an output
    # MuJoCo's RK4 at omega dt <= 0.01: error ~(omega dt)^5 / 120 ~ 1e-12 per step
    substeps = next(d for d in DIVISORS if output_step / d * omega <= 0.01)
    ranges = {j.name: j.range for j in scene.joints}
    # The states span the state space a derivation must hold in (docs/own-case.md): an angle's whole turn (or its
    # joint's range); a slide without a range three quarters of the scene's size either way, which keeps a
    # slide along a rod of that length (a spring's extension) a quarter of it from the hinge, where M(q)
    # vanishes; rates of four times the fastest frequency (a whole turn's rate, over the top, is about twice
    # it); times over four horizons (a law of time beyond the runs' is checked too).
    span = lambda c, unit: list(ranges[joints[c]]) if c in joints and ranges[joints[c]] else (
        [-math.pi, math.pi] if unit == "rad" else [-0.75 * length, 0.75 * length])
    rate = lambda unit: 4 * omega * (1.0 if unit == "rad" else length)
    gravity = next((p for p, location in places.items() if location.element == "option"), None)
    masses = [p for p, location in places.items() if location.attribute == "mass"]
    weight = (f"({' + '.join(masses)})" if masses else f"{sum(scene.masses.values()):.6g}") + \
        (f" * abs({gravity})" if gravity else " * 9.81")
    derived = {
        "name": folder.name,
        "title": docstring_parts(module.__doc__ or folder.name)[0].rstrip("."),
        "summary": docstring_parts(module.__doc__)[1],
        "derivation": where,
        "coords": list(coords),
        "reactions": reactions,
        "coord_units": units,
        "params": {p: {"value": value, "unit": param_units[p],
                       "about": "in the applied forces (`scene.applied` of case.toml)" if p in forcing else
                       ABOUT[places[p].attribute].format(name=places[p].name, index=component(places[p]))}
                   for p, value in params.items()},  # every other parameter is bound (bindings refuses the rest)
        "initial": {"q": q0.tolist(), "v": v0.tolist(), "t_end": t_end},
        "sample": {"count": SAMPLE_COUNT, "budget": SAMPLE_BUDGET, "seed": 1, "t": [0.0, 4 * t_end],
                   "q": [span(c, u) for c, u in zip(coords, units)], "v": [[-rate(u), rate(u)] for u in units],
                   "params": {"sets": 8, "states": 20, "seed": 2,
                              "ranges": {p: sorted([0.5 * v, 2.0 * v]) for p, v in params.items()}}},
        "integration": {"output_step": output_step, "rtol": 1e-10, "tight_rtol": 1e-12,
                        "mujoco_step": output_step / substeps},
        "tolerance": {
            "pointwise": {"value": 1e-9, "force_scale": weight, "moment_scale": f"{weight} * {length:.6g}",
                          "why": "The derivation's and the engines' rounding (1e-13 or so of each quantity's size)"
                                 + (f", and the placeholder inertias (at most 1e-14 kg m^2) of the point mass"
                                    f"{'es' * (len(scene.point_masses) > 1)} {', '.join(scene.point_masses)}, which "
                                    "the derivation leaves out"
                                    if scene.point_masses else "") + ": far below 1e-9."},
            "trajectory": {"safety": 10.0, "why": "Ten times each run's own error estimate."},
            "energy": {"safety": 10.0, "why": "Ten times each balance's own error estimate."}},
        "report": {"modelling": f"{SCENE} as written, read by MuJoCo and by Pinocchio; {where} the derivation"
                                + ("" if given else "; no case.toml")
                                + ("" if not mapped else f"; the derivation in coordinates of its own, the joints at "
                                   + ", ".join(f"{j} = {x}" for j, x in mapped.items()))
                                + ("" if start is None else f"; {unsettled(units, length, start)}"
                                   if equilibrium is None else f"; the runs start {displaced(units, length)}, from "
                                   f"the stable equilibrium at rest, q = {(np.round(equilibrium, 6) + 0.0).tolist()}")},
        "scene": {"coords": joints, **({"joints": mapped} if mapped else {}), "driven": {}, "reactions": reaction_sensors(reactions, scene, file),
                  "bindings": bound, **({"dependent": dependent} if dependent else {})},
        "work_precision": work_precision(omega),
    }
    return merged(derived, given)


def numbers(overrides, params):
    """The overrides of the module's parameters that are numbers (Case checks them all, and says so, after)."""
    out = {}
    for name, value in overrides.items():
        try:
            out[name] = float(value)
        except (TypeError, ValueError):
            continue
    return {name: x for name, x in out.items() if name in params and math.isfinite(x)}


def docstring_parts(docstring):
    """The page's title and opening text from the module's docstring: its first sentence (a summary line, or a
    sentence wrapped over the lines up to one that ends it, within the first paragraph), joined; then the rest as
    written (or the title again, where there is none)."""
    lines = (docstring or "").strip().splitlines() or [""]
    ends = next((i for i, line in enumerate(lines) if not line.strip() or line.rstrip().endswith(".")), len(lines))
    end = ends + 1 if ends < len(lines) and lines[ends].strip() else max(ends, 1)
    title = " ".join(line.strip() for line in lines[:end])
    return title, "\n".join(lines[end:]).strip() or title


def work_precision(omega):
    """The studies' settings from the case's fastest frequency: two periods, the fixed steps from a
    twentieth of a period down by halves, the tolerances of the adaptive methods over their useful range."""
    period = 2 * math.pi / omega
    output_step = nice(period / 20)
    steps = lambda *divisors: [output_step / d for d in divisors]
    return {"t_end": 40 * output_step, "output_step": output_step, "repeat": 3, "repeat_under": 0.25,
            "why": f"Derived from the fastest frequency omega = {omega:.4g} rad/s of the derivation's linearisation "
                   "at the initial state: two periods, the fixed steps omega h from about 0.3 down by halves.",
            "solution": {"rtol": 1e-13, "max_step": output_step / 4},
            "sweep": {"reference": {"RK45": [1e-4, 1e-6, 1e-8], "DOP853": [1e-4, 1e-6, 1e-8, 1e-10, 1e-12],
                                    "explicit Euler": steps(8, 16, 32, 64), "semi-implicit Euler": steps(8, 16, 32, 64),
                                    "RK4": steps(1, 2, 4, 8)},
                      "pinocchio": {"DOP853": [1e-4, 1e-6, 1e-8, 1e-10, 1e-12]},
                      "mujoco": {"mujoco:Euler": steps(8, 16, 32, 64), "mujoco:RK4": steps(1, 2, 4, 8)}},
            "convergence": {"omega": omega, "omega_t": 3, "why": "omega h = 0.01 for the Eulers, 0.04 for RK4.",
                            "omega_h": {"explicit Euler": 0.01, "semi-implicit Euler": 0.01, "RK4": 0.04,
                                        "mujoco:Euler": 0.01, "mujoco:RK4": 0.04}}}


def merged(derived, given):
    """`derived` with `given` over it, table by table: a case.toml's value replaces the derived one."""
    out = dict(derived)
    for key, value in given.items():
        out[key] = merged(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


def toml_value(x):
    """A number or a string as TOML writes it."""
    return f'"{x}"' if isinstance(x, str) else repr(x)
