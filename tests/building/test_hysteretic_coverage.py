"""Statistical honesty of the pendulum, Bouc-Wen and power-law damper fits (fit_isolation, issue 24) on records
made by the independent solve_ivp of isolator_reference.py (never the fit's own model).

Records like those of test_isolation_coverage.py: 200 Hz, the base displacement (LVDT, noise 0.2 mm) and the
acceleration on its own clock (noise 0.02 m/s^2, zero 0.01 m/s^2), a quiet second before an unknown release
instant. One reference simulation per model; the noise is drawn per seed. Slow (a fit of these models takes
seconds to tens of seconds here): 3 seeds per model by default (run with -m slow), 200 with QUICKRELEASE_SLOW=1
(and ``-p no:timeout``: 6-45 minutes a model, past the suite's 600 s limit a test), where each parameter's
coverage must lie in the 0.05%-99.95% band of Binomial(200, 0.95) (179-198) and the pooled coverage in 90-99%.
"""

import math
import os
from functools import cache

import numpy as np
import pytest

pytest.importorskip("quickrelease.building.hysteretic")

import isolator_reference as ref  # noqa: E402
from coverage_records import NOISE_A, NOISE_X, binomial_band, chi2_band, clocks, joint_deviation, noisy_channels  # noqa: E402

from quickrelease.building.isolation_fit import fit_isolation  # noqa: E402

SLOW = bool(os.environ.get("QUICKRELEASE_SLOW"))
SEEDS = 200 if SLOW else 3
PRE, RELEASE = 1.0, 1.0137

# three reversals before it sticks (with one half-cycle only, a shift of x by delta and of both friction coefficients
# by delta / R leaves the motion unchanged: the LVDT's offset, d0 and the friction level are then not separable)
M_P, R, MU_SLOW, MU_FAST, A, ZETA_P, D0_P = 1.0e6, 2.5, 0.005, 0.015, 30.0, 0.01, 0.2
M_B, KD, QD, DY, N, ZETA_B, D0_B = 8.0e5, 1.6e6, 4.0e5, 0.025, 1.0, 0.02, 0.2
# rubber bearings with sliders and fluid viscous dampers (bench_isolators' "power" layer): F = C |v|^alpha, the
# layer creeping on the damper's slow manifold after its turns
M_D, T_D, FS_D, C_D, ALPHA_D, D0_D = 8.0e5, 2.5, 0.008 * 8.0e5 * ref.GRAVITY, 3.0e5, 0.4, 0.15

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
    "power": dict(
        system=ref.linear(M_D, M_D * (2 * math.pi / T_D) ** 2, C_D, ALPHA_D, friction=FS_D),
        mass=M_D, d0=D0_D, duration=8.0, model="linear", damping="power",
        truth={"period": T_D, "friction": FS_D, "damping_coefficient": C_D, "damping_exponent": ALPHA_D,
               "d0": D0_D, "release_time": RELEASE}),
    # lead-rubber bearings with fluid dampers (examples/lead_rubber_damper_building.toml's layer)
    "boucwen-power": dict(
        system=ref.boucwen(M_B, KD, QD, DY, shape=N, damping=2.0e5, damping_exponent=0.5),
        mass=M_B, d0=D0_B, duration=10.0, model="boucwen", damping="power",
        truth={"period": 2 * math.pi * math.sqrt(M_B / KD), "characteristic_strength": QD,
               "yield_displacement": DY, "shape": N, "damping_coefficient": 2.0e5, "damping_exponent": 0.5,
               "d0": D0_B, "release_time": RELEASE}),
}


@cache
def _rows(model):
    spec = MODELS[model]
    tx, ta = clocks(PRE, spec["duration"])
    x = ref.simulate(spec["system"], spec["d0"], tx - RELEASE, t_end=spec["duration"] + 1.0).x
    a = ref.simulate(spec["system"], spec["d0"], ta - RELEASE, t_end=spec["duration"] + 1.0).a
    return tx, x, ta, a


@pytest.mark.slow
@pytest.mark.parametrize("model", list(MODELS))
def test_intervals_cover_the_truth(model):
    """The pendulum's 200 seeds (2400-2599, measured 2026-11-27): each parameter covered 186-191 times (band
    179-198), pooled 0.941, the z-scores' spread 0.88-1.05. (A strict-free xfail said friction_fast and
    damping_ratio, correlated -0.998, were ~1.4 too narrow: seeds 2400-2411 alone, three of them off together
    along that direction by 2-3 standard errors.) The default run's few seeds are judged by their joint
    deviation (:func:`coverage_records.joint_deviation`): a count of misses per parameter (at most one in three
    seeds) failed on seeds 2400 and 2402, each off by 2-3 standard errors in four parameters at once, a
    3-parameter event of chi-square 7 degrees of freedom. The power-law layer's 200 seeds (2400-2599, measured
    2026-11-27): period 187, friction 198, C 197, alpha 191, d0 198, release 193, pooled 0.970; before the
    covariance left out a damper's cusp parked on a sample (see the test below) 179-192, pooled 0.917, d0 179 and
    period 180 at the band's lower edge."""
    spec = MODELS[model]
    rows = _rows(model)
    covered = dict.fromkeys(spec["truth"], 0)
    missed = []
    joint = []
    for seed in range(SEEDS):
        fit = fit_isolation(noisy_channels(rows, 2400 + seed), spec["mass"], spec.get("model", model),
                            damping=spec.get("damping", "viscous"))
        joint.append(joint_deviation(fit, spec["truth"]))
        for name, value in spec["truth"].items():
            lo, hi = fit.ci95[name]
            ok = lo <= value <= hi
            covered[name] += ok
            if not ok:
                missed.append((seed, name, fit.estimates[name], (lo, hi)))
    pooled = sum(covered.values()) / (SEEDS * len(covered))
    print(f"coverage of {model} over {SEEDS} seeds: {covered}, pooled {pooled:.3f}")  # (pytest -s)
    if SLOW:
        lo, hi = binomial_band(SEEDS)
        assert all(lo <= c <= hi for c in covered.values()), (covered, missed[:20])
        assert 0.90 <= pooled <= 0.99, (pooled, covered)
    else:  # a few seeds: their joint deviations from the truth, summed, within chi-square's 0.05%-99.95% band
        lo, hi = chi2_band(SEEDS * len(spec["truth"]))
        assert lo <= sum(joint) <= hi, (joint, (lo, hi), missed)


@cache
def _reference_errors(model):
    """The standard errors the record's noise allows at the truth, from the independent simulator alone: the
    Fisher information ``J^T J`` of the weighted samples (nominal noise NOISE_X, NOISE_A), J by central differences
    of isolator_reference's motion over 1e-6 of each parameter (the reversal's nearest acceleration sample lies
    115 us from it at the truth, the release moves 1 us), with a zero for each channel (its column 1 / sigma)."""
    spec = MODELS[model]
    truth = spec["truth"]
    tx, ta = clocks(PRE, spec["duration"])

    def channels(p):
        system = ref.linear(spec["mass"], spec["mass"] * (2 * math.pi / p["period"]) ** 2, p["damping_coefficient"],
                            p["damping_exponent"], friction=p["friction"])
        x = ref.simulate(system, p["d0"], tx - p["release_time"], t_end=spec["duration"] + 1.0).x
        a = ref.simulate(system, p["d0"], ta - p["release_time"], t_end=spec["duration"] + 1.0).a
        return np.concatenate([x / NOISE_X, a / NOISE_A])

    columns = []
    for name, value in truth.items():
        h = 1e-6 * abs(value)
        columns.append((channels({**truth, name: value + h}) - channels({**truth, name: value - h})) / (2 * h))
    zeros = [np.r_[np.full(tx.size, 1 / NOISE_X), np.zeros(ta.size)],
             np.r_[np.zeros(tx.size), np.full(ta.size, 1 / NOISE_A)]]
    J = np.column_stack(columns + zeros)
    cov = np.linalg.inv(J.T @ J)
    return {name: math.sqrt(cov[i, i]) for i, name in enumerate(truth)}


@pytest.mark.slow
@pytest.mark.parametrize("seed", [2405, 2403, 2471])
def test_a_damper_cusp_on_a_sample_keeps_the_standard_errors(seed):
    """The power-law damper's force C |v|^0.4 has a cusp (an infinite slope) at each reversal and at the stick, and
    the fit likes to park one on a sample: seeds 2405's and 2471's reversal on the acceleration sample at 2.2713 s
    (0 us), seed 2403's stick 14 us from the one at 3.5613 s. The tangent Jacobian gave that one sample 98-99.9 %
    of the leverage and standard errors 1.4-14 times too small (2405: damping_exponent 0.07 of the usual, friction
    0.44, period 0.72; 2403: friction 0.20, damping_exponent 0.27; 2471: damping_exponent 0.10, friction 0.48):
    83 of the 200 fits of seeds 2400-2599 had such a sample, and they made nearly all the misses (period covered
    180 times of 200, d0 179, release 180). (A secant Jacobian over each parameter's standard error, iterated,
    fixed 2405 and 2403 but not 2471: there it fell back to the cusp's slope, damping_exponent 0.017.) Each
    standard error must lie within 0.75-1.33 of the independent simulator's information at the truth (the estimate
    lies a few standard errors from the truth, the noise levels come from the quiet second, 5 % each). Over the
    200 seeds after the fix: 0.72-1.18 (before: 0.068-1.13); the lowest, seed 2417's friction, has a second cusp,
    the stick, 130 us from a sample (leverage 0.37, kept: a cusp off the sample informs, as at the truth, where
    the reversal's nearest sample, 115 us off, has leverage 0.2)."""
    spec = MODELS["power"]
    fit = fit_isolation(noisy_channels(_rows("power"), seed), spec["mass"], "linear", damping="power")
    reference = _reference_errors("power")
    ratios = {name: fit.std_errors[name] / se for name, se in reference.items()}
    assert all(0.75 <= r <= 1.33 for r in ratios.values()), ratios
