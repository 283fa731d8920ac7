import math
import re
from pathlib import Path

import mpmath
import numpy as np
import pytest
from conftest import PAPER_CASE
from hypothesis import given, settings
from hypothesis import strategies as st

from quickrelease import METHODS, ParameterError, simulate, stop_time
from quickrelease.device import dynamics


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
    t_ref, a_ref = _mp_stop_time(*PAPER_CASE.values())
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


def test_energy_balance_of_rk(solutions):
    """rk integrates Eq. 4 and knows nothing of the first integral: E_K + W_F = E_S along it is a real check.
    (The energy method's alpha_dot is defined from that balance, so there it would hold by construction; its
    history is checked against mpmath's t(alpha) instead, below.)"""
    err = solutions["rk"].energy_balance_error()
    assert np.max(np.abs(err)) < 1e-9


def test_energy_method_history_against_mpmath_time_of_angle(solutions):
    """t(alpha) = int_alpha0^alpha sqrt(M / (E_S - W_F)) (Eq. 10) by mpmath at five interior angles: the
    energy solution passes each angle at that time (its state at t_j is alpha_j to 1e-12)."""
    from quickrelease.device.solvers import FirstIntegral

    mpmath.mp.dps = 30
    E_S, a0, F1, F2 = (mpmath.mpf(x) for x in ("2900", "0.2", "419.85", "804.57"))
    m1, m2, L1, c = mpmath.mpf("576.78"), mpmath.mpf("531.69"), mpmath.mpf("2.477"), mpmath.mpf(2) / 3

    def integrand(a):
        W = 2 * F1 * L1 * (mpmath.sin(a) - mpmath.sin(a0)) + 4 * F2 * L1 * (mpmath.cos(a0) - mpmath.cos(a))
        return mpmath.sqrt(m2 * L1**2 * (c * m1 / m2 + mpmath.sin(a) ** 2) / (E_S - W))

    r = solutions["energy"]
    fi = FirstIntegral(*PAPER_CASE.values(), r.device.m1, r.device.m2, r.device.L1, 2.0 / 3.0)
    for alpha_j in (0.25, 0.35, 0.5, 0.65, 0.73):
        t_j = float(mpmath.quad(integrand, [a0, mpmath.mpf(alpha_j)]))
        alpha, _ = fi.state_at(np.array([t_j]))
        assert alpha[0] == pytest.approx(alpha_j, abs=1e-12), alpha_j
        assert np.interp(t_j, r.t, r.alpha) == pytest.approx(alpha_j, abs=2e-6)  # the 1001-sample history


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
    # alpha increases monotonically to alpha_F and the velocity vanishes there, linearly in time at the rate
    # Eq. 4 gives at rest on the moving branch: alpha_ddot(alpha_F, 0) = -(2 F2 sin + F1 cos) / (m2 L1 (k + sin^2))
    assert np.all(np.diff(r.alpha) > 0)
    k_mass, aF = 2.0 / 3.0 * 576.78 / 531.69, 0.7377992890709009  # alpha_F: mpmath root of Eq. 8 (test above)
    decel = (2 * 804.57 * math.sin(aF) + 419.85 * math.cos(aF)) / (531.69 * 2.477 * (k_mass + math.sin(aF) ** 2))
    dt_last = r.t[-1] - r.t[-2]
    assert r.alpha_dot[-2] == pytest.approx(decel * dt_last, rel=1e-3)
    # the deceleration grows in magnitude to a maximum before the stop, then drops: the maximum of
    # |alpha_ddot(alpha)| along Eq. 10 (alpha_dot^2 = (E_S - W_F) / M), found by mpmath, lies strictly inside
    # (alpha0, alpha_F), above both ends; the sampled history peaks there with that value
    mpmath.mp.dps = 30
    m1, m2, L1, c = mpmath.mpf("576.78"), mpmath.mpf("531.69"), mpmath.mpf("2.477"), mpmath.mpf(2) / 3

    def mag(a):
        W = 2 * mpmath.mpf("419.85") * L1 * (mpmath.sin(a) - mpmath.sin(mpmath.mpf("0.2"))) + 4 * mpmath.mpf(
            "804.57") * L1 * (mpmath.cos(mpmath.mpf("0.2")) - mpmath.cos(a))
        d = c * m1 / m2 + mpmath.sin(a) ** 2
        ad2 = (2900 - W) / (m2 * L1**2 * d)
        return ad2 * mpmath.sin(a) * mpmath.cos(a) / d + (2 * mpmath.mpf("804.57") * mpmath.sin(a) + mpmath.mpf(
            "419.85") * mpmath.cos(a)) / (m2 * L1 * d)

    grid = [0.2 + (aF - 0.2) * j / 400 for j in range(401)]
    j_max = max(range(401), key=lambda j: mag(grid[j]))
    a_star = mpmath.findroot(lambda a: mpmath.diff(mag, a), grid[j_max])
    peak = float(mag(a_star))
    assert 0.2 < float(a_star) < aF and peak > float(mag(mpmath.mpf("0.2"))) and peak > float(mag(aF))
    sampled = np.abs(r.alpha_ddot[:-1])
    k = int(np.argmax(sampled))
    assert sampled[k] == pytest.approx(peak, rel=1e-5)
    assert abs(r.alpha[k] - float(a_star)) < 2 * np.max(np.diff(r.alpha))


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
    # no friction: the kinetic energy of the integrated Eq. 4 stays E_S (the energy method has it by construction)
    np.testing.assert_allclose(rk.kinetic_energy, 2900.0, rtol=1e-9)


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


def test_lumped_is_slower_than_distributed():
    d = simulate(**PAPER_CASE)
    l = simulate(**PAPER_CASE, mass_model="lumped")
    assert l.alpha_final == pytest.approx(d.alpha_final, rel=1e-14)  # Eq. 8 does not depend on mass
    assert l.stop_time > d.stop_time


def test_to_pandas_columns(solutions):
    df = solutions["energy"].to_pandas()
    assert df.index.name == "t_s" and np.array_equal(df.index.to_numpy(), solutions["energy"].t)
    assert list(df.columns)[:3] == ["alpha_rad", "alpha_dot_rad_s", "alpha_ddot_rad_s2"]
    assert len(df) == 1001
    assert df["E_K_J"].iloc[0] == pytest.approx(2900.0, rel=1e-14)


@pytest.mark.parametrize("kwargs,match", [
    (dict(stored_energy=-1.0), r"E_S = -1 J is outside \(0, inf\)"),
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
    from quickrelease.batch.sampling import random_releases
    from quickrelease.device.reference import stop_time_mp
    from quickrelease.device.solvers import FirstIntegral

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
    from quickrelease.device.solvers import FirstIntegral

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


# -- the paper's Table 6 scheme, pinned by hand -------------------------------------------------------------

_M1, _M2, _L1, _C = 576.78, 531.69, 2.477, 2.0 / 3.0  # Table 2; distributed mass (Eq. 4)


def _eq4(a, ad, F1, F2, sin, cos):
    """Table 6, third line (Eq. 4, sign(alpha_dot) = +1), written out here independently of the package."""
    d = _C * _M1 / _M2 + sin(a) ** 2
    return -ad**2 * sin(a) * cos(a) / d - (2 * F2 * sin(a) + F1 * cos(a)) / (_M2 * _L1 * d)


def _table6_by_hand(E_S, alpha0, F1, F2, dt, steps=None):
    """Table 6 step by step, from Eq. 6, in plain floats; the stop inside the last step where the velocity
    (linear within a step, first line of Table 6) vanishes, the angle there by the mid-point rule of the
    second line with alpha_dot = 0 at the end: alpha + (alpha_dot + 0) / 2 * tau."""
    ad = math.sqrt(E_S / (_M2 * _L1**2 * (_C * _M1 / _M2 + math.sin(alpha0) ** 2)))  # Eq. 6
    a, t = alpha0, 0.0
    add = _eq4(a, ad, F1, F2, math.sin, math.cos)
    out = [(t, a, ad)]
    k = 0
    while steps is None or k < steps:
        k += 1
        ad_new = ad + add * dt
        if ad_new <= 0:
            tau = ad / -add
            out.append((t + tau, a + ad / 2 * tau, 0.0))
            break
        a = a + (ad_new + ad) / 2 * dt
        ad, t = ad_new, k * dt
        add = _eq4(a, ad, F1, F2, math.sin, math.cos)
        out.append((t, a, ad))
    return out


def test_table_6_first_steps_by_hand_in_mpmath():
    """Three steps of Table 6 at dt = 10 ms in 30-digit arithmetic: the package's explicit scheme follows them
    to rounding. An acceleration one step late, or the angle by backward Euler instead of the mid-point rule,
    moves a state by more than 1e-6 relative, eight orders of magnitude above this tolerance."""
    mpmath.mp.dps = 30
    E_S, a0, F1, F2 = (mpmath.mpf(x) for x in ("2900", "0.2", "419.85", "804.57"))
    dt = mpmath.mpf("0.01")
    a = a0
    ad = mpmath.sqrt(E_S / (_M2 * _L1**2 * (_C * _M1 / _M2 + mpmath.sin(a0) ** 2)))  # Eq. 6
    add = _eq4(a, ad, F1, F2, mpmath.sin, mpmath.cos)
    states = [(a, ad, add)]
    for _ in range(3):
        ad_new = ad + add * dt                      # Table 6, line 1
        a = a + (ad_new + ad) / 2 * dt              # Table 6, line 2
        ad = ad_new
        add = _eq4(a, ad, F1, F2, mpmath.sin, mpmath.cos)  # Table 6, line 3
        states.append((a, ad, add))
    r = simulate(**PAPER_CASE, method="explicit", dt=0.01)
    for k in range(4):
        assert r.t[k] == pytest.approx(0.01 * k, abs=1e-15)
        assert r.alpha[k] == pytest.approx(float(states[k][0]), rel=1e-14), k
        assert r.alpha_dot[k] == pytest.approx(float(states[k][1]), rel=1e-14), k
        assert r.alpha_ddot[k] == pytest.approx(float(states[k][2]), rel=1e-12), k
    # and the size of the two plausible slips, for the record
    a1, ad1, add1 = states[1]
    lagged = a1 + (ad1 + states[0][2] * dt + ad1) / 2 * dt  # second step with the first step's acceleration
    assert abs(lagged / states[2][0] - 1) > 1e-6
    euler = a0 + (ad1 + 0) * dt  # backward Euler on the first step
    assert abs(euler / states[1][0] - 1) > 1e-6


def test_table_6_whole_run_and_stop_inside_the_last_step_by_hand():
    """The whole run, the last (fractional) step included, equals the hand scheme above to rounding."""
    for dt in (1e-3, 3.7e-4):
        hand = _table6_by_hand(*PAPER_CASE.values(), dt)
        r = simulate(**PAPER_CASE, method="explicit", dt=dt)
        assert r.t.size == len(hand) and r.stopped_by == "friction"
        t, a, ad = (np.array(x) for x in zip(*hand, strict=True))
        np.testing.assert_allclose(r.t, t, rtol=1e-13, atol=0)
        np.testing.assert_allclose(r.alpha, a, rtol=1e-13, atol=0)
        np.testing.assert_allclose(r.alpha_dot, ad, rtol=1e-11, atol=1e-13)
        assert r.stop_time == pytest.approx(t[-1], rel=1e-13)
        assert r.alpha_final == pytest.approx(a[-1], rel=1e-14)
        # the last step: velocity from its start value to 0, the angle by the mid-point rule over tau
        tau = t[-1] - t[-2]
        assert 0 < tau <= dt
        assert r.alpha_final - r.alpha[-2] == pytest.approx(0.5 * r.alpha_dot[-2] * tau, rel=1e-9)


def _readme_convergence_table():
    text = (Path(__file__).parents[2] / "docs" / "paper.md").read_text(encoding="utf-8")  # moved from the README
    head = text.index("| dt [s] | t_F [s] | error in t_F [s]")
    rows = []
    for line in text[head:].splitlines()[2:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        rows.append([float(c) if c else None for c in cells])
    ref = re.search(r"reference t_F =\s+([\d.]+) s, alpha_F = ([\d.]+) rad", text[:head].replace("\n", " "))
    return rows, float(ref.group(1)), float(ref.group(2))


def test_readme_convergence_table_of_the_explicit_scheme():
    """Every printed digit of the README's table: t_F from the hand scheme, errors against the 30-digit mpmath
    reference, and the observed order (ratios of successive errors -> 2 when dt halves: first order)."""
    rows, t_ref_printed, a_ref_printed = _readme_convergence_table()
    assert [row[0] for row in rows] == [1e-3 / 2**j for j in range(6)]
    t_ref, a_ref = _mp_stop_time(*PAPER_CASE.values())
    assert t_ref == pytest.approx(t_ref_printed, abs=0.5e-10)
    assert a_ref == pytest.approx(a_ref_printed, abs=0.5e-10)
    prev = None
    for dt, t_F, err_t, ratio_t, err_a, ratio_a in rows:
        hand = _table6_by_hand(*PAPER_CASE.values(), dt)[-1]
        r = simulate(**PAPER_CASE, method="explicit", dt=dt)
        assert r.stop_time == pytest.approx(hand[0], rel=1e-13) and r.alpha_final == pytest.approx(hand[1], rel=1e-14)
        e_t, e_a = r.stop_time - t_ref, r.alpha_final - a_ref
        assert abs(r.stop_time - t_F) <= 0.5e-10 * (1 + 1e-6)
        assert e_t == pytest.approx(err_t, abs=0.5 * 10 ** (math.floor(math.log10(abs(err_t))) - 3))
        assert e_a == pytest.approx(err_a, abs=0.5 * 10 ** (math.floor(math.log10(abs(err_a))) - 3))
        if prev is not None:
            assert prev[0] / e_t == pytest.approx(ratio_t, abs=0.5e-3)
            assert prev[1] / e_a == pytest.approx(ratio_a, abs=0.5e-3)
            # first order: halving dt halves the error (to 2% here, to 0.2% on the finest steps)
            assert abs(prev[0] / e_t - 2) < 0.02 and abs(prev[1] / e_a - 2) < 0.02
        prev = (e_t, e_a)
