"""The closed-form results of the paper for a device: the public face of :mod:`quickrelease.device.dynamics`.

The physics layer (:mod:`quickrelease.device.dynamics`) takes the device's numbers (m1, m2, L1, c) as SI floats or
arrays, as the paper's equations do. These are the same functions with the one vocabulary of the rest of the
API: the device as ``device=`` (the paper's by default), the mass model as ``mass_model=`` (``"distributed"``,
``"lumped"`` or a number c), the stored energy as ``stored_energy``. Quantity arguments take SI numbers or
arrays, strings with units and pint Quantities.

The old calls, with the device's numbers after the other arguments (``final_angle(E_S, alpha0, F1, F2, L1)``),
still work and give a DeprecationWarning; so does the keyword ``E_S=``.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._validate import renamed
from ..units import si
from . import dynamics
from .parameters import Device, preset

__all__ = ["angular_acceleration", "kinetic_energy", "initial_rate", "dissipated_energy", "final_angle",
           "reaches_geometric_limit", "friction_limits"]

#: The kind of quantity of each of the device's numbers the old signatures took.
_KINDS = {"m1": "mass", "m2": "mass", "L1": "length", "c": "dimensionless"}


def _device_numbers(func: str, old: tuple[Any, ...], names: tuple[str, ...], device: Device | None,
                    mass_model: str | float | None = None, depth: int = 0) -> tuple[float, ...]:
    """The device's numbers ``names`` (m1, m2, L1 and the mass factor c) for ``func``: from ``device`` and
    ``mass_model``, or from the old trailing positional numbers (with a DeprecationWarning pointing at the
    caller; ``depth`` 1 when ``func`` is wrapped once more, by :func:`~quickrelease._validate.renamed`)."""
    if old:
        if len(old) != len(names):
            raise TypeError(f"{func}() takes the device as device= (got {len(old)} extra positional arguments)")
        if device is not None:
            raise TypeError(f"{func}() got the device twice: device= and the numbers {', '.join(names)}")
        warnings.warn(f"{func}(..., {', '.join(names)}) is now {func}(..., device=..."
                      f"{', mass_model=...' if 'c' in names else ''}); the old form will be removed",
                      DeprecationWarning, stacklevel=3 + depth)
        return tuple(si(v, _KINDS[n], n) for n, v in zip(names, old, strict=True))
    device = device or preset("paper")
    values = {"m1": device.m1, "m2": device.m2, "L1": device.L1}
    if "c" in names:
        values["c"] = dynamics.mass_factor("distributed" if mass_model is None else mass_model)
    return tuple(values[n] for n in names)


def angular_acceleration(alpha, alpha_dot, F1, F2, *old, device: Device | None = None,
                         mass_model: str | float = "distributed"):
    """Angular acceleration of the bars, alpha_ddot (Eq. 3 lumped, Eq. 4 distributed) [rad/s^2].

    Parameters
    ----------
    alpha, alpha_dot : float or array
        Angle [rad] and angular velocity [rad/s].
    F1, F2 : float or array
        Friction at the central hinges and at the rail supports [N].
    device : Device, optional
        The device (m1, m2, L1 enter); the paper's by default.
    mass_model : {"distributed", "lumped"} or float
        Mass factor c (Eq. 5).
    """
    m1, m2, L1, c = _device_numbers("angular_acceleration", old, ("m1", "m2", "L1", "c"), device, mass_model)
    return dynamics.angular_acceleration(si(alpha, "angle", "alpha"), si(alpha_dot, "angular_velocity", "alpha_dot"),
                                         si(F1, "force", "F1"), si(F2, "force", "F2"), m1, m2, L1, c)


def kinetic_energy(alpha, alpha_dot, *old, device: Device | None = None, mass_model: str | float = "distributed"):
    """Kinetic energy of the device, ``E_K = m2 L1^2 (c m1/m2 + sin^2 alpha) alpha_dot^2`` (Eq. 5) [J].

    ``alpha`` [rad] and ``alpha_dot`` [rad/s] are floats or arrays; ``device`` and ``mass_model`` as in
    :func:`angular_acceleration`.
    """
    m1, m2, L1, c = _device_numbers("kinetic_energy", old, ("m1", "m2", "L1", "c"), device, mass_model)
    return dynamics.kinetic_energy(si(alpha, "angle", "alpha"), si(alpha_dot, "angular_velocity", "alpha_dot"),
                                   m1, m2, L1, c)


@renamed(E_S="stored_energy")
def initial_rate(stored_energy, alpha0, *old, device: Device | None = None, mass_model: str | float = "distributed"):
    """Angular velocity just after release, ``sqrt(E_S / (m2 L1^2 (c m1/m2 + sin^2 alpha0)))`` (Eq. 6) [rad/s].

    ``stored_energy`` E_S [J], ``alpha0`` [rad]; ``device`` and ``mass_model`` as in :func:`angular_acceleration`.
    """
    m1, m2, L1, c = _device_numbers("initial_rate", old, ("m1", "m2", "L1", "c"), device, mass_model, 1)
    return dynamics.initial_rate(si(stored_energy, "energy", "E_S"), si(alpha0, "angle", "alpha0"), m1, m2, L1, c)


def dissipated_energy(alpha, alpha0, F1, F2, *old, device: Device | None = None):
    """Energy dissipated by friction from alpha0 to alpha, W_F (Eq. 7) [J].

    ``alpha``, ``alpha0`` [rad], ``F1``, ``F2`` [N]; ``device`` (L1 enters) the paper's by default.
    """
    (L1,) = _device_numbers("dissipated_energy", old, ("L1",), device)
    return dynamics.dissipated_energy(si(alpha, "angle", "alpha"), si(alpha0, "angle", "alpha0"),
                                      si(F1, "force", "F1"), si(F2, "force", "F2"), L1)


@renamed(E_S="stored_energy")
def final_angle(stored_energy, alpha0, F1, F2, *old, device: Device | None = None):
    """Angle at which the device stops, alpha_F, from Eq. 8 in closed form [rad] (pi/2 where it reaches the
    flat rhombus, :func:`reaches_geometric_limit`).

    Parameters
    ----------
    stored_energy : float or array
        E_S [J].
    alpha0 : float or array
        Angle at release [rad].
    F1, F2 : float or array
        Friction at the central hinges and at the rail supports [N].
    device : Device, optional
        The device (L1 enters); the paper's by default.

    See :func:`quickrelease.device.dynamics.final_angle` for the cancellation-free evaluation.
    """
    (L1,) = _device_numbers("final_angle", old, ("L1",), device, depth=1)
    return dynamics.final_angle(stored_energy, alpha0, F1, F2, L1)


@renamed(E_S="stored_energy")
def reaches_geometric_limit(stored_energy, alpha0, F1, F2, *old, device: Device | None = None):
    """True where friction cannot dissipate E_S before the rhombus is flat: ``E_S > W_F(pi/2)`` (Eq. 7).

    Arguments as in :func:`final_angle`.
    """
    (L1,) = _device_numbers("reaches_geometric_limit", old, ("L1",), device, depth=1)
    return dynamics.reaches_geometric_limit(si(stored_energy, "energy", "E_S"), si(alpha0, "angle", "alpha0"),
                                            si(F1, "force", "F1"), si(F2, "force", "F2"), L1)


@renamed(E_S="stored_energy")
def friction_limits(stored_energy, alpha0, alpha_final, *old, device: Device | None = None) -> dict[str, Any]:
    """Upper bounds of the friction forces, F1* (Eq. 11) and F2* (Eq. 12) [N].

    ``F1* = E_S / (2 L1 (sin alpha_F - sin alpha0))``, ``F2* = E_S / (4 L1 (cos alpha0 - cos alpha_F))``.
    ``stored_energy`` E_S [J], ``alpha0`` and ``alpha_final`` alpha_F [rad]; ``device`` (L1 enters) the
    paper's by default. Returns ``{"F1_max": F1*, "F2_max": F2*}``.
    """
    (L1,) = _device_numbers("friction_limits", old, ("L1",), device, depth=1)
    limits = dynamics.friction_limits(si(stored_energy, "energy", "E_S"), si(alpha0, "angle", "alpha0"),
                                      si(alpha_final, "angle", "alpha_final"), L1)
    return {k: float(v) if np.ndim(v) == 0 else v for k, v in limits.items()}  # floats for scalars, as elsewhere
