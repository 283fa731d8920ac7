"""The vectorised stop-time setup (:func:`quickrelease.batch._fast.stop_kernel_sides`) and what it relies on.

* the block kernel gives, case by case and bit for bit, what the one-case loop ``_fast._stop_one`` gives (the
  vectorised setup computes both regimes and selects one: a wrong select, a row mixed up or a case left out of the
  scalar path shows as a difference), on the bench and wide samples and on cases built to sit on every branch;
* the compiled loop's sin and cos (libm's, called opaquely) round as numpy's ``sin`` and ``cos``, which the
  single-case solver calls: the same alpha0 terms on every path;
* ``dynamics.amplitude_terms`` (R = sqrt(A^2 + B^2), the library's hypot) within one ulp of mpmath from subnormal
  to 1e300 inputs, and the same bits in numpy and compiled.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from numba import njit

from quickrelease import batch
from quickrelease.batch import _fast
from quickrelease.batch.sampling import random_releases, wide_releases
from quickrelease.device import dynamics

ARGS = ("E_S", "alpha0", "F1", "F2", "k", "m2", "L1")


def _cases(draw) -> dict[str, np.ndarray]:
    n = draw["E_S"].size
    out = {key: np.ascontiguousarray(np.broadcast_to(np.asarray(draw[key], float), (n,))) for key in
           ("E_S", "alpha0", "F1", "F2", "m2", "L1")}
    out["k"] = np.broadcast_to(draw["c"] * draw["m1"] / draw["m2"], (n,)).astype(float)
    return out


def _edge_cases() -> dict[str, np.ndarray]:
    """Releases on every branch of the setup: the limit reached with room and barely, a stop at pi/2 within
    rounding (the scalar path), creeping (no rail friction, margin 0 within rounding), pure hinge and pure rail
    friction, nearly immediate stops, alpha0 near 0 and near pi/2, huge and subnormal forces."""
    L1, m2, k = 2.0, 1500.0, 0.2
    rows = []
    for a0 in (1e-6, 0.05, 0.7, 1.2, math.pi / 2 - 1e-7):
        for F1, F2 in ((1e4, 0.0), (0.0, 1e4), (3e4, 2e4), (1e300, 1e300), (5e-324, 0.0)):
            W = dynamics.dissipation_at_limit(a0, F1, F2, L1)
            for E in (W * (1 + 1e-3), W * (1 + 1e-15), W, W * (1 - 1e-15), W * (1 - 1e-12), W * (1 - 3e-11),
                      W * (1 - 1e-10), W * (1 - 1e-9), W * 0.5, W * 1e-9, 1.0):
                if np.isfinite(E) and E > 0:
                    rows.append((E, a0, F1, F2, k, m2, L1))
    a = np.array(rows)
    c = {key: np.ascontiguousarray(a[:, i]) for i, key in enumerate(ARGS)}
    # as batch hands them to the kernel: negligible friction 0, cases beyond the float range out
    c["F1"], c["F2"], c["E_S"], bad = batch._screen(c["E_S"], c["F1"], c["F2"], c["L1"])
    return {key: np.ascontiguousarray(v[~bad]) for key, v in c.items()}


def _one_by_one(c):
    t = np.empty(c["E_S"].size)
    aF, N, D = np.empty_like(t), np.empty_like(t), np.empty_like(t)
    code = np.empty(t.size, dtype=np.int8)
    x16, w16, x24, w24 = _fast.rules()
    near, hard, msq, mhard = _fast.tier_constants()
    from quickrelease.device import _kernels

    for i in range(t.size):
        s, co = math.sin(c["alpha0"][i]), math.cos(c["alpha0"][i])
        t[i], aF[i], code[i], _, N[i], D[i] = _fast._stop_one(
            c["E_S"][i], s, co, c["alpha0"][i], c["F1"][i], c["F2"][i], c["k"][i], c["m2"][i], c["L1"][i], x16, w16,
            x24, w24, near, hard, msq, mhard, _kernels.GRADING, _fast.GRADED_REACH, _kernels.N_PANELS)
    return t, aF, N, D, code


@pytest.mark.slow
@pytest.mark.parametrize("source", ["bench", "wide", "edges"])
def test_block_kernel_is_the_one_case_loop_bit_for_bit(source):
    if source == "bench":
        c = _cases(random_releases(3000, seed=5))
    elif source == "wide":
        c = _cases(wide_releases(3000, seed=5))
    else:
        c = _edge_cases()
    n = c["E_S"].size
    t, aF, N, D = (np.empty(n) for _ in range(4))
    code = np.empty(n, dtype=np.int8)
    _fast.stop_kernel_sides(*(c[key] for key in ARGS), *_fast.rules(), *_fast.tier_constants(), t, aF, N, D, code)
    t1, aF1, N1, D1, code1 = _one_by_one(c)
    assert np.array_equal(code, code1)
    for got, want in ((t, t1), (aF, aF1), (N, N1), (D, D1)):
        assert np.array_equal(got, want, equal_nan=True), np.flatnonzero(~((got == want) | np.isnan(want)))[:5]
    if source == "edges":  # every regime is there, and the scalar path (creeping, a stop at pi/2) was taken
        assert set(np.unique(code)) == {0, 1, 2}


def test_libm_sine_and_cosine_are_numpys():
    """The kernel's sin and cos (libm's, called opaquely: never vectorised, so never Intel's SVML) round as numpy's."""

    @njit
    def sincos(x, s, c):
        for i in range(x.size):
            s[i], c[i] = _fast._libm_sincos(x[i])

    rng = np.random.default_rng(3)
    x = np.concatenate([rng.uniform(0.0, math.pi / 2, 200_000), np.geomspace(1e-300, 1e-2, 2000),
                        math.pi / 2 - np.geomspace(1e-16, 1e-2, 2000)])
    s, c = np.empty_like(x), np.empty_like(x)
    sincos(x, s, c)
    assert np.array_equal(s, np.sin(x)) and np.array_equal(c, np.cos(x))

    @njit
    def sine(x, s):
        for i in range(x.size):
            s[i] = _fast._libm_sin(x[i])

    sine(x, s)  # the limit's sin((pi/2 - alpha0) / 2) of the setup
    assert np.array_equal(s, np.sin(x))


def test_amplitude_within_an_ulp_of_mpmath_from_subnormal_to_huge():
    rng = np.random.default_rng(4)
    A = 10.0 ** rng.uniform(-320, 300, 3000)
    B = A * 10.0 ** rng.uniform(-30, 8, 3000)
    A = np.concatenate([A, [0.0, 5e-324, 1e300, 3.0, 0.0, 2.0**500, 2.0**-500]])
    B = np.concatenate([B, [0.0, 5e-324, 1e300, 4.0, 7.0, 2.0**500, 2.0**-500]])
    with np.errstate(all="ignore"):
        R = dynamics.amplitude_terms(A, B)
    compiled = np.array([_fast._amplitude(a, b) for a, b in zip(A, B, strict=True)])
    assert np.array_equal(R, compiled)
    assert R[-7] == 0.0 and R[-4] == 5.0 and R[-3] == 7.0
    mpmath.mp.prec = 120
    for a, b, r in zip(A, B, R, strict=True):
        exact = mpmath.sqrt(mpmath.mpf(float(a)) ** 2 + mpmath.mpf(float(b)) ** 2)
        if exact == 0:
            assert r == 0.0
            continue
        if exact < mpmath.mpf(2.0) ** -1022:  # a subnormal result: within half its ulp (2^-1075) absolutely
            assert abs(mpmath.mpf(float(r)) - exact) <= mpmath.mpf(2.0) ** -1074
            continue
        assert abs(mpmath.mpf(float(r)) - exact) / exact <= 2.0**-52, (a, b)


def test_batch_angle_is_the_single_case_solvers_bit_for_bit():
    c = _cases(wide_releases(2000, seed=6))
    st = batch.stop_time(c["E_S"], c["alpha0"], c["F1"], c["F2"], 1.0, c["k"], 1.0, c["L1"])
    with np.errstate(all="ignore"):
        want = dynamics.final_angle(c["E_S"], c["alpha0"], c["F1"], c["F2"], c["L1"])
    assert np.array_equal(st.alpha_final, want)


@pytest.mark.parametrize("F", [1e30, 1e150, 1e300])
def test_huge_friction_stops_at_once_as_constant_deceleration(F):
    """E_S = 1 J against friction of up to 1e300 N: the sweep is ~1e-300 rad, over which the friction work is
    ``G x`` with ``G = A cos(alpha0) + B sin(alpha0)`` and the mass M(alpha0) constant, so
    ``t_F = 2 sqrt(M E_S) / G`` (Eq. 10 integrated by hand). Before the setup had numpy's error model, the square of
    the half sweep underflowed and the kernel raised ZeroDivisionError (a traceback from ``batch.stop_time``)."""
    m1, m2, L1 = batch._paper_defaults(None, None, None)
    k = 2.0 / 3.0 * m1 / m2
    a0 = 0.7
    G = 2.0 * F * L1 * math.cos(a0) + 4.0 * F * L1 * math.sin(a0)
    t = 2.0 * math.sqrt(m2 * L1**2 * (k + math.sin(a0) ** 2)) * math.sqrt(1.0) / G
    st = batch.stop_time(1.0, a0, F, F)
    assert float(st.stop_time) == pytest.approx(t, rel=1e-14) and float(st.alpha_final) == a0


@pytest.mark.slow
def test_cases_out_of_range_come_back_nan_and_leave_the_others_alone():
    """E_S not positive and finite, or friction whose work overflows (2 F1 L1 = inf), is out of range: t_F and
    alpha_F NaN, chunk by chunk on the threads (``batch._screened_chunk``), the valid cases beside them as alone."""
    good = _cases(random_releases(40, seed=8))
    E, F1 = good["E_S"].copy(), good["F1"].copy()
    E[[1, 5, 9, 13]] = [0.0, -1.0, np.nan, np.inf]
    F1[17] = 1e308  # 2 F1 L1 overflows
    st = batch.stop_time(E, good["alpha0"], F1, good["F2"], 1.0, good["k"], 1.0, good["L1"])
    out = np.zeros(40, dtype=bool)
    out[[1, 5, 9, 13, 17]] = True
    assert np.all(np.isnan(st.stop_time[out])) and np.all(np.isnan(st.alpha_final[out]))
    alone = batch.stop_time(good["E_S"][~out], good["alpha0"][~out], good["F1"][~out], good["F2"][~out], 1.0,
                            good["k"][~out], 1.0, good["L1"][~out])
    assert np.array_equal(st.stop_time[~out], alone.stop_time) and np.array_equal(st.alpha_final[~out],
                                                                                  alone.alpha_final)
