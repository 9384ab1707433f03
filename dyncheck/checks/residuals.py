"""The derivation's equations of motion one by one against the engines', and the term a wrong one lacks.

At a state, the residual of equation i is r_i = (M_e (q''_d - q''_e))_i: M_e the engine's mass matrix in
the case's coordinates, q''_d the derivation's accelerations, q''_e the engine's.  It is the generalised
force by which the derivation's equation i, written M q'' = f, differs from the engine's: where the
derivation's M is right, r_i = f_d,i - f_e,i exactly, so a term missing from equation i shows in r_i and
in no other (the accelerations, coupled through M^-1, all go wrong together).  Where the derivation also
gives M and f (mass_matrix, forces), they are compared with the engine's directly.

A failing equation is then localised: its residual, over random states and random parameter sets, is
fitted by a few terms of a library built from the derivation's own symbols (dyncheck.checks.terms), naming the
term to add to its force side (or to its acceleration as written, or to that acceleration's Cramer
numerator; or to a given M entry) with its coefficient as a product of the parameters.  A reaction
that fails while the equations hold is fitted the same way.  The book's printed Newton and Euler rows
are checked here too, each with MuJoCo's accelerations and reactions put in (printed_rows).
"""

from dataclasses import dataclass, fields

import numpy as np

from dyncheck.checks import terms
from dyncheck.common import ceilings
from dyncheck.results.values import Localisation, Status, no_number, row

ENGINES = ("mujoco", "pinocchio")
CHECK = "equation"


def derivation_sources(case):
    """The sources whose equations are under test: the book's and the reference's, or a researcher's one
    derivation (Case.one_derivation)."""
    return ("reference",) if case.one_derivation else ("reference", "book")


def quantity(coordinate):
    return f"{coordinate} residual"


@dataclass(frozen=True)
class Residuals:
    """One derivation against one engine at some states: the engine's mass matrices M_e and accelerations
    q''_e, the derivation's accelerations q''_d, and the derivation's own M and f where it gives them
    (None where not)."""
    t: np.ndarray  # (N,)
    q: np.ndarray  # (N, n)
    v: np.ndarray
    mass: np.ndarray  # (N, n, n)
    engine_acc: np.ndarray  # (N, n)
    derived_acc: np.ndarray
    given_mass: np.ndarray | None
    given_forces: np.ndarray | None

    def first(self, count):
        """These residuals at the first `count` states only."""
        cut = lambda array: None if array is None else array[:count]
        return Residuals(*(cut(getattr(self, field.name)) for field in fields(self)))

    @property
    def engine_forces(self):
        """f_e = M_e q''_e, the engine's generalised forces."""
        return np.einsum("nij,nj->ni", self.mass, self.engine_acc)

    @property
    def derivation_forces(self):
        """M_e q''_d: the derivation's accelerations in the engine's form."""
        return np.einsum("nij,nj->ni", self.mass, self.derived_acc)

    def of(self, place):
        """The residual at `place`, over the states, and the size it is judged against:
        ("residual", i) equation i's, M_e (q''_d - q''_e); ("f", i) its given force side's, f_d - f_e;
        ("M", i, j) a given mass matrix entry's, M_d - M_e; ("acceleration", i) q''_d - q''_e, the
        residual of a derivation that writes each acceleration as an expression; ("numerator", i)
        det(M_e) (q''_d - q''_e), of one that solves M q'' = f by Cramer's rule, q''_i = N_i / det M."""
        kind, i, *j = place
        if kind == "M":
            return self.given_mass[:, i, j[0]] - self.mass[:, i, j[0]], np.max(np.abs(self.mass))
        if kind in ("acceleration", "numerator"):
            factor = np.linalg.det(self.mass) if kind == "numerator" else np.ones(len(self.t))
            mine, theirs = factor * self.derived_acc[:, i], factor * self.engine_acc[:, i]
            return mine - theirs, max(np.max(np.abs(mine)), np.max(np.abs(theirs)))
        mine = (self.derivation_forces if kind == "residual" else self.given_forces)[:, i]
        theirs = self.engine_forces[:, i]
        summed = [self.terms(self.engine_acc, i)] + ([self.terms(self.derived_acc, i)] if kind == "residual" else [])
        return mine - theirs, max([np.max(np.abs(mine)), np.max(np.abs(theirs))] + [np.max(each) for each in summed])

    def terms(self, acc, i):
        """sum_j |M_e,ij q''_j| over the states: the size of the terms that equation i sums, the scale of its
        residual's rounding.  An accelerations vector solved from M q'' = f in a backward-stable way satisfies
        (M + dM) q'' = f with |dM| <= c n eps |M| entry by entry, so M q'' - f, and M_e q''_d - M_e q''_e with the
        entries of M_e and M_d apart by their rounding, is a few n eps of this sum in row i whatever cond(M): the
        residual judged against it is rounding-limited to ~1e-15 where its own force vanishes (g = 0: the
        cart-pendulum's theta force is 0, its M q'' terms 1 N m each) or is the small difference of large terms (a
        spring of 1e9 N/m: 7.5e6 N m in the theta row that cancel to 1.5; its MuJoCo placeholder inertia of 1e-14
        kg m^2 times theta'' = 1e8 rad/s^2 adds 1e-6 N m, 1.3e-13 of the terms).  It is at least the force itself,
        |f_i| = |sum_j M_ij q''_j|, so nothing judged against the force passes more easily by more than the terms'
        cancellation."""
        return np.sum(np.abs(self.mass[:, i, :] * acc), axis=1)


# Where a wrong equation's terms are looked for, in order, and what the terms are added to: its force
# side in the engine's form, its acceleration as the derivation may write it, or the numerator of that
# acceleration solved by Cramer's rule.  The first whose fit names parameter products is reported.
FORMS = (("residual", "its force side f (M q'' = f)"), ("acceleration", "its acceleration {c}''"),
         ("numerator", "the numerator N of its acceleration {c}'' = N / det M"))


def residuals(case, source, engine, states, derived_acc=None, engine_acc=None):
    """Residuals of `source`'s equations against `engine`'s at `states`; the accelerations may be given
    (the pointwise check has them)."""
    model, derivation = case.model(engine), case.model(source)
    n = len(case.coords)
    with np.errstate(all="ignore"):
        each = lambda method: np.array([method(t, q, v) for t, q, v in states], dtype=float)
        mass = each(model.mass_matrix).reshape(len(states), n, n)
        a_e = each(model.accelerations) if engine_acc is None else engine_acc
        a_d = each(derivation.accelerations) if derived_acc is None else derived_acc
        given_mass = each(derivation.mass_matrix).reshape(mass.shape) if hasattr(derivation, "mass_matrix") else None
        given_forces = each(derivation.forces).reshape(a_e.shape) if hasattr(derivation, "forces") else None
    return Residuals(np.array([t for t, _, _ in states]), np.array([q for _, q, _ in states]),
                     np.array([v for _, _, v in states]), mass, np.asarray(a_e, dtype=float).reshape(-1, n),
                     np.asarray(a_d, dtype=float).reshape(-1, n), given_mass, given_forces)


def accelerations_of(values, case):
    return np.column_stack([values[f"{c}_acc"] for c in case.coords]).reshape(-1, len(case.coords))


def places(case, r):
    """(row quantity, place, what its row says) of every comparison that residuals `r` allow: each
    equation's residual; each entry of a given M (both triangles: a derivation's M may be asymmetric,
    which is itself an error); each given force side."""
    coords, out = case.coords, []
    out += [(quantity(c), ("residual", i), "M_e (q''_d - q''_e), relative to the largest sum of its terms' sizes, "
             "sum_j |M_e,ij q''_j|") for i, c in enumerate(coords)]
    if r.given_mass is not None:
        out += [(f"M[{a},{b}]", ("M", i, j), "mass matrix entry, relative to the engine's largest entry")
                for i, a in enumerate(coords) for j, b in enumerate(coords)]
    if r.given_forces is not None:
        out += [(f"f[{a}]", ("f", i), "force side against M_e q''_e, relative to the larger of its largest and of "
                 "sum_j |M_e,ij q''_e,j|") for i, a in enumerate(coords)]
    return out


def equation_rows(case, sample):
    """One row per equation, derivation and engine: its residual relative to the size of its generalised
    forces, to the pointwise tolerance; and the derivation's own M and f where it gives them."""
    if not case.coords:
        return [], {}
    states, values, failures = sample["states"], sample["values"], sample["failures"]
    tolerance = case.tolerance["pointwise"]["value"]
    rows, found = [], {}
    for source in derivation_sources(case):
        for engine in ENGINES:
            failed = [failures[s] for s in (source, engine) if s in failures]
            if failed:
                rows.append(no_number(CHECK, "every equation", (source, engine), failed[0], Status.FAIL))
                continue
            try:
                found[source, engine] = r = residuals(case, source, engine, states, accelerations_of(values[source], case),
                                                      accelerations_of(values[engine], case))
            except Exception as error:  # a singular matrix, or any error of a derivation's own mass_matrix or forces
                rows.append(no_number(CHECK, "every equation", (source, engine), f"{type(error).__name__}: {error}",
                                      Status.FAIL))
                continue
            for name, place, what in places(case, r):
                residual, scale = r.of(place)
                error = float(np.max(np.abs(residual)) / scale) if scale > 0 else 0.0
                rows.append(row(CHECK, name, (source, engine), error, tolerance, f"{what}, at {len(states)} random states",
                                ceiling=ceilings.POINTWISE))
    return rows, found


def localise(case, rows, found, drawn):
    """For each comparison of a derivation's equations that fails against MuJoCo, the terms that explain it
    (dyncheck.checks.terms), fitted over the pointwise states at the case's parameters and at its random parameter
    sets `drawn` (dyncheck.checks.runs.parameter_sets): a given mass matrix entry or force side where those
    fail, else the equation's residual (which a wrong M spoils: it is then M's error times q'')."""
    failing = {(r.sources[0], r.quantity) for r in rows
               if r.check == CHECK and r.sources[1] == "mujoco" and r.status == Status.FAIL
               and (r.sources[0], "mujoco") in found}  # not where a source gave no numbers: its row says why
    if not failing:
        return ()
    try:
        return _localised(case, failing, found, drawn)
    except Exception as error:  # whatever the search meets (a MemoryError, a set's arithmetic), the rows stay
        out = []
        for source, name in sorted(failing):
            place = {name: place for name, place, _ in places(case, found[source, "mujoco"])}[name]
            out.append(not_localised(case, source, place, name, found[source, "mujoco"], 1, error))
        return tuple(out)


def not_localised(case, source, place, name, r, sets, error):
    """The Localisation of the comparison `name` at `place` whose term search raised `error`: where, and why."""
    kind, i, *_ = place
    return Localisation(source=source, equation=case.coords[i], place=_place(case, kind, i, name),
                        text=f"not localised: the term search failed ({type(error).__name__}: {error})",
                        exact=False, identified=False, residual=float(np.max(np.abs(r.of(place)[0]))), left=0.0,
                        sets=sets)


def _localised(case, failing, found, drawn):
    """localise's Localisations of the comparisons `failing`, {(source, row quantity)}."""
    others = parameter_cases(case, drawn)
    units = case.spec["coord_units"]
    driven = driven_units(case)
    out = []
    for source in sorted({s for s, _ in failing}):
        fitted = case.spec["sample"]["count"]  # the states a term search is sized for (terms.MEMORY), not all
        samples = [(dict(case.params), case, found[source, "mujoco"].first(fitted))]
        for other in others[1:]:
            try:
                samples.append((dict(other.params), other, residuals(other, source, "mujoco",
                                                                    other.sample_states(fitted))))
            except Exception:  # a set where a source fails: the random-parameters rows say so
                continue
        named = {name: place for name, place, _ in places(case, samples[0][2])}
        shifted = shifted_residuals(case, source, samples[0][2])
        wrong = [(name, named[name]) for s, name in sorted(failing) if s == source and name in named]
        # the coordinates whose given M or f is wrong: their residual is explained there, not refitted
        explained = {i for _, place in wrong if place[0] != "residual" for i in place[1:]}
        for name, place in wrong:
            kind, i, *_ = place
            if kind == "residual" and i in explained:
                continue
            forms = FORMS if kind == "residual" else [(kind, "it" if kind == "M" else "its force side f (M q'' = f)")]
            fits = []
            try:
                for form, where in forms:
                    fit = fit_at(case, samples, (form, *place[1:]), units, driven,
                                 cyclic_angles(case, samples[0][2], shifted, (form, *place[1:])))
                    if fit is not None:
                        fits.append((fit, where.format(c=case.coords[i])))
                        if fit.identified or fit.unsearched:  # the other forms' libraries are as large
                            break
            except Exception as error:  # a MemoryError, say: this equation's rows and the others' localisations stay
                if not fits:
                    out.append(not_localised(case, source, place, name, samples[0][2], len(samples), error))
                    continue
            if not fits:  # a source's arithmetic failed at every set: its rows say where
                continue
            # the first that names parameter products, else the first exact, else the force side's closest
            fit, where = next((f for f in fits if f[0].identified), next((f for f in fits if f[0].exact), fits[0]))
            text, identified = fit.says(where), fit.identified
            if fit.exact and not fit.terms:  # this equation's acceleration is right: M_e couples it to a wrong one
                text = (f"{where} agrees with the engines (to {fit.before:.1e}): this equation's residual comes "
                        "through the mass matrix from another acceleration's error")
                identified = False
            out.append(Localisation(source=source, equation=case.coords[i], place=_place(case, kind, i, name),
                                    text=text, exact=fit.exact, identified=identified,
                                    residual=fit.before, left=fit.left, sets=fit.sets))
    return tuple(out)


def _place(case, kind, i, name):
    """Where a Localisation is: "equation x" (its residual or force side), or the mass matrix entry "M[x,theta]"."""
    return f"equation {case.coords[i]}" if kind != "M" else name


def fit_at(case, samples, place, units, driven, cyclic=()):
    """The terms that explain the residual at `place` over the sets `samples` ((params, case, Residuals));
    None where no set gives finite residuals.  A derivation that gives its accelerations only may have its
    mass matrix wrong: in its force side's residual, dM q''_d, the terms in its accelerations are candidates."""
    in_accelerations = place[0] == "residual" and samples[0][2].given_mass is None
    fitted = [(params, with_driven(other, r.t, r.q, r.v), r.v, *r.of(place), r.derived_acc, r)
              for params, other, r in samples]
    finite = [f for f in fitted if np.all(np.isfinite(f[3]))]
    usable = [(params, q, v, residual, a if in_accelerations else None) for params, q, v, residual, _, a, _ in finite]
    if not usable:
        return None
    floor = case.tolerance["pointwise"]["value"] * fitted[0][4]
    fit = terms.fit(case.coords, units, list(case.params), usable, floor, driven, cyclic)
    if in_accelerations and fit.exact and whole_equation(case, fit, usable[0], finite[0][6], place[1], driven):
        fit = terms.fit(case.coords, units, list(case.params), [u[:4] for u in usable], floor, driven, cyclic)
    return fit


# The share of an equation's inertia terms M_e,i q''_d by which a fit's terms in the accelerations may miss them all
# and still be the whole equation: a wrong entry of M leaves the others' terms, of the same order as the row.
WHOLE = 1e-6


def whole_equation(case, fit, sample, r, i, driven):
    """Whether the fit's terms in the accelerations are all of equation i's inertia terms, -M_e,i q''_d: then
    they and its force terms are the engine's whole equation, which fits the residual M_e,i q''_d - f_e,i of ANY
    wrong accelerations (with few terms, as a 2-dof row has), and name nothing."""
    params, q, v, _, a = sample
    index = {name: k for k, name in enumerate(list(case.coords) + [name for name, _ in driven])}
    in_accelerations = [term for term in fit.terms if any(f.function == "acceleration" for f in term.state)]
    if not in_accelerations:
        return False
    inertia = np.einsum("nj,nj->n", r.mass[:, i, :], a)
    missed = inertia + sum(term.value(params, q, v, a, index) for term in in_accelerations)
    return bool(np.max(np.abs(missed)) <= WHOLE * np.max(np.abs(inertia)))


SHIFT = 1.0  # rad: not a divisor of 2 pi, so that no term of the library (periods 2 pi and pi) is unchanged by it
SHIFTED_STATES = 32  # random states: a residual that depends on the angle changes at nearly all of them


def shifted_residuals(case, source, r):
    """{angle: the residuals at SHIFTED_STATES of the states of `r`, that angle shifted by SHIFT}, for
    cyclic_angles; an angle where the derivation fails is left out (its rows say so; it stays a candidate)."""
    first = r.first(SHIFTED_STATES)
    out = {}
    for i, (name, unit) in enumerate(zip(case.coords, case.spec["coord_units"])):
        if unit != "rad":
            continue
        q = first.q.copy()
        q[:, i] += SHIFT
        try:
            out[name] = residuals(case, source, "mujoco", list(zip(first.t, q, first.v)))
        except Exception:
            continue
    return out


def cyclic_angles(case, r, shifted, place):
    """The angles that the residual at `place` does not depend on (a Furuta pendulum's arm, a free chain's first
    link): shifted (shifted_residuals), it stays within the pointwise tolerance of its size; terms in them are not
    candidates (they could only fit rounding)."""
    first = r.first(SHIFTED_STATES)
    residual, size = first.of(place)
    tolerance = case.tolerance["pointwise"]["value"] * size
    return tuple(name for name, moved in shifted.items() if np.max(np.abs(moved.of(place)[0] - residual)) <= tolerance)


def parameter_cases(case, drawn):
    """The case itself, then the case at each random parameter set `drawn` (dyncheck.checks.runs.parameter_sets:
    random values of the parameters that are not overridden), over which a residual is fitted."""
    return [case] + [case.with_params(**values) for values in drawn]


def driven_units(case):
    """(joint, unit) of each prescribed motion, and (law, terms.FORCE) of each component of an applied force
    that is a law of time and state: candidates of the fit as functions of time (dyncheck.checks.terms), the law
    in the case file's words, "(F0 * cos(Omega * t))"."""
    kinds = {body.joint: body.joint_type for body in case.model("mujoco").tree()}
    return tuple((joint, "rad" if kinds[joint] == "hinge" else "m") for joint in case.scene.driven) + tuple(
        (f"({law})", terms.FORCE) for force in case.scene.applied.values() if not force.constant
        for law in force.components)


def with_driven(case, t, q, v):
    """The states' coordinates q and, after them, the prescribed motions' positions at the states' times t
    and the varying applied forces' components there (driven_units): the terms of a scene on a driven base
    depend on its angle, alpha0 + alpha_rate t; a derivation may lack a push F0 cos(Omega t)."""
    motions = [law.at(t) for law in case.scene.driven.values()]
    forces = [np.array([force(ti, qi, vi) for ti, qi, vi in zip(np.broadcast_to(t, len(q)), q, v)]).T
              for force in case.scene.applied.values() if not force.constant]
    return np.column_stack([q, *motions, *[row for force in forces for row in force]]) if motions or forces else q


PRINTED_ROWS = "printed row"
# The reactions and accelerations put into a printed row carry rounding of a few 1e-16 of the case's
# largest terms (measured: 2.9e-16 in a row that vanishes, the particle's X3 at alpha' = 0); judged against
# 1e-4 of those, such a row stays 100 times below the pointwise tolerance 1e-9, while an error in any term
# larger than 1e-4 of the case's scale still shows.
VANISHING = 1e-4


def printed_rows(case, sample):
    """The book's printed equations, each before it is solved (a Newton or Euler row), with MuJoCo's
    accelerations and reactions put in: one row per printed equation, its residual (the sum of its terms,
    which is zero where the printed equation holds) relative to its largest term over the random states.
    Only where the book's module gives them (Book.printed_rows, docs/model-interface.md)."""
    book = case.model("book")
    if not hasattr(book, "printed_rows") or "mujoco" in sample["failures"] or "book" in sample["failures"]:
        return []
    engine, states = sample["values"]["mujoco"], sample["states"]
    terms_at = []
    for k, (t, q, v) in enumerate(states):
        acc = np.array([engine[f"{c}_acc"][k] for c in case.coords])
        reactions = {name: float(engine[name][k]) for name in case.reaction_names}
        try:
            with np.errstate(all="ignore"):
                terms_at.append({label: np.asarray(terms, dtype=float)
                                 for label, terms in book.printed_rows(t, q, v, acc, reactions).items()})
        except Exception as error:  # the book's module's own error: a failing row that says where
            return [no_number(PRINTED_ROWS, "every printed row", ("book", "mujoco"),
                              f"book: printed rows at random state {k}: {type(error).__name__}: {error}", Status.FAIL)]
    largest = {label: max(np.max(np.abs(at[label]), initial=0.0) for at in terms_at) for label in terms_at[0]}
    # A row whose terms all vanish at these parameters (a Newton row along an axis nothing loads) is judged
    # against VANISHING of the case's largest term, not by its rounding relative to zero.
    floor = VANISHING * max(largest.values(), default=0.0)
    rows = []
    for label in terms_at[0]:
        sums = np.array([np.sum(at[label]) for at in terms_at])
        scale = max(largest[label], floor)
        error = float(np.max(np.abs(sums)) / scale) if scale > 0 else 0.0
        rows.append(row(PRINTED_ROWS, label, ("book", "mujoco"), error, case.tolerance["pointwise"]["value"],
                        f"the printed equation's terms with MuJoCo's accelerations and reactions at {len(states)} "
                        f"random states, their sum relative to the largest term (at least {VANISHING:g} of the case's "
                        "largest)",
                        ceiling=ceilings.POINTWISE))
    return rows


def localise_values(case, rows, sample, drawn, wrong_equations):
    """For each reaction, and the energy, of a derivation that fails against MuJoCo at the random states while
    its equations of motion hold (`wrong_equations`: the sources whose equations are wrong, whose reactions
    and energy along runs follow from them), the terms that explain it, as for an equation: the derivation's
    value less the engine's over the random states and parameter sets (the energy's library has the
    constant and the velocities to degree 2 that T + V has)."""
    failing = [(r.sources[0], r.quantity) for r in rows
               if r.check == "pointwise" and r.sources[1:] == ("mujoco",)
               and (r.quantity in case.reaction_names or r.quantity == "energy")
               and r.status == Status.FAIL and r.sources[0] in derivation_sources(case)
               and r.sources[0] not in wrong_equations and r.sources[0] not in sample["failures"]]
    if not failing or "mujoco" in sample["failures"]:
        return ()
    driven = driven_units(case)
    others = parameter_cases(case, drawn)
    out = []
    for source, name in failing:
        value = (lambda model, t, q, v: model.energy(t, q, v)) if name == "energy" else \
            (lambda model, t, q, v: model.reactions(t, q, v)[name])
        samples, scale = [], None
        for other in others:
            fitted = case.spec["sample"]["count"]  # the states a term search is sized for (terms.MEMORY), not all
            if other is case:  # the pointwise check has them
                states, mine, theirs = (sample["states"][:fitted], sample["values"][source][name][:fitted],
                                        sample["values"]["mujoco"][name][:fitted])
            else:
                states = other.sample_states(fitted)
                try:
                    with np.errstate(all="ignore"):
                        mine, theirs = (np.array([value(other.model(s), t, q, v) for t, q, v in states])
                                        for s in (source, "mujoco"))
                except Exception:  # a set where a source fails: the random-parameters rows say so
                    continue
            t = np.array([t for t, _, _ in states])
            q, v = (np.array([state[k] for state in states]).reshape(len(states), -1) for k in (1, 2))
            if np.all(np.isfinite(mine - theirs)):
                samples.append((dict(other.params), with_driven(other, t, q, v), v, mine - theirs))
                if other is case:  # judged as the pointwise rows judge it: against its largest size at the
                    # case's parameters, for a reaction at least the force (moment) scale
                    scale = max(np.max(np.abs(mine)), np.max(np.abs(theirs)),
                                0.0 if name == "energy" else case.least_reaction_scale(name))
        if scale is None:  # no numbers at the case's own parameters: the pointwise rows say why
            continue
        place = "energy" if name == "energy" else f"reaction {name}"
        try:
            fit = terms.fit(case.coords, case.spec["coord_units"], list(case.params), samples,
                            case.tolerance["pointwise"]["value"] * scale, driven)
        except Exception as error:  # a MemoryError, say: the rows stay, and this says where the search failed
            out.append(Localisation(source=source, equation="", place=place, text=f"not localised: the term search "
                                    f"failed ({type(error).__name__}: {error})", exact=False, identified=False,
                                    residual=max(float(np.max(np.abs(d))) for *_, d in samples), left=0.0,
                                    sets=len(samples)))
            continue
        out.append(Localisation(source=source, equation="", place=place, text=fit.says("it"),
                                exact=fit.exact, identified=fit.identified, residual=fit.before, left=fit.left,
                                sets=fit.sets))
    return tuple(out)
