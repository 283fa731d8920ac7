"""The record fit's streamed stages (issue 9, item 11): a long record is fitted in chunks of rows, with the
solver on the QR-compressed system, and gives the dense fit's answer (estimates, covariance, chi-square)."""

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

from quickrelease._lsq import jacobian_covariance
from quickrelease.io.case import load_case
from quickrelease.studies import fit
from quickrelease.studies.fit import _Problem, _start, fit_record
from quickrelease.studies.synth import synthesize

EXAMPLES = Path(__file__).parents[2] / "examples"


@pytest.fixture(scope="module")
def paper():
    return load_case(EXAMPLES / "paper.toml")


@pytest.fixture(scope="module")
def problem(paper):
    """5,001 rows (2,387 of them within the motion: the channel table is used), u, v and the head
    acceleration with 2% of the samples missing (the channels' rows differ), offsets, the release estimated."""
    syn = synthesize(paper, ["u", "v", "a_head"], rate=2500.0, duration=2.0, offsets={"u": 1e-3, "v": -2e-3},
                     release_time=0.43, seed=3, missing=0.02)
    prob = _Problem(paper, syn.record(), paper.fit)
    x, _ = _start(prob)
    x[0] *= 1.05  # away from the optimum: residuals and Jacobian of a fit under way
    lower = np.full(x.size, -np.inf)
    upper = np.full(x.size, np.inf)
    lower[:2] = 0.0
    return prob, x, lower, upper


def dense(prob, x, lower, upper):
    """[r, J] as the dense path's solver forms them at x (least_squares stopped before its first step)."""
    res = least_squares(prob.residuals, x, bounds=(lower, upper), method="trf", max_nfev=1)
    assert np.array_equal(res.x, x)
    return np.column_stack([res.fun, res.jac])


def assert_same_system(R, A, tol):
    """R^T R = A^T A, each entry to ``tol`` of sqrt(A_ii A_jj) (the scale-free comparison)."""
    assert R.shape == (A.shape[1], A.shape[1])
    assert np.all(np.diag(R) >= 0.0)
    assert np.allclose(np.triu(R), R, rtol=0, atol=0)
    G, H = A.T @ A, R.T @ R
    scale = np.sqrt(np.outer(np.diag(G), np.diag(G)))
    assert np.max(np.abs(H - G) / scale) < tol


@pytest.mark.parametrize("chunk", [7, 5001, 10**6])
def test_compressed_system_is_the_dense_one(problem, chunk):
    """Chunks of 7 rows (the last one partial: 5001 = 714 x 7 + 3), exactly the rows, more than the rows."""
    prob, x, lower, upper = problem
    A = dense(prob, x, lower, upper)
    prob.chunk = chunk
    R = prob.compressed(x, lower, upper)
    assert_same_system(R, A, 1e-12)
    r = A[:, 0]
    assert R[0, 0] ** 2 == pytest.approx(r @ r, rel=1e-12)  # the chi-square
    assert prob.cost(x) == pytest.approx(r @ r, rel=1e-12)
    assert np.allclose(R[0, 0] * R[0, 1:], A[:, 1:].T @ r, rtol=1e-10, atol=1e-12 * np.abs(r) @ np.abs(A[:, 1:]))
    cov_dense, cov = jacobian_covariance(A[:, 1:]), jacobian_covariance(R[:, 1:])
    assert np.max(np.abs(cov - cov_dense) / np.sqrt(np.outer(np.diag(cov_dense), np.diag(cov_dense)))) < 1e-10


def test_chunks_of_one_row(paper):
    """One row per chunk (5 parameters: F1, F2, release instant, offset of u), on a short record with missing
    samples (chunks without a sample of a channel, or without any)."""
    syn = synthesize(paper, ["u", "a_head"], rate=25.0, duration=2.0, offsets={"u": 1e-3}, release_time=0.43, seed=4,
                     missing=0.1)
    prob = _Problem(paper, syn.record(), paper.fit)
    x, _ = _start(prob)
    lower, upper = np.full(x.size, -np.inf), np.full(x.size, np.inf)
    A = dense(prob, x, lower, upper)
    prob.chunk = 1
    assert_same_system(prob.compressed(x, lower, upper), A, 1e-12)


def test_chunks_in_a_coarse_stage(problem):
    """The decimated rows and widened window of a coarse stage (every 6th sample of each channel)."""
    prob, x, lower, upper = problem
    try:
        prob.smooth(12.1 * prob.window)
        A = dense(prob, x, lower, upper)
        assert A.shape[0] == prob.size() and prob.rows() < 3000
        prob.chunk = 500
        assert_same_system(prob.compressed(x, lower, upper), A, 1e-12)
    finally:
        prob.smooth(0.0)


@pytest.mark.slow
def test_streamed_fit_is_where_the_dense_fit_ends(paper, problem, monkeypatch):
    """A whole fit with every stage streamed (chunks of 1,000 rows), then the dense solver (every residual,
    least_squares' own Jacobian) started at its estimates: it stays there (within 1e-5 standard errors), and
    its covariance and chi-square are the streamed fit's. The bound 1e-5 is the dense fit's own
    reproducibility: rounding alone moves it (from a start 1 ulp away, a 1e4-row fit moves by 3.6e-7 SE and its
    standard errors by 2.8e-7 relative), and its termination test (ftol 1e-12) would allow 1e-4 SE."""
    prob, _, _, _ = problem
    monkeypatch.setattr(fit, "FIT_CHUNK_ROWS", 1000)
    got = fit_record(paper, prob.record)
    assert got.converged and got.names == tuple(prob.names)
    x = np.array([got.estimates[n] for n in got.names])
    lower, upper = np.full(x.size, -np.inf), np.full(x.size, np.inf)
    lower[:2] = 0.0
    lower[2], upper[2] = prob.record.t[0], prob.record.t[-1]
    prob.chunk = 10**9
    res = least_squares(prob.residuals, x, bounds=(lower, upper), x_scale="jac", method="trf", xtol=1e-12,
                        ftol=1e-12, gtol=1e-12)
    dof = res.fun.size - x.size
    assert got.dof == dof == sum(ch.values.size for ch in prob.channels.values()) - x.size
    chi2_red = float(res.fun @ res.fun) / dof
    assert got.chi2_reduced == pytest.approx(chi2_red, rel=1e-10)
    se = np.sqrt(np.diag(jacobian_covariance(res.jac)) * chi2_red)
    for i, n in enumerate(got.names):
        assert abs(res.x[i] - x[i]) < 1e-5 * se[i]
        assert got.std_errors[n] == pytest.approx(se[i], rel=1e-5)


@pytest.mark.slow
def test_memory_of_a_streamed_jacobian_does_not_grow_with_the_rows(paper):
    """Peak memory allocated while forming the compressed system (chunks of 4,096 rows, the residuals and
    Jacobian of three channels and five parameters): the same for 1e5 and 2e5 rows, and a small part of the
    dense [r, J] of 2e5 rows (28.8 MB)."""
    import tracemalloc

    peaks = []
    for rows in (100_000, 200_000):
        syn = synthesize(paper, ["u", "v", "a_head"], rate=rows / 2.2, duration=2.2, seed=1)
        record = syn.record()
        prob = _Problem(paper, record, paper.fit)
        fit._noise(prob, record.release_time)
        truth = syn.truth | {"offset_u": 0.0, "offset_v": 0.0}
        x = np.array([truth[n] for n in prob.names])
        lower, upper = np.full(x.size, -np.inf), np.full(x.size, np.inf)
        prob.chunk = 4096
        prob.compressed(x, lower, upper)  # compiled and cached paths warm
        tracemalloc.start()
        prob.compressed(x, lower, upper)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    dense_bytes = 3 * 200_001 * (x.size + 1) * 8
    assert peaks[1] < 1.25 * peaks[0], peaks
    assert peaks[1] < dense_bytes / 4, (peaks, dense_bytes)
