"""Statistical honesty of the isolation-system fit (isolation_fit.py), on records made by the independent
event-located solve_ivp of tests/building_reference.py (never the fit's own model).

Realistic records: 200 Hz, the base displacement (LVDT, noise 0.2 mm) and the floor acceleration (on its own
clock, noise 0.02 m/s^2, sensor zero 0.01 m/s^2), a quiet segment before an unknown release instant. The
coverage tests make one reference simulation per case and draw the noise per seed (the noise is what
varies between seeds). Seeds in the ordinary run: 60 (linear + Coulomb), 10 (no friction), 6 (noise
from the residuals), 2 (model choice on linear records), 1 (bilinear); with QUICKRELEASE_SLOW=1: 200, 200,
200, 50 and 200.
The binomial band of a coverage count is the 0.05%-99.95% range of Binomial(n, 0.95) (for 200 seeds:
179-198, i.e. 90%-99%).
"""

import math
import os
from functools import cache

import numpy as np
import pytest
from building_reference import reference
from coverage_records import OFFSET_A, binomial_band, clocks, noisy_channels
from scipy import stats

from quickrelease.building.isolation_fit import compare_models, decay_check, fit_isolation

SLOW = bool(os.environ.get("QUICKRELEASE_SLOW"))
M = 4.0e5  # kg
PRE = 1.5  # s of quiet record before the release
RELEASE = 1.5137  # s, record time (not given to the fit)
T, ZETA, FS, D0 = 2.0, 0.04, 1.2e4, 0.15  # the linear + Coulomb building
K = M * (2 * math.pi / T) ** 2
C = 2 * ZETA * math.sqrt(K * M)


@cache
def _rows(k1, k2, fp, c, Fs, d0, duration):
    """The noise-free channels x(tx), a(ta) by the independent solve_ivp (one simulation per case)."""
    tx, ta = clocks(PRE, duration)
    x = reference(M, k1, k2, fp, c, Fs, d0, tx - RELEASE)[0]
    a = reference(M, k1, k2, fp, c, Fs, d0, ta - RELEASE, with_rates=True)[0][2]
    return tx, x, ta, a


def _rms_band(n, tail=0.0005):
    """The range of the RMS of n standard normal z-scores, sqrt(chi2(n) / n), between its tail quantiles."""
    return math.sqrt(stats.chi2.ppf(tail, n) / n), math.sqrt(stats.chi2.isf(tail, n) / n)


LINEAR_TRUTH = {"period": T, "damping_ratio": ZETA, "friction": FS, "d0": D0, "release_time": RELEASE,
                "offset_lvdt": 0.0, "offset_acc": OFFSET_A}


def _coverage(rows, truth, n, **kw):
    covered = dict.fromkeys(truth, 0)
    z = {name: [] for name in truth}
    fits = []
    for seed in range(n):
        fit = fit_isolation(noisy_channels(rows, 1000 + seed), M, "linear", **kw)
        fits.append(fit)
        for name, value in truth.items():
            lo, hi = fit.ci95[name]
            covered[name] += lo <= value <= hi
            if fit.interval_method[name] == "jacobian":
                z[name].append((fit.estimates[name] - value) / fit.std_errors[name])
    return covered, z, fits


@cache
def _linear_coverage(n):
    return _coverage(_rows(K, K, math.inf, C, FS, D0, 8.0), LINEAR_TRUTH, n)


def test_round_trip_linear():
    """Period within 1%, damping ratio and friction within 5% of the truth (one record)."""
    fit = fit_isolation(noisy_channels(_rows(K, K, math.inf, C, FS, D0, 8.0), 7), M, "linear")
    assert fit.estimates["period"] == pytest.approx(T, rel=0.01)
    assert fit.estimates["damping_ratio"] == pytest.approx(ZETA, rel=0.05)
    assert fit.estimates["friction"] == pytest.approx(FS, rel=0.05)
    assert fit.converged and not fit.warnings


@pytest.mark.slow
def test_round_trip_bilinear_from_design_values_and_model_choice():
    """Rubber bearings k1 = 40 MN/m, k2 = 4 MN/m, F_y = 80 kN with sliders: from design values 20-30% off,
    period and stiffness ratio within 1%, damping, friction and yield force within 5%; the comparison
    prefers the bilinear model on its record."""
    k1, k2, Fy, zeta, Fs, d0 = 4.0e7, 4.0e6, 8.0e4, 0.03, 8.0e3, 0.2
    rows = _rows(k1, k2, Fy * (1 - k2 / k1), 2 * zeta * math.sqrt(k1 * M), Fs, d0, 4.0)
    channels = noisy_channels(rows, 11)
    T1 = 2 * math.pi * math.sqrt(M / k1)
    design = {"period": 1.2 * T1, "damping_ratio": 0.75 * zeta, "friction": 0.7 * Fs, "stiffness_ratio": 1.25 * k2 / k1,
              "yield_force": 0.75 * Fy}
    fit = fit_isolation(channels, M, "bilinear", start=design, profile=False)
    assert fit.estimates["period"] == pytest.approx(T1, rel=0.01)
    assert fit.estimates["stiffness_ratio"] == pytest.approx(k2 / k1, rel=0.01)
    for name, value in (("damping_ratio", zeta), ("friction", Fs), ("yield_force", Fy)):
        assert fit.estimates[name] == pytest.approx(value, rel=0.05), name
    linear = fit_isolation(channels, M, "linear", profile=False)
    table = compare_models([linear, fit])
    assert table[0]["model"] == "bilinear" and min(r["delta_aic"] for r in table[1:]) > 10


@pytest.mark.slow
def test_coverage_linear_coulomb():
    """Over the seeds the 95% intervals hold the truth for every parameter in the binomial band; pooled
    over the parameters at least 92% (an interval of 90% sold as 95% covers ~90%); the z-scores of the
    Jacobian intervals have an RMS near 1 (standard errors of the right size)."""
    n = 200 if SLOW else 60
    covered, z, _ = _linear_coverage(n)
    lo, hi = binomial_band(n)
    assert all(lo <= c <= hi for c in covered.values()), (covered, (lo, hi))
    assert sum(covered.values()) >= 0.92 * n * len(covered), covered
    for name, values in z.items():
        rms = float(np.sqrt(np.mean(np.square(values))))
        lo, hi = _rms_band(len(values))  # for 60 seeds [0.71, 1.31]
        assert lo < rms < hi, (name, rms, (lo, hi))


@pytest.mark.slow
def test_coverage_without_friction():
    """Friction truly 0, at its bound: the profile interval starts at 0 and holds the truth in the
    binomial band (a boundary: the likelihood ratio at 0 exceeds the quantile in ~2.5% of seeds)."""
    n = 200 if SLOW else 10
    rows = _rows(K, K, math.inf, C, 0.0, D0, 6.0)
    truth = {**LINEAR_TRUTH, "friction": 0.0}
    covered, z, fits = _coverage(rows, truth, n)
    lo, hi = binomial_band(n)
    assert all(f.interval_method["friction"] == "profile" for f in fits)
    assert sum(f.ci95["friction"][0] == 0.0 for f in fits) == covered["friction"]
    assert all(lo <= c <= hi for c in covered.values()), (covered, (lo, hi))


@pytest.mark.slow
def test_coverage_with_noise_from_the_residuals():
    """A record that starts at the release (no quiet segment): the noise levels come from the residuals
    and the covariance is scaled by the reduced chi-square; the intervals keep their coverage and the
    z-scores their unit RMS."""
    n = 200 if SLOW else 6
    tx, x, ta, a = _rows(K, K, math.inf, C, FS, D0, 8.0)
    keep_x, keep_a = tx > RELEASE, ta > RELEASE
    rows = (tx[keep_x], x[keep_x], ta[keep_a], a[keep_a])
    truth = {n_: v for n_, v in LINEAR_TRUTH.items() if n_ != "release_time"}
    covered, z, fits = _coverage(rows, truth, n, release_time=RELEASE, fit_release_time=False)
    assert all(f.noise_source == {"lvdt": "residuals", "acc": "residuals"} for f in fits)
    lo, hi = binomial_band(n)
    assert all(lo <= covered[k] <= hi for k in truth), (covered, (lo, hi))
    for name in truth:
        rms = float(np.sqrt(np.mean(np.square(z[name]))))
        lo, hi = _rms_band(len(z[name]))  # for 6 seeds [0.22, 2.0]: the unweighted fit gave 0.17
        assert lo < rms < hi, (name, rms, (lo, hi))


@pytest.mark.slow
def test_model_choice_on_linear_records_prefers_linear():
    """On linear + Coulomb records the bilinear model (two more parameters) does not win by AIC in more
    than 10% of the seeds (measured: 47 of 50 seeds, and 19 of the first 20; the CI's 10 seeds hold one that
    prefers bilinear). The linear fits are the coverage test's of the same records (its profile intervals
    change no estimate and no misfit: the comparison reads only those)."""
    n = 50 if SLOW else 10
    rows = _rows(K, K, math.inf, C, FS, D0, 8.0)
    _, _, linear_fits = _linear_coverage(200 if SLOW else 60)
    prefers_linear = 0
    for seed in range(n):
        channels = noisy_channels(rows, 1000 + seed)
        linear = linear_fits[seed]
        start = {"period": linear.estimates["period"], "damping_ratio": linear.estimates["damping_ratio"],
                 "friction": linear.estimates["friction"], "stiffness_ratio": 0.5, "yield_force": 0.5 * K * D0}
        bilinear = fit_isolation(channels, M, "bilinear", start=start, profile=False)
        table = compare_models([linear, bilinear])
        prefers_linear += next(r for r in table if r["model"] == "linear")["delta_aic"] == 0.0
    assert prefers_linear >= 0.9 * n, (prefers_linear, n)


@pytest.mark.slow
def test_decay_cross_check_recovers_friction_and_damping():
    """The model-free decay (combined decrement law) holds the true friction and damping ratio within its
    own 95% intervals in most seeds, and agrees with the fit within a few combined standard errors."""
    n = 20
    _, _, fits = _linear_coverage(200 if SLOW else 60)
    inside = {"friction": 0, "damping_ratio": 0}
    for fit in fits[:n]:
        rows = {r["parameter"]: r for r in decay_check(fit)["rows"]}
        for name, truth in (("friction", FS), ("damping_ratio", ZETA)):
            r = rows[name]
            inside[name] += abs(r["decay"] - truth) <= 1.96 * r["decay_se"]
            assert abs(r["difference_in_se"]) < 5, r
    assert all(v >= 0.8 * n for v in inside.values()), inside


def test_standard_errors_survive_a_reversal_on_a_sample():
    """Friction of 1% of the weight: the acceleration jumps by 2 F_s / m (10 noise levels) at each
    reversal, and the optimiser likes to park a reversal on an acceleration sample. Plain central
    differences then see the jump over the step: on this record the damping ratio's standard error came out
    2.6 times too small (z = 5.0, friction -5.5; on another record 50 times, z = 89); the guarded
    differences keep every estimate within 4 standard errors (measured: |z| <= 2.3)."""
    Fs, zeta, d0 = 0.01 * M * 9.80665, 0.05, 0.12
    fit = fit_isolation(noisy_channels(_rows(K, K, math.inf, 2 * zeta * math.sqrt(K * M), Fs, d0, 6.0), 1), M, "linear")
    truth = {"period": T, "damping_ratio": zeta, "friction": Fs, "d0": d0, "release_time": RELEASE}
    z = {name: (fit.estimates[name] - value) / fit.std_errors[name] for name, value in truth.items()}
    assert all(abs(v) < 4.0 for v in z.values()), z


def test_hard_record_lands_in_the_right_basin():
    """Sliders of 1% of the weight, four half-cycles (the record of the test above), noise seed 16: the rest's
    largest noise sample fell among the last four samples, the decay analysis missed the stick (no decay
    law, so a start without friction), and every start led to a wrong count of half-cycles (reduced
    chi-square 21; 3 of 100 seeds did, 0 now). The fit reaches the noise level and the truth."""
    Fs, zeta, d0 = 0.01 * M * 9.80665, 0.05, 0.12
    fit = fit_isolation(noisy_channels(_rows(K, K, math.inf, 2 * zeta * math.sqrt(K * M), Fs, d0, 6.0), 16), M, "linear",
                        profile=False)
    assert fit.chi2_reduced < 1.3, fit.chi2_reduced
    truth = {"period": T, "damping_ratio": zeta, "friction": Fs, "d0": d0, "release_time": RELEASE}
    z = {name: (fit.estimates[name] - value) / fit.std_errors[name] for name, value in truth.items()}
    assert all(abs(v) < 4.0 for v in z.values()), z


BILINEAR = (4.0e7, 4.0e6, 8.0e4, 0.03, 8.0e3, 0.2)  # k1, k2 [N/m], F_y [N], zeta, F_s [N], d0 [m]


@pytest.mark.slow  # one seed of a coverage matrix (2-3 s); the quick run fits bilinear records in test_isolation_identify
def test_coverage_bilinear():
    """Rubber bearings with sliders (the round-trip building above), fitted from the record alone (no design
    values: the hysteresis loop's start, the multi-start and the polish), unknown release: over the seeds the
    95% intervals hold the truth for every parameter in the binomial band, pooled at least 92%. Measured
    over seeds 0-119: pooled 94.8% (the physical parameters 95.3%); period 116, k2/k1 116, F_y 114, zeta
    114, F_s 112, d0 113, release 116, LVDT zero 114 and accelerometer zero 109 of 120 (the band for 120:
    105-120; z-score RMS 0.82-1.09); 4.7 s of CPU a seed on a loaded machine. The CI's one seed holds every
    parameter."""
    n = 200 if SLOW else 1
    k1, k2, Fy, zeta, Fs, d0 = BILINEAR
    rows = _rows(k1, k2, Fy * (1 - k2 / k1), 2 * zeta * math.sqrt(k1 * M), Fs, d0, 4.0)
    truth = {"period": 2 * math.pi * math.sqrt(M / k1), "stiffness_ratio": k2 / k1, "yield_force": Fy,
             "damping_ratio": zeta, "friction": Fs, "d0": d0, "release_time": RELEASE, "offset_lvdt": 0.0,
             "offset_acc": OFFSET_A}
    covered = dict.fromkeys(truth, 0)
    for seed in range(n):
        fit = fit_isolation(noisy_channels(rows, 1000 + seed), M, "bilinear")
        for name, value in truth.items():
            lo, hi = fit.ci95[name]
            covered[name] += lo <= value <= hi
    if SLOW:
        lo, hi = binomial_band(n)
        assert all(lo <= c <= hi for c in covered.values()), (covered, (lo, hi))
        assert sum(covered.values()) >= 0.92 * n * len(covered), covered
    else:
        assert all(c == n for c in covered.values()), covered
