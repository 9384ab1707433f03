"""dyncheck.case.halton draws the random states as scipy.stats.qmc.Halton does, bit for bit: the reports' states
(and every number measured at them) stay what they were."""

import numpy as np
import pytest
from scipy.stats import qmc

from dyncheck.case.halton import halton, primes


@pytest.mark.parametrize("d", [1, 2, 5, 9, 15, 30])
def test_the_sequence_is_scipys(d):
    for seed, stream in [(0, 0), (12345, 0), (12345, 3), (7, 11)]:
        theirs = qmc.Halton(d, scramble=True, seed=np.random.default_rng([seed, stream])).random(300)
        assert np.array_equal(halton(d, 300, np.random.default_rng([seed, stream])), theirs), (d, seed, stream)


def test_a_point_does_not_depend_on_how_many_follow():
    rng = lambda: np.random.default_rng([3, 0])
    assert np.array_equal(halton(4, 20, rng()), halton(4, 256, rng())[:20])


def test_the_bases_are_the_primes():
    assert primes(10) == [2, 3, 5, 7, 11, 13, 17, 19, 23, 29] and primes(0) == []
