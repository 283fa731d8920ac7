"""Fits with fluid viscous dampers (``damping="power"``, ``C |v|^alpha sign(v)``) under a flexible superstructure
(issue 24: each damping law usable in 2dof): the 2dof model (its linear layer with dampers, on the flexible
integrator) and lead-rubber bearings with dampers (``boucwen``, ``flexible=True``), on records made by the independent
solve_ivp reference ``isolator_reference.simulate_2dof`` (no package code): the base's LVDT and accelerometer and the
roof's accelerometer at 100 Hz with their sensor zeros and white noise of known level, a quiet second before an
unknown release. The truth lies in the fit's joint 95% region and each parameter near its estimate, the misfit at the
noise level, the fitted model the FlexibleBuilding of the estimates."""

import math
import os
import time

import isolator_reference as ref
import numpy as np
import pytest
from test_isolation_fit_flexible import ZEROS as FLEXIBLE_ZEROS
from test_isolation_fit_flexible import _truth_in_the_joint_region

from quickrelease.building.flexible import FlexibleBuilding
from quickrelease.building.hysteretic import BoucWen
from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation
from quickrelease.building.model import Isolation

NOISE = {"x": 2e-4, "a": 0.02, "a_roof": 0.02}
ZEROS = FLEXIBLE_ZEROS  # (test_isolation_fit_flexible's: its joint-region check adds them)
T_R = 0.537
M, MS = 8.0e5, 4.8e5
# the linear layer with sliders and dampers of alpha 0.4 under a storey of 0.5 s: it sticks, the roof breaks it away
# again, and it creeps in and out of the sliders' hold while the roof rings
TWO_DOF = dict(period=2.5, damping_coefficient=1.2e5, damping_exponent=0.4, friction=1.5e4, superstructure_period=0.5,
               superstructure_damping_ratio=0.02, d0=0.2, release_time=T_R)
# lead-rubber bearings with dampers of alpha 0.4 (bench_isolators' boucwen-damper) under the storey: after the swing
# the base creeps back on the dampers' slow manifold while the roof rings
LEAD_RUBBER = dict(period=2 * math.pi * math.sqrt(M / 3.5e6), damping_coefficient=3e5, damping_exponent=0.4,
                   friction=0.0, characteristic_strength=4e5, yield_displacement=0.025, shape=1.0,
                   superstructure_period=0.5, superstructure_damping_ratio=0.02, d0=0.2, release_time=T_R)


def _system(model, p):
    k = M * (2 * math.pi / p["period"]) ** 2
    c, alpha = p["damping_coefficient"], p["damping_exponent"]
    if model == "boucwen":
        return ref.boucwen(M, k, p["characteristic_strength"], p["yield_displacement"], p["shape"], damping=c,
                           damping_exponent=alpha, friction=p["friction"])
    return ref.linear(M, k, damping=c, damping_exponent=alpha, friction=p["friction"])


def _clean(model, p, duration=15.0, rate=100.0):
    """The reference's record without noise: (t, [(name, kind, values)])."""
    t = np.arange(-1.0, duration, 1.0 / rate)
    system = _system(model, p)
    ks = MS * (2 * math.pi / p["superstructure_period"]) ** 2
    cs = 2 * p["superstructure_damping_ratio"] * math.sqrt(ks * MS)
    creep = 1e-8 * math.sqrt(2.0 * system.stored(p["d0"], system.pushed_z(p["d0"])) / M)  # (the kernel's convention)
    motion = ref.simulate_2dof(system, MS, ks, cs, p["d0"], t - p["release_time"], duration, creep_speed=creep)
    return t, [("lvdt", "x", motion.x), ("base_acc", "a", motion.a), ("roof_acc", "a_roof", motion.as_)]


def _noisy(rows, seed):
    t, channels = rows
    rng = np.random.default_rng(seed)
    return [BuildingChannel(name, kind, t, y + ZEROS[kind] + rng.normal(0.0, NOISE[kind], t.size), NOISE[kind])
            for name, kind, y in channels]


def _record(model, p, seed, duration=15.0, rate=100.0):
    return _noisy(_clean(model, p, duration, rate), seed)


def _checked(fit, truth):
    """The truth (the sensors' zeros too) inside the fit's joint 95% region (its chi-square above the fit's by less
    than the quantile of the parameters' count); each true parameter within 3.3 standard errors of its estimate (a
    marginal 95% interval misses one of ten parameters on 40% of the records; 3.3 on 1%); the misfit at the
    noise. (Seed 1 of the lead-rubber record: the release 2.1 standard errors off, every other parameter inside its
    95% interval.)"""
    far = {n: (v, fit.estimates[n], fit.std_errors[n]) for n, v in truth.items()
           if not abs(fit.estimates[n] - v) < 3.3 * fit.std_errors[n]}
    assert far == {}
    _truth_in_the_joint_region(fit, truth)  # (the same sensors' zeros, ZEROS)
    assert 0.9 < fit.chi2_reduced < 1.1


@pytest.mark.slow
def test_2dof_with_fluid_dampers_fitted_back():
    """model="2dof", damping="power": the linear layer with its dampers' C and alpha and the storey fitted back
    (:func:`_checked`); the fitted model the FlexibleBuilding of the linear layer with the power-law damper."""
    fit = fit_isolation(_record("linear", TWO_DOF, seed=1), M, "2dof", damping="power", superstructure_mass=MS,
                        profile=False)
    _checked(fit, TWO_DOF)
    building = fit.isolation()
    assert isinstance(building, FlexibleBuilding) and isinstance(building.isolation, Isolation)
    assert building.isolation.damping_exponent == fit.estimates["damping_exponent"]
    assert fit.model == "2dof" and fit.damping == "power" and fit.label == "2dof"


@pytest.mark.slow
def test_2dof_with_fluid_dampers_reaches_the_minimum_on_a_minute():
    """The benchmark's minute (bench_flexible_fit's 2dof-power record: 60 s at 200 Hz): the auto fit ends at or
    below the fit started from the truth. The misfit has cusps where a turn (C |v|^alpha) passes a sample, where the
    least-squares solves stop short (xtol); 2dof skipped the polish, whose restarts reach past them: its auto fit
    ended 16.3 above the truth-started fit (36 017.0, the base accelerometer's zero 5.6 standard errors off), now
    35 994.4 against 35 998.6 (still "not confirmed")."""
    channels = _record("linear", TWO_DOF, seed=1, duration=60.0, rate=200.0)
    fit = fit_isolation(channels, M, "2dof", damping="power", superstructure_mass=MS, profile=False)
    start = {**TWO_DOF, **{f"offset_{c.name}": ZEROS[c.kind] for c in channels}}
    truth = fit_isolation(channels, M, "2dof", damping="power", superstructure_mass=MS, profile=False, start=start,
                          global_search=False)
    assert fit.chi2 <= truth.chi2 + 0.5, (fit.chi2, truth.chi2)


@pytest.mark.slow
def test_lead_rubber_with_fluid_dampers_under_a_storey_fitted_back():
    """Lead-rubber bearings with dampers (alpha 0.4) under a flexible superstructure: Kd's period, Qd, dy, n, C,
    alpha, the storey, d0 and the release fitted back (:func:`_checked`; the sliders' friction near its bound 0)."""
    fit = fit_isolation(_record("boucwen", LEAD_RUBBER, seed=1), M, "boucwen", flexible=True, damping="power",
                        superstructure_mass=MS, profile=False)
    _checked(fit, {n: v for n, v in LEAD_RUBBER.items() if n != "friction"})
    assert fit.estimates["friction"] < 3.0 * fit.std_errors["friction"]
    assert isinstance(fit.isolation().isolation, BoucWen) and fit.label == "boucwen (flexible)"
    # three starts reach the minimum (before the solver's steps were measured against each parameter's magnitude,
    # the loop's alone: "not confirmed", a second basin 1 835 above)
    assert fit.global_minimum_confirmed, fit.search.warnings


def _reference_errors(model, p, duration, rate=100.0):
    """The standard errors the record's noise allows at the truth ``p``, from the independent simulator alone: the
    Fisher information ``J^T J`` of the weighted samples (NOISE), J by central differences of
    isolator_reference's motion over 1e-6 of each parameter (the sliders' friction, true 0 at its bound, forward
    over 50 N: the fit frees it), with a zero for each channel (its column 1 / sigma)."""
    names = list(p)

    def weighted(q):
        return np.concatenate([y / NOISE[kind] for _, kind, y in _clean(model, q, duration, rate)[1]])

    at = weighted(p)
    columns = []
    for name in names:
        if p[name] == 0.0:
            columns.append((weighted({**p, name: 50.0}) - at) / 50.0)
        else:
            h = 1e-6 * abs(p[name])
            columns.append((weighted({**p, name: p[name] + h}) - weighted({**p, name: p[name] - h})) / (2 * h))
    n = at.size // 3
    for i, kind in enumerate(("x", "a", "a_roof")):
        zero = np.zeros(at.size)
        zero[i * n:(i + 1) * n] = 1.0 / NOISE[kind]
        columns.append(zero)
    J = np.column_stack(columns)
    cov = np.linalg.inv(J.T @ J)
    return {name: math.sqrt(cov[i, i]) for i, name in enumerate(names)}


@pytest.mark.slow
def test_lead_rubber_with_fluid_dampers_under_a_storey_standard_errors():
    """The standard errors of the lead-rubber + dampers + storey fit (a 6 s record, seed 3401) each within
    0.8-1.25 of those the independent simulator's information gives at the truth (:func:`_reference_errors`; the
    fit's at its estimate, a few standard errors away). Measured: 1.00-1.03. (The coverage check below is
    opt-in; this one runs in CI.)"""
    channels = _record("boucwen", LEAD_RUBBER, 3401, duration=6.0)
    fit = fit_isolation(channels, M, "boucwen", flexible=True, damping="power", superstructure_mass=MS,
                        profile=False)
    reference = _reference_errors("boucwen", LEAD_RUBBER, 6.0)
    ratios = {name: fit.std_errors[name] / se for name, se in reference.items()}
    assert all(0.8 <= r <= 1.25 for r in ratios.values()), ratios


COVERAGE_SEEDS = 25  # 25 records x 8 parameters: 200 intervals


@pytest.mark.slow
@pytest.mark.skipif(not os.environ.get("QUICKRELEASE_SLOW"), reason="opt-in (QUICKRELEASE_SLOW=1, -p no:timeout): 25 "
                    "fits of 2dof with fluid dampers, ~10 minutes; the fits above run in CI")
def test_2dof_with_fluid_dampers_intervals_cover_the_truth():
    """The 95% intervals of the 2dof fit with fluid dampers over 25 records (seeds 3100-3124, 10 s each; 200
    intervals of its 8 parameters): the pooled coverage in 90-99% and each parameter's count within the
    0.05%-99.95% band of Binomial(25, 0.95). Measured 2026-11-27: period 24, C 23, alpha 22, friction 22, T_s 24,
    zeta_s 24, d0 24, release 25 of 25; pooled 0.940 (4.9 minutes here)."""
    from coverage_records import binomial_band

    truth = dict(TWO_DOF)
    rows = _clean("linear", TWO_DOF, duration=10.0)
    covered = dict.fromkeys(truth, 0)
    for seed in range(3100, 3100 + COVERAGE_SEEDS):
        fit = fit_isolation(_noisy(rows, seed), M, "2dof", damping="power", superstructure_mass=MS, profile=False)
        for name, value in truth.items():
            covered[name] += fit.ci95[name][0] <= value <= fit.ci95[name][1]
    pooled = sum(covered.values()) / (COVERAGE_SEEDS * len(covered))
    print(f"coverage of 2dof with fluid dampers over {COVERAGE_SEEDS} seeds: {covered}, pooled {pooled:.3f}")
    lo, hi = binomial_band(COVERAGE_SEEDS)
    assert all(lo <= c <= hi for c in covered.values()), covered
    assert 0.90 <= pooled <= 0.99, (pooled, covered)


LEAD_RUBBER_SEEDS = 24  # 24 records x 10 parameters: 240 intervals


@pytest.mark.slow
@pytest.mark.skipif(not os.environ.get("QUICKRELEASE_SLOW"), reason="opt-in (QUICKRELEASE_SLOW=1, -p no:timeout): 24 "
                    "fits of lead-rubber bearings with fluid dampers under a storey, ~15 minutes; the fits above run "
                    "in CI")
def test_lead_rubber_with_fluid_dampers_under_a_storey_intervals_cover_the_truth():
    """The 95% intervals of the lead-rubber + fluid dampers + storey fit over 24 records (seeds 3400-3423, 6 s after
    the release: the base is still below the noise from 4 s on; 240 intervals of its 10 parameters, the sliders'
    friction, true 0 at its bound, left out): each record released at its own instant, a seeded 0-10 ms after
    LEAD_RUBBER's (the release's and the turns' places between the samples vary as in the field). The pooled
    coverage in 90-99% and each parameter's count within the 0.05%-99.95% band of Binomial(24, 0.95) (18-24).
    Measured 2026-11-27 (15.2 minutes at load ~2-3, a fit 19-79 s, median 36 s): period, C, alpha, Qd, dy, n,
    T_s, zeta_s, d0 23 of 24 each, release 21; pooled 0.950; the z-scores' spread 0.74-0.90, the release's 1.20
    (its three misses late by 2.2-2.6 standard errors); reduced chi-square 0.946-1.067; 21 of 24 "confirmed".
    20 more records (seeds 3424-3443, a scratch run): 18-20 of 20, pooled 0.985; the 44 together pooled 0.966,
    the release 39 of 44 (Binomial(44, 0.95) puts 39 or fewer at 7 %; its 44 z-scores' sum of squares at 6 %,
    Kolmogorov-Smirnov p 0.57): its standard error is the reference's (1.00 of the simulator's information at the
    truth on seeds 3401, 3408, 3411, 3412, three of them misses), the package's motion at the truth the
    reference's to far below the noise; left as chance.
    The friction's bound pulls the parameters correlated with it (period, C, alpha, Qd, dy, zeta_s, d0: |rho|
    0.65-0.89) off by +-0.2-0.5 on average and narrows their spread: with the friction free the intervals are
    those of the unconstrained fit, a linearised fit held at 0 half the time covers 0.97 of them. Seed 3422 had
    run for tens of minutes (a Bouc-Wen start from a bilinear fit that never yielded: see
    test_isolation_start's test_boucwen_start_of_a_bilinear_fit_keeps_its_layer); now 57 s."""
    from coverage_records import binomial_band

    names = [n for n in LEAD_RUBBER if n != "friction"]
    covered = dict.fromkeys(names, 0)
    z = {n: [] for n in names}
    for seed in range(3400, 3400 + LEAD_RUBBER_SEEDS):
        truth = {**LEAD_RUBBER, "release_time": T_R + np.random.default_rng(seed).uniform(0.0, 0.01)}
        channels = _record("boucwen", truth, seed, duration=6.0)
        start = time.perf_counter()
        fit = fit_isolation(channels, M, "boucwen", flexible=True, damping="power", superstructure_mass=MS,
                            profile=False)
        seconds = time.perf_counter() - start
        for name in names:
            covered[name] += fit.ci95[name][0] <= truth[name] <= fit.ci95[name][1]
            z[name].append((fit.estimates[name] - truth[name]) / fit.std_errors[name])
        print(f"seed {seed}: {seconds:.1f} s, chi2_red {fit.chi2_reduced:.3f}, confirmed {fit.global_minimum_confirmed}, z "
              + " ".join(f"{name} {z[name][-1]:+.2f}" for name in names), flush=True)
    pooled = sum(covered.values()) / (LEAD_RUBBER_SEEDS * len(covered))
    spread = {name: round(float(np.std(v)), 2) for name, v in z.items()}
    print(f"coverage of lead-rubber + fluid dampers + storey over {LEAD_RUBBER_SEEDS} records: {covered}, pooled "
          f"{pooled:.3f}; the z-scores' spread {spread}")
    lo, hi = binomial_band(LEAD_RUBBER_SEEDS)
    assert all(lo <= c <= hi for c in covered.values()), covered
    assert 0.90 <= pooled <= 0.99, (pooled, covered)
