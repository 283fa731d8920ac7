"""Per-release cost of the three solvers, as ratios against scipy solve_ivp measured in the same run.

Run: python benchmarks/bench_solvers.py
The baseline is a bare ``solve_ivp`` (DOP853, rtol 1e-10, stop event) on the paper case; every solver
is timed on the same machine in the same process, so the ratios do not depend on the machine's speed.
"""

from __future__ import annotations

from common import best_of, solve_ivp_release

from quickrelease import simulate, stop_time
from quickrelease.device.identify import identify_friction

CASE = dict(E_S=2900.0, alpha0=0.2, F1=419.85, F2=804.57)


def baseline():
    return solve_ivp_release(**CASE)


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
