"""The physics at its edges (issue 9, items 12, 14, 15, 16, 18) against independent 30-digit references.

The reference integrates Eq. 10 with mpmath (mp.dps = 30) straight from Eq. 7-9 of the paper:
``t_F = int_{alpha0}^{alpha_F} sqrt(M(alpha) / (E_S - W_F(alpha))) dalpha`` with alpha_F from Eq. 8
(pi/2 where E_S > W_F(pi/2), the geometric limit). Near a friction stop the remaining energy is written
with the product formulas ``sin a - sin b = 2 cos((a+b)/2) sin((a-b)/2)`` (a hand step, no code of the
package), so 30 digits hold at the stop itself; tanh-sinh takes the inverse square root there.
"""

from __future__ import annotations

import dataclasses
import math

import mpmath as mp
import numpy as np
import pytest

import quickrelease as qr
from quickrelease import batch
from quickrelease.device import _kernels, dynamics, solvers

PAPER = qr.preset("paper")


def mp_reference(E_S, alpha0, F1, F2, m1, m2, L1, c, dps=30):
    """(t_F, alpha_F, stopped_by, E_S - W_F(pi/2)) of the exact float inputs, to 30 digits (more working
    digits, dps, where E_S / R is far below 1e-30)."""
    with mp.workdps(dps):
        E, a0, F1, F2, m1, m2, L1, c = (mp.mpf(float(v)) for v in (E_S, alpha0, F1, F2, m1, m2, L1, c))
        A, B = 2 * F1 * L1, 4 * F2 * L1
        hp = mp.pi / 2

        def W(a):  # Eq. 7
            return A * (mp.sin(a) - mp.sin(a0)) + B * (mp.cos(a0) - mp.cos(a))

        def M(a):  # Eq. 9
            return m2 * L1**2 * (c * m1 / m2 + mp.sin(a) ** 2)

        margin = E - W(hp)
        if margin > 0:
            t = mp.quad(lambda a: mp.sqrt(M(a) / (E - W(a))), [a0, hp - mp.mpf("1e-6"), hp])
            return t, hp, "geometric_limit", margin
        R, phi = mp.hypot(A, B), mp.atan2(B, A)
        aF = phi + mp.asin(mp.sin(a0 - phi) + E / R)  # Eq. 8

        def remaining(y):  # E_S - W_F(aF - y) = W_F(aF) - W_F(aF - y), by the product formulas
            return 2 * mp.sin(y / 2) * (A * mp.cos(aF - y / 2) + B * mp.sin(aF - y / 2))

        t = mp.quad(lambda y: mp.sqrt(M(aF - y) / remaining(y)), [0, aF - a0])
        return t, aF, "friction", margin


def _device(m1, m2, L1):
    return dataclasses.replace(PAPER, m1=float(m1), m2=float(m2), L1=float(L1))


# -- item 12: geometric limit with a small mass factor and a small alpha0 --------------------------------

def _item12_cases(n=24, seed=12):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        k = 10 ** rng.uniform(-5, math.log10(0.075))  # c m1/m2
        a0 = 10 ** rng.uniform(-4, math.log10(0.05))
        F1, F2 = rng.uniform(0, 400), rng.uniform(0, 400)
        W_lim = 2 * F1 * PAPER.L1 * (1 - math.sin(a0)) + 4 * F2 * PAPER.L1 * math.cos(a0)
        out.append((W_lim * 10 ** rng.uniform(1e-4, 0.7) + 1e-3, a0, F1, F2, k * PAPER.m2 / PAPER.m1))
    return out


@pytest.mark.slow
def test_item12_geometric_limit_small_mass_factor_batch_and_energy_to_1e10():
    cases = _item12_cases()
    E, a0, F1, F2, c = (np.array(v) for v in zip(*cases, strict=True))
    b = batch.stop_time(E, a0, F1, F2, c=c)
    assert np.all(b.stopped_by == 1)
    for i, case in enumerate(cases):
        t_ref, _, how, _ = mp_reference(*case[:4], PAPER.m1, PAPER.m2, PAPER.L1, case[4])
        assert how == "geometric_limit"
        t_single = qr.simulate(*case[:4], mass_model=case[4], n_points=2).stop_time
        assert abs(b.stop_time[i] / float(t_ref) - 1) < 1e-10, case
        assert abs(t_single / float(t_ref) - 1) < 1e-10, case


@pytest.mark.slow
def test_item12_small_mass_factor_friction_stop_too():
    rng = np.random.default_rng(121)
    for _ in range(12):
        c = 10 ** rng.uniform(-5, math.log10(0.075)) * PAPER.m2 / PAPER.m1
        a0 = 10 ** rng.uniform(-4, math.log10(0.05))
        F1, F2 = rng.uniform(1, 400), rng.uniform(1, 400)
        W_lim = 2 * F1 * PAPER.L1 * (1 - math.sin(a0)) + 4 * F2 * PAPER.L1 * math.cos(a0)
        E = W_lim * rng.uniform(0.05, 0.95)
        t_ref, _, how, _ = mp_reference(E, a0, F1, F2, PAPER.m1, PAPER.m2, PAPER.L1, c)
        assert how == "friction"
        t = float(batch.stop_time(E, a0, F1, F2, c=c).stop_time)
        assert abs(t / float(t_ref) - 1) < 1e-10


# -- item 14: tiny sweeps alpha_F - alpha0 ---------------------------------------------------------------

@pytest.mark.parametrize("log_sweep", [-6, -8, -10, -12, -14])
def test_item14_tiny_sweep_t_F_u_F_and_sweep_angle(log_sweep):
    rng = np.random.default_rng(1400 - log_sweep)
    for _ in range(4):
        a0 = rng.uniform(0.02, 1.5)
        F1, F2 = rng.uniform(0, 300), rng.uniform(1, 300)
        R = math.hypot(2 * F1 * PAPER.L1, 4 * F2 * PAPER.L1)
        E = R * 10 ** (log_sweep + rng.uniform(-0.5, 0.5))  # sweep ~ E_S / (R cos(alpha0 - phi))
        t_ref, aF_ref, how, _ = mp_reference(E, a0, F1, F2, PAPER.m1, PAPER.m2, PAPER.L1, 2 / 3)
        assert how == "friction"
        with mp.workdps(30):
            sweep_ref = aF_ref - mp.mpf(a0)
            u_ref = 2 * PAPER.L1 * mp.sin((aF_ref + a0) / 2) * mp.sin(sweep_ref / 2)  # cos a0 - cos aF, Table 4
            u_ref2 = PAPER.L1 * (mp.cos(mp.mpf(a0)) - mp.cos(aF_ref))
            assert abs(u_ref / u_ref2 - 1) < 1e-12  # the two forms of the reference agree
        sweep = dynamics.sweep_angle(E, a0, F1, F2, PAPER.L1)
        assert abs(sweep / float(sweep_ref) - 1) < 1e-14
        aF = dynamics.final_angle(E, a0, F1, F2, PAPER.L1)
        assert aF >= a0 and abs(aF - float(aF_ref)) <= math.ulp(float(aF_ref))  # item 18: never below alpha0
        rel = batch.release(E, a0, F1, F2)
        assert abs(float(rel.stop_time) / float(t_ref) - 1) < 1e-10
        assert abs(float(rel.u_final) / float(u_ref) - 1) < 1e-10
        assert abs(qr.simulate(E, a0, F1, F2, n_points=2).stop_time / float(t_ref) - 1) < 1e-10


# -- item 16: stops at or within rounding of pi/2 ----------------------------------------------------------

def _boundary_cases():
    """F1 = 0 (the issue's case) and F1 > 0: F2 set so that W_F(pi/2) = E_S in floating point, +-4 ulps."""
    out = []
    for E, a0, F1, m1, m2, L1 in ((148.413, 1.0, 0.0, 100.0, 100.0, 1.0), (2000.0, 0.3, 150.0, 576.78, 531.69, 2.477),
                                  (50.0, 1.4, 0.0, 576.78, 531.69, 2.477)):
        F2b = (E - 2 * F1 * L1 * (1 - math.sin(a0))) / (4 * L1 * math.cos(a0))
        for k in (-4, -1, 0, 1, 4):
            out.append((E, a0, F1, F2b + k * math.ulp(F2b), m1, m2, L1))
    return out


def _backward_band(E, a0, F1, F2, m1, m2, L1, c=2 / 3):
    """The reference t_F over E_S +- 8 ulps: the margin E_S - W_F(pi/2) is itself rounded by a few ulps of E_S,
    and t_F has a square-root kink at the boundary (dt/dmargin -> inf), so a method is right when it is exact
    for inputs within that rounding (backward stable); 1e-10 relative on top."""
    d = 8 * math.ulp(E)
    ts = [float(mp_reference(E + s * d, a0, F1, F2, m1, m2, L1, c)[0]) for s in (-1, 0, 1)]
    return min(ts) * (1 - 1e-10), max(ts) * (1 + 1e-10)


@pytest.mark.slow
@pytest.mark.parametrize("case", _boundary_cases())
def test_item16_every_method_agrees_on_stopped_by_and_t_F_at_the_boundary(case):
    E, a0, F1, F2, m1, m2, L1 = case
    dev = _device(m1, m2, L1)
    runs = {m: qr.simulate(E, a0, F1, F2, device=dev, method=m, n_points=3, dt=1e-4) for m in qr.METHODS}
    b = batch.stop_time(E, a0, F1, F2, m1=m1, m2=m2, L1=L1)
    b_rel = batch.release(E, a0, F1, F2, m1=m1, m2=m2, L1=L1)
    by = {r.stopped_by for r in runs.values()}
    assert len(by) == 1
    code = {"friction": 0, "geometric_limit": 1}[by.pop()]
    assert int(b.stopped_by) == code and int(b_rel.stopped_by) == code
    assert dynamics.reaches_geometric_limit(E, a0, F1, F2, L1) == bool(code)
    lo, hi = _backward_band(E, a0, F1, F2, m1, m2, L1)
    for t in (runs["energy"].stop_time, float(b.stop_time), float(b_rel.stop_time)):
        assert lo <= t <= hi
    # rk: its tolerance (rtol 1e-10) on top of the band; a friction stop's event is well conditioned
    assert lo * (1 - 1e-8) <= runs["rk"].stop_time <= hi * (1 + 1e-8)
    for r in runs.values():
        assert r.alpha_final <= math.pi / 2
    if code:  # the explicit scheme's own trajectory may end within its O(dt) error of pi/2 (see its stats)
        assert runs["energy"].alpha_final == runs["rk"].alpha_final == math.pi / 2
    assert runs["explicit"].stats["scheme_end"] in ("friction", "geometric_limit")


@pytest.mark.slow
def test_item16_clear_of_the_boundary_the_classification_is_the_exact_one():
    """Where |E_S - W_F(pi/2)| is well above rounding, stopped_by is the sign of the 30-digit margin."""
    rng = np.random.default_rng(16)
    for _ in range(20):
        a0, F1, F2 = rng.uniform(0.05, 1.5), rng.uniform(0, 300), rng.uniform(0, 300)
        W_lim = 2 * F1 * PAPER.L1 * (1 - math.sin(a0)) + 4 * F2 * PAPER.L1 * math.cos(a0)
        E = W_lim * (1 + rng.choice([-1, 1]) * 10 ** rng.uniform(-12, -2))
        how = mp_reference(E, a0, F1, F2, PAPER.m1, PAPER.m2, PAPER.L1, 2 / 3)[2]
        assert qr.simulate(E, a0, F1, F2, n_points=2).stopped_by == how
        assert int(batch.stop_time(E, a0, F1, F2).stopped_by) == (how == "geometric_limit")


# -- item 15: the ends of the feasible interval of the identification ----------------------------------------

@pytest.mark.parametrize("which", ["F1 = 0", "F2 = 0"])
def test_item15_identify_accepts_simulate_output_on_either_boundary(which):
    """simulate with F1 = 0 (or F2 = 0) lands on an end of the feasible interval: identify returns that end."""
    E, a0 = 500.0, 0.6
    forces = np.linspace(5.0, 400.0, 100)
    obs = []
    for F in forces:
        F1, F2 = (0.0, F) if which == "F1 = 0" else (F, 0.0)
        r = qr.simulate(E, a0, F1, F2, n_points=2)
        if r.stopped_by == "friction":
            obs.append((F, r.alpha_final, r.stop_time))
    assert len(obs) >= 40  # the weaker forces reach the flat rhombus
    F, aF, tF = (np.array(v) for v in zip(*obs, strict=True))
    b = batch.identify(a0, aF, tF, E)
    assert np.all(b.status == 0), b.reasons()
    zero, other = (b.F1, b.F2) if which == "F1 = 0" else (b.F2, b.F1)
    assert np.all(zero == 0.0)
    np.testing.assert_allclose(other, F, rtol=1e-9)
    for Fi, aFi, tFi in obs[::7]:
        ident = qr.identify_friction(a0, aFi, tFi, stored_energy=E)
        assert ident.boundary == which
        assert (ident.F1 if which == "F1 = 0" else ident.F2) == 0.0
        assert abs((ident.F2 if which == "F1 = 0" else ident.F1) / Fi - 1) < 1e-9


@pytest.mark.parametrize("side", [-1, 1])
def test_item15_observations_clearly_outside_are_still_rejected(side):
    E, a0, aF = 500.0, 0.6, 1.2
    b = batch.identify(a0, aF, 1.0, E)
    end = float(b.stop_time_min if side < 0 else b.stop_time_max)
    t_obs = end * (1 + side * 1e-9)  # 250 times the rounding allowance
    out = batch.identify(a0, aF, t_obs, E)
    assert int(out.status) == (1 if side < 0 else 2) and np.isnan(out.F1)
    with pytest.raises(qr.InfeasibleObservationError):
        qr.identify_friction(a0, aF, t_obs, stored_energy=E)
    inside = batch.identify(a0, aF, end * (1 - side * 1e-9), E)
    assert int(inside.status) == 0 and 0.0 < float(inside.F1) < float(inside.F1_max)


@pytest.mark.parametrize("lam", [0.05, 0.31, 0.7])
def test_item15_batch_identify_one_ulp_below_half_pi(lam):
    """alpha_F one ulp below pi/2: the identified F1/F1* is the true one (30-digit forward reference)."""
    E, a0, L1 = 500.0, 0.6, PAPER.L1
    aF = math.nextafter(math.pi / 2, 0.0)
    with mp.workdps(30):
        F1s = mp.mpf(E) / (2 * L1 * (mp.sin(mp.mpf(aF)) - mp.sin(mp.mpf(a0))))  # Eq. 11
        F2s = mp.mpf(E) / (4 * L1 * (mp.cos(mp.mpf(a0)) - mp.cos(mp.mpf(aF))))  # Eq. 12
        F1, F2 = float(lam * F1s), float((1 - lam) * F2s)
    t_ref = float(mp_reference(E, a0, F1, F2, PAPER.m1, PAPER.m2, L1, 2 / 3)[0])
    b = batch.identify(a0, aF, t_ref, E)
    assert int(b.status) == 0
    assert abs(float(b.F1 / b.F1_max) - lam) < 1e-6
    ident = qr.identify_friction(a0, aF, t_ref, stored_energy=E)
    assert abs(ident.F1 / ident.F1_max - lam) < 1e-6


# -- item 18: extreme inputs give finite, correct answers ------------------------------------------------------

def test_item18_extreme_energies_and_forces_are_finite_and_right():
    # no friction: t_F ~ E_S^(-1/2), rates ~ E_S^(1/2), accelerations ~ E_S (Eq. 3/4 and 10 scale so)
    one = batch.release(1.0, 0.2, 0.0, 0.0)
    for E in (1e300, 1e-300):
        b = batch.release(E, 0.2, 0.0, 0.0)
        for name, p in (("stop_time", -0.5), ("alpha_dot0", 0.5), ("peak_u_dot", 0.5), ("peak_v_dot", 0.5),
                        ("peak_u_ddot", 1.0), ("peak_v_ddot", 1.0)):
            got, base = float(getattr(b, name)), float(getattr(one, name))
            assert math.isfinite(got) and abs(got / (base * E**p) - 1) < 1e-12, name
    # the smallest subnormal carries one bit: its t_F would be off in the leading digit (7% measured against
    # the 1/sqrt(E_S) scaling), so it is refused naming E_S; 1e-308 (51 bits) is finite and scales exactly
    with pytest.raises(qr.ParameterError, match=r"^E_S = 4.94066e-324 J"):
        qr.simulate(5e-324, 0.2, 0.0, 0.0, n_points=5)
    r = qr.simulate(1e-308, 0.2, 0.0, 0.0, n_points=5)
    assert np.all(np.isfinite(r.alpha)) and np.all(np.isfinite(r.alpha_dot))
    assert np.all(np.diff(r.alpha) > 0) and r.alpha_final == math.pi / 2
    assert abs(r.stop_time / (float(one.stop_time) / math.sqrt(1e-308)) - 1) < 1e-9
    # a sweep of ~1e-297 rad: 400 working digits for the reference
    t = qr.stop_time(2900.0, 0.2, 1e300, 0.0)
    t_ref = mp_reference(2900.0, 0.2, 1e300, 0.0, PAPER.m1, PAPER.m2, PAPER.L1, 2 / 3, dps=400)[0]
    assert abs(t / float(t_ref) - 1) < 1e-10
    assert dynamics.final_angle(1e-17, 0.2, 100.0, 100.0, PAPER.L1) >= 0.2


# -- item 15 follow-up: rail friction with a small alpha0 (u = sin(alpha_F - phi) near -1) ---------------------

@pytest.mark.parametrize("F2", [7255.0, 3624.5, 512.0, 20000.0])
@pytest.mark.parametrize("a0", [1e-4, 3e-3])
def test_item15_small_alpha0_rail_friction_alpha_F_t_F_and_the_F1_0_end(F2, a0):
    """E_S = 0.1 J, F1 = 0: alpha_F (Eq. 8) and t_F to 1e-13 of the 30-digit reference, and identify / batch.identify
    return the F1 = 0 end for simulate's own output (cos(alpha_F - phi) = sin(alpha_F) was computed as
    sqrt((1 - u)(1 + u)) with 1 + u ~ 1e-6 rounded to an ulp: alpha_F and t_F 2e-11 to 3e-11 off, t_F 7e-12 below
    t_F(F1 = 0), outside the 4e-12 allowance)."""
    E, c = 0.1, 2 / 3
    t_ref, aF_ref, how, _ = mp_reference(E, a0, 0.0, F2, PAPER.m1, PAPER.m2, PAPER.L1, c)
    assert how == "friction"
    r = qr.simulate(E, a0, 0.0, F2, mass_model=c, n_points=2)
    b = batch.release(E, a0, 0.0, F2, c=c)
    with mp.workdps(30):
        for aF, tF in ((r.alpha_final, r.stop_time), (float(b.alpha_final), float(b.stop_time))):
            assert abs((mp.mpf(aF) - a0) / (aF_ref - a0) - 1) < 1e-13
            assert abs(mp.mpf(tF) / t_ref - 1) < 1e-13
    bi = batch.identify(a0, r.alpha_final, r.stop_time, E, c=c)
    assert int(bi.status) == 0 and float(bi.F1) == 0.0 and abs(float(bi.F2) / F2 - 1) < 1e-12
    ident = qr.identify_friction(a0, r.alpha_final, r.stop_time, stored_energy=E, mass_model=c)
    assert ident.boundary == "F1 = 0" and ident.F1 == 0.0 and abs(ident.F2 / F2 - 1) < 1e-12


def test_item15_stop_cosine_against_mpmath_where_u_is_near_minus_one():
    """cos(alpha_F - phi) to a few ulps of itself where 1 + u is tiny (Eq. 8 in 30 digits)."""
    rng = np.random.default_rng(15)
    worst = 0.0
    for _ in range(200):
        a0, E, F2 = 10 ** rng.uniform(-5, -1), 10 ** rng.uniform(-3, 1), 10 ** rng.uniform(1, 5)
        F1 = 0.0 if rng.random() < 0.5 else F2 * 10 ** rng.uniform(-6, -2)
        A, B = 2 * F1 * PAPER.L1, 4 * F2 * PAPER.L1
        R = math.hypot(A, B)
        if dynamics.limit_margin_terms(E, A, B, math.sin(a0), math.cos(a0)) > 0:
            continue
        got = float(dynamics.stop_cosine_terms(E, A, B, R, math.sin(a0), math.cos(a0)))
        with mp.workdps(30):
            phi = mp.atan2(B, A)
            u = mp.sin(mp.mpf(a0) - phi) + mp.mpf(E) / mp.hypot(A, B)
            ref = mp.sqrt(1 - u * u)
            worst = max(worst, abs(float(got / ref - 1)))
    assert worst < 1e-14


# -- item 18 (creep): F2 = 0 and E_S = W_F(pi/2) within rounding: the device creeps towards pi/2 ----------------

CREEP = (1.0, 1.5, 80.58123980909687, 0.0)  # E_S [J], alpha0 [rad], F1, F2 [N]: the float margin is exactly 0


def _creep_mp(E_S, alpha0, F1, dps=50):
    """(exact margin of the float inputs, rho, t_F(margin = +rho), t_F(exact margin), frictionless t) at dps digits.

    F2 = 0: E_S - W_F(alpha) = d + 2 A sin^2(x/2), x = pi/2 - alpha, d the margin (a hand step from Eq. 7); for
    d < 0 the stop is at sin(x_F/2) = sqrt(-d / (2A)) and the remaining energy 2 A cos(aF - y/2) sin(y/2)."""
    with mp.workdps(dps):
        E, a0, F1m, L1, m1, m2 = (mp.mpf(v) for v in (E_S, alpha0, F1, PAPER.L1, PAPER.m1, PAPER.m2))
        A, hp, c = 2 * F1m * L1, mp.pi / 2, mp.mpf(2) / 3

        def M(a):
            return m2 * L1**2 * (c * m1 / m2 + mp.sin(a) ** 2)

        def t_of(d):
            if d > 0:
                s = mp.sqrt(d / A)
                return mp.quad(lambda x: mp.sqrt(M(hp - x) / (d + 2 * A * mp.sin(x / 2) ** 2)), [0, s, 1e4 * s, hp - a0])
            aF = hp - 2 * mp.asin(mp.sqrt(-d / (2 * A)))
            return mp.quad(lambda y: mp.sqrt(M(aF - y) / (2 * A * mp.cos(aF - y / 2) * mp.sin(y / 2))),
                           [0, hp - aF, 1e4 * (hp - aF), aF - a0])

        margin = E - A * (1 - mp.sin(a0))
        rho = mp.mpf(dynamics.MARGIN_RTOL) * (2 * E - margin)  # of E_S + W_F(pi/2)
        t0 = mp.quad(lambda a: mp.sqrt(M(a) / E), [a0, hp])
        return margin, rho, t_of(rho), t_of(margin), t0


@pytest.mark.slow
def test_item18_creep_rule_justified_at_50_digits():
    """Why a margin within rho of 0 (F2 = 0) is reported as creeping: at 50 digits the float inputs' exact margin
    is inside the band (-3.7e-16 J, 21% of rho = 4 eps (E_S + W_F(pi/2)) = 1.8e-15 J), every t_F the band allows is
    >= 17 frictionless times (93.8 s; t_F(-rho) is the same to leading order), and the inputs' own t_F (98.0 s, a
    friction stop 1.4e-9 rad short of pi/2) lies in that range: a number set by 2 ulps of rounding of W_F(pi/2),
    not by the device (t_F -> inf as margin -> 0). (With the band of the naive 1 - sin(alpha0), 4 eps (E_S + A),
    this release's F1 was 31 ulps higher: margin -5.8e-15 J, now reported as the friction stop it is, 90.8 s.)"""
    E, a0, F1, _ = CREEP
    margin, rho, t_rho, t_true, t0 = _creep_mp(E, a0, F1)
    assert float(dynamics.limit_margin(E, a0, F1, 0.0, PAPER.L1)) == 0.0
    assert abs(margin) <= rho and margin != 0
    assert t_rho > 15 * t0 and t_true > t_rho
    fi = solvers.FirstIntegral(E, a0, F1, 0.0, PAPER.m1, PAPER.m2, PAPER.L1, 2 / 3)
    assert fi.horizon() < t_rho / 2  # the returned history ends well before any release of the band could
    # just outside the band (margin -100 rho): a determined friction stop, finite, and right to within what the
    # rounding of the margin allows (dt_F / dmargin = tau / (2 |margin|), tau ~ t0 here: a margin known to rho
    # moves t_F by t0 rho / (2 |margin| t_F) relatively, 3e-4 here; 5.9e-5 measured)
    F1_out = F1 * float(1 + 100 * rho / E)  # W_F(pi/2) above E_S by about 100 rho
    r = qr.simulate(E, a0, F1_out, 0.0, n_points=3)
    m_out, _, _, t_ref, _ = _creep_mp(E, a0, F1_out)
    assert r.stopped_by == "friction" and m_out < -10 * rho
    assert abs(r.stop_time / float(t_ref) - 1) < float(t0 * rho / (2 * abs(m_out) * t_ref))


@pytest.mark.parametrize("ulps", [0, -2, 3])
def test_item18_creep_every_method_agrees(ulps):
    """energy, rk, explicit, batch (compiled and numpy) and the scalar API: t_F = inf, alpha_F = pi/2, the reason,
    finite arrays; the returned history against an independent 30-digit integral of Eq. 10 with margin 0."""
    E, a0, F1, F2 = CREEP
    F1 += ulps * math.ulp(F1)  # the margin within a few ulps of 0: still inside the rounding band
    runs = {m: qr.simulate(E, a0, F1, F2, method=m, n_points=9, dt=1e-3) for m in ("energy", "rk", "explicit")}
    for m, r in runs.items():
        assert (r.stop_time, r.alpha_final, r.stopped_by) == (math.inf, math.pi / 2, "creeps_to_limit"), m
        for arr in (r.t, r.alpha, r.alpha_dot, r.alpha_ddot, r.u, r.v_ddot):
            assert np.all(np.isfinite(arr)), m
        assert np.all(np.diff(r.alpha) >= 0) and r.alpha[-1] < math.pi / 2 and r.summary()["stop_time_s"] is None
    en, rk = runs["energy"], runs["rk"]
    assert np.allclose(rk.t, en.t, rtol=1e-15) and np.max(np.abs(rk.alpha - en.alpha)) < 1e-9
    assert abs(en.alpha_dot[-1] / en.alpha_dot[0] - 1e-3) < 1e-3 * 0.05  # the horizon: E_K = 1e-6 E_S
    with mp.workdps(30):  # t(alpha_end) with E_S - W_F = A (1 - sin a) (margin 0, F2 = 0)
        A, L1, hp = 2 * mp.mpf(F1) * PAPER.L1, mp.mpf(PAPER.L1), mp.pi / 2
        x_end = hp - mp.mpf(float(en.alpha[-1]))
        t_ref = mp.quad(lambda x: mp.sqrt(PAPER.m2 * L1**2 * (mp.mpf(2) / 3 * PAPER.m1 / PAPER.m2 + mp.cos(x) ** 2)
                                          / (2 * A * mp.sin(x / 2) ** 2)), [x_end, 10 * x_end, hp - a0])
    assert abs(en.t[-1] / float(t_ref) - 1) < 1e-9
    assert qr.stop_time(E, a0, F1, F2) == math.inf
    assert dynamics.final_angle(E, a0, F1, F2, PAPER.L1) == math.pi / 2
    assert not dynamics.reaches_geometric_limit(E, a0, F1, F2, PAPER.L1)
    for out in (batch.stop_time(E, a0, F1, F2), batch.release(E, a0, F1, F2)):
        assert (float(out.stop_time), float(out.alpha_final), int(out.stopped_by)) == (math.inf, math.pi / 2, 2)
        assert batch.STOPPED_BY[2] == "creeps_to_limit"
    rel = batch.release(E, a0, F1, F2)
    assert int(rel.status) == 0 and all(np.isfinite(getattr(rel, k)) for k in ("u_final", "peak_u_ddot", "peak_v_ddot"))
    numpy_path = _kernels.Releases.build(*(np.array([v]) for v in (E, a0, F1, F2, 2 / 3 * PAPER.m1 / PAPER.m2,
                                                                    PAPER.m2, PAPER.L1)))
    assert int(numpy_path.regime[0]) == 2 and numpy_path.stop_time()[0] == math.inf
    # the compiled loop itself decides (not only its graded-tier fallback to numpy)
    t, aF, code = np.empty(1), np.empty(1), np.empty(1, dtype=np.int8)
    one = [np.array([v]) for v in (E, a0, F1, F2, 2 / 3 * PAPER.m1 / PAPER.m2, PAPER.m2, PAPER.L1)]
    batch._stop_chunk(*one, t, aF, code)  # the compiled loop (_fast.stop_kernel_sides) as batch calls it
    assert (int(code[0]), t[0], aF[0]) == (2, math.inf, math.pi / 2)


def test_item18_creep_needs_no_rail_friction():
    """With rail friction resolving the approach (B^2 >> 2 A rho) the margin-0 release arrives in finite time:
    the flat rhombus or a stop (rail friction decelerates it there), never inf."""
    E, a0, F1, _ = CREEP
    for F2 in (1e-3, 1.0):
        F1_0 = (E - 4 * F2 * PAPER.L1 * math.cos(a0)) / (2 * PAPER.L1 * (1 - math.sin(a0)))
        b = batch.stop_time(E, a0, F1_0, F2)
        r = qr.simulate(E, a0, F1_0, F2, n_points=2)
        assert int(b.stopped_by) in (0, 1) and math.isfinite(r.stop_time) and r.stopped_by != "creeps_to_limit"
        assert abs(float(b.stop_time) / r.stop_time - 1) < 1e-12


def test_item18_creep_cli_says_it_in_words():
    import json

    from typer.testing import CliRunner

    from quickrelease.cli import app

    args = ["simulate", "--energy", "1 J", "--alpha0", "1.5 rad", "--f1", "80.58123980909687 N", "--f2", "0 N"]
    out = CliRunner().invoke(app, [*args, "--json"])
    assert out.exit_code == 0, out.output
    summary = json.loads(out.output)
    assert summary["stop_time_s"] is None and summary["stopped_by"] == "creeps_to_limit"
    table = CliRunner().invoke(app, args)
    assert table.exit_code == 0 and "inf (never arrives)" in table.output and "never arrives" in table.output
    assert "nan" not in table.output.lower()


# -- items 12-16 follow-up: at the geometric limit (alpha0 and the stop within 1e-3 to 1e-8 rad of pi/2) ---------

def _near_limit_reference(E_S, alpha0, F1, F2, x_stop, c=2 / 3, dps=40):
    """(t_F, x_F = pi/2 - alpha_F, stopped_by) of the exact float inputs, in the distance x = pi/2 - alpha.

    Hand steps from Eq. 7: with x0 = pi/2 - alpha0, ``W_F(x) = A (cos x - cos x0) + B (sin x0 - sin x)
    = 2 sin((x0 - x)/2) (A sin((x0 + x)/2) + B cos((x0 + x)/2))`` (A = 2 F1 L1, B = 4 F2 L1), so the margin is
    ``E_S - 2 A sin^2(x0/2) - B sin(x0)``; a friction stop x_F solves W_F(x_F) = E_S (Newton from x_stop, the stop
    the case was built for), and ``E_S - W_F(x) = W_F(x_F) - W_F(x) = 2 sin((x - x_F)/2) (A sin((x + x_F)/2)
    + B cos((x + x_F)/2))``; at the limit ``E_S - W_F(x) = margin + 2 A sin^2(x/2) + B sin(x)``. Every term of one
    sign: 30 digits of t_F from 40 working digits (x0 = pi/2 - alpha0 itself costs up to 8 of them)."""
    with mp.workdps(dps):
        E, a0, F1, F2, m1, m2, L1, c = (mp.mpf(float(v)) for v in (E_S, alpha0, F1, F2, PAPER.m1, PAPER.m2,
                                                                    PAPER.L1, c))
        A, B, x0 = 2 * F1 * L1, 4 * F2 * L1, mp.pi / 2 - a0

        def M(x):  # Eq. 9 at alpha = pi/2 - x
            return m2 * L1**2 * (c * m1 / m2 + mp.cos(x) ** 2)

        def W(x):
            return 2 * mp.sin((x0 - x) / 2) * (A * mp.sin((x0 + x) / 2) + B * mp.cos((x0 + x) / 2))

        margin = E - 2 * A * mp.sin(x0 / 2) ** 2 - B * mp.sin(x0)
        if margin > 0:
            t = mp.quad(lambda x: mp.sqrt(M(x) / (margin + 2 * A * mp.sin(x / 2) ** 2 + B * mp.sin(x))), [0, x0])
            return t, mp.mpf(0), "geometric_limit"
        xF = mp.findroot(lambda x: W(x) - E, mp.mpf(x_stop))

        def f(s):  # y = x - xF = s^2 takes out the inverse square root at the stop: dt = 2 sqrt(M y / K(y)) ds
            y = s * s
            return 2 * mp.sqrt(M(xF + y) / (2 * mp.sin(y / 2) / y * (A * mp.sin(xF + y / 2) + B * mp.cos(xF + y / 2))))

        return mp.quad(f, [0, mp.sqrt(x0 - xF)]), xF, "friction"


def _near_limit_cases(k):
    """(kind, E_S, alpha0, F1, F2, x_stop) with alpha0 = pi/2 - 10^-k (its float) or 1.0, E_S rounded from the
    energy of the stop x_stop (W_F of Eq. 7 at 40 digits) or a multiple of W_F(pi/2)."""
    a0 = math.pi / 2 - 10.0**-k
    with mp.workdps(40):
        x0 = mp.pi / 2 - mp.mpf(a0)

        def W(x, F1, F2, x0=x0):
            return float(2 * mp.sin((x0 - x) / 2) * (2 * F1 * PAPER.L1 * mp.sin((x0 + x) / 2)
                                                     + 4 * F2 * PAPER.L1 * mp.cos((x0 + x) / 2)))

        return [("hinge (F2 = 0)", W(x0 / 2, 100.0, 0.0), a0, 100.0, 0.0, x0 / 2),
                ("rail (F1 = 0)", W(x0 / 2, 0.0, 100.0), a0, 0.0, 100.0, x0 / 2),
                ("both", W(x0 / 3, 100.0, 1.0), a0, 100.0, 1.0, x0 / 3),
                ("hinge, limit", 3 * W(0, 100.0, 0.0), a0, 100.0, 0.0, 0),
                ("rail, limit", 3 * W(0, 0.0, 100.0), a0, 0.0, 100.0, 0),
                ("rail from alpha0 = 1", W(10 * mp.mpf(10) ** -k, 0.0, 100.0, mp.pi / 2 - 1), 1.0, 0.0, 100.0,
                 10 * mp.mpf(10) ** -k)]


@pytest.mark.parametrize("k", [3, 4, 5, 6, 7, 8])
def test_near_the_geometric_limit_t_F_alpha_F_u_F_and_the_boundary_round_trip(k):
    """Stops within 10^-k rad of pi/2 (and releases from there to the flat rhombus): simulate and batch t_F to 1e-10
    of the reference (both reach 7e-16 or better), alpha_F to an ulp, u_F, v_F and the sweep to 1e-13.

    Before: 1 - sin(alpha0) kept the rounding of sin(alpha0), 1.1e-16, relative to itself (x0^2 / 2), and 1 - u that
    of u: F2 = 0 stops at x0 / 2 had t_F off by 1e-10, 1.7e-9, 2.6e-6, 2.6e-5 and 6.8e-3 for k = 3 to 7, and
    releases to the limit 1.8e-4 at k = 7; pi/2 - alpha0 was short by the 6.1e-17 rad of fl(pi/2) (u_F, t_F 6e-9 off
    at k = 8 with rail friction); the creep band 4 eps (E_S + A) took in every F2 = 0 release at k = 8; batch.identify
    rejected simulate's output at k = 3, 4, 5, 7 and identify at k = 5, 6, or returned F2 = 2.7e-12 to 2.9e-7 N. Now the round trip returns
    the boundary itself (F2 = 0 or F1 = 0 exactly), the other force F1* or F2* of the observed (rounded) alpha_F."""
    for kind, E, a0, F1, F2, x_stop in _near_limit_cases(k):
        t_ref, xF_ref, how = _near_limit_reference(E, a0, F1, F2, x_stop)
        r = qr.simulate(E, a0, F1, F2, n_points=2)
        b = batch.release(E, a0, F1, F2)
        assert r.stopped_by == how and batch.STOPPED_BY[int(b.stopped_by)] == how, (k, kind)
        with mp.workdps(40):
            x0 = mp.pi / 2 - mp.mpf(a0)
            aF_ref = mp.pi / 2 - xF_ref
            u_ref = 2 * PAPER.L1 * mp.cos((x0 + xF_ref) / 2) * mp.sin((x0 - xF_ref) / 2)  # L1 (cos a0 - cos aF)
            for t in (r.stop_time, float(b.stop_time)):
                assert abs(mp.mpf(t) / t_ref - 1) < 1e-10, (k, kind, t, t_ref)
            for aF in (r.alpha_final, float(b.alpha_final), dynamics.final_angle(E, a0, F1, F2, PAPER.L1)):
                assert abs(mp.mpf(aF) - aF_ref) <= math.ulp(math.pi / 2), (k, kind)
            v_ref = 2 * PAPER.L1 * mp.sin((x0 + xF_ref) / 2) * mp.sin((x0 - xF_ref) / 2)  # L1 (sin aF - sin a0)
            assert abs(mp.mpf(float(b.u_final)) / u_ref - 1) < 1e-13, (k, kind)
            assert abs(mp.mpf(float(b.v_final)) / v_ref - 1) < 1e-13, (k, kind)
            sweep = dynamics.sweep_angle(E, a0, F1, F2, PAPER.L1)
            assert abs(mp.mpf(sweep) / (x0 - xF_ref) - 1) < 1e-13, (k, kind)
        if how == "friction" and 0.0 in (F1, F2):
            end = "F2 = 0" if F2 == 0.0 else "F1 = 0"
            ident = qr.identify_friction(a0, r.alpha_final, r.stop_time, stored_energy=E)
            bi = batch.identify(a0, r.alpha_final, r.stop_time, E)
            assert ident.boundary == end and int(bi.status) == 0, (k, kind, bi.reasons())
            with mp.workdps(40):  # the other force is F1* (Eq. 11) or F2* (Eq. 12) of the observed, rounded alpha_F,
                aF = mp.mpf(r.alpha_final)  # off the true one by |aF - aF_ref| times the slope of Eq. 11 or 12
                if end == "F2 = 0":
                    star = E / (2 * PAPER.L1 * (mp.sin(aF) - mp.sin(a0)))
                    moved = abs(aF - aF_ref) * mp.cos(aF_ref) / (mp.sin(aF_ref) - mp.sin(a0))
                else:
                    star = E / (4 * PAPER.L1 * (mp.cos(a0) - mp.cos(aF)))
                    moved = abs(aF - aF_ref) * mp.sin(aF_ref) / (mp.cos(a0) - mp.cos(aF_ref))
                assert abs(star / max(F1, F2) - 1) <= 1.01 * moved + 1e-14, (k, kind)  # 1.5e-8 at k = 8
                for F1_id, F2_id in ((ident.F1, ident.F2), (float(bi.F1), float(bi.F2))):
                    assert (F1_id if end == "F1 = 0" else F2_id) == 0.0  # the boundary itself, not 8e-12 N beside it
                    assert abs(max(F1_id, F2_id) / star - 1) < 1e-12, (k, kind)


def test_fast_kernel_cache_flushed_when_the_modules_it_inlines_change(tmp_path):
    """numba stamps a cached kernel with its own source file only (since 0.6x by a sha256 of its content, so touching
    _fast.py, the earlier remedy, invalidated nothing: a stale stop_kernel then reported as creeping a release that
    the numpy path stopped by friction). _fast keeps the sha256 of dynamics.py and _kernels.py beside its cache and
    flushes the indexes of all its kernels when it differs."""
    import types

    from quickrelease.batch import _fast

    class Cache:
        cache_path = str(tmp_path)
        flushed = 0

        def flush(self):
            self.flushed += 1

    kernels = [types.SimpleNamespace(_cache=Cache()) for _ in range(3)]
    assert _fast._refresh_stale_cache(kernels, "sources 1")  # no stamp yet: flushed
    assert [k._cache.flushed for k in kernels] == [1, 1, 1]
    assert not _fast._refresh_stale_cache(kernels, "sources 1")  # unchanged: kept
    assert _fast._refresh_stale_cache(kernels, "sources 2") and [k._cache.flushed for k in kernels] == [2, 2, 2]
    # every kernel compiled from this file is covered, and the stamp of the installed cache is of today's sources
    own = {v for v in vars(_fast).values() if hasattr(v, "py_func") and v.py_func.__code__.co_filename == _fast.__file__}
    assert own and own <= set(_fast.KERNELS)
    with open(f"{_fast.stop_kernel_sides._cache.cache_path}/{_fast._STAMP_FILE}") as f:
        assert f.read() == _fast._dependency_stamp()
