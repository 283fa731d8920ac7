import math

import mpmath
import numpy as np
import pytest
from conftest import PAPER_CASE
from hypothesis import given, settings
from hypothesis import strategies as st

from quickrelease import METHODS, ParameterError, dynamics, simulate, stop_time


@pytest.fixture(scope="module")
def solutions():
    return {m: simulate(**PAPER_CASE, method=m, dt=1e-5) for m in METHODS}


def _mp_stop_time(E_S, alpha0, F1, F2, c=(2, 3), m1=576.78, m2=531.69, L1=2.477):
    """Independent high-precision reference: Eq. 10 integrated by mpmath (tanh-sinh handles the endpoint)."""
    mpmath.mp.dps = 30
    c = mpmath.mpf(c[0]) / c[1]
    E_S, alpha0, F1, F2 = (mpmath.mpf(x) for x in (E_S, alpha0, F1, F2))
    m1, m2, L1 = mpmath.mpf(m1), mpmath.mpf(m2), mpmath.mpf(L1)

    def W(a):
        return 2 * F1 * L1 * (mpmath.sin(a) - mpmath.sin(alpha0)) + 4 * F2 * L1 * (mpmath.cos(alpha0) - mpmath.cos(a))

    aF = mpmath.findroot(lambda a: W(a) - E_S, 0.7)
    t = mpmath.quad(lambda a: mpmath.sqrt(m2 * L1**2 * (c * m1 / m2 + mpmath.sin(a) ** 2) / (E_S - W(a))),
                    [alpha0, aF])
    return float(t), float(aF)


def test_energy_method_against_mpmath(solutions):
    t_ref, a_ref = _mp_stop_time(**PAPER_CASE)
    r = solutions["energy"]
    assert r.stop_time == pytest.approx(t_ref, rel=1e-13)
    assert r.alpha_final == pytest.approx(a_ref, rel=1e-14)
    assert stop_time(**PAPER_CASE) == pytest.approx(t_ref, rel=1e-13)


def test_rk_and_energy_agree_to_1e_8(solutions):
    e, r = solutions["energy"], solutions["rk"]
    assert r.stop_time == pytest.approx(e.stop_time, rel=1e-8)
    assert r.alpha_final == pytest.approx(e.alpha_final, rel=1e-8)
    # whole histories, on the same time grid
    np.testing.assert_allclose(r.alpha, e.alpha, rtol=0, atol=1e-8)
    np.testing.assert_allclose(r.alpha_dot, e.alpha_dot, rtol=0, atol=1e-7)


def test_rk45_also_agrees():
    e = simulate(**PAPER_CASE)
    r = simulate(**PAPER_CASE, method="rk", rk_method="RK45")
    assert r.stop_time == pytest.approx(e.stop_time, rel=1e-7)


def test_explicit_converges_at_first_order():
    ref = simulate(**PAPER_CASE)
    dts = [4e-4, 2e-4, 1e-4, 5e-5]
    errs = [abs(simulate(**PAPER_CASE, method="explicit", dt=dt).stop_time - ref.stop_time) for dt in dts]
    ratios = [errs[i] / errs[i + 1] for i in range(len(errs) - 1)]
    for ratio in ratios:
        assert 1.8 < ratio < 2.2, (errs, ratios)
    errs_a = [abs(simulate(**PAPER_CASE, method="explicit", dt=dt).alpha_final - ref.alpha_final) for dt in dts]
    assert 1.7 < errs_a[-2] / errs_a[-1] < 2.3


@pytest.mark.parametrize("method", ["energy", "rk"])
def test_energy_balance(solutions, method):
    err = solutions[method].energy_balance_error()
    assert np.max(np.abs(err)) < 1e-9


def test_explicit_state_diagram_on_eq_10_curve(solutions):
    """Fig. 15: the explicit scheme's (alpha, alpha_dot) points lie on the analytic curve of Eq. 10."""

    def gaps(r):
        d = r.device
        W = dynamics.dissipated_energy(r.alpha, r.alpha0, r.F1, r.F2, d.L1)
        M = dynamics.generalized_mass(r.alpha, d.m1, d.m2, d.L1, r.mass_factor)
        analytic = np.sqrt(np.maximum(r.stored_energy - W, 0.0) / M)
        away = analytic > 0.05 * r.alpha_dot0  # where the curve is not vertical (near the stop it is)
        return np.max(np.abs(r.alpha_dot - analytic)[away]) / r.alpha_dot0, np.max(np.abs(r.energy_balance_error()))

    fine = gaps(solutions["explicit"])  # dt = 1e-5 s
    coarse = gaps(simulate(**PAPER_CASE, method="explicit", dt=1e-4))
    assert fine[0] < 2e-5 and fine[1] < 2e-6
    # both gaps shrink at first order: a tenth of dt, a tenth of the gap
    assert 8 < coarse[0] / fine[0] < 12
    assert 8 < coarse[1] / fine[1] < 12


def test_fig_14_statements(solutions):
    r = solutions["energy"]
    s = r.summary()
    assert np.all(r.v[1:] > 1.5 * r.u[1:])  # the opening is much larger than the retraction
    assert r.v_final > 1.9 * r.u_final
    assert 2.0 < s["peak_v_dot_m_s"] < 3.0
    assert 0.5 < s["peak_u_dot_m_s"] < 1.5


def test_fig_13_statements(solutions):
    r = solutions["energy"]
    # alpha increases monotonically to alpha_F and the velocity vanishes there
    assert np.all(np.diff(r.alpha) > 0)
    assert r.alpha_dot[-1] == 0.0 and r.alpha_ddot[-1] == 0.0
    # the deceleration grows in magnitude to a maximum before the stop, then drops to 0
    mag = np.abs(r.alpha_ddot[:-1])
    k = int(np.argmax(mag))
    assert 0 < k < mag.size - 1
    assert mag[0] < mag[k]


def test_after_the_stop_the_device_rests():
    r = simulate(**PAPER_CASE, t_end=1.5, n_points=201)
    after = r.t > r.stop_time
    assert after.sum() > 10 and r.t[-1] == pytest.approx(1.5)
    assert np.all(r.alpha_dot[after] == 0.0) and np.all(r.alpha_ddot[after] == 0.0)
    assert np.all(r.alpha[after] == r.alpha_final)


def test_explicit_has_no_chattering():
    r = simulate(**PAPER_CASE, method="explicit", dt=1e-3)
    assert np.all(r.alpha_dot >= 0.0)
    assert np.all(np.diff(r.t) > 0) and r.t[-1] == r.stop_time


@pytest.mark.parametrize("method", METHODS)
def test_geometric_limit_is_reported(method):
    r = simulate(2900.0, 0.2, 100.0, 50.0, method=method, dt=1e-5)
    assert r.stopped_by == "geometric_limit"
    assert r.alpha_final == math.pi / 2
    assert np.all(np.isfinite(r.alpha)) and np.max(r.alpha) <= math.pi / 2
    assert r.alpha_dot[-1] > 0
    ref = simulate(2900.0, 0.2, 100.0, 50.0)
    tol = 1e-9 if method != "explicit" else 1e-4
    assert r.stop_time == pytest.approx(ref.stop_time, rel=tol)


def test_geometric_limit_without_friction():
    r = simulate(2900.0, 0.2)
    rk = simulate(2900.0, 0.2, method="rk")
    assert r.stopped_by == rk.stopped_by == "geometric_limit"
    assert r.stop_time == pytest.approx(rk.stop_time, rel=1e-9)
    # no friction: kinetic energy stays E_S
    np.testing.assert_allclose(r.kinetic_energy, 2900.0, rtol=1e-12)


@settings(max_examples=25, deadline=None)
@given(st.floats(200.0, 2e4), st.floats(0.08, 1.2), st.floats(0.0, 1.0), st.floats(50.0, 5e3),
       st.sampled_from(["distributed", "lumped"]))
def test_rk_and_energy_agree_everywhere(E_S, alpha0, share, F, model):
    F1, F2 = share * F, (1 - share) * F
    e = simulate(E_S, alpha0, F1, F2, mass_model=model, n_points=50)
    r = simulate(E_S, alpha0, F1, F2, mass_model=model, method="rk", n_points=50)
    assert e.stopped_by == r.stopped_by
    assert r.stop_time == pytest.approx(e.stop_time, rel=1e-7)
    assert r.alpha_final == pytest.approx(e.alpha_final, rel=1e-8)
    assert np.max(np.abs(e.energy_balance_error())) < 1e-9


def test_lumped_is_slower_than_distributed():
    d = simulate(**PAPER_CASE)
    l = simulate(**PAPER_CASE, mass_model="lumped")
    assert l.alpha_final == pytest.approx(d.alpha_final, rel=1e-14)  # Eq. 8 does not depend on mass
    assert l.stop_time > d.stop_time


def test_to_pandas_columns(solutions):
    df = solutions["energy"].to_pandas()
    assert list(df.columns)[:4] == ["t_s", "alpha_rad", "alpha_dot_rad_s", "alpha_ddot_rad_s2"]
    assert len(df) == 1001
    assert df["E_K_J"].iloc[0] == pytest.approx(2900.0, rel=1e-14)


@pytest.mark.parametrize("kwargs,match", [
    (dict(E_S=-1.0), r"E_S = -1 J is outside \(0, inf\)"),
    (dict(alpha0=1.6), r"alpha0 = 1.6 rad is outside \(0, pi/2\)"),
    (dict(F1=-3.0), r"F1 = -3 N is outside \[0, inf\)"),
    (dict(method="euler"), r"method = euler is outside 'energy', 'rk', 'explicit'"),
    (dict(mass_model="heavy"), r"mass_model = heavy"),
    (dict(method="explicit", dt=-1e-3), r"dt = -0.001 s is outside"),
])
def test_bad_input(kwargs, match):
    args = dict(PAPER_CASE)
    args.update(kwargs)
    with pytest.raises(ParameterError, match=match):
        simulate(**args)


def test_time_map_against_mpmath_on_random_cases():
    """The Chebyshev time map t(w) of the energy solution: t(0) = t_F to ~1e-15 against mpmath, hard cases included."""
    from quickrelease.reference import stop_time_mp
    from quickrelease.sampling import random_releases
    from quickrelease.solvers import FirstIntegral

    cases = random_releases(16, seed=11, limit_share=0.4)
    worst = 0.0
    for i in range(16):
        a = {k: float(v[i]) for k, v in cases.items()}
        fi = FirstIntegral(a["E_S"], a["alpha0"], a["F1"], a["F2"], a["m1"], a["m2"], a["L1"], a["c"])
        t_ref, _ = stop_time_mp(a["E_S"], a["alpha0"], a["F1"], a["F2"], a["c"] * a["m1"] / a["m2"], a["m2"], a["L1"])
        worst = max(worst, abs(fi.time_map.total / t_ref - 1.0))
        w = np.linspace(0.0, 1.0, 7)
        np.testing.assert_allclose(fi.time_map.time(w), fi.elapsed(w), rtol=0, atol=1e-11 * t_ref)
    assert worst < 1e-13


def test_state_at_uneven_times_matches_rk_with_rest_before_and_after():
    from quickrelease.solvers import FirstIntegral

    d = simulate(**PAPER_CASE).device
    fi = FirstIntegral(*PAPER_CASE.values(), d.m1, d.m2, d.L1, 2.0 / 3.0)
    rng = np.random.default_rng(1)
    t = np.sort(rng.uniform(-0.3, 1.6, 400))
    alpha, alpha_dot = fi.state_at(t)
    rk = simulate(**PAPER_CASE, method="rk", n_points=20001)
    inside = (t > 0) & (t < rk.stop_time)
    np.testing.assert_allclose(alpha[inside], np.interp(t[inside], rk.t, rk.alpha), atol=2e-8)
    # the inverse of the time map reproduces the times to rounding
    np.testing.assert_allclose(fi.time_map.time(fi.w_at_times(t[inside])), t[inside], rtol=0, atol=1e-15)
    assert np.all(alpha[t <= 0] == 0.2) and np.all(alpha_dot[t <= 0] == 0.0)
    assert np.all(alpha[t > fi.stop_time()] == fi.alpha_final) and np.all(alpha_dot[t > fi.stop_time()] == 0.0)
    assert np.all(alpha_dot[inside] > 0)
