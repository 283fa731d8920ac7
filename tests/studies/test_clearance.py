"""Clearance with the building (issue 9, item 19a; issue 10, item 1): the building's motion from
:mod:`quickrelease.building.model`, the first contact located on the continuous gap, the gap that never falls.

The reference is written here, independently of the package: the device's equation of motion (Eq. 4, c = 2/3)
and the building's (``x'' = -2 zeta w x' - w^2 x - a_f sign(x')``) integrated together by ``solve_ivp`` with a
terminal event on the gap ``L1 (cos alpha0 - cos alpha) - (d0 - x)`` (Table 4).
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from quickrelease import preset
from quickrelease.device.solvers import FirstIntegral
from quickrelease.io.case import BuildingSpec
from quickrelease.studies.planning import GAP_GROWS, building_motion, clearance, gap_figure

DEVICE = preset("paper")


def _release(E_S=2900.0, alpha0=0.2, F1=419.85, F2=804.57):
    d = DEVICE
    return FirstIntegral(E_S, alpha0, F1, F2, d.m1, d.m2, d.L1, 2 / 3)


def _event_contact(E_S, alpha0, F1, F2, T, zeta, a_f, d0, t_max):
    """First contact time by solve_ivp with a terminal event (the device and the building integrated together)."""
    m1, m2, L1, c = DEVICE.m1, DEVICE.m2, DEVICE.L1, 2.0 / 3.0
    D0 = c * m1 / m2 + math.sin(alpha0) ** 2
    rate0 = math.sqrt(E_S / (m2 * L1**2 * D0))  # Eq. 6: all of E_S turns into kinetic energy
    w = 2 * math.pi / T

    def rhs(_t, y):
        a, ad, x, xd = y
        D = c * m1 / m2 + math.sin(a) ** 2
        add = (-ad * ad * math.sin(a) * math.cos(a) - (2 * F2 * math.sin(a) + F1 * math.cos(a)) / (m2 * L1)) / D
        xdd = -2 * zeta * w * xd - w * w * x + a_f  # moving back (x' < 0): the sliders push towards +x
        return [ad, add, xd, xdd]

    def gap(_t, y):
        return L1 * (math.cos(alpha0) - math.cos(y[0])) - (d0 - y[2])

    gap.terminal, gap.direction = True, -1
    y0 = [alpha0, rate0, d0, 0.0]
    sol = solve_ivp(rhs, (0.0, t_max), y0, method="DOP853", rtol=1e-13, atol=1e-15, events=[gap],
                    first_step=1e-9)
    assert sol.status == 1 and sol.t_events[0].size == 1
    assert np.all(sol.y[1] > 0) and np.all(sol.y[3] <= 0)  # within one smooth piece of both motions
    return float(sol.t_events[0][0])


@pytest.mark.parametrize("T, zeta, mass, friction, d0", [
    (0.4, 0.05, 1e6, 1e5, 0.25),  # contact at about 0.0182 s, between two samples 2.6e-4 s apart
    (0.5, 0.0, None, 0.0, 0.3),
])
def test_first_contact_matches_an_event_located_integration(T, zeta, mass, friction, d0):
    building = BuildingSpec(period=T, damping_ratio=zeta, mass=mass, friction=friction)
    rel = _release()
    c = clearance(rel, building, d0)
    assert c.contact and c.min_gap < 0
    a_f = friction / mass if mass else 0.0
    t_ref = _event_contact(2900.0, 0.2, 419.85, 804.57, T, zeta, a_f, d0, c.min_gap_time)
    spacing = c.t[1] - c.t[0]
    assert spacing > 1e-4  # the grid alone would be off by up to this
    assert c.first_contact_time == pytest.approx(t_ref, rel=1e-9)
    # and it is where the gap closes: the grid gap changes sign across it
    j = np.searchsorted(c.t, c.first_contact_time)
    assert c.gap[j - 1] >= 0 > c.gap[j]


def test_building_motion_is_the_building_module_with_friction_stick():
    """building_motion (unit mass, a_f) against solve_ivp with events at the reversals (independent)."""
    T, zeta, a_f, d0 = 1.5, 0.08, 0.5, 0.12
    w = 2 * math.pi / T
    t_out = np.linspace(0.0, 2.0 * T, 401)
    x, v, _ = building_motion(t_out, d0, T, zeta, a_f)
    # reference: integrate half-cycle by half-cycle, each with its own friction sign, ending where x' = 0
    t0, y, xs = 0.0, [d0, 0.0], []
    ts = []
    while t0 < t_out[-1]:
        s = -math.copysign(1.0, y[0])
        if w * w * abs(y[0]) <= a_f:  # sticks
            break

        def rhs(_t, yy, s=s):
            return [yy[1], -2 * zeta * w * yy[1] - w * w * yy[0] - a_f * s]

        def turn(_t, yy, s=s, start=t0):
            return yy[1] if _t > start else s

        turn.terminal, turn.direction = True, -s
        sol = solve_ivp(rhs, (t0, t_out[-1] + 1.0), y, rtol=1e-12, atol=1e-14, events=[turn], dense_output=True)
        t1 = float(sol.t_events[0][0]) if sol.t_events[0].size else t_out[-1] + 1.0
        m = (t_out >= t0) & (t_out < t1)
        ts.append(t_out[m])
        xs.append(sol.sol(t_out[m])[0])
        t0, y = t1, [float(sol.sol(t1)[0]), 0.0]
    m = t_out >= t0
    ts.append(t_out[m])
    xs.append(np.full(m.sum(), y[0]))
    np.testing.assert_allclose(x, np.concatenate(xs), atol=1e-9)


def test_gap_that_keeps_growing_reports_no_minimum():
    """A small push of a slow building and a device still moving at its largest approach: the gap grows over the
    whole horizon. No minimum is reported (None), the note says why, no contact."""
    rel = _release()  # t_F = 1.05 s
    building = BuildingSpec(period=1.8, displacement=0.01)  # T/2 = 0.9 s < t_F < 2T/3 = 1.2 s
    c = clearance(rel, building, 0.01)
    assert np.all(np.diff(c.gap) >= 0)  # the premise: the gap never falls
    assert c.min_gap is None and c.min_gap_time is None and c.note == GAP_GROWS
    assert not c.contact and c.first_contact_time is None and c.margin_needed == 0.0
    s = c.summary()
    assert s["min_gap_m"] is None and s["note"] == GAP_GROWS
    assert c.describe_minimum().startswith("no minimum gap")
    from quality import figure_faults

    assert figure_faults(gap_figure(c)) == []  # draws without a minimum to mark
    # the same building pushed further catches up: the gap falls, and the minimum is reported
    c2 = clearance(rel, BuildingSpec(period=1.8, displacement=0.3), 0.3)
    assert c2.min_gap is not None and c2.note == ""
