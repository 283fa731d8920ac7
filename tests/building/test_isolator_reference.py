"""The independent reference of the isolator models (isolator_reference.py) checked against what is exact:
the package's closed-form free vibration of the linear and bilinear isolation (quickrelease.building.model,
event-exact, no integrator), closed forms written here (the viscous oscillator; the first turning point of
the quadratic damper, alpha = 2, from its energy first integral; the Bouc-Wen law of z along x for n = 1),
the Bouc-Wen model's approach to the bilinear one as n grows, and the reference's own energy balance.
"""

import math

import numpy as np
import pytest
from isolator_reference import GRAVITY, bilinear, bouc_wen_push, boucwen, linear, pendulum, simulate
from scipy.optimize import brentq

from quickrelease.building.model import Isolation, free_vibration

T_OUT = np.linspace(-0.5, 30.0, 1000)


def _close(ref, exact, d0, tol=1e-9):
    x, v, a = exact.state(T_OUT)
    moving = T_OUT < (exact.stop_time if math.isfinite(exact.stop_time) else np.inf)
    w = 2 * math.pi / exact.isolation.period
    assert np.max(np.abs(ref.x - x)) < tol * d0
    assert np.max(np.abs(ref.v - v)) < tol * d0 * w
    assert np.max(np.abs((ref.a - a)[moving])) < tol * d0 * w * w


# -- the pendulum with constant friction is linear + Coulomb (k = W / R, F_s = mu W) ----------------------------

@pytest.mark.parametrize("m, R, mu, C, d0", [
    (1.0e6, 2.5, 0.01, 0.0, 0.15),
    (1.0e6, 2.5, 0.005, 2.0e5, 0.15),
    (4.0e5, 1.5, 0.02, 5.0e4, -0.10),
    (2.0e6, 4.0, 0.001, 0.0, 0.30),
])
def test_pendulum_with_constant_friction_is_linear_coulomb(m, R, mu, C, d0):
    ref = simulate(pendulum(m, R, mu, damping=C), d0, T_OUT, t_end=200.0)
    W = m * GRAVITY
    exact = free_vibration(Isolation(mass=m, stiffness=W / R, damping=C, friction=mu * W), d0)
    _close(ref, exact, abs(d0))
    assert ref.stop_time == pytest.approx(exact.stop_time, rel=1e-10)
    np.testing.assert_allclose(ref.reversal_times, exact.reversal_times, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ref.turning_points, exact.turning_points, rtol=0, atol=1e-10 * abs(d0))


@pytest.mark.slow
def test_pendulum_at_a_large_rate_slides_with_mu_fast_and_sticks_with_mu_slow():
    """rate -> inf: mu = mu_fast at any speed, so the motion tends to linear + Coulomb with mu_fast W until that
    model sticks (|k x| <= mu_fast W); the gap falls like 1 / rate. The pendulum sticks only where
    |k x| <= mu_slow W: it goes on where the other stops."""
    m, R, slow, fast, d0 = 1.0e6, 2.5, 0.002, 0.01, 0.16
    W = m * GRAVITY
    exact = free_vibration(Isolation(mass=m, stiffness=W / R, friction=fast * W), d0)
    before = T_OUT < exact.stop_time
    gaps = []
    for rate in (1e3, 1e4, 1e5):
        ref = simulate(pendulum(m, R, slow, fast, rate=rate), d0, T_OUT)
        gaps.append(np.max(np.abs(ref.x - exact.state(T_OUT)[0])[before]))
    assert gaps[1] < 0.2 * gaps[0] and gaps[2] < 0.2 * gaps[1] and gaps[2] < 3e-5 * d0, gaps
    # the linear model sticks at x = -0.01 m (|x| / R = 0.004 <= mu_fast); the pendulum does not (> mu_slow): it
    # creeps on at the speed where mu(v) = |x| / R, towards -mu_slow R = -5 mm, never reversing again
    assert exact.rest[0] == pytest.approx(-0.01, abs=1e-12) and ref.stop_time == math.inf
    assert -0.01 + 1e-5 < ref.x[-1] < -0.005


def test_pendulum_does_not_move_when_mu_slow_holds_it():
    ref = simulate(pendulum(1e6, 2.5, 0.07, 0.1, rate=30.0), 0.15, T_OUT)
    assert ref.stop_time == 0.0
    assert np.all(ref.x == 0.15) and np.all(ref.v == 0.0) and np.all(ref.a == 0.0)


# -- the power-law damper: alpha = 1 is viscous; alpha = 2 from its first integral --------------------------

@pytest.mark.parametrize("zeta, Fs", [(0.02, 0.0), (0.10, 0.0), (0.05, 3.0e4)])
def test_power_damper_at_alpha_1_is_viscous(zeta, Fs):
    m, T, d0 = 8.0e5, 2.5, 0.2
    k = m * (2 * math.pi / T) ** 2
    c = 2 * zeta * math.sqrt(k * m)
    ref = simulate(linear(m, k, damping=c, damping_exponent=1.0, friction=Fs), d0, T_OUT, t_end=T_OUT[-1])
    exact = free_vibration(Isolation(mass=m, stiffness=k, damping=c, friction=Fs), d0, t_end=T_OUT[-1])
    _close(ref, exact, d0)
    if Fs == 0.0:  # and the textbook closed form, written here
        w = 2 * math.pi / T
        wd = w * math.sqrt(1 - zeta**2)
        t = np.clip(T_OUT, 0.0, None)
        x = d0 * np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))
        assert np.max(np.abs(ref.x - x)) < 1e-9 * d0


def _quadratic_damper_turning_point(m, k, C, Fs, d0):
    """First turning point of m x'' + C v |v| + k x + Fs sign(v) = 0 from d0 > 0 at rest: moving left,
    w = v^2 solves (m / 2) dw/dx = -(k x - Fs) + C w, w(d0) = 0, so with y = x - Fs / k,
    w = (k / C) y + m k / (2 C^2) + A exp(2 C x / m); the turning point is w's other zero."""
    def w(x):
        y, y0 = x - Fs / k, d0 - Fs / k
        A = -((k / C) * y0 + m * k / (2 * C**2)) * math.exp(-2 * C * d0 / m)
        return (k / C) * y + m * k / (2 * C**2) + A * math.exp(2 * C * x / m)

    return brentq(w, -d0 - 1.0, Fs / k - 1e-9, xtol=1e-15, rtol=1e-15)


@pytest.mark.parametrize("C, Fs", [(1.0e5, 0.0), (4.0e5, 0.0), (2.0e5, 2.0e4)])
def test_quadratic_damper_turning_point_from_the_first_integral(C, Fs):
    m, k, d0 = 8.0e5, 5.0e6, 0.2
    ref = simulate(linear(m, k, damping=C, damping_exponent=2.0, friction=Fs), d0, T_OUT, t_end=5.0)
    assert ref.turning_points[1] == pytest.approx(_quadratic_damper_turning_point(m, k, C, Fs, d0), abs=1e-11)


@pytest.mark.parametrize("alpha", [0.2, 0.5, 1.0, 1.5, 1.8])
def test_power_damper_on_the_pendulum_at_alpha_2_limit_and_energy(alpha):
    """The pendulum with a power damper: kinetic + stored + friction + damper work = the initial energy."""
    ref = simulate(pendulum(1e6, 2.5, 0.01, 0.05, rate=25.0, damping=3e5, damping_exponent=alpha), 0.15, T_OUT)
    total = ref.kinetic + ref.stored + ref.friction + ref.viscous + ref.hysteretic
    assert np.max(np.abs(total - ref.initial)) < 1e-10 * ref.initial
    assert np.all(ref.viscous[T_OUT > 1.0] > 0) and np.all(ref.hysteretic == 0.0)


# -- the bilinear reference against the package's closed form, and Bouc-Wen's approach to it ----------------

@pytest.mark.parametrize("Fs, c, d0", [(0.0, 5.0e4, 0.2), (2.0e4, 1.0e5, 0.2), (1.0e4, 0.0, -0.05), (5.0e4, 3.0e5, 0.3)])
def test_bilinear_reference_is_the_closed_form(Fs, c, d0):
    m, k1, k2, Fy = 8.0e5, 3.0e7, 1.6e6, 4.24e5
    ref = simulate(bilinear(m, k1, k2, Fy, damping=c, friction=Fs), d0, T_OUT, t_end=T_OUT[-1])
    exact = free_vibration(Isolation(mass=m, stiffness=k1, damping=c, friction=Fs, post_yield_stiffness=k2,
                                     yield_force=Fy), d0, t_end=T_OUT[-1])
    _close(ref, exact, abs(d0), tol=1e-8)
    np.testing.assert_allclose(ref.reversal_times, exact.reversal_times[:ref.reversal_times.size], atol=1e-9)
    assert ref.reversal_times.size == exact.reversal_times.size


def test_bouc_wen_tends_to_bilinear_as_n_grows():
    """k1 = Kd + Qd / dy, k2 = Kd, F_y = Qd + Kd dy: the largest gap in x over the first 3 s (before either
    sticks) falls steadily with n and is below 1e-5 d0 at n = 100."""
    m, Kd, Qd, dy, c, Fs, d0 = 8.0e5, 1.6e6, 4.0e5, 0.015, 1.0e5, 2.0e4, 0.2
    t = np.linspace(0.0, 3.0, 600)
    exact = free_vibration(Isolation(mass=m, stiffness=Kd + Qd / dy, damping=c, friction=Fs, post_yield_stiffness=Kd,
                                     yield_force=Qd + Kd * dy), d0)
    x = exact.state(t)[0]
    gaps = [np.max(np.abs(simulate(boucwen(m, Kd, Qd, dy, shape=n, damping=c, friction=Fs), d0, t).x - x))
            for n in (1, 2, 5, 10, 30, 100)]
    assert all(b < 0.6 * a for a, b in zip(gaps, gaps[1:], strict=False)), gaps
    assert gaps[0] > 1e-2 * d0 and gaps[-1] < 1e-4 * d0


@pytest.mark.parametrize("n", [1.0, 2.0, 5.0])
def test_bouc_wen_push(n):
    d0, dy = 0.2, 0.015
    if n == 1.0:
        assert bouc_wen_push(d0, dy, n) == pytest.approx(1 - math.exp(-d0 / dy), rel=1e-13)
        assert bouc_wen_push(-0.01, dy, n) == pytest.approx(-(1 - math.exp(-0.01 / dy)), rel=1e-13)
    else:  # x(z) = dy * int_0^z dz / (1 - z^n), by quadrature
        from scipy.integrate import quad

        z = bouc_wen_push(0.02, dy, n)
        assert dy * quad(lambda u: 1.0 / (1.0 - u**n), 0.0, z, epsabs=0, epsrel=1e-13)[0] == pytest.approx(0.02, rel=1e-10)


def test_bouc_wen_n1_follows_its_closed_form_z_of_x():
    """n = 1 on the first half-cycle (moving left from d0, z0 > 0): unloading z = z0 + (x - d0) / dy down to
    z = 0 at x* = d0 - z0 dy, then loading 1 + z = exp(-(x* - x) / dy)."""
    m, Kd, Qd, dy, d0 = 8.0e5, 1.6e6, 4.0e5, 0.015, 0.2
    t = np.linspace(0.0, 2.5, 2000)
    ref = simulate(boucwen(m, Kd, Qd, dy, shape=1.0, damping=5e4), d0, t, t_end=2.5)
    first = (t > 0) & (t < ref.reversal_times[1])
    x, z = ref.x[first], ref.z[first]
    z0 = 1 - math.exp(-d0 / dy)
    xs = d0 - z0 * dy
    expected = np.where(x >= xs, z0 + (x - d0) / dy, np.exp(-(xs - x) / dy) - 1)
    assert np.max(np.abs(z - expected)) < 1e-10
    assert np.any(x < xs - 5 * dy)  # the loading branch is reached


@pytest.mark.parametrize("system, d0", [
    (boucwen(8e5, 1.6e6, 4e5, 0.015, shape=1.0, damping=1e5, damping_exponent=0.3, friction=1e4), 0.2),
    (boucwen(8e5, 1.6e6, 4e5, 0.015, shape=3.0), 0.2),
    (bilinear(8e5, 3e7, 1.6e6, 4.24e5, damping=2e5, damping_exponent=1.7, friction=2e4), -0.2),
    (pendulum(1e6, 2.5, 0.02, 0.06, rate=40.0), 0.25),
])
def test_reference_energy_balance(system, d0):
    ref = simulate(system, d0, T_OUT, t_end=T_OUT[-1])
    total = ref.kinetic + ref.stored + ref.friction + ref.viscous + ref.hysteretic
    assert np.max(np.abs(total - ref.initial)) < 1e-10 * ref.initial
    if system.kind == "boucwen":
        assert ref.hysteretic[-1] > 0.05 * ref.initial
