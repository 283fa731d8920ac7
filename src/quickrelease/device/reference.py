"""High-precision references (mpmath) for the stop time and the identification.

Independent of the double-precision kernels (another substitution, another quadrature, 30 digits):

* :func:`stop_time_mp`: alpha_F solves Eq. 8 by mpmath's bracketing root finder; the time integral of Eq. 10 is
  taken in w = sqrt((alpha_F - alpha) / (alpha_F - alpha0)), a smooth integrand, with E_S - W_F(alpha) written
  by sum-to-product so that it keeps its digits next to the stop, by tanh-sinh quadrature on panels graded
  towards the stop (the kernels use another substitution and Gauss-Legendre nodes). About 0.05 s a case.
* :func:`identify_mp`: F1/F1* on the line of Eq. 13 by the secant method on the same integral: about 0.1 s a
  case from a start near the root (``start=``), 0.2 to 0.7 s without.

For tests and the benchmark's accuracy columns.
"""

from __future__ import annotations

__all__ = ["stop_time_mp", "stop_time_mpf", "identify_mp", "identify_lambda_mp", "line_time_mpf"]


def _setup(dps: int):
    import mpmath as mp

    mp.mp.dps = dps
    return mp


#: Panels of the integral in w (tanh-sinh on each), graded towards w = 0, the stop, where a stop near pi/2 with
#: almost no rail friction, or a flat rhombus reached with almost no energy to spare, has its scale.
_PANELS = ("0", "1e-8", "1e-6", "1e-4", "1e-3", "1e-2", "0.1", "1")


def _time_integral(mp, a0, end, A, B, spare, k, m2, L1):
    """t_F of Eq. 10 from alpha0 to ``end`` [s]: the integral of sqrt(M(alpha) / (E_S - W_F(alpha))), M = m2 L1^2
    (k + sin^2 alpha) (Eq. 5), W_F(alpha) = A (sin alpha - sin alpha0) + B (cos alpha0 - cos alpha) (Eq. 7, A = 2 F1
    L1, B = 4 F2 L1), with ``spare`` = E_S - W_F(end) (0 at a friction stop).

    Integrated in w, alpha = end - (end - alpha0) w^2, which turns the inverse square root at a friction stop into a
    smooth integrand; E_S - W_F(alpha) = spare + W_F(end) - W_F(alpha) with the difference written by
    sum-to-product, 2 sin(x/2) (A cos(end - x/2) + B sin(end - x/2)), x = end - alpha = (end - alpha0) w^2, so it
    keeps its digits at the nodes next to the stop (where E_S - W_F(alpha) itself would cancel)."""
    d = end - a0
    inertia = m2 * L1**2

    def f(w):
        if not w:  # the limit w -> 0: at a friction stop E_S - W_F ~ (A cos end + B sin end) x; else the integrand -> 0
            return mp.mpf(0) if spare else 2 * mp.sqrt(inertia * (k + mp.sin(end) ** 2) * d
                                                     / (A * mp.cos(end) + B * mp.sin(end)))
        x = d * w * w
        rest = spare + 2 * mp.sin(x / 2) * (A * mp.cos(end - x / 2) + B * mp.sin(end - x / 2))
        return 2 * d * w * mp.sqrt(inertia * (k + mp.sin(end - x) ** 2) / rest)

    return mp.quad(f, [mp.mpf(p) for p in _PANELS])


def stop_time_mpf(E_S, alpha0, F1, F2, k, m2, L1, dps: int = 30):
    """(t_F [s], alpha_F [rad]) as mpmath numbers: see :func:`stop_time_mp`."""
    mp = _setup(dps)
    E_S, alpha0, F1, F2, k, m2, L1 = (mp.mpf(float(v)) for v in (E_S, alpha0, F1, F2, k, m2, L1))
    A, B = 2 * F1 * L1, 4 * F2 * L1

    def W(a):  # Eq. 7
        return A * (mp.sin(a) - mp.sin(alpha0)) + B * (mp.cos(alpha0) - mp.cos(a))

    half_pi = mp.pi / 2
    spare = E_S - W(half_pi)
    if spare > 0:
        end = half_pi
    else:
        end, spare = mp.findroot(lambda a: W(a) - E_S, (alpha0, half_pi), solver="anderson"), mp.mpf(0)
    return _time_integral(mp, alpha0, end, A, B, spare, k, m2, L1), end


def stop_time_mp(E_S, alpha0, F1, F2, k, m2, L1, dps: int = 30) -> tuple[float, float]:
    """(t_F [s], alpha_F [rad]) of a release (Eq. 8 and 10) to about ``dps`` digits before rounding; alpha_F = pi/2
    when the flat rhombus is reached first (Eq. 9). About 0.05 s a case.

    alpha_F solves W_F(alpha_F) = E_S (Eq. 8) by mpmath's bracketing root finder; t_F is :func:`_time_integral`.
    E_S [J], alpha0 [rad], F1, F2 [N], k = c m1/m2 [-], m2 [kg], L1 [m]; the floats are taken exactly.
    """
    t, end = stop_time_mpf(E_S, alpha0, F1, F2, k, m2, L1, dps=dps)
    return float(t), float(end)


def _secant(g, lam0, lam1, tol, steps: int = 30):
    """The root of g by the secant method from (lam0, lam1), or None when it leaves [0, 1] or does not settle."""
    g0, g1 = g(lam0), g(lam1)
    for _ in range(steps):
        if g1 == g0:
            return lam1 if g1 == 0 else None
        lam2 = lam1 - g1 * (lam1 - lam0) / (g1 - g0)
        if not 0 <= lam2 <= 1:
            return None
        if abs(lam2 - lam1) <= tol:
            return lam2
        lam0, g0, lam1 = lam1, g1, lam2
        g1 = g(lam1)
    return None


def _line(mp, alpha0, alpha_final, E_S, k, m2, L1):
    """(F1*, F2*) of Eq. 11-12 and t(lambda), the stop time at F1 = lambda F1*, F2 = (1 - lambda) F2* (the line of
    Eq. 13, on which every lambda stops at alpha_F) [s], the floats taken exactly."""
    a0, aF, E, k_, m2_, L1_ = (mp.mpf(float(v)) for v in (alpha0, alpha_final, E_S, k, m2, L1))
    F1s = E / (2 * L1_ * (mp.sin(aF) - mp.sin(a0)))  # Eq. 11
    F2s = E / (4 * L1_ * (mp.cos(a0) - mp.cos(aF)))  # Eq. 12

    def t(lam):
        return _time_integral(mp, a0, aF, 2 * lam * F1s * L1_, 4 * (1 - lam) * F2s * L1_, mp.mpf(0), k_, m2_, L1_)

    return F1s, F2s, t


def line_time_mpf(lam, alpha0, alpha_final, E_S, k, m2, L1, dps: int = 30):
    """(t_F, F1*, F2*) as mpmath numbers on the line of Eq. 13 at lambda = F1/F1* (an mpmath number or a float):
    the stop time [s] of F1 = lambda F1*, F2 = (1 - lambda) F2* (Eq. 10-12), to about ``dps`` digits."""
    mp = _setup(dps)
    F1s, F2s, t = _line(mp, alpha0, alpha_final, E_S, k, m2, L1)
    return t(mp.mpf(lam)), F1s, F2s


def identify_lambda_mp(alpha0, alpha_final, stop_time, E_S, k, m2, L1, dps: int = 30, start=None):
    """lambda = F1/F1* on the line of Eq. 13 with the stop time t_F, and (F1*, F2*) (Eq. 11-12), as mpmath numbers
    to about ``dps`` digits: see :func:`identify_mp`."""
    mp = _setup(dps)
    F1s, F2s, t = _line(mp, alpha0, alpha_final, E_S, k, m2, L1)
    tF = mp.mpf(float(stop_time))

    def g(lam):  # on the line W_F(alpha_F) = E_S for every lambda: a friction stop at alpha_F
        return t(lam) - tF

    tol = mp.mpf(10) ** (3 - dps)
    if start is not None and 0 < float(start) < float(F1s):
        lam0 = mp.mpf(float(start)) / F1s
        lam = _secant(g, lam0, lam0 + (1 - lam0) * mp.mpf(10) ** -9, tol)
    else:  # t(lambda) increases and is convex: from the right of the root the secant converges monotonically
        lam = _secant(g, mp.mpf(1), 1 - mp.mpf(10) ** -6, tol)
    if lam is None:  # bracketing: g changes sign on [0, 1] for a feasible observation
        lam = mp.findroot(g, (mp.mpf(0), mp.mpf(1)), solver="anderson", tol=mp.mpf(10) ** (-2 * dps + 16),
                          verify=False)
    return lam, F1s, F2s


def identify_mp(alpha0, alpha_final, stop_time, E_S, k, m2, L1, dps: int = 30, start=None) -> tuple[float, float]:
    """(F1, F2) [N] on the line of Eq. 13 with the stop time t_F (Eq. 10), to about ``dps`` digits before rounding.

    Parameters
    ----------
    alpha0, alpha_final : float
        Release and stop angles [rad], 0 < alpha0 < alpha_final < pi/2.
    stop_time : float
        t_F [s], between the stop times at F1 = 0 and F1 = F1* (a feasible observation).
    E_S : float
        Stored energy [J].
    k, m2, L1 : float
        Mass ratio c m1/m2 [-], head mass [kg], bar length [m].
    dps : int
        Decimal digits of the computation.
    start : float, optional
        An estimate of F1 [N] (the double-precision kernel's, say): the secant method starts there and ends in
        three or four integrals (about 0.1 s a case). The answer does not depend on it beyond the tolerance
        10^(3 - dps) in F1/F1*: the root is unique (t_F increases with F1 along the line). Without it the
        secant starts from F1 = F1*, from where it converges monotonically (t_F is convex in F1 there), in
        about ten integrals; if either leaves [0, F1*], a bracketing solver on [0, F1*] takes over.
    """
    lam, F1s, F2s = identify_lambda_mp(alpha0, alpha_final, stop_time, E_S, k, m2, L1, dps=dps, start=start)
    return float(lam * F1s), float((1 - lam) * F2s)
