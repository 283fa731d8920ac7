"""The decrement laws of decay.py (viscous, Coulomb, combined, quadratic, power) against peak sequences built
by hand and solve_ivp written here, their physical bounds, their standard errors, the AIC choice, turning
points that time-stamp jitter does not move, and records that start mid-swing."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from quickrelease.building.decay import (
    analyse_decay,
    combined_decay_law,
    decay_laws,
    first_turning_point,
    power_next_amplitude,
    quadratic_next_amplitude,
)

REST = 0.004  # the sensor's reading at the unloaded position [m]


def _signed(amplitudes, rest=REST):
    """Turning points from amplitudes about the rest reading, a maximum first."""
    a = np.asarray(amplitudes, dtype=float)
    return rest + a * (-1.0) ** np.arange(a.size)


def _hand_quadratic(a, mu):
    """The next amplitude of x'' + mu x'|x'| + w^2 x = 0 by bisection on the exact half-cycle relation
    (1 + 2 mu a) exp(-2 mu a) = (1 - 2 mu b) exp(2 mu b), written here."""
    lhs = (1 + 2 * mu * a) * math.exp(-2 * mu * a)
    return brentq(lambda b: (1 - 2 * mu * b) * math.exp(2 * mu * b) - lhs, 0.0, 1 / (2 * mu), xtol=1e-16, rtol=1e-15)


def _sequence(law, n=12, a0=0.15):
    r, delta, mu = 0.86, 2.0e-3, 1.2
    steps = {"viscous": lambda a: r * a,
             "coulomb": lambda a: a - 2 * delta,
             "combined": lambda a: r * a - (1 + r) * delta,
             "quadratic": lambda a: _hand_quadratic(a, mu),
             # dA/dn = -kappa A^1.5 (scaled by a0), integrated by hand: A^-0.5 grows by 0.5 kappa a0^-0.5 a step
             "power": lambda a: (a**-0.5 + 0.5 * 0.12 * a0**-0.5) ** -2}
    amps = [a0]
    for _ in range(n):
        amps.append(steps[law](amps[-1]))
    return _signed(amps)


def test_quadratic_half_cycle_against_solve_ivp():
    """One half-cycle of x'' + mu x'|x'| + w^2 x = 0 from rest at a, integrated with an event at v = 0."""
    w, mu = 2 * math.pi / 2.5, 3.0

    def rhs(_, y):
        return [y[1], -mu * y[1] * abs(y[1]) - w * w * y[0]]

    def stop(_, y):
        return y[1]

    stop.terminal, stop.direction = True, 1  # the velocity comes back to zero from below
    for a in (0.01, 0.1, 0.25):
        sol = solve_ivp(rhs, (0.0, 10.0), [a, 0.0], events=stop, method="DOP853", rtol=1e-12, atol=1e-15,
                        first_step=1e-6)
        b = -float(sol.y_events[0][0][0])
        assert quadratic_next_amplitude(np.array([a]), mu)[0] == pytest.approx(b, rel=1e-8)
        # the averaged law (4/3) mu a^2 per half-cycle is its first order
        assert a - b == pytest.approx(4 / 3 * mu * a * a, rel=3 * mu * a)


def test_power_law_contains_viscous_and_coulomb_exactly():
    a = np.array([0.2, 0.1, 0.05])
    np.testing.assert_allclose(power_next_amplitude(a, 0.3, 1.0, 0.2), a * math.exp(-0.3), rtol=1e-14)
    np.testing.assert_allclose(power_next_amplitude(a, 0.02 / 0.2, 0.0, 0.2), a - 0.02, rtol=1e-12)
    assert power_next_amplitude(np.array([0.01]), 0.1, 0.0, 0.2)[0] == 0.0  # stuck: no negative amplitude


@pytest.mark.parametrize("law", ["viscous", "coulomb", "combined", "quadratic", "power"])
def test_each_law_is_chosen_by_aic_on_its_own_peaks(law):
    """Exact peaks of one law: that law is first by AIC (the others either misfit, or fit as well with
    more parameters); on noisy peaks with known errors the true law is first or within 2 AIC in most seeds
    and the others that misfit are far behind."""
    peaks = _sequence(law)
    fits = decay_laws(peaks)
    assert fits[0].name == law, [(f.name, f.aic) for f in fits]
    p = fits[0].parameters
    assert p["rest"] == pytest.approx(REST, abs=1e-9)
    expected = {"viscous": ("ratio", 0.86), "coulomb": ("friction_displacement", 2e-3),
                "combined": ("friction_displacement", 2e-3), "quadratic": ("quadratic_coefficient", 1.2),
                "power": ("exponent", 1.5)}[law]
    assert p[expected[0]] == pytest.approx(expected[1], rel=1e-6)
    sigma = 2e-5
    first = 0
    for seed in range(6):
        noisy = peaks + np.random.default_rng(seed).normal(0.0, sigma, peaks.size)
        fits = decay_laws(noisy, peak_se=sigma)
        aic = {f.name: f.aic for f in fits}
        first += aic[law] - min(aic.values()) <= 2.0
    assert first >= 5, first


def test_aic_prefers_the_simpler_law_that_fits():
    """Viscous peaks: viscous, combined (delta = 0) and power (alpha = 1) fit them exactly; the viscous law
    has one parameter fewer and comes first, the combined law's delta sits on its bound 0."""
    fits = decay_laws(_sequence("viscous"))
    names = [f.name for f in fits]
    assert names[0] == "viscous" and names.index("combined") < names.index("coulomb")
    combined = next(f for f in fits if f.name == "combined")
    assert combined.parameters["friction_displacement"] < 1e-12 and "friction_displacement" in combined.at_bound


def test_the_laws_never_report_the_impossible():
    """Noisy peaks of a viscous decay (delta = 0) and of a pure Coulomb decay (r = 1): unbounded least
    squares gives a negative friction or a ratio above 1 (negative damping) in about half the seeds; the
    bounded laws never do, and say when a value sits on its bound."""
    sigma = 1e-4
    negative = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        for law in ("viscous", "coulomb"):
            clean = _sequence(law)
            noisy = clean + rng.normal(0.0, sigma, clean.size)
            for fit in decay_laws(noisy, peak_se=sigma) if seed < 4 else ():
                p = fit.parameters
                if "ratio" in p:
                    assert 0.0 < p["ratio"] <= 1.0 and 0.0 <= p["damping_ratio"] < 1.0
                if "friction_displacement" in p:
                    assert p["friction_displacement"] >= 0.0
                for key in ("quadratic_coefficient", "kappa"):
                    assert p.get(key, 0.0) >= 0.0
                assert 0.0 <= p.get("exponent", 1.0) <= 3.0
            law_c = combined_decay_law(noisy, peak_se=sigma)
            assert law_c.friction_displacement >= 0.0 and 0.0 <= law_c.damping_ratio < 1.0
            negative += bool(law_c.at_bound)
    assert negative >= 10  # the bounds were needed, not idle


def test_combined_law_standard_errors_are_calibrated():
    """60 noisy sequences of the combined law (known peak errors): the z-scores of zeta and delta have an
    RMS near 1. Standard errors from the scatter of a few residuals, or ones that leave out the peaks'
    shared errors, miss this by far."""
    peaks = _sequence("combined", n=10)
    sigma = 3e-4
    z = []
    zeta_true = -math.log(0.86) / math.hypot(math.pi, math.log(0.86))
    for seed in range(60):
        noisy = peaks + np.random.default_rng(100 + seed).normal(0.0, sigma, peaks.size)
        law = combined_decay_law(noisy, peak_se=sigma)
        z.append((law.damping_ratio - zeta_true) / law.damping_ratio_se)
        z.append((law.friction_displacement - 2e-3) / law.friction_displacement_se)
    rms = float(np.sqrt(np.mean(np.square(z))))
    assert 0.75 < rms < 1.3, rms


def test_a_law_that_misfits_says_so_and_widens_its_errors():
    """Quadratic-damping peaks fitted by the combined law: chi2 / dof far above 1, and the standard errors
    scaled up so that they cover the spread of its estimates over seeds."""
    peaks = _sequence("quadratic")
    sigma = 2e-5
    laws = [combined_decay_law(peaks + np.random.default_rng(s).normal(0, sigma, peaks.size), peak_se=sigma)
            for s in range(12)]
    assert all(law.reduced_chi2 > 10 for law in laws)
    estimates = np.array([law.damping_ratio for law in laws])
    assert np.median([law.damping_ratio_se for law in laws]) > np.std(estimates)


def _viscous_decay(t, d0, zeta, period):
    """x(t) of m x'' + c x' + k x = 0 released from rest at d0 (t >= 0), by hand."""
    w = 2 * math.pi / period
    wd = w * math.sqrt(1 - zeta**2)
    return d0 * np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))


def test_turning_points_are_not_moved_by_time_stamp_jitter():
    """A viscous decay sampled at 200 Hz on a clock whose stamps scatter by 2 ms, with noise 20 um: the
    stamps move the samples on the flanks by up to 0.6 mm (jitter |dx/dt|), thirty times the noise. Given
    the jitter, the analysis makes no half-cycles of it, and the turning points come back without outward
    bias against the exact ones, d0 (-1)^n exp(-zeta w t_n) at t_n = n pi / w_d, within about the noise
    (without it: 2000 spurious turning points, errors of thousands of noise levels); the raw largest
    sample of each swing lies outward (the largest of several noisy samples)."""
    zeta, period, d0, sigma, jitter = 0.01, 2.0, 0.1, 2e-5, 2e-3
    rng = np.random.default_rng(7)
    true_t = np.arange(0.0, 20.0, 0.005)
    x = _viscous_decay(true_t, d0, zeta, period) + rng.normal(0.0, sigma, true_t.size)
    stamps = true_t + rng.normal(0.0, jitter, true_t.size)
    stamps[0] = 0.0
    order = np.argsort(stamps)
    stamps, x = stamps[order], x[order]
    x[0] = d0
    analysis = analyse_decay(stamps, x, noise=sigma, jitter=jitter)
    w = 2 * math.pi / period
    wd = w * math.sqrt(1 - zeta**2)
    n = np.arange(analysis.peaks.size)
    assert n.size == 20  # the release and a turning point each second (the last falls on the end)
    exact = d0 * (-1.0) ** n * np.exp(-zeta * w * n * math.pi / wd)
    outward = ((analysis.peaks - exact) * np.sign(exact))[1:]
    assert abs(float(np.mean(outward))) < 0.3 * sigma  # no outward bias
    assert float(np.sqrt(np.mean(outward**2))) < 1.2 * sigma
    raw_max = []
    for tn, sign in zip(n[1:] * math.pi / wd, np.sign(exact[1:]), strict=True):
        near = np.abs(stamps - tn) < 0.1
        raw_max.append(float(np.max(sign * x[near])))
    raw_bias = float(np.mean(np.array(raw_max) - np.abs(exact[1:])))  # what a raw maximum gives
    assert raw_bias > max(0.4 * sigma, 3 * abs(float(np.mean(outward))))
    law = analysis.law
    assert law.damping_ratio == pytest.approx(zeta, abs=4 * law.damping_ratio_se)
    assert law.friction_displacement >= 0.0


def test_a_record_that_starts_mid_swing():
    """A viscous decay caught 0.3 s after a turning point, its sensor's zero 5% of the swing off: the first
    turning point (t = pi / w_d after the release) becomes the release from rest, d0 the reading there, and
    the decay gives zeta and no friction. Taking the first sample as a release (the old behaviour) gives a
    first half-cycle of the wrong size and a friction that is not there."""
    zeta, period, d0, sigma = 0.0065, 2.5, 0.08, 1e-4
    offset = 0.05 * d0
    wd = 2 * math.pi / period * math.sqrt(1 - zeta**2)
    t = np.arange(0.3, 40.0, 0.01)
    rng = np.random.default_rng(3)
    x = _viscous_decay(t, d0, zeta, period) + offset + rng.normal(0.0, sigma, t.size)
    start = first_turning_point(t, x, sigma)
    t1 = math.pi / wd
    assert start.time == pytest.approx(t1, abs=0.01)
    assert start.d0 == pytest.approx(offset - d0 * math.exp(-zeta * 2 * math.pi / period * t1), abs=3 * sigma)
    assert start.t[0] == start.time and start.x[0] == start.d0 and np.all(np.diff(start.t) > 0)
    analysis = analyse_decay(t, x, noise=sigma, start_in_motion=True)
    law = analysis.law
    assert law.damping_ratio == pytest.approx(zeta, abs=max(4 * law.damping_ratio_se, 3e-4))
    assert law.rest == pytest.approx(offset, abs=5 * sigma)
    assert law.friction_displacement < 5 * law.friction_displacement_se + 1e-12
    assert any("starts in motion" in n for n in analysis.notes)
    assert law.reduced_chi2 < 2.0
    naive = analyse_decay(t, x, noise=sigma)  # the first sample taken as the release from rest
    assert naive.law.reduced_chi2 > 100 and any("misfits" in n for n in naive.notes)


#: The physical dimension (power of the length) of each law parameter: how it scales with the peaks' unit.
_LENGTH_POWER = {"ratio": 0, "damping_ratio": 0, "friction_displacement": 1, "quadratic_coefficient": -1, "kappa": 0,
                 "exponent": 0, "reference_amplitude": 1, "rest": 1}


def _noisy(law, sigma, seed):
    return _sequence(law) + np.random.default_rng(seed).normal(0.0, sigma, 13)


@pytest.mark.parametrize("law", ["quadratic", "power"])
def test_a_sensor_zero_far_away_does_not_move_the_laws(law):
    """The same noisy peaks read on a sensor whose zero lies far from the motion (a survey coordinate: 4.5e5 m, and
    a northing of -6e6 m): every law gives the parameters (the rest reading less the shift) and standard errors of
    the peaks read about 0, and the true law's own parameter is where the peaks were made (by hand, _sequence).
    The solvers' step tolerance (1e-10 |theta|) and the rest reading's difference step (sqrt(eps) |e|) were set by
    the zero's distance: at -6e6 m the power law ended 140-240 standard errors away (AIC +2.8e4), the quadratic law
    at 4.5e5 m 9e-3 of one, and the combined law's standard errors doubled. Left: the readings' rounding (9e-10 m
    at 6e6 m, 5e-5 of the noise)."""
    sigma = 2e-5
    peaks = _noisy(law, sigma, 3)
    truth = {"quadratic": ("quadratic_coefficient", 1.2), "power": ("exponent", 1.5)}[law]
    near = {f.name: f for f in decay_laws(peaks, peak_se=sigma)}
    assert near[law].parameters[truth[0]] == pytest.approx(truth[1], abs=4 * near[law].std_errors[truth[0]])
    for shift in (4.5e5, -6e6):
        far = {f.name: f for f in decay_laws(peaks + shift, peak_se=sigma)}
        assert set(far) == set(near)
        for name, a in near.items():
            b = far[name]
            for key, se in a.std_errors.items():
                if se == 0.0:  # the power law's reference amplitude: half the first swing, read off the peaks
                    continue
                moved = b.parameters[key] - (shift if key == "rest" else 0.0) - a.parameters[key]
                assert abs(moved) <= 1e-3 * se, (name, key, shift, moved / se)
                assert b.std_errors[key] == pytest.approx(se, rel=1e-3, abs=1e-300), (name, key, shift)
        for name in near:  # the laws' order and their AIC differences
            assert far[name].aic - far[law].aic == pytest.approx(near[name].aic - near[law].aic, abs=0.05), name


@pytest.mark.parametrize("law", ["quadratic", "power"])
def test_tiny_peaks_fit_as_large_ones(law):
    """The same peaks and errors times 1e-5 (a swing of 1.5 um, errors of 0.2 nm): each parameter scales with its
    dimension (mu as 1/length, the rest reading as a length, kappa and the exponent not at all) to 1e-4 of a
    standard error, and so do the standard errors (to 1e-4). In the law's own coefficients the rest reading's
    steps were measured against the coefficients (xtol 1e-10 of |theta|, about 2e-11 absolute) and its difference
    step was sqrt(eps) m, 1e-3 of the amplitude: 4e-3 standard errors and 5e-4 in the errors."""
    sigma, k = 2e-5, 1e-5
    peaks = _noisy(law, sigma, 4)
    big = {f.name: f for f in decay_laws(peaks, peak_se=sigma)}
    small = {f.name: f for f in decay_laws(peaks * k, peak_se=sigma * k)}
    for name in ("quadratic", "power"):
        a, b = big[name], small[name]
        for key, se in a.std_errors.items():
            if se == 0.0:
                continue
            unit = k ** _LENGTH_POWER[key]
            assert abs(b.parameters[key] / unit - a.parameters[key]) < 1e-4 * se, (name, key)
            assert b.std_errors[key] / unit == pytest.approx(se, rel=1e-4), (name, key)


@pytest.mark.parametrize("peaks", [[1e308, -1e308, 9e307, -8e307, 7e307], [1e-300, -1e-300, 9e-301, -8e-301, 7e-301],
                                   [2e100, -1.5e100, 1.1e100, -0.8e100], [1e-101, -1e-101, 0.9e-101, -0.8e-101]])
def test_peaks_beyond_the_representable_range_are_refused_in_one_line(peaks):
    """Readings of 1e308 m overflowed (OverflowError) and swings of 1e-300 m underflowed into a math domain error:
    both, and readings beyond +-1e100 m or swings under 1e-100 m, are refused naming the parameter and its range
    (peaks of 1e-99 and 1e99 m fit as those of 1 m: measured)."""
    from quickrelease.errors import ParameterError

    with pytest.raises(ParameterError, match=r"peaks = readings up to .* is outside readings within \+-1e\+100"):
        decay_laws(peaks)
