"""The fast unit table of units.py against pint: every entry, factor and kind (issue 9, item 19)."""

import pint
import pytest

from quickrelease.units import _FAST_UNITS, DIMENSIONS, parse_quantity

UREG = pint.UnitRegistry()


@pytest.mark.parametrize("unit", sorted(_FAST_UNITS))
def test_fast_unit_factor_and_kind_against_pint(unit):
    """pint converts one of the unit to the kind's SI unit: the table's factor, to the last bit or two, and the
    unit's dimensionality is the kind's; the parser gives the same through the table."""
    kind, factor = _FAST_UNITS[unit]
    si, dimensionality = DIMENSIONS[kind]
    q = UREG.Quantity(1.0, unit.replace("^", "**"))
    assert q.dimensionality == UREG.Quantity(1.0, si.replace("^", "**") or "dimensionless").dimensionality
    if dimensionality:
        assert str(q.dimensionality) == dimensionality
    assert q.to(si.replace("^", "**")).magnitude == pytest.approx(factor, rel=4e-16)
    assert parse_quantity(f"2.5 {unit}", kind, "x") == pytest.approx(2.5 * factor, rel=4e-16)
