"""Exceptions raised by quickrelease.

Every error raised for bad input is a :class:`ValueError` subclass, so callers may
catch either the specific type or the built-in one. Messages are one line and name
the parameter, the value given and the valid range, e.g.
``alpha0 = -0.1 rad is outside (0, pi/2)``.
"""

from __future__ import annotations

__all__ = [
    "QuickReleaseError",
    "ParameterError",
    "DeviceFileError",
    "UnitError",
    "InfeasibleObservationError",
    "OutputError",
    "CaseFileError",
]


class QuickReleaseError(ValueError):
    """Base class of every input error raised by quickrelease."""


class ParameterError(QuickReleaseError):
    """A parameter value is outside its valid range.

    Parameters
    ----------
    name : str
        The parameter's name as the user knows it (``alpha0``, ``F1``, ``m1``).
    value : object
        The offending value (printed with ``unit``).
    valid : str
        The valid range in words or interval notation, e.g. ``"(0, pi/2)"``.
    unit : str, optional
        Unit printed after the value.
    """

    def __init__(self, name: str, value: object, valid: str, unit: str = "") -> None:
        self.name = name
        self.value = value
        self.valid = valid
        self.unit = unit
        shown = f"{value:.6g}" if isinstance(value, float) else f"{value}"
        if unit:
            shown = f"{shown} {unit}"
        super().__init__(f"{name} = {shown} is outside {valid}")

    def __reduce__(self):
        """Pickled with its own arguments: a campaign's release fitted in another process raises it back whole (it
        came back as a TypeError, a traceback, as ``Exception`` pickles the message alone)."""
        return type(self), (self.name, self.value, self.valid, self.unit)


class DeviceFileError(QuickReleaseError):
    """A device or case file is malformed, or an entry in it is missing, unknown or invalid.

    The message names the file and the key.
    """


class UnitError(QuickReleaseError):
    """A quantity could not be parsed, or it has the wrong physical dimension."""


class InfeasibleObservationError(QuickReleaseError):
    """The observed stop time cannot be produced on the line of Eq. 13.

    Attributes
    ----------
    stop_time : float
        The observed stop time t_F [s].
    feasible : tuple of float
        ``(t_F(F1 = 0), t_F(F1 = F1*))`` [s], the interval the model can produce.
    """

    def __init__(self, stop_time: float, feasible: tuple[float, float]) -> None:
        self.stop_time = stop_time
        self.feasible = feasible
        lo, hi = feasible
        super().__init__(
            f"t_F = {stop_time:.6g} s is outside the feasible interval "
            f"[t_F(F1 = 0), t_F(F1 = F1*)] = [{lo:.6g}, {hi:.6g}] s"
        )


class OutputError(QuickReleaseError):
    """An output path cannot take the result, or a folder holds something the run must not mix with."""


class CaseFileError(QuickReleaseError):
    """A case file is malformed or one of its entries is missing, unknown or invalid."""
