"""Test planning: fuse and angle, member checks, release envelope, clearance with the building (issue: planning)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import mp_alpha_final
from typer.testing import CliRunner

from quickrelease import ParameterError, load_device, preset, simulate, strain_energy
from quickrelease.cli import app
from quickrelease.device.solvers import FirstIntegral
from quickrelease.io.case import BuildingSpec, CaseFileError, load_case
from quickrelease.studies.planning import (
    building_motion,
    clearance,
    friction_samples,
    fuse_choices,
    member_checks,
    plan_case,
    release_envelope,
)

EXAMPLES = Path(__file__).parents[2] / "examples"
runner = CliRunner()

P, A0 = 1598e3, 0.2


@pytest.fixture(scope="module")
def device():
    return load_device(EXAMPLES / "device_checked.toml")


# -- member checks: the paper's device at P = 1598 kN, alpha0 = 0.2 rad, by hand -------------------------------

def test_member_checks_against_hand_calculation(device):
    m = member_checks(P, A0, device, rupture_strength=610e6)
    by = {(c.member, c.check.split(" (")[0]): c for c in m.checks}
    # Table 3 and Eq. 1 (Table 3's angle): the fuse carries P tan(alpha0) on A4 = 531 mm^2
    assert m.fuse_stress == pytest.approx(1598e3 * math.tan(0.2) / 531e-6, rel=1e-14)
    assert m.fuse_stress / 1e6 == pytest.approx(610.04, abs=0.01)
    # E1: N1 = P / (2 cos alpha0) on the HEB 300's 149.1 cm^2, against 275 MPa
    N1 = 1598e3 / (2 * math.cos(0.2))
    assert by[("E1", "axial compression N1/A1")].utilisation == pytest.approx(N1 / 14910e-6 / 275e6, rel=1e-14)
    assert by[("E1", "axial compression N1/A1")].utilisation == pytest.approx(0.1988, abs=1e-4)
    # Euler: pi^2 E I_z / L1^2 with I_z = 8563 cm^4 (HEB 300), pinned bars
    N_cr = math.pi**2 * 205970e6 * 8563e-8 / 2.477**2
    assert by[("E1", "flexural buckling")].capacity == pytest.approx(N_cr, rel=1e-14)
    assert by[("E1", "flexural buckling")].utilisation == pytest.approx(0.02874, abs=1e-5)
    # E2: N2 = P tan(a)/2, M2 = P L2 / 4, V2 = P / 2, W2 = I2 / 0.2 m, shear on kappa A2, von Mises
    sigma = 1598e3 * math.tan(0.2) / 2 / 40780e-6 + 1598e3 * 1.062 / 4 / (791175e-9 / 0.2)
    tau = 1598e3 / 2 / (0.2 * 40780e-6)
    assert by[("E2", "axial + bending + shear")].demand == pytest.approx(math.sqrt(sigma**2 + 3 * tau**2), rel=1e-14)
    assert by[("E2", "axial + bending + shear")].utilisation == pytest.approx(0.7378, abs=1e-4)
    # E3: no yield strength for the fuse rods' steel in the device file: skipped, with a note
    assert by[("E3", "axial tension N3/A3")].utilisation is None
    assert "fy3 not in the device file" in by[("E3", "axial tension N3/A3")].note
    assert m.utilisation() == {"E1": pytest.approx(0.1988, abs=1e-4), "E2": pytest.approx(0.7378, abs=1e-4),
                               "E3": None}
    assert by[("E4", "fuse stress N4/A4")].utilisation == pytest.approx(1.0, abs=1e-4)


def test_checks_skipped_without_data():
    from quickrelease import preset

    m = member_checks(P, A0, preset("paper"))
    assert all(c.utilisation is None for c in m.checks)
    assert {c.note.split(":")[0] for c in m.checks} == {"skipped", "no rupture strength given ([fuse])"}


def test_device_check_keys(tmp_path):
    from quickrelease import DeviceFileError

    text = (EXAMPLES / "device_checked.toml").read_text()
    path = tmp_path / "d.toml"
    path.write_text(text.replace('fy = "275 MPa"', 'fy = "-275 MPa"'))
    with pytest.raises(DeviceFileError, match=r"d.toml: fy = '-275 MPa' must be positive"):
        load_device(path)
    path.write_text(text + 'fy9 = "1 MPa"\n')
    with pytest.raises(DeviceFileError, match=r"unknown key 'fy9'.*for member checks: fy, fy1, fy2, fy3, I1, Lcr1"):
        load_device(path)
    d = load_device(EXAMPLES / "device_checked.toml")
    assert d.yield_strength(1) == d.yield_strength(2) == 275e6 and d.yield_strength(3) is None
    assert d.I1 == pytest.approx(8563e-8) and d.h2 == pytest.approx(0.4)


# -- fuse and angle ---------------------------------------------------------------------------------------------

def test_fuse_choices_by_hand(device):
    table = fuse_choices((1520e3, 1680e3), 610e6, 15e6, [0.024, 0.026], [0.175, 0.2], device)
    c = {(round(x.diameter * 1e3), x.alpha0): x for x in table.choices}
    S = 610e6 * math.pi * 0.026**2 / 4
    assert c[(26, 0.2)].push_force == pytest.approx(S / math.tan(0.2), rel=1e-14)
    assert c[(26, 0.2)].push_force_std == pytest.approx(15e6 * math.pi * 0.026**2 / 4 / math.tan(0.2), rel=1e-14)
    z_hi = (1680e3 - c[(26, 0.2)].push_force) / c[(26, 0.2)].push_force_std
    z_lo = (1520e3 - c[(26, 0.2)].push_force) / c[(26, 0.2)].push_force_std
    expected = 0.5 * (math.erf(z_hi / math.sqrt(2)) - math.erf(z_lo / math.sqrt(2)))
    assert c[(26, 0.2)].probability_within == pytest.approx(expected, rel=1e-12)
    assert [round(x.diameter * 1e3) for x in table.choices if x.within] == [24, 26]
    assert table.best is c[(26, 0.2)]
    # the stored energy is Eq. 2 with this fuse's section
    from quickrelease import strain_energy

    assert c[(24, 0.175)].stored_energy == pytest.approx(
        strain_energy(c[(24, 0.175)].push_force, 0.175, device.replace(A4=math.pi * 0.024**2 / 4)).total)


def test_fuse_that_cannot_reach_the_target(device):
    with pytest.raises(ParameterError, match=r"target push force = \[4500, 5500\] kN is outside what the candidate "
                                             r"fuses and angles reach, \[1143.9, 2142.89\] kN"):
        fuse_choices((4500e3, 5500e3), 610e6, 0.0, [0.022, 0.026], [0.15, 0.2], device)
    table = fuse_choices((1700e3, 1750e3), 610e6, 0.0, [0.022, 0.026], [0.15, 0.2], device)
    assert not any(c.within for c in table.choices)
    assert "no candidate lies in the target range; the closest is d = 26 mm at alpha0 = 0.2 rad" in table.warnings[0]


# -- release envelope -------------------------------------------------------------------------------------------

def test_envelope_for_the_table_7_friction_by_hand():
    """The paper case identified from Table 7: alpha_F is the observed 0.7378 rad, so the stroke and the opening
    follow from Table 4 by hand."""
    case = load_case(EXAMPLES / "paper.toml")
    env = release_envelope(case)
    assert env.samples == 1 and env.friction == "identified from [observations]"
    L1 = 2.477
    assert env.nominal["alpha_final"] == pytest.approx(0.7378, abs=1e-12)
    assert env.nominal["u_final"] == pytest.approx(L1 * (math.cos(0.2) - math.cos(0.7378)), rel=1e-12)
    assert env.nominal["v_final"] == pytest.approx(L1 * (math.sin(0.7378) - math.sin(0.2)), rel=1e-12)
    assert env.nominal["stop_time"] == pytest.approx(1.05, rel=1e-12)
    r = simulate(2900.0, 0.2, env.F1, env.F2, n_points=100001).summary()
    for key, name in (("peak_u_dot", "peak_u_dot_m_s"), ("peak_v_dot", "peak_v_dot_m_s"),
                      ("peak_u_ddot", "peak_u_ddot_m_s2"), ("peak_v_ddot", "peak_v_ddot_m_s2")):
        assert env.nominal[key] == pytest.approx(r[name], rel=1e-4), key


def test_friction_with_a_correlated_scatter(tmp_path):
    text = (EXAMPLES / "larger_push.toml").read_text().replace(
        'F1 = "419.85 N"', 'F1 = { value = "420 N", std = "40 N" }').replace(
        'F2 = "0.80457 kN"', 'F2 = { low = "700 N", high = "900 N" }\ncorrelation = -0.8')
    text = text.replace('file = "device.toml"', f'file = "{EXAMPLES / "device.toml"}"')
    path = tmp_path / "c.toml"
    path.write_text(text)
    case = load_case(path)
    fs = friction_samples(case, 50_000, seed=3)
    F1, F2, how, clipped = fs.F1, fs.F2, fs.description, fs.dropped_share
    assert fs.nominal == (420.0, 800.0)
    assert F1.mean() == pytest.approx(420, abs=1) and F1.std() == pytest.approx(40, rel=0.02)
    assert F2.min() >= 700 and F2.max() <= 900 and F2.mean() == pytest.approx(800, abs=1)
    assert np.corrcoef(F1, F2)[0, 1] == pytest.approx(-0.78, abs=0.03)  # the copula's -0.8 on uniform marginals
    assert "correlation -0.8" in how and clipped == 0.0
    env = release_envelope(case, samples=20_000)
    r = env.ranges["u_final"]
    assert r["min"] <= r["p5"] <= env.nominal["u_final"] <= r["p95"] <= r["max"]


# -- the building and the clearance -------------------------------------------------------------------------------

def test_building_motion_closed_forms():
    t = np.linspace(0, 5, 2001)
    x, v, a = building_motion(t, 0.1, 2.0)
    w = math.pi
    np.testing.assert_allclose(x, 0.1 * np.cos(w * t), atol=1e-15)
    np.testing.assert_allclose(v, -0.1 * w * np.sin(w * t), atol=1e-14)
    # Coulomb friction alone: the amplitude drops by 2 a_f / w^2 every half cycle, then the building sticks
    a_f = 0.05
    x, v, _ = building_motion(t, 0.1, 2.0, 0.0, a_f)
    drop = 2 * a_f / w**2
    assert x[np.searchsorted(t, 1.0)] == pytest.approx(-(0.1 - drop), abs=1e-12)
    assert x[np.searchsorted(t, 2.0)] == pytest.approx(0.1 - 2 * drop, abs=1e-12)
    n_half = math.ceil((0.1 - a_f / w**2) / drop)
    assert np.all(v[t >= n_half * 1.0] == 0.0)


def test_building_motion_against_solve_ivp():
    from scipy.integrate import solve_ivp

    T, zeta, a_f, d0 = 2.5, 0.1, 0.098, 0.2
    w = 2 * math.pi / T

    def rhs(_t, y):
        return [y[1], -2 * zeta * w * y[1] - w * w * y[0] - a_f * np.sign(y[1])]

    t = np.linspace(0, 2.4, 200)  # within the first two half cycles (the friction sign is smooth inside each)
    sol = solve_ivp(rhs, (0, 2.4), [d0, 0.0], t_eval=t, rtol=1e-11, atol=1e-13, max_step=0.01)
    x, v, _ = building_motion(t, d0, T, zeta, a_f)
    np.testing.assert_allclose(x, sol.y[0], atol=2e-7)
    np.testing.assert_allclose(v, sol.y[1], atol=2e-6)


@pytest.mark.parametrize("kw, message", [
    (dict(period=-1.0), r"period = -1 s is outside \(0, inf\)"),
    (dict(damping_ratio=-0.1), r"damping_ratio = -0.1 is outside \[0, 1\)"),
    (dict(damping_ratio=1.0), r"damping_ratio = 1 is outside \[0, 1\)"),
])
def test_building_motion_bad_input(kw, message):
    args = {"period": 2.0, "damping_ratio": 0.0} | kw
    with pytest.raises(ParameterError, match=message):
        building_motion(np.array([0.0]), 0.1, args["period"], args["damping_ratio"])


def _release(E_S=2900.0, alpha0=0.2, F1=419.85, F2=804.57):
    from quickrelease import preset

    d = preset("paper")
    return FirstIntegral(E_S, alpha0, F1, F2, d.m1, d.m2, d.L1, 2 / 3)


def test_realistic_building_and_the_paper_device_stay_clear():
    building = BuildingSpec(period=2.5, damping_ratio=0.1, mass=1.2e6, friction_coefficient=0.01)
    c = clearance(_release(), building, 0.19)
    assert not c.contact and c.first_contact_time is None and c.margin_needed == 0.0
    # after the device stops at u_F the gap is u_F minus the approach, smallest at the largest approach
    w = 2 * math.pi / 2.5
    assert c.min_gap_time == pytest.approx(math.pi / (w * math.sqrt(1 - 0.01)), rel=1e-6)
    assert c.min_gap == pytest.approx(c.head[-1] - c.max_approach, abs=1e-6)


def test_fast_building_and_slow_device_touch():
    # a stiff building pushed far (T = 0.6 s, d0 = 0.3 m) and a device released at a small angle with heavy friction
    building = BuildingSpec(period=0.6, damping_ratio=0.05, displacement=0.3)
    slow = _release(E_S=700.0, alpha0=0.1, F1=1500.0, F2=1500.0)
    c = clearance(slow, building, 0.3)
    assert c.contact and c.min_gap < 0 and c.margin_needed == pytest.approx(-c.min_gap)
    assert 0 < c.first_contact_time < 0.3


def test_gap_at_small_times_follows_its_series():
    """gap(t) = u_dot0 t + (u_ddot0 - a_b0) t^2 / 2 + O(t^3), a_b0 = w^2 d0 - a_f the building's initial acceleration."""
    building = BuildingSpec(period=1.0, damping_ratio=0.1, mass=1e6, friction=2e5)
    rel = _release()
    c = clearance(rel, building, 0.25)
    u_dot0, half_acc = c.gap_series
    d = rel
    assert u_dot0 == pytest.approx(d.L1 * math.sin(0.2) * d.alpha_dot0, rel=1e-14)
    w = 2 * math.pi
    from quickrelease.device.dynamics import angular_acceleration

    acc0 = angular_acceleration(0.2, d.alpha_dot0, d.F1, d.F2, d.m1, d.m2, d.L1, d.c)
    u_ddot0 = d.L1 * (math.cos(0.2) * d.alpha_dot0**2 + math.sin(0.2) * acc0)
    assert half_acc == pytest.approx(0.5 * (u_ddot0 - (w * w * 0.25 - 0.2)), rel=1e-12)
    from quickrelease.studies.planning import _gap_at

    errors = []
    for t in (0.004, 0.002, 0.001):
        exact = _gap_at(t, rel, building, 0.25)
        errors.append(abs(exact - (u_dot0 * t + half_acc * t * t)))
    assert errors[0] / errors[1] == pytest.approx(8, rel=0.1) and errors[1] / errors[2] == pytest.approx(8, rel=0.1)
    assert errors[-1] < 1e-5 * (u_dot0 * 0.001)


# -- the whole plan, the command line, bad input -------------------------------------------------------------------

@pytest.mark.slow
def test_plan_example_json_and_outputs(tmp_path):
    result = runner.invoke(app, ["plan", str(EXAMPLES / "plan.toml"), "--json", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    for key in ("fuse_stress_Pa", "utilisation", "stroke_m", "opening_m", "min_gap_m", "min_gap_time_s", "contact"):
        assert key in data
    assert data["fuse_stress_Pa"] == pytest.approx(1598e3 * math.tan(0.2) / 531e-6)
    assert set(data["utilisation"]) == {"E1", "E2", "E3"} and data["utilisation"]["E3"] is None
    assert data["contact"] is False and data["min_gap_m"] > 0.2
    assert data["fuse"]["best"]["diameter_m"] == pytest.approx(0.026)
    assert data["envelope"]["samples"] > 19_000 and data["clearance"]["contact_share"] == 0.0
    for stem in ("plan_choices", "plan_utilisation", "plan_envelope", "plan_gap"):
        png = tmp_path / "figures" / f"{stem}.png"
        assert png.stat().st_size > 15_000, stem
    report = (tmp_path / "report.html").read_text()
    assert ">Test planning</h2>" in report and '<figure id="plan_gap"><svg' in report
    assert json.loads((tmp_path / "plan.json").read_text())["stroke_m"] == pytest.approx(data["stroke_m"])


def test_plan_needs_a_push_force(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('[test]\nenergy = "2.9 kJ"\nalpha0 = 0.2\n[friction]\nF1 = 400\nF2 = 800\n')
    result = runner.invoke(app, ["plan", str(path)])
    assert result.exit_code == 2 and "planning needs the push force" in result.output


@pytest.mark.parametrize("table, message", [
    ('[building]\nperiod = "-2 s"\ndisplacement = "0.1 m"', r"\[building\] period = '-2 s': expected an isolation period in \[0.01, 1000\] s"),
    ('[building]\nperiod = "2 s"\ndamping_ratio = -0.1\ndisplacement = "0.1 m"',
     r"\[building\] damping_ratio = -0.1: expected a damping ratio in \[0, 1\)"),
    ('[building]\nperiod = "2 s"\ndamping_ratio = 1.2\ndisplacement = "0.1 m"',
     r"\[building\] damping_ratio = 1.2: expected a damping ratio in \[0, 1\)"),
    ('[building]\nperiod = "2 s"', r"\[building\] needs displacement \(d0\) or the mass or weight"),
    ('[fuse]\nrupture_strength = "610 MPa"\nangles = ["0.2 rad", "1.6 rad"]',
     r"\[fuse\] angles = '1.6 rad': expected a list of angles in \(0, pi/2\)"),
])
def test_bad_planning_tables(tmp_path, table, message):
    path = tmp_path / "c.toml"
    path.write_text(f'[test]\nforce = "1598 kN"\nalpha0 = 0.2\n[friction]\nF1 = 400\nF2 = 800\n{table}\n')
    with pytest.raises(CaseFileError, match=message):
        load_case(path)
    result = runner.invoke(app, ["plan", str(path)])
    assert result.exit_code == 2 and result.output.startswith("error: ") and result.output.count("\n") == 1


def test_alpha0_at_the_geometric_limit_is_rejected(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('[test]\nforce = "1598 kN"\nalpha0 = "90 deg"\n[friction]\nF1 = 400\nF2 = 800\n')
    result = runner.invoke(app, ["plan", str(path)])
    assert result.exit_code == 2 and "alpha0 = '90 deg': expected an angle in (0, pi/2)" in result.output


def test_target_out_of_reach_on_the_command_line(tmp_path):
    text = (EXAMPLES / "plan.toml").read_text().replace('target = "1600 kN"', 'target = "9000 kN"')
    text = text.replace('file = "device_checked.toml"', f'file = "{EXAMPLES / "device_checked.toml"}"')
    text = text.replace('case = "uq_paper.toml"', f'case = "{EXAMPLES / "uq_paper.toml"}"')
    path = tmp_path / "plan.toml"
    path.write_text(text)
    result = runner.invoke(app, ["plan", str(path)])
    assert result.exit_code == 2
    assert "target push force = [8550, 9450] kN is outside what the candidate fuses and angles reach" in result.output


def test_plan_case_without_building_or_fuse():
    plan = plan_case(load_case(EXAMPLES / "larger_push.toml"))
    assert plan.fuse is None and plan.clearance is None
    s = plan.summary()
    # the stroke by hand: E_S of Eq. 2 at P = 2200 kN, alpha0 = 14.32 deg; alpha_F from Eq. 8 by mpmath;
    # u_F = L1 (cos alpha0 - cos alpha_F) (Table 4): 1.4383 m
    a0 = math.radians(14.32)
    aF = float(mp_alpha_final(strain_energy(2200e3, a0, preset("paper")).total, a0, 419.85, 804.57))
    assert s["min_gap_m"] is None and s["stroke_m"] == pytest.approx(2.477 * (math.cos(a0) - math.cos(aF)), rel=1e-10)
