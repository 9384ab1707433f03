"""The units that dyncheck.case.units reads without pint (COHERENT and their products) mean what pint reads them as;
every other unit is pint's to judge."""

import subprocess
import sys

import pytest

from dyncheck.case import units
from dyncheck.case.units import BASE, COHERENT, coherent_dimension, registry, si_dimension


def pints(unit):
    """Pint's reading of `unit`: its factor to SI and its dimension as dyncheck writes it."""
    base = registry().Quantity(1.0, unit).to_base_units()
    return base.magnitude, tuple(int(base.dimensionality.get(name, 0)) for name in BASE)


@pytest.mark.parametrize("unit", sorted(COHERENT))
def test_each_coherent_unit_is_pints(unit):
    assert pints(unit) == (1.0, coherent_dimension(unit))


@pytest.mark.parametrize("unit", ["N s/m", "N/m s", "m/s/s", "1/s", "1 / s^2", "kg m^2", "kg*m**2", "m**-2 kg",
                                  "m^2/s^-1", "rad/s", "W s", "kg / m / s", "N m/rad"])
def test_a_product_of_them_is_read_as_pint_reads_it(unit):
    assert pints(unit) == (1.0, coherent_dimension(unit))


def test_any_other_unit_is_pints_to_judge():
    assert coherent_dimension("newton") is None and si_dimension("newton") == si_dimension("N")
    assert coherent_dimension("mm") is None
    with pytest.raises(ValueError, match="not a coherent SI unit: 1 N/mm = 1000"):
        si_dimension("N/mm")
    assert si_dimension("-") == (0,) * len(BASE) == si_dimension("rad")


def test_reading_the_coherent_units_imports_no_pint():
    code = "import sys\nfrom dyncheck.case import units\nunits.si_dimension('N s/m')\nprint('pint' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout == "False\n"
    assert units.POSITIVE_DIMENSIONS[si_dimension("N/m")] == "a stiffness"
