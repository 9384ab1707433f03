"""The amplitude of the vibration analysis's runs (dyncheck.vibration.settled_amplitude): halved while its nonlinear
shift would take the rows' tolerance near their ceiling, and no further than HALVINGS."""

import math

import pytest

from dyncheck import ceilings, vibration


class _Run:  # a run's measured exponent, as a Motion gives it
    def __init__(self, exponent, ok=True):
        self.exponent, self.ok = exponent, ok


@pytest.mark.parametrize("power, halvings", [(2, 2), (1, 4)])
def test_the_amplitude_is_halved_until_its_shift_is_a_tenth_of_the_ceiling(power, halvings):
    # A shift of 1.5e-5 |lambda| at the case's amplitude, quadratic or linear in it: 10 x the shift must come within
    # a tenth of the ceiling 1e-4, i.e. the shift within 1e-6: two halvings (9.4e-7) or four (9.4e-7).
    size, asked = 50.0, []
    pair = lambda a: asked.append(a) or (_Run(0.0), _Run(1.5e-5 * size * (a / 1e-3) ** power))
    amplitude, runs, shift = vibration.settled_amplitude(1e-3, size, pair, lambda at, doubled: doubled.exponent - at.exponent)
    assert amplitude == 1e-3 / 2**halvings and asked == [1e-3 / 2**k for k in range(halvings + 1)]
    assert shift == runs[1].exponent and vibration.SAFETY * shift <= ceilings.MOTION / 10 * size


def test_a_failed_or_hopeless_run_is_not_halved_forever():
    failed = lambda a: (_Run(None, ok=False), _Run(0.0))
    assert vibration.settled_amplitude(1e-3, 1.0, failed, None)[::2] == (1e-3, math.inf)
    large = lambda a: (_Run(0.0), _Run(1.0))  # a shift no amplitude removes: the case's amplitude / 2^HALVINGS
    assert vibration.settled_amplitude(1e-3, 1.0, large, lambda at, d: d.exponent)[0] == 1e-3 / 2**vibration.HALVINGS
