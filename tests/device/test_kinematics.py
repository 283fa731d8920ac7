import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from quickrelease.device import kinematics as k

L1 = 2.477


@given(st.floats(0.01, 1.5), st.floats(0.0, 1.0))
def test_table_4_displacements(alpha0, frac):
    alpha = alpha0 + frac * (np.pi / 2 - alpha0)
    assert k.retraction(alpha, alpha0, L1) == pytest.approx(L1 * (np.cos(alpha0) - np.cos(alpha)), abs=1e-14)
    assert k.opening(alpha, alpha0, L1) == pytest.approx(L1 * (np.sin(alpha) - np.sin(alpha0)), abs=1e-14)


def test_rates_are_time_derivatives():
    # alpha(t) = 0.2 + 0.5 t + 0.3 t^2 (any smooth motion), checked by central differences
    t = np.linspace(0.1, 0.9, 9)
    h = 1e-5

    def alpha(t):
        return 0.2 + 0.5 * t + 0.3 * t**2

    ad, add = 0.5 + 0.6 * t, 0.6 + 0 * t
    for disp, rate, acc in [(k.retraction, k.retraction_rate, k.retraction_acceleration),
                            (k.opening, k.opening_rate, k.opening_acceleration)]:
        fd1 = (disp(alpha(t + h), 0.2, L1) - disp(alpha(t - h), 0.2, L1)) / (2 * h)
        fd2 = (disp(alpha(t + h), 0.2, L1) - 2 * disp(alpha(t), 0.2, L1) + disp(alpha(t - h), 0.2, L1)) / h**2
        np.testing.assert_allclose(rate(alpha(t), ad, L1), fd1, rtol=1e-8)
        np.testing.assert_allclose(acc(alpha(t), ad, add, L1), fd2, rtol=1e-4)


def test_section_kinematics_table_5_ends():
    s = k.section_kinematics(np.array([0.0, L1 / 2, L1]), 0.6, 1.1, -2.0, 0.2, L1)
    u, v = k.retraction(0.6, 0.2, L1), k.opening(0.6, 0.2, L1)
    np.testing.assert_allclose(s["x"], [0.0, u / 2, u])
    np.testing.assert_allclose(s["y"], [v, v / 2, 0.0])
    assert s["x_dot"][2] == pytest.approx(k.retraction_rate(0.6, 1.1, L1))
    assert s["y_ddot"][0] == pytest.approx(k.opening_acceleration(0.6, 1.1, -2.0, L1))
