"""The pointwise checks: every source at random states (`pointwise`) and along the book's run, the placeholders'
effect measured on load (`validate_placeholders`), and the same at random parameter sets (`random_parameters`,
drawn by `parameter_sets`)."""

import itertools

import numpy as np

from dyncheck.case import schema
from dyncheck.case.folder import SOURCES
from dyncheck.case.scene import PLACEHOLDER_INERTIA, PLACEHOLDER_MASS
from dyncheck.common import ceilings
from dyncheck.results.values import OWN_WORDS, Status, no_number, row
from dyncheck.run.simulate import at_many_states, state_columns

EPS = np.finfo(float).eps
INTEGRATED = ("reference", "book", "pinocchio")  # sources driven by scipy's DOP853


# -- pointwise ------------------------------------------------------------------

def evaluate(case, source, states, model=None):
    """Every quantity of `source` (or of `model`, a variant of it) at `states`: {quantity: array over the states}.
    Raises ArithmeticError saying which quantity at which state when the source's arithmetic fails (an overflow in
    its float arithmetic, a singular matrix) or gives a value that is not finite."""
    model = case.model(source) if model is None else model

    def each(quantity, method):
        out = []
        with np.errstate(all="ignore"):
            for i, (t, q, v) in enumerate(states):
                try:
                    out.append(method(t, q, v))
                except Exception as error:  # an overflow, a singular matrix, any error of a case's own code
                    raise ArithmeticError(f"{source}: {quantity} at random state {i}: {type(error).__name__}: "
                                          f"{error}") from None
        return out

    def accelerations():
        """All the states' in one call where the model has a many-state form (`at_many_states`), else state by
        state, so that `each` names the state where one fails."""
        acc = at_many_states(model, "accelerations", *[np.array(column) for column in zip(*states)])
        if acc is not None and np.shape(acc) == (len(states), len(case.coords)):
            return np.asarray(acc, dtype=float)
        return np.array(each("accelerations", model.accelerations), dtype=float)

    try:
        acc = accelerations()
    except (TypeError, ValueError):  # vectors of different lengths, or not numbers
        acc = np.empty(0)
    if acc.shape != (len(states), len(case.coords)):  # one number per coordinate at every state
        raise ArithmeticError(f"{source}: accelerations give {acc.shape[1:] if acc.ndim > 1 else 'no vector'} at "
                              f"the random states, not ({len(case.coords)},)")
    values = {f"{c}_acc": acc[:, i] for i, c in enumerate(case.coords)}
    reactions = each("reactions", model.reactions)
    values.update({name: np.array([r[name] for r in reactions]) for name in case.reaction_names})
    if case.scene.points:
        points = each("point accelerations", model.point_accelerations)
        for name in case.scene.points:
            for axis, label in enumerate("xyz"):
                values[f"{name}_{label}"] = np.array([p[name][axis] for p in points])
    if case.scene.dependent and hasattr(model, "dependent"):  # a closed loop's position and velocity solve
        solved = each("dependent joints", lambda t, q, v: [(f"{joint}{rate} (dependent)", by_joint[joint])
                                                            for rate, by_joint in zip(("", "_rate"), model.dependent(t, q, v))
                                                            for joint in case.scene.dependent])
        for k, (quantity, _) in enumerate(solved[0]):
            values[quantity] = np.array([float(pairs[k][1]) for pairs in solved])
    if hasattr(model, "energy"):  # optional of a derivation: its rows are then not applicable (`pointwise`)
        values["energy"] = np.array(each("energy", model.energy))
    if case.driven and hasattr(model, "drive_power"):  # optional of a derivation, as energy
        values["drive_power"] = np.array(each("drive power", model.drive_power))
    for quantity, x in values.items():
        if not np.all(np.isfinite(x)):
            raise ArithmeticError(f"{source}: {quantity} is {x[~np.isfinite(x)][0]} at random state "
                                  f"{np.argmin(np.isfinite(x))}")
    return values


def relative_error(x, y, scale=None):
    """Largest difference relative to `scale`, by default the largest magnitude of x and y over the sample."""
    if scale is None:
        scale = max(np.max(np.abs(x)), np.max(np.abs(y)))
    return float(np.max(np.abs(x - y)) / scale) if scale > 0 else 0.0


def quantity_scales(case, a, b):
    """Scales for quantities that may vanish identically, so that they are not judged by rounding
    noise: the reactions relative to the largest of them (at least the weight); a point's kinematics component-wise
    relative to the vector's largest magnitude (for an acceleration at least g); the drive power
    (zero when nothing moves the base) relative to at least the energy per second."""
    scales = {}
    # The reactions are components of forces (and moments): each is judged against the largest of its kind and
    # at least the case's force (moment) scale, so that a component that vanishes identically (the force along
    # an axis nothing loads, at constant rates) is not judged by rounding noise relative to zero.
    for quantity in ("force", "moment"):
        names = [name for name in case.reaction_names if name in a and name in b
                 and case.scene.reactions[name].quantity == quantity]
        if names:
            scale = max([case.least_reaction_scale(names[0])]
                        + [np.max(np.abs(s[name])) for s in (a, b) for name in names])
            scales.update(dict.fromkeys(names, scale))
    if "drive_power" in a and "drive_power" in b:
        energy = max([np.max(np.abs(s["energy"])) for s in (a, b) if "energy" in s], default=0.0)
        scales["drive_power"] = max(np.max(np.abs(a["drive_power"])), np.max(np.abs(b["drive_power"])),
                                    energy / 1.0)  # J per 1 s
    for name, spec in case.scene.points.items():
        parts = [f"{name}_{axis}" for axis in "xyz"]
        scale = max(np.max(np.linalg.norm(np.column_stack([s[p] for p in parts]), axis=1)) for s in (a, b))
        if spec.kind.endswith("acceleration") and "angular" not in spec.kind:
            # a base at rest: judged against g
            scale = max(scale, case.params.get("g", 0.0))
        scales.update(dict.fromkeys(parts, scale))
    return scales


def compare(case, a, b):
    """{quantity: relative error} between two sources' values at the same states, for the quantities both give."""
    scales = quantity_scales(case, a, b)
    return {quantity: relative_error(a[quantity], b[quantity], scales.get(quantity)) for quantity in a if quantity in b}


def not_defined(case, quantity, sources, lacking, method):
    """The `not applicable` row of a check of what a source's derivation does not define (energy or
    drive_power are optional)."""
    who = OWN_WORDS.get(lacking, lacking) if case.one_derivation else lacking
    needs = "" if method == "energy" else ": the work-energy balance needs the power of the dampers, applied forces " \
                                          "and prescribed motions"
    return no_number(quantity[0], quantity[1], sources, f"the {who} defines no {method}{needs}; there is nothing of "
                     "its own to check (optional, docs/model-interface.md)", Status.NOT_APPLICABLE)


PLACEHOLDER_SHARE = 0.5
"""How much MuJoCo's placeholders (Case.placeholders) may change its values at the random states, as a share of the
pointwise tolerance, at the case's parameters.  Every comparison with MuJoCo's evaluations (the pointwise, equation,
printed-row and linearisation rows) holds them negligible; beyond the tolerance a derivation would be blamed for them,
and within it they may take half, the rest left to rounding (1e-13) and to the rows that amplify them (a Floquet
monodromy matrix integrates the linearisation's error over a period: 135 times on one of the book's cases).  The
book's cases keep them below 8.9e-11; near the share every row at a case's parameters passed (measured at 4.7e-10
and 8.1e-10: docs/own-case.md).  At the random parameter sets, where nothing is measured before the run, a failing
MuJoCo row is judged again with its set's effect allowed (random_parameters)."""


def placeholders_effect(case, states, values=None):
    """How much MuJoCo's placeholders change its `values` at `states` (evaluated here where not given):
    {quantity: relative change}, as doubling them changes them (Case.approximations_doubled: they are small, so
    MuJoCo's values respond linearly); {} for a scene without any, which evaluates nothing.  Raises ArithmeticError
    where MuJoCo's arithmetic fails (evaluate)."""
    if not case.placeholders():
        return {}
    values = evaluate(case, "mujoco", states) if values is None else values
    doubled = case.approximations_doubled()
    return {**compare(case, values, evaluate(case, "mujoco", states, doubled)),
            **inertia_share(case, states, case.model("mujoco"), doubled)}


def inertia_share(case, states, model, doubled):
    """{"M[c,c]": the share of each coordinate's own inertia, MuJoCo's mass matrix's diagonal entry, that doubling
    the placeholders adds}, the largest over `states`: the placeholders' part of that inertia.  The change of a
    value that vanishes in both scenes says nothing (0 of 0), while the diagonal is positive at every state: where
    the placeholders are most of a coordinate's inertia (the cart-pendulum's bob at l = 1e-7 m, whose m l^2 =
    3e-15 kg m^2, is a third of its placeholder's 1e-14: MuJoCo puts its centre of mass at the hinge there, so that
    its theta'' is 0 with the placeholders and with them doubled, and its M[theta,theta] is the placeholder's) it is
    of the order of 1.  At the book's numbers it is at most 8.9e-11 (of an inner link's M entry); at the
    edges docs/own-case.md gives, 8.1e-10 (refused) and, beside the values' change of 4.7e-10, accepted.  Raises
    ArithmeticError as `evaluate` does."""
    with np.errstate(all="ignore"):
        try:
            diagonals = [np.array([np.diagonal(np.reshape(each.mass_matrix(t, q, v), (len(q), len(q))))
                                   for t, q, v in states]) for each in (model, doubled)]
        except Exception as error:  # MuJoCo's arithmetic, as evaluate says it
            raise ArithmeticError(f"mujoco: mass matrix: {type(error).__name__}: {error}") from None
    share = np.max(np.abs(diagonals[1] - diagonals[0]) / np.abs(diagonals[0]), axis=0)
    return {f"M[{c},{c}]": float(x) if np.isfinite(x) else np.inf for c, x in zip(case.coords, share)}


def validate_placeholders(case):
    """Refuse a case whose MuJoCo scene's placeholders are not negligible at its parameters (PLACEHOLDER_SHARE): a
    ValueError naming the case file, the overrides, the bodies and the quantity.  A case whose MuJoCo evaluation
    fails there is left to the pointwise rows, which say where."""
    # at every random state the comparisons take: the effect is far from uniform (near a folded pendulum's
    # singular mass matrix it is 50 times its size at the first five), and they cost 15 ms
    states = case.sample_states()
    try:
        effect = placeholders_effect(case, states)
    except ArithmeticError:
        return
    tolerance = case.tolerance["pointwise"]["value"]
    quantity = max(effect, key=effect.get, default=None)
    if quantity is not None and effect[quantity] > PLACEHOLDER_SHARE * tolerance:
        held = [f"{name} ({' and '.join(what for what, flag in zip(('mass', 'inertia'), pair) if flag)})"
                for name, pair in case.placeholders().items()]
        # the field: the overrides that made the bodies so light or small, or else the tolerance they are held to
        field = f"override {case.overrides_text()}" if case.overrides else f"tolerance.pointwise.value = {tolerance:g}"
        needed = effect[quantity] / PLACEHOLDER_SHARE  # a tolerance above its ceiling is refused as well
        raise ValueError(
            f"{case.origin}: {field}: MuJoCo's placeholders ({PLACEHOLDER_MASS:g} kg, {PLACEHOLDER_INERTIA:g} kg m^2, "
            f"where the scene means none: {', '.join(held)}) change its {quantity} by {effect[quantity]:.2g} of its "
            f"size at the random states, above {PLACEHOLDER_SHARE:g} of the pointwise tolerance {tolerance:g}: every "
            f"comparison with MuJoCo would blame them on a derivation. Heavier or larger bodies"
            + (f", or a [tolerance.pointwise] value of at least {needed:.2g}," if needed <= ceilings.POINTWISE else "")
            + " would do")


def pointwise(case):
    states = case.sample_states()
    values, failures = {}, {}
    for source in SOURCES:
        try:
            values[source] = evaluate(case, source, states)
        except ArithmeticError as failure:  # its comparisons fail, saying why
            failures[source] = str(failure)
    tolerance = case.tolerance["pointwise"]["value"]
    rows = []
    for a, b in itertools.combinations(SOURCES, 2):
        failed = [failures[s] for s in (a, b) if s in failures]
        if failed:
            rows.append(no_number("pointwise", "every quantity", (a, b), failed[0], Status.FAIL))
            continue
        for quantity, error in compare(case, values[a], values[b]).items():
            rows.append(row("pointwise", quantity, (a, b), error, tolerance,
                            f"{len(states)} random states", ceiling=ceilings.POINTWISE))
        for quantity in ("energy", "drive_power") if case.driven else ("energy",):
            lacking = [s for s in (a, b) if quantity not in values[s]]
            if lacking:
                rows.append(not_defined(case, ("pointwise", quantity), (a, b), lacking[0], quantity))
    return rows, {"states": states, "values": values, "failures": failures}


ALONG_RUN = 200  # states: every output row of the book's runs would cost a second of MuJoCo's reactions per case


def along_run(case, runs):
    """Reference and both engines at states the reference's tight run visits (ALONG_RUN output rows, evenly
    spaced): the pointwise comparison where the motion goes, beside the random states that span the state space.
    None where that run did not finish (its trajectory rows say why)."""
    tight = runs["reference"]
    if not tight.ok or not case.coords:  # a scene without free coordinates is a function of time alone
        return []
    n, frame = len(case.coords), tight.twin
    frame = frame.iloc[np.unique(np.linspace(0, len(frame) - 1, ALONG_RUN).round().astype(int))]
    columns = frame[state_columns(case)].to_numpy()
    states = [(float(t), x[0::2][:n], x[1::2][:n]) for t, x in zip(frame.index, columns)]
    values, rows = {}, []
    for source in ENGINES:
        try:
            values[source] = evaluate(case, source, states)
        except ArithmeticError as failure:
            values[source] = str(failure)
    tolerance = case.tolerance["pointwise"]["value"]
    for a, b in itertools.combinations(ENGINES, 2):
        failed = [values[s] for s in (a, b) if isinstance(values[s], str)]
        if failed:
            rows.append(no_number("along the run", "every quantity", (a, b), failed[0], Status.FAIL))
            continue
        errors = compare(case, values[a], values[b])
        quantity = max(errors, key=errors.get)
        rows.append(row("along the run", quantity, (a, b), errors[quantity], tolerance,
                        f"the worst of {len(errors)} quantities at the {len(states)} states of the tight "
                        "reference's run", ceiling=ceilings.POINTWISE))
    return rows


# -- random parameters ------------------------------------------------------------

ENGINES = ("reference", "mujoco", "pinocchio")  # the sources that must agree everywhere


DRAWS = 100
"""Draws per random parameter set.  The ranges are physical on their own (schema.check_values), but
beside an override they may not be (the top's Ixx with the ranges of m, h and Izz can break A + B >= C).
A draw that is not physical is drawn again (rejection): the constraints couple several parameters, so
no range can be clipped alone, and redrawing keeps the sets uniform over the physical part of the
ranges with the same test as loading (schema.check_params).  A set is given up only when its draws all
fail, which for a physical part of 5 % of the ranges happens with probability 0.95^100 = 0.6 %."""


def parameter_sets(case, count=None):
    """Seeded random parameter sets over [sample.params.ranges], physical with the user's overrides,
    which stay fixed: (sets, how many could not be drawn).  A set holds the random values only.
    `count` sets instead of the case file's `sets` (a campaign's): the first ones are the same."""
    spec = case.spec["sample"].get("params")
    if not spec:
        return [], 0
    count = spec["sets"] if count is None else count
    rng = np.random.default_rng(spec["seed"])
    ranges = {name: (case.value(lo), case.value(hi)) for name, (lo, hi) in spec["ranges"].items()
              if name not in case.overrides}
    sets = []
    for _ in range(count):
        for _ in range(DRAWS):
            drawn = {name: float(rng.uniform(lo, hi)) for name, (lo, hi) in ranges.items()}
            try:
                schema.check_params(case.spec, {**case.params, **drawn}, case.overrides, case.origin)
            except ValueError:
                continue
            if scene_breaks(case, drawn) is None:
                sets.append(drawn)
                break
    return sets, count - len(sets)


# What a binding may write of a body's mass and inertia (the schema's BINDABLE), which a drawn set can leave no rigid
# body's.
INERTIAL = ("mass", "ipos", "inertia_about_origin", "inertia", "fullinertia")


def scene_breaks(case, drawn):
    """Why the scene has no rigid bodies at the parameters `drawn` over the case's, or None: the constraints its
    bindings imply, which no bound of one parameter states.  A body whose mass, centre of mass or inertia is bound
    to parameters must keep a positive mass and, about its centre of mass, principal moments that are positive and
    satisfy the triangle inequality A + B >= C (engines.bindings.unphysical): a moment about the origin, I_o,i, leaves
    I_o,i - m (|c|^2 - c_i^2) about the centre of mass c, which a drawn mass or centre of mass (or the moment
    itself) can make impossible (a Furuta pendulum's arm with its moments about the hub bound); bound principal
    moments (inertia) or entries of the tensor (fullinertia) can break it themselves.  As the engines write them
    (MujocoModel's `_write`): a moment about the origin is the principal moment of that axis less the parallel-axis
    term and a ball joint's armature; the values no binding writes are the scene's, read from MuJoCo's model (a
    welded body's too)."""
    # here, not above: rendering saved results imports no engine module
    from engines.bindings import SceneLocation, full_tensor, parallel_axis, unphysical
    params = {**case.params, **drawn}
    bodies = {}  # name: {attribute: {index: value}}
    for binding in case.bindings:
        location = binding.location
        if location.element == "body" and location.attribute in INERTIAL:
            bodies.setdefault(location.name, {}).setdefault(location.attribute, {})[location.index] = \
                params[binding.param] * binding.scale
    if not bodies:
        return None
    model = case.model("mujoco")
    for name, written in bodies.items():
        scene = lambda attribute, i=0: model.read(SceneLocation("body", name, attribute, i))
        value = lambda attribute, i=0: written.get(attribute, {}).get(i, scene(attribute, i))
        mass, com = value("mass"), np.array([value("ipos", i) for i in range(3)])
        if not mass > 0:
            return f"body '{name}': mass {mass:.4g} kg is not positive"
        if "fullinertia" in written:  # the tensor in the body frame
            inertia = full_tensor([value("fullinertia", i) for i in range(6)])
        else:  # the principal moments, in the inertial frame
            inertia = np.diag([value("inertia", i) for i in range(3)])
        scene_com = np.array([scene("ipos", i) for i in range(3)])
        for i, about_origin in written.get("inertia_about_origin", {}).items():
            armature = (scene("inertia_about_origin", i) - scene("inertia", i)
                        - parallel_axis(scene("mass"), scene_com, i))
            inertia[i, i] = about_origin - parallel_axis(mass, com, i) - armature
        why = unphysical(name, inertia)
        if why:
            return why
    return None


def random_parameters(case):
    """Reference and both engines at each random parameter set, at that set's first `states` random
    states: one row per comparison, the worst quantity over every set.  Sets that cannot be drawn, and
    a set at which a source's arithmetic fails, are failing rows that say so."""
    sets, missing = parameter_sets(case)
    if not sets and not missing:
        return []
    spec = case.spec["sample"]["params"]
    count, seed = spec["states"], spec["seed"]
    named = lambda params: ", ".join(f"{k} = {v:.4g}" for k, v in params.items())
    rows = []
    if missing:
        rows.append(no_number("random parameters", "parameter sets", ("every source",),
                                 f"{missing} of {spec['sets']} sets (seed {seed}) not physical in {DRAWS} draws each "
                                 "(the case file's bounds and constraints, and rigid bodies in the scene: scene_breaks)"
                                 + (f" beside the overrides {named(case.overrides)}" if case.overrides else ""),
                                 Status.FAIL))
    tolerance = case.tolerance["pointwise"]["value"]
    worst = {}  # comparison -> (error beyond its tolerance, error, its tolerance, quantity, set, placeholders' effect)
    for i, params in enumerate(sets):
        try:  # a set that the constraints allow and the engines still cannot load: their reason, in the row
            other = case.with_params(**params)
            for source in ENGINES:
                other.model(source)
        except Exception as failure:  # MuJoCo's compiler, Pinocchio's reader, a binding the engine did not take
            rows.append(no_number("random parameters", "every quantity", ("every source",),
                                  f"at {named(params)}: the scene cannot be loaded there: {type(failure).__name__}: "
                                  f"{failure}", Status.FAIL))
            continue
        states = other.sample_states(count, stream=i + 1)  # each set its own states: together they cover more
        try:
            values = {source: evaluate(other, source, states) for source in ENGINES}
            errors = {(a, b): compare(other, values[a], values[b]) for a, b in itertools.combinations(ENGINES, 2)}
            # MuJoCo's placeholders, measured only where a comparison with it fails: allowed, they pass nothing
            # that passes without them
            failing = any(error > tolerance for (a, b), by in errors.items() if "mujoco" in (a, b)
                          for error in by.values())
            effect = placeholders_effect(other, states, values["mujoco"]) if failing else {}
        except ArithmeticError as failure:
            rows.append(no_number("random parameters", "every quantity", ("every source",),
                                     f"at {named(params)}: {failure}", Status.FAIL))
            continue
        for (a, b), by in errors.items():
            for quantity, error in by.items():
                allowed = effect.get(quantity, 0.0) if "mujoco" in (a, b) else 0.0
                judged = tolerance + allowed
                if error - judged >= worst.get((a, b), (-np.inf,))[0]:
                    worst[(a, b)] = (error - judged, error, judged, quantity, params, allowed)
    return rows + [row("random parameters", quantity, (a, b), error, judged,
                       f"{len(sets)} parameter sets (seed {seed}) x {count} states; worst at {named(params)}"
                       + (f", MuJoCo's placeholders' effect there {allowed:.2g} allowed" if allowed else "")
                       + (f" (overrides: {named(case.overrides)})" if case.overrides else ""),
                       ceiling=ceilings.POINTWISE)
                   for (a, b), (_, error, judged, quantity, params, allowed) in worst.items()]
