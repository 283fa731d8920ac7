"""The records of the coverage tests (test_isolation_coverage.py, test_hysteretic_coverage.py): the clocks, the
channels with their noise, and the binomial band of a coverage count (no package code but BuildingChannel).

Realistic records: 200 Hz, the base displacement (LVDT, noise 0.2 mm) and the acceleration on its own clock
(1.3 ms late; noise 0.02 m/s^2, sensor zero 0.01 m/s^2).
"""

import numpy as np
from scipy import stats

from quickrelease.building.isolation_fit import BuildingChannel

RATE = 200.0  # Hz
NOISE_X, NOISE_A, OFFSET_A = 2e-4, 0.02, 0.01  # m, m/s^2, m/s^2
CLOCK_LAG = 0.0013  # s: the accelerometer's own clock


def clocks(pre, duration):
    """The LVDT's and the accelerometer's sample times [s] of a record of ``pre + duration`` seconds."""
    tx = np.arange(round((pre + duration) * RATE)) / RATE
    return tx, tx + CLOCK_LAG


def noisy_channels(rows, seed):
    """The LVDT and accelerometer channels of the noise-free ``rows = (tx, x, ta, a)`` with seed's noise."""
    tx, x, ta, a = rows
    rng = np.random.default_rng(seed)
    return [BuildingChannel("lvdt", "x", tx, x + rng.normal(0.0, NOISE_X, x.size)),
            BuildingChannel("acc", "a", ta, a + OFFSET_A + rng.normal(0.0, NOISE_A, a.size))]


def binomial_band(n, p=0.95, tail=0.0005):
    """The ``tail`` to ``1 - tail`` range of Binomial(n, p): where a coverage count of n intervals falls."""
    return int(stats.binom.ppf(tail, n, p)), int(stats.binom.isf(tail, n, p))


def joint_deviation(fit, truth):
    """The fit's Mahalanobis distance from ``truth`` (a dict of some of its parameters): ``d^T C^-1 d``, d the
    estimates less the truth, C the fit's covariance of those parameters (its correlations and standard errors).
    With honest intervals it follows chi-square with ``len(truth)`` degrees of freedom whatever the correlations,
    which a count of intervals missed does not: strongly correlated parameters miss together."""
    names = list(fit.names)
    idx = [names.index(n) for n in truth]
    se = np.array([fit.std_errors[n] for n in truth])
    cov = np.asarray(fit.correlation)[np.ix_(idx, idx)] * np.outer(se, se)
    d = np.array([fit.estimates[n] - v for n, v in truth.items()])
    return float(d @ np.linalg.solve(cov, d))


def chi2_band(dof, tail=0.0005):
    """The ``tail`` to ``1 - tail`` range of chi-square with ``dof`` degrees of freedom."""
    return float(stats.chi2.ppf(tail, dof)), float(stats.chi2.isf(tail, dof))

