"""One rule of "not identified" (building.identified.parameter_identified) for the building's JSON and building
campaigns: a parameter whose profile interval runs over its whole range is listed in the JSON's ``not_identified``
(no interval), as a campaign leaves it out of its laws. Before, the JSON listed only what the fit itself marked
"not identified", and gave Constantinou's rate the interval [0, 1000] s/m as if the record bounded it.

The record comes from the independent reference simulator (tests/building/isolator_reference.py: solve_ivp with
events, no package code): a slider of constant friction mu = 1 % (1000 t, R = 2.5 m, 1 % damping) released from
0.1 m, 3 s at 20 Hz. Its friction does not change with the velocity, so Constantinou's law fitted to it finds mu_fast
at mu and cannot say how fast mu goes from mu_slow to it: the rate's profile runs from 0 to 1000 s/m. The period,
damping, d0 and mu_slow are held at the truth, so that the fit (its profiles above all) takes under a second (2.8 s
with mu_slow free, loaded machine)."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from quickrelease.building.isolation_fit import PARAMETER_BOUNDS, BuildingChannel, fit_isolation
from quickrelease.studies.building_analysis import physical_estimates
from quickrelease.studies.building_campaign import BuildingRelease, _estimates

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "building"))
import isolator_reference as ref  # noqa: E402

G = ref.GRAVITY
M, R, MU, ZETA, D0 = 1.0e6, 2.5, 0.01, 0.01, 0.1
RATE, PRE, DURATION, RELEASE, NOISE = 20.0, 1.0, 3.0, 0.0137, 2e-4  # Hz, s, s, s, m


@pytest.fixture(scope="module")
def slow_rate():
    """Constantinou's law fitted to the constant-friction record, and the record's channels."""
    t = np.arange(round((PRE + DURATION) * RATE)) / RATE - PRE
    k = M * G / R
    x = ref.simulate(ref.pendulum(M, R, MU, damping=2 * ZETA * math.sqrt(k * M)), D0, t - RELEASE).x
    channels = [BuildingChannel("x", "x", t, x + np.random.default_rng(3).normal(0.0, NOISE, t.size), noise=NOISE)]
    fit = fit_isolation(channels, M, "pendulum", release_time=RELEASE, fit_release_time=False, global_search=False,
                        start={"friction_slow": 0.007, "friction_fast": 0.02, "rate": 20.0},
                        fixed={"period": 2 * math.pi * math.sqrt(R / G), "damping_ratio": ZETA, "d0": D0,
                               "friction_slow": MU})
    return fit, channels


def test_a_rate_over_its_whole_range_is_not_identified_in_the_json_as_in_campaigns(slow_rate):
    fit, channels = slow_rate
    assert PARAMETER_BOUNDS["rate"] == (0.0, 1000.0)
    assert fit.interval_method["rate"] == "profile" and tuple(fit.ci95["rate"]) == (0.0, 1000.0)  # the premise
    lo, hi = fit.ci95["friction_fast"]
    assert lo < MU < hi and hi - lo < 0.1 * MU  # the record does bound mu_fast: listed only what it does not
    data = physical_estimates(fit)
    assert data["not_identified"] == ["rate_s_m"]
    assert data["interval_method"]["rate"] == "not identified"  # labelled as campaigns label it
    assert data["interval_method"]["friction_fast"] == fit.interval_method["friction_fast"]
    assert data["rate_s_m_ci95"] is None and data["rate_s_m"] == fit.estimates["rate"]
    assert data["friction_fast_ci95"] == [lo, hi] and data["friction_slow_ci95"] is None  # mu_slow held
    # a campaign of this one release says the same of the rate, and of mu_fast
    release = _estimates(BuildingRelease("R1", channels, d0=D0), fit, ("rate", "friction_fast"))
    assert not release.identified("rate") and release.interval_method["rate"] == "not identified"
    assert release.identified("friction_fast")
    # an interval cut by one bound alone is the likelihood's on its other side: identified (planted, [0, 500] s/m)
    from dataclasses import replace

    from quickrelease.building.identified import parameter_identified

    one_side = replace(fit, ci95={**fit.ci95, "rate": (0.0, 500.0)})
    assert parameter_identified(one_side, "rate") and physical_estimates(one_side)["not_identified"] == []
