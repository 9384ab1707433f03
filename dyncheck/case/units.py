"""The units of a case's parameters: any coherent SI unit that pint reads, or "-" for a pure number
(`si_dimension`), and the dimensions whose every value must be positive."""

import functools
import math
import re

# A parameter's unit (params.<name>.unit) is any SI unit that pint reads ("N s/m", "kg m^2", "rad/s"),
# coherent (no prefix, no factor: every value of a case is in SI), or "-" for a pure number.
DIMENSIONLESS = "-"
UNIT_TEXT = re.compile(r"(?:1\s*/\s*)?[A-Za-z_ ]+(?:(?:\^|\*\*)-?[1-9])?(?:\s*[*/ ]\s*[A-Za-z_]+(?:(?:\^|\*\*)-?[1-9])?)*")
# A dimension: its exponents of pint's base dimensions, in this order.
BASE = ("[mass]", "[length]", "[time]", "[current]", "[temperature]", "[substance]", "[luminosity]")
# The coherent SI units that case files write, by their dimensions, read here: pint's import and its registry of
# units take three quarters of a second, which every command's start-up would pay (`dyncheck run --quick`'s checks
# take less).  Pint reads every other unit, and judges it (a prefix, a name, "deg"): tests/test_units.py holds these
# to pint's reading.
COHERENT = {"kg": (1, 0, 0), "m": (0, 1, 0), "s": (0, 0, 1), "rad": (0, 0, 0), "N": (1, 1, -2), "J": (1, 2, -2),
            "W": (1, 2, -3), "Pa": (1, -1, -2), "Hz": (0, 0, -1), "A": (0, 0, 0, 1), "K": (0, 0, 0, 0, 1),
            "mol": (0, 0, 0, 0, 0, 1), "cd": (0, 0, 0, 0, 0, 0, 1)}
FACTOR = re.compile(r"([*/]?)\s*([A-Za-z_]+)(?:(?:\^|\*\*)(-?[1-9]))?")  # an operator, a unit, its power
# Quantities whose every value must be positive, in every case, by their dimension.  Whatever else a
# parameter must satisfy depends on the case (a length may be a body's size, > 0, or a position, of any
# sign): its bounds in [params] and the case's [[constraints]].
POSITIVE_UNITS = {"kg": "a mass", "N/m": "a stiffness", "kg m^2": "a moment of inertia"}


@functools.cache
def registry():
    """Pint's registry of units, loaded where a unit is not one of COHERENT's products."""
    import pint
    return pint.UnitRegistry()


def coherent_dimension(unit):
    """The dimension of `unit`, text that UNIT_TEXT matches, where it is a product of COHERENT's units and their
    powers; None where it names another.  As pint reads it: left to right, a space or * multiplying, / dividing by
    the one factor after it ("N/m s" is N s/m)."""
    dimension = [0] * len(BASE)
    for operator, name, power in FACTOR.findall(unit):  # a leading "1/" is an operator before its first unit
        if name not in COHERENT:
            return None
        exponent = int(power or 1) * (-1 if operator == "/" else 1)
        for i, base in enumerate(COHERENT[name]):
            dimension[i] += exponent * base
    return tuple(dimension)


@functools.cache  # pint parses a unit in ~0.1 ms, and every parameter set drawn checks every parameter's unit
def si_dimension(unit):
    """The dimension of `unit`, a coherent SI unit or "-"; ValueError saying why it is not one."""
    if unit == DIMENSIONLESS:
        return (0,) * len(BASE)
    if not unit.strip():
        raise ValueError(f"is empty; write '{DIMENSIONLESS}' for a pure number")
    if not UNIT_TEXT.fullmatch(unit):  # before pint's parser, which evaluates what it reads
        raise ValueError(f"is not a unit: write SI units with letters, spaces, / and ^ or ** and small integer "
                         f"powers, as in 'N s/m' or 'kg m^2', or '{DIMENSIONLESS}' for a pure number")
    known = coherent_dimension(unit)
    if known is not None:
        return known
    try:
        base = registry().Quantity(1.0, unit).to_base_units()
    except Exception as error:  # pint's parser fails in many ways (its errors, tokenize's, Python's)
        raise ValueError(f"is not a unit ({type(error).__name__}: {error}); write SI units as in 'N s/m' or "
                         f"'kg m^2', or '{DIMENSIONLESS}' for a pure number") from None
    if not math.isclose(base.magnitude, 1.0, rel_tol=1e-12):
        raise ValueError(f"is not a coherent SI unit: 1 {unit} = {base.magnitude:g} {base.units:~}; every value of a "
                         f"case is in SI, so give it in {base.units:~}")
    return tuple(int(base.dimensionality.get(name, 0)) for name in BASE)


POSITIVE_DIMENSIONS = {si_dimension(unit): what for unit, what in POSITIVE_UNITS.items()}
