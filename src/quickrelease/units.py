"""Quantities at the boundary: parse numbers with units into SI floats (pint).

Inside quickrelease every number is SI (N, m, kg, s, rad, J, Pa). This module is
the one place where strings such as ``"1598 kN"`` or ``"11.46 deg"`` become floats;
it is used by the device loader and the command line, never by the physics.
pint is imported on first use only.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

from .errors import UnitError

__all__ = ["DIMENSIONS", "parse_quantity"]

#: Physical kinds understood by :func:`parse_quantity`: (SI unit, pint dimensionality).
DIMENSIONS: dict[str, tuple[str, str]] = {
    "force": ("N", "[mass] * [length] / [time] ** 2"),
    "energy": ("J", "[mass] * [length] ** 2 / [time] ** 2"),
    "angle": ("rad", ""),
    "time": ("s", "[time]"),
    "length": ("m", "[length]"),
    "area": ("m^2", "[length] ** 2"),
    "second_moment": ("m^4", "[length] ** 4"),
    "section_modulus": ("m^3", "[length] ** 3"),
    "mass": ("kg", "[mass]"),
    "pressure": ("Pa", "[mass] / [length] / [time] ** 2"),
    "dimensionless": ("", ""),
    "frequency": ("Hz", "1 / [time]"),
    "velocity": ("m/s", "[length] / [time]"),
    "acceleration": ("m/s^2", "[length] / [time] ** 2"),
    "angular_velocity": ("rad/s", "1 / [time]"),
    "angular_acceleration": ("rad/s^2", "1 / [time] ** 2"),
}


#: Exact SI factors of common units, so that "1598 kN" needs no pint (importing it costs ~0.3 s).
#: Anything else goes to pint. A test checks every entry against pint.
_FAST_UNITS: dict[str, tuple[str, float]] = {
    "N": ("force", 1.0), "kN": ("force", 1e3), "MN": ("force", 1e6),
    "J": ("energy", 1.0), "kJ": ("energy", 1e3), "MJ": ("energy", 1e6),
    "rad": ("angle", 1.0), "deg": ("angle", math.pi / 180.0), "mrad": ("angle", 1e-3),
    "s": ("time", 1.0), "ms": ("time", 1e-3),
    "m": ("length", 1.0), "cm": ("length", 1e-2), "mm": ("length", 1e-3),
    "m^2": ("area", 1.0), "cm^2": ("area", 1e-4), "mm^2": ("area", 1e-6),
    "m^4": ("second_moment", 1.0), "cm^4": ("second_moment", 1e-8), "mm^4": ("second_moment", 1e-12),
    "m^3": ("section_modulus", 1.0), "cm^3": ("section_modulus", 1e-6), "mm^3": ("section_modulus", 1e-9),
    "kg": ("mass", 1.0), "t": ("mass", 1e3),
    "Pa": ("pressure", 1.0), "kPa": ("pressure", 1e3), "MPa": ("pressure", 1e6), "GPa": ("pressure", 1e9),
    "Hz": ("frequency", 1.0),
    "m/s": ("velocity", 1.0), "m/s^2": ("acceleration", 1.0),
    "rad/s": ("angular_velocity", 1.0), "rad/s^2": ("angular_acceleration", 1.0),
}


def _fast(text: str, kind: str) -> float | None:
    """SI value of '<number> <unit>' for a unit of :data:`_FAST_UNITS` of the right kind, else None."""
    number, _, unit = text.partition(" ")
    entry = _FAST_UNITS.get(unit.strip())
    if entry is None or entry[0] != kind:
        return None
    try:
        value = float(number)
    except ValueError:
        return None
    return value * entry[1] if entry[1] != 1.0 else value


@lru_cache(maxsize=1)
def _registry() -> Any:
    import pint

    return pint.UnitRegistry()


def parse_quantity(value: object, kind: str, name: str) -> float:
    """Convert ``value`` to a float in the SI unit of ``kind``.

    Parameters
    ----------
    value : float, int or str
        A bare number (taken as SI) or a string with units (``"1598 kN"``,
        ``"531 mm^2"``, ``"11.46 deg"``, ``"0.57678 t"``). A string without a unit
        is a bare number.
    kind : str
        One of :data:`DIMENSIONS` (``"force"``, ``"angle"``, ...).
    name : str
        The parameter's name, used in error messages.

    Returns
    -------
    float
        The value in SI units (angles in rad).

    Raises
    ------
    UnitError
        When the string is not a quantity, the unit is unknown, or the dimension
        does not match ``kind``.
    """
    if kind not in DIMENSIONS:
        raise UnitError(f"unknown quantity kind {kind!r} for {name}; valid: {sorted(DIMENSIONS)}")
    si_unit, dimensionality = DIMENSIONS[kind]
    if isinstance(value, bool):
        raise UnitError(f"{name} = {value!r} is not a number or a quantity with units")
    if isinstance(value, int | float):
        return float(value)
    if not isinstance(value, str):
        raise UnitError(f"{name} = {value!r} is not a number or a quantity with units")
    text = value.strip()
    try:
        return float(text)
    except ValueError:
        pass
    fast = _fast(text, kind)
    if fast is not None:
        return fast
    ureg = _registry()
    import pint

    try:
        quantity = ureg.Quantity(text)
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError) as exc:
        raise UnitError(f"{name} = {text!r}: unknown unit ({exc})") from None
    except Exception:  # tokenizer errors of all kinds
        raise UnitError(f"{name} = {text!r} is not a number or a quantity with units") from None
    if not isinstance(quantity, ureg.Quantity):  # e.g. "pi" parses to a plain number
        return float(quantity)
    expected = ureg.Quantity(1.0, si_unit if si_unit else "dimensionless")
    if kind == "angle":
        expected = ureg.Quantity(1.0, "rad")
    if quantity.dimensionality != expected.dimensionality:
        want = si_unit or "a dimensionless number"
        got = str(quantity.dimensionality) if quantity.dimensionality else "dimensionless"
        noun = kind.replace("_", " ")
        article = "an" if noun[0] in "aeiou" else "a"
        raise UnitError(f"{name} = {text!r} has dimension {got}; expected {article} {noun} (e.g. in {want})")
    return float(quantity.to(expected.units).magnitude)
