"""Cost of fitting a record, as ratios against scipy solve_ivp measured in the same run.

Run: python benchmarks/bench_fit.py

The fit evaluates the release model at every sample time of the record, many times. The baseline is
what one would write without the energy solution's time map: ``solve_ivp`` (DOP853, rtol 1e-10, stop
event, dense output) evaluated at the same sample times. Timed: one model evaluation at the ~1000 sample
times of ``examples/records/paper_500Hz.csv`` (all three channels, as the fit needs them), a whole fit of
``examples/fit.toml`` (start values, least squares, covariance), and the Cramer-Rao bound of a synthetic
record (``quickrelease synth``'s precision table).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from common import best_of, solve_ivp_release

from quickrelease.device.solvers import FirstIntegral
from quickrelease.io.case import load_case
from quickrelease.io.records import load_record, release_channels
from quickrelease.studies.fit import fit_record
from quickrelease.studies.synth import predicted_errors, synthesize

EXAMPLES = Path(__file__).parent.parent / "examples"
F1, F2, E_S, ALPHA0, RELEASE = 419.85, 804.57, 2900.0, 0.2, 0.62


def baseline(t):
    """solve_ivp with dense output, evaluated at the record's times (alpha, alpha_dot)."""
    sol = solve_ivp_release(E_S, ALPHA0, F1, F2, dense_output=True)
    return sol.sol(np.clip(t - RELEASE, 0.0, sol.t[-1]))


def main() -> None:
    case = load_case(EXAMPLES / "fit.toml")
    record = load_record(case.record)
    d = case.device
    t = record.t
    names = list(record.channels)
    window = record.sampling_interval()
    base = best_of(lambda: baseline(t))

    def model():
        fi = FirstIntegral(E_S, ALPHA0, F1, F2, d.m1, d.m2, d.L1, 2 / 3)
        return release_channels(names, t, RELEASE, fi, window)

    syn = synthesize(load_case(EXAMPLES / "paper.toml"), ["u", "v", "a_head"], rate=500.0, seed=1)
    rows = [
        (f"solve_ivp DOP853, dense output at {t.size} times (baseline)", base),
        (f"model: {', '.join(names)} at {t.size} times", best_of(model)),
        ("fit_record(examples/fit.toml)", best_of(lambda: fit_record(case, record), repeat=3, number=1)),
        ("predicted_errors (synth precision table)", best_of(lambda: predicted_errors(case, syn), repeat=3, number=1)),
    ]
    print(f"{'task':58s} {'time [ms]':>10s} {'vs baseline':>12s}")
    for name, seconds in rows:
        print(f"{name:58s} {1e3 * seconds:10.3f} {seconds / base:11.2f}x")


if __name__ == "__main__":
    main()
