"""Batch kernels: agreement with the core solver, accuracy against mpmath, flags, broadcasting."""

import numpy as np
import pytest

from quickrelease import batch, simulate, stop_time
from quickrelease.batch.sampling import random_releases
from quickrelease.device import _kernels
from quickrelease.device.reference import identify_mp, stop_time_mp


@pytest.fixture(scope="module")
def cases():
    return random_releases(10_000, seed=11)


def _rk(cases, i, F1=None, F2=None):
    """The release of case i by the rk method (solve_ivp on Eq. 3-4 with a stop event): it knows nothing of
    the first integral and the Gauss time map the batch kernels share with FirstIntegral."""
    from quickrelease import Device

    dev = Device(m1=cases["m1"][i], m2=cases["m2"][i], L1=cases["L1"][i], L2=1, L3=1, L4=1, A1=1, A2=1, A3=1, A4=1,
                 I2=1, E=1, G=1, kappa=1)
    return simulate(cases["E_S"][i], cases["alpha0"][i], cases["F1"][i] if F1 is None else F1,
                    cases["F2"][i] if F2 is None else F2, device=dev, mass_model=cases["c"][i], method="rk")


@pytest.mark.slow
def test_agrees_with_rk_on_200_of_10000_cases(cases):
    """t_F, alpha_F and the stop's kind against the rk solver on every 50th case (41 of them reach pi/2); the
    rk tolerances put its t_F within ~4e-10 of the truth (mpmath below checks the kernels to 1e-12)."""
    r = batch.stop_time(**cases)
    assert (r.stopped_by == 1).mean() == pytest.approx(0.15, abs=0.02)
    for i in range(0, 10_000, 50):
        s = _rk(cases, i)
        assert r.stop_time[i] == pytest.approx(s.stop_time, rel=2e-9), i
        assert r.alpha_final[i] == pytest.approx(s.alpha_final, abs=1e-9), i
        assert (r.stopped_by[i] == 1) == (s.stopped_by == "geometric_limit"), i


def test_identification_round_trip_through_rk(cases):
    sub = {key: v[:300] for key, v in cases.items()}
    st = batch.stop_time(**sub)
    fr = st.stopped_by == 0
    ident = batch.identify(sub["alpha0"][fr], st.alpha_final[fr], st.stop_time[fr], sub["E_S"][fr], sub["c"][fr],
                           sub["m1"][fr], sub["m2"][fr], sub["L1"][fr])
    assert np.all(ident.status == 0)
    # the identified pair, released by rk, stops where and when the observations say
    for j, i in enumerate(np.nonzero(fr)[0][:60]):
        s = _rk(sub, i, ident.F1[j], ident.F2[j])
        assert s.stop_time == pytest.approx(st.stop_time[i], rel=2e-9)
        assert s.alpha_final == pytest.approx(st.alpha_final[i], abs=1e-9)
    # and the round trip: the friction that produced the stop comes back
    err = np.maximum(np.abs(ident.F1 - sub["F1"][fr]) / ident.F1_max, np.abs(ident.F2 - sub["F2"][fr]) / ident.F2_max)
    assert np.median(err) < 1e-13 and np.max(err) < 1e-9


def test_stop_time_against_mpmath():
    cases = random_releases(20, seed=5)
    r = batch.stop_time(**cases)
    k = cases["c"] * cases["m1"] / cases["m2"]
    ref = np.array([stop_time_mp(cases["E_S"][i], cases["alpha0"][i], cases["F1"][i], cases["F2"][i], k[i],
                                 cases["m2"][i], cases["L1"][i])[0] for i in range(20)])
    err = np.abs(r.stop_time / ref - 1)
    assert np.median(err) < 1e-14 and np.max(err) < 1e-12


def test_identify_against_mpmath():
    cases = random_releases(3, seed=9, limit_share=0.0)
    st = batch.stop_time(**cases)
    k = cases["c"] * cases["m1"] / cases["m2"]
    ident = batch.identify(cases["alpha0"], st.alpha_final, st.stop_time, cases["E_S"], cases["c"], cases["m1"],
                           cases["m2"], cases["L1"])
    for i in range(3):
        F1, F2 = identify_mp(cases["alpha0"][i], st.alpha_final[i], st.stop_time[i], cases["E_S"][i], k[i],
                             cases["m2"][i], cases["L1"][i])
        assert abs(ident.F1[i] - F1) <= 1e-12 * ident.F1_max[i]
        assert abs(ident.F2[i] - F2) <= 1e-12 * ident.F2_max[i]


def test_compiled_and_numpy_kernels_agree(cases):
    """_fast fuses the formulas of _kernels: the two give the same numbers case by case."""
    sub = {key: v[:2000] for key, v in cases.items()}
    k = sub["c"] * sub["m1"] / sub["m2"]
    rel = _kernels.Releases.build(sub["E_S"], sub["alpha0"], sub["F1"], sub["F2"], k, sub["m2"], sub["L1"])
    t_np = rel.stop_time()
    n = k.size
    t, aF, code = np.empty(n), np.empty(n), np.empty(n, dtype=np.int8)
    batch._stop_chunk(sub["E_S"], sub["alpha0"], sub["F1"], sub["F2"], k, sub["m2"], sub["L1"], t, aF, code)
    assert np.all(code == rel.regime) and np.any(rel.tier == 2)  # every tier compiled, the graded one included
    assert np.max(np.abs(t / t_np - 1)) < 1e-14
    assert np.max(np.abs(aF - rel.alpha_final)) < 1e-15


def test_near_the_geometric_limit_accuracy_follows_the_conditioning():
    """Stops within ~1e-6 rad of pi/2 with almost no rail friction: t_F moves by up to 1e-6 when one input
    moves by one ulp (the difference E_S - W_F(pi/2) is ill-conditioned); the kernel stays within that."""
    E, a0, F1, F2, k, m2, L1 = 2496.7064827214417, 0.9878228096162034, 2737.145215750118, 0.0005289992104389708, \
        0.2508887330655966, 1839.7073266913917, 2.76125386875275
    t = batch.stop_time(E, a0, F1, F2, k, m2, m2, L1)  # c = k with m1 = m2
    ref = stop_time_mp(E, a0, F1, F2, k, m2, L1)[0]
    sens = abs(stop_time_mp(np.nextafter(E, np.inf), a0, F1, F2, k, m2, L1)[0] / ref - 1)
    assert sens > 1e-7  # ill-conditioned indeed
    assert abs(float(t.stop_time) / ref - 1) < 4 * sens


def test_release_envelope_matches_simulate():
    r = batch.release(2900.0, 0.2, 419.85, 804.57)
    s = simulate(2900.0, 0.2, 419.85, 804.57, method="rk", n_points=20001).summary()
    assert float(r.u_final) == pytest.approx(s["u_final_m"], rel=1e-9)
    assert float(r.v_final) == pytest.approx(s["v_final_m"], rel=1e-9)
    assert float(r.peak_v_dot) == pytest.approx(s["peak_v_dot_m_s"], rel=1e-12)
    # the kernel's peak is the true maximum; the sampled one is below it, by less than the sampling step allows
    assert float(r.peak_u_dot) >= s["peak_u_dot_m_s"]
    assert float(r.peak_u_dot) == pytest.approx(s["peak_u_dot_m_s"], rel=1e-8)
    assert float(r.stop_time) == pytest.approx(stop_time(2900.0, 0.2, 419.85, 804.57), rel=1e-14)


def test_broadcasting_and_shapes():
    P = np.linspace(1000, 3000, 5)[:, None]
    a0 = np.array([0.15, 0.2, 0.25])[None, :]
    r = batch.release(P, a0, 400.0, 800.0)
    assert r.stop_time.shape == (5, 3) and r.peak_u_dot.shape == (5, 3)
    assert np.all(np.diff(r.stop_time, axis=0) > 0)  # more energy, longer release
    df = r.to_pandas()
    assert len(df) == 15 and "u_final" in df


def test_infeasible_cases_are_flagged_not_dropped():
    ident = batch.identify([0.2, 0.2, 0.2, 0.8, 0.2, np.nan, 1.7], [0.7378, 0.7378, 0.7378, 0.7, 1.6, 0.5, 1.0],
                           [0.9, 1.05, 1.3, 1.0, 1.0, 1.0, 1.0], 2900.0)
    assert ident.status.tolist() == [1, 0, 2, 3, 3, 5, 4]
    assert np.isnan(ident.F1[[0, 2, 3, 4, 5, 6]]).all() and np.isfinite(ident.F1[1])
    assert ident.stop_time_min[0] == pytest.approx(0.990644, abs=1e-6) and ident.stop_time_max[2] == pytest.approx(
        1.213893, abs=1e-6)
    assert ident.reasons()["ok"] == 1
    assert "faster than any friction" in batch.IDENTIFY_STATUS[1]


def test_peak_accelerations_against_dense_single_releases():
    """Peak |u_ddot|, |v_ddot| of the batch kernel: the compiled loop equals its numpy reference, and both
    match the maximum over a 100,001-sample single release to 1e-4."""
    from quickrelease import preset, simulate
    from quickrelease.batch.sampling import random_releases

    cases = random_releases(40, seed=21)
    r = batch.release(**cases)
    k = cases["c"] * cases["m1"] / cases["m2"]
    pu, pv = batch._peak_accelerations(cases["E_S"], cases["alpha0"], r.alpha_final, cases["F1"], cases["F2"], k,
                                       cases["m2"], cases["L1"])
    np.testing.assert_allclose(r.peak_u_ddot, pu, rtol=1e-11)
    np.testing.assert_allclose(r.peak_v_ddot, pv, rtol=1e-11)
    for i in range(0, 40, 4):
        a = {key: float(v[i]) for key, v in cases.items()}
        d = preset("paper").replace(m1=a["m1"], m2=a["m2"], L1=a["L1"])
        s = simulate(a["E_S"], a["alpha0"], a["F1"], a["F2"], device=d, mass_model=a["c"], n_points=100001).summary()
        assert r.peak_u_ddot[i] == pytest.approx(s["peak_u_ddot_m_s2"], rel=1e-4)
        assert r.peak_v_ddot[i] == pytest.approx(s["peak_v_ddot_m_s2"], rel=1e-4)


def test_read_only_inputs_are_copied_not_compiled_for_again():
    """Read-only arrays (np.broadcast_to views, read-only memory maps, another library's frozen arrays) give the
    results of writeable copies, bit for bit, and no kernel compiled for them: a read-only array is another type to
    numba, and a second compilation of the stop-time kernel cost ~4 s (the first call of each kernel here compiles
    it when the cache is cold, once, for writeable arrays)."""
    from quickrelease.batch import _fast

    cases = random_releases(40, seed=4)
    frozen = {key: np.broadcast_to(np.asarray(v, float), (40,)) for key, v in cases.items()}
    assert not any(a.flags.writeable for a in frozen.values())
    st, st_w = batch.stop_time(**frozen), batch.stop_time(**cases)
    assert np.array_equal(st.stop_time, st_w.stop_time) and np.array_equal(st.alpha_final, st_w.alpha_final)
    fr = st.stopped_by == 0
    args = [np.broadcast_to(v[fr], (fr.sum(),)) for v in (cases["alpha0"], st.alpha_final, st.stop_time, cases["E_S"],
                                                          cases["c"], cases["m1"], cases["m2"], cases["L1"])]
    ident = batch.identify(*args)
    ident_w = batch.identify(*(v.copy() for v in args))
    assert np.array_equal(ident.F1, ident_w.F1, equal_nan=True) and np.array_equal(ident.F2, ident_w.F2, equal_nan=True)
    assert np.all(ident.status == 0)
    for kernel in (_fast.stop_kernel_sides, _fast.identify_kernel):  # their first seven arguments: the cases'
        read_only = [sig[:7] for sig in kernel.signatures if not all(a.mutable for a in sig[:7])]
        assert kernel.signatures and not read_only, (kernel, read_only)
