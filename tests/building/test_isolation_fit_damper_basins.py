"""The isolation fit's multi-start on lead-rubber bearings with fluid viscous dampers (Bouc-Wen + power law): the
benchmark's 60 s records at 200 Hz (bench_isolators' ``boucwen-damper``), made by the independent solve_ivp
simulator of isolator_reference.py. Two failures of the starts that left the certificate at "not confirmed":

* scipy's ``xtol`` compares a step with the norm of the parameters in their own units, where the dampers'
  coefficient (3e5 N (s/m)^0.4) outweighs the period, the exponent and the rest: starts' solves ended after 6-10
  evaluations, thousands above a minimum (seed 1: every start but the hysteresis loop's);
* four starts ended in a basin with 10.6 kN of sliders' friction, 1 534 above the truth's, which has none (seed 3):
  the stick the friction causes changes the motion's pieces and no local search crosses to the face without
  sliders; the fit solves the lowest such start again with the sliders removed.
"""

import math

import isolator_reference as ref
import numpy as np
import pytest

from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation

M, D0, RELEASE, RATE, DURATION = 8e5, 0.20, 2.0137, 200.0, 60.0
NOISE = {"x": 2e-4, "v": 1e-3, "a": 0.02}
ZERO = {"x": 0.002, "v": 0.0, "a": 0.01}
KD, QD, DY, C, ALPHA = 3.5e6, 4e5, 0.025, 3e5, 0.4


def _record(seed: int):
    system = ref.boucwen(M, KD, QD, DY, 1.0, damping=C, damping_exponent=ALPHA)
    rng = np.random.default_rng(seed)
    t = np.arange(round((DURATION + 2.0) * RATE)) / RATE
    m = ref.simulate(system, D0, t - RELEASE, t_end=DURATION + 1.0)
    return [BuildingChannel(n, n, t, y + ZERO[n] + rng.normal(0.0, NOISE[n], t.size))
            for n, y in (("x", m.x), ("v", m.v), ("a", m.a))]


TRUTH = {"period": 2.0 * math.pi * math.sqrt(M / KD), "characteristic_strength": QD, "yield_displacement": DY,
         "shape": 1.0, "friction": 0.0, "damping_coefficient": C, "damping_exponent": ALPHA, "d0": D0,
         "release_time": RELEASE, "offset_x": ZERO["x"], "offset_v": ZERO["v"], "offset_a": ZERO["a"]}


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 3])
def test_the_dampers_records_minimum_is_found_and_confirmed(seed):
    channels = _record(seed)
    fit = fit_isolation(channels, M, "boucwen", damping="power", profile=False)
    truth_started = fit_isolation(channels, M, "boucwen", damping="power", profile=False, global_search=False,
                                  start=TRUTH)
    assert fit.chi2 <= truth_started.chi2 + 0.01, (fit.chi2, truth_started.chi2)
    assert fit.global_minimum_confirmed, fit.search.warnings
    best = fit.search.minima[0]
    assert len(best.starts) >= 2
    if seed == 3:  # the basin with sliders, reached by most starts, lies far above; the sliders' removal crossed
        assert fit.search.minima[1].delta_chi2 > 1000.0
        assert any(s.endswith("no sliders") for s in best.starts), best.starts
    for n in ("period", "characteristic_strength", "damping_coefficient", "damping_exponent"):
        assert abs(fit.estimates[n] - TRUTH[n]) < 4.0 * fit.std_errors[n], (n, fit.estimates[n], fit.std_errors[n])
