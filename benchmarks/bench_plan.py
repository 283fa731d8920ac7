"""Cost of planning a test, with ratios against scipy solve_ivp measured in the same run.

Run: python benchmarks/bench_plan.py

The release envelope of ``examples/plan.toml`` runs the batch kernel over 20,000 friction samples; the
baseline is the same work done one sample at a time with ``solve_ivp`` (DOP853, rtol 1e-10, stop event),
timed on the first 100 samples and scaled. Also timed: the clearance check of one release (the gap over
6001 instants, the minimum refined), and the whole ``plan_case`` (fuse table, member checks, envelope,
clearance over 200 friction samples).
"""

from __future__ import annotations

import time
from pathlib import Path

from common import best_of, solve_ivp_release

from quickrelease import batch
from quickrelease.device.solvers import FirstIntegral
from quickrelease.io.case import load_case
from quickrelease.studies.planning import clearance, friction_samples, plan_case, pushed_displacement

EXAMPLES = Path(__file__).parent.parent / "examples"


def main() -> None:
    case = load_case(EXAMPLES / "plan.toml")
    samples = friction_samples(case, case.plan.samples, case.plan.seed)
    F1, F2 = samples.F1, samples.F2
    d = case.device
    n = F1.size
    t0 = time.perf_counter()
    for i in range(100):
        solve_ivp_release(case.stored_energy, case.alpha0, float(F1[i]), float(F2[i]))
    base = (time.perf_counter() - t0) / 100 * n
    kernel = best_of(lambda: batch.release(case.stored_energy, case.alpha0, F1, F2, case.mass_factor, d.m1, d.m2,
                                           d.L1), repeat=3, number=1)
    fi = FirstIntegral(case.stored_energy, case.alpha0, float(F1[0]), float(F2[0]), d.m1, d.m2, d.L1,
                       case.mass_factor)
    d0 = pushed_displacement(case.push_force, case.building)
    rows = [
        (f"solve_ivp, {n:,} friction samples one at a time (baseline)", base),
        (f"batch.release, {n:,} samples (stroke, opening, peaks)", kernel),
        ("clearance of one release (6001 instants, refined)", best_of(lambda: clearance(fi, case.building, d0))),
        ("plan_case(examples/plan.toml), everything", best_of(lambda: plan_case(case), repeat=3, number=1)),
    ]
    print(f"{'task':58s} {'time [ms]':>11s} {'vs baseline':>12s}")
    for name, seconds in rows:
        print(f"{name:58s} {1e3 * seconds:11.2f} {seconds / base:11.4f}x")


if __name__ == "__main__":
    main()
