"""Name the term a derivation got wrong: a sparse fit of one equation's residual over candidate terms.

The residual of equation i, r_i = (M_e (q''_d - q''_e))_i, is the generalised force by which the
derivation's force side f (M q'' = f) differs from the engines': where the derivation lacks a term T,
r_i = -T, so the terms fitted here are those of -r, the terms to ADD to the derivation's f.

The candidates are built from the derivation's own coordinates: position factors (sin and cos of an
angle, a length itself, sin and cos of the difference and of the sum of two angles), products of up
to two of them, times the velocities to degree 0, 1 or 2 (as Lagrange's equations are).  Where the
derivation gives its accelerations only, a wrong mass matrix is a term too: r = dM q''_d, so the position
parts times each of the derivation's accelerations are candidates, and a term in x'' names M's column x.
A coordinate the residual does not depend on (a cyclic angle) enters no position factor.  The support is chosen jointly
over the parameter sets (the same terms in every set): every single term, every pair, then the best
pairs extended greedily to three; each candidate support is verified by least squares and is exact
when what it leaves is under the noise floor.  Each term's coefficient, one per set, is then identified
as a simple number times a product of integer powers of the parameters.  The library grows as n^6 in n
angles and the search as its square: a library beyond a budget of memory and work (MEMORY, WORK) is
narrowed to one position factor per term, and one still beyond it is not searched, which the fit says.
"""

import math
from dataclasses import dataclass, replace
from fractions import Fraction
from itertools import combinations, combinations_with_replacement, product

import numpy as np

MAX_TERMS = 3
FORCE = "force"  # the unit of a `driven` entry that is an applied force's value at each state (library)
MAX_EXPONENT = 2  # a parameter's power in a coefficient, either sign: m l^2, g / l, m / M^2
VERIFIED = 40  # supports verified by least squares at each size: the exact ones rank first, a few at most tie
EXTENDED = 5  # the best pairs extended to three terms
# A column this close to the span of others (sin^2 of its angle to it) is a function of them at the
# states sampled: its pair with them would rank on rounding, so it is skipped.
DEPENDENT = 1e-9
# A coefficient is a product of parameters when its ratio to that product agrees over the sets to this
# relative size: a fitted coefficient is good to about floor / |column| relative, orders below, and a
# wrong product of powers differs by far more over random parameter sets.
SAME = 1e-6
SIMPLE = 12  # numbers written as fractions: numerator and denominator up to 12 (1/2, 4/3, 1/12)
ENUMERATED = 200_000  # exponent combinations tried when the sets are too few for least squares
# A closest fit that is not exact is named only where it leaves at most this share of the residual: one that
# leaves more explains too little of it to point a reader at its terms.
CLOSEST = 0.1


@dataclass(frozen=True)
class Factor:
    """One function of the state to a power: sin or cos of an angle or of two angles' difference,
    a coordinate itself, a velocity, or the derivation's acceleration."""
    function: str  # "sin", "cos", "coordinate", "velocity" or "acceleration"
    of: tuple[str, ...]  # a coordinate, or two angles (sin(of[0] - of[1]), or with `sum` of[0] + of[1])
    power: int = 1
    sum: bool = False  # of two angles: their sum (the absolute angle of a link hung from another), not their difference

    @property
    def text(self):
        argument = (" + " if self.sum else " - ").join(self.of)
        base = {"sin": f"sin({argument})", "cos": f"cos({argument})", "coordinate": argument,
                "velocity": argument + "'", "acceleration": argument + "''"}[self.function]
        return base if self.power == 1 else f"{base}^{self.power}"

    def value(self, q, v, a, index):
        """The factor at states q, v (N, n) with the derivation's accelerations a (N, n, or None where none is a
        candidate); `index` gives each coordinate's column."""
        if self.function == "velocity":
            base = v[:, index[self.of[0]]]
        elif self.function == "acceleration":
            base = a[:, index[self.of[0]]]
        elif self.function == "coordinate":
            base = q[:, index[self.of[0]]]
        else:
            other = (q[:, index[self.of[1]]] * (1 if self.sum else -1)) if len(self.of) == 2 else 0.0
            angle = q[:, index[self.of[0]]] + other
            base = np.sin(angle) if self.function == "sin" else np.cos(angle)
        return base ** self.power


@dataclass(frozen=True)
class Term:
    """A term to add to the derivation's force side: number * prod(parameter^power) * prod(state)."""
    number: float  # the simple number when identified, else the coefficient at the first parameter set
    powers: tuple[tuple[str, int], ...]  # (parameter, nonzero power), in the derivation's order
    state: tuple[Factor, ...]
    identified: bool  # number * prod(parameter^power) (or the sum) is the coefficient in every set, to SAME
    # A coefficient that is a sum of such products, ((number, powers), ...), its first number positive; `number`
    # is then the sum's sign, +-1: `(Ixx - m h^2) sin(theta)`.
    sum: tuple = ()

    def value(self, params, q, v, a, index):
        """The term at states q, v, a (Factor.value) of the parameter set `params` ({name: value}); a coefficient
        that is no product of parameters has its value at the first set."""
        product = lambda number, powers: number * math.prod(params[name] ** power for name, power in powers)
        if self.sum:
            coefficient = self.number * sum(product(number, powers) for number, powers in self.sum)
        else:
            coefficient = product(self.number, self.powers) if self.identified else self.number
        return coefficient * math.prod((factor.value(q, v, a, index) for factor in self.state), start=np.ones(len(q)))

    @property
    def magnitude_text(self):
        """The term without its sign: `m l sin(theta) theta'^2`, `g m / M cos(theta)`, `0.15 sin(theta)`,
        `(Ixx - m h^2) sin(theta)`."""
        if self.sum:
            parts = [("- " if number < 0 else "+ ") * (i > 0) + _monomial(abs(number), powers)
                     for i, (number, powers) in enumerate(self.sum)]
            coefficient = "(" + " ".join(parts) + ")"
        else:
            coefficient = _monomial(abs(self.number), self.powers) if self.identified else f"{abs(self.number):.6g}"
        state = [factor.text for factor in self.state]
        return " ".join(state if coefficient == "1" and state else [coefficient] + state)

    @property
    def text(self):
        """The term with its sign: `-2 m2 l1 l2 sin(theta1 - theta2) theta2'^2`."""
        return ("-" if self.number < 0 else "") + self.magnitude_text


@dataclass(frozen=True)
class TermFit:
    """The terms that, added to the derivation's force side of one equation, make it agree with the
    engines; the residual before and after."""
    terms: tuple[Term, ...]  # the fewest that fit; the closest three when none is exact
    before: float  # largest |residual| over every state of every set
    left: float  # largest |residual - fit|
    exact: bool  # left <= the noise floor
    sets: int  # parameter sets fitted
    unvaried: tuple[str, ...]  # parameters equal in every set: their powers are inside the numbers
    alternatives: tuple[tuple[Term, ...], ...]  # other sets of as many terms that fit as exactly
    narrowed: str = ""  # how the library was narrowed to fit the budget (MEMORY, WORK), else ""
    unsearched: str = ""  # why no term was searched (even the narrowed library beyond the budget), else ""

    @property
    def relative(self):
        return self.left / self.before if self.before else 0.0

    @property
    def text(self):
        """A sentence fragment to follow "equation x:"."""
        return self.says("its force side f (M q'' = f)")

    @property
    def identified(self):
        """Whether the fit is exact and every coefficient a simple number times a product of parameters."""
        return self.exact and self.sets > 1 and all(term.identified for term in self.terms)

    def says(self, where):
        """A sentence fragment to follow the name of what was fitted, e.g. "equation x:"; `where`: what
        the terms are added to, e.g. "its force side f (M q'' = f)", "it"."""
        if self.unsearched:
            return f"its terms not searched ({self.unsearched}); its residual is up to {self.before:.2g}"
        if not self.terms and self.exact:
            return f"nothing to add: its residual {self.before:.1e} is at the noise floor"
        if not self.terms:
            return f"no candidate term can be fitted to its residual (up to {self.before:.2g}: beyond the fit's arithmetic)"
        if self.exact:
            words = (f"add {_signed(self.terms)} to {where} to agree with the engines "
                     f"(residual left {self.left:.1e} of {self.before:.2g})")
        elif self.left <= CLOSEST * self.before:
            words = (f"no sum of up to {MAX_TERMS} candidate terms explains its residual (the closest, "
                     f"{_signed(self.terms)}, leaves {self.left:.2g} of {self.before:.2g})")
        else:
            words = (f"no sum of up to {MAX_TERMS} candidate terms explains its residual (up to {self.before:.2g}; "
                     f"the closest leaves {self.left / self.before:.0%} of it)")
        return words + "".join(f" ({note})" for note in self._notes())

    def _notes(self):
        if not self.exact:
            return [self.narrowed] if self.narrowed else []
        if self.sets == 1:
            return ["one parameter set: numbers only"] + ([self.narrowed] if self.narrowed else [])
        notes = [f"the coefficient of {_state_text(term)} is no product of parameters' powers: its value at "
                 "the first set" for term in self.terms if not term.identified]
        notes += [f"a term in {term.state[-1].text} is M's: this equation's entry in its column {term.state[-1].of[0]} lacks "
                  f"{'-' if term.number > 0 else '+'} {replace(term, state=term.state[:-1]).magnitude_text}"
                  for term in self.terms if term.state and term.state[-1].function == "acceleration"]
        if self.unvaried and any(term.identified for term in self.terms):
            notes.append(f"{', '.join(self.unvaried)} the same in every set: inside the numbers")
        notes += [f"as well explained by {_signed(other)}" for other in self.alternatives[:2]]
        return notes + ([self.narrowed] if self.narrowed else [])


def _power(name, power):
    return name if power == 1 else f"{name}^{power}"


def _monomial(number, powers):
    """A simple positive number times a product of parameters' powers: `m l^2`, `g m / M`, `4/3`."""
    simple = _simple(number)
    numerator = ([str(simple.numerator)] if simple.numerator != 1 else []) if simple is not None else [f"{number:.6g}"]
    denominator = [str(simple.denominator)] if simple is not None and simple.denominator != 1 else []
    numerator += [_power(name, power) for name, power in powers if power > 0]
    denominator += [_power(name, -power) for name, power in powers if power < 0]
    coefficient = " ".join(numerator) or "1"
    if denominator:
        below = " ".join(denominator)
        coefficient += " / " + (f"({below})" if len(denominator) > 1 else below)
    return coefficient


def _state_text(term):
    return " ".join(factor.text for factor in term.state) or "the constant term"


def _signed(terms):
    """`+ m l sin(theta) theta'^2 - g m cos(theta)`: every sign written, so that a wrong one shows."""
    return " ".join(("- " if term.number < 0 else "+ ") + term.magnitude_text for term in terms)


def _simple(number):
    """number as a Fraction with numerator and denominator up to SIMPLE, or None."""
    fraction = Fraction(number).limit_denominator(SIMPLE)
    if fraction and fraction.numerator <= SIMPLE and abs(float(fraction) - number) <= SAME * abs(number):
        return fraction
    return None


def library(coords, units, driven=(), products=2, accelerations=False, cyclic=()):
    """The candidate terms' state parts, fewest factors first, each a tuple of Factors: products of up
    to `products` (2 or 1) position factors times velocities to degree 0 to 2, and with `accelerations` times
    each acceleration.  `driven`: (name, unit) of prescribed motions, whose positions (functions of time) enter
    as position factors (their rates are parameters), and (name, FORCE) of applied forces that are laws of time
    and state, each a candidate on its own.  `cyclic`: coordinates in no position factor.  As many as
    library_size counts."""
    positions, velocities, forces = _factors(coords, units, driven, cyclic)
    # cos^2 = 1 - sin^2 of the same angle: with all three, a constant plus sin^2 would fit three ways
    position_parts = [()] + [(factor,) for factor in positions] + ([
        _product(a, b) for a, b in combinations_with_replacement(positions, 2)
        if not (a == b and a.function == "cos")] if products == 2 else [])
    velocity_parts = [()] + [(factor,) for factor in velocities] + [
        _product(a, b) for a, b in combinations_with_replacement(velocities, 2)]
    acceleration_parts = [(Factor("acceleration", (name,)),) for name in coords] if accelerations else []
    parts = [position + rest for position in position_parts for rest in velocity_parts + acceleration_parts] + forces
    return sorted(parts, key=lambda part: sum(factor.power for factor in part))


def library_size(coords, units, driven=(), products=2, accelerations=False, cyclic=()):
    """len(library(...)), counted without building it: the full library grows as n^6 in n angles (1,810 terms
    at 3, 27,321 at 5, 176,436 at 7, without accelerations)."""
    positions, velocities, forces = _factors(coords, units, driven, cyclic)
    p, n = len(positions), len(velocities)
    cosines = sum(factor.function == "cos" for factor in positions)
    position_parts = 1 + p + ((p * (p + 1) // 2 - cosines) if products == 2 else 0)
    return position_parts * (1 + n + n * (n + 1) // 2 + (n if accelerations else 0)) + len(forces)


def _factors(coords, units, driven, cyclic=()):
    """The library's position factors (none of a `cyclic` coordinate), velocity factors and applied forces'
    candidates; ValueError for a unit the terms do not know."""
    if len(units) != len(coords):
        raise ValueError(f"units: {len(units)} given for {len(coords)} coordinates {', '.join(coords)}")
    forces = [(Factor("coordinate", (name,)),) for name, unit in driven if unit == FORCE]
    every = list(zip(coords, units)) + [(name, unit) for name, unit in driven if unit != FORCE]
    for name, unit in every:
        if unit not in ("rad", "m"):
            raise ValueError(f"coordinate {name}: unit {unit!r}; the candidate terms know 'rad' and 'm'")
    every = [(name, unit) for name, unit in every if name not in cyclic]
    angles = [name for name, unit in every if unit == "rad"]
    positions = [Factor(function, (name,)) for name, unit in every
                 for function in (("sin", "cos") if unit == "rad" else ("coordinate",))]
    positions += [Factor(function, pair, sum=total) for pair in combinations(angles, 2) for total in (False, True)
                  for function in ("sin", "cos")]
    return positions, [Factor("velocity", (name,)) for name in coords], forces


# What a fit may take.  The search's largest arrays are L x L for L candidate terms: a Gram matrix per parameter set,
# and at two terms the residual left by every pair with its temporaries (about six more: the base's columns, their
# solve, the pairs' cross terms, norms, residuals and their ranking), so its peak is about 8 (sets + 6) L^2 bytes
# (measured: 249 MB for the top's 1,810 terms over 9 sets, 8 (9 + 6) L^2 = 393 MB), and its time grows as sets L^2
# (2.7 s there, 9e-8 s per set and pair).  MEMORY is a twentieth of the 23 GB of the machine the reports are made on
# and four times the top's peak; WORK, sets x L^2, is some 10 s of one fit (the top's is 3e7).  A library over
# either is built with one position factor per term (products=1: 1,071 terms at 5 angles); one that is still over
# is not searched, and the fit says so.
MEMORY = 1e9  # bytes
TEMPORARIES = 6
WORK = 1e8


def cost(size, sets):
    """(bytes, sets x pairs) of a search over `size` candidate terms and `sets` parameter sets."""
    return 8.0 * (sets + TEMPORARIES) * size**2, float(sets) * size**2


def within_budget(size, sets):
    memory, work = cost(size, sets)
    return memory <= MEMORY and work <= WORK


def _product(a, b):
    return (replace(a, power=2),) if a == b else (a, b)


def fit(coords, units, param_names, samples, floor, driven=(), cyclic=()):
    """The fewest candidate terms (up to MAX_TERMS) that, added to the force side of one equation of
    the derivation, explain its residual r = (M_e (q''_d - q''_e))_i in every parameter set.

    coords, units: the derivation's coordinates and their units ('rad' or 'm'); param_names: its
    parameters, in the order the terms write them; samples: one (params {name: value}, q (N, n),
    v (N, n), residual (N,)) per parameter set, or (params, q, v, residual, a) with the derivation's
    accelerations a (N, n), whose terms are then candidates too (a wrong M); floor: the absolute residual that
    is noise (the engines' rounding), under which a fit is exact.  `driven`: (name, unit) of prescribed motions,
    whose positions at each state follow the coordinates in q (library); `cyclic`: coordinates the residual
    does not depend on."""
    if not samples:
        raise ValueError("samples: none given; a fit needs at least one parameter set")
    positions = list(coords) + [name for name, _ in driven]
    sets = [_sample(number, sample, coords, positions, param_names) for number, sample in enumerate(samples)]
    params = [values for values, *_ in sets]
    targets = [-residual for *_, residual, _ in sets]  # what the derivation's force side lacks
    accelerations = all(a is not None for *_, a in sets)
    unvaried = tuple(name for name in param_names if len({values[name] for values in params}) == 1)
    before = max(float(np.max(np.abs(target))) for target in targets)
    if before <= floor:
        return TermFit((), before, before, True, len(sets), unvaried, ())
    size_of = lambda products: library_size(coords, units, driven, products, accelerations, cyclic)
    full = size_of(2)
    products = next((products for products in (2, 1) if within_budget(size_of(products), len(sets))), None)
    if products is None:
        size = size_of(1)
        memory, work = cost(size, len(sets))
        return TermFit((), before, before, False, len(sets), unvaried, (), unsearched=(
            f"even {size:,} candidate terms of one position factor each, over {len(sets)} parameter sets, would take "
            f"{memory / 1e9:.3g} GB and {work:.2g} set-pairs, beyond the budget of {MEMORY / 1e9:g} GB and {WORK:g}"))
    narrowed = "" if products == 2 else (f"candidates of one position factor each: the {full:,} of up to two "
                                         f"would not fit the budget of {MEMORY / 1e9:g} GB")
    parts = library(coords, units, driven, products, accelerations, cyclic)
    index = {name: i for i, name in enumerate(positions)}
    raw = [_columns(parts, q, v, a, index) for _, q, v, _, a in sets]
    scales = np.array([np.linalg.norm(columns, axis=0) for columns in raw])
    # a candidate zero at every state of a set (no velocity sampled, say) can fit nothing there
    usable = np.flatnonzero(np.all(scales > 1e-12 * scales.max(axis=1, keepdims=True), axis=0))
    parts, scales = [parts[j] for j in usable], scales[:, usable]
    normalised = [columns[:, usable] / scale for columns, scale in zip(raw, scales)]

    def terms(support, coefficients):
        numbers = coefficients / scales[:, list(support)]  # per set, of the columns as evaluated
        return tuple(_term(parts[j], numbers[:, i], params, param_names) for i, j in enumerate(support))

    exact, closest = _search(normalised, targets, floor)
    if closest is None and not exact:
        return TermFit((), before, before, False, len(sets), unvaried, (), narrowed)
    if not exact:
        support, left, coefficients = closest
        return TermFit(terms(support, coefficients), before, left, False, len(sets), unvaried, (), narrowed)
    explanations = [(terms(support, coefficients), left) for support, left, coefficients in exact]
    # the first in the library's order whose coefficients are all products of parameters
    explanations.sort(key=lambda explanation: not all(term.identified for term in explanation[0]))
    (chosen, left), others = explanations[0], explanations[1:]
    # as ambiguous as it gets: others as small whose coefficients are as well identified
    alternatives = tuple(other for other, _ in others if all(term.identified for term in other)
                         == all(term.identified for term in chosen))
    return TermFit(chosen, before, left, True, len(sets), unvaried, alternatives, narrowed=narrowed)


def _sample(number, sample, coords, positions, param_names):
    """One parameter set's (params, q, v, residual, a or None), checked; ValueError names what is wrong.  q
    holds the `positions`: the coordinates, then the prescribed motions' positions."""
    where = f"samples[{number}]"
    params, q, v, residual, a = (*sample, None) if len(sample) == 4 else sample
    q, v, residual = (np.asarray(array, dtype=float) for array in (q, v, residual))
    a = None if a is None else np.asarray(a, dtype=float)
    if q.ndim != 2 or q.shape[1] != len(positions) or v.shape != (len(q), len(coords)) or residual.shape != (len(q),) \
            or (a is not None and a.shape != v.shape):
        raise ValueError(f"{where}: q {q.shape}, v {v.shape}, residual {residual.shape}"
                         f"{'' if a is None else f', a {a.shape}'}; expected "
                         f"(N, {len(positions)}), (N, {len(coords)}), (N,){'' if a is None else ', (N, n)'}")
    # MAX_TERMS coefficients fit any MAX_TERMS states exactly: an exact fit says something only on many more
    if len(q) < 4 * MAX_TERMS:
        raise ValueError(f"{where}: {len(q)} states; a fit of up to {MAX_TERMS} terms needs at least "
                         f"{4 * MAX_TERMS}")
    missing = [name for name in param_names if name not in params]
    if missing:
        raise ValueError(f"{where}: no value for parameter(s) {', '.join(missing)}")
    values = {name: float(params[name]) for name in param_names}
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v)) and np.all(np.isfinite(residual))
            and (a is None or np.all(np.isfinite(a))) and np.all(np.isfinite(list(values.values())))):
        raise ValueError(f"{where}: a state, acceleration, residual or parameter value is not finite")
    return values, q, v, residual, a


def _columns(parts, q, v, a, index):
    """The candidates evaluated at the states: (N, len(parts)), each factor computed once."""
    values = {}
    for factor in {factor for part in parts for factor in part}:
        values[factor] = factor.value(q, v, a, index)
    ones = np.ones(len(q))
    return np.column_stack([np.prod([values[factor] for factor in part], axis=0) if part else ones
                            for part in parts])


def _search(normalised, targets, floor):
    """(exact, closest): the supports of the fewest columns that fit every set to the floor, each
    (support, left, coefficients (sets, size)), in the library's order; or, when none does, no exact
    one and the closest support of MAX_TERMS columns found.  Every column alone, every pair, then the
    best pairs extended by one: each size ranks its candidates on the Gram matrices (the left residual
    squared summed over the sets, each relative to its own residual) and verifies the best VERIFIED
    by least squares, since the ranking, a difference of squares, is blind below ~1e-8 relative."""
    grams = [columns.T @ columns for columns in normalised]
    projections = [columns.T @ target for columns, target in zip(normalised, targets)]
    squares = [target @ target for target in targets]
    weights = [1.0 / (square + len(target) * floor**2) for square, target in zip(squares, targets)]
    count = normalised[0].shape[1]
    bases = np.zeros((1, 0), dtype=int)
    for size in range(1, MAX_TERMS + 1):
        left = sum(weight * _left_after(gram, projection, square, bases)
                   for gram, projection, square, weight in zip(grams, projections, squares, weights))
        ranked = []  # a pair comes twice, as (i, j) and (j, i): twice as many, then the first of each
        for flat in np.argsort(left, axis=None)[:2 * VERIFIED]:
            base, j = divmod(int(flat), count)
            support = tuple(sorted([*bases[base].tolist(), j]))
            if np.isfinite(left.flat[flat]) and support not in ranked:
                ranked.append(support)
        verified = sorted(((support, *_solve(support, normalised, targets)) for support in ranked[:VERIFIED]),
                          key=lambda candidate: candidate[1])
        exact = sorted(candidate for candidate in verified if candidate[1] <= floor)
        if exact:
            return exact, None
        if not verified:  # no candidate with a finite residual left: a residual past float's range (1e300 parameters)
            return [], None
        bases = np.arange(count)[:, None] if size == 1 else np.array([support for support, *_ in verified[:EXTENDED]])
    return [], verified[0]


def _left_after(gram, projection, square, bases):
    """(bases, columns): the squared residual of one set left after a least-squares fit over the
    columns of a base (a row of `bases`) and column j, from the Gram matrix of the normalised columns
    and their projections on the residual; inf where j is (nearly) in the span of the base."""
    if bases.shape[1] == 0:
        return (square - projection**2)[None, :]
    within = gram[bases[:, :, None], bases[:, None, :]]  # (bases, size, size)
    across = gram[bases]  # (bases, size, columns)
    onto = projection[bases]  # (bases, size)
    solved = np.linalg.solve(within, np.concatenate([onto[:, :, None], across], axis=2))
    coefficients, mix = solved[:, :, 0], solved[:, :, 1:]
    cross = projection[None, :] - np.einsum("bkj,bk->bj", across, coefficients)  # column j off the base, . residual
    norm = 1.0 - np.einsum("bkj,bkj->bj", across, mix)  # |column j off the span of the base|^2
    fitted = np.einsum("bk,bk->b", onto, coefficients)
    with np.errstate(divide="ignore", invalid="ignore"):
        left = square - fitted[:, None] - cross**2 / norm
    return np.where(norm > DEPENDENT, left, np.inf)


def _solve(support, normalised, targets):
    """(largest |residual left| over every set, the coefficients (sets, size)) of a least-squares fit."""
    left, coefficients = 0.0, []
    for columns, target in zip(normalised, targets):
        chosen = columns[:, list(support)]
        solution = np.linalg.lstsq(chosen, target, rcond=None)[0]
        left = max(left, float(np.max(np.abs(target - chosen @ solution))))
        coefficients.append(solution)
    return left, np.array(coefficients)


def _term(state, coefficients, params, param_names):
    """The Term of `state` whose coefficient in set s is coefficients[s]: a product of parameters' powers, or
    else a sum of a few."""
    number, powers, identified = _identify(coefficients, params, param_names)
    if not identified:
        monomials = _identify_sum(coefficients, params, param_names)
        if monomials:
            sign = 1.0 if monomials[0][0] > 0 else -1.0
            return Term(sign, (), state, True, tuple((sign * n, p) for n, p in monomials))
    return Term(number, powers, state, identified)


MAX_SUM = 3  # products in a coefficient that is a sum: (alpha' + beta')^2 has three
SUM_DEGREE = 3  # their parameters' powers, in absolute value, add up to at most this (m h^2, m2 l1 g): three at most
TRIED = 50  # the closest pairs extended to three products (a triple of many parameters may be missed)


def _sum_exponents(count):
    """The powers of `count` parameters in a product of a sum: the constant, and one to three parameters, each
    to -1, 1 or 2, their absolute powers adding up to at most SUM_DEGREE (a weight's moment (m1 lc1 + m2 l1) g has
    three; about 1,300 products for ten parameters)."""
    rows = [(0,) * count]
    for size in (1, 2, 3):
        for chosen in combinations(range(count), size):
            for powers in product((-1, 1, 2), repeat=size):
                if sum(map(abs, powers)) <= SUM_DEGREE:
                    row = [0] * count
                    for k, power in zip(chosen, powers):
                        row[k] = power
                    rows.append(tuple(row))
    return rows


def _identify_sum(coefficients, params, param_names):
    """((number, powers), ...): up to MAX_SUM products of the varying parameters' powers (_sum_exponents;
    the constant 1 among them), each times a simple number, whose sum is
    coefficients[s] in every set to SAME; () when none is, or when the sets are too few to tell (more
    sets than products).  Pairs are tried all at once (their 2 x 2 normal equations), the closest pairs
    extended by a third."""
    varying = [name for name in param_names
               if len({values[name] for values in params}) > 1 and all(values[name] != 0 for values in params)]
    target = np.asarray(coefficients, dtype=float)
    if len(target) < MAX_SUM + 2 or not varying:
        return ()
    values = np.array([[each[name] for name in varying] for each in params])
    exponents = np.array(_sum_exponents(len(varying)), dtype=float)
    columns = np.prod(values[:, None, :] ** exponents[None, :, :], axis=2)  # (sets, products)
    scale = np.linalg.norm(columns, axis=0)
    unit = columns / scale
    gram, projection, norm = unit.T @ unit, unit.T @ target, float(target @ target)
    i, j = np.triu_indices(len(exponents), 1)
    det = gram[i, i] * gram[j, j] - gram[i, j] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (gram[j, j] * projection[i] - gram[i, j] * projection[j]) / det
        b = (gram[i, i] * projection[j] - gram[i, j] * projection[i]) / det
        left = norm - a * projection[i] - b * projection[j]  # |target - fit|^2
    left = np.where(det > DEPENDENT, left, np.inf)
    pairs = [(int(i[k]), int(j[k])) for k in np.argsort(left)[:TRIED]]
    triples = []
    for pair in pairs:  # each other product's least squares with the pair at once: its part off the pair's span
        basis = np.linalg.qr(unit[:, list(pair)])[0]
        rest = target - basis @ (basis.T @ target)
        off = unit - basis @ (basis.T @ unit)
        with np.errstate(divide="ignore", invalid="ignore"):
            left3 = rest @ rest - (rest @ off) ** 2 / np.sum(off * off, axis=0)
        left3[list(pair)] = np.inf
        triples += [pair + (int(m),) for m in np.argsort(left3)[:3]]
    for support in pairs + triples:
        chosen = columns[:, list(support)]
        numbers = np.linalg.lstsq(chosen, target, rcond=None)[0]
        if np.max(np.abs(target - chosen @ numbers)) > SAME * np.max(np.abs(target)):
            continue
        simple = [_simple(abs(n)) for n in numbers]
        if all(x is not None for x in simple):
            return tuple((float(np.sign(n) * x), tuple((name, int(p)) for name, p in zip(varying, exponents[k]) if p))
                         for n, x, k in zip(numbers, simple, support))
    return ()


def _identify(coefficients, params, param_names):
    """(number, powers, identified): coefficients[s] = number * prod(params[s][name]^power) in every
    set, number simple or not (a parameter equal in every set hides inside it); else the first set's
    coefficient, no powers, False.  The powers of the parameters that vary (and are never zero): from
    a log-linear least squares, rounded, when the sets are at least one more than those parameters;
    from every combination, fewest parameters first, when they are fewer."""
    first = float(coefficients[0])
    varying = [name for name in param_names
               if len({values[name] for values in params}) > 1 and all(values[name] != 0 for values in params)]
    if len(coefficients) < 2 or not np.all(coefficients != 0):
        return first, (), False
    values = np.array([[each[name] for name in varying] for each in params]).reshape(len(params), len(varying))
    logs, target = np.log(np.abs(values)), np.log(np.abs(coefficients))
    design = np.column_stack([np.ones(len(params)), logs])
    if np.linalg.matrix_rank(design) == design.shape[1]:
        guesses = np.round(np.linalg.lstsq(design, target, rcond=None)[0][1:])[None, :]
        guesses = guesses[np.all(np.abs(guesses) <= MAX_EXPONENT, axis=1)]
    else:
        guesses = _sparse_exponents(len(varying))
    log_ratios = target[None, :] - guesses @ logs.T  # (guesses, sets)
    signs = np.sign(coefficients)[None, :] * (-1.0) ** (np.abs(guesses) @ (values < 0).T)
    # a log ratio's spread is the ratio's relative spread, to first order
    agree = (np.ptp(log_ratios, axis=1) <= SAME) & np.all(signs == signs[:, :1], axis=1)
    if not np.any(agree):
        return first, (), False
    best = int(np.flatnonzero(agree)[0])
    number = float(signs[best, 0] * np.exp(np.mean(log_ratios[best])))
    simple = _simple(abs(number))
    if simple is not None:
        number = float(np.sign(number) * simple)
    return number, tuple((name, int(power)) for name, power in zip(varying, guesses[best]) if power), True


def _sparse_exponents(count):
    """Integer powers of `count` parameters in [-MAX_EXPONENT, MAX_EXPONENT], as rows, fewest nonzero
    first, as many levels as fit in ENUMERATED rows."""
    nonzero = [power for power in range(-MAX_EXPONENT, MAX_EXPONENT + 1) if power]
    rows, total = [np.zeros((1, count))], 1
    for size in range(1, count + 1):
        subsets = np.array(list(combinations(range(count), size)))
        choices = np.array(list(product(nonzero, repeat=size)), dtype=float)
        total += len(subsets) * len(choices)
        if total > ENUMERATED:
            break
        level = np.zeros((len(subsets), len(choices), count))
        level[np.arange(len(subsets))[:, None, None], np.arange(len(choices))[None, :, None],
              subsets[:, None, :]] = choices[None, :, :]
        rows.append(level.reshape(-1, count))
    return np.concatenate(rows)
