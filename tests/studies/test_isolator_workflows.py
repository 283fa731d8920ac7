"""The isolation systems in use today (issue 24) in planning and synth: a friction pendulum, lead-rubber bearings
(Bouc-Wen) and fluid viscous dampers (damping = "power"), checked against hand calculations written here."""

import math

import pytest
from scipy.optimize import brentq

from quickrelease.io.case import load_case
from quickrelease.report.html import _building_design
from quickrelease.studies.planning import plan_case
from quickrelease.studies.synth import predicted_building_errors, synthesize_building

G = 9.80665
P = 1598e3  # N, the planned push

HEAD = f"""[device]
preset = "paper"
[test]
force = "{P / 1e3} kN"
alpha0 = "0.2 rad"
mass_model = "distributed"
[friction]
F1 = "419.85 N"
F2 = "804.57 N"
"""


def case(tmp_path, building: str, head: str = HEAD):
    path = tmp_path / "case.toml"
    path.write_text(head + "[building]\n" + building, encoding="utf-8")
    return load_case(path, require_test=False)


PENDULUM = 'model = "pendulum"\nmass = "1200 t"\nradius = "2.5 m"\nfriction_coefficient = 0.03\n'
BOUCWEN = ('model = "boucwen"\nmass = "1200 t"\npost_yield_stiffness = "2.4 MN/m"\ncharacteristic_strength = '
           '"600 kN"\nyield_displacement = "25 mm"\nshape = 1.0\n')


def test_plan_of_a_pendulum_uses_the_weight_over_the_radius_and_the_friction(tmp_path):
    """Pushed by P, the pendulum holds it with W d0 / R + mu W, so d0 = (P / W - mu) R; released, it swings for
    half its period pi sqrt(R / g) (whatever the mass) to -(d0 - 2 mu R) (Coulomb: 2 mu R lost a half-cycle)."""
    R, mu, W = 2.5, 0.03, 1200e3 * G
    plan = plan_case(case(tmp_path, PENDULUM))
    c = plan.clearance
    d0 = (P / W - mu) * R
    assert c.d0 == pytest.approx(d0, rel=1e-12)
    assert c.building_period == pytest.approx(2 * math.pi * math.sqrt(R / G), rel=1e-12)
    assert c.first_return_time == pytest.approx(math.pi * math.sqrt(R / G), rel=1e-9)
    assert c.max_approach == pytest.approx(d0 + (d0 - 2 * mu * R), rel=1e-6)  # sampled on the clearance's grid
    assert c.summary()["building_period_s"] == c.building_period
    text = _building_design(plan.case.building, c.building_period)
    assert "R = 2.5 m" in text and f"{2 * math.pi * math.sqrt(R / G):.5f}" in text and "friction 0.03" in text


def test_plan_of_lead_rubber_bearings_pushes_along_the_bouc_wen_curve(tmp_path):
    """n = 1 from rest: dz/dx = (1 - z) / dy, so z = 1 - exp(-x / dy) and P = Kd d0 + Qd (1 - exp(-d0 / dy))."""
    Kd, Qd, dy, m = 2.4e6, 600e3, 0.025, 1200e3
    c = plan_case(case(tmp_path, BOUCWEN)).clearance
    d0 = brentq(lambda d: Kd * d + Qd * (1 - math.exp(-d / dy)) - P, 1e-9, P / Kd, xtol=1e-15)
    assert c.d0 == pytest.approx(d0, rel=1e-9)
    assert c.building_period == pytest.approx(2 * math.pi * math.sqrt(m / Kd), rel=1e-12)
    assert c.first_return_time is not None and 0 < c.max_approach < 2 * d0


def test_plan_with_fluid_viscous_dampers_ends_and_pushes_as_without_them(tmp_path):
    """A damper carries no force at rest: the push is the bearings' alone; the clearance of each friction draw
    needs the first return only (before: 100 periods of the damper's creep per draw, minutes)."""
    power = BOUCWEN + 'damping = "power"\ndamping_coefficient = "300 kN"\ndamping_exponent = 0.5\n'
    with_dampers = plan_case(case(tmp_path, power)).clearance
    without = plan_case(case(tmp_path, BOUCWEN)).clearance
    assert with_dampers.d0 == pytest.approx(without.d0, rel=1e-12)
    assert with_dampers.max_approach < without.max_approach  # the dampers take energy out of the first swing
    assert with_dampers.first_return_time is not None




def synth_case(tmp_path, building: str):
    path = tmp_path / "b.toml"
    path.write_text("[building]\n" + building + 'displacement = "250 mm"\n', encoding="utf-8")
    return load_case(path, require_test=False)


def test_synth_of_a_pendulum_swings_to_the_coulomb_amplitude_and_reports_its_precision(tmp_path):
    R, mu, d0 = 2.5, 0.03, 0.25
    syn = synthesize_building(synth_case(tmp_path, PENDULUM), ["x", "a"], rate=200.0, release_time=1.0,
                              duration=8.0)
    x = syn.clean["x"]
    assert x.min() == pytest.approx(-(d0 - 2 * mu * R), abs=2e-5)  # a 200 Hz sample within 1e-4 of the extreme
    assert syn.truth["period_s"] == pytest.approx(2 * math.pi * math.sqrt(R / G), rel=1e-12)
    rows = predicted_building_errors(syn).physical()
    T, se_T = rows["period_s"]["truth"], rows["period_s"]["se"]
    assert rows["radius_m"]["truth"] == pytest.approx(R, rel=1e-12)
    assert rows["radius_m"]["se"] == pytest.approx(2 * R / T * se_T, rel=1e-12)  # R = g (T / 2 pi)^2
    # a constant friction_coefficient: the constant-friction fit's one coefficient (rate and mu_fast held)
    assert "friction_coefficient" in rows and not {"friction_slow", "friction_fast", "rate_s_m"} & set(rows)
    assert list(rows).index("radius_m") == list(rows).index("period_s") + 1


def test_synth_with_power_dampers_reports_the_damper_law(tmp_path):
    power = BOUCWEN + 'damping = "power"\ndamping_coefficient = "300 kN"\ndamping_exponent = 0.5\n'
    syn = synthesize_building(synth_case(tmp_path, power), ["x"], rate=100.0, release_time=1.0, duration=10.0)
    rows = predicted_building_errors(syn).physical()
    assert rows["damping_coefficient"]["truth"] == 300e3 and rows["damping_exponent"]["truth"] == 0.5
    assert rows["Kd_N_m"]["truth"] == pytest.approx(2.4e6, rel=1e-12)
    assert {"Qd_N", "dy_m", "shape"} <= set(rows) and "damping_ratio" not in rows


PENDULUM_LAW = ('model = "pendulum"\nmass = "1200 t"\nradius = "2.5 m"\nfriction_slow = 0.03\nfriction_fast = 0.06\n'
                'rate = "30 s/m"\n')
POWER = BOUCWEN + 'damping = "power"\ndamping_coefficient = "300 kN"\ndamping_exponent = 0.5\n'


@pytest.mark.parametrize("building", [PENDULUM_LAW, POWER], ids=["pendulum", "boucwen-power"])
def test_the_predicted_rows_line_up_with_the_fitted_ones(tmp_path, building):
    """The precision's rows carry the keys, in the order, of the fitted values in the building's JSON
    (studies.building_analysis.physical_estimates), so predicted and fitted rows of each model line up."""
    from types import SimpleNamespace

    from quickrelease.building.isolation_fit import _isolation
    from quickrelease.studies.building_analysis import physical_estimates

    syn = synthesize_building(synth_case(tmp_path, building), ["x"], rate=50.0, release_time=1.0, duration=4.0)
    pred = predicted_building_errors(syn)
    t = syn.truth
    fit = SimpleNamespace(model=t["model"], mass=t["mass_kg"], estimates=dict(pred.parameters), ci95={},
                          interval_method={}, parameters=dict(pred.parameters),
                          damping="power" if "damping_exponent" in pred.parameters else "viscous",
                          isolation=lambda: _isolation(t["model"], t["mass_kg"], pred.parameters))
    fitted = [k for k in physical_estimates(fit) if not k.endswith("_ci95") and k not in ("not_identified",
                                                                                         "interval_method")]
    predicted = [k for k in pred.physical() if k not in ("d0_m", "release_time_s") and not k.startswith("offset_")]
    assert predicted == fitted
    assert set(fitted) >= ({"radius_m", "friction_slow", "friction_fast", "rate_s_m"} if t["model"] == "pendulum"
                           else {"Kd_N_m", "Qd_N", "dy_m", "shape", "damping_coefficient", "damping_exponent"})


@pytest.mark.parametrize("name", ["pendulum", "boucwen"])
def test_synth_json_and_table_give_the_new_models_rows(tmp_path, name):
    """`quickrelease synth --building --json` (planning the instrumentation): under predicted.parameters the
    pendulum's R = g (T / 2 pi)^2 with se(R) = 2 R / T se(T) and its friction law, the Bouc-Wen bearings' Kd =
    m (2 pi / T)^2 with se(Kd) = 2 Kd / T se(T), Qd, dy, n and the sliders' F_s, each with the standard error of
    its own parameter; the printed table has a row for each. (The power-law damper's rows: the two tests above;
    its synthetic record costs 2 s here, the viscous one's nothing.)"""
    import json

    from typer.testing import CliRunner

    from quickrelease.cli import app

    runner = CliRunner()
    args = ["--channels", "x", "--rate", "50 Hz", "--release-time", "1 s", "--duration", "4 s",
            "--noise", "x=0.1 mm"]
    keys = {"pendulum": ("friction_slow", "friction_fast", "rate"),
            "boucwen": ("characteristic_strength", "yield_displacement", "shape", "damping_ratio", "friction")}
    json_keys = {"rate": "rate_s_m", "characteristic_strength": "Qd_N", "yield_displacement": "dy_m",
                 "friction": "friction_N"}
    building = {"pendulum": PENDULUM_LAW, "boucwen": BOUCWEN + 'friction = "20 kN"\ndamping_ratio = 0.02\n'}[name]
    (tmp_path / f"{name}.toml").write_text("[building]\n" + building + 'displacement = "250 mm"\n')
    r = runner.invoke(app, ["synth", str(tmp_path / f"{name}.toml"), "--building", *args, "--out",
                            str(tmp_path / f"{name}.csv"), "--overwrite", "--json"])
    assert r.exit_code == 0, r.output
    pred = json.loads(r.stdout)["predicted"]
    rows, se = pred["parameters"], pred["std_errors"]
    T, se_T = rows["period_s"]["truth"], rows["period_s"]["se"]
    assert se_T == se["period"] and 0 < se_T < T
    if name == "pendulum":
        R = G * (T / (2 * math.pi)) ** 2
        assert R == pytest.approx(2.5, rel=1e-12)
        assert rows["radius_m"]["truth"] == pytest.approx(R, rel=1e-12)
        assert rows["radius_m"]["se"] == pytest.approx(2 * R / T * se_T, rel=1e-9)
        assert rows["rate_s_m"]["truth"] == 30.0 and rows["rate_s_m"]["unit"] == "s/m"
    else:
        Kd = 1200e3 * (2 * math.pi / T) ** 2
        assert Kd == pytest.approx(2.4e6, rel=1e-12)
        assert rows["Kd_N_m"]["truth"] == pytest.approx(Kd, rel=1e-12)
        assert rows["Kd_N_m"]["se"] == pytest.approx(2 * Kd / T * se_T, rel=1e-9)
        assert rows["Qd_N"]["truth"] == 600e3 and rows["friction_N"]["truth"] == 20e3
    for n in keys[name]:
        assert rows[json_keys.get(n, n)]["se"] == pytest.approx(se[n], rel=1e-9), n
    r = runner.invoke(app, ["synth", str(tmp_path / f"{name}.toml"), "--building", *args, "--out",
                            str(tmp_path / f"{name}.csv"), "--overwrite"])
    assert r.exit_code == 0, r.output
    table = r.stdout[r.stdout.index("Precision of a"):]
    labels = {"pendulum": ("period T", "radius", "friction slow", "friction fast", "rate"),
              "boucwen": ("period T", "Kd", "Qd", "dy", "shape", "damping ratio zeta", "slider friction F_s")}
    for label in labels[name]:
        assert f"│ {label} " in table, (label, table)


def test_the_whole_test_carries_an_identified_pendulum_into_the_clearance(tmp_path):
    """The run's clearance uses the pendulum fitted to the record (before: the assumed values, with a note): its
    radius from the fitted period, R = g (T / 2 pi)^2, and the fitted friction law and d0."""
    from types import SimpleNamespace

    from quickrelease.building import Pendulum
    from quickrelease.studies.planning import clearance
    from quickrelease.workflow import identified_building

    spec = case(tmp_path, PENDULUM).building
    T, d0 = 3.0, 0.2
    est = {"period": T, "friction_slow": 0.025, "friction_fast": 0.025, "rate": 0.0, "damping_ratio": 0.0, "d0": d0}
    R = G * (T / (2 * math.pi)) ** 2
    fit = SimpleNamespace(model="pendulum", mass=1200e3, parameters=est, std_errors={}, damping="viscous",
                          isolation=lambda: Pendulum(1200e3, R, 0.025, 0.025, 0.0))
    identified, note = identified_building(spec, SimpleNamespace(fit=fit))
    assert "identified from its record (pendulum model" in note and "radius R = 2.2" in note
    assert identified.radius == pytest.approx(R, rel=1e-12) and identified.friction_fast == 0.025
    assert identified.friction_force == pytest.approx(0.025 * 1200e3 * G, rel=1e-12)  # mu_slow W holds it
    release = plan_case(case(tmp_path, PENDULUM))
    c = clearance(_first_integral(release), identified, d0)
    assert c.building_period == pytest.approx(T, rel=1e-12)
    assert c.first_return_time == pytest.approx(T / 2, rel=1e-9)  # constant friction: half a period


def _first_integral(plan):
    from quickrelease.device.solvers import FirstIntegral

    case_, env, d = plan.case, plan.envelope, plan.case.device
    return FirstIntegral(case_.stored_energy, case_.alpha0, env.F1, env.F2, d.m1, d.m2, d.L1, case_.mass_factor)


@pytest.mark.slow
def test_the_bouc_wen_summary_keeps_its_qd_with_its_own_interval(tmp_path):
    """With sliders beside the lead-rubber bearings, the JSON's Qd_N is the bearings' fitted Qd inside its own 95%
    interval (before: overwritten by Qd + F_s, outside the interval printed beside it); F_s is friction_N."""
    from quickrelease.studies.building_analysis import analyse_building

    text = BOUCWEN.replace('mass = "1200 t"', 'mass = "1200 t"\nfriction = "60 kN"') + 'damping_ratio = 0.02\n'
    syn = synthesize_building(synth_case(tmp_path, text), ["x", "a"], rate=50.0, release_time=1.0, duration=12.0)
    start = {k: v for k, v in syn.fit_parameters().items() if not k.startswith("offset_")}
    result = analyse_building(channels=syn.building_channels(), mass=1200e3, model="boucwen", start=start,
                              global_search=False)
    s = result.summary()
    lo, hi = s["Qd_N_ci95"]
    assert lo <= s["Qd_N"] <= hi
    assert s["Qd_N"] == pytest.approx(result.fit.estimates["characteristic_strength"], rel=1e-12)
    assert s["friction_N"] == pytest.approx(result.fit.estimates["friction"], rel=1e-12)
