"""The isolation's design described for a person: the synthetic truth (studies.synth.describe_truth, text) and the
planned building (the report's HTML), both from report.display.describe_isolation. The texts are pinned here,
each value worked by hand from the inputs (1.6e6 N/m = 1600 kN/m; dy 0.025 m = 25 mm; friction 0.002 x 8e5 kg x
9.80665 m/s^2 = 15.691 kN; a bilinear k1 = 40 MN/m under 800 t: T = 2 pi sqrt(8e5 / 4e7) = 0.888577 s)."""

import pytest

from quickrelease.io.case import BuildingSpec
from quickrelease.report.html import _building_design
from quickrelease.studies.synth import describe_truth

PEND = dict(model="pendulum", radius_m=2.5, period_s=3.1716, friction_N=0.0)
BW = dict(model="boucwen", Kd_N_m=1.6e6, period_s=4.4429, Qd_N=4e5, dy_m=0.025, shape=1.0)
POWER = dict(damping_coefficient=2e5, damping_exponent=0.5)


@pytest.mark.parametrize("truth, text", [
    ({**PEND, "friction_slow": 0.02, "friction_fast": 0.06, "rate_s_m": 30.0, "damping_ratio": 0.01},
     "R = 2.5 m (T = 3.1716 s), friction mu = 0.02 to 0.06 (rate 30 s/m), zeta = 0.01"),
    ({**PEND, "friction_slow": 0.04, "friction_fast": 0.04, "rate_s_m": 0.0, **POWER},
     "R = 2.5 m (T = 3.1716 s), friction mu = 0.04 (constant), dampers C = 200 kN (s/m)^alpha, "
     "alpha = 0.5"),  # a constant-friction case's truth (rate 0): one mu, as the planned spec's text below
    ({**PEND, "friction_slow": 0.02, "friction_fast": 0.06, "rate_s_m": 0.0, "damping_ratio": 0.01},
     "R = 2.5 m (T = 3.1716 s), friction mu = 0.02 (constant), zeta = 0.01"),  # rate 0: mu(v) is mu_slow
    ({**BW, "damping_ratio": 0.02, "friction_N": 0.0},
     "Kd = 1600 kN/m (T = 4.4429 s), Qd = 400 kN, dy = 0.025 m, n = 1, zeta = 0.02, F_s = 0 N"),
    ({**BW, **POWER, "friction_N": 1.5e4},
     "Kd = 1600 kN/m (T = 4.4429 s), Qd = 400 kN, dy = 0.025 m, n = 1, dampers C = 200 kN (s/m)^alpha, "
     "alpha = 0.5, F_s = 15 kN"),
    (dict(model="linear", period_s=2.0, damping_ratio=0.05, friction_N=1.57e5), "T = 2 s, zeta = 0.05, F_s = 157 kN"),
    (dict(model="bilinear", period_s=1.2, damping_ratio=0.05, friction_N=0.0), "T = 1.2 s, zeta = 0.05, F_s = 0 N"),
    (dict(model="linear", period_s=2.5, damping_coefficient=3e5, damping_exponent=0.3, friction_N=2e4),
     "T = 2.5 s, dampers C = 300 kN (s/m)^alpha, alpha = 0.3, F_s = 20 kN"),
])
def test_the_synthetic_truth_in_its_models_terms(truth, text):
    assert describe_truth(truth) == text


LR = dict(model="boucwen", mass=8e5, post_yield_stiffness=1.6e6, characteristic_strength=4e5,
          yield_displacement=0.025)


@pytest.mark.parametrize("spec, period, text", [
    (BuildingSpec(model="pendulum", mass=1e6, radius=2.5, friction_slow=0.02, friction_fast=0.06, rate=30.0,
                  damping_ratio=0.01), 3.1716,
     "R = 2.5 m (T = 2π√(R/g) = 3.1716 s), friction 0.02 to 0.06 (rate 30 s/m) of the weight, ζ = 0.01"),
    (BuildingSpec(model="pendulum", mass=1e6, radius=2.5, friction_slow=0.04, damping="power", **POWER), 3.1716,
     "R = 2.5 m (T = 2π√(R/g) = 3.1716 s), friction 0.04 of the weight, dampers C = 200 kN (s/m)<sup>α</sup>, "
     "α = 0.5"),
    (BuildingSpec(model="pendulum", mass=1e6, radius=2.5, friction_slow=0.02, friction_fast=0.06, rate=0.0), 3.1716,
     "R = 2.5 m (T = 2π√(R/g) = 3.1716 s), friction 0.02 of the weight, ζ = 0"),  # rate 0: mu is mu_slow
    (BuildingSpec(**LR, damping_ratio=0.02), 4.4429,
     "K<sub>d</sub> = 1600 kN/m (T = 4.4429 s), Q<sub>d</sub> = 400 kN, d<sub>y</sub> = 25 mm, n = 1, ζ = 0.02, "
     "isolator friction 0 kN"),
    (BuildingSpec(**LR, shape=2.0, damping="power", **POWER, friction_coefficient=0.002), 4.4429,
     "K<sub>d</sub> = 1600 kN/m (T = 4.4429 s), Q<sub>d</sub> = 400 kN, d<sub>y</sub> = 25 mm, n = 2, dampers "
     "C = 200 kN (s/m)<sup>α</sup>, α = 0.5, isolator friction 15.691 kN"),
    (BuildingSpec(model="linear", mass=8e5, period=2.0, damping_ratio=0.05, friction=1.57e5), 2.0,
     "T = 2 s, ζ = 0.05, isolator friction 157 kN"),
    (BuildingSpec(model="bilinear", mass=8e5, k1=4e7, k2=4e6, yield_force=1.2e5, damping_ratio=0.05), 9.9,
     "T = 0.888577 s, ζ = 0.05, isolator friction 0 kN"),  # the initial period, not the one passed
])
def test_the_planned_building_in_its_models_terms(spec, period, text):
    assert _building_design(spec, period) == text
