"""The isolated building's free vibration (building.py) against independent references.

References: solve_ivp (DOP853, events) on the equation of motion written here from scratch; the
textbook decay laws of Coulomb and viscous damping; quadrature of c v^2 for the viscous dissipation.
"""

import math

import numpy as np
import pytest
from building_reference import reference as _reference
from scipy.integrate import quad

from quickrelease.building.model import Isolation, free_vibration, pushed_state
from quickrelease.errors import ParameterError

G = 9.80665


@pytest.mark.parametrize("zeta, mu", [(0.0, 0.02), (0.03, 0.015), (0.08, 0.0), (0.0, 0.0)])
def test_linear_coulomb_against_solve_ivp(zeta, mu):
    m, T, d0 = 4.0e5, 2.0, 0.15
    iso = Isolation.linear(m, T, zeta, mu * m * G)
    t = np.linspace(0.0, 9.0, 1801)
    fv = free_vibration(iso, d0, t_end=9.0)
    ref, t_stop = _reference(m, iso.stiffness, iso.stiffness, math.inf, iso.damping, iso.friction, d0, t)
    x = fv.state(t)[0]
    assert np.max(np.abs(x - ref)) < 1e-9 * d0
    if math.isfinite(t_stop):
        assert fv.stop_time == pytest.approx(t_stop, rel=1e-9)


@pytest.mark.parametrize("model", ["linear", "bilinear"])
def test_every_sample_inside_the_motion_against_solve_ivp(model):
    """x, v and the acceleration where every sample lies on the moving pieces of one kind (after the release,
    before the stick; a bilinear layer that never yields): the evaluation without gathers, against the independent
    solve_ivp simulator."""
    import isolator_reference as ref

    m, k, c, Fs = 4.0e5, 4.0e6, 4.0e4, 8.0e3
    if model == "linear":
        iso, system, d0 = Isolation(m, k, c, Fs), ref.linear(m, k, c, friction=Fs), 0.15
    else:  # F_y far above what d0 = 2 cm pushes: every piece elastic
        iso, system, d0 = Isolation(m, k, c, Fs, 0.1 * k, 1.0e6), ref.bilinear(m, k, 0.1 * k, 1.0e6, c, friction=Fs), 0.02
    fv = free_vibration(iso, d0, t_end=3.0)
    t = np.linspace(0.01, 2.0, 400)
    assert fv.stop_time > 2.0
    x, v, a = fv.state(t)
    want = ref.simulate(system, d0, t, t_end=3.0)
    scale = abs(d0) * k / m
    assert np.max(np.abs(x - want.x)) < 1e-8 * abs(d0)
    assert np.max(np.abs(v - want.v)) < 1e-8 * abs(d0) * math.sqrt(k / m)
    assert np.max(np.abs(a - want.a)) < 1e-8 * scale


@pytest.mark.parametrize("zeta, Fs, d0", [(0.05, 2.0e4, 0.15), (0.0, 0.0, 0.2), (0.1, 5.0e4, -0.12),
                                          (0.02, 1.0e4, 0.01), (0.5, 2.0e4, 0.15)])
def test_bilinear_against_solve_ivp(zeta, Fs, d0):
    """zeta = 0.5 of k1: the yielding pieces (k2 = k1 / 10) are overdamped (cosh and sinh)."""
    m, k1, k2, Fy = 4.0e5, 4.0e7, 4.0e6, 8.0e4
    iso = Isolation.bilinear(m, k1, k2, Fy, zeta, Fs)
    t = np.linspace(0.0, 4.0, 1601)
    fv = free_vibration(iso, d0, t_end=4.0)
    ref, _ = _reference(m, k1, k2, iso.plastic_yield, iso.damping, Fs, d0, t)
    assert np.max(np.abs(fv.state(t)[0] - ref)) < 1e-9 * abs(d0)


@pytest.mark.parametrize("q", [75.0, -15.0, 0.0])
def test_a_piece_at_one_time_is_its_state_there_bit_for_bit(q):
    """_Piece.at (floats, the hot path of free_vibration's piece ends) is _Piece.state's arithmetic (0-d arrays)
    exactly, for an underdamped (q > 0), overdamped (q < 0) and critically damped (q = 0) piece."""
    from quickrelease.building.model import _Piece

    a = 5.0
    piece = _Piece(t0=0.37, x0=0.15, v0=-0.8, z0=0.0, direction=-1.0, yielding=False, k=4.0e7, x_eq=-0.002, a=a,
                   b=q + a * a, q=q)
    for t in np.linspace(0.37, 9.0, 401):
        x, v = piece.state(float(t))
        assert piece.at(float(t)) == (float(x), float(v)), t


def test_coulomb_decay_law():
    """Without viscous damping the amplitude falls by 4 F_s / k per cycle, and the half-period is pi / w."""
    m, T, Fs, d0 = 3.0e5, 2.2, 1.5e4, 0.18
    iso = Isolation.linear(m, T, 0.0, Fs)
    fv = free_vibration(iso, d0)
    k = m * (2 * math.pi / T) ** 2
    peaks = fv.turning_points  # signed: each half-cycle is centred on x_eq = sign(x_n) F_s / k
    n = peaks.size - 1
    assert n == math.floor((d0 - Fs / k) / (2 * Fs / k)) + 1  # half-cycles until |x_n| <= F_s / k
    np.testing.assert_allclose(peaks[:-1] + peaks[1:], 2 * Fs / k * np.sign(peaks[:-1]), rtol=1e-12)
    assert np.all(np.abs(peaks[:-1]) > Fs / k)
    np.testing.assert_allclose(np.diff(fv.reversal_times), T / 2, rtol=1e-12)
    assert abs(fv.rest[0]) <= Fs / k


def test_viscous_logarithmic_decrement():
    """Without friction ln(x_n / x_{n+1}) over a cycle is 2 pi zeta / sqrt(1 - zeta^2), with period T_d."""
    zeta, T = 0.07, 1.8
    iso = Isolation.linear(2.0e5, T, zeta, 0.0)
    fv = free_vibration(iso, 0.1, t_end=20.0)
    peaks = fv.turning_points
    decrement = np.log(peaks[:-2] / peaks[2:])
    np.testing.assert_allclose(decrement, 2 * math.pi * zeta / math.sqrt(1 - zeta**2), rtol=1e-11)
    np.testing.assert_allclose(np.diff(fv.reversal_times), T / 2 / math.sqrt(1 - zeta**2), rtol=1e-12)


@pytest.mark.parametrize("model", ["linear", "bilinear"])
def test_energy_balance_with_viscous_quadrature(model):
    """kinetic + springs + hysteresis + friction + viscous = stored at release, the viscous term from the
    quadrature of c v^2 (not from the pieces' invariants)."""
    m = 4.0e5
    iso = (Isolation.linear(m, 2.0, 0.05, 1.0e4) if model == "linear"
           else Isolation.bilinear(m, 4.0e7, 4.0e6, 8.0e4, 0.05, 1.0e4))
    fv = free_vibration(iso, 0.15)
    e = fv.energies(np.linspace(0, fv.stop_time * 1.05, 23))
    pieces = [(p.t0, p.t1) for p in fv.pieces]  # v is smooth inside a piece: integrate piece by piece
    times = np.linspace(0, fv.stop_time * 1.05, 23)
    viscous = np.array([sum(quad(lambda s: iso.damping * fv.state(s)[1] ** 2, a, min(b, tt), epsabs=0,
                                 epsrel=1e-13, limit=200)[0] for a, b in pieces if a < tt)
                        for tt in times])
    total = e["kinetic"] + e["stored"] + e["hysteretic"] + e["friction"] + viscous
    np.testing.assert_allclose(total, e["initial"], rtol=1e-8)
    np.testing.assert_allclose(viscous, e["viscous"], rtol=1e-8, atol=1e-8 * e["initial"][0])


def test_bilinear_hand_calculation_of_the_first_yield():
    """Undamped, frictionless bilinear from the pushed state: unloading is elastic with k1 about
    x_c = d0 - R0 / k1, so the element reaches -fp after x drops by (z0 + fp) / (k1 - k2): in closed form
    the time is acos(1 - dx / (d0 - x_c)) / w1."""
    m, k1, k2, Fy, d0 = 1.0e5, 2.0e7, 2.0e6, 4.0e4, 0.1
    iso = Isolation.bilinear(m, k1, k2, Fy)
    fp = Fy * (1 - k2 / k1)
    R0 = k2 * d0 + fp
    amplitude = R0 / k1
    dx = 2 * fp / (k1 - k2)
    t_yield = math.acos(1 - dx / amplitude) / math.sqrt(k1 / m)
    fv = free_vibration(iso, d0, t_end=1.0)
    assert fv.pieces[0].end == "yield"
    assert fv.pieces[0].t1 == pytest.approx(t_yield, rel=1e-13)
    assert pushed_state(iso, d0)[1] == pytest.approx(R0, rel=1e-15)


def test_held_by_friction_and_bad_input():
    iso = Isolation.linear(1.0e5, 2.0, 0.0, 1.0e6)
    fv = free_vibration(iso, 0.1)
    assert fv.stop_time == 0.0 and fv.rest[0] == 0.1
    with pytest.raises(ParameterError, match="t_end"):
        free_vibration(Isolation.linear(1.0e5, 2.0, 0.05, 0.0), 0.1)
    with pytest.raises(ParameterError, match="post_yield_stiffness"):
        Isolation.bilinear(1.0e5, 2.0e7, 3.0e7, 1.0e4)
    with pytest.raises(ParameterError, match="damping_ratio"):
        Isolation.linear(1.0e5, 2.0, 1.0)
    with pytest.raises(ParameterError, match="period"):
        Isolation.linear(1.0e5, float("nan"))
    with pytest.raises(ParameterError, match="d0"):
        free_vibration(Isolation.linear(1.0e5, 2.0, 0.0, 1.0), float("inf"))
    for bad in (True, "0.1", np.array([0.1])):  # pushed_state called directly: True was 1 m
        with pytest.raises(ParameterError, match="d0"):
            pushed_state(Isolation.linear(1.0e5, 2.0, 0.0, 1.0), bad)


@pytest.mark.parametrize("t_end", [float("nan"), float("inf"), -1.0, 0.0])
def test_a_horizon_that_is_not_a_finite_positive_time_is_refused(t_end):
    """For the one-mass layer and the 2dof building alike (building.model._horizon)."""
    from quickrelease.building.model import TwoDOF

    with pytest.raises(ParameterError, match="t_end"):
        free_vibration(Isolation.linear(1.0e5, 2.0, 0.05, 1.0e3), 0.1, t_end=t_end)
    with pytest.raises(ParameterError, match="t_end"):
        free_vibration(TwoDOF(1.0e6, 0.5e6, 2.0, 0.5, friction=1.0e3), 0.1, t_end=t_end)
