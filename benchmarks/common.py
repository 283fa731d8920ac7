"""Shared by the benchmark scripts: best-of timing and the plain scipy baseline on the paper's device."""

from __future__ import annotations

import math
import time

from scipy.integrate import solve_ivp

from quickrelease import preset


def best_of(func, repeat=5, number=3):
    """The best mean time of ``number`` calls over ``repeat`` rounds [s]."""
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            func()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def solve_ivp_release(E_S: float, alpha0: float, F1: float, F2: float, dense_output: bool = False):
    """The baseline: Eq. 4 (c = 2/3) on the paper's device with ``solve_ivp`` (DOP853, rtol 1e-10, stop event)."""
    d = preset("paper")
    k = 2 / 3 * d.m1 / d.m2
    q = 1 / (d.m2 * d.L1)

    def rhs(_t, y):
        s, c = math.sin(y[0]), math.cos(y[0])
        den = k + s * s
        return [y[1], -y[1] ** 2 * s * c / den - (2 * F2 * s + F1 * c) * q / den]

    def stopped(_t, y):
        return y[1]

    stopped.terminal, stopped.direction = True, -1
    ad0 = math.sqrt(E_S / (d.m2 * d.L1**2 * (k + math.sin(alpha0) ** 2)))
    return solve_ivp(rhs, (0, 100), [alpha0, ad0], method="DOP853", rtol=1e-10, atol=1e-12, events=stopped,
                     dense_output=dense_output)
