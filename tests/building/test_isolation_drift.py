"""A drifting sensor zero (issue 21, item 6): ``BuildingChannel(drift=True)`` / ``drift = true`` in
``[building.record]`` fits ``drift_<channel>`` beside the offset.

The records come from the independent event-located solve_ivp of tests/building_reference.py; the drift is
written into them here (a straight line of known slope), so the truth of every parameter is known.
"""

import json
import math

import numpy as np
import pytest
from building_reference import reference
from typer.testing import CliRunner

from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation
from quickrelease.cli import app
from quickrelease.errors import QuickReleaseError
from quickrelease.io.building_case import load_building
from quickrelease.io.case import load_case
from quickrelease.io.records import RecordError, parse_record_spec

M, T, ZETA, FS, D0 = 8.0e5, 2.5, 0.05, 0.008 * 8.0e5 * 9.81, 0.15
RELEASE, RATE = 2.0137, 200.0
DRIFT = 4.0e-5  # m/s: 2.4 mm over the minute, twelve noise levels
NOISE_X, NOISE_A = 2e-4, 0.02


def _record(drift: float, seed: int = 4):
    k = M * (2 * math.pi / T) ** 2
    t = np.arange(round(60.0 * RATE)) / RATE
    (x, _, a), _ = reference(M, k, k, math.inf, 2 * ZETA * math.sqrt(k * M), FS, D0, t - RELEASE, with_rates=True)
    rng = np.random.default_rng(seed)
    x = x + 0.002 + drift * t + rng.normal(0, NOISE_X, t.size)  # the LVDT's zero: 2 mm at t = 0, creeping
    a = a + 0.01 + rng.normal(0, NOISE_A, t.size)
    return t, x, a


def _covers(fit, name, truth):
    lo, hi = fit.ci95[name]
    return lo <= truth <= hi


@pytest.fixture(scope="module")
def drifting_fits():  # two fits with the global stage: the tests that use it are slow
    t, x, a = _record(DRIFT)
    plain = fit_isolation([BuildingChannel("x", "x", t, x), BuildingChannel("a", "a", t, a)], M)
    drifting = fit_isolation([BuildingChannel("x", "x", t, x, drift=True), BuildingChannel("a", "a", t, a)], M)
    return plain, drifting


@pytest.mark.slow
def test_a_drifting_zero_is_fitted_and_the_building_comes_back(drifting_fits):
    plain, fit = drifting_fits
    assert "drift_x" in fit.names and "drift_x" not in plain.names
    assert _covers(fit, "drift_x", DRIFT)
    for name, truth in (("period", T), ("damping_ratio", ZETA), ("friction", FS), ("d0", D0)):
        assert _covers(fit, name, truth), (name, fit.ci95[name], truth)
    # the offset is the zero at the drift's origin (the detected release), the line written above
    assert fit.drift_origin == pytest.approx(RELEASE, abs=0.1)
    assert fit.estimates["offset_x"] == pytest.approx(0.002 + DRIFT * fit.drift_origin, abs=3 * fit.std_errors["offset_x"])
    assert fit.chi2_reduced == pytest.approx(1.0, abs=0.1)
    # without the drift parameter the same record is misfitted (the rest creeps away from the model)
    assert plain.chi2 - fit.chi2 > 1000.0
    summary = fit.summary()
    assert summary["units"]["drift_x"] == "m/s"
    assert summary["drift_origin_s"] == fit.drift_origin
    # the model drawn with the channel's zero follows the record: residuals at the noise
    ch = fit.channels[0]
    resid = ch.values - fit.model_values(ch)
    assert np.std(resid[ch.t > 20.0]) == pytest.approx(NOISE_X, rel=0.1)


def test_a_steady_zero_fitted_with_a_drift_finds_none():
    t, x, a = _record(0.0, seed=5)
    fit = fit_isolation([BuildingChannel("x", "x", t, x, drift=True), BuildingChannel("a", "a", t, a, drift=True)],
                        M, global_search=False)
    assert _covers(fit, "drift_x", 0.0) and _covers(fit, "drift_a", 0.0)
    assert fit.summary()["units"]["drift_a"] == "m/s^3"
    assert _covers(fit, "period", T) and _covers(fit, "friction", FS)


@pytest.mark.slow
def test_the_case_file_reads_drift_for_the_building_only(tmp_path):
    t, x, a = _record(DRIFT)
    np.savetxt(tmp_path / "rec.csv", np.column_stack([t, 1e3 * x, a]), delimiter=",", header="t_s,x_mm,a",
               comments="", fmt="%.10g")
    (tmp_path / "case.toml").write_text(
        'title = "drift"\n[building]\nmass = "800 t"\n[building.record]\nfile = "rec.csv"\ntime = "t_s"\n'
        '[building.record.channels]\nx = { column = "x_mm", unit = "mm", drift = true }\na = "a"\n')
    data = load_building(load_case(tmp_path / "case.toml", require_test=False))
    assert {c.name: c.drift for c in data.channels} == {"x": True, "a": False}
    with pytest.raises(RecordError, match="drift = true: a drifting zero is fitted for the building's channels only"):
        parse_record_spec({"file": "r.csv", "time": "t", "channels": {"u": {"column": "u", "drift": True}}}, "c.toml",
                          tmp_path)
    with pytest.raises(QuickReleaseError, match="channels.x: drift = 'yes': expected true or false"):
        load_case(_edited(tmp_path, "drift = true", 'drift = "yes"'), require_test=False)
    out = CliRunner().invoke(app, ["building", str(tmp_path / "case.toml"), "--json"])
    assert out.exit_code == 0, out.output
    summary = json.loads(out.stdout)
    fit = summary.get("fit", summary)
    assert "drift_x" in fit["estimates"] and fit["units"]["drift_x"] == "m/s"
    lo, hi = fit["ci95"]["drift_x"]
    assert lo <= DRIFT <= hi


def _edited(folder, old, new):
    path = folder / "edited.toml"
    path.write_text((folder / "case.toml").read_text().replace(old, new))
    return path
