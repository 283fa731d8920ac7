"""Model values of long records (issue 9, item 11): the tabulated path against independent references.

References: the triangular window average of the instantaneous acceleration integrated by scipy ``quad``
(with the release and the stop as break points, and the Dirac of the velocity drop at the geometric
limit) on the state from the time map inverted at each time; the state from ``solve_ivp`` (DOP853) for the
interpolated state table. Neither uses the tables, the Gauss rules or the second difference under test.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from quickrelease import preset
from quickrelease._statetable import CHANNEL_TOL, TOL, ChannelTable, StateTable
from quickrelease.device.dynamics import angular_acceleration
from quickrelease.device.solvers import FirstIntegral
from quickrelease.io.records import _direct, channel_model, release_channels

D = preset("paper")
CASES = {"friction": (2900.0, 0.2, 419.85, 804.57), "geometric_limit": (2900.0, 0.2, 0.0, 0.0)}
RATE_NAME = {"a_head": "u_dot", "a_hinge": "v_dot"}


def release(kind):
    E, a0, F1, F2 = CASES[kind]
    return FirstIntegral(E, a0, F1, F2, D.m1, D.m2, D.L1, 2 / 3)


def window_reference(fi, name, s, window):
    """(x(s+D) - 2 x(s) + x(s-D)) / D^2 as int_0^1 (1-y) (x''(s+Dy) + x''(s-Dy)) dy by quad, exact state."""
    t_stop = fi.stop_time()

    def inst(t):
        if t <= 0.0 or t > t_stop:
            return 0.0
        a, ad = fi.state_at(np.array([t]))
        add = angular_acceleration(a, np.maximum(ad, 1e-300), fi.F1, fi.F2, fi.m1, fi.m2, fi.L1, fi.c)
        return float(channel_model(name, a, ad, add, fi.alpha0, fi.L1)[0])

    cuts = [y for y in (abs(s) / window, abs(t_stop - s) / window) if 0.0 < y < 1.0]
    value = quad(lambda y: (1.0 - y) * (inst(s + window * y) + inst(s - window * y)), 0.0, 1.0,
                 points=cuts or None, epsabs=0.0, epsrel=2e-14, limit=200)[0]
    if fi.geometric_limit and abs(t_stop - s) < window:
        a, ad = fi.state_at(np.array([t_stop]))
        v_F = float(channel_model(RATE_NAME[name], a, ad, 0.0, fi.alpha0, fi.L1)[0])
        value -= (1.0 - abs(t_stop - s) / window) / window * v_F
    return value


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(CASES))
def test_window_accelerations_at_50_khz_match_quad(kind):
    """A 50 kHz record (~60,000 samples): every acceleration sample within 1e-12 of the channel's range of the
    quad reference, the samples whose window reaches across the release and the stop included. The second
    difference of the exact path is off by ~1e-6 of the range there (rounding / Delta^2)."""
    fi = release(kind)
    window, t0 = 2e-5, 0.3
    t = np.arange(-0.1, fi.stop_time() + 0.1, window) + t0
    model = release_channels(["a_head", "a_hinge", "u"], t, t0, fi, window)
    s = t - t0
    near = np.nonzero((np.abs(s) < 1.5 * window) | (np.abs(s - fi.stop_time()) < 1.5 * window))[0]
    picks = np.unique(np.concatenate([np.linspace(0, t.size - 1, 16).astype(int), near]))
    for name in ("a_head", "a_hinge"):
        ref = np.array([window_reference(fi, name, float(s[i]), window) for i in picks])
        scale = np.ptp(model[name])
        assert np.max(np.abs(model[name][picks] - ref)) < 1e-12 * scale, name
    u_ref = channel_model("u", *fi.state_at(s[picks]), 0.0, fi.alpha0, fi.L1)
    assert np.max(np.abs(model["u"][picks] - u_ref)) < 1e-13 * np.ptp(model["u"])


def test_channel_table_meets_its_tolerance():
    """Built from a coarse start, the table stops where its check points meet CHANNEL_TOL; between them the
    values stay within 1e-10 of the range of the direct evaluation (which the quad test above pins)."""
    fi = release("friction")
    window = 2e-4
    names = ["u", "u_dot", "a_head"]
    lo, hi = window, fi.stop_time() - window
    table = ChannelTable.build(lambda x: _direct(names, x, fi, window, exact=False), names, lo, hi, start=2)
    assert table is not None and table.error <= CHANNEL_TOL
    x = np.linspace(lo, hi, 3001)
    direct = _direct(names, x, fi, window, exact=False)
    values = table.values(x)
    for name in names:
        assert np.max(np.abs(values[name] - direct[name])) < 1e-10 * np.ptp(direct[name]), name


@pytest.mark.parametrize("kind", sorted(CASES))
def test_state_table_matches_solve_ivp(kind):
    """alpha, alpha_dot and alpha_ddot of the state table from a coarse start against DOP853 (rtol 1e-13)."""
    fi = release(kind)
    t_stop = fi.stop_time()

    def acceleration(a, ad):
        return angular_acceleration(a, np.maximum(ad, 1e-300), fi.F1, fi.F2, fi.m1, fi.m2, fi.L1, fi.c)

    def exact(t):
        w = fi.w_at_times(t)
        return fi.alpha(w), fi._rel.rate_at(w)

    table = StateTable.build(t_stop, exact, acceleration, start=4)
    assert table is not None and table.error <= TOL
    t = np.linspace(0.0, t_stop, 2001)
    sol = solve_ivp(lambda _t, y: [y[1], float(acceleration(y[0], y[1]))], (0.0, t_stop), [fi.alpha0, fi.alpha_dot0],
                    method="DOP853", rtol=1e-13, atol=1e-15, t_eval=t)
    a, ad, add = table.state(t, acceleration=True)
    assert np.max(np.abs(a - sol.y[0])) < 1e-11 * np.ptp(sol.y[0])
    assert np.max(np.abs(ad - sol.y[1])) < 1e-9 * np.max(np.abs(sol.y[1]))
    # the stated tolerance, between the nodes, against the time map inverted at each time
    ea, ead = exact(t)
    eadd = acceleration(ea, ead)
    for got, ref in ((a, ea), (ad, ead), (add, eadd)):
        assert np.max(np.abs(got - ref)) < 10 * TOL * np.max(np.abs(ref))
