"""Parameters a record cannot see (isolation_fit, _lsq, fit.py): standard error inf, no interval, a warning naming
the parameter, valid JSON (null) and "not identified" in the tables; on a record made by the independent
event-located solve_ivp of tests/building_reference.py."""

import json
import math
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from coverage_records import noisy_channels as _channels
from test_isolation_coverage import D0, FS, RELEASE, ZETA, C, K, M, T, _rows

from quickrelease._lsq import identified_covariance, unidentified
from quickrelease.studies.building_analysis import analyse_building

EXAMPLES = Path(__file__).parents[2] / "examples"


def test_unidentified_columns():
    """A zero column and a pair of equal columns (only their sum is seen) are not identified; columns 20 orders
    of magnitude apart in scale, or merely correlated (rho = 0.99), are, and their covariance is the inverse."""
    rng = np.random.default_rng(0)
    a, b, c = rng.normal(size=(3, 50))
    J = np.column_stack([a, np.zeros(50), b, b, c])
    assert unidentified(J).tolist() == [False, True, True, True, False]
    cov, bad = identified_covariance(J)
    assert np.all(np.isinf(np.diag(cov)[bad])) and np.all(cov[bad][:, ~bad] == 0.0)
    expected = np.linalg.inv(np.column_stack([a, c]).T @ np.column_stack([a, c]))
    assert cov[np.ix_(~bad, ~bad)] == pytest.approx(expected, rel=1e-10)
    K2 = np.column_stack([1e-10 * a, 1e10 * (b + 0.99 * a)])
    assert not unidentified(K2).any()
    assert identified_covariance(K2)[0] == pytest.approx(np.linalg.inv(K2.T @ K2), rel=1e-8)


@cache
def _never_yielding():
    """The linear + Coulomb record (T = 2 s, zeta 0.04, F_s 12 kN, d0 0.15 m) fitted with the bilinear model from
    a yield force ten times the largest spring force: the spring never yields, F_y has no effect on the
    residuals (its Jacobian column is 0) and k2 / k1 none either."""
    from unittest import mock

    import quickrelease.building.isolation_fit as isolation_fit

    channels = _channels(_rows(K, K, math.inf, C, FS, D0, 6.0), 3)
    # the design values' local fit alone (no record starts, no global stage): it stays where the spring never
    # yields, the region whose reporting is tested here (the other starts find equally good fits that yield,
    # test_a_record_that_never_yields_has_many_equal_minima)
    with mock.patch.object(isolation_fit, "_start_points", lambda *args, **kwargs: []):
        return analyse_building(channels=channels, mass=M, model="bilinear", global_search=False,
                                start={"stiffness_ratio": 0.5, "yield_force": 10.0 * K * D0})


@pytest.mark.slow
def test_a_record_that_never_yields_has_many_equal_minima():
    """A linear record fitted with the bilinear model: springs that never yield, and springs that yield at any
    force up to the largest reached, describe it alike. The fit's certificate must say so: minima within delta
    chi-square 4 whose yield forces lie below and above the largest spring force k d0, the minimum not
    confirmed, and the 95% interval of F_y covering them."""
    channels = _channels(_rows(K, K, math.inf, C, FS, D0, 6.0), 3)
    fit = analyse_building(channels=channels, mass=M, model="bilinear",
                           start={"stiffness_ratio": 0.5, "yield_force": 10.0 * K * D0}).fit
    close = [m.parameters["yield_force"] for m in fit.search.minima if m.delta_chi2 < 4.0]
    assert min(close) < K * D0 < max(close), close
    assert not fit.global_minimum_confirmed
    lo, hi = fit.ci95["yield_force"]
    assert lo <= min(close) and hi >= max(close)


def test_bilinear_fit_of_a_record_that_never_yields():
    result = _never_yielding()
    fit = result.fit
    assert math.isinf(fit.std_errors["yield_force"]) and all(math.isnan(v) for v in fit.ci95["yield_force"])
    assert fit.interval_method["yield_force"] == "not identified"
    assert any(w.startswith("yield_force not identified by this record") for w in fit.warnings), fit.warnings
    assert any(w.startswith("stiffness_ratio not identified") for w in fit.warnings), fit.warnings
    # the parameters the record does see keep honest standard errors (before: F_y's SE ~1e-9 of F_y)
    truth = {"period": T, "damping_ratio": ZETA, "friction": FS, "d0": D0, "release_time": RELEASE}
    z = {n: (fit.estimates[n] - v) / fit.std_errors[n] for n, v in truth.items()}
    assert all(abs(v) < 4.0 for v in z.values()), z
    summary = result.summary()
    text = json.dumps(summary, allow_nan=False)  # no inf/nan: null
    assert summary["Fy_N_ci95"] is None and summary["not_identified"] == ["k2_N_m", "Fy_N"], summary["not_identified"]
    assert summary["fit"]["std_errors"]["yield_force"] is None and '"yield_force": null' in text


def test_tables_and_report_say_not_identified(capsys):
    from quickrelease.cli import _building_tables
    from quickrelease.report.html import building_section

    result = _never_yielding()
    _building_tables(result, result.summary(), "never yields")
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if "yield force" in line)
    assert "not identified" in row, out
    html = building_section(result, {})
    assert html.count("not identified") >= 2  # the engineering table and the table of every parameter


@pytest.mark.slow
def test_device_fit_writes_a_parameter_it_cannot_see_as_null(monkeypatch):
    """The device's record fit (fit.py) takes the same covariance: a parameter marked unidentified (here the last
    offset, by a wrapper) gets SE inf, a warning, null in ``fit --json`` (written with allow_nan=False) and
    "not identified" in the table."""
    from typer.testing import CliRunner

    import quickrelease.studies.fit as fit_module
    from quickrelease.cli import app

    real = fit_module.identified_covariance

    def blind_last(J):
        cov, bad = real(J)
        bad = bad.copy()
        bad[-1] = True
        cov = cov.copy()
        cov[-1, :] = cov[:, -1] = 0.0
        cov[-1, -1] = math.inf
        return cov, bad

    monkeypatch.setattr(fit_module, "identified_covariance", blind_last)
    runner = CliRunner()
    result = runner.invoke(app, ["fit", str(EXAMPLES / "fit.toml"), "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    last = list(data["std_errors"])[-1]
    assert data["std_errors"][last] is None and data["ci95"][last] == [None, None]
    assert any(w.startswith(f"{last} not identified by this record") for w in data["warnings"])
    table = runner.invoke(app, ["fit", str(EXAMPLES / "fit.toml")])
    assert table.exit_code == 0 and "not identified" in table.output, table.output


def test_campaign_release_with_a_parameter_not_identified():
    """A campaign's release (building_campaign._estimates) on the never-yielding fit: F_y keeps SE inf and no
    interval, the quantities that do not depend on it (the secant period and equivalent damping at d0: the
    spring is elastic there) keep finite standard errors by the delta method (the covariance with an infinite
    variance gave NaN for all of them), and the release's JSON is valid."""
    from quickrelease.studies.building_campaign import BuildingRelease, _estimates

    fit = _never_yielding().fit
    quantities = ("secant_period", "equivalent_damping_ratio", "yield_force", "damping_ratio")
    release = _estimates(BuildingRelease("r1", tuple(fit.channels)), fit, quantities)
    assert math.isinf(release.std_errors["yield_force"]) and release.interval_method["yield_force"] == "not identified"
    for q in ("secant_period", "equivalent_damping_ratio", "damping_ratio"):
        assert math.isfinite(release.std_errors[q]) and release.std_errors[q] > 0.0, (q, release.std_errors)
    summary = json.loads(json.dumps(release.summary(), allow_nan=False))
    assert summary["std_errors"]["yield_force"] is None and summary["ci95"]["yield_force"] == [None, None]
