"""Quantities at the boundary: parse numbers with units into SI floats (pint).

Inside quickrelease every number is SI (N, m, kg, s, rad, J, Pa). This module is
the one place where strings such as ``"1598 kN"`` or ``"11.46 deg"`` become floats;
it is used by the device loader, the command line and the Python API's entry points (which also take
pint Quantities: :func:`si`, :func:`si_scalar`), never by the physics. pint is imported on first use only.
"""

from __future__ import annotations

import math
import numbers
import re
import sys
from functools import lru_cache
from typing import Any

import numpy as np

from .errors import ParameterError, UnitError

__all__ = ["DIMENSIONS", "parse_quantity", "si", "si_scalar", "is_quantity"]

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
    "stiffness": ("N/m", "[mass] / [time] ** 2"),
    "slowness": ("s/m", "[time] / [length]"),
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
    "N/m": ("stiffness", 1.0), "kN/m": ("stiffness", 1e3), "MN/m": ("stiffness", 1e6),
    "s/m": ("slowness", 1.0),
}


#: Longest quantity string accepted (a number and a unit never need more); longer text is refused before
#: any parsing, so no input can make pint's tokenizer work for long.
MAX_LENGTH = 100

#: A quantity: a finite decimal number (no nan, inf, hex or underscores), then optionally a unit.
#: ASCII digits only: Python's \d and float() take any script's digits ('２.５' would read as 2.5).
_QUANTITY = re.compile(r"(?P<number>[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)\s*(?P<unit>.*)",
                       re.DOTALL)
#: A unit: names joined by '*', '/' or a space, each with an optional small integer power (^2, **-1);
#: '1/s' style reciprocals too. No numbers elsewhere, no nested powers, no parentheses: nothing pint
#: could spend long on, and nothing that is an expression rather than a unit.
_NAME = r"(?:[A-Za-z_\u00b0\u00b5\u03bc\u03a9\u2126%][A-Za-z_0-9\u00b0\u00b5\u03bc\u03a9\u2126]*)"
_POWER = r"(?:\s*(?:\^|\*\*)\s*[+-]?[0-9]{1,2})?"
_UNIT = re.compile(rf"(?:1\s*/\s*)?{_NAME}{_POWER}(?:\s*(?:\*|/|\s)\s*{_NAME}{_POWER})*")


def _split(text: str, name: str) -> tuple[float, str]:
    """``"1598 kN"`` -> (1598.0, "kN"): the number (finite) and the unit text ("" for a bare number).

    Raises UnitError naming ``name`` for text that is not a number optionally followed by a unit.
    """
    if len(text) > MAX_LENGTH:
        raise UnitError(f"{name} = {text[:20]!r}... is {len(text)} characters long; a quantity is a number and "
                        f"a unit of at most {MAX_LENGTH} characters, e.g. '1598 kN'")
    match = _QUANTITY.fullmatch(text)
    if match is None:
        what = "is not a finite number" if text.lower().lstrip("+-").startswith(("nan", "inf")) else "has no number"
        raise UnitError(f"{name} = {text!r} {what}; expected a number optionally followed by a unit, e.g. '1598 kN'")
    number, unit = float(match["number"]), match["unit"].strip()
    if not math.isfinite(number):
        raise UnitError(f"{name} = {text!r}: the number overflows (its magnitude is above {sys.float_info.max:.4g})")
    if unit and _UNIT.fullmatch(unit) is None:
        raise UnitError(f"{name} = {text!r}: {unit!r} is not a unit (a unit is a name such as kN, m/s^2 or "
                        "kN*m, with small integer powers; no expressions)")
    return number, unit


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
        is a bare number. The grammar is bounded: a finite decimal number, then
        optionally a unit (names with small integer powers joined by ``*``, ``/`` or
        a space), at most :data:`MAX_LENGTH` characters; a unit alone (``"kN"``), an
        expression (``"9**9**9"``, ``"2*3 kN"``), NaN and infinity are refused.
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
        When the value is not a finite quantity in that grammar, the unit is
        unknown, the dimension does not match ``kind``, or the value overflows
        in SI units (``"1e308 MN"``).
    """
    if kind not in DIMENSIONS:
        raise UnitError(f"unknown quantity kind {kind!r} for {name}; valid: {sorted(DIMENSIONS)}")
    si_unit, dimensionality = DIMENSIONS[kind]
    if isinstance(value, bool):
        raise UnitError(f"{name} = {value!r} is not a number or a quantity with units")
    if isinstance(value, int | float):
        try:
            number = float(value)
        except OverflowError:  # an int beyond the float range
            raise UnitError(f"{name} = an integer of {len(str(abs(value)))} digits is too large (above "
                            f"{sys.float_info.max:.4g})") from None
        if not math.isfinite(number):
            raise UnitError(f"{name} = {value!r} is not a finite number")
        return number
    if not isinstance(value, str):
        raise UnitError(f"{name} = {value!r} is not a number or a quantity with units")
    text = value.strip()
    number, unit = _split(text, name)
    if not unit:
        return number
    fast = _FAST_UNITS.get(unit)
    if fast is not None and fast[0] == kind:
        return _finite(number * fast[1], text, name)
    ureg = _registry()
    import pint

    try:
        units = ureg.parse_units(unit)
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError) as exc:
        raise UnitError(f"{name} = {text!r}: unknown unit ({exc})") from None
    except Exception:  # tokenizer errors of all kinds
        raise UnitError(f"{name} = {text!r}: {unit!r} is not a unit") from None
    quantity = ureg.Quantity(number, units)
    expected = ureg.Quantity(1.0, si_unit if si_unit else "dimensionless")
    if kind == "angle":
        expected = ureg.Quantity(1.0, "rad")
    if quantity.dimensionality != expected.dimensionality:
        got = str(quantity.dimensionality) if quantity.dimensionality else "dimensionless"
        raise UnitError(f"{name} = {text!r} has dimension {got}; expected {_expected_kind(kind, si_unit)}")
    try:
        converted = float(quantity.to(expected.units).magnitude)
    except OverflowError:
        converted = math.inf
    return _finite(converted, text, name)


#: pint's spelling of the SI unit of each kind (pint reads "**", not "^").
_PINT_SI = {kind: (unit.replace("^", "**") if unit else "dimensionless") for kind, (unit, _) in DIMENSIONS.items()}
_PINT_SI["angle"] = "radian"


def is_quantity(value: object) -> bool:
    """Whether ``value`` is a pint Quantity (of any registry), without importing pint."""
    return type(value).__module__.split(".")[0] == "pint" and hasattr(value, "magnitude") and hasattr(value, "to")


def quantity_to_si(value: Any, kind: str, name: str) -> Any:
    """A pint Quantity (scalar or array, of the user's own registry) as its magnitude in the SI unit of
    ``kind``; a UnitError naming ``name`` when its dimension is not that of ``kind``."""
    import pint

    try:
        magnitude = value.to(_PINT_SI[kind]).magnitude
    except pint.errors.DimensionalityError:
        raise UnitError(f"{name} = {value:~} has dimension {value.dimensionality or 'dimensionless'}; expected "
                        f"{_expected_kind(kind, DIMENSIONS[kind][0])}") from None
    return float(magnitude) if np.ndim(magnitude) == 0 else np.asarray(magnitude, dtype=float)


def _expected_kind(kind: str, si_unit: str | None) -> str:
    """What a quantity of ``kind`` is, for a dimension error: "a force (e.g. in N)"; "a dimensionless number (no
    unit)" where the kind has no unit (it read "a dimensionless (e.g. in a dimensionless number)")."""
    if not si_unit:
        return "a dimensionless number (no unit)"
    noun = kind.replace("_", " ")
    return f"{'an' if noun[0] in 'aeiou' else 'a'} {noun} (e.g. in {si_unit})"


def si(value: Any, kind: str, name: str) -> Any:
    """An argument of the Python API in SI units: a pint Quantity converted (scalar or array), a string with
    units parsed by :func:`parse_quantity`; numbers and arrays (taken as SI) pass unchanged."""
    if is_quantity(value):
        return quantity_to_si(value, kind, name)
    if isinstance(value, str):
        return parse_quantity(value, kind, name)
    return value


def si_scalar(value: Any, kind: str, name: str) -> float:
    """A scalar argument of the Python API as a float in SI units: a number, a string with units or a pint
    Quantity. An array, a list, None or anything else is a :class:`ParameterError` naming ``name``."""
    value = si(value, kind, name)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        shape = np.shape(value) if isinstance(value, np.ndarray | list | tuple) else None
        got = f"an array of shape {shape}" if shape else repr(value) if len(repr(value)) < 40 else type(value).__name__
        raise ParameterError(name, got, f"single numbers in {DIMENSIONS[kind][0] or '1'} (a float, a string with "
                                        "units or a pint Quantity; for arrays, quickrelease.batch)")
    return float(value)


def _finite(value: float, text: str, name: str) -> float:
    """``value`` if finite, else the UnitError saying that ``text`` overflows in SI units."""
    if not math.isfinite(value):
        raise UnitError(f"{name} = {text!r} overflows in SI units (above {sys.float_info.max:.4g})")
    return value
