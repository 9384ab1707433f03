"""dyncheck.checks.terms: the wrong term of a derivation named from its residual, on synthetic residuals.

A residual is r = f_derivation - f_engines (M q'' = f, M right): a term T the derivation lacks gives
r = -T, and the fit names +T, the term to add.  States and parameter sets are random; rounding noise of
1e-12 is added, under a floor of 1e-10 (the largest of 600 normal draws of 1e-12 is about 4e-12)."""

import numpy as np
import pytest

from dyncheck.checks.terms import fit, library, library_size

NOISE, FLOOR = 1e-12, 1e-10
CART = (["x", "theta"], ["m", "rad"], ["M", "m", "l", "k", "g"])  # a cart on a spring, a pendulum hung from it
ARMS = (["theta1", "theta2"], ["rad", "rad"], ["m1", "m2", "l1", "l2", "g"])  # two arms, one hung from the other


def samples(system, missing, sets=6, states=100, seed=0):
    """One (params, q, v, residual) per parameter set, where the derivation lacks missing(p, q, v)."""
    coords, units, names = system
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(sets):
        params = {name: rng.uniform(0.5, 2.0) for name in names}
        q = np.column_stack([rng.uniform(-np.pi, np.pi, states) if unit == "rad" else rng.uniform(-0.5, 0.5, states)
                             for unit in units])
        v = rng.uniform(-3.0, 3.0, (states, len(coords)))
        out.append((params, q, v, -missing(params, q, v) + rng.normal(0.0, NOISE, states)))
    return out


def run(system, missing, **kwargs):
    coords, units, names = system
    return fit(coords, units, names, samples(system, missing, **kwargs), FLOOR)


def centripetal(p, q, v):
    return p["m"] * p["l"] * np.sin(q[:, 1]) * v[:, 1] ** 2


def test_a_dropped_term_is_named_with_its_coefficient_in_the_derivations_symbols():
    result = run(CART, centripetal)
    assert result.exact and result.left <= FLOOR and result.relative < 1e-10
    (term,) = result.terms
    assert term.identified and term.number == 1 and term.powers == (("m", 1), ("l", 1))
    assert [factor.text for factor in term.state] == ["sin(theta)", "theta'^2"]
    assert term.text == "m l sin(theta) theta'^2"
    assert result.text.startswith("add + m l sin(theta) theta'^2 to its force side f (M q'' = f)")


def test_a_flipped_sign_is_twice_the_term():
    result = run(CART, lambda p, q, v: 2 * centripetal(p, q, v))
    assert result.exact and [term.text for term in result.terms] == ["2 m l sin(theta) theta'^2"]


def test_sin_written_for_cos_is_two_terms_with_their_signs():
    """The derivation wrote m g sin(theta) where the engines have m g cos(theta)."""
    result = run(CART, lambda p, q, v: p["m"] * p["g"] * (np.cos(q[:, 1]) - np.sin(q[:, 1])))
    assert result.exact
    assert sorted(term.text for term in result.terms) == ["-m g sin(theta)", "m g cos(theta)"]
    assert "- m g sin(theta)" in result.text and "+ m g cos(theta)" in result.text


def test_a_missing_factor_2_leaves_the_term_once():
    """The derivation wrote -m l cos(theta) x' theta' for -2 m l cos(theta) x' theta'."""
    result = run(CART, lambda p, q, v: -p["m"] * p["l"] * np.cos(q[:, 1]) * v[:, 0] * v[:, 1])
    assert result.exact and [term.text for term in result.terms] == ["-m l cos(theta) x' theta'"]
    assert result.text.startswith("add - m l cos(theta) x' theta'")


def test_a_term_in_two_angles_difference():
    result = run(ARMS, lambda p, q, v: -2 * p["m2"] * p["l1"] * p["l2"] * np.sin(q[:, 0] - q[:, 1]) * v[:, 1] ** 2)
    assert result.exact
    assert [term.text for term in result.terms] == ["-2 m2 l1 l2 sin(theta1 - theta2) theta2'^2"]


def test_a_parameter_in_a_denominator():
    result = run(CART, lambda p, q, v: p["g"] * p["m"] / p["M"] * np.cos(q[:, 1]))
    assert result.exact and [term.text for term in result.terms] == ["m g / M cos(theta)"]
    assert result.terms[0].powers == (("M", -1), ("m", 1), ("g", 1))


def test_fewer_sets_than_parameters_still_identify_the_product():
    """Four sets, five parameters: too few for least squares, every combination tried."""
    result = run(CART, centripetal, sets=4)
    assert result.exact and [term.text for term in result.terms] == ["m l sin(theta) theta'^2"]


def test_a_coefficient_that_is_a_sum_of_products_is_named_as_one():
    """(M + m) g, the top's Ixx - m h^2: a sum of a few products of parameters, found over the sets."""
    result = run(CART, lambda p, q, v: (p["M"] + p["m"]) * p["g"] * np.sin(q[:, 1]))
    (term,) = result.terms
    assert result.exact and term.identified and result.identified
    assert result.text.startswith("add + (M g + m g) sin(theta) to its force side"), result.text


def test_a_coefficient_that_is_no_sum_of_products_stays_a_number():
    result = run(CART, lambda p, q, v: np.exp(p["m"]) * np.sin(q[:, 1]))
    (term,) = result.terms
    assert result.exact and not term.identified and term.powers == () and not term.sum
    assert "no product of parameters' powers" in result.text


def test_one_parameter_set_gives_numbers_only():
    data = samples(CART, centripetal, sets=1)
    params = data[0][0]
    result = fit(*CART[:2], CART[2], data, FLOOR)
    (term,) = result.terms
    assert result.exact and not term.identified and result.unvaried == tuple(CART[2])
    assert term.number == pytest.approx(params["m"] * params["l"], rel=1e-9)
    assert term.text == f"{params['m'] * params['l']:.6g} sin(theta) theta'^2"
    assert "one parameter set" in result.text


def test_a_residual_no_candidate_explains_is_not_exact():
    result = run(CART, lambda p, q, v: np.exp(0.3 * np.sin(q[:, 1]) * q[:, 0]) * np.tanh(v[:, 1]))
    assert not result.exact and result.left > 1e3 * FLOOR and len(result.terms) == 3
    assert result.text.startswith("no sum of up to 3 candidate terms explains its residual")


def test_a_residual_at_the_floor_needs_nothing():
    result = run(CART, lambda p, q, v: np.zeros(len(q)))
    assert result.exact and result.terms == () and result.text.startswith("nothing to add")


def test_the_library_has_no_duplicate_and_no_cos_squared():
    parts = library(*CART[:2])
    texts = [" ".join(factor.text for factor in part) for part in parts]
    assert len(set(texts)) == len(texts) and not any("cos(theta)^2" in text for text in texts)
    assert len(library(*ARMS[:2])) < 300


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="coordinate theta: unit 'deg'"):
        library(["x", "theta"], ["m", "deg"])
    data = samples(CART, centripetal, sets=2)
    del data[1][0]["k"]
    with pytest.raises(ValueError, match=r"samples\[1\]: no value for parameter\(s\) k"):
        fit(*CART, data, FLOOR)


def test_a_wrong_mass_matrix_entry_is_named_from_the_accelerations():
    """A derivation of accelerations only, its M11 short of m2 l1^2: its residual is -m2 l1^2 theta1''_d, fitted
    as a term in its own acceleration (given with the samples) and named as M's; without the accelerations no
    term of the library fits it."""
    rng = np.random.default_rng(3)
    with_accelerations = [(params, q, v, residual, a) for (params, q, v, residual), a in zip(
        samples(ARMS, lambda p, q, v: np.zeros(len(q))),
        [rng.uniform(-20.0, 20.0, (100, 2)) for _ in range(6)])]
    data = [(params, q, v, residual + params["m2"] * params["l1"] ** 2 * a[:, 0], a)
            for params, q, v, residual, a in with_accelerations]
    result = fit(*ARMS[:2], ARMS[2], data, FLOOR)
    assert result.identified and [term.text for term in result.terms] == ["-m2 l1^2 theta1''"], result.text
    assert "this equation's entry in its column theta1 lacks + m2 l1^2" in result.text
    assert not fit(*ARMS[:2], ARMS[2], [sample[:4] for sample in data], FLOOR).exact


def test_a_cyclic_angle_enters_no_candidate():
    parts = library(*ARMS[:2], cyclic=("theta1",))
    assert parts and not any("theta1" in factor.of for part in parts for factor in part
                             if factor.function in ("sin", "cos"))
    assert len(parts) == library_size(*ARMS[:2], cyclic=("theta1",)) < library_size(*ARMS[:2])
    assert len(library(*ARMS[:2], accelerations=True)) == library_size(*ARMS[:2], accelerations=True)
