"""The isolation-system fit's cost and result against the sampling rate (issue 10), on records made by the
independent event-located solve_ivp of tests/building_reference.py (never the fit's own model)."""

import math

import numpy as np
from building_reference import reference

import quickrelease.isolation_fit as isolation_fit
from quickrelease.isolation_fit import BuildingChannel, fit_isolation

M = 4.0e5  # kg
T, ZETA, FS, D0, RELEASE = 2.0, 0.04, 1.2e4, 0.15, 1.5137  # the linear + Coulomb building; release [s]
K = M * (2 * math.pi / T) ** 2
C = 2 * ZETA * math.sqrt(K * M)


def _lvdt(rate, seed=1, pre=1.5, duration=6.0):
    """The isolation layer's displacement alone (LVDT, noise 0.2 mm) at ``rate`` [Hz]."""
    t = np.arange(round((pre + duration) * rate)) / rate
    x = reference(M, K, K, math.inf, C, FS, D0, t - RELEASE)[0]
    return [BuildingChannel("lvdt", "x", t, x + np.random.default_rng(seed).normal(0.0, 2e-4, t.size))]


def test_evaluations_and_estimates_do_not_depend_on_the_sampling_rate(monkeypatch):
    """A displacement leaves its rest quadratically, so the detected release lags the true one by a time
    (here about 50 ms: 157 samples at 3200 Hz), not by a count of samples. The fit's search for the release
    reached back 50 samples only: at 800 Hz it found the release (72 model evaluations), at 3200 Hz it could
    not and settled in a wrong basin (589 evaluations, chi2/dof 101). From the decay start and from the
    truth, 4x the rows must cost at most 1.5x + 20 model evaluations (each fit's whole count, every start and
    Jacobian included), and both starts must reach the same minimum, within 4 standard errors of the truth."""
    evaluations = [0]
    free_vibration = isolation_fit.free_vibration

    def counted(*args, **kwargs):
        evaluations[0] += 1
        return free_vibration(*args, **kwargs)

    monkeypatch.setattr(isolation_fit, "free_vibration", counted)
    truth = {"period": T, "damping_ratio": ZETA, "friction": FS, "d0": D0, "release_time": RELEASE}
    cost = {}
    for rate in (800.0, 3200.0):
        channels = _lvdt(rate)
        evaluations[0] = 0
        fit = fit_isolation(channels, M, "linear", profile=False)
        cost[rate] = evaluations[0]
        good = fit_isolation(channels, M, "linear", start=truth, profile=False)
        assert fit.converged and fit.chi2_reduced < 1.3, (rate, fit.chi2_reduced, fit.warnings)
        for name, value in truth.items():
            assert abs(fit.estimates[name] - value) < 4 * fit.std_errors[name], (rate, name)
            assert abs(fit.estimates[name] - good.estimates[name]) < 0.05 * fit.std_errors[name], (rate, name)
    assert cost[3200.0] <= 1.5 * cost[800.0] + 20, cost
