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

from .._validate import HALF_PI
from ..errors import ParameterError
from ..units import si

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
    "sweep_angle",
    "reaches_geometric_limit",
    "limit_margin",
    "creeps_terms",
    "creeps_to_limit",
    "MARGIN_RTOL",
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
    evaluated with the half-angle products (no cancellation near alpha0, nor near pi/2: :func:`_half_angles`).
    """
    h, cos_m, sin_m = _half_angles(alpha, alpha0)
    return 4.0 * L1 * h * (F1 * cos_m + 2.0 * F2 * sin_m)


def _half_angles(alpha, alpha0):
    """``sin((alpha - alpha0)/2)`` and the cosine and sine of ``m = (alpha + alpha0)/2`` [-].

    cos(m) and sin(m) come from those of alpha and of the half difference ``h = (alpha - alpha0)/2`` (exact):
    ``cos(m) = cos(alpha) cos(h) + sin(alpha) sin(h)``, ``sin(m) = sin(alpha) cos(h) - cos(alpha) sin(h)``.
    ``np.cos(0.5 * (alpha + alpha0))`` would carry the rounding of the sum (up to 1.1e-16 rad) relative to a
    cosine of about pi/2 - m: 1e-11 of itself for angles 1e-5 rad from pi/2 (F1* of Eq. 11 with it).
    """
    half = 0.5 * (alpha - alpha0)
    h, ch = np.sin(half), np.cos(half)
    sa, ca = np.sin(alpha), np.cos(alpha)
    return h, ca * ch + sa * h, sa * ch - ca * h


#: pi/2 as the sum of two floats: ``PIO2_HI`` = fl(pi/2) = HALF_PI, 6.1e-17 below pi/2, and ``PIO2_LO`` the rest
#: (to 1e-33). An angle's distance to the flat rhombus is ``(PIO2_HI - a) + PIO2_LO`` (:func:`limit_sweep`).
PIO2_HI = 1.5707963267948966
PIO2_LO = 6.123233995736766e-17


def limit_sweep(alpha):
    """``pi/2 - alpha`` to an ulp of itself [rad]: the sweep to the flat rhombus (two-term pi/2).

    ``PIO2_HI - alpha`` is exact by Sterbenz for alpha in [pi/4, pi] (and rounded once, to a result above pi/4,
    below), and ``PIO2_LO`` adds the 6.1e-17 rad by which fl(pi/2) falls short of pi/2. ``HALF_PI - alpha`` alone
    is short by those 6.1e-17 rad: a relative error of 6e-9 of a sweep of 1e-8 rad, and of t_F with it.
    Pure arithmetic (compiled as is by :mod:`quickrelease.batch._fast`).
    """
    return (PIO2_HI - alpha) + PIO2_LO


#: Scaling of :func:`amplitude_terms`: inputs above ``2^500`` (or below ``2^-500``) are scaled by ``2^-600`` (or
#: ``2^600``), exactly, so that neither square overflows nor loses digits to underflow.
_AMPLITUDE_EDGE = 2.0**500
_AMPLITUDE_DOWN = 2.0**-600
_AMPLITUDE_UP = 2.0**600


def amplitude_terms(A, B):
    """``R = sqrt(A^2 + B^2)``, the amplitude of W_F(alpha) = R (sin(alpha - phi) - sin(alpha0 - phi)) (Eq. 7-8),
    within an ulp of itself, from ``A = 2 F1 L1`` and ``B = 4 F2 L1`` [J].

    The square root of the sum of squares, each input first scaled by a power of two where it is beyond 2^+-500
    (exact: ``2^-600`` above, ``2^600`` below, and the result scaled back), so that 1e300 N neither overflows nor 1e-300
    underflows. Pure arithmetic with no branch and no library call (numpy's ``hypot`` is one): every method computes R
    with these very operations, and the compiled kernels (:mod:`quickrelease.batch._fast`) vectorise them across cases.
    """
    m = np.maximum(np.abs(A), np.abs(B))
    big = (m > _AMPLITUDE_EDGE) * 1.0
    small = (m < 1.0 / _AMPLITUDE_EDGE) * 1.0
    scale = big * _AMPLITUDE_DOWN + small * _AMPLITUDE_UP + (1.0 - big - small)  # one term nonzero: exact
    a = A * scale
    b = B * scale
    return np.sqrt(a * a + b * b) / scale


def one_minus_sin_terms(sin_a, cos_a):
    """``1 - sin(a)`` to a few ulps of itself, from sin(a) and cos(a) (a in [0, pi/2]) [-].

    ``cos^2(a) / (1 + sin(a))`` where sin(a) >= 1/2, ``1 - sin(a)`` below (there >= 1/2: no cancellation).
    The textbook ``1 - sin(a)`` is exact by Sterbenz but keeps the rounding of sin(a), half an ulp of 1 (1.1e-16),
    relative to a result that is ``x^2 / 2`` for a = pi/2 - x: 2e-6 of itself at x = 1e-5. cos(a) near pi/2 is
    known to an ulp of itself, so the quotient is too. The mirror image of :func:`stop_cosine_terms` (there
    ``1 + u`` for u near -1). Pure arithmetic, no branch (compiled as is by :mod:`quickrelease.batch._fast`).
    """
    near = (sin_a >= 0.5) * 1.0  # both branches finite: 1 + sin(a) >= 1
    return near * (cos_a * cos_a / (1.0 + sin_a)) + (1.0 - near) * (1.0 - sin_a)


def _limit_dissipation(A, B, sin_alpha0, cos_alpha0):
    """W_F(pi/2) from ``A = 2 F1 L1``, ``B = 4 F2 L1`` and sin, cos of alpha0 (Eq. 7) [J].

    ``A (1 - sin alpha0) + B cos alpha0``, every term >= 0 and each to a few ulps of itself
    (:func:`one_minus_sin_terms`). Pure arithmetic (no trigonometric call), so the compiled kernels
    (:mod:`quickrelease.batch._fast`) compile this very function: every method rounds W_F(pi/2) the same way.
    """
    return A * one_minus_sin_terms(sin_alpha0, cos_alpha0) + B * cos_alpha0


def limit_margin_terms(E_S, A, B, sin_alpha0, cos_alpha0):
    """``E_S - W_F(pi/2)`` from the terms of :func:`_limit_dissipation` [J]: THE classifier of the stop.

    The motion ends at the geometric limit (the flat rhombus) exactly where this is > 0, and by friction
    (alpha_F <= pi/2, Eq. 8) where it is <= 0. Every method (``energy``, ``rk``, ``explicit``, the batch
    kernels, compiled or not) takes ``stopped_by`` from this one expression, evaluated on the same
    floating-point inputs, so they cannot disagree on a stop within rounding of pi/2: there the
    classification is a convention (both answers describe a device that comes to rest at the flat
    rhombus), and this is the one place it is made. W_F(pi/2) is known to a few ulps of itself, so the margin
    is within a few ulps of ``E_S + W_F(pi/2)`` of the exact margin of the float inputs (not of ``A``: a release
    from near pi/2, where ``W_F(pi/2) << A``, is classified as exactly as any other).
    """
    return E_S - _limit_dissipation(A, B, sin_alpha0, cos_alpha0)


#: Rounding allowance of the margin E_S - W_F(pi/2), as a share of ``E_S + W_F(pi/2)``: its computed value
#: (:func:`limit_margin_terms`) is within about ``4.5 eps W_F(pi/2)`` of the exact margin of the float inputs
#: (A, B, sin and cos of alpha0 each rounded once, 1 - sin alpha0 from them to 3 eps of itself by
#: :func:`one_minus_sin_terms`, the products and the sum each rounded once, the final difference exact by Sterbenz
#: where the margin is small); 4 eps of ``E_S + W_F(pi/2)`` (8 eps of E_S there) covers that with room. (Before
#: ``1 - sin alpha0`` was computed from a rounded sin alpha0, the error was up to ``eps A``, and the band was
#: ``4 eps (E_S + A + B)``: 10^5 times wider than the rounding for a release from 1e-5 rad short of pi/2.)
MARGIN_RTOL = 4.0 * 2.220446049250313e-16


def creeps_terms(margin, E_S, A, B):
    """True where the device creeps towards the flat rhombus and never arrives: t_F = inf [-].

    With ``B = 4 F2 L1 = 0`` and the margin ``K_lim = E_S - W_F(pi/2)`` (:func:`limit_margin_terms`) at 0,
    the remaining energy near pi/2 is ``A (1 - sin alpha) ~ A x^2 / 2`` (x = pi/2 - alpha, A = 2 F1 L1), so
    ``x_dot = -x sqrt(A / (2 M(pi/2)))``: x decays exponentially with the time constant
    ``tau = sqrt(2 M(pi/2) / A)`` and alpha = pi/2 is never reached. For a margin ``K_lim`` of either sign
    t_F is finite, ``tau (ln(2 x0) + ln(A / (2 |K_lim|)) / 2)`` to leading order (the flat rhombus reached for
    K_lim > 0, a friction stop at ``x_F = sqrt(2 |K_lim| / A)`` for K_lim < 0): it grows without bound as the
    margin vanishes. The rule: where the margin lies within its rounding allowance
    ``rho = MARGIN_RTOL (E_S + W_F(pi/2))`` (``W_F(pi/2) = E_S - margin``) of 0, t_F of the float inputs is not
    determined by what the code can compute (every value from about ``tau (ln(2 x0) + ln(A / (2 rho)) / 2)``, at
    least 16.5 tau, up to infinity is consistent with it), and the release is reported as creeping: ``stop_time = inf``,
    ``alpha_final = pi/2`` (the limit), ``stopped_by = "creeps_to_limit"``. Rail friction resolves the
    approach (K ~ B x, finite arrival) once ``B^2 > 2 A rho``; below that it is as if B were 0.
    Pure arithmetic (compiled as is by :mod:`quickrelease.batch._fast`): the one place this is decided, used by
    every method next to :func:`limit_margin_terms`.
    """
    rho = MARGIN_RTOL * E_S + (MARGIN_RTOL * E_S - MARGIN_RTOL * margin)  # E_S + W_F(pi/2), without overflow
    return (abs(margin) <= rho) & (B <= np.sqrt(2.0 * A) * np.sqrt(rho))


def creeps_to_limit(E_S, alpha0, F1, F2, L1):
    """True where the release creeps towards pi/2 without arriving (see :func:`creeps_terms`)."""
    A, B = 2.0 * F1 * L1, 4.0 * F2 * L1
    return creeps_terms(limit_margin(E_S, alpha0, F1, F2, L1), E_S, A, B)


def dissipation_at_limit(alpha0, F1, F2, L1):
    """Energy dissipated on the way from alpha0 to the flat rhombus alpha = pi/2 (Eq. 7) [J]."""
    return _limit_dissipation(2.0 * F1 * L1, 4.0 * F2 * L1, np.sin(alpha0), np.cos(alpha0))


def limit_margin(E_S, alpha0, F1, F2, L1):
    """``E_S - W_F(pi/2)`` [J]: > 0 where the device reaches the flat rhombus with kinetic energy left."""
    return limit_margin_terms(E_S, 2.0 * F1 * L1, 4.0 * F2 * L1, np.sin(alpha0), np.cos(alpha0))


def reaches_geometric_limit(E_S, alpha0, F1, F2, L1):
    """True where friction cannot dissipate E_S before the rhombus is flat (alpha = pi/2).

    That is ``E_S > W_F(pi/2)`` (Eq. 7), decided by :func:`limit_margin_terms` (the single classifier
    used by every solver); there the device reaches the geometric limit with kinetic energy left. False where
    the margin is within its rounding of 0 without rail friction: the device creeps (:func:`creeps_terms`).
    """
    margin = limit_margin(E_S, alpha0, F1, F2, L1)
    return (margin > 0.0) & ~creeps_terms(margin, E_S, 2.0 * F1 * L1, 4.0 * F2 * L1)


def _stop_terms(E_S, A, B, R, sin_alpha0, cos_alpha0):
    """``(s, cv, e, u, cu)`` of a friction stop (Eq. 8) [-]: the sines and cosines of :func:`sweep_terms`.

    ``s = sin(alpha0 - phi)``, ``cv = cos(alpha0 - phi)``, ``e = E_S / R``, ``u = s + e = sin(alpha_F - phi)``
    and ``cu = cos(alpha_F - phi) = sqrt((1 - u)(1 + u)) >= 0``, cu to a few ulps of itself at both ends of u:

    - ``1 - u`` from the classifier's margin ``K_lim`` (:func:`limit_margin_terms`):
      ``R (1 - u) = R - A sin(alpha0) + B cos(alpha0) - E_S = B^2 / (R + A) - K_lim`` (``R - A = B^2 / (R + A)``),
      both terms >= 0 for a friction stop (K_lim <= 0). The textbook ``1 - (s + e)`` keeps the rounding of
      sin(alpha0), an absolute 1.1e-16, relative to ``1 - u = x_F^2 / 2`` for a stop at pi/2 - x_F with little rail
      friction (4e-7 of cu at x_F = 1e-5, and a stop within 1.5e-8 rad of pi/2 rounds to u = 1). With B = 0,
      ``R (1 - u) = -K_lim`` exactly: the stop angle is consistent with its classification.
    - ``1 + u = cv^2 / (1 - s) + e`` for s < 0 (``cv^2 = 1 - s^2``; every term >= 0): the textbook ``1 + u``
      rounds to an absolute ulp where u is near -1 (rail friction, phi near pi/2, with a small alpha0:
      ``cu = sin(alpha_F)``, 1.7e-3 for E_S = 0.1 J, alpha0 = 1e-4 rad, F2 = 7255 N), a relative ``eps / cu^2``
      of cu (1.5e-11 there), which moved alpha_F and t_F by 2e-11 to 3e-11.

    Pure arithmetic and one square root (compiled as is by :mod:`quickrelease.batch._fast`, with the functions it
    calls).
    """
    s = (A * sin_alpha0 - B * cos_alpha0) / R
    cv = (A * cos_alpha0 + B * sin_alpha0) / R
    e = E_S / R
    u = s + e
    one_minus_u = (B * (B / (R + A)) - limit_margin_terms(E_S, A, B, sin_alpha0, cos_alpha0)) / R
    neg = (s < 0.0) * 1.0  # 1 + s = cv^2 / (1 - s) for s < 0 (there 1 - s >= 1)
    one_plus_u = neg * (cv * cv / np.maximum(1.0 - s, 1.0) + e) + (1.0 - neg) * (1.0 + u)
    cu = np.sqrt(np.maximum(one_minus_u * one_plus_u, 0.0))
    return s, cv, e, u, cu


def sweep_terms(E_S, A, B, R, sin_alpha0, cos_alpha0):
    """The friction-stop sweep ``delta = alpha_F - alpha0`` of Eq. 8 without cancellation [rad].

    With ``s = sin(alpha0 - phi)``, ``cv = cos(alpha0 - phi)`` (both from A, B, R: no call) and
    ``e = E_S / R``, Eq. 8 reads ``sin(alpha_F - phi) = u = s + e``; then
    ``delta = arcsin(u) - arcsin(s) = atan2(N, D)`` with ``D = cos(delta) = cu cv + u s``,
    ``cu = cos(alpha_F - phi)`` and ``N = sin(delta) = u cv - s cu = e (cv + s (u + s) / (cu + cv))``
    (using ``cv - cu = (u^2 - s^2) / (cu + cv)``): for a small sweep ``N ~ e / cv``, every term of the
    same sign, so delta keeps full relative accuracy however small it is (alpha_F - alpha0 computed from a
    rounded alpha_F would carry an absolute error of about 1e-16 rad). ``cu`` is that of :func:`_stop_terms`
    (not ``sqrt((1 - u)(1 + u))``, which loses ``eps / cu^2`` of cu when u is near -1 or +1: rail friction with a
    small alpha0, or a stop near pi/2 with little rail friction). Pure arithmetic and one square root and atan2
    (compiled as is by :mod:`quickrelease.batch._fast`). Meaningful for the friction regime
    (``limit_margin_terms <= 0``); the geometric limit's sweep is ``pi/2 - alpha0`` (:func:`limit_sweep`).
    """
    return np.arctan2(*sweep_sides(*_stop_terms(E_S, A, B, R, sin_alpha0, cos_alpha0)))


def sweep_sides(s, cv, e, u, cu):
    """``(N, D) = (sin(delta), cos(delta))`` of the friction-stop sweep from the terms of :func:`_stop_terms` [-]
    (see :func:`sweep_terms`: ``delta = atan2(N, D)``). Pure arithmetic (compiled as is by
    :mod:`quickrelease.batch._fast`, which takes the half-angle sine ``sin(delta / 2)`` from N and D without a call)."""
    N = e * (cv + s * (u + s) / (cu + cv))
    D = cu * cv + u * s
    return N, D


def stop_cosine_terms(E_S, A, B, R, sin_alpha0, cos_alpha0):
    """``cos(alpha_F - phi)`` of a friction stop (Eq. 8) to a few ulps of itself, cu >= 0 [-].

    See :func:`_stop_terms` (``1 - u`` from the classifier's margin, ``1 + u`` from ``cv^2 / (1 - s)``).
    Pure arithmetic, no branch (compiled as is by :mod:`quickrelease.batch._fast`).
    """
    return _stop_terms(E_S, A, B, R, sin_alpha0, cos_alpha0)[4]


def sweep_angle(E_S, alpha0, F1, F2, L1):
    """The angle swept from release to the end of the motion, ``alpha_F - alpha0`` [rad] (Eq. 8).

    Cancellation-free (see :func:`sweep_terms`): accurate to a few ulps of itself even for sweeps of
    1e-12 rad and below, and for stops within 1e-8 rad of pi/2; ``pi/2 - alpha0`` (:func:`limit_sweep`) where
    the device reaches the geometric limit; never negative.
    """
    A = 2.0 * F1 * L1
    B = 4.0 * F2 * L1
    R = amplitude_terms(A, B)
    sa0, ca0 = np.sin(alpha0), np.cos(alpha0)
    margin = limit_margin_terms(E_S, A, B, sa0, ca0)
    limit = (margin > 0.0) | creeps_terms(margin, E_S, A, B)  # the sweep to pi/2: reached, or its limit
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = sweep_terms(E_S, A, B, R, sa0, ca0)
    to_limit = limit_sweep(alpha0)
    delta = np.where(limit, to_limit, np.clip(delta, 0.0, to_limit))
    return float(delta) if np.ndim(delta) == 0 else delta


def final_angle(E_S, alpha0, F1, F2, L1):
    """Angle at which the device stops, alpha_F, from Eq. 8 in closed form [rad].

    W_F(alpha) of Eq. 7 is a sinusoid: ``W_F = R (sin(alpha - phi) - sin(alpha0 - phi))``
    with ``R = hypot(2 F1 L1, 4 F2 L1)`` and ``phi = atan2(4 F2 L1, 2 F1 L1)``, so Eq. 8
    gives ``alpha_F = phi + arcsin(sin(alpha0 - phi) + E_S / R)``; it is computed as
    ``alpha0 + delta`` with the cancellation-free sweep of :func:`sweep_angle`, so alpha_F >= alpha0
    always (and > alpha0 unless the sweep is below half an ulp of alpha0).

    Where friction cannot stop the device before the rhombus is flat (see
    :func:`reaches_geometric_limit`), the motion ends at the geometric limit and
    pi/2 is returned; so too where it creeps towards it (:func:`creeps_to_limit`: pi/2 is its limit).
    """
    E_S, alpha0 = si(E_S, "energy", "E_S"), si(alpha0, "angle", "alpha0")
    F1, F2, L1 = si(F1, "force", "F1"), si(F2, "force", "F2"), si(L1, "length", "L1")
    delta = sweep_angle(E_S, alpha0, F1, F2, L1)
    limit = reaches_geometric_limit(E_S, alpha0, F1, F2, L1) | creeps_to_limit(E_S, alpha0, F1, F2, L1)
    alpha_F = np.where(limit, HALF_PI, np.minimum(np.asarray(alpha0, dtype=float) + delta, HALF_PI))
    return float(alpha_F) if np.ndim(alpha_F) == 0 else alpha_F


def remaining_energy(alpha, alpha_F, F1, F2, L1):
    """Kinetic energy left at angle alpha of a release that stops at alpha_F: ``E_S - W_F(alpha)`` (Eq. 9) [J].

    Uses ``E_S - W_F(alpha) = W_F(alpha_F) - W_F(alpha)
    = 2 R cos((alpha_F + alpha)/2 - phi) sin((alpha_F - alpha)/2)``, which is exact
    to rounding even as alpha approaches alpha_F (no cancellation). alpha_F must be
    the stop angle of Eq. 8 (possibly beyond pi/2 for a virtual stop). ``R cos(m - phi) = A cos(m) + B sin(m)``
    (A = 2 F1 L1, B = 4 F2 L1) with cos(m), sin(m) of :func:`_half_angles`: no cancellation near pi/2 either.
    """
    h, cos_m, sin_m = _half_angles(alpha_F, alpha)
    return 2.0 * (2.0 * F1 * L1 * cos_m + 4.0 * F2 * L1 * sin_m) * h


def friction_limits(E_S, alpha0, alpha_F, L1):
    """Upper bounds of the friction forces, F1* (Eq. 11) and F2* (Eq. 12) [N].

    ``F1* = E_S / (2 L1 (sin alpha_F - sin alpha0))``: all of E_S dissipated at the hinges.
    ``F2* = E_S / (4 L1 (cos alpha0 - cos alpha_F))``: all of E_S dissipated on the rail.

    Returns
    -------
    dict
        ``{"F1_max": F1*, "F2_max": F2*}``.
    """
    h, cos_m, sin_m = _half_angles(alpha_F, alpha0)  # no cancellation near alpha0 or near pi/2
    return {
        "F1_max": E_S / (4.0 * L1 * cos_m * h),
        "F2_max": E_S / (8.0 * L1 * sin_m * h),
    }
