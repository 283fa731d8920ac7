"""The 2-DOF shear building (building.TwoDOF) against independent references.

References: solve_ivp (DOP853, events, stick/slip logic written from scratch in tests/building_reference.py);
the viscous and friction dissipation integrated by that reference as extra states; the 2x2 eigenproblem
det(K - w^2 M) = 0 solved by hand (quadratic formula) with the mode shapes; the rigid 1-DOF closed form in
the limits m_s -> 0 and T_s -> 0.
"""

import math

import numpy as np
import pytest
from building_reference import reference_2dof

from quickrelease.building.model import Isolation, TwoDOF, free_vibration, free_vibration_2dof
from quickrelease.errors import ParameterError

G = 9.80665
M = 4.0e5
KEYS = (("xb", "x_b"), ("xs", "x_s"), ("vb", "v_b"), ("vs", "v_s"), ("ab", "a_b"), ("as", "a_s"))


def _reference(b, d0, t):
    return reference_2dof(b.mass, b.superstructure_mass, b.stiffness, b.damping, b.superstructure_stiffness,
                          b.superstructure_damping, b.friction, d0, t)


# (zeta, mu, T_s, zeta_s, m_s / m, d0): stick-slip with breakaways, undamped, no friction, light roof, pulled
CASES = [(0.03, 0.02, 0.5, 0.02, 0.75, 0.15), (0.0, 0.03, 0.4, 0.0, 0.75, 0.15), (0.05, 0.0, 0.6, 0.05, 0.6, 0.12),
         (0.02, 0.05, 0.8, 0.01, 0.75, -0.15)]


@pytest.mark.parametrize("zeta, mu, Ts, zs, ratio, d0", CASES)
def test_closed_form_against_solve_ivp(zeta, mu, Ts, zs, ratio, d0):
    """Base and roof displacement to 1e-9 d0, velocity and acceleration to 1e-9 of their scales
    (d0 w, d0 w^2 of the fastest mode), the time the base is held for good to 1e-9; the energy balance
    with the reference's own integrals of the viscous and friction power to 1e-8 of the initial energy."""
    b = TwoDOF(M, ratio * M, 2.0, Ts, zeta, mu * M * G, zs)
    t = np.linspace(-0.5, 8.0, 1701)
    fv = free_vibration_2dof(b, d0, t_end=8.0)
    ref, t_stop = _reference(b, d0, t)
    s = fv.states(t)
    w = 2 * math.pi / min(Ts, 2.0) * 2.5  # above the highest modal frequency
    scale = {"x": abs(d0), "v": abs(d0) * w, "a": abs(d0) * w * w}
    for r, k in KEYS:
        assert np.max(np.abs(s[k] - ref[r])) < 1e-9 * scale[k[0]], k
    if math.isfinite(t_stop):
        assert fv.stop_time == pytest.approx(t_stop, rel=1e-9)
    else:
        assert fv.stop_time == math.inf
    e = fv.energies(t[t >= 0])
    initial = 0.5 * b.stiffness * d0**2
    total = e["kinetic"] + e["stored"] + ref["viscous"][t >= 0] + ref["friction"][t >= 0]
    np.testing.assert_allclose(total, initial, rtol=0, atol=1e-8 * initial)
    own = e["kinetic"] + e["stored"] + e["viscous"] + e["friction"]
    np.testing.assert_allclose(own, e["initial"], rtol=0, atol=1e-8 * initial)


def test_stick_slip_is_exercised():
    """The first case sticks, breaks away again (the roof drags the base) and sticks for good."""
    zeta, mu, Ts, zs, ratio, d0 = CASES[0]
    fv = free_vibration_2dof(TwoDOF(M, ratio * M, 2.0, Ts, zeta, mu * M * G, zs), d0)
    ends = [p.end for p in fv.pieces]
    assert "breakaway" in ends and "reversal" in ends and math.isfinite(fv.stop_time)
    # every piece lasts: no spurious event at a piece's start (a breakaway starts with a_b = 0)
    assert min(p.t1 - p.t0 for p in fv.pieces[:-1]) > 1e-3
    for p in fv.pieces[:-1]:  # the base slides the way each piece says
        if p.kind == "slide":
            assert np.sign(fv.state(0.5 * (p.t0 + p.t1))[1]) == p.direction
    assert fv.pieces[-1].kind == "stick" and fv.rest[0] == fv.pieces[-1].xb
    tail = np.linspace(fv.stop_time, fv.stop_time + 3.0, 50)
    assert np.all(fv.state(tail)[0] == fv.rest[0])  # the base is held while the roof still rings
    assert np.ptp(fv.roof_state(tail)[0]) > 0


def test_undamped_frictionless_modes_by_hand():
    """Without friction and damping the motion is the sum of two modes: w^2 from
    m_b m_s w^4 - (m_b k_s + m_s (k + k_s)) w^2 + k k_s = 0, shapes (1, r) with r = k_s / (k_s - m_s w^2),
    amplitudes from x_b = x_s = d0 at rest."""
    m, ms, T, Ts, d0 = 5.0e5, 3.5e5, 2.2, 0.45, 0.1
    mb = m - ms
    k = m * (2 * math.pi / T) ** 2
    ks = ms * (2 * math.pi / Ts) ** 2
    A, B, C = mb * ms, -(mb * ks + ms * (k + ks)), k * ks
    w2 = [(-B - s * math.sqrt(B * B - 4 * A * C)) / (2 * A) for s in (1, -1)]
    r = [ks / (ks - ms * q) for q in w2]
    a2 = d0 * (1 - r[0]) / (r[1] - r[0])
    a1 = d0 - a2
    t = np.linspace(0, 10, 3001)
    xb = a1 * np.cos(math.sqrt(w2[0]) * t) + a2 * np.cos(math.sqrt(w2[1]) * t)
    xs = a1 * r[0] * np.cos(math.sqrt(w2[0]) * t) + a2 * r[1] * np.cos(math.sqrt(w2[1]) * t)
    fv = free_vibration(TwoDOF(m, ms, T, Ts), d0, t_end=10.0)
    np.testing.assert_allclose(fv.state(t)[0], xb, rtol=0, atol=1e-11 * d0)
    np.testing.assert_allclose(fv.roof_state(t)[0], xs, rtol=0, atol=1e-11 * d0)


@pytest.mark.parametrize("ms, Ts, tol", [(1e-8 * M, 0.5, 1e-8), pytest.param(0.7 * M, 1e-3, 1e-4, marks=pytest.mark.slow)])
def test_rigid_limits(ms, Ts, tol):
    """m_s -> 0 or T_s -> 0: the base follows the rigid model's closed form (deviations of order
    m_s / m, and of T_s / T for a stiff storey: where the base turns, the roof's ringing makes the sliders
    stick and break away again within a storey period, so the stop drifts by a fraction of T_s); turning
    points and the stop time as well. The roof follows the base only for T_s -> 0 (a massless roof on a
    flexible storey is a probe oscillator that still rings)."""
    zeta, Fs, d0 = 0.03, 0.02 * M * G, 0.15
    b = TwoDOF(M, ms, 2.0, Ts, zeta, Fs, 0.05)
    rigid = free_vibration(Isolation.linear(M, 2.0, zeta, Fs), d0)
    fv = free_vibration_2dof(b, d0)
    t = np.linspace(0, rigid.stop_time * 1.2, 801)
    assert np.max(np.abs(fv.state(t)[0] - rigid.state(t)[0])) < tol * d0
    if Ts < 0.01:
        assert np.max(np.abs(fv.roof_state(t)[0] - rigid.state(t)[0])) < tol * d0
    tp = fv.turning_points  # the stiff storey's chatter adds turns of sub-tolerance size near each peak
    major = tp[np.r_[True, np.abs(np.diff(tp)) > 10 * tol * abs(d0)]]
    assert major.size == rigid.turning_points.size
    np.testing.assert_allclose(major, rigid.turning_points, rtol=0, atol=tol * d0)
    assert fv.stop_time == pytest.approx(rigid.stop_time, rel=10 * tol)
    assert b.rigid().period == 2.0


def test_held_at_release_and_bad_input():
    b = TwoDOF(M, 0.5 * M, 2.0, 0.5, 0.05, 1.0e6)  # k d0 below F_s: nothing moves
    fv = free_vibration(b, 0.1)
    assert fv.stop_time == 0.0 and fv.rest[0] == 0.1
    assert np.all(fv.roof_state(np.linspace(0, 3, 7))[0] == 0.1)
    with pytest.raises(ParameterError, match="superstructure_mass"):
        TwoDOF(M, M, 2.0, 0.5)
    with pytest.raises(ParameterError, match="superstructure_damping_ratio"):
        TwoDOF(M, 0.5 * M, 2.0, 0.5, superstructure_damping_ratio=1.0)
    with pytest.raises(ParameterError, match="superstructure_period"):
        TwoDOF(M, 0.5 * M, 2.0, float("nan"))
    with pytest.raises(ParameterError, match="t_end"):
        free_vibration(TwoDOF(M, 0.5 * M, 2.0, 0.5), 0.1)
    with pytest.raises(ParameterError, match="d0"):
        free_vibration(TwoDOF(M, 0.5 * M, 2.0, 0.5, friction=1.0), 0.0)


@pytest.mark.parametrize("d0, valid", [(True, "finite and non-zero"), (False, "finite and non-zero"),
                                       ("0.1", "finite and non-zero"), (np.array([0.1]), "finite and non-zero"),
                                       (math.inf, "finite and non-zero"), (0.0, "finite and non-zero"),
                                       (1.0e200, "1e+300 J")])
def test_a_bad_d0_given_to_free_vibration_2dof_is_named(d0, valid):
    """free_vibration_2dof called directly checks d0 as free_vibration does (hysteretic.checked_d0): a bool (True
    was taken as 1 m), a string or an array is a ParameterError naming d0 and its valid range, and so is a push
    storing more than 1e300 J in the isolators (1e200 m ran); a 0-d array and a numpy scalar are their number."""
    b = TwoDOF(M, 0.5 * M, 2.0, 0.5, 0.05, 0.02 * M * G)
    for call in (free_vibration_2dof, free_vibration):
        with pytest.raises(ParameterError) as exc:
            call(b, d0, 5.0)
        assert exc.value.name == "d0" and valid in exc.value.valid, exc.value
    t = np.array([0.7, 3.0])
    for same in (np.array(0.1), np.float64(0.1)):
        np.testing.assert_array_equal(free_vibration_2dof(b, same, 5.0).state(t), free_vibration_2dof(b, 0.1, 5.0).state(t))
    with pytest.raises(ParameterError, match="building"):
        free_vibration_2dof(Isolation(M, 1.0e7), 0.1, 5.0)


@pytest.mark.slow
def test_matrix_exponential_fallback(monkeypatch):
    """Where the eigenvectors are ill-conditioned (near a critically damped mode) a piece is evaluated
    by the matrix exponential instead: forced here, it must still match the reference."""
    import quickrelease.building.model as building

    monkeypatch.setattr(building, "EIGEN_CONDITION", 0.0)
    b = TwoDOF(M, 0.75 * M, 2.0, 0.8, 0.02, 0.05 * M * G, 0.01)
    t = np.linspace(0.0, 1.2, 121)
    fv = free_vibration_2dof(b, 0.15, t_end=1.2)
    assert not fv.pieces[0].modal
    ref, _ = _reference(b, 0.15, t)
    assert np.max(np.abs(fv.state(t)[0] - ref["xb"])) < 1e-9 * 0.15
    assert np.max(np.abs(fv.roof_state(t)[0] - ref["xs"])) < 1e-9 * 0.15
