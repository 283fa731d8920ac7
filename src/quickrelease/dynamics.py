"""Release dynamics: equation of motion, energies, initial rate and final angle (Eq. 3-13).

One degree of freedom, the bar angle alpha(t). Coulomb friction F1 acts at the
central hinges (work ``2 F1 dv``) and F2 at the rail supports of the heads (work
``4 F2 du``), Fig. 9. The mass factor c is 1 for the lumped mass model (Eq. 3) and
2/3 for the distributed mass model (Eq. 4). All functions are pure and accept
floats or numpy arrays (broadcast).

Symbols: m1 mass of one bar E1 [kg], m2 mass of one head E2 [kg], L1 bar length [m],
E_S stored strain energy [J], F1, F2 friction forces [N].
"""

from __future__ import annotations

import math

import numpy as np

from ._validate import HALF_PI
from .errors import ParameterError

__all__ = [
    "MASS_MODELS",
    "mass_factor",
    "generalized_mass",
    "angular_acceleration",
    "kinetic_energy",
    "initial_rate",
    "dissipated_energy",
    "dissipation_at_limit",
    "remaining_energy",
    "final_angle",
    "reaches_geometric_limit",
    "friction_limits",
]

#: Named mass models and their factor c (Eq. 5): lumped (Eq. 3) and distributed (Eq. 4).
MASS_MODELS: dict[str, float] = {"lumped": 1.0, "distributed": 2.0 / 3.0}


def mass_factor(model: str | float) -> float:
    """The factor c multiplying m1/m2 in Eq. 3-6.

    Parameters
    ----------
    model : {"distributed", "lumped"} or float
        ``"distributed"`` (c = 2/3, Eq. 4), ``"lumped"`` (c = 1, Eq. 3), or a
        positive number (or a string holding one, such as ``"0.7"``, ``"2/3"``).

    Returns
    -------
    float
        c [-].
    """
    if isinstance(model, str):
        key = model.strip().lower()
        if key in MASS_MODELS:
            return MASS_MODELS[key]
        try:
            if "/" in key:
                num, den = key.split("/", 1)
                value = float(num) / float(den)
            else:
                value = float(key)
        except (ValueError, ZeroDivisionError):
            raise ParameterError(
                "mass_model", model, "'distributed', 'lumped' or a positive number c"
            ) from None
    elif isinstance(model, int | float) and not isinstance(model, bool):
        value = float(model)
    else:
        raise ParameterError("mass_model", model, "'distributed', 'lumped' or a positive number c")
    if not math.isfinite(value) or value <= 0.0:
        raise ParameterError("mass_factor c", value, "(0, inf)")
    return value


def generalized_mass(alpha, m1, m2, L1, c):
    """Coefficient of alpha_dot^2 in the kinetic energy, ``m2 L1^2 (c m1/m2 + sin^2 alpha)`` (Eq. 5) [kg m^2]."""
    return m2 * L1**2 * (c * m1 / m2 + np.sin(alpha) ** 2)


def angular_acceleration(alpha, alpha_dot, F1, F2, m1, m2, L1, c):
    """Angular acceleration from the equation of motion (Eq. 3 for c = 1, Eq. 4 for c = 2/3) [rad/s^2].

    ``alpha_ddot = -alpha_dot^2 sin(alpha) cos(alpha) / (c m1/m2 + sin^2 alpha)
    - (2 F2 sin(alpha) + F1 cos(alpha)) / (m2 L1 (c m1/m2 + sin^2 alpha)) sign(alpha_dot)``

    At rest (alpha_dot = 0) sign(0) = 0: friction balances inertia and the result is 0.
    """
    d = c * m1 / m2 + np.sin(alpha) ** 2
    return (
        -(alpha_dot**2) * np.sin(alpha) * np.cos(alpha) / d
        - (2.0 * F2 * np.sin(alpha) + F1 * np.cos(alpha)) / (m2 * L1 * d) * np.sign(alpha_dot)
    )


def kinetic_energy(alpha, alpha_dot, m1, m2, L1, c):
    """Kinetic energy of the device, ``E_K = m2 L1^2 (c m1/m2 + sin^2 alpha) alpha_dot^2`` (Eq. 5) [J]."""
    return generalized_mass(alpha, m1, m2, L1, c) * alpha_dot**2


def initial_rate(E_S, alpha0, m1, m2, L1, c):
    """Angular velocity just after release, ``sqrt(E_S / (m2 L1^2 (c m1/m2 + sin^2 alpha0)))`` (Eq. 6) [rad/s]."""
    return np.sqrt(E_S / generalized_mass(alpha0, m1, m2, L1, c))


def dissipated_energy(alpha, alpha0, F1, F2, L1):
    """Energy dissipated by friction from alpha0 to alpha (Eq. 7) [J].

    ``W_F = 2 F1 L1 (sin alpha - sin alpha0) + 4 F2 L1 (cos alpha0 - cos alpha)``,
    evaluated with the half-angle products (no cancellation near alpha0).
    """
    h = np.sin(0.5 * (alpha - alpha0))
    m = 0.5 * (alpha + alpha0)
    return 4.0 * L1 * h * (F1 * np.cos(m) + 2.0 * F2 * np.sin(m))


def dissipation_at_limit(alpha0, F1, F2, L1):
    """Energy dissipated on the way from alpha0 to the flat rhombus alpha = pi/2 (Eq. 7) [J]."""
    return 2.0 * F1 * L1 * (1.0 - np.sin(alpha0)) + 4.0 * F2 * L1 * np.cos(alpha0)


def reaches_geometric_limit(E_S, alpha0, F1, F2, L1):
    """True where friction cannot dissipate E_S before the rhombus is flat (alpha = pi/2).

    That is ``E_S > W_F(pi/2)`` (Eq. 7); there the device reaches the geometric limit
    with kinetic energy left.
    """
    return E_S > dissipation_at_limit(alpha0, F1, F2, L1)


def _phase(F1, F2, L1):
    """Amplitude R and phase phi with ``A sin(a) - B cos(a) = R sin(a - phi)``, A = 2 F1 L1, B = 4 F2 L1."""
    A = 2.0 * F1 * L1
    B = 4.0 * F2 * L1
    return np.hypot(A, B), np.arctan2(B, A)


def final_angle(E_S, alpha0, F1, F2, L1):
    """Angle at which the device stops, alpha_F, from Eq. 8 in closed form [rad].

    W_F(alpha) of Eq. 7 is a sinusoid: ``W_F = R (sin(alpha - phi) - sin(alpha0 - phi))``
    with ``R = hypot(2 F1 L1, 4 F2 L1)`` and ``phi = atan2(4 F2 L1, 2 F1 L1)``, so Eq. 8
    gives ``alpha_F = phi + arcsin(sin(alpha0 - phi) + E_S / R)``.

    Where friction cannot stop the device before the rhombus is flat (see
    :func:`reaches_geometric_limit`), the motion ends at the geometric limit and
    pi/2 is returned.
    """
    R, phi = _phase(F1, F2, L1)
    limit = reaches_geometric_limit(E_S, alpha0, F1, F2, L1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.sin(alpha0 - phi) + E_S / R
        s = np.minimum(s, 1.0)
        alpha_F = phi + np.arctan2(s, np.sqrt((1.0 - s) * (1.0 + s)))
    alpha_F = np.where(limit, HALF_PI, np.minimum(alpha_F, HALF_PI))
    return float(alpha_F) if np.ndim(alpha_F) == 0 else alpha_F


def remaining_energy(alpha, alpha_F, F1, F2, L1):
    """Kinetic energy left at angle alpha of a release that stops at alpha_F: ``E_S - W_F(alpha)`` (Eq. 9) [J].

    Uses ``E_S - W_F(alpha) = W_F(alpha_F) - W_F(alpha)
    = 2 R cos((alpha_F + alpha)/2 - phi) sin((alpha_F - alpha)/2)``, which is exact
    to rounding even as alpha approaches alpha_F (no cancellation). alpha_F must be
    the stop angle of Eq. 8 (possibly beyond pi/2 for a virtual stop).
    """
    R, phi = _phase(F1, F2, L1)
    return 2.0 * R * np.cos(0.5 * (alpha_F + alpha) - phi) * np.sin(0.5 * (alpha_F - alpha))


def friction_limits(E_S, alpha0, alpha_F, L1):
    """Upper bounds of the friction forces, F1* (Eq. 11) and F2* (Eq. 12) [N].

    ``F1* = E_S / (2 L1 (sin alpha_F - sin alpha0))``: all of E_S dissipated at the hinges.
    ``F2* = E_S / (4 L1 (cos alpha0 - cos alpha_F))``: all of E_S dissipated on the rail.

    Returns
    -------
    dict
        ``{"F1_max": F1*, "F2_max": F2*}``.
    """
    h = np.sin(0.5 * (alpha_F - alpha0))
    m = 0.5 * (alpha_F + alpha0)
    return {
        "F1_max": E_S / (4.0 * L1 * np.cos(m) * h),
        "F2_max": E_S / (8.0 * L1 * np.sin(m) * h),
    }
