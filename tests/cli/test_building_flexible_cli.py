"""``[building] flexible = true`` and ``quickrelease building --flexible``: a Bouc-Wen layer under a flexible
superstructure, its record made by the independent solve_ivp reference (tests/building/isolator_reference.py,
``simulate_2dof``: no package code), written in the case file's grammar (the LVDT in mm, the base and roof
accelerometers in g0 on their own clock); and the case file's inconsistencies, one line each."""

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parents[1] / "building"))
import isolator_reference as ref  # noqa: E402
from test_building_cli import _one_line_error, run  # noqa: E402  (the CLI's runner and its one-line check)

G0 = 9.80665
M, MS, T, ZETA, FS, QD, DY, TS, ZS, D0, T_R = 8.0e5, 4.8e5, 3.0, 0.03, 2.0e4, 3.9e5, 0.02, 0.5, 0.02, 0.15, 1.0037


def _write_record(folder, duration=11.0, seed=1):
    kd = M * (2 * math.pi / T) ** 2
    system = ref.boucwen(M, kd, QD, DY, 1.0, damping=2 * ZETA * math.sqrt(kd * M), friction=FS)
    ks = MS * (2 * math.pi / TS) ** 2
    t = np.arange(0.0, duration, 0.01)
    mo = ref.simulate_2dof(system, MS, ks, 2 * ZS * math.sqrt(ks * MS), D0, t - T_R, duration)
    acc = ref.simulate_2dof(system, MS, ks, 2 * ZS * math.sqrt(ks * MS), D0, t + 0.002 - T_R, duration)  # own clock
    rng = np.random.default_rng(seed)
    x = mo.x + 0.003 + rng.normal(0, 2e-4, t.size)
    a = acc.a + rng.normal(0, 0.02, t.size)
    a_roof = acc.as_ + rng.normal(0, 0.02, t.size)
    np.savetxt(folder / "x.csv", np.column_stack([t, 1e3 * x]), delimiter=",", header="t_s,x_mm", comments="",
               fmt="%.10g")
    np.savetxt(folder / "acc.csv", np.column_stack([t + 0.002, a / G0, a_roof / G0]), delimiter=",",
               header="t_acc_s,a_base_g,a_roof_g", comments="", fmt="%.10g")


def _case(folder, building="", flexible="flexible = true", mass="superstructure_mass = '480 t'"):
    path = folder / "case.toml"
    path.write_text(f'''title = "Snap-back of a lead-rubber building"
[building]
model = "boucwen"
mass = "800 t"
{flexible}
{mass}
{building}
[building.record]
file = "x.csv"
time = "t_s"
[building.record.channels]
x = {{ column = "x_mm", unit = "mm" }}
a = {{ column = "a_base_g", unit = "g0", file = "acc.csv", time = "t_acc_s" }}
a_roof = {{ column = "a_roof_g", unit = "g0", file = "acc.csv", time = "t_acc_s" }}
''')
    return path


def _check(data):
    fit = data["fit"]
    assert fit["flexible"] is True and fit["label"] == "boucwen (flexible)" and fit["superstructure_mass_kg"] == MS
    truth = {"period": T, "characteristic_strength": QD, "yield_displacement": DY, "superstructure_period": TS,
             "superstructure_damping_ratio": ZS, "damping_ratio": ZETA, "friction": FS}
    for name, value in truth.items():  # (the marginal 95% intervals of ten parameters miss one now and then)
        est, se = fit["estimates"][name], fit["std_errors"][name]
        assert abs(est - value) < 4.0 * se and se < 0.05 * value, (name, est, se, value)
    assert data["superstructure_period_s"] == pytest.approx(fit["estimates"]["superstructure_period"])
    assert fit["isolation"]["model"] == "flexible" and fit["isolation"]["isolation_model"] == "boucwen"


@pytest.mark.slow
def test_a_case_with_flexible_true_fits_the_layer_under_the_storey(tmp_path):
    """``[building] flexible = true`` with superstructure_mass: ``quickrelease building --json`` fits the Bouc-Wen
    layer under the storey; every true value within 4 standard errors (each under 5% of it), the storey's period
    reported beside the layer's values."""
    _write_record(tmp_path)
    r = run("building", _case(tmp_path), "--json")
    assert r.exit_code == 0, r.output
    _check(json.loads(r.stdout))


@pytest.mark.slow
def test_the_flexible_option_on_a_rigid_case(tmp_path):
    """``--flexible`` on a case without ``flexible = true`` (but with superstructure_mass, which a rigid layer's case
    may hold for this and --compare): the same fit."""
    _write_record(tmp_path)
    case = _case(tmp_path, flexible="")
    r = run("building", case, "--flexible", "--json")
    assert r.exit_code == 0, r.output
    _check(json.loads(r.stdout))


def test_flexible_without_the_superstructure_mass_is_one_line(tmp_path):
    _write_record(tmp_path, duration=4.0)
    _one_line_error(run("building", _case(tmp_path, mass=""), "--json"), "superstructure_mass", "flexible = true")
    _one_line_error(run("building", _case(tmp_path, flexible="", mass=""), "--flexible", "--json"),
                    "superstructure_mass", "flexible superstructure needs it")


def test_the_case_file_reads_flexible(tmp_path):
    """``flexible = true``: the data say so, the superstructure's mass and design period come with the layer's start
    values, and the design building is the layer under the storey."""
    from quickrelease.building.flexible import FlexibleBuilding
    from quickrelease.io.building_case import load_building
    from quickrelease.io.case import load_case

    _write_record(tmp_path, duration=4.0)
    body = ("superstructure_period = '0.6 s'\npost_yield_stiffness = '3.5 MN/m'\ncharacteristic_strength = '390 kN'\n"
            "yield_displacement = '20 mm'")
    data = load_building(load_case(_case(tmp_path, body), require_test=False))
    assert data.flexible and data.superstructure_mass == MS
    assert data.start["superstructure_period"] == 0.6
    assert data.start["period"] == pytest.approx(2 * math.pi * math.sqrt(M / 3.5e6), rel=1e-12)
    assert isinstance(data.isolation, FlexibleBuilding) and data.isolation.superstructure_period == 0.6


@pytest.mark.parametrize("body, fragments", [
    ("model = 'linear'", ("flexible = true with model = 'linear'", "model = '2dof'")),
])
def test_flexible_with_what_it_cannot_take_is_one_line(tmp_path, body, fragments):
    _write_record(tmp_path, duration=4.0)
    text = _case(tmp_path).read_text().replace('model = "boucwen"\n', "").replace("[building]\n",
                                                                                  f"[building]\n{body}\n")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    _one_line_error(run("building", path, "--json"), *fragments)


def test_a_storey_key_without_flexible_names_flexible(tmp_path):
    _write_record(tmp_path, duration=4.0)
    _one_line_error(run("building", _case(tmp_path, "superstructure_period = '0.5 s'", flexible=""), "--json"),
                    "[building] superstructure_period", "belongs to model = '2dof' or flexible = true")


@pytest.mark.slow
def test_compare_adds_the_flexible_variant_where_the_superstructure_mass_is_known(tmp_path, monkeypatch):
    """``--compare`` on a rigid Bouc-Wen case that gives the superstructure's mass: the comparison holds the chosen
    layer's flexible variant, ranked first by far (the roof accelerometer rings), and the note names it. (The other
    models are cut to linear here: each costs its own fit, and the ranking of those is tested elsewhere.)"""
    import quickrelease.studies.building_analysis as analysis

    monkeypatch.setattr(analysis, "MODELS", ("linear", "boucwen"))
    _write_record(tmp_path)
    r = run("building", _case(tmp_path, flexible=""), "--compare", "--json")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    assert data["fit"]["flexible"] is False
    table = data["comparison"]
    assert [row["model"] for row in table] == ["boucwen (flexible)", "boucwen", "linear"], table
    assert table[1]["delta_bic"] > 1000
    assert any("supports the boucwen (flexible) model" in note for note in data["notes"])
