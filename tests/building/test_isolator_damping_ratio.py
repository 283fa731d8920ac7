"""The viscous damping ratio the Pendulum and BoucWen systems report (hysteretic.viscous_damping_ratio): the
damper's c over 2 sqrt(k2 m), k2 the post-yield stiffness (W / R of a pendulum, Kd of Bouc-Wen bearings, never
the Bouc-Wen initial stiffness Kd + Qd / dy); nan for a power-law damper. Hand calculations."""

import math

import pytest

from quickrelease.building import BoucWen, Pendulum

G = 9.80665


def test_pendulum_ratio_refers_to_w_over_r():
    m, R, c = 1.0e6, 2.5, 1.2e5
    k2 = m * G / R  # 3.92266e6 N/m
    assert Pendulum(m, R, 0.02, damping=c).damping_ratio == pytest.approx(c / (2 * math.sqrt(k2 * m)), rel=1e-12)
    assert Pendulum(m, R, 0.02, damping=c).damping_ratio == pytest.approx(0.030295, rel=1e-4)


def test_bouc_wen_ratio_refers_to_the_post_yield_stiffness():
    m, kd, qd, dy, c = 8.0e5, 1.6e6, 4.0e5, 0.025, 1.0e5
    ratio = BoucWen(m, kd, qd, dy, damping=c).damping_ratio
    assert ratio == pytest.approx(c / (2 * math.sqrt(kd * m)), rel=1e-12)  # 0.0441942
    assert ratio == pytest.approx(0.0441942, rel=1e-5)


@pytest.mark.parametrize("system", [Pendulum(1.0e6, 2.5, 0.02, damping=1.0e5, damping_exponent=0.3),
                                    BoucWen(8.0e5, 1.6e6, 4.0e5, 0.025, damping=1.0e5, damping_exponent=0.3)])
def test_a_power_law_damper_has_no_viscous_ratio(system):
    assert math.isnan(system.damping_ratio)
