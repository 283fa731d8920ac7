"""Statistical honesty of the pendulum and Bouc-Wen fits (fit_isolation, issue 24) on records made by the
independent solve_ivp of isolator_reference.py (never the fit's own model).

Records like those of test_isolation_coverage.py: 200 Hz, the base displacement (LVDT, noise 0.2 mm) and the
acceleration on its own clock (noise 0.02 m/s^2, zero 0.01 m/s^2), a quiet second before an unknown release
instant. One reference simulation per model; the noise is drawn per seed. Slow (a fit of these models takes
tens of seconds here): 3 seeds per model by default (run with -m slow), 200 with QUICKRELEASE_SLOW=1, where
each parameter's coverage must lie in the 0.05%-99.95% band of Binomial(200, 0.95) (179-198) and the pooled
coverage in 90-99%.
"""

import math
import os
from functools import cache

import pytest

pytest.importorskip("quickrelease.building.hysteretic")

import isolator_reference as ref  # noqa: E402
from coverage_records import binomial_band, clocks, noisy_channels  # noqa: E402

from quickrelease.building.isolation_fit import fit_isolation  # noqa: E402

SLOW = bool(os.environ.get("QUICKRELEASE_SLOW"))
SEEDS = 200 if SLOW else 3
PRE, RELEASE = 1.0, 1.0137

# three reversals before it sticks (with one half-cycle only, a shift of x by delta and of both friction coefficients
# by delta / R leaves the motion unchanged: the LVDT's offset, d0 and the friction level are then not separable)
M_P, R, MU_SLOW, MU_FAST, A, ZETA_P, D0_P = 1.0e6, 2.5, 0.005, 0.015, 30.0, 0.01, 0.2
M_B, KD, QD, DY, N, ZETA_B, D0_B = 8.0e5, 1.6e6, 4.0e5, 0.025, 1.0, 0.02, 0.2

MODELS = {
    "pendulum": dict(
        system=ref.pendulum(M_P, R, MU_SLOW, MU_FAST, A,
                            damping=2 * ZETA_P * math.sqrt(M_P * ref.GRAVITY / R * M_P)),
        mass=M_P, d0=D0_P, duration=6.0,
        truth={"period": 2 * math.pi * math.sqrt(R / ref.GRAVITY), "friction_slow": MU_SLOW,
               "friction_fast": MU_FAST, "rate": A, "damping_ratio": ZETA_P, "d0": D0_P, "release_time": RELEASE}),
    "boucwen": dict(
        system=ref.boucwen(M_B, KD, QD, DY, shape=N, damping=2 * ZETA_B * math.sqrt(KD * M_B)),
        mass=M_B, d0=D0_B, duration=10.0,
        truth={"period": 2 * math.pi * math.sqrt(M_B / KD), "characteristic_strength": QD,
               "yield_displacement": DY, "shape": N, "damping_ratio": ZETA_B, "d0": D0_B,
               "release_time": RELEASE}),
}


@cache
def _rows(model):
    spec = MODELS[model]
    tx, ta = clocks(PRE, spec["duration"])
    x = ref.simulate(spec["system"], spec["d0"], tx - RELEASE, t_end=spec["duration"] + 1.0).x
    a = ref.simulate(spec["system"], spec["d0"], ta - RELEASE, t_end=spec["duration"] + 1.0).a
    return tx, x, ta, a


KNOWN = {"pendulum": pytest.mark.xfail(strict=False, reason=(
    "the pendulum's friction_fast and damping_ratio trade: their Jacobian intervals cover 9 of 12 seeds (2400-2411;"
    " z spread 1.45): too narrow by ~1.4 (issue 24's notes)"))}


@pytest.mark.slow
@pytest.mark.parametrize("model", [pytest.param(m, marks=KNOWN.get(m, ())) for m in MODELS])
def test_intervals_cover_the_truth(model):
    spec = MODELS[model]
    rows = _rows(model)
    covered = dict.fromkeys(spec["truth"], 0)
    missed = []
    for seed in range(SEEDS):
        fit = fit_isolation(noisy_channels(rows, 2400 + seed), spec["mass"], model)
        for name, value in spec["truth"].items():
            lo, hi = fit.ci95[name]
            ok = lo <= value <= hi
            covered[name] += ok
            if not ok:
                missed.append((seed, name, fit.estimates[name], (lo, hi)))
    pooled = sum(covered.values()) / (SEEDS * len(covered))
    if SLOW:
        lo, hi = binomial_band(SEEDS)
        assert all(lo <= c <= hi for c in covered.values()), (covered, missed[:20])
        assert 0.90 <= pooled <= 0.99, (pooled, covered)
    else:  # a few seeds: at most one miss per parameter
        assert all(c >= SEEDS - 1 for c in covered.values()), (covered, missed)
