"""High-precision references (mpmath) for the stop time and the identification.

Independent of the double-precision kernels: the time integral of Eq. 10 is taken directly in
alpha with mpmath's tanh-sinh quadrature (which handles the inverse-square-root end point), at
30 significant digits, with breakpoints crowding the end of the interval; alpha_F solves Eq. 8 by
mpmath's root finder. Slow (tens of milliseconds a case): for tests and benchmark accuracy columns.
"""

from __future__ import annotations

__all__ = ["stop_time_mp", "identify_mp"]


def _setup(dps: int):
    import mpmath as mp

    mp.mp.dps = dps
    return mp


def stop_time_mp(E_S, alpha0, F1, F2, k, m2, L1, dps: int = 30) -> tuple[float, float]:
    """(t_F, alpha_F) to about ``dps`` digits; alpha_F = pi/2 when the flat rhombus is reached first."""
    mp = _setup(dps)
    E_S, alpha0, F1, F2, k, m2, L1 = (mp.mpf(float(v)) for v in (E_S, alpha0, F1, F2, k, m2, L1))

    def W(a):
        return 2 * F1 * L1 * (mp.sin(a) - mp.sin(alpha0)) + 4 * F2 * L1 * (mp.cos(alpha0) - mp.cos(a))

    half_pi = mp.pi / 2
    if E_S > W(half_pi):
        end = half_pi
    else:
        end = mp.findroot(lambda a: W(a) - E_S, (alpha0, half_pi), solver="anderson")

    def f(a):
        r = E_S - W(a)
        return mp.sqrt(m2 * L1**2 * (k + mp.sin(a) ** 2) / r) if r > 0 else mp.mpf(0)

    d = end - alpha0
    points = [alpha0, alpha0 + d / 2] + [end - d * mp.mpf(10) ** (-j) for j in range(1, 13)] + [end]
    return float(mp.quad(f, points)), float(end)


def identify_mp(alpha0, alpha_final, stop_time, E_S, k, m2, L1, dps: int = 30) -> tuple[float, float]:
    """(F1, F2) on the line of Eq. 13 with the stop time t_F, to about ``dps`` digits (bracketed on F1/F1*)."""
    mp = _setup(dps)
    a0, aF, tF, E, k_, m2_, L1_ = (mp.mpf(float(v)) for v in (alpha0, alpha_final, stop_time, E_S, k, m2, L1))
    F1s = E / (2 * L1_ * (mp.sin(aF) - mp.sin(a0)))
    F2s = E / (4 * L1_ * (mp.cos(a0) - mp.cos(aF)))

    def t_of(lam):
        F1, F2 = lam * F1s, (1 - lam) * F2s

        def f(a):
            r = E - 2 * F1 * L1_ * (mp.sin(a) - mp.sin(a0)) - 4 * F2 * L1_ * (mp.cos(a0) - mp.cos(a))
            return mp.sqrt(m2_ * L1_**2 * (k_ + mp.sin(a) ** 2) / r) if r > 0 else mp.mpf(0)

        d = aF - a0
        return mp.quad(f, [a0, a0 + d / 2, aF - d / 10, aF]) - tF

    lam = mp.findroot(t_of, (mp.mpf(0), mp.mpf(1)), solver="anderson", tol=mp.mpf(10) ** (-2 * dps + 16),
                      verify=False)  # bracketing: t(lambda) - t_F changes sign on [0, 1]
    return float(lam * F1s), float((1 - lam) * F2s)
