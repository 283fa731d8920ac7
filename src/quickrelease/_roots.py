"""A bracketed scalar root finder (Brent's method), so the core paths need not import scipy.optimize."""

from __future__ import annotations

import math
from collections.abc import Callable

__all__ = ["brent"]


def brent(f: Callable[[float], float], a: float, b: float, fa: float | None = None, fb: float | None = None,
          xtol: float = 0.0, rtol: float = 4.0 * 2.220446049250313e-16, maxiter: int = 200) -> float:
    """Root of ``f`` in ``[a, b]`` where ``f(a)`` and ``f(b)`` differ in sign (Brent, 1973).

    Inverse quadratic interpolation and secant steps, safeguarded by bisection: it never leaves the
    bracket and converges superlinearly on smooth functions. Stops when the bracket is narrower than
    ``2 (xtol + rtol |x|)``.
    """
    fa = f(a) if fa is None else fa
    fb = f(b) if fb is None else fb
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if math.copysign(1.0, fa) == math.copysign(1.0, fb):
        raise ValueError(f"f(a) = {fa:g} and f(b) = {fb:g} must differ in sign")
    c, fc = a, fa
    d = e = b - a
    for _ in range(maxiter):
        if math.copysign(1.0, fb) == math.copysign(1.0, fc):
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):
            a, b, c = b, c, b
            fa, fb, fc = fb, fc, fb
        tol = 2.0 * rtol * abs(b) + 0.5 * xtol
        m = 0.5 * (c - b)
        if abs(m) <= tol or fb == 0.0:
            return b
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:  # secant
                p, q = 2.0 * m * s, 1.0 - s
            else:  # inverse quadratic interpolation
                q, r = fa / fc, fb / fc
                p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0))
                q = (q - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                q = -q
            else:
                p = -p
            if 2.0 * p < min(3.0 * m * q - abs(tol * q), abs(e * q)):
                e, d = d, p / q
            else:
                d = e = m
        else:
            d = e = m
        a, fa = b, fb
        b = b + (d if abs(d) > tol else math.copysign(tol, m))
        fb = f(b)
    return b
