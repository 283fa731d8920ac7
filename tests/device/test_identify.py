import math

import mpmath
import numpy as np
import pytest
from conftest import TABLE2_L1, mp_alpha_final, mp_dissipated, mp_identify, mp_stop_time
from hypothesis import given, settings
from hypothesis import strategies as st

from quickrelease import InfeasibleObservationError, ParameterError, identify_friction, simulate
from quickrelease.device.paper import printed_table7, reproduce_table7


@pytest.fixture(scope="module")
def comparison():
    return reproduce_table7()


def test_table_7_within_the_papers_rounding(comparison):
    """The paper's F1, F2 lie inside what its printed inputs allow once their rounding is counted."""
    p = printed_table7()
    lo, hi = comparison.F1_range_all
    assert lo < p["F1"].value < hi
    lo, hi = comparison.F2_range_all
    assert lo < p["F2"].value < hi
    # with t_F's rounding alone (1.045 to 1.055 s) F1 spans 387.6 to 451.5 N (mpmath identification)
    assert comparison.F1_range_t_F[0] == pytest.approx(mp_identify(2900, 0.2, 0.7378, 1.045)[0], rel=1e-10)
    assert comparison.F1_range_t_F[1] == pytest.approx(mp_identify(2900, 0.2, 0.7378, 1.055)[0], rel=1e-10)
    # the measured t_F that gives the paper's F1 prints as 1.05 s
    assert 1.045 <= comparison.t_F_for_paper_F1 < 1.055


def test_table_7_values(comparison):
    F1, F2 = mp_identify(2900, 0.2, 0.7378, 1.05)  # 419.850, 804.568 N
    assert comparison.F1_printed_inputs == pytest.approx(F1, rel=1e-10)
    assert comparison.F2_printed_inputs == pytest.approx(F2, rel=1e-10)
    assert comparison.E_S_eq2 == pytest.approx(2915.419, abs=1e-3)
    # the paper's pair sits 0.27% off its own Eq. 13 line; on it, E_S would be 2892.3 J: Eq. 7 at alpha_F by hand
    # with F1 = 405.6 N, F2 = 815.4 N, L1 = 2.477 m
    E_implied = float(mp_dissipated(mpmath.mpf("0.7378"), mpmath.mpf("0.2"), mpmath.mpf("405.6"),
                                    mpmath.mpf("815.4"), mpmath.mpf(TABLE2_L1)))
    assert comparison.E_S_implied_by_paper_pair == pytest.approx(E_implied, rel=1e-12)
    assert round(E_implied, 1) == 2892.3
    assert round(comparison.paper_pair_stop_time_on_line, 2) == 1.05
    # the lumped model cannot produce t_F = 1.05 s: the paper used c = 2/3
    assert comparison.lumped_feasible_stop_times[0] > 1.15


def test_comparison_notes_follow_the_numbers(comparison):
    """The notes of the demo's table are derived from the computed numbers, not fixed strings: moving a number
    across the boundary a note states flips the note."""
    from dataclasses import replace

    def note(c, quantity):
        return {row[0]: row[3] for row in c.rows()}[quantity]

    t_row, lumped_row = "t_F giving the paper's F1", "t_F range, lumped mass (c = 1)"
    assert note(comparison, t_row).startswith("inside the rounding of 1.05 s")
    assert note(replace(comparison, t_F_for_paper_F1=1.0556), t_row).startswith("outside the rounding of 1.05 s")
    assert note(comparison, lumped_row).startswith("1.05 s is infeasible with c = 1; feasible with c = 0.6667")
    assert note(replace(comparison, lumped_feasible_stop_times=(1.0, 1.2)), lumped_row).startswith(
        "1.05 s is feasible with c = 1")
    assert note(replace(comparison, lumped_feasible_stop_times=(1.05, 1.2)), lumped_row).startswith(
        "part of the rounding of 1.05 s is feasible with c = 1")
    assert note(replace(comparison, feasible_stop_times=(1.1, 1.3)), lumped_row).endswith(
        "infeasible with c = 0.6667 too")


def test_identification_result_fields():
    r = identify_friction(0.2, 0.7378, 1.05, stored_energy=2900.0)
    # the pair against an mpmath identification, and both observations back from mpmath's Eq. 8 and Eq. 10
    assert (r.F1, r.F2) == pytest.approx(mp_identify(2900, 0.2, 0.7378, 1.05), rel=1e-10)
    aF = mp_alpha_final(2900, 0.2, r.F1, r.F2)
    assert float(aF) == pytest.approx(0.7378, abs=1e-12)
    assert float(mp_stop_time(2900, 0.2, aF, r.F1, r.F2)) == pytest.approx(1.05, abs=1e-12)
    # F1* and F2* of Eq. 11-12 by hand: the friction of one kind alone that dissipates E_S by alpha_F
    s, c = math.sin(0.7378) - math.sin(0.2), math.cos(0.2) - math.cos(0.7378)
    assert r.F1_max == pytest.approx(2900 / (2 * 2.477 * s), rel=1e-14)
    assert r.F2_max == pytest.approx(2900 / (4 * 2.477 * c), rel=1e-14)
    assert r.F1_ratio == pytest.approx(r.F1 / r.F1_max, rel=1e-14)
    assert abs(r.stop_time_residual) < 1e-13
    assert r.feasible_stop_times[0] < 1.05 < r.feasible_stop_times[1]
    keys = {"F1_N", "F2_N", "F1_max_N", "F2_max_N", "F2_ratio", "stored_energy_J", "stop_time_residual_s"}
    assert keys <= set(r.summary())


def test_identification_from_push_force_uses_eq_2(paper_device):
    from quickrelease import strain_energy

    r = identify_friction(0.2, 0.7378, 1.05, push_force=1598e3)
    assert r.stored_energy == strain_energy(1598e3, 0.2, paper_device).total
    assert r.push_force == 1598e3


@settings(max_examples=20, deadline=None)
@given(st.floats(500.0, 1e4), st.floats(0.1, 0.8), st.floats(0.02, 0.98), st.floats(0.2, 0.8),
       st.sampled_from(["distributed", "lumped"]))
def test_round_trip(E_S, alpha0, share, stop_fraction, model):
    """Simulate with known F1, F2; identify from (alpha0, alpha_F, t_F, E_S); get them back."""
    # choose the friction so that the device stops at a given fraction of the way to pi/2
    aF_target = alpha0 + stop_fraction * (np.pi / 2 - alpha0)
    from quickrelease import friction_limits

    lim = friction_limits(E_S, alpha0, aF_target)  # the paper's device (L1 = 2.477 m)
    F1 = share * lim["F1_max"]
    F2 = (1 - share) * lim["F2_max"]
    s = simulate(E_S, alpha0, F1, F2, mass_model=model, method="rk", n_points=10)
    e = simulate(E_S, alpha0, F1, F2, mass_model=model, n_points=10)
    r = identify_friction(alpha0, e.alpha_final, e.stop_time, stored_energy=E_S, mass_model=model)
    assert r.F1 == pytest.approx(F1, rel=1e-8)
    assert r.F2 == pytest.approx(F2, rel=1e-8)
    # and from the Runge-Kutta observation, to its accuracy
    r2 = identify_friction(alpha0, s.alpha_final, s.stop_time, stored_energy=E_S, mass_model=model)
    assert r2.F1 == pytest.approx(F1, rel=1e-4, abs=1e-6 * lim["F1_max"])


def test_infeasible_stop_time_states_the_interval():
    with pytest.raises(InfeasibleObservationError,
                       match=r"t_F = 1.5 s is outside the feasible interval \[t_F\(F1 = 0\), t_F\(F1 = F1\*\)\] "
                             r"= \[0.990644, 1.21389\] s"):
        identify_friction(0.2, 0.7378, 1.5, stored_energy=2900.0)


@pytest.mark.parametrize("args,match", [
    ((0.2, 0.15, 1.05), r"alpha_final = 0.15 rad is outside \(alpha0, pi/2\)"),
    ((0.2, 1.6, 1.05), r"alpha_final = 1.6 rad is outside \(0, pi/2\)"),
    ((0.0, 0.7, 1.05), r"alpha0 = 0 rad is outside \(0, pi/2\)"),
    ((0.2, 0.7378, -1.0), r"stop_time = -1 s is outside \(0, inf\)"),
])
def test_bad_observations(args, match):
    with pytest.raises(ParameterError, match=match):
        identify_friction(*args, stored_energy=2900.0)


def test_energy_or_force_exactly_one():
    with pytest.raises(ParameterError, match="exactly one"):
        identify_friction(0.2, 0.7378, 1.05)
    with pytest.raises(ParameterError, match=r"E_S = -2 J"):
        identify_friction(0.2, 0.7378, 1.05, stored_energy=-2.0)
