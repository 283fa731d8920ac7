"""One vocabulary (issue 11): the closed-form results take ``device=`` and ``mass_model=`` like the rest of the
API; the old trailing device numbers still work with a DeprecationWarning. References are the paper's
equations written out here (Eq. 5-8, 11-12), not the package's cancellation-free forms."""

import dataclasses
import math
import warnings

import numpy as np
import pytest

import quickrelease as qr
from quickrelease.device import dynamics

#: A device unlike the paper's: other bar length and masses (its other members do not enter these results).
OTHER = dataclasses.replace(qr.preset("paper"), L1=3.1, m1=812.0, m2=377.0, name="other")
E_S, A0, F1, F2 = 2900.0, 0.2, 419.85, 804.57


def eq8_alpha_final(E, a0, f1, f2, L1):
    """Eq. 8 solved as written: W_F(alpha) = R (sin(alpha - phi) - sin(alpha0 - phi)) = E_S."""
    A, B = 2 * f1 * L1, 4 * f2 * L1
    R, phi = math.hypot(A, B), math.atan2(B, A)
    return phi + math.asin(math.sin(a0 - phi) + E / R)


@pytest.mark.parametrize("device", [None, OTHER])
def test_device_keyword_against_the_equations(device):
    d = device or qr.preset("paper")
    assert qr.final_angle(E_S, A0, F1, F2, device=device) == pytest.approx(
        eq8_alpha_final(E_S, A0, F1, F2, d.L1), rel=1e-12)
    aF = 0.7378
    limits = qr.friction_limits(E_S, A0, aF, device=device)
    assert all(type(v) is float for v in limits.values())  # plain floats for scalar inputs (a readable repr)
    assert limits["F1_max"] == pytest.approx(E_S / (2 * d.L1 * (math.sin(aF) - math.sin(A0))), rel=1e-12)  # Eq. 11
    assert limits["F2_max"] == pytest.approx(E_S / (4 * d.L1 * (math.cos(A0) - math.cos(aF))), rel=1e-12)  # Eq. 12
    for model, c in (("distributed", 2 / 3), ("lumped", 1.0), (0.8, 0.8)):
        mass = d.m2 * d.L1**2 * (c * d.m1 / d.m2 + math.sin(A0) ** 2)  # Eq. 5
        assert qr.initial_rate(E_S, A0, device=device, mass_model=model) == pytest.approx(
            math.sqrt(E_S / mass), rel=1e-12)  # Eq. 6
        assert qr.kinetic_energy(A0, 1.3, device=device, mass_model=model) == pytest.approx(mass * 1.3**2, rel=1e-12)
        num = -(1.3**2) * math.sin(A0) * math.cos(A0) - (2 * F2 * math.sin(A0) + F1 * math.cos(A0)) / (d.m2 * d.L1)
        assert qr.angular_acceleration(A0, 1.3, F1, F2, device=device, mass_model=model) == pytest.approx(
            num / (c * d.m1 / d.m2 + math.sin(A0) ** 2), rel=1e-12)  # Eq. 3/4
    W = 2 * F1 * d.L1 * (math.sin(0.5) - math.sin(A0)) + 4 * F2 * d.L1 * (math.cos(A0) - math.cos(0.5))  # Eq. 7
    assert qr.dissipated_energy(0.5, A0, F1, F2, device=device) == pytest.approx(W, rel=1e-12)
    flat = 2 * F1 * d.L1 * (1 - math.sin(A0)) + 4 * F2 * d.L1 * math.cos(A0)
    assert bool(qr.reaches_geometric_limit(1.01 * flat, A0, F1, F2, device=device))
    assert not bool(qr.reaches_geometric_limit(0.99 * flat, A0, F1, F2, device=device))


def test_the_default_device_is_the_papers():
    assert qr.final_angle(E_S, A0, F1, F2) == qr.final_angle(E_S, A0, F1, F2, device=qr.preset("paper"))
    assert qr.final_angle(E_S, A0, F1, F2) == pytest.approx(0.7378, abs=5e-5)  # Table 7: alpha_F = 0.7378 rad


def test_old_signatures_warn_and_agree():
    d = OTHER
    cases = [
        (qr.final_angle, (E_S, A0, F1, F2), (d.L1,), {}),
        (qr.friction_limits, (E_S, A0, 0.7378), (d.L1,), {}),
        (qr.dissipated_energy, (0.5, A0, F1, F2), (d.L1,), {}),
        (qr.reaches_geometric_limit, (E_S, A0, F1, F2), (d.L1,), {}),
        (qr.initial_rate, (E_S, A0), (d.m1, d.m2, d.L1, 1.0), {"mass_model": "lumped"}),
        (qr.kinetic_energy, (A0, 1.3), (d.m1, d.m2, d.L1, 2 / 3), {}),
        (qr.angular_acceleration, (A0, 1.3, F1, F2), (d.m1, d.m2, d.L1, 2 / 3), {}),
    ]
    for func, args, old, new in cases:
        with pytest.warns(DeprecationWarning, match=rf"{func.__name__}\(\.\.\., .*device=") as record:
            before = func(*args, *old)
        assert record[0].filename == __file__  # the warning points at the caller's line
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            after = func(*args, device=d, **new)
        assert after == before, func.__name__
    with pytest.warns(DeprecationWarning, match=r"final_angle\(E_S=\.\.\.\) is now"):
        assert qr.final_angle(E_S=E_S, alpha0=A0, F1=F1, F2=F2) == qr.final_angle(E_S, A0, F1, F2)


def test_bad_mixtures_are_type_errors():
    with pytest.raises(TypeError, match="device twice"):
        qr.final_angle(E_S, A0, F1, F2, 2.477, device=OTHER)
    with pytest.raises(TypeError, match="device="):
        qr.kinetic_energy(A0, 1.3, 576.78, 531.69)


def test_physics_layer_keeps_floats_and_arrays():
    """dynamics stays on the device's numbers (DESIGN.md); the public names broadcast arrays like it."""
    a = np.array([0.3, 0.5, 0.7])
    d = qr.preset("paper")
    np.testing.assert_array_equal(qr.kinetic_energy(a, 1.0), dynamics.kinetic_energy(a, 1.0, d.m1, d.m2, d.L1, 2 / 3))
    assert qr.final_angle is not dynamics.final_angle
    assert qr.dissipated_energy(0.5, "11.46 deg", "0.42 kN", F2) == pytest.approx(
        qr.dissipated_energy(0.5, math.radians(11.46), 420.0, F2), rel=1e-12)
