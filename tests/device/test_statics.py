import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from quickrelease import ParameterError, fuse_force, internal_forces, push_force, strain_energy

P = 1598e3
A0 = 0.2


def test_table_3_hand_values(paper_device):
    f = internal_forces(P, A0, paper_device)
    # hand calculation: cos 0.2 = 0.980067, tan 0.2 = 0.202710
    assert f.N1 == pytest.approx(1598e3 / (2 * 0.9800665778412416), rel=1e-15)
    assert f.N1 == pytest.approx(815.2507e3, rel=1e-7)
    assert f.N2 == pytest.approx(161.965e3, rel=1e-5)
    assert f.V2 == 799e3
    assert f.M2 == pytest.approx(1598e3 * 1.062 / 4, rel=1e-15)
    assert f.N3 == f.N4 == pytest.approx(323.931e3, rel=1e-5)


def test_fuse_force_and_push_force_are_inverse_eq_1():
    S = fuse_force(P, A0)
    assert S == pytest.approx(P * math.tan(A0), rel=1e-15)
    assert push_force(S, A0) == pytest.approx(P, rel=1e-15)
    # the paper's fuse stress: 324 kN over 531 mm^2 is ~610 MPa (a high-strength steel)
    assert S / 531e-6 == pytest.approx(610.04e6, rel=1e-4)


@given(st.floats(1e3, 1e8), st.floats(0.01, 1.5))
def test_push_force_round_trip(S, alpha0):
    assert fuse_force(push_force(S, alpha0), alpha0) == pytest.approx(S, rel=1e-12)


def test_strain_energy_terms_by_hand(paper_device):
    d = paper_device
    es = strain_energy(P, A0, d)
    N4 = P * math.tan(A0)
    assert es.axial_E4 == pytest.approx(N4**2 * 0.433 / (2 * 205970e6 * 531e-6), rel=1e-14)
    assert es.shear_E2 == pytest.approx(2 * (P / 2) ** 2 * 1.062 / (2 * 0.2 * 80000e6 * 40780e-6), rel=1e-14)
    assert es.bending_E2 == pytest.approx(2 * (P * 1.062 / 4) ** 2 * 1.062 / (6 * 205970e6 * 791175e-9), rel=1e-14)
    assert es.total == pytest.approx(2915.4186, abs=1e-4)
    assert sum(es.by_member.values()) == pytest.approx(es.total, rel=1e-15)
    assert sum(es.by_effect.values()) == pytest.approx(es.total, rel=1e-15)
    assert es.by_effect["shear"] == pytest.approx(1039.085, abs=1e-3)


@given(st.floats(1e4, 1e7), st.floats(0.05, 1.4), st.floats(1.1, 3.0))
def test_strain_energy_is_quadratic_in_P(paper_device, p, alpha0, k):
    e1 = strain_energy(p, alpha0, paper_device).total
    e2 = strain_energy(k * p, alpha0, paper_device).total
    assert e2 == pytest.approx(k**2 * e1, rel=1e-12)


@pytest.mark.parametrize("bad", [0.0, -1.0, math.pi / 2, 2.0, math.nan])
def test_bad_angle(paper_device, bad):
    with pytest.raises(ParameterError, match=r"alpha0 = .* rad is outside \(0, pi/2\)"):
        strain_energy(P, bad, paper_device)


def test_bad_force(paper_device):
    with pytest.raises(ParameterError, match=r"^P = -5 N is outside \(0, inf\)$"):
        internal_forces(-5.0, A0, paper_device)
    with pytest.raises(ParameterError, match="fuse_strength"):
        push_force(np.array([1.0, -1.0]), A0)
