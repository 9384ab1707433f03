"""The units of a case's parameters: any coherent SI unit that pint reads, or "-" for a pure number
(`si_dimension`), and the dimensions whose every value must be positive."""

import functools
import math
import re

import pint

# A parameter's unit (params.<name>.unit) is any SI unit that pint reads ("N s/m", "kg m^2", "rad/s"),
# coherent (no prefix, no factor: every value of a case is in SI), or "-" for a pure number.
UNIT_REGISTRY = pint.UnitRegistry()
DIMENSIONLESS = "-"
UNIT_TEXT = re.compile(r"(?:1\s*/\s*)?[A-Za-z_ ]+(?:(?:\^|\*\*)-?[1-9])?(?:\s*[*/ ]\s*[A-Za-z_]+(?:(?:\^|\*\*)-?[1-9])?)*")
# Quantities whose every value must be positive, in every case, by their dimension.  Whatever else a
# parameter must satisfy depends on the case (a length may be a body's size, > 0, or a position, of any
# sign): its bounds in [params] and the case's [[constraints]].
POSITIVE_UNITS = {"kg": "a mass", "N/m": "a stiffness", "kg m^2": "a moment of inertia"}
POSITIVE_DIMENSIONS = {UNIT_REGISTRY.Quantity(1.0, unit).dimensionality: what for unit, what in POSITIVE_UNITS.items()}


@functools.cache  # pint parses a unit in ~0.1 ms, and every parameter set drawn checks every parameter's unit
def si_dimension(unit):
    """The dimension of `unit`, a coherent SI unit or "-"; ValueError saying why it is not one."""
    if unit == DIMENSIONLESS:
        return UNIT_REGISTRY.Quantity(1.0).dimensionality
    if not unit.strip():
        raise ValueError(f"is empty; write '{DIMENSIONLESS}' for a pure number")
    if not UNIT_TEXT.fullmatch(unit):  # before pint's parser, which evaluates what it reads
        raise ValueError(f"is not a unit: write SI units with letters, spaces, / and ^ or ** and small integer "
                         f"powers, as in 'N s/m' or 'kg m^2', or '{DIMENSIONLESS}' for a pure number")
    try:
        base = UNIT_REGISTRY.Quantity(1.0, unit).to_base_units()
    except Exception as error:  # pint's parser fails in many ways (its errors, tokenize's, Python's)
        raise ValueError(f"is not a unit ({type(error).__name__}: {error}); write SI units as in 'N s/m' or "
                         f"'kg m^2', or '{DIMENSIONLESS}' for a pure number") from None
    if not math.isclose(base.magnitude, 1.0, rel_tol=1e-12):
        raise ValueError(f"is not a coherent SI unit: 1 {unit} = {base.magnitude:g} {base.units:~}; every value of a "
                         f"case is in SI, so give it in {base.units:~}")
    return base.dimensionality
