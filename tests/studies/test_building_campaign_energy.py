"""The equivalent damping of the new isolation systems in building campaigns (building_campaign.py, issue 24): the
energy per harmonic cycle of a power-law damper, of a friction pendulum's Constantinou friction and of a Bouc-Wen
loop, each against a loop integrated here step by step (or a textbook closed form), never the package's model."""

import math

import numpy as np
import pytest

from quickrelease.studies.building_campaign import (
    boucwen_cycle,
    damper_energy,
    derived_quantity,
    pendulum_friction_energy,
)

G = 9.80665


def _harmonic(d, omega, n=400_000):
    """Midpoints of one cycle x = d cos(omega t): x, v and the steps dx."""
    theta = (np.arange(n) + 0.5) * (2 * math.pi / n)
    x = d * np.cos(theta)
    v = -d * omega * np.sin(theta)
    dx = v * (2 * math.pi / n) / omega
    return x, v, dx


def _damper_loop(C, alpha, d, omega):
    _, v, dx = _harmonic(d, omega)
    return float(np.sum(C * np.abs(v) ** alpha * np.sign(v) * dx))


@pytest.mark.parametrize("alpha", [0.05, 0.3, 1.0, 1.7, 2.0])
def test_damper_energy_against_a_loop_and_the_textbook(alpha):
    """FEMA 274's form lambda = 2^(2 + alpha) Gamma(1 + alpha / 2)^2 / Gamma(2 + alpha), and the loop itself."""
    C, d, omega = 2.0e5, 0.17, 2.3
    lam = 2 ** (2 + alpha) * math.gamma(1 + alpha / 2) ** 2 / math.gamma(2 + alpha)
    assert damper_energy(C, alpha, d, omega) == pytest.approx(lam * C * d ** (1 + alpha) * omega**alpha, rel=1e-12)
    assert damper_energy(C, alpha, d, omega) == pytest.approx(_damper_loop(C, alpha, d, omega), rel=1e-6)
    if alpha == 1.0:
        assert damper_energy(C, 1.0, d, omega) == pytest.approx(math.pi * C * omega * d * d, rel=1e-14)


@pytest.mark.parametrize("rate", [0.0, 3.0, 30.0, 1000.0])
def test_pendulum_friction_energy_against_a_loop(rate):
    """mu(|v|) W |v| summed over the cycle's steps (400 000 of them: the boundary layer of a = 1000 s/m at v = 0
    is 0.5 mm/s wide); constant friction: 4 mu W d."""
    W, slow, fast, d, omega = 9.8e6, 0.02, 0.06, 0.15, 2.0
    _, v, dx = _harmonic(d, omega)
    mu = fast - (fast - slow) * np.exp(-rate * np.abs(v))
    loop = float(np.sum(mu * W * np.sign(v) * dx))
    assert pendulum_friction_energy(W, slow, fast, rate, d, omega) == pytest.approx(loop, rel=2e-6)
    if rate == 0.0:
        assert pendulum_friction_energy(W, slow, fast, 0.0, d, omega) == pytest.approx(4 * slow * W * d, rel=1e-14)


def _boucwen_loop(n, dy, d, steps=2000):
    """The steady loop of the Bouc-Wen element (beta = gamma = 1/2) between -d and +d: the half-cycle from x = d
    down to -d, dz/dx = (1 - |z|^n (sign(dx z) / 2 + 1 / 2)) / dy stepped by RK4 in x from z_m, must end at -z_m
    (the up half is its image); z_m found by brentq. Returns z_m and the loop integral of z dx (twice the down
    half's, by the symmetry)."""
    from scipy.optimize import brentq

    h = -2 * d / steps

    def rate(z):
        return (1.0 - abs(z) ** n * (0.5 * math.copysign(1.0, -z) + 0.5)) / dy

    def down(z):
        area = 0.0
        for _ in range(steps):
            k1 = rate(z)
            k2 = rate(z + 0.5 * h * k1)
            k3 = rate(z + 0.5 * h * k2)
            k4 = rate(z + h * k3)
            z_new = z + h * (k1 + 2 * k2 + 2 * k3 + k4) / 6
            area += 0.5 * (z + z_new) * h
            z = z_new
        return z, area

    z_m = brentq(lambda z: down(z)[0] + z, 1e-9, 1.0 - 1e-15, xtol=1e-14)
    return z_m, 2.0 * down(z_m)[1]


@pytest.mark.parametrize("n, ratio", [(1.0, 0.5), (1.0, 4.0), (2.0, 1.5), (0.7, 3.0)])
def test_boucwen_cycle_against_a_stepped_loop(n, ratio):
    dy = 0.02
    z_m, area = boucwen_cycle(n, dy, ratio * dy)
    z_ref, area_ref = _boucwen_loop(n, dy, ratio * dy)
    assert z_m == pytest.approx(z_ref, rel=1e-6) and area == pytest.approx(area_ref, rel=1e-5)
    if n == 1.0:  # closed form: -ln(1 - z_m) + z_m = 2 d / dy, area = 2 dy (2 d / dy - 2 z_m - z_m^2 / 2)
        assert -math.log1p(-z_m) + z_m == pytest.approx(2 * ratio, rel=1e-12)
        assert area == pytest.approx(2 * dy * (2 * ratio - 2 * z_m - z_m**2 / 2), rel=1e-10)


def test_boucwen_cycle_tends_to_the_bilinear_loop():
    """EDC = 4 Qd (d - dy) of the bilinear loop as n grows (and z_m -> 1), for d > dy."""
    dy, d = 0.02, 0.1
    gaps = [abs(boucwen_cycle(n, dy, d)[1] / (4 * (d - dy)) - 1) for n in (2.0, 8.0, 25.0)]
    assert gaps[0] > gaps[1] > gaps[2] and gaps[2] < 0.01, gaps
    assert boucwen_cycle(25.0, dy, 5 * dy)[0] == pytest.approx(1.0, abs=1e-12)


M = 8.0e5


def test_equivalent_damping_of_each_model_against_its_loop():
    """zeta_eq = EDC / (2 pi k_sec d^2) of the harmonic cycle at the secant frequency: for a pendulum with
    Constantinou friction and a viscous damper, a Bouc-Wen bearing with sliders and a power-law damper, a linear
    spring with a power-law damper; each loop's forces summed here over the cycle."""
    d = 0.18
    # pendulum: k = W / R, c = 2 zeta sqrt(k m)
    R, slow, fast, a, zeta = 2.5, 0.02, 0.06, 30.0, 0.01
    T = 2 * math.pi * math.sqrt(R / G)
    k = M * G / R
    omega = math.sqrt(k / M)
    x, v, dx = _harmonic(d, omega)
    mu = fast - (fast - slow) * np.exp(-a * np.abs(v))
    edc = float(np.sum((mu * M * G * np.sign(v) + 2 * zeta * math.sqrt(k * M) * v) * dx))
    p = {"period": T, "friction_slow": slow, "friction_fast": fast, "rate": a, "damping_ratio": zeta, "d0": -d}
    assert derived_quantity("equivalent_damping_ratio", "pendulum", M, p) == pytest.approx(
        edc / (2 * math.pi * k * d * d), rel=1e-6)
    assert derived_quantity("radius", "pendulum", M, p) == pytest.approx(R, rel=1e-14)
    # at constant friction the pendulum is the linear spring k = W / R on sliders F_s = mu W
    const = {**p, "friction_fast": slow, "rate": 0.0}
    lin = {"period": T, "damping_ratio": zeta, "friction": slow * M * G, "d0": d}
    assert derived_quantity("equivalent_damping_ratio", "pendulum", M, const) == pytest.approx(
        derived_quantity("equivalent_damping_ratio", "linear", M, lin), rel=1e-13)
    assert derived_quantity("equivalent_damping_ratio", "pendulum", M, const) == pytest.approx(
        zeta + 2 * slow * R / (math.pi * d), rel=1e-12)
    # Bouc-Wen with sliders and a power-law damper: k_sec from the steady loop's force at d
    Kd, Qd, dy, n, Fs, C, alpha = 1.6e6, 4.0e5, 0.025, 1.0, 2.0e4, 3.0e5, 0.4
    z_m, area = _boucwen_loop(n, dy, d)
    k_sec = Kd + Qd * z_m / d
    omega = math.sqrt(k_sec / M)
    edc = Qd * area + 4 * Fs * d + _damper_loop(C, alpha, d, omega)
    p = {"period": 2 * math.pi * math.sqrt(M / Kd), "characteristic_strength": Qd, "yield_displacement": dy,
         "shape": n, "friction": Fs, "damping_coefficient": C, "damping_exponent": alpha, "d0": d}
    assert derived_quantity("equivalent_damping_ratio", "boucwen", M, p) == pytest.approx(
        edc / (2 * math.pi * k_sec * d * d), rel=1e-5)
    assert derived_quantity("secant_period", "boucwen", M, p) == pytest.approx(2 * math.pi * math.sqrt(M / k_sec),
                                                                               rel=1e-6)
    assert derived_quantity("post_yield_stiffness", "boucwen", M, p) == pytest.approx(Kd, rel=1e-14)
    # linear spring, sliders, power-law damper
    Tl, Fs = 2.5, 3.9e4
    k = M * (2 * math.pi / Tl) ** 2
    omega = math.sqrt(k / M)
    edc = 4 * Fs * d + _damper_loop(1.0e5, 0.4, d, omega)
    p = {"period": Tl, "friction": Fs, "damping_coefficient": 1.0e5, "damping_exponent": 0.4, "d0": d}
    assert derived_quantity("equivalent_damping_ratio", "linear", M, p) == pytest.approx(
        edc / (2 * math.pi * k * d * d), rel=1e-6)
