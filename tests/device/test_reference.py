"""The mpmath references (reference.py) against independent mpmath computations written here: the integral in
alpha itself (tanh-sinh over [alpha0, alpha_F], no substitution), the stop by its own root finder, and F1 as the
root of that integral by a bracketing solver, at more digits."""

import mpmath
import numpy as np
import pytest

from quickrelease.batch.sampling import WIDE_STRATA, wide_releases
from quickrelease.device.reference import identify_lambda_mp, identify_mp, stop_time_mp


def _w(a, a0, A, B):
    return A * (mpmath.sin(a) - mpmath.sin(a0)) + B * (mpmath.cos(a0) - mpmath.cos(a))


def _t_direct(E, a0, A, B, k, m2, L1, end):
    """Eq. 10 in alpha over [alpha0, end]; at a friction stop E_S - W_F(alpha) = W_F(end) - W_F(alpha) by
    sum-to-product (the integrand keeps its digits where tanh-sinh crowds its nodes), else E_S - W_F(alpha)."""
    friction_stop = end < mpmath.pi / 2

    def f(a):
        if friction_stop:
            m = (end + a) / 2
            rest = 2 * mpmath.sin((end - a) / 2) * (A * mpmath.cos(m) + B * mpmath.sin(m))
        else:
            rest = E - _w(a, a0, A, B)
        return mpmath.sqrt(m2 * L1**2 * (k + mpmath.sin(a) ** 2) / rest) if rest > 0 else mpmath.mpf(0)

    return mpmath.quad(f, [a0, end])


def _independent_stop(E_S, alpha0, F1, F2, k, m2, L1, dps=40):
    with mpmath.workdps(dps):
        E, a0, F1, F2, k, m2, L1 = (mpmath.mpf(float(x)) for x in (E_S, alpha0, F1, F2, k, m2, L1))
        A, B = 2 * F1 * L1, 4 * F2 * L1
        top = mpmath.pi / 2
        end = top if E > _w(top, a0, A, B) else mpmath.findroot(lambda a: _w(a, a0, A, B) - E, (a0, top),
                                                                solver="illinois")
        return _t_direct(E, a0, A, B, k, m2, L1, end), end


def _cases(per_stratum, seed=3, friction_stop=None):
    s = wide_releases(4000, seed=seed, strata=True)
    W_top = 2 * s["F1"] * s["L1"] * (1 - np.sin(s["alpha0"])) + 4 * s["F2"] * s["L1"] * np.cos(s["alpha0"])
    stops = s["E_S"] < W_top
    out = []
    for j, (name, _, _) in enumerate(WIDE_STRATA):
        pick = s["stratum"] == j
        if friction_stop is not None:
            pick &= stops if friction_stop else ~stops
        for i in np.flatnonzero(pick)[:per_stratum]:
            out.append((name, tuple(float(s[x][i]) for x in ("E_S", "alpha0", "F1", "F2")) +
                        (float(s["c"][i] * s["m1"][i] / s["m2"][i]), float(s["m2"][i]), float(s["L1"][i]))))
    return out


@pytest.mark.parametrize("name,case", _cases(1))
def test_stop_time_mp_against_the_integral_in_alpha(name, case):
    """Every stratum of the wide sample (limit reached, missed by a hair, small mass factors...): the 30-digit
    reference agrees with a 40-digit computation written independently to its rounding to double."""
    t, aF = stop_time_mp(*case)
    ref, end = _independent_stop(*case)
    assert abs(t / ref - 1) <= 1.2e-16, name
    assert abs(aF - end) <= 1.2e-16 * end, name


def _independent_lambda(alpha0, aF, tF, E_S, k, m2, L1, dps=45):
    """lambda = F1/F1* (Eq. 11-13) with t(lambda) = t_F, by a bracketing solver (Illinois) on [0, 1]. The integral
    in alpha loses digits next to the stop (the nodes themselves are rounded there): 45 digits give about 20."""
    with mpmath.workdps(dps):
        a0, aF, tF, E, k, m2, L1 = (mpmath.mpf(float(x)) for x in (alpha0, aF, tF, E_S, k, m2, L1))
        F1s = E / (2 * L1 * (mpmath.sin(aF) - mpmath.sin(a0)))
        F2s = E / (4 * L1 * (mpmath.cos(a0) - mpmath.cos(aF)))
        return mpmath.findroot(lambda lam: _t_direct(E, a0, 2 * lam * F1s * L1, 4 * (1 - lam) * F2s * L1, k, m2, L1,
                                                     aF) - tF, (mpmath.mpf(0), mpmath.mpf(1)), solver="illinois",
                               tol=mpmath.mpf(10) ** -60, verify=False)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["typical", "one force near zero"])
def test_identify_mp_against_a_bracketed_root_of_the_integral_in_alpha(name):
    E_S, alpha0, F1, F2, k, m2, L1 = next(c for n, c in _cases(1, friction_stop=True) if n == name)
    tF, aF = stop_time_mp(E_S, alpha0, F1, F2, k, m2, L1)
    obs = (alpha0, aF, tF, E_S, k, m2, L1)
    ref = _independent_lambda(*obs)
    lam, F1s, F2s = identify_lambda_mp(*obs)
    assert abs(lam - ref) < 1e-20, name
    # from a start near the root (the kernels' answer, say) or far from it: the same root to the tolerance
    for start in (float(ref * F1s) * (1 + 1e-13), 0.3 * float(F1s)):
        assert abs(identify_lambda_mp(*obs, start=start)[0] - ref) < 1e-20, (name, start)
    F1_id, F2_id = identify_mp(*obs, start=F1)
    assert abs(F1_id - float(ref * F1s)) <= 1.2e-16 * float(F1s)
    assert abs(F2_id - float((1 - ref) * F2s)) <= 1.2e-16 * float(F2s)
    # and the round trip to the friction that produced the stop, within what t_F's rounding allows
    assert abs(F1_id - F1) < 1e-11 * float(F1s) and abs(F2_id - F2) < 1e-11 * float(F2s)
