"""bounded_least_squares (quickrelease._lsq): the active set around scipy's TRF, against scipy's own solves of
the same problems (the unbounded reduced problem where the bound is active) and the problem's exact solution."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import least_squares

from quickrelease._lsq import bounded_least_squares

T = np.linspace(0.0, 3.0, 200)
TRUTH = np.array([1.0, 0.3, 2.0])
LO, HI = np.array([0.0, 0.0, 0.5, 0.0]), np.array([5.0, 5.0, 5.0, 10.0])
X0 = np.array([0.8, 0.5, 2.1, 2.0])


def _central(fun, rel: float):
    """The Jacobian of ``fun`` by central differences written here (steps ``rel`` times max(1, |p_i|))."""

    def jac(p):
        f0 = fun(p)
        J = np.empty((f0.size, p.size))
        for i in range(p.size):
            h = rel * max(1.0, abs(p[i]))
            up, down = p.copy(), p.copy()
            up[i] += h
            down[i] -= h
            J[:, i] = (fun(up) - fun(down)) / (2.0 * h)
        return J

    return jac


def _model(p):
    """A decaying cosine a exp(-r t) cos(w t) plus a constant c >= 0 (the bounded parameter)."""
    a, r, w, c = p
    return a * np.exp(-r * T) * np.cos(w * T) + c


def _problem(c_true: float):
    data = _model([*TRUTH, c_true])

    def fun(p):
        return (_model(p) - data) / 1e-3

    return fun, _central(fun, 1e-6)


def test_minimum_at_the_bound_is_the_reduced_problems_minimum():
    """Data with c = -0.2 (outside c >= 0): the bounded minimum is at c = 0, the others those of the problem
    without c, solved by scipy unbounded; the gradient at c = 0 points out of the box (KKT)."""
    fun, jac = _problem(-0.2)
    r = bounded_least_squares(fun, X0, jac, LO, HI, tol=1e-12, x_scale="jac")
    ref = least_squares(lambda q: fun(np.append(q, 0.0)), X0[:3], xtol=1e-14, ftol=1e-14, gtol=1e-14)
    assert r.x[3] == 0.0 and r.held == [3]
    np.testing.assert_allclose(r.x[:3], ref.x, rtol=1e-5)  # a misfit 2400 times the noise: flat to 1e-6
    assert r.cost == pytest.approx(ref.cost, rel=1e-10)
    assert (r.jac.T @ r.fun)[3] > 0.0  # increasing c would raise the cost
    assert r.jac.shape == (T.size, 4)


def test_optimum_on_the_bound_reached_without_the_geometric_crawl():
    """Exact data with c = 0: plain TRF halves its way to the bound (tens of Jacobians); the active set holds c
    there after a few and ends at the truth."""
    fun, jac = _problem(0.0)
    plain = least_squares(fun, X0, jac=jac, bounds=(LO, HI), x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12)
    r = bounded_least_squares(fun, X0, jac, LO, HI, tol=1e-12, x_scale="jac")
    np.testing.assert_allclose(r.x, [*TRUTH, 0.0], atol=1e-9)
    assert r.held == [3]
    assert r.njev < plain.njev / 2  # 11 against 42 when written


@pytest.mark.parametrize("c_true", [1e-4, 0.05])
def test_interior_optimum_near_the_bound_is_freed(c_true):
    """c = 1e-4 just inside the bound: held or not on the way, the result is the truth (a held parameter whose
    gradient points inwards is freed)."""
    fun, jac = _problem(c_true)
    r = bounded_least_squares(fun, X0, jac, LO, HI, tol=1e-12, x_scale="jac")
    np.testing.assert_allclose(r.x, [*TRUTH, c_true], rtol=1e-8, atol=1e-12)
    assert r.held == []


@pytest.mark.parametrize("x0", [(-1.2, 1.0), (-3.0, 8.0)])
def test_a_slow_steady_descent_is_not_taken_for_a_stall(x0):
    """Rosenbrock's valley as least squares (r = (10 (y - x^2), 1 - x)): 24-30 iterations of steady progress, past the
    stall's window of 20 (``STALL_STEPS``): solved to its exact minimum (1, 1), not stopped as a staircase."""
    def fun(p):
        return np.array([10.0 * (p[1] - p[0] ** 2), 1.0 - p[0], 0.0])

    def jac(p):
        return np.array([[-20.0 * p[0], 10.0], [-1.0, 0.0], [0.0, 0.0]])

    r = bounded_least_squares(fun, np.array(x0), jac, np.array([-10.0, -10.0]), np.array([10.0, 10.0]), tol=1e-14)
    assert r.njev > 20 and "staircase" not in r.message
    np.testing.assert_allclose(r.x, [1.0, 1.0], atol=1e-10)



def _curved(amplitude: float):
    """Residuals whose minimum (0) is at ``(amplitude, 2)``: an exponential in the second parameter (a Gauss-Newton
    step from below it overshoots, and the trust region shrinks) beside a first parameter of magnitude
    ``amplitude`` (a damper's coefficient in N (s/m)^alpha beside a period in s)."""

    def fun(p):
        return np.array([1e3 * (np.exp(5.0 * (p[1] - 2.0)) - 1.0), 1e3 * (p[0] / amplitude - 1.0),
                         0.1 * (p[0] / amplitude - 1.0) * p[1]])

    return fun, _central(fun, 1e-7)


@pytest.mark.parametrize("w0", [0.5, 1.0, 3.0])
def test_a_large_parameter_does_not_end_the_small_ones_solve(w0):
    """scipy's xtol compares the step with the norm of x in the parameters' own units: beside a coefficient of 1e6
    a step of 0.5 reads as converged after the trust region shrank once, and the solve stops short (the guarded
    failure); measured against each parameter's own magnitude (``scale``) it reaches the exact minimum."""
    amplitude = 1e6
    fun, jac = _curved(amplitude)
    x0 = np.array([amplitude, w0])
    lo, hi = np.array([0.0, 0.0]), np.array([5e6, 5.0])
    plain = bounded_least_squares(fun, x0, jac, lo, hi, tol=1e-6, x_scale="jac")
    assert abs(plain.x[1] - 2.0) > 0.1 and "xtol" in plain.message  # what this guards against
    scaled = bounded_least_squares(fun, x0, jac, lo, hi, tol=1e-6, x_scale="jac", scale=np.abs(x0))
    np.testing.assert_allclose(scaled.x, [amplitude, 2.0], rtol=1e-7)
    assert 2.0 * scaled.cost < 1e-8
    np.testing.assert_allclose(scaled.jac, jac(scaled.x), rtol=1e-4, atol=1e-6)  # the Jacobian back in x's units
    np.testing.assert_allclose(scaled.grad, scaled.jac.T @ scaled.fun, rtol=1e-6, atol=1e-12)

def test_the_release_times_origin_keeps_its_solve_relative():
    """A parameter far from 0 in its own units (a release at a logger's time of day, 36 000 s) measured from an
    origin: the solve reaches the minimum as from the shifted problem."""
    fun, jac = _problem(0.0)
    shift = 36000.0

    def fun_s(p):
        return fun(np.array([p[0], p[1], p[2] - shift, p[3]]))

    def jac_s(p):
        return jac(np.array([p[0], p[1], p[2] - shift, p[3]]))

    x0 = X0 + np.array([0.0, 0.0, shift, 0.0])
    r = bounded_least_squares(fun_s, x0, jac_s, LO + [0, 0, shift, 0], HI + [0, 0, shift, 0], tol=1e-8,
                              x_scale="jac", scale=[1.0, 0.3, 2.0, 0.1], origin=[0.0, 0.0, shift, 0.0])
    np.testing.assert_allclose(r.x - [0.0, 0.0, shift, 0.0], [*TRUTH, 0.0], atol=1e-7)


@pytest.mark.parametrize("scale", [[0.0, 1.0, 1.0], [np.nan, 1.0, 1.0], [1.0, 1.0]])
def test_a_bad_scale_is_refused(scale):
    fun, jac = _problem(0.0)
    with pytest.raises(ValueError, match="scale"):
        bounded_least_squares(fun, X0[:3], jac, LO[:3], HI[:3], scale=scale)
