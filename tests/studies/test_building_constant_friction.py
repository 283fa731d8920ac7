"""`quickrelease building` on a friction pendulum of constant friction (``[building] friction_coefficient``): the fit
holds Constantinou's rate at 0, as building campaigns do (io.building_case.constant_friction_fixed), and reports one
friction coefficient mu with its interval, not mu_slow, mu_fast and a "not identified" rate.

The record comes from the independent reference simulator (tests/building/isolator_reference.py: solve_ivp with
events, no package code): 1000 t on sliders of R = 2.5 m, mu = 1 %, 1 % viscous damping, released from 0.2 m; it
sticks 6.3 s after the release (four half-cycles, each 2 mu R = 50 mm shorter). 8 s at 50 Hz: the fit takes about
1 s (the three-parameter friction law took 40 s on it)."""

import json
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import quickrelease.studies.building_analysis as ba
from quickrelease.building import Pendulum
from quickrelease.cli import _building_tables
from quickrelease.report.html import building_section

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "building"))
import isolator_reference as ref  # noqa: E402
from analysis_capture import invoke_keeping_analysis  # noqa: E402

pytestmark = pytest.mark.usefixtures("few_band_draws")  # the bands' width is not looked at here

G = ref.GRAVITY
M, R, MU, ZETA, D0 = 1.0e6, 2.5, 0.01, 0.01, 0.2
K = M * G / R
RATE, PRE, RELEASE, DURATION, NOISE = 50.0, 1.0, 0.0137, 8.0, 2e-4  # Hz, s, s, s, m

# design values a little off the truth (start values of the fit)
BUILDING = """[building]
model = "pendulum"
mass = "1000 t"
radius = "2.3 m"
damping_ratio = 0.02
"""
RECORD = """[building.record]
file = "x.csv"
time = "t_s"
[building.record.channels]
x = { column = "x_mm", unit = "mm", noise = "0.2 mm" }
"""


def _case(folder: Path, friction: str = "friction_coefficient = 0.007\n") -> Path:
    """The case file and its LVDT record [mm]: 1 s at rest at d0, a 2 mm sensor zero, 0.2 mm noise."""
    t = np.arange(round((PRE + DURATION) * RATE)) / RATE - PRE
    system = ref.pendulum(M, R, MU, damping=2 * ZETA * math.sqrt(K * M))
    x = ref.simulate(system, D0, t - RELEASE).x + 0.002 + np.random.default_rng(3).normal(0.0, NOISE, t.size)
    np.savetxt(folder / "x.csv", np.column_stack([t, 1e3 * x]), delimiter=",", header="t_s,x_mm", comments="",
               fmt="%.10g")
    path = folder / "case.toml"
    path.write_text('title = "constant friction"\n' + BUILDING + friction + RECORD, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def command(tmp_path_factory):
    """`quickrelease building --json` on the constant-friction case, run once: its output and the analysis it printed
    (analyse_building's return, taken on its way to the command)."""
    folder = tmp_path_factory.mktemp("constant")
    path = _case(folder)
    r, kept = invoke_keeping_analysis(["building", str(path), "--json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout), kept[0]


def test_the_constant_friction_fit_holds_the_rate_and_covers_the_truth(command):
    data, result = command
    fit = result.fit
    assert fit.model == "pendulum" and fit.fixed == {"rate": 0.0, "friction_fast": 0.007}  # the case's mu
    assert "rate" not in fit.names and "friction_fast" not in fit.names
    assert "not identified" not in fit.interval_method.values()
    assert data["constant_friction"] is True and data["not_identified"] == []
    for key, truth in (("friction_coefficient", MU), ("radius_m", R), ("damping_ratio", ZETA)):
        lo, hi = data[f"{key}_ci95"]
        assert lo < truth < hi, (key, data[key], lo, hi)
        assert lo < data[key] < hi
    assert data["friction_coefficient"] == fit.estimates["friction_slow"]
    assert hi - lo < 0.2 * ZETA  # an interval, not a parameter's whole range
    lo, hi = data["friction_coefficient_ci95"]
    assert hi - lo < 0.1 * MU
    # one coefficient: none of Constantinou's three keys
    assert not {"friction_slow", "friction_fast", "rate_s_m"} & set(data)
    assert data["Qd_N"] == pytest.approx(data["friction_coefficient"] * M * G, rel=1e-12)  # mu W at x = 0


def test_the_tables_and_the_report_name_one_friction_coefficient(command, capsys):
    data, result = command
    _building_tables(result, data, "t")
    table = capsys.readouterr().out
    assert "│ friction coefficient mu " in table and "friction slow" not in table and "rate" not in table
    report = building_section(result, {})  # the report's building section (figures left out)
    assert 'id="building-friction_coefficient"' in report and 'id="building-radius_m"' in report
    assert "building-rate_s_m" not in report and "building-friction_fast" not in report


def test_constantinou_cases_and_other_models_keep_the_free_friction_law(tmp_path, monkeypatch):
    """What analyse_building hands fit_isolation (each call recorded): the constant-friction case holds the rate at 0
    (and mu_fast at the case's mu) in the chosen pendulum fit and in the compared pendulum fit, and nowhere else; a
    case with Constantinou's friction_slow, friction_fast and rate holds nothing."""
    from quickrelease.io.building_case import load_building
    from quickrelease.io.case import load_case

    calls = []

    def recorded(channels, mass, model, **kwargs):
        calls.append((model, kwargs.get("fixed")))
        raise ba.QuickReleaseError("recorded")

    monkeypatch.setattr(ba, "fit_isolation", recorded)
    constant = load_building(load_case(_case(tmp_path), require_test=False))
    assert constant.constant_friction
    for model in ("pendulum", "linear"):
        calls.clear()
        with pytest.raises(ba.QuickReleaseError, match="recorded"):
            ba.analyse_building(constant, model=model)
        assert calls == [(model, {"rate": 0.0, "friction_fast": 0.007} if model == "pendulum" else None)]
    law = load_building(load_case(_case(tmp_path, "friction_slow = 0.01\nfriction_fast = 0.03\nrate = '20 s/m'\n"),
                                  require_test=False))
    assert not law.constant_friction
    calls.clear()
    with pytest.raises(ba.QuickReleaseError, match="recorded"):
        ba.analyse_building(law)
    assert calls == [("pendulum", None)]
    # --compare: the compared pendulum of a constant-friction case holds the rate too (the analysis stopped once
    # the models are fitted)
    fits = []

    def stub(channels, mass, model, **kwargs):
        fits.append((model, kwargs.get("fixed")))
        return SimpleNamespace(model=model, excluded={}, warnings=())

    def stop(compared):
        raise ba.QuickReleaseError("compared")

    monkeypatch.setattr(ba, "fit_isolation", stub)
    monkeypatch.setattr(ba, "_check_long_enough", lambda fit, prefix: None)
    monkeypatch.setattr(ba, "compare_models", stop)
    with pytest.raises(ba.QuickReleaseError, match="compared"):
        ba.analyse_building(constant, model="linear", compare=True)
    assert fits[0] == ("linear", None) and ("pendulum", {"rate": 0.0, "friction_fast": 0.007}) in fits
    assert all(fixed is None for model, fixed in fits if model != "pendulum") and len(fits) >= 4


def test_the_identified_constant_friction_pendulum_in_the_clearance_note():
    """The whole test's clearance check carries the fitted mu as the case's friction_coefficient: mu_fast and the
    rate left out (None, as a case with friction_coefficient reads), the note names "friction coefficient mu"."""
    from quickrelease.io.case import BuildingSpec
    from quickrelease.workflow import identified_building

    spec = BuildingSpec(model="pendulum", mass=M, radius=2.3, friction_coefficient=0.007, friction_slow=0.007,
                        damping_ratio=0.02, displacement=D0)
    T = 2 * math.pi * math.sqrt(R / G)
    est = {"period": T, "friction_slow": 0.0101, "damping_ratio": ZETA, "d0": D0}
    for fixed, constant in (({"rate": 0.0, "friction_fast": 0.007}, True), ({}, False)):
        params = {**fixed, **est} if constant else {**est, "friction_fast": 0.03, "rate": 20.0}
        fit = SimpleNamespace(model="pendulum", mass=M, parameters=params, fixed=fixed, std_errors={},
                              damping="viscous", isolation=lambda p=params: Pendulum(
                                  M, R, p["friction_slow"], p["friction_fast"], p["rate"]))
        identified, note = identified_building(spec, SimpleNamespace(fit=fit))
        assert identified.friction_slow == 0.0101 and identified.friction_coefficient == 0.0101
        if constant:
            assert identified.friction_fast is None and identified.rate is None
            assert "friction coefficient mu = 0.0101" in note and "mu_slow" not in note, note
        else:
            assert identified.friction_fast == 0.03 and identified.rate == 20.0
            assert "friction mu_slow = 0.0101" in note and "friction coefficient" not in note, note
