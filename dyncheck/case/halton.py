"""The scrambled Halton sequence that the random states are drawn from: scipy.stats.qmc.Halton(d, scramble=True,
seed=rng), the same numbers bit for bit (tests/test_halton.py), without scipy.stats, whose import (its distributions'
docstrings parsed, scipy.optimize, .spatial and .special) takes a second, more than `dyncheck run --quick`'s checks."""

import math

import numpy as np

def halton(d, count, rng):
    """The first `count` points of the d-dimensional sequence scrambled by `rng` (a numpy Generator), (count, d) in
    [0, 1).  As scipy draws it: a child of rng's seed sequence shuffles, base after base, one permutation of the
    digits per digit that a double resolves (Owen's scrambling, A. B. Owen, "A randomized Halton algorithm in R",
    arXiv:1706.02808), and point i in base b is sum_j perm_j(digit_j of i) b^-(j+1), summed from the first digit."""
    bits = rng.bit_generator
    shuffler = np.random.Generator(type(bits)(bits.seed_seq.spawn(1)[0]))
    index = np.arange(count)
    points = np.empty((count, d))
    for k, base in enumerate(primes(d)):
        permutations = np.repeat(np.arange(base)[None], math.ceil(54 / math.log2(base)) - 1, axis=0)
        for permutation in permutations:
            shuffler.shuffle(permutation)
        quotient, weight, value = index.copy(), 1.0 / base, np.zeros(count)
        for permutation in permutations:
            value += permutation[quotient % base] * weight
            quotient //= base
            weight /= base
        points[:, k] = value
    return points


def primes(count):
    """The first `count` primes, the bases of the sequence's dimensions."""
    found, candidate = [], 2
    while len(found) < count:
        if all(candidate % p for p in found if p * p <= candidate):
            found.append(candidate)
        candidate += 1
    return found
