"""The two case distributions of quickrelease.batch.sampling: valid, reproducible, and the wide one as documented."""

import numpy as np

from quickrelease import batch
from quickrelease.batch.sampling import WIDE_STRATA, random_releases, wide_releases


def _valid(cases):
    assert set(cases) >= {"E_S", "alpha0", "F1", "F2", "c", "m1", "m2", "L1"}
    for key, value in cases.items():
        assert np.all(np.isfinite(value)), key
    assert np.all(cases["E_S"] > 0) and np.all(cases["F1"] >= 0) and np.all(cases["F2"] >= 0)
    assert np.all(cases["alpha0"] > 0) and np.all(cases["alpha0"] < 0.5 * np.pi)


def test_both_samples_are_valid_and_seeded():
    for draw in (random_releases, wide_releases):
        a, b, c = draw(5000, seed=3), draw(5000, seed=3), draw(5000, seed=4)
        _valid(a)
        assert all(np.array_equal(a[k], b[k]) for k in a)
        assert not np.array_equal(a["E_S"], c["E_S"])


def test_the_wide_sample_covers_the_hard_corners_in_its_documented_shares():
    n = 40_000
    cases = wide_releases(n, seed=0, strata=True)
    stratum = cases.pop("stratum")
    _valid(cases)
    shares = np.bincount(stratum, minlength=len(WIDE_STRATA)) / n
    expected = np.array([s for _, s, _ in WIDE_STRATA])
    assert abs(expected.sum() - 1.0) < 1e-12
    assert np.all(np.abs(shares - expected) < 4.0 * np.sqrt(expected * (1 - expected) / n) + 1e-3)
    k = cases["c"] * cases["m1"] / cases["m2"]
    # the corners, from the cases themselves: mass factors over seven decades, releases within 1e-5 of pi/2,
    # the limit reached and missed by a hair, one force a trillionth of the other's scale
    assert k.min() < 1e-4 and k.max() > 1e3
    assert (0.5 * np.pi - cases["alpha0"]).min() < 1e-5 and cases["alpha0"].min() < 1e-3
    st = batch.stop_time(**cases)
    limit = st.stopped_by == 1
    assert 0.1 < limit.mean() < 0.4
    A, B = 2 * cases["F1"] * cases["L1"], 4 * cases["F2"] * cases["L1"]
    W_limit = A * (1 - np.sin(cases["alpha0"])) + B * np.cos(cases["alpha0"])
    margin = (cases["E_S"] - W_limit) / cases["E_S"]
    assert np.sum(limit & (margin < 1e-9)) > 10  # reaching pi/2 with a billionth of E_S to spare
    assert np.sum(~limit & (0.5 * np.pi - st.alpha_final < 1e-8)) > 10  # stops a hair short of pi/2
    sweep = (st.alpha_final - cases["alpha0"]) / (0.5 * np.pi - cases["alpha0"])
    assert np.sum(sweep < 1e-6) > 10  # nearly immediate stops
    ratio = np.minimum(A, B) / np.maximum(A, B)
    assert np.sum(ratio < 1e-9) > 10
