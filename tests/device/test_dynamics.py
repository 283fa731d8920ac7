import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from quickrelease import ParameterError
from quickrelease.device import dynamics

m1, m2, L1 = 576.78, 531.69, 2.477


@pytest.mark.parametrize("model,c", [("distributed", 2 / 3), ("lumped", 1.0), ("Lumped", 1.0), (0.7, 0.7),
                                     ("0.5", 0.5), ("2/3", 2 / 3)])
def test_mass_factor(model, c):
    assert dynamics.mass_factor(model) == pytest.approx(c, rel=1e-15)


@pytest.mark.parametrize("model", ["heavy", -1.0, 0.0, "1/0", None])
def test_bad_mass_model(model):
    with pytest.raises(ParameterError, match="mass"):
        dynamics.mass_factor(model)


@given(st.floats(0.05, 1.5), st.floats(0.01, 5.0), st.floats(0.0, 5e3), st.floats(0.0, 5e3),
       st.sampled_from([1.0, 2 / 3, 0.4]))
def test_equation_of_motion_conserves_energy(alpha, alpha_dot, F1, F2, c):
    """d/dt (E_K + W_F) = 0 along Eq. 3/4: the equation is the Lagrange equation of Eq. 5 and Eq. 7."""
    add = dynamics.angular_acceleration(alpha, alpha_dot, F1, F2, m1, m2, L1, c)
    Mass = dynamics.generalized_mass(alpha, m1, m2, L1, c)
    dM = m2 * L1**2 * 2 * math.sin(alpha) * math.cos(alpha)
    dEK = dM * alpha_dot**3 + 2 * Mass * alpha_dot * add
    dW = (2 * F1 * L1 * math.cos(alpha) + 4 * F2 * L1 * math.sin(alpha)) * alpha_dot
    scale = abs(dM * alpha_dot**3) + abs(dW) + 1e-30
    assert abs(dEK + dW) <= 1e-12 * scale


def test_at_rest_acceleration_is_zero():
    assert dynamics.angular_acceleration(0.7, 0.0, 400.0, 800.0, m1, m2, L1, 2 / 3) == 0.0


def test_lumped_and_distributed_equations_3_and_4():
    a, ad, F1, F2 = 0.5, 1.2, 400.0, 800.0
    for c, text in [(1.0, "Eq. 3"), (2 / 3, "Eq. 4")]:
        d = c * m1 / m2 + math.sin(a) ** 2
        expected = -ad**2 * math.sin(a) * math.cos(a) / d - (2 * F2 * math.sin(a) + F1 * math.cos(a)) / (m2 * L1 * d)
        assert dynamics.angular_acceleration(a, ad, F1, F2, m1, m2, L1, c) == pytest.approx(expected, rel=1e-14), text


def test_initial_rate_eq_6():
    ad0 = dynamics.initial_rate(2900.0, 0.2, m1, m2, L1, 2 / 3)
    assert dynamics.kinetic_energy(0.2, ad0, m1, m2, L1, 2 / 3) == pytest.approx(2900.0, rel=1e-15)
    assert ad0 == pytest.approx(math.sqrt(2900 / (m2 * L1**2 * (2 / 3 * m1 / m2 + math.sin(0.2) ** 2))), rel=1e-15)


@given(st.floats(0.05, 1.5), st.floats(0.0, 1.0))
def test_dissipated_energy_eq_7(alpha0, frac):
    alpha = alpha0 + frac * (math.pi / 2 - alpha0)
    direct = 2 * 400 * L1 * (math.sin(alpha) - math.sin(alpha0)) + 4 * 800 * L1 * (math.cos(alpha0) - math.cos(alpha))
    assert dynamics.dissipated_energy(alpha, alpha0, 400.0, 800.0, L1) == pytest.approx(direct, abs=1e-10)


@given(st.floats(10.0, 1e4), st.floats(0.05, 1.4), st.floats(0.0, 5e3), st.floats(0.0, 5e3))
def test_final_angle_solves_eq_8(E_S, alpha0, F1, F2):
    assume(F1 + F2 > 1.0)
    aF = dynamics.final_angle(E_S, alpha0, F1, F2, L1)
    assert alpha0 < aF <= math.pi / 2
    W = dynamics.dissipated_energy(aF, alpha0, F1, F2, L1)
    if dynamics.reaches_geometric_limit(E_S, alpha0, F1, F2, L1):
        assert aF == math.pi / 2 and W < E_S
    else:
        # Eq. 8 to rounding: the derivative of W_F bounds the error in alpha_F
        assert W == pytest.approx(E_S, rel=1e-11, abs=1e-9 * (F1 + F2) * L1)


def test_final_angle_paper_identified_pair():
    # (F1, F2) from Eq. 13 with printed E_S = 2900 J stop exactly at alpha_F = 0.7378 (Eq. 8)
    lim = dynamics.friction_limits(2900.0, 0.2, 0.7378, L1)
    F1 = 0.34 * lim["F1_max"]
    F2 = lim["F2_max"] * (1 - F1 / lim["F1_max"])
    assert dynamics.final_angle(2900.0, 0.2, F1, F2, L1) == pytest.approx(0.7378, rel=1e-14)
    assert lim["F1_max"] == pytest.approx(2900 / (2 * L1 * (math.sin(0.7378) - math.sin(0.2))), rel=1e-14)
    assert lim["F2_max"] == pytest.approx(2900 / (4 * L1 * (math.cos(0.2) - math.cos(0.7378))), rel=1e-14)


def test_no_friction_reaches_geometric_limit():
    assert dynamics.reaches_geometric_limit(100.0, 0.2, 0.0, 0.0, L1)
    assert dynamics.final_angle(100.0, 0.2, 0.0, 0.0, L1) == math.pi / 2


def test_remaining_energy_is_cancellation_free():
    F1, F2, a0 = 400.0, 800.0, 0.2
    aF = dynamics.final_angle(2900.0, a0, F1, F2, L1)
    alpha = aF - np.array([1e-3, 1e-6, 1e-9, 1e-12])
    eps = aF - alpha  # exact (Sterbenz): the distance actually represented
    rem = dynamics.remaining_energy(alpha, aF, F1, F2, L1)
    slope = 2 * F1 * L1 * math.cos(aF) + 4 * F2 * L1 * math.sin(aF)  # dW_F/dalpha at alpha_F
    np.testing.assert_allclose(rem / eps, slope, rtol=2e-3)
    np.testing.assert_allclose(rem[1:] / eps[1:], slope, rtol=1e-6)
    # the naive difference E_S - W_F(alpha) loses 4 to 5 digits at 1e-12 from the stop
    naive = 2900.0 - dynamics.dissipated_energy(alpha[-1], a0, F1, F2, L1)
    assert abs(naive / eps[-1] / slope - 1) > 1e-6
