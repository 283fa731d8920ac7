"""The building fit's global stage and its certificate (isolation_search.py), on records made by the independent
event-located solve_ivp of tests/building_reference.py (never the fit's own model).

Every fit must land within delta chi-square 1 of a fit started at the truth, from design values 20, 30 and 50%
off or none, with the channels x + a, x alone and a alone; the certificate must say when a second basin is as
good as the best (an aliased record, where two periods give the same samples). The ordinary run takes a few
records per class (tests marked slow: CI runs them); QUICKRELEASE_SLOW=1 runs the whole matrix.
"""

import math
import os
from functools import cache

import numpy as np
import pytest
from building_reference import reference

from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation
from quickrelease.building.isolation_search import SearchBox, cma_es, record_period, same_basin
from quickrelease.errors import QuickReleaseError

SLOW = bool(os.environ.get("QUICKRELEASE_SLOW"))
M = 8.0e5
RATE = 200.0
RELEASE = 2.0137  # s, record time (not given to the fit)


@cache
def _linear_truth(seed: int):
    rng = np.random.default_rng(seed)
    T, zeta = rng.uniform(2.0, 3.2), rng.uniform(0.02, 0.10)
    Fs, d0 = rng.uniform(0.003, 0.012) * M * 9.81, rng.uniform(0.08, 0.2)
    return {"period": T, "damping_ratio": zeta, "friction": Fs, "d0": d0}


@cache
def _bilinear_truth(seed: int):
    rng = np.random.default_rng(seed)
    T1, r = rng.uniform(0.8, 1.4), rng.uniform(0.08, 0.2)
    Fy, zeta = rng.uniform(0.04, 0.08) * M * 9.81, rng.uniform(0.01, 0.04)
    Fs, d0 = rng.uniform(0.005, 0.02) * M * 9.81, rng.uniform(0.1, 0.2)
    return {"period": T1, "stiffness_ratio": r, "yield_force": Fy, "damping_ratio": zeta, "friction": Fs, "d0": d0}


@cache
def _rows(kind: str, seed: int):
    """x, v, a of the independent simulation at 200 Hz over 60 s (the accelerometer on its own clock)."""
    p = _linear_truth(seed) if kind == "linear" else _bilinear_truth(seed)
    k1 = M * (2 * math.pi / p["period"]) ** 2
    if kind == "linear":
        k2, fp = k1, math.inf
    else:
        k2, fp = p["stiffness_ratio"] * k1, p["yield_force"] * (1 - p["stiffness_ratio"])
    c = 2 * p["damping_ratio"] * math.sqrt(k1 * M)
    t = np.arange(round(60.0 * RATE)) / RATE
    (x, _, _), _ = reference(M, k1, k2, fp, c, p["friction"], p["d0"], t - RELEASE, with_rates=True)
    (_, _, a), _ = reference(M, k1, k2, fp, c, p["friction"], p["d0"], t + 0.0013 - RELEASE, with_rates=True)
    return t, x, a


def _channels(kind: str, seed: int, which: str):
    t, x, a = _rows(kind, seed)
    rng = np.random.default_rng(1000 + seed)
    out = []
    if "x" in which:  # an LVDT with a 2 mm zero, 0.2 mm noise
        out.append(BuildingChannel("lvdt", "x", t, x + 0.002 + rng.normal(0, 2e-4, t.size)))
    if "a" in which:  # an accelerometer with a 0.01 m/s^2 zero, 0.02 m/s^2 noise
        out.append(BuildingChannel("acc", "a", t + 0.0013, a + 0.01 + rng.normal(0, 0.02, t.size)))
    return out


def _design(truth: dict, off: float | None, seed: int):
    """Design values off by ``off`` (each parameter up or down at random), or None."""
    if off is None:
        return None
    rng = np.random.default_rng(50 + seed)
    return {k: v * (1 + off * rng.choice([-1, 1])) for k, v in truth.items() if k != "d0"}


def _truth_fit(kind, seed, which):
    truth = _linear_truth(seed) if kind == "linear" else _bilinear_truth(seed)
    return fit_isolation(_channels(kind, seed, which), M, kind, profile=False, global_search=False,
                         start={**truth, "release_time": RELEASE})


#: (5, "a", 0.2): an acceleration-only record whose local search stopped on a step of the misfit 87 above the
#: truth-started fit, every parameter within its standard error of it (the acceleration jumps at the release,
#: each reversal and the stick, and each sample such an event crosses is a step): the step search
#: (``isolation_fit._step_search``) takes it down the staircase.
LINEAR_CASES = [(0, "xa", 0.3), (2, "xa", None), (4, "x", 0.5), (4, "a", 0.3), (5, "a", 0.2)]
LINEAR_SLOW = [(s, w, o) for s in range(6) for w in ("xa", "x", "a") for o in (0.2, 0.3, 0.5, None)
               if (s, w, o) not in LINEAR_CASES]


@pytest.mark.slow
@pytest.mark.parametrize("seed, which, off", LINEAR_CASES + (LINEAR_SLOW if SLOW else []))
def test_linear_fit_reaches_the_truth_started_minimum(seed, which, off):
    """From design values far off, or none, and with any channel subset: within delta chi-square 1 of the
    fit started at the truth, and the certificate says how it got there."""
    truth = _linear_truth(seed)
    fit = fit_isolation(_channels("linear", seed, which), M, "linear", profile=False, start=_design(truth, off, seed))
    ref = _truth_fit("linear", seed, which)
    assert fit.chi2 <= ref.chi2 + 1.0, (fit.estimates, ref.estimates)
    cert = fit.search
    assert cert.starts >= 4 and 1 <= cert.reached_best <= cert.starts
    assert fit.global_minimum_confirmed == (cert.reached_best >= 2 and cert.next_best_delta_chi2 >= 4.0)
    # the period within its interval of the truth (an independent simulation: the fit shares no code with it)
    lo, hi = fit.ci95["period"]
    assert lo - 1e-9 <= truth["period"] <= hi + 1e-9 or abs(fit.estimates["period"] / truth["period"] - 1) < 2e-3


BILINEAR_CASES = [(1, "xa", 0.3)]
#: (0, "xa", None): one release (the sliders stick at the first turning point), d0, the LVDT's zero and F_s not
#: separated by the record; the fit ends 1.9 above the truth-started one and says the minimum is not confirmed.
BILINEAR_SLOW = [pytest.param(s, w, o, marks=pytest.mark.xfail(reason="d0, zero and F_s not separated", strict=False))
                 if (s, w, o) == (0, "xa", None) else (s, w, o)
                 for s in range(4) for w in ("xa", "x") for o in (0.2, 0.3, None) if (s, w, o) not in BILINEAR_CASES]


@pytest.mark.slow
@pytest.mark.parametrize("seed, which, off", BILINEAR_CASES + (BILINEAR_SLOW if SLOW else []))
def test_bilinear_fit_reaches_the_truth_started_minimum(seed, which, off):
    truth = _bilinear_truth(seed)
    fit = fit_isolation(_channels("bilinear", seed, which), M, "bilinear", profile=False,
                        start=_design(truth, off, seed))
    ref = _truth_fit("bilinear", seed, which)
    assert fit.chi2 <= ref.chi2 + 1.0, (fit.estimates, ref.estimates)


@pytest.mark.slow
def test_the_global_stage_finds_what_the_design_values_miss():
    """A record whose sliders stick after a swing and a half: from design values 30% off, the local search
    ends in another basin (more than 100 above the best), the fit with its global stage within delta
    chi-square 1 of the fit started at the truth, its CMA-ES runs among the starts that reached it. Without
    the global stage no search runs at all (no evaluations, no global start)."""
    seed, which = 7, "xa"
    truth = _linear_truth(seed)
    start = _design(truth, 0.3, seed)
    fit = fit_isolation(_channels("linear", seed, which), M, "linear", profile=False, start=start)
    ref = _truth_fit("linear", seed, which)
    assert fit.chi2 <= ref.chi2 + 1.0
    assert any(s.startswith("global search") for s in fit.search.minima[0].starts)
    design = next(m for m in fit.search.minima if "design values" in m.starts)
    assert design.delta_chi2 > 100.0  # the design values alone: a wrong minimum
    local = fit_isolation(_channels("linear", seed, which), M, "linear", profile=False, start=start,
                          global_search=False)
    assert local.search.evaluations == 0 and not any(s.startswith("global") for m in local.search.minima
                                                     for s in m.starts)


def _aliased_channels():
    """An undamped, frictionless layer sampled at 0.8 Hz: the periods 2.0 s and 1 / (0.8 - 0.5) = 3.333 s give
    the same samples (cos(w t_k) = cos((2 pi / dt - w) t_k) at t_k = k dt after the release, which is on a
    sample). A little damping makes the two basins nearly, not exactly, equal."""
    dt = 1.25
    t = np.arange(60) * dt - 5.0  # the release at t = 0, on a sample
    zeta, w = 0.002, 2 * math.pi / 2.0  # the analytic free decay from rest at d0 = 0.1 m
    wd, tau = w * math.sqrt(1 - zeta**2), np.clip(t, 0.0, None)
    x = 0.1 * np.exp(-zeta * w * tau) * (np.cos(wd * tau) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * tau))
    rng = np.random.default_rng(3)
    return [BuildingChannel("lvdt", "x", t, x + rng.normal(0, 2e-3, t.size), noise=2e-3, offset=False)]


@pytest.mark.slow
def test_certificate_reports_two_nearly_equal_basins():
    """The aliased record has two minima (T = 2 s and T = 3.33 s) within a few units of chi-square: the fit
    must not claim a confirmed global minimum, must list both, and its 95% interval of the period must cover
    both."""
    fit = fit_isolation(_aliased_channels(), M, "linear", profile=False, release_time=0.0, fit_release_time=False,
                        fixed={"friction": 0.0})
    cert = fit.search
    periods = sorted(m.parameters["period"] for m in cert.minima if m.delta_chi2 < 4.0)
    assert len(periods) >= 2
    assert periods[0] == pytest.approx(2.0, rel=0.01) and periods[-1] == pytest.approx(1 / (0.8 - 0.5), rel=0.01)
    assert cert.next_best_delta_chi2 < 4.0
    assert not fit.global_minimum_confirmed
    assert any("second minimum" in w for w in fit.warnings)
    lo, hi = fit.ci95["period"]
    assert lo <= periods[0] and hi >= periods[-1]
    assert fit.interval_method["period"] == "covers two minima"


def test_certificate_confirms_a_clean_record():
    """A clean linear record with both channels: every kind of start reaches one minimum, confirmed."""
    fit = fit_isolation(_channels("linear", 0, "xa"), M, "linear", profile=False)
    assert fit.global_minimum_confirmed
    assert fit.search.reached_best >= 2 and fit.search.next_best_delta_chi2 >= 4.0
    assert fit.summary()["global_minimum_confirmed"] is True


def test_growing_oscillation_is_refused_at_once():
    """A free vibration from a push only decays: a record whose swing grows is refused with one line, before
    any fit (it once ran for over a minute and returned the fit of its last seconds)."""
    t = np.arange(0, 60, 0.005)
    tau = np.clip(t - 2.0, 0, None)
    x = 0.1 * np.exp(0.02 * tau) * np.cos(2 * math.pi / 2.5 * tau)
    rng = np.random.default_rng(1)
    with pytest.raises(QuickReleaseError, match="the oscillation grows"):
        fit_isolation([BuildingChannel("x", "x", t, x + rng.normal(0, 2e-4, t.size))], M, "linear")


@pytest.mark.parametrize("d0, seed", [(0.12, 10), (0.18, 11)])
def test_constant_friction_pendulum_fit_reaches_its_minimum(d0, seed):
    """A pendulum with constant friction (mu 0.5 %, R 2.5 m, 1 % damping; the independent reference's record, LVDT
    at 50 Hz, 12 s, noise 0.2 mm, zero 2 mm; h28a's campaign records). The Jacobian stepped the friction coefficient
    by 1e-4 absolute, 2 % of it, and its guarded difference got the gradient's sign wrong: the fit of d0 0.12 m
    stopped 10.5 above the minimum with mu 29 standard errors low, that of 0.18 m 8 above. With the step 1e-4 of
    the value (the starts on the thinned record keep the wide one, which carries them over the cliff of the
    half-cycles' count: with the fine step everywhere, every start of 0.12 m ended a micro-swing later, 300 above)
    the fit ends where the fit started at the truth ends, the truth within 4 standard errors."""
    import isolator_reference as ref

    m, radius, mu, zeta = 1.0e6, 2.5, 0.005, 0.01
    k = m * ref.GRAVITY / radius
    system = ref.pendulum(m, radius, mu, damping=2 * zeta * math.sqrt(k * m))
    t = np.arange(round(13.0 * 50.0)) / 50.0 - 1.0
    x = ref.simulate(system, d0, t - 0.0137).x + 0.002 + np.random.default_rng(seed).normal(0.0, 2e-4, t.size)
    channels = [BuildingChannel("x", "x", t, x, 2e-4)]
    truth = {"period": 2 * math.pi * math.sqrt(radius / ref.GRAVITY), "friction_slow": mu, "damping_ratio": zeta,
             "d0": d0, "release_time": 0.0137}
    fixed = {"rate": 0.0, "friction_fast": 0.007}  # constant friction: mu_fast has no effect with the rate at 0
    fit = fit_isolation(channels, m, "pendulum", fixed=fixed, profile=False)
    from_truth = fit_isolation(channels, m, "pendulum", fixed=fixed, profile=False, start=truth, global_search=False)
    assert fit.chi2 <= from_truth.chi2 + 1.0, (fit.chi2, from_truth.chi2)
    z = {n: (fit.estimates[n] - v) / fit.std_errors[n] for n, v in truth.items()}
    assert all(abs(v) < 4.0 for v in z.values()), z


def _pendulum_record(seed: int):
    """The benchmark's friction pendulum (bench_isolators ``pendulum``): 1000 t on sliders R = 3 m, Constantinou's
    mu 0.01 / 0.025 with a = 40 s/m, d0 = 0.30 m; 60 s at 200 Hz after 2 s at rest, x (0.2 mm noise, 2 mm zero),
    v (1 mm/s) and a (0.02 m/s^2, 0.01 zero), from the independent solve_ivp simulator."""
    import isolator_reference as ref

    t = np.arange(round(62.0 * 200.0)) / 200.0
    motion = ref.simulate(ref.pendulum(1e6, 3.0, 0.01, 0.025, 40.0), 0.30, t - 2.0137, t_end=61.0)
    rng = np.random.default_rng(seed)
    return [BuildingChannel(n, n, t, y + zero + rng.normal(0.0, sd, t.size))
            for n, y, zero, sd in (("x", motion.x, 0.002, 2e-4), ("v", motion.v, 0.0, 1e-3),
                                   ("a", motion.a, 0.01, 0.02))]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [2, 3, 6])
def test_velocity_dependent_pendulum_fit_reaches_the_truth_started_minimum(seed):
    """Constantinou's law trades the slow friction against the rate: on these records every start (the record's
    and the three global runs) ended at mu_slow 0.0012-0.0013, a 61 s/m, 426-593 above the basin of the truth
    (0.0105, 38), and the certificate confirmed it (4 of 4 starts). The starts spread over mu_slow / mu_fast
    (``isolation_fit.PENDULUM_RATIOS``) reach the truth's basin: the fit ends where the fit started at the truth
    ends, the truth's friction law within its intervals."""
    import isolator_reference as ref

    channels = _pendulum_record(seed)
    truth = {"period": 2 * math.pi * math.sqrt(3.0 / ref.GRAVITY), "friction_slow": 0.01, "friction_fast": 0.025,
             "rate": 40.0, "d0": 0.30, "release_time": 2.0137}
    fit = fit_isolation(channels, 1e6, "pendulum", profile=False)
    from_truth = fit_isolation(channels, 1e6, "pendulum", profile=False, start=truth, global_search=False)
    assert fit.chi2 <= from_truth.chi2 + 1.0, (fit.chi2, from_truth.chi2, fit.estimates)
    for n in ("friction_slow", "friction_fast", "rate"):
        lo, hi = fit.ci95[n]
        assert lo <= truth[n] <= hi, (n, fit.estimates[n], fit.ci95[n])


@cache
def _model_choice_fit(model: str):
    """(case, channels, fit) of test_model_choice's record ``draw(model, 3)`` fitted as it is (profile=False): the
    reference fit of the two symmetry tests below, made once (fit_isolation is deterministic, and neither test
    changes it)."""
    from test_model_choice import draw, record

    case = draw(model, 3)
    channels, _ = record(case)
    return case, channels, fit_isolation(channels, case.mass, model, profile=False)


@pytest.mark.slow
def test_a_clock_of_the_time_of_day_gives_the_same_fit():
    """Loggers stamp samples with the time of day (36 000 s at 10 am): the record's time origin carries no physics,
    so the fit must not depend on it. The Jacobian stepped the release instant by 1e-4 of its clock value, 3.6 s
    there: a model-choice record (LVDT and accelerometer, the independent reference's) ended 453 above its fit at
    the origin, the release 0.9 ms off, its standard error 8 times too large. Now every estimate agrees within 1 %
    of its standard error."""
    case, channels, a = _model_choice_fit("linear")
    shift = 36000.0
    moved = [BuildingChannel(c.name, c.kind, c.t + shift, c.values, c.noise, c.offset, c.drift) for c in channels]
    b = fit_isolation(moved, case.mass, "linear", profile=False)
    for n in a.names:
        lag = shift if n == "release_time" else 0.0
        assert b.estimates[n] - lag == pytest.approx(a.estimates[n], abs=0.01 * a.std_errors[n]), n
        assert b.std_errors[n] == pytest.approx(a.std_errors[n], rel=0.01), n


def test_the_solvers_coordinates_do_not_depend_on_the_clock():
    """The solver's coordinates (each parameter's origin and magnitude, _Misfit.scales): the release time measured from
    the record's first sample, so that a clock of the time of day (36 000 s) does not make the release's steps
    relative to 36 000 s (the starts' solves stop at 1e-4 of each magnitude: 3.6 s); the others from their values,
    a force at least 1e-3 of the weight."""
    from quickrelease.building.isolation_fit import _Misfit

    t = np.arange(0.0, 10.0, 0.01)
    names = ["period", "friction", "d0", "release_time", "offset_x"]
    scales = []
    for shift in (0.0, 36000.0):
        ch = [BuildingChannel("x", "x", t + shift, np.cos(t), 1e-3)]
        misfit = _Misfit(ch, {"x": 1e-3}, 8e5, "linear", None, {}, {})
        origin, scale = misfit.scales(names, np.array([2.5, 0.0, 0.2, 1.3 + shift, 0.0]))
        scales.append(scale)
        assert origin[3] == shift and scale[3] == pytest.approx(1.3)
    np.testing.assert_allclose(scales[0], scales[1], rtol=1e-9)
    np.testing.assert_allclose(scales[0], [2.5, 1e-3 * 8e5 * 9.80665, 0.2, 1.3, 1e-3], rtol=1e-9)


@pytest.mark.parametrize("model", ["linear", pytest.param("bilinear", marks=[pytest.mark.slow, pytest.mark.skipif(
    not SLOW, reason="opt-in (QUICKRELEASE_SLOW=1): three bilinear fits; CI's whole run took 884 s of its 900")])])
@pytest.mark.slow
def test_a_mirrored_record_and_a_scaled_mass_give_the_same_fit(model):
    """Two symmetries of the physics, not of the code: a record pushed the other way (every channel negated: a
    sensor mounted the other way round) is the same building, d0 negated; and the record fixes the parameters per
    unit mass, so a mass 1000 times smaller gives forces 1000 times smaller and the same period, damping, d0 and
    release. Each estimate within 1e-6 of its standard error (measured 2026-11-27: 2e-7 at worst; pendulum and
    Bouc-Wen likewise, 1e-7 and 9e-10, left out here for time)."""
    case, channels, base = _model_choice_fit(model)
    mirrored = fit_isolation([BuildingChannel(c.name, c.kind, c.t, -c.values, c.noise, c.offset, c.drift)
                              for c in channels], case.mass, model, profile=False)
    light = fit_isolation(channels, 1e-3 * case.mass, model, profile=False)
    for n in base.names:
        sign = -1.0 if n == "d0" or n.startswith("offset_") else 1.0
        scale = 1e3 if n in ("friction", "yield_force") else 1.0
        assert sign * mirrored.estimates[n] == pytest.approx(base.estimates[n], abs=1e-6 * base.std_errors[n]), n
        assert scale * light.estimates[n] == pytest.approx(base.estimates[n], abs=1e-6 * base.std_errors[n]), n


def test_record_that_ends_mid_swing_is_not_refused():
    """A record that ends before the building settles (5 s of a 2 s building, its last tenth near a turning point)
    decays: it was refused as growing ("a swing of 0.102 m after a first of 0.0798 m", h28a's finding), its level
    taken from the last tenth. Now it is fitted, and the independent reference's truth lies within 4 standard
    errors."""
    m, k, zeta, fs, d0 = 4.0e5, 4.0e5 * math.pi**2, 0.03, 2.0e4, 0.10
    t = np.arange(250) / 50.0 - 1.0
    x = reference(m, k, k, 0.0, 2 * zeta * math.sqrt(k * m), fs, d0, t - 0.0137)[0]
    x = x + np.random.default_rng(7).normal(0.0, 2e-4, t.size)
    fit = fit_isolation([BuildingChannel("lvdt", "x", t, x)], m, "linear", profile=False)
    truth = {"period": 2.0, "damping_ratio": zeta, "friction": fs, "d0": d0}
    z = {n: (fit.estimates[n] - v) / fit.std_errors[n] for n, v in truth.items()}
    assert all(abs(v) < 4.0 for v in z.values()), z


@pytest.mark.parametrize("period, rate, cycles", [(2.0, 200.0, 8), (3.1, 50.0, 4), (0.9, 100.0, 20)])
def test_record_period_of_a_sampled_decay(period, rate, cycles):
    """A damped cosine of a known damped period (hand calculation: T_d = T / sqrt(1 - zeta^2)), with noise."""
    zeta = 0.03
    td = period / math.sqrt(1 - zeta**2)
    t = np.arange(0, cycles * period + 1.0, 1.0 / rate)
    tau = np.clip(t - 1.0, 0, None)
    x = 0.1 * np.exp(-zeta * 2 * math.pi / period * tau) * np.cos(2 * math.pi / td * tau)
    x += np.random.default_rng(0).normal(0, 1e-4, t.size)
    ch = BuildingChannel("x", "x", t, x)
    assert record_period([ch], 1.0) == pytest.approx(td, rel=0.02)


def test_cma_es_minimises_a_rotated_ellipsoid_and_rosenbrock():
    """The CMA-ES of the global stage against functions with known minima: a rotated ill-conditioned ellipsoid
    centred at c (minimum 0 at c) and the Rosenbrock function scaled into the unit cube (minimum 0 at 0.6)."""
    rng = np.random.default_rng(0)
    q, _ = np.linalg.qr(rng.normal(size=(4, 4)))
    h = q @ np.diag([1.0, 10.0, 100.0, 1000.0]) @ q.T
    c = np.array([0.3, 0.7, 0.45, 0.6])
    x, f, spent = cma_es(lambda u: float((u - c) @ h @ (u - c)), np.full(4, 0.5), 0.3, 6000, 1, tolfun=1e-14,
                         tolx=1e-9)
    assert np.allclose(x, c, atol=1e-5) and f < 1e-9 and spent <= 6000

    def rosen(u):
        y = 5 * (np.asarray(u) - 0.6) + 1.0  # the minimum (1, 1, 1) at u = 0.6
        return float(np.sum(100 * (y[1:] - y[:-1] ** 2) ** 2 + (1 - y[:-1]) ** 2))

    x, f, _ = cma_es(rosen, np.full(3, 0.3), 0.2, 8000, 2, tolfun=1e-14, tolx=1e-10)
    assert f < 1e-8 and np.allclose(x, 0.6, atol=1e-4)


def test_search_box_round_trip():
    box = SearchBox(("period", "damping_ratio", "release_time"), (0.5, 0.0, 1.0), (4.0, 0.4, 2.0),
                    ("log", "sqrt", "linear"))
    values = {"period": 2.0, "damping_ratio": 0.05, "release_time": 1.25}
    u = box.to_unit(values)
    # hand: log(2/0.5)/log(4/0.5) = 2/3; sqrt(0.05)/sqrt(0.4); 0.25
    assert u == pytest.approx([2 / 3, math.sqrt(0.05 / 0.4), 0.25])
    assert box.to_values(u) == pytest.approx(values)


def test_same_basin_counts_standard_errors():
    """Two fits are one basin when every parameter lies within 3 standard errors (hand values), and a
    parameter without a finite standard error (not identified) does not tell them apart."""
    se = {"period": 0.1, "friction": math.inf}
    assert same_basin({"period": 1.0, "friction": 5.0}, {"period": 1.25, "friction": 500.0}, se)  # 2.5 SE
    assert not same_basin({"period": 1.0, "friction": 5.0}, {"period": 1.35, "friction": 5.0}, se)  # 3.5 SE
    assert not same_basin({"period": 1.0}, {"period": 0.65}, {"period": 0.1})


@pytest.mark.slow
def test_a_record_that_never_stops_gets_a_clear_answer():
    """An undamped, frictionless layer (the analytic cosine) over the whole record: the fit says so (damping
    and friction at their lower bound 0, their profile intervals from 0) instead of raising from a root
    bracket of the profile likelihood ("f(a) and f(b) must have different signs", issue 22 item 8)."""
    t = np.arange(0, 30, 0.01)
    tau = np.clip(t - 2.0137, 0, None)
    x = 0.1 * np.cos(2 * math.pi / 2.5 * tau) + np.random.default_rng(1).normal(0, 2e-4, t.size)
    fit = fit_isolation([BuildingChannel("x", "x", t, x)], M, "linear")
    assert fit.estimates["period"] == pytest.approx(2.5, rel=1e-4)
    assert fit.ci95["damping_ratio"][0] == 0.0 and fit.ci95["damping_ratio"][1] < 1e-3
    assert fit.ci95["friction"][0] == 0.0 and fit.interval_method["friction"] == "profile"


@pytest.mark.slow
def test_a_record_that_starts_mid_swing():
    """A record caught mid-swing (no quiet segment: it starts 0.3 of a period after the release): the fit
    takes the first turning point as a release from rest (exact for the linear layer with Coulomb sliders:
    at a turning point it is at rest, and the motion after it is that of a release from there), says so,
    and its intervals hold the truth of the independent simulation."""
    seed = 1
    truth = _linear_truth(seed)
    t, x, a = _rows("linear", seed)
    cut = t >= RELEASE + 0.3 * truth["period"]
    rng = np.random.default_rng(11)
    channels = [BuildingChannel("lvdt", "x", t[cut], x[cut] + 0.002 + rng.normal(0, 2e-4, cut.sum())),
                BuildingChannel("acc", "a", t[cut] + 0.0013, a[cut] + 0.01 + rng.normal(0, 0.02, cut.sum()))]
    fit = fit_isolation(channels, M, "linear", profile=False)
    assert any("starts in motion" in w for w in fit.warnings)
    # the turning point half a period after the release
    assert fit.release_time == pytest.approx(RELEASE + 0.5 * truth["period"], abs=0.02)
    for name in ("period", "damping_ratio", "friction"):
        lo, hi = fit.ci95[name]
        assert lo <= truth[name] <= hi, (name, fit.estimates[name], truth[name], (lo, hi))


@pytest.mark.parametrize("model", ["linear", "pendulum", "bilinear", "boucwen"])
def test_a_record_caught_mid_swing_says_what_its_first_turn_means(model):
    """A record caught mid-swing is fitted from its first turning point, taken as a release from rest: exact where
    the layer's state at rest is its displacement alone (linear, pendulum), and the warning says so; the bilinear
    and Bouc-Wen elements yielded the other way on the swing before it, not as a push to it: the warning says their
    estimates are biased (measured: a Bouc-Wen record cut 0.3 of its period after the release fitted to a period
    of 1.64 +- 0.003 s against 3.0 s). The record: lead-rubber bearings (Kd 3.5 MN/m, Qd 400 kN, dy 25 mm) from the
    independent solve_ivp simulator, cut 0.9 s after the release."""
    import isolator_reference as ref

    from quickrelease.building.isolation_fit import _start_in_motion

    system = ref.boucwen(M, 3.5e6, 4.0e5, 0.025, 1.0, damping=2 * 0.02 * math.sqrt(3.5e6 * M))
    t = np.arange(round(20.0 * RATE)) / RATE + RELEASE + 0.9
    x = ref.simulate(system, 0.2, t - RELEASE, t_end=21.0).x + np.random.default_rng(3).normal(0.0, 2e-4, t.size)
    kept, turn, warnings = _start_in_motion([BuildingChannel("lvdt", "x", t, x)], model)
    assert turn is not None and kept[0].t[0] >= turn and len(warnings) == 1
    assert "starts in motion" in warnings[0]
    if model in ("bilinear", "boucwen"):
        assert "biased" in warnings[0] and "yielded the other way" in warnings[0], warnings[0]
    else:
        assert "exact" in warnings[0] and "biased" not in warnings[0], warnings[0]


def test_progress_says_what_runs():
    """A long fit says which model and start runs, with counts (the CLI's spinner text, or its progress lines
    when piped)."""
    said = []
    fit_isolation(_channels("linear", 0, "x"), M, "linear", profile=False, progress=said.append)
    assert said[0] == "linear: global search, run 1 of 3" and "linear: global search, run 3 of 3" in said
    starts = [s for s in said if s.startswith("linear: start ")]
    assert starts and all(s.endswith(")") for s in starts) and "of" in starts[0]
    assert any(s.startswith("linear: minimum 1 of") for s in said)


@cache
def _motion_without_a_crossing(kind: str):
    """(t, the reference's motion) of a record without a crossing (kind: creeps, sticks), simulated once for the
    noise levels below (the reference is deterministic)."""
    import isolator_reference as ref

    if kind == "creeps":
        system = ref.boucwen(M, 1.6e6, 4.0e5, 0.025, 1.0, damping=2 * 0.02 * math.sqrt(1.6e6 * M))
    else:
        k = M * (2 * math.pi / 2.5) ** 2
        system = ref.linear(M, k, 2 * 0.05 * math.sqrt(k * M), friction=0.3 * k * 0.2)
    t = np.arange(0.0, 62.0, 1.0 / RATE)
    return t, ref.simulate(system, 0.2, t - RELEASE, t_end=61.0)


@pytest.mark.parametrize("kind, noise", [("creeps after its first turn", 2e-4), ("sticks at its first turn", 2e-4),
                                         ("creeps after its first turn", 2e-3)])
def test_record_period_of_a_record_without_a_crossing(kind, noise):
    """A displacement that never crosses its final level: twice the time from the release to its first turning
    point, by the independent reference (isolator_reference.py). A Bouc-Wen element whose Qd exceeds Kd d0 (n 1,
    no sliders) turns short of its final level and creeps towards it for a minute (before: twice the time to
    that level, 84 s, and the fit's search box and release window followed it); a linear isolation with sliders
    that stick at the first turn. The noisy record (noise 2 mm): its noise alone turns back by more than half the
    band (5 mm) near the first turning point, but not by ten noise levels (20 mm)."""
    t, motion = _motion_without_a_crossing(kind.split()[0])
    first_turn = motion.reversal_times[1]  # (the release's the first)
    assert kind.startswith("sticks") == (motion.stop_time == first_turn)
    x = motion.x + 0.002 + np.random.default_rng(3).normal(0.0, noise, t.size)
    assert record_period([BuildingChannel("x", "x", t, x)], 2.01) == pytest.approx(2 * first_turn, abs=0.1)
