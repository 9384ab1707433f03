"""Checks: each yields rows (dyncheck.results.values.Row); `run_case` runs them all into a CaseResult."""

import itertools
import math
import re
import time
from dataclasses import replace

import numpy as np


from dyncheck.run import cache
from dyncheck.common import ceilings
from dyncheck.checks import residuals, vibration
from dyncheck.case import schema
from dyncheck.case.folder import PLACEHOLDER_INERTIA, PLACEHOLDER_MASS, SOURCES
from dyncheck.common.ceilings import ROUNDING_FLOOR
from dyncheck.common.expressions import evaluate as evaluate_expression
from dyncheck.common.expressions import namespace, of_parameters
from dyncheck.checks.localise import localise, values_at
from dyncheck.common.messages import suggest
from dyncheck.results.values import OWN_WORDS, CaseResult, Finding, Outcome, Pair, Status, no_number, row
from dyncheck.run.simulate import (ERROR_EXPONENT, Escape, Unstable, at_many_states, energy_residual, fastest_frequency,
                               richardson_factor, simulate, state_columns)
from dyncheck.checks.horizon import agreement_horizon
from dyncheck.checks.convergence import NoFrequency, convergence
from dyncheck.checks.drawings import drawings, frames, with_paths

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
    if case.scene["points"]:
        points = each("point accelerations", model.point_accelerations)
        for name in case.scene["points"]:
            for axis, label in enumerate("xyz"):
                values[f"{name}_{label}"] = np.array([p[name][axis] for p in points])
    if case.scene.get("dependent") and hasattr(model, "dependent"):  # a closed loop's position and velocity solve
        solved = each("dependent joints", lambda t, q, v: [(f"{joint}{rate} (dependent)", by_joint[joint])
                                                            for rate, by_joint in zip(("", "_rate"), model.dependent(t, q, v))
                                                            for joint in case.scene["dependent"]])
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
                 and case.scene["reactions"][name].get("quantity", "force") == quantity]
        if names:
            scale = max([case.least_reaction_scale(names[0])]
                        + [np.max(np.abs(s[name])) for s in (a, b) for name in names])
            scales.update(dict.fromkeys(names, scale))
    if "drive_power" in a and "drive_power" in b:
        energy = max([np.max(np.abs(s["energy"])) for s in (a, b) if "energy" in s], default=0.0)
        scales["drive_power"] = max(np.max(np.abs(a["drive_power"])), np.max(np.abs(b["drive_power"])),
                                    energy / 1.0)  # J per 1 s
    for name, spec in case.scene["points"].items():
        parts = [f"{name}_{axis}" for axis in "xyz"]
        scale = max(np.max(np.linalg.norm(np.column_stack([s[p] for p in parts]), axis=1)) for s in (a, b))
        if spec.get("kind", "acceleration").endswith("acceleration") and "angular" not in spec.get("kind", ""):
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


# MuJoCo's compiler refuses principal moments that break A + B >= C beyond its rounding; this much of their sum
# is taken as rounding (a flat plate's A + B = C, to a few ulps).
TRIANGLE_ROUNDING = 1e-12


def scene_breaks(case, drawn):
    """Why the scene has no rigid bodies at the parameters `drawn` over the case's, or None: the constraints its
    bindings imply, which no bound of one parameter states.  A body whose mass, centre of mass or moment of
    inertia about its origin is bound to parameters must keep a positive mass and, about its centre of mass,
    principal moments that are positive and satisfy the triangle inequality A + B >= C: a moment about the origin,
    I_o,i, leaves I_o,i - m (|c|^2 - c_i^2) about the centre of mass c, which a drawn mass or centre of mass (or
    the moment itself) can make impossible (a Furuta pendulum's arm with its moments about the hub bound).  As the
    engines write them (engines' `_write`): the moments about the origin are about the body's axes, the others
    stay as the scene gives them about the centre of mass."""
    bindings = case.spec["scene"].get("bindings", {})
    params = {**case.params, **drawn}
    bodies = {}  # name: {attribute: {index: value}}
    for param, locations in bindings.items():
        for location in locations:
            if location["element"] == "body" and location.get("attribute") in ("mass", "ipos", "inertia_about_origin"):
                bodies.setdefault(location["name"], {}).setdefault(location["attribute"], {})[
                    location.get("index", 0)] = params[param] * location.get("scale", 1.0)
    if not bodies:
        return None
    tree = {body.name: body for body in case.model("mujoco").tree()}
    for name, written in bodies.items():
        body = tree[name]
        mass = written.get("mass", {}).get(0, body.mass)
        com = np.array([written.get("ipos", {}).get(i, x) for i, x in enumerate(body.com)])
        inertia = np.array(body.inertia, dtype=float)
        for i, about_origin in written.get("inertia_about_origin", {}).items():
            inertia[i, i] = about_origin - mass * (com @ com - com[i] ** 2)
        if not mass > 0:
            return f"body '{name}': mass {mass:.4g} kg is not positive"
        moments = np.sort(np.linalg.eigvalsh(inertia))
        if not (moments[0] > 0 and moments[0] + moments[1] >= moments[2] * (1 - TRIANGLE_ROUNDING)):
            return (f"body '{name}': principal moments of inertia about its centre of mass "
                    f"{', '.join(f'{x:.4g}' for x in moments)} kg m^2 are not a rigid body's (each > 0, A + B >= C)")
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


# -- trajectories -----------------------------------------------------------------

def run_sources(case, bound=None):
    """The book's initial conditions integrated by every source, each with a tighter twin.

    Returns {source: Outcome}; the tight reference solution is the reference's twin, its outputs step ends or
    its steps capped (tight_steps).  DOP853 twins run at tight_rtol; MuJoCo's RK4 twin at dt/2, and MuJoCo's run once more with its
    scene's approximations doubled (Outcome.approximations).  A run that blew up is an
    Outcome with its failure; with `bound` (a Runaway's), a run that left it an Outcome with its Escape.
    """
    q0, v0, t_end = case.initial
    setting = case.integration
    out_step = setting["output_step"]
    runs = {}
    for source in INTEGRATED:
        options = dict(output_step=out_step, work=case.driven, omega=fastest_frequency(case), bound=bound)
        try:
            runs[source] = Outcome(simulate(case.model(source), (q0, v0), t_end, "DOP853", rtol=setting["rtol"],
                                            **options),
                                   cache.solution(case, source, (q0, v0), t_end, "DOP853", rtol=setting["tight_rtol"],
                                                  **(tight_steps(case) if source == "reference" else TWIN), **options))
        except Unstable as failure:
            runs[source] = Outcome(failure=failure.failure)
    dt = setting["mujoco_step"]
    mujoco_run = lambda model, h, **twin: simulate(model, (q0, v0), t_end, "mujoco:RK4", dt=h, output_step=out_step,
                                                   work=case.driven, bound=bound, **twin)
    model, doubled = case.model("mujoco"), case.approximations_doubled()
    try:
        run = mujoco_run(model, dt)
        # a scene without approximations is its own doubled scene, whose run would repeat this one bit for bit
        runs["mujoco"] = Outcome(run, mujoco_run(model, dt / 2, **TWIN),
                                 approximations=run if doubled is model else mujoco_run(doubled, dt, **TWIN))
    except Unstable as failure:
        runs["mujoco"] = Outcome(failure=failure.failure)
    return runs


# A twin of a source's run, and MuJoCo's run with its approximations doubled, give an error estimate of the run's
# states and energy (trajectory, energy): nothing reads their reactions.
TWIN = {"quantities": ("energy",)}


def tight_steps(case):
    """How the tight reference solution steps, so that its outputs are as good as its step ends.  DOP853 controls
    its error at the ends of its steps; an output between them comes from its dense output, a 7th-order
    interpolant outside that control, whose error grows as its step^8.  Where the motion is slower than the case's
    fastest frequency omega the controller takes longer steps, and the interpolant strays far beyond the step
    ends: two pendulums under g = 1 m/s^2 (steps up to omega h = 0.3) are off by 4.7e-11 of their largest rate at
    rtol 1e-12 (3e-12 at the step ends), 17 times the estimate trajectory() makes of it.  So either every output
    is a step's end (simulate's land_on_outputs), or the steps are capped at tight_rtol^(1/8) / omega, the step
    the controller takes at omega (simulate.ERROR_EXPONENT), where the interpolant is as good as the ends.
    Landing costs a step per output at least, the cap one per capped step: the cheaper is taken, landing where
    the outputs are no closer than the cap.  Against DOP853 at rtol 2.2e-14 with steps a quarter of the cap, the
    book's four integrated cases at rtol 1e-12 are off by 6.5e-12 to 1.1e-9 of their largest values with neither,
    and by 6e-15 to 1.6e-10 as chosen (three landed, in 2,500 to 4,900 steps where the cap takes 4,000 to 9,900;
    one capped, in 2,500 where landing takes 8,000): each at least 1,000 times below its case's runs at rtol
    1e-10 (5e-10 to 1.6e-7).  Where the cap is the shorter step it is better still (50 times, on two pendulums),
    which no check needs.
    No cap without omega."""
    omega = fastest_frequency(case)
    cap = case.integration["tight_rtol"] ** (1 / ERROR_EXPONENT["DOP853"]) / omega if omega else np.inf
    return {"land_on_outputs": True} if case.integration["output_step"] >= cap else {"max_step": cap}


def error_estimate(outcome):
    """Estimated error of `run`, per column, from its tighter twin (Richardson for RK4)."""
    return twin_factor(outcome) * (outcome.run - outcome.twin).abs()


def twin_factor(outcome):
    """What a run's difference from its twin is multiplied by to estimate the run's error: 1 for an adaptive
    twin (its error is far below the run's), Richardson's for a fixed step (simulate.richardson_factor)."""
    run, twin = outcome.run.attrs, outcome.twin.attrs
    return richardson_factor(run["method"], run["dt"], twin["dt"]) if run["dt"] else 1.0


def approximations_effect(outcome):
    """What a scene's approximations of the case's physics (MuJoCo's placeholders, the drift of its
    prescribed motions) change in its run, per column: the run with them doubled minus the run, both
    linear in them; zero for a source without them.  It is allowed as it is, not times a safety factor:
    the two runs' common integration error cancels in it, and their rounding is the floor's."""
    if outcome.approximations is None:
        return 0 * outcome.run
    return (outcome.approximations - outcome.run).abs()


def trajectory(case, runs):
    """Each source's trajectory against the tight reference solution, up to the agreement horizon
    (where the motion's sensitivity would make a comparison test chaos rather than the equations)."""
    def every_comparison(failure, status=Status.UNSTABLE):
        return [no_number("trajectory", c, (source, "tight reference"), failure, status)
                for source in ("book", "pinocchio", "mujoco") for c in state_columns(case)]

    if not runs["reference"].ok:  # nothing to compare with
        return every_comparison(runs["reference"].failure)
    horizon, why = agreement_horizon(case)
    within = slice(None, horizon)
    tight = runs["reference"].twin.loc[within]
    # Errors need time to build: a span shorter than a radian of the fastest motion (or than ten
    # output steps, where the case names no frequency) compares starts, which agree by construction.
    omega = fastest_frequency(case)
    least = 1 / omega if omega else 10 * case.integration["output_step"]
    if tight.index[-1] < least:
        return every_comparison(f"the agreement horizon {horizon:.3g} s is shorter than {least:.3g} s "
                                f"({'1/omega' if omega else 'ten output steps'}): nothing to compare; "
                                f"{why['sentence']}", Status.INCONCLUSIVE)
    # 100x tighter rtol, order 8, and its outputs as good as its step ends (tight_steps): >= 100x better
    tight_error = error_estimate(runs["reference"]).loc[within] / 100
    safety = case.tolerance["trajectory"]["safety"]
    rows = []
    for source in ("book", "pinocchio", "mujoco"):
        label = (source, "tight reference")
        outcome = runs[source]
        if not outcome.ok:
            rows += [no_number("trajectory", c, label, outcome.failure) for c in state_columns(case)]
            continue
        attrs = outcome.run.attrs
        run = outcome.run.loc[within]
        estimate = error_estimate(outcome).loc[within]
        approximations = approximations_effect(outcome).loc[within]
        method = attrs["method"] + (f" dt={attrs['dt']:g}" if attrs["dt"] else f" rtol={attrs['rtol']:g}")
        for column in state_columns(case):
            scale = tight[column].abs().max() or 1.0  # a coordinate at rest: its error in SI units
            error = (run[column] - tight[column]).abs().max() / scale
            effect = approximations[column].max() / scale
            allowed = safety * (estimate[column].max() + tight_error[column].max()) / scale + effect + ROUNDING_FLOOR
            rows.append(row("trajectory", column, label, error, allowed,
                            f"{method}, max over {min(horizon, case.initial[2]):g} s"
                            + (f", the scene's approximations' effect {effect:.2g} allowed{soft_loops(case)}"
                               if outcome.approximations is not None else "")
                            + (f"; {why['sentence']}" if math.isfinite(horizon) else ""), ceiling=ceilings.RUN))
    if runs["mujoco"].ok and case.scene["driven"]:
        # The armature holds the driven rates while MuJoCo steps: small enough a drift that its effect on the
        # motion, allowed in the rows above, is measured to first order (ceilings.DRIVEN_RATE).
        rows.append(row("trajectory", "driven rate", ("mujoco", "prescribed"),
                        runs["mujoco"].run.attrs["driven_rate_error"], ceilings.DRIVEN_RATE,
                        "max |rate - prescribed| over the run and the driven joints / largest rate of the run (at least 1)",
                        ceiling=ceilings.DRIVEN_RATE))
    return rows


def soft_loops(case):
    """What a row's "the scene's approximations' effect" holds beyond placeholders and prescribed motions."""
    return " (MuJoCo's soft loops among them: its run with their softness doubled)" if case.scene.get("dependent") else ""


def energy(case, runs):
    safety = case.tolerance["energy"]["safety"]
    quantity = "work-energy balance" if case.driven else "energy drift"
    rows = []
    for source in INTEGRATED + ("mujoco",):
        label = (source,)
        if not runs[source].ok:
            rows.append(no_number("energy", quantity, label, runs[source].failure))
            continue
        run, twin = runs[source].run, runs[source].twin
        lacking = [method for method, column in (("energy", "energy"), ("drive_power", "work")) if column not in run]
        if lacking:
            rows.append(not_defined(case, ("energy", quantity), label, source, lacking[0]))
            continue
        scale = max(run["energy"].abs().max(), run["work"].abs().max()) or 1.0  # at rest: in joules
        residual = energy_residual(run)
        estimate = (residual - energy_residual(twin)).abs().max() * twin_factor(runs[source])
        approximated = runs[source].approximations  # the scene's approximations' effect, as in `trajectory`
        effect = 0.0 if approximated is None else (energy_residual(approximated) - residual).abs().max()
        rows.append(row("energy", quantity, label, residual.abs().max() / scale,
                        safety * estimate / scale + effect / scale + ROUNDING_FLOOR,
                        f"max |E(t) - E(0) - W(t)| / max(|E|, |W|), {run.attrs['method']}"
                        + (f", the scene's approximations' effect {effect / scale:.2g} allowed{soft_loops(case)}"
                           if approximated is not None and case.scene.get("dependent") else ""), ceiling=ceilings.RUN))
    return rows


# -- physical runaway -------------------------------------------------------------

RUN_CHECKS = ("trajectory", "energy")  # the checks of run_sources' runs: a row's first source is its run's


def runaway_rows(limit, runs, rows):
    """The rows of the runs where the case's physics runs away (`limit`, a Runaway; None: `rows` as they
    are).  Every source escaped: the physics, confirmed by each independent model; their rows are runaway,
    saying why and when each escaped.  Some escaped and others not: not that physics, whichever is
    wrong; a run that stayed within the bound to its end fails, the others are unstable.  None escaped
    (a growth too slow to reach the bound within the run): the rows as they are."""
    escapes = {source: outcome.failure for source, outcome in runs.items() if isinstance(outcome.failure, Escape)}
    if limit is None or not escapes:
        return rows
    name, _, escape = limit.bound
    escaped = ", ".join(f"{source} at {failure.t:.4g} s" for source, failure in escapes.items())
    bounded = [source for source, outcome in runs.items() if outcome.ok]
    blown = [source for source, outcome in runs.items() if not outcome.ok and source not in escapes]
    summary = "; ".join([f"escaped: {escaped}"]
                        + ([f"within |{name}| <= {escape:g} to the end: {', '.join(bounded)}"] if bounded else [])
                        + ([f"blew up before escaping: {', '.join(blown)}"] if blown else []))
    out = []
    for r in rows:
        source = r.sources[0]
        if r.check not in RUN_CHECKS or source not in runs:
            out.append(r)
        elif len(escapes) == len(runs):
            out.append(replace(r, status=Status.RUNAWAY, finding=None,
                               detail=f"{limit.why}: {escapes[source]}; every source escaped ({escaped})"))
        elif not runs[source].ok:
            out.append(replace(r, status=Status.UNSTABLE, finding=None, detail=f"{runs[source].failure}; not the "
                               f"runaway the case states ({limit.why}): {summary}"))
        else:
            out.append(no_number(r.check, r.quantity, r.sources, f"{source} did not run away where the case says "
                                 f"it must ({limit.why}): {summary}", Status.FAIL))
    return out


# -- findings ---------------------------------------------------------------------

def apply_findings(case, rows):
    """A failing row that a registered finding explains is a finding; a finding that no longer fails
    fails (at the book's own parameters: overridden ones may legitimately hide an error, e.g. a
    Coriolis term at zero spin, which is then said in the row)."""
    out = []
    for r in rows:
        for finding in case.findings:
            # A finding names whole sources ("book": every comparison with it) or one comparison.
            involved = (set(r.sources) | {r.comparison}) & set(finding["sources"])
            if involved and r.quantity in finding["quantities"] and r.status in (Status.PASS, Status.FAIL):
                if r.status == Status.FAIL:
                    r = replace(r, finding=finding["id"], status=Status.FINDING)
                elif case.overrides:
                    r = replace(r, finding=finding["id"],
                                detail=f"finding {finding['id']} does not show with these parameters; " + r.detail)
                else:
                    r = replace(r, finding=finding["id"], status=Status.FAIL,
                                detail=f"registered finding {finding['id']} no longer reproduces; " + r.detail)
        out.append(r)
    return out


BOOK_ONLY = ("figure", "data")  # compared with what the book printed, for its own parameters


def book_numbers_only(case, rows):
    """Under overrides, the rows that compare with the book's printed figures and data are not applicable (the
    book printed them for its own numbers): shown, counted apart, never a failure.  Whatever the run measures
    at the overrides (the book's program run at them against the exact motion, say) stays a measured row."""
    if not case.overrides:
        return rows
    return [replace(r, status=Status.NOT_APPLICABLE, finding=None,
                    detail=f"the book printed this for its own parameters, not for {case.overrides_text()}; "
                           + r.detail)
            if r.check in BOOK_ONLY and r.status in (Status.PASS, Status.FAIL, Status.FINDING) else r for r in rows]


def data_checks(case):
    """The book's printed data against its own formulas and geometry ([[data]] in the case file):
    `printed` must equal `formula` to the printed digits, or be at most it (`relation`)."""
    rows = []
    for item in case.spec.get("data", []):
        printed, formula = case.value(item["printed"]), case.value(item["formula"])
        if item.get("relation", "equal") == "equal":
            error = abs(printed - formula) / abs(formula)
        else:  # "at most"
            error = max(printed - formula, 0.0) / abs(formula)
        rows.append(row("data", item["name"], ("book data", "book formula"), error, item["tolerance"],
                        f"{item['where']}: printed {printed:.6g}, formula {item['formula']} = {formula:.6g}",
                        ceiling=ceilings.DATA))
    return rows


def run_case(case, localise=True):
    """All checks of a case, the findings they establish and what the figures draw: a CaseResult.
    `localise`: search each finding's smallest edit of the printed expression (seconds per finding;
    what is written or saved shows it, a table of rows does not need it)."""
    start = time.perf_counter()
    rows, sample = pointwise(case)
    equations, residuals_found = residuals.equation_rows(case, sample)
    rows += equations + residuals.printed_rows(case, sample) + random_parameters(case)
    limit = case.runaway()
    runs = run_sources(case, None if limit is None else limit.bound)
    rows += trajectory(case, runs) + energy(case, runs) + along_run(case, runs)
    try:
        rows += convergence(case)
    except NoFrequency as error:  # nothing to converge on where nothing moves; a motion without omega is the case's fault
        reference = runs["reference"]
        at_rest = reference.ok and bool((reference.twin[state_columns(case)].nunique() == 1).all())
        rows.append(no_number("convergence", "every method", ("reference",),
                              f"not measured: {error}" + ("; nothing moves" if at_rest else ", yet the scene moves"),
                              Status.NOT_APPLICABLE if at_rest else Status.FAIL))
    except ValueError as error:  # a step within rounding
        rows.append(no_number("convergence", "every method", ("reference",), f"not measured: {error}", Status.FAIL))
    program_rows, program = program_checks(case, sample)
    vibrations = vibration.analyse(case)
    rows += vibrations.rows if vibrations else []
    rows = book_numbers_only(case, apply_findings(case, rows + program_rows + data_checks(case)))
    right_rows, right = right_sides(case, sample)
    rows += right_rows
    rows = runaway_rows(limit, runs, rows)  # a bounded run's failure is no finding of the book
    parameter_draws = parameter_sets(case)[0]
    localisations = residuals.localise(case, rows, residuals_found, parameter_draws)
    localisations += residuals.localise_values(case, rows, sample, parameter_draws,
                                               {loc.source for loc in localisations})
    # What the pages draw along runs: each source's run, and the reference's tight twin (report.trajectories).
    drawn = lambda source, outcome: replace(outcome, **({"twin": with_paths(case, outcome.twin)} if source == "reference"
                                                        else {"run": with_paths(case, outcome.run)}))
    runs = {source: drawn(source, outcome) if outcome.ok else outcome for source, outcome in runs.items()}
    findings = tuple(findings_of(case, rows, sample, runs, localise, right, program))
    if case.one_derivation:
        rows, localisations = in_own_words(rows), tuple(replace(loc, source=OWN_WORDS[loc.source])
                                                       for loc in localisations)
    return CaseResult(folder=str(case.folder), spec=case.spec, overrides=dict(case.overrides), rows=tuple(rows),
                      findings=findings, sample=sample, runs=runs, program=program,
                      drawings={**drawings(case, runs), "animation": frames(case, runs, program)},
                      wall=time.perf_counter() - start, localisations=localisations, vibration=vibrations)


def unfinished(case, why):
    """The result of a case whose checks could not finish (its process died or overran its budget, or its checks
    stopped on an error: dyncheck.case.isolation): one failing row that says why, and nothing else to show."""
    source = "derivation" if case.one_derivation else "reference"
    return CaseResult(folder=str(case.folder), spec=case.spec, overrides=dict(case.overrides),
                      rows=(no_number("checks", "every check", (source,), f"the checks did not finish: {why}",
                                      Status.FAIL),),
                      findings=(), sample={}, runs={}, program={}, drawings={}, wall=0.0)


def in_own_words(rows):
    """The rows of a case with one derivation (Case.one_derivation) in its own words: its Book is its
    Reference, so the rows that compare the two, or repeat a reference's row for the book, go; the book's
    run at the case's tolerance against the tight one stays, as the derivation's."""
    kept = [r for r in rows if "book" not in r.sources or r.check == "trajectory"]
    return [replace(r, sources=tuple(OWN_WORDS.get(s, s) for s in r.sources)) for r in kept]


# -- what the figures draw ------------------------------------------------------------





# -- the book's programs ------------------------------------------------------------

def program_checks(case, sample):
    """The book's printed program against its derived equations, the engines and its own figures.

    (1) its formulas at the random states, against `reference`; (2) its run against the book's
    derived equations integrated by the same integrator and step (isolates formula errors from
    integrator errors); (3) its run against the tight reference solution (the integrator's own
    error, allowed up to `safety` times the Richardson estimate of that integrator at that step);
    (4) its run inside the ranges of the book's figures; (5) what it writes out against MuJoCo at its
    own states (program_output_checks).  Returns rows and the runs.
    """
    if not case.has_program:
        return [], {}
    program = case.model("program")
    rows = program_pointwise(case, sample)
    try:
        run_rows, runs = program_run_checks(case, program)
    except (Unstable, ArithmeticError) as failure:  # the listing's integrator, or its twins, blew up
        return rows + [no_number("program", column, ("program run",), failure) for column in state_columns(case)], {}
    return rows + run_rows, runs


def program_pointwise(case, sample):
    """The program's formulas at the pointwise check's random states (`sample`), against the reference."""
    program = case.model("program")
    states, right = sample["states"], sample["values"].get("reference")
    tolerance = case.tolerance["pointwise"]["value"]
    rows = []
    try:
        if "reference" in sample["failures"]:  # the reference's evaluation failed there (pointwise)
            raise ArithmeticError(sample["failures"]["reference"])
        with np.errstate(all="ignore"):
            acc = np.array([program.accelerations(t, q, v) for t, q, v in states])
            reactions = [program.reactions(t, q, v) for t, q, v in states]
        mine = {f"{coord}_acc": acc[:, i] for i, coord in enumerate(case.coords)}
        mine.update({name: np.array([r[name] for r in reactions]) for name in program.reaction_names})
        for quantity, values in mine.items():
            rows.append(row("program", quantity, ("program", "reference"), relative_error(values, right[quantity]),
                            tolerance, f"{len(states)} random states", ceiling=ceilings.POINTWISE))
    except ArithmeticError as failure:  # an overflow in the program's or the reference's float arithmetic
        rows = [no_number("program", "every quantity", ("program", "reference"), failure, Status.FAIL)]
    return rows


def program_run_checks(case, program):
    """The program's run against the book's equations run the same way, the tight reference solution,
    the book's figures and MuJoCo at its own states (see program_checks)."""
    rows = []
    q0, v0, _ = case.initial
    every = max(1, int(round(case.integration["output_step"] / program.dt)))
    listing = with_paths(case, program.run(q0, v0).iloc[::every])
    t_end = (len(listing) - 1) * every * program.dt
    book = case.model("book")
    same = lambda q, dt, work=False, **twin: simulate(book, (q, v0), t_end, program.integrator, dt=dt,
                                                      output_step=every * program.dt, work=work, **twin)
    # Richardson's twin at half the step: a listing's step may be far from the asymptotic range (the book's explicit
    # Euler amplifies a fast spring's free oscillation by exp(omega^2 dt T / 2), twofold over 1.8.3's run), and a
    # twin at twice it would stray further, or blow up where the listing does not.  The run at the listing's step
    # carries the work of the drives, so that the pages can say how much energy the listing's integrator makes.
    twin_runs = {"same": same(q0, program.dt, work=True), "half": same(q0, program.dt / 2, quantities=())}
    # Rounding: the same run from a start moved by a few ulps shows how the motion amplifies them.
    twin_runs["nudged"] = same(q0 + 4 * EPS * np.maximum(np.abs(q0), 1.0), program.dt, quantities=())
    tight = with_paths(case, cache.solution(case, "reference", (q0, v0), t_end, "DOP853",
                                            rtol=case.integration["tight_rtol"], output_step=every * program.dt,
                                            work=False, omega=fastest_frequency(case)))
    safety = case.tolerance["trajectory"]["safety"]
    label = f"{program.integrator}, dt = {program.dt:.4g} s, {t_end:.4g} s"
    for column in state_columns(case):
        x = listing[column].to_numpy()
        scale = np.max(np.abs(tight[column])) or 1.0  # a coordinate at rest: its error in SI units
        rounding = np.max(np.abs(twin_runs["same"][column] - twin_runs["nudged"][column])) / scale
        rows.append(row("program", column, ("program", "book equations, same integrator"),
                        np.max(np.abs(x - twin_runs["same"][column].to_numpy())) / scale,
                        safety * rounding + ROUNDING_FLOOR, label, ceiling=ceilings.RUN))
        # Does the listing draw the right curve?  Judged at a figure's resolution; whether its
        # integrator or its formulas stray shows beside it: the scheme's own error at its step, by
        # Richardson, while its steps are in the asymptotic range.
        integrator = richardson_factor(program.integrator, program.dt, program.dt / 2) * np.max(
            np.abs(twin_runs["same"][column] - twin_runs["half"][column])) / scale
        rows.append(row("program", column, ("program", "tight reference"),
                        np.max(np.abs(x - tight[column].to_numpy())) / scale, ceilings.LISTING,
                        f"{label}; its integrator's own error at this step, by Richardson: {integrator:.2g}",
                        ceiling=ceilings.LISTING))
    for name, figure in case.spec.get("program", {}).get("figures", {}).items():
        lo, hi = figure["range"]
        for source, run in (("program", listing), ("tight reference", tight)):
            values = evaluate_expression(figure["expression"], namespace(case, run))
            outside = max(lo - np.min(values), np.max(values) - hi, 0.0) / (hi - lo)
            rows.append(row("figure", name, (source, "book figure"), outside, ceilings.FIGURE,
                            f"{figure['where']}: range [{lo:g}, {hi:g}]; run [{np.min(values):.4g}, {np.max(values):.4g}]",
                            ceiling=ceilings.FIGURE))
    rows += program_output_checks(case, listing)
    return rows, {"listing": listing, "same integrator": twin_runs["same"], "tight": tight,
                  "integrator": program.integrator, "dt": program.dt}


OUTPUT_ROWS = 200  # the program's output rows compared with MuJoCo: evenly over its run, ends included


def program_output_checks(case, listing):
    """What the program writes out (its figures' positions, its reactions) against MuJoCo at the same
    states: each column of [program.outputs] against its expression of MuJoCo's values at that row's
    (t, q, v), at up to OUTPUT_ROWS of the program's own rows.  At the same state both evaluate closed
    forms (the listing's formula, MuJoCo's kinematics or dynamics) in doubles, so the pointwise
    tolerance, argued for the same kind of evaluation, applies; a wrong sign, axis or term is of the
    order of the value itself.  The difference is relative to the largest value of either side and at
    least a scale, as the pointwise check's: for a position the scene's size (the farthest body origin
    or traced centre of mass from the world origin over these rows), so that a coordinate that stays
    zero (the plane's normal) is not judged by rounding noise; for a reaction the case's force scale."""
    outputs = case.spec.get("program", {}).get("outputs", {})
    if not outputs:
        return []
    chosen = np.unique(np.linspace(0, len(listing) - 1, min(OUTPUT_ROWS, len(listing))).round().astype(int))
    rows_at = listing.iloc[chosen]
    model = case.model("mujoco")
    states = list(zip(rows_at.index, rows_at[list(case.coords)].to_numpy(),
                      rows_at[[f"{c}_rate" for c in case.coords]].to_numpy()))
    # The engine's values only: the program's own columns (R, x, ...) must not shadow them.
    names = of_parameters(case.params)
    points = [model.points(t, q) for t, q, _ in states]  # traced centres of mass, body origins
    paths = np.array([traced for traced, _, _ in points])  # (row, body, xyz)
    names.update({f"{body}_{axis}": paths[:, b, i]
                  for b, body in enumerate(case.scene["paths"]) for i, axis in enumerate("xyz")})
    size = max(np.max(np.linalg.norm(np.vstack([traced, origins]), axis=1)) for traced, origins, _ in points)
    reactions = [model.reactions(t, q, v) for t, q, v in states]
    names.update({name: np.array([r[name] for r in reactions]) for name in case.reaction_names})
    force_scale = case.value(case.tolerance["pointwise"]["force_scale"])
    rows = []
    for column, expression in outputs.items():
        if column not in listing:
            rows.append(no_number("program", column, ("program", "mujoco at the program's states"),
                                  f"{case.origin}: program.outputs.{column}: the program writes no column '{column}'"
                                  f"{suggest(column, listing.columns)}", Status.FAIL))
            continue
        engine = np.broadcast_to(evaluate_expression(expression, names), len(states))
        printed = rows_at[column].to_numpy()
        floor = force_scale if set(re.findall(r"[A-Za-z_]\w*", expression)) & set(case.reaction_names) else size
        scale = max(np.max(np.abs(printed)), np.max(np.abs(engine)), floor)
        at = int(np.argmax(np.abs(printed - engine)))
        rows.append(row("program", column, ("program", "mujoco at the program's states"),
                        relative_error(printed, engine, scale), case.tolerance["pointwise"]["value"],
                        f"{len(states)} of the program's rows; {column} = {expression}; largest difference at "
                        f"t = {rows_at.index[at]:.4g} s: program {printed[at]:.6g}, MuJoCo {engine[at]:.6g} "
                        f"(scale {scale:.3g})", ceiling=ceilings.POINTWISE))
    return rows


def finding_effect(case, finding, runs):
    """What a finding changes in the book's own results: for an error of its equations, its reactions
    in newtons and its energy balance in joules along its run; otherwise the case file's `effect`."""
    if "book" not in finding["sources"] or not all(runs[s].ok for s in ("book", "reference")):
        return account(case, finding, "effect") if finding.get("effect") else ""
    book, tight = runs["book"].run, runs["reference"].twin
    parts = [f"the book's {q} is off by up to {(book[q] - tight[q]).abs().max():.3g} N"
             f" (|{q}| up to {tight[q].abs().max():.3g} N)"
             for q in finding["quantities"] if q in case.reaction_names]
    if "work-energy balance" in finding["quantities"]:
        parts.append(f"its work-energy balance misses by up to {energy_residual(book).abs().max():.3g} J")
    return (f"Over the book's run ({case.initial[2]:g} s from the book's initial conditions), "
            + "; ".join(parts) + ".") if parts else ""


# How a page under overrides marks a finding's explanation and effect: what the case file says of the book's numbers.
BOOK_ACCOUNT = "At the book's numbers (the case file's account; a number it computes from the parameters is this run's)"


def account(case, finding, field):
    """A finding's text from the case file, its `{= formulas}` at these parameters; under overrides
    marked as the case file's account of the book's numbers (the measured error is this run's, and so is what the
    finding's `measured` text says)."""
    where = f"findings[{case.findings.index(finding)}].{field}"
    text = " ".join(case.prose(finding[field], where).split())
    return f"*{BOOK_ACCOUNT}:* {text}" if case.overrides else text


def measured_account(case, finding):
    """A finding's `measured` text, its `{= formulas}` at these parameters and its `{~ measures}` left for the pages
    to write from the saved results (dyncheck.results.measured): never marked, every number in it this run's."""
    field = f"findings[{case.findings.index(finding)}].measured"
    return " ".join(case.prose(finding.get("measured", ""), field).split())


def finding_source(case, finding):
    """The model a finding's printed expressions belong to: the book's derived equations, or its program."""
    return case.model("program" if any("program" in s for s in finding["sources"]) else "book")


def components(key, values):
    """A printed vector's components as the checks name them in `values`: a_eq110_x, ... or Rx, ..."""
    for names in ([f"{key}_{axis}" for axis in "xyz"], [f"{key}{axis}" for axis in "xyz"]):
        if all(n in values for n in names):
            return names
    return [key]


def localise_finding(case, finding, sample):
    """The smallest edit of the book's printed expression that explains `finding` (dyncheck.checks.localise), in
    words, and the pairs (printed, edited expression) of the quantities it explains."""
    book = finding_source(case, finding)
    printed = getattr(book, "PRINTED", {})
    if "mujoco" in sample["failures"]:
        return f"not searched: MuJoCo's values at the random states failed ({sample['failures']['mujoco']})", ()
    engine = sample["values"]["mujoco"]
    quantities = [k for k in printed if set(components(k, engine)) & set(finding["quantities"])
                  and all(n in engine for n in components(k, engine))]
    if not quantities:
        return ("not searched: the book's module declares no printed expression of the engines' values for "
                + ", ".join(finding["quantities"])), ()
    parts, pairs = [], []
    for quantity in quantities:
        names = components(quantity, engine)
        target = engine[names[0]] if len(names) == 1 else np.column_stack([engine[n] for n in names])
        namespaces = [book.symbols(t, q, v) for t, q, v in sample["states"]]
        found, tried, printed_error = localise(printed[quantity], namespaces, target,
                                               case.tolerance["pointwise"]["value"])
        if found:
            parts.append(f"{quantity}: " + "; or ".join(f"{label} (then off by {err:.1e})" for label, err, _ in found)
                         + f" [{tried} edits tried; as printed off by {printed_error:.2g}]")
            label, err, edited = found[0]
            pairs.append(Pair(printed[quantity], edited, "the book's expression, the code that runs",
                              f"the localised edit: {label} (then off by {err:.1e} from MuJoCo at the random states)",
                              quantity, getattr(book, "LATEX", {})))
        else:
            parts.append(f"{quantity}: none of the {tried} searched edits (single and pairs) explains it"
                         f" (as printed off by {printed_error:.2g})")
    return "; ".join(parts), tuple(pairs)


def right_sides(case, sample):
    """Each finding's `right` expressions (case file) at the random states against the reference, a row
    each: the right side the errata typeset is proven, not retyped.  The target is the reference's value
    of the quantity, or 0 for a printed row (right side minus left side, which is 0 when the row holds)."""
    rows, pairs = [], {}
    for i, finding in enumerate(case.findings):
        if not finding.get("right"):
            continue
        model = finding_source(case, finding)
        printed = getattr(model, "PRINTED", {})
        for key, expression in finding["right"].items():
            if key not in printed:
                raise ValueError(f"{case.folder / 'case.toml'}: findings[{i}].right: '{key}' is not a printed "
                                 f"expression of the book's module{suggest(key, printed)}")
            sources = ("finding's right", "reference")
            if "reference" in sample["failures"]:
                rows.append(no_number("pointwise", key, sources, sample["failures"]["reference"], Status.FAIL))
                continue
            reference = sample["values"]["reference"]
            names = components(key, reference)
            namespaces = [model.symbols(t, q, v) for t, q, v in sample["states"]]
            right, book = values_at(expression, namespaces), values_at(printed[key], namespaces)
            of_reference = all(n in reference for n in names)
            target = (np.column_stack([reference[n] for n in names]).reshape(right.shape) if of_reference
                      else np.zeros_like(right))
            scale = max(np.max(np.abs(target)), np.max(np.abs(book))) or 1.0
            rows.append(row("pointwise", key, sources, relative_error(right, target, scale),
                            case.tolerance["pointwise"]["value"], f"finding {finding['id']}: {key} = {expression}, "
                            f"at {len(namespaces)} random states, relative to the larger of the printed and the "
                            f"reference's largest magnitude ({scale:.3g})", ceiling=ceilings.POINTWISE))
            pairs.setdefault(finding["id"], []).append(
                Pair(printed[key], expression, "the book's expression, the code that runs", "the case file's right "
                     "expression, checked against the reference at the random states", key if of_reference else "0",
                     getattr(model, "LATEX", {})))
    return rows, pairs


def value_pairs(case, finding, program):
    """The book's values against the right ones, for a finding of its data, its figures or its program's
    integrator: the printed datum against its formula, a figure's axis against the exact motion's range,
    the listing's run against the exact motion at the end of the run."""
    pairs = []
    for item in case.spec.get("data", []):
        if item["name"] in finding["quantities"] and "book data vs book formula" in finding["sources"]:
            valued = lambda expression: (expression if re.fullmatch(r"[\d.e+-]+", expression)
                                         else f"{expression} == {case.value(expression):.6g}")
            bound = "" if item.get("relation", "equal") == "equal" else ", the most the printed value may be"
            pairs.append(Pair(valued(item["printed"]), valued(item["formula"]), f"printed ({item['where']})",
                              f"the book's formula at the case's parameters{bound}"))
    if not program:
        return pairs
    figures = case.spec.get("program", {}).get("figures", {})
    for name, figure in figures.items():
        if name in finding["quantities"] and any("book figure" in s for s in finding["sources"]):
            lo, hi = figure["range"]
            values = evaluate_expression(figure["expression"], namespace(case, program["tight"]))
            pairs.append(Pair(f"{lo:g} <= {figure['expression']} <= {hi:g}",
                              f"{np.min(values):.4g} <= {figure['expression']} <= {np.max(values):.4g}",
                              f"the figure's axis ({figure['where']})",
                              "the exact motion (the reference integrated tightly) over the book's run"))
    columns = [q for q in finding["quantities"] if q in program["listing"].columns]
    if columns and "program vs tight reference" in finding["sources"]:
        end = program["listing"].index[-1]
        at = lambda run: ", ".join(f"{run[c].iloc[-1]:.4g}" for c in columns)
        pairs.append(Pair(f"array([{at(program['listing'])}])", f"array([{at(program['tight'])}])",
                          f"the listing's run ({program['integrator']} at dt = {program['dt']:.4g} s) at "
                          f"t = {end:.4g} s", f"the exact motion at t = {end:.4g} s",
                          f"array([{', '.join(columns)}])", getattr(case.model("book"), "LATEX", {})))
    return pairs


def findings_of(case, rows, sample, runs, localise=True, right=None, program=None):
    """The case's registered findings with their measured size, where and how established, and effect;
    with their book-vs-right pairs: the localised edits, the case file's checked `right` ({id: pairs},
    right_sides), or the values `program` (program_checks' runs) and the case's data give."""
    engines = [r.error for r in rows if r.check == "pointwise" and set(r.sources) <= set(ENGINES)]
    out = []
    for finding in case.findings:
        errors = [r.error for r in rows if r.finding == finding["id"] and r.error is not None]
        localised, pairs = localise_finding(case, finding, sample) if localise else (
            "not searched in this run (`dyncheck run` searches with --json or --results)", ())
        pairs += tuple((right or {}).get(finding["id"], ())) + tuple(value_pairs(case, finding, program))
        out.append(Finding(
            id=finding["id"], title=finding["title"], where=finding["where"],
            quantities=tuple(finding["quantities"]), sources=tuple(finding["sources"]),
            error=max(errors, default=None), explanation=account(case, finding, "explanation"),
            established=f"reference, MuJoCo and Pinocchio agree with each other to {max(engines, default=0):.1e} "
                        f"at {len(sample['states'])} random states",
            effect=finding_effect(case, finding, runs), localised=localised, pairs=pairs,
            measured=measured_account(case, finding)))
    return out
