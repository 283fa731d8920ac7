"""Quantities at the boundary: the fast unit table against pint, and the bounded grammar."""

from __future__ import annotations

import math

import pint
import pytest

from quickrelease.errors import UnitError
from quickrelease.units import _FAST_UNITS, DIMENSIONS, MAX_LENGTH, parse_quantity

UREG = pint.UnitRegistry()


@pytest.mark.parametrize("unit", sorted(_FAST_UNITS))
def test_fast_unit_table_entry_agrees_with_pint(unit):
    """Every entry of the fast table: pint's factor to the kind's SI unit, and pint's dimension of the kind."""
    kind, factor = _FAST_UNITS[unit]
    si_unit, dimensionality = DIMENSIONS[kind]
    quantity = UREG.Quantity(1.0, unit)
    si = UREG.Quantity(1.0, si_unit or "dimensionless")
    assert quantity.dimensionality == si.dimensionality
    # as dimensions, not as text: pint 0.23 orders the factors otherwise ([length] ** 2 * [mass] / ...)
    assert quantity.dimensionality == (UREG.get_dimensionality(dimensionality) if dimensionality else
                                       UREG.Quantity(1.0).dimensionality)
    assert factor == pytest.approx(quantity.to(si.units).magnitude, rel=1e-15)


def test_fast_table_agrees_with_the_pint_path():
    """Parsed through the table or (with a spelling the table lacks) through pint: the same SI value."""
    assert parse_quantity("2.5 MN", "force", "P") == pytest.approx(
        parse_quantity("2.5 meganewton", "force", "P"), rel=1e-15)
    assert parse_quantity("11.46 deg", "angle", "a") == pytest.approx(11.46 * math.pi / 180, rel=1e-15)


@pytest.mark.parametrize("text,fragment", [
    ("kN", "'kN' has no number"),
    ("deg", "has no number"),
    ("9**9**9", "is not a unit"),
    ("2*3 kN", "is not a unit"),
    ("1 2", "is not a unit"),
    ("nan", "is not a finite number"),
    ("-inf kN", "is not a finite number"),
    ("1e99999", "overflows"),
    ("1e308 MN", "overflows in SI units"),
    ("", "has no number"),
    ("1 m^999", "is not a unit"),
    ("\x1b[31m1", "has no number"),
    ("\uff12.\uff15 kN", "has no number"),  # fullwidth digits: float() would read 2.5
    ("\u0662 kN", "has no number"),  # an Arabic-Indic two
    ("1 m^\u0662", "is not a unit"),
])
def test_bad_quantities_are_refused_naming_the_parameter(text, fragment):
    with pytest.raises(UnitError) as info:
        parse_quantity(text, "force", "--force")
    message = str(info.value)
    assert message.startswith("--force = ") and fragment in message and "\n" not in message
    assert "\x1b" not in message


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf"), 10**400])
def test_bad_numbers_from_files_are_refused(value):
    with pytest.raises(UnitError, match="force = "):
        parse_quantity(value, "force", "force")


def test_long_text_is_refused_at_once():
    """A 100k-character string never reaches pint (it hung there): refused by its length."""
    for text in ("1" * 100_000, "1 " + "k" * 100_000, "(" * 50_000 + "1"):
        with pytest.raises(UnitError, match=f"at most {MAX_LENGTH} characters"):
            parse_quantity(text, "force", "P")


@pytest.mark.parametrize("text,kind,expected", [
    ("1598 kN", "force", 1.598e6), ("1598kN", "force", 1.598e6), ("0.5 mm", "length", 5e-4),
    ("5 m/s^2", "acceleration", 5.0), ("2 kN*m", "energy", 2000.0), ("1 1/s", "frequency", 1.0),
    ("10 degree", "angle", math.pi / 18), ("+.5e1 s", "time", 5.0), ("2 lbf", "force", 2 * 4.4482216152605),
])
def test_good_quantities(text, kind, expected):
    assert parse_quantity(text, kind, "x") == pytest.approx(expected, rel=1e-13)


@pytest.mark.parametrize("value", ["2.5 kg", "0.3 m"])
def test_a_unit_on_a_dimensionless_number_says_so(value):
    """A friction coefficient or damping exponent given a unit: "expected a dimensionless number (no unit)"; it read
    "expected a dimensionless (e.g. in a dimensionless number)". A quantity of a unit's kind names its SI unit."""
    with pytest.raises(UnitError) as exc:
        parse_quantity(value, "dimensionless", "damping_exponent")
    assert str(exc.value).endswith("; expected a dimensionless number (no unit)"), str(exc.value)
    assert str(exc.value).startswith(f"damping_exponent = {value!r} has dimension [")
    with pytest.raises(UnitError, match=r"has dimension \[mass\]; expected a force \(e\.g\. in N\)$"):
        parse_quantity("2 kg", "force", "force")
    with pytest.raises(UnitError, match=r"has dimension \[length\]; expected an angle \(e\.g\. in rad\)$"):
        parse_quantity("3 m", "angle", "alpha0")
