"""Per-release cost of the three solvers, as ratios against scipy solve_ivp measured in the same run.

Run: python benchmarks/bench_solvers.py
The baseline is a bare ``solve_ivp`` (DOP853, rtol 1e-10, stop event) on the paper case; every solver
is timed on the same machine in the same process, so the ratios do not depend on the machine's speed.
"""

from __future__ import annotations

import math
import time

from scipy.integrate import solve_ivp

from quickrelease import preset, simulate, stop_time
from quickrelease.identify import identify_friction

CASE = dict(E_S=2900.0, alpha0=0.2, F1=419.85, F2=804.57)


def best_of(func, repeat=5, number=3):
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            func()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def baseline():
    d = preset("paper")
    k = 2 / 3 * d.m1 / d.m2
    q = 1 / (d.m2 * d.L1)
    F1, F2 = CASE["F1"], CASE["F2"]

    def rhs(t, y):
        s, c = math.sin(y[0]), math.cos(y[0])
        den = k + s * s
        return [y[1], -y[1] ** 2 * s * c / den - (2 * F2 * s + F1 * c) * q / den]

    def ev(t, y):
        return y[1]

    ev.terminal, ev.direction = True, -1
    ad0 = math.sqrt(CASE["E_S"] / (d.m2 * d.L1**2 * (k + math.sin(0.2) ** 2)))
    return solve_ivp(rhs, (0, 100), [0.2, ad0], method="DOP853", rtol=1e-10, atol=1e-12, events=ev)


def main() -> None:
    base = best_of(baseline)
    rows = [
        ("solve_ivp DOP853 + event (baseline)", base),
        ("stop_time (energy, t_F only)", best_of(lambda: stop_time(**CASE), number=50)),
        ("simulate energy, 1001 samples", best_of(lambda: simulate(**CASE))),
        ("simulate rk, 1001 samples", best_of(lambda: simulate(**CASE, method="rk"))),
        ("simulate explicit, dt = 1e-4 s", best_of(lambda: simulate(**CASE, method="explicit"))),
        ("identify_friction (Table 7)", best_of(lambda: identify_friction(0.2, 0.7378, 1.05, stored_energy=2900.0))),
    ]
    print(f"{'task':40s} {'time [ms]':>10s} {'vs baseline':>12s}")
    for name, t in rows:
        print(f"{name:40s} {1e3 * t:10.3f} {t / base:11.2f}x")


if __name__ == "__main__":
    main()
