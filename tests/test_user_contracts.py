"""What users rely on, each against a value the code did not compute (issue 22, items 10-18).

Each test names the plausible bug it was written against (planted, seen failing, reverted): a building pushed to
exactly its stick limit, the push force's sign, AIC/BIC against their definitions, the "did not move" status, the
uq percentiles of F2, the plan's defaults, the NetCDF units and long names, the report's unit scaling and the
files ``run --json`` lists.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from quickrelease import batch
from quickrelease.building.model import Isolation, free_vibration, pushed_state

ROOT = Path(__file__).resolve().parent.parent

# -- 10. a building pushed to exactly its stick limit never moves -----------------------------------------------

# k d0 = F_s exactly in binary floating point: k = 2^21 N/m, d0 = 2^-7 m, F_s = 2^14 N.
K_EXACT, D0_EXACT, FS_EXACT = 2.0**21, 2.0**-7, 2.0**14


@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("damping", [0.0, 3.0e4])
def test_building_pushed_exactly_to_its_stick_limit_never_moves(sign, damping):
    """|k d0| = F_s: the sliders hold the building where it was pushed (the condition is |R| <= F_s, equality
    included). A strict inequality lets it start a half-cycle from its own equilibrium."""
    assert K_EXACT * D0_EXACT == FS_EXACT  # the premise, exact
    iso = Isolation(mass=2.0e5, stiffness=K_EXACT, damping=damping, friction=FS_EXACT)
    d0 = sign * D0_EXACT
    fv = free_vibration(iso, d0)
    assert fv.stop_time == 0.0
    assert fv.pieces == ()
    assert fv.rest == (d0, 0.0)
    assert list(fv.reversal_times) == [0.0] and list(fv.turning_points) == [d0]
    x, v, a = fv.state(np.array([0.0, 0.5, 3.0]))
    assert np.all(x == d0) and np.all(v == 0.0) and np.all(a == 0.0)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_building_pushed_past_its_stick_limit_makes_one_half_cycle(sign):
    """Undamped, |k d0| = 1.5 F_s: it swings about x_eq = sign F_s / k to 2 x_eq - d0, where |R| = 0.5 F_s <= F_s
    holds it: the stop time is half the period, pi sqrt(m / k), by hand."""
    m = 2.0e5
    iso = Isolation(mass=m, stiffness=K_EXACT, friction=FS_EXACT)
    d0 = sign * 1.5 * D0_EXACT
    fv = free_vibration(iso, d0)
    assert fv.stop_time == pytest.approx(math.pi * math.sqrt(m / K_EXACT), rel=1e-12)
    assert [p.end for p in fv.pieces] == ["stick"]
    assert fv.rest[0] == pytest.approx(sign * 0.5 * D0_EXACT, rel=1e-12)


# -- 11. the push force holds the restoring force and the friction, in either direction --------------------------

@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_pushed_state_push_force_linear(sign):
    """P = k d0 + F_s sign(d0): the jack overcomes the spring and the sliders' friction, both against it."""
    k, Fs, d0 = 3.0e6, 2.5e4, sign * 0.12
    iso = Isolation(mass=1.0e5, stiffness=k, friction=Fs)
    z0, R0, P = pushed_state(iso, d0)
    assert z0 == 0.0
    assert R0 == pytest.approx(sign * 3.6e5, rel=1e-15)
    assert P == pytest.approx(sign * (3.6e5 + 2.5e4), rel=1e-15)


@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("d0, R0", [(0.01, 2.0e5),  # elastic: k1 d0, below d_y = F_y / k1 = 0.02 m
                                    (0.12, 4.0e5 + 2.0e6 * 0.10)])  # yielded: F_y + k2 (d0 - d_y)
def test_pushed_state_push_force_bilinear(sign, d0, R0):
    """The bilinear push curve by hand: k1 = 2e7 N/m up to F_y = 4e5 N (d_y = 0.02 m), then k2 = 2e6 N/m;
    P = R0 + F_s sign(d0) with F_s = 3e4 N."""
    iso = Isolation.bilinear(1.0e5, 2.0e7, 2.0e6, 4.0e5, friction=3.0e4)
    z0, R, P = pushed_state(iso, sign * d0)
    assert R == pytest.approx(sign * R0, rel=1e-14)
    assert P == pytest.approx(sign * (R0 + 3.0e4), rel=1e-14)


# -- 13. identification of a device that did not move ------------------------------------------------------------

def test_batch_identify_alpha_final_equal_to_alpha0_is_did_not_move():
    """alpha_F = alpha0 (the device did not open) is status 3, "alpha_final not in (alpha0, pi/2)", with NaN
    friction; the next float above alpha0 is not refused for that reason."""
    a0 = 0.2
    ident = batch.identify(np.array([a0, a0, a0]), np.array([a0, np.nextafter(a0, 1.0), 0.7378]),
                           np.array([1.05, 1.05, 1.05]), np.array([2900.0, 2900.0, 2900.0]))
    assert ident.status[0] == 3
    assert batch.IDENTIFY_STATUS[3] == "alpha_final not in (alpha0, pi/2)"
    assert math.isnan(ident.F1[0]) and math.isnan(ident.F2[0])
    assert ident.status[1] != 3  # it moved by one ulp: refused for its stop time, not for not moving
    assert ident.status[2] == 0
    assert ident.reasons()["alpha_final not in (alpha0, pi/2)"] == 1


# -- 12. AIC and BIC as defined ----------------------------------------------------------------------------------

def _building_record(seed: int, noise: float | None):
    """A linear isolation's free vibration (independent solve_ivp, tests/building_reference.py), 100 Hz
    displacement with 0.2 mm noise and a 1 s quiet segment before the release at 0.5 s."""
    from building_reference import reference

    from quickrelease.building.isolation_fit import BuildingChannel

    m, T, zeta, Fs, d0 = 4.0e5, 2.0, 0.05, 1.2e4, 0.15
    k = m * (2 * math.pi / T) ** 2
    t = np.arange(-1.0, 6.0, 0.01)
    x = reference(m, k, k, math.inf, 2 * zeta * math.sqrt(k * m), Fs, d0, t - 0.5)[0]
    rng = np.random.default_rng(seed)
    return m, [BuildingChannel("lvdt", "x", t, x + 0.003 + rng.normal(0.0, 2e-4, t.size), noise=noise)]


def test_building_fit_aic_bic_are_their_definitions():
    """AIC = chi2 + 2 p and BIC = chi2 + p ln n with the noise given (chi2 recomputed here from the fitted
    model's residuals), p counted here: period, damping ratio, friction, d0, release time and the sensor's
    offset (6); n the samples (700)."""
    from quickrelease.building.isolation_fit import fit_isolation

    m, channels = _building_record(3, noise=2e-4)
    fit = fit_isolation(channels, m, "linear")
    p, n = 6, 700
    assert channels[0].t.size == n and len(fit.names) == p
    ch = channels[0]
    chi2 = float(np.sum(((ch.values - fit.model_values(ch)) / 2e-4) ** 2))
    assert fit.chi2 == pytest.approx(chi2, rel=1e-9)
    assert fit.aic == pytest.approx(chi2 + 2 * p, rel=1e-9)
    assert fit.bic == pytest.approx(chi2 + p * math.log(n), rel=1e-9)
    assert fit.dof == n - p


def test_building_fit_aic_bic_with_the_noise_from_the_residuals():
    """No noise level known: the chi-square is scaled by its reduced value, chi2 / (chi2 / (n - p)) = n - p, so
    AIC = n - p + 2 p = n + p and BIC = n - p + p ln n, whatever the residuals."""
    from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation

    m, channels = _building_record(4, noise=None)
    ch = channels[0]
    moving = ch.t >= 0.45  # 5 samples before the release: no quiet segment, the noise comes from the residuals
    channels = [BuildingChannel(ch.name, ch.kind, ch.t[moving], ch.values[moving])]
    fit = fit_isolation(channels, m, "linear", release_time=0.5)
    p, n = 6, int(moving.sum())
    assert fit.noise_source == {"lvdt": "residuals"} and len(fit.names) == p
    assert fit.aic == pytest.approx(n + p, rel=1e-9)
    assert fit.bic == pytest.approx(n - p + p * math.log(n), rel=1e-9)


# -- 14. uq: the percentiles of F2 as well as F1's ---------------------------------------------------------------

def test_uq_percentiles_of_both_frictions_match_exact_ones(tmp_path):
    """The histogram percentiles of F1 and F2 within two bins of numpy's exact percentiles of the same 40,000
    identified samples (chunk 0 draws from SeedSequence([seed, 0])). Reading F2 on F1's histogram edges moves its
    median by 1.8%, hundreds of bins."""
    from conftest import UQ_CASE

    from quickrelease.io.case import load_case
    from quickrelease.studies import uq

    path = tmp_path / "uq.toml"
    path.write_text(UQ_CASE)
    case = load_case(path)
    r = uq.run_uq(case, 40_000, seed=1, chunk=40_000)
    rng = np.random.default_rng(np.random.SeedSequence([1, 0]))
    ident = uq._identify(case, uq._inputs(case, rng, 40_000))
    ok = ident.status == 0
    for name in ("F1", "F2"):
        values = getattr(ident, name)[ok]
        exact = np.percentile(values, [2.5, 50, 97.5])
        got = [r.percentiles[name][k] for k in ("p2.5", "p50", "p97.5")]
        resolution = (1.25 * np.nanmax(getattr(ident, f"{name}_max"))) / 65536  # the bins span 0 to 1.25 F*
        assert r.resolution[name] < 2 * resolution
        np.testing.assert_allclose(got, exact, atol=2 * r.resolution[name], err_msg=name)
        assert r.mean[name] == pytest.approx(values.mean(), rel=1e-12)
        assert r.std[name] == pytest.approx(values.std(ddof=1), rel=1e-10)


# -- 15. the plan's defaults -------------------------------------------------------------------------------------

PLAN_CASE = """
title = "plan defaults"
[test]
force = "1598 kN"
alpha0 = "0.2 rad"
[friction]
F1 = { value = "420 N", std = "30 N" }
F2 = { value = "805 N", std = "40 N" }
[fuse]
rupture_strength = "610 MPa"
[building]
period = "2.5 s"
damping_ratio = 0.1
mass = "1200 t"
friction = "100 kN"
"""


def test_plan_defaults_used_by_a_case_that_omits_them(tmp_path):
    """A case without [plan], without [fuse] target, tolerance, diameters or angles and without the building's
    displacement: 20,000 friction samples drawn with seed 0 (F1 and F2 independent normals, drawn here), the
    target P +- 5%, the device's own fuse at the case's angle, and d0 = (P - F_f) / k with k = m (2 pi / T)^2."""
    from quickrelease.io.case import load_case
    from quickrelease.studies.planning import plan_case, pushed_displacement

    path = tmp_path / "plan.toml"
    path.write_text(PLAN_CASE)
    case = load_case(path)
    plan = plan_case(case, clearance_samples=3)
    env = plan.envelope
    assert env.samples == 20_000
    rng = np.random.default_rng(0)
    z1 = rng.standard_normal(20_000)
    z2 = rng.standard_normal(20_000)  # correlation 0: the second normal as drawn
    np.testing.assert_allclose(env.values["F1"], np.maximum(420.0 + 30.0 * z1, 0.0), rtol=1e-15)
    np.testing.assert_allclose(env.values["F2"], np.maximum(805.0 + 40.0 * z2, 0.0), rtol=1e-15)
    lo, hi = plan.fuse.target
    assert (lo, hi) == (pytest.approx(1598e3 * 0.95, rel=1e-15), pytest.approx(1598e3 * 1.05, rel=1e-15))
    area = case.device.A4
    assert [c.diameter for c in plan.fuse.choices] == [pytest.approx(math.sqrt(4 * area / math.pi), rel=1e-15)]
    assert [c.alpha0 for c in plan.fuse.choices] == [0.2]
    k = 1.2e6 * (2 * math.pi / 2.5) ** 2
    assert pushed_displacement(1598e3, case.building) == pytest.approx((1598e3 - 1e5) / k, rel=1e-14)
    assert plan.clearance.d0 == pytest.approx((1598e3 - 1e5) / k, rel=1e-14)


# -- 16. NetCDF: every variable's units and long name ------------------------------------------------------------

#: What a reader of timeseries.nc is promised: variable -> (units, long_name), written out here (UDUNITS units).
TIMESERIES_NC = {
    "t": ("s", "time since the fuse broke"),
    "alpha": ("rad", "angle of the bars with the loading axis"),
    "alpha_dot": ("rad/s", "angular velocity of the bars"),
    "alpha_ddot": ("rad/s^2", "angular acceleration of the bars"),
    "u": ("m", "retraction of the head along the loading axis"),
    "v": ("m", "opening of the rhombus across the loading axis"),
    "u_dot": ("m/s", "velocity of the head"),
    "v_dot": ("m/s", "opening velocity"),
    "u_ddot": ("m/s^2", "acceleration of the head"),
    "v_ddot": ("m/s^2", "opening acceleration"),
    "E_K": ("J", "kinetic energy of the device"),
    "W_F": ("J", "energy dissipated by friction"),
    "E_S": ("J", "strain energy stored at release"),
}

#: A sweep's file: the outputs, and the swept coordinates used below.
SWEEP_NC = {
    "F1": ("N", "friction at the central hinges F1"),
    "alpha0": ("rad", "release angle alpha0"),
    "stop_time": ("s", "time from release to the end of the motion t_F"),
    "alpha_final": ("rad", "final angle alpha_F"),
    "stopped_by": ("1", "0: friction stop, 1: geometric limit (flat rhombus), 2: creeps towards it (stop_time inf)"),
    "u_final": ("m", "head stroke u_F"),
    "v_final": ("m", "central hinge opening v_F"),
    "alpha_dot0": ("rad/s", "initial angular velocity (Eq. 6)"),
    "peak_u_dot": ("m/s", "peak head velocity"),
    "peak_v_dot": ("m/s", "peak central hinge velocity"),
    "peak_u_ddot": ("m/s^2", "peak head acceleration"),
    "peak_v_ddot": ("m/s^2", "peak central hinge acceleration"),
    "stored_energy": ("J", "stored strain energy E_S"),
    "status": ("1", "0: computed, 1: outside the floating-point range (outputs NaN; batch.RELEASE_STATUS)"),
}


def _netcdf_attributes(path: Path) -> dict[str, tuple[str, str]]:
    """units and long_name of every variable, read by scipy's NetCDF-3 reader (not xarray, which wrote it)."""
    from scipy.io import netcdf_file

    def text(value) -> str:
        return value.decode("utf-8") if isinstance(value, bytes) else str(value)

    with netcdf_file(path, "r", mmap=False) as f:
        return {name: (text(var.units), text(var.long_name)) for name, var in f.variables.items()}


def test_timeseries_netcdf_units_and_long_names(tmp_path):
    from quickrelease import simulate
    from quickrelease.io.export import write_netcdf

    r = simulate(2900.0, 0.2, 419.85, 804.57, method="energy")
    path = write_netcdf(r, tmp_path / "timeseries.nc")
    assert _netcdf_attributes(path) == TIMESERIES_NC


def test_sweep_netcdf_units_and_long_names(tmp_path):
    from quickrelease.io.case import load_case
    from quickrelease.studies.sweep import sweep

    case = load_case(ROOT / "examples" / "paper.toml")
    sweep(case, {"F1": np.array([300.0, 420.0]), "alpha0": np.array([0.19, 0.2, 0.21])},
          out=tmp_path / "sweep.nc")
    assert _netcdf_attributes(tmp_path / "sweep.nc") == SWEEP_NC


# -- 17. the report's parameter tables: numbers in the unit printed beside them ----------------------------------

def _cells(page: str, row_start: str) -> list[str]:
    """The cells of the table row whose first cell is ``row_start`` (HTML tags and entities removed)."""
    import html

    for row in re.findall(r"<tr>(.*?)</tr>", page, re.S):
        cells = [html.unescape(re.sub(r"<[^>]+>", "", c)).strip() for c in re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", row, re.S)]
        if cells and cells[0] == row_start:
            return cells
    raise AssertionError(f"no row {row_start!r}")


def _hand_made_fit():
    """A linear fit with round numbers chosen here: F_s = 12,010 N +- 31 N, d0 = 0.15 m +- 0.2 mm, ..."""
    from quickrelease.building.isolation_fit import BuildingChannel, IsolationFit
    from quickrelease.studies.building_analysis import BuildingResult

    names = ("period", "damping_ratio", "friction", "d0", "release_time", "offset_lvdt")
    est = {"period": 2.0, "damping_ratio": 0.05, "friction": 12010.0, "d0": 0.15, "release_time": 0.5,
           "offset_lvdt": 0.003}
    se = {"period": 0.0012, "damping_ratio": 0.0021, "friction": 31.0, "d0": 0.0002, "release_time": 0.004,
          "offset_lvdt": 0.0001}
    ci = {n: (est[n] - 2 * se[n], est[n] + 2 * se[n]) for n in names}
    t = np.arange(0.0, 1.0, 0.01)
    ch = BuildingChannel("lvdt", "x", t, np.zeros_like(t), noise=2e-4)
    fit = IsolationFit(model="linear", mass=4.0e5, names=names, estimates=est, std_errors=se, ci95=ci,
                       interval_method=dict.fromkeys(names, "jacobian"), correlation=np.eye(6), condition_number=3.0,
                       noise={"lvdt": 2e-4}, noise_source={"lvdt": "given"}, residual_rms={"lvdt": 2e-4},
                       samples={"lvdt": 100}, chi2=94.0, dof=94, chi2_reduced=1.0, absolute_sigma=True, aic=106.0,
                       bic=109.6, whiteness_p={"lvdt": 0.5}, converged=True, nfev=12, channels=(ch,))
    return BuildingResult(fit=fit, source="hand-made")


def test_building_report_tables_scale_values_and_standard_errors_to_their_units():
    """Every fitted parameter's row: estimate, standard error and interval in the unit printed beside them
    (F_s in kN: 12.01 +- 0.031, never 12.01 kN +- 31; d0 in mm: 150 +- 0.20)."""
    from quickrelease.report.html import building_section

    page = building_section(_hand_made_fit(), {})
    expected = {  # name: (estimate, standard error, interval, unit), by hand
        "friction": ("12.01", "0.031", "[11.948, 12.072]", "kN"),
        "d0": ("150", "0.20", "[149.6, 150.4]", "mm"),
        "period": ("2", "0.0012", "[1.9976, 2.0024]", "s"),
        "damping_ratio": ("0.05", "0.0021", "[0.0458, 0.0542]", "–"),
        "offset_lvdt": ("0.003", "1.0e-4", "[0.0028, 0.0032]", "m"),
    }
    for name, (value, se, interval, unit) in expected.items():
        cells = _cells(page, name)
        assert (float(cells[2]), float(cells[3]), cells[-1]) == (pytest.approx(float(value)), pytest.approx(float(se)),
                                                                  unit), (name, cells)
        lo, hi = (float(x) for x in cells[4].strip("[]").split(","))
        want = [float(x) for x in interval.strip("[]").split(",")]
        assert (lo, hi) == (pytest.approx(want[0]), pytest.approx(want[1])), (name, cells)
    cells = _cells(page, "slider friction F_s")  # the engineering table: kN as well
    assert float(cells[1]) == pytest.approx(12.01) and cells[-1] == "kN"


# -- 18. run --json: the files it lists are the files it wrote ---------------------------------------------------

@pytest.mark.slow
def test_run_json_lists_the_files_written_and_they_exist(tmp_path):
    from typer.testing import CliRunner

    from quickrelease.cli import app

    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["run", str(ROOT / "examples" / "paper.toml"), "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    files = json.loads(r.stdout)["files"]
    listed = {Path(p).resolve() for p in files.values()}
    on_disk = {p.resolve() for p in out.rglob("*") if p.is_file()}
    assert all(p.is_file() and p.stat().st_size > 0 for p in listed)
    assert listed <= on_disk
    assert on_disk - listed <= {(out / "manifest.json").resolve()}  # the run folder's own bookkeeping
    names = {str(p.relative_to(out.resolve())) for p in listed}
    figures = ("fig13_response", "fig14_displacements", "fig15_state_diagram", "identification", "strain_energy")
    assert names >= {"summary.json", "identification.json", "timeseries.csv", "timeseries.nc", "report.html",
                     *(f"figures/{f}.{ext}" for f in figures for ext in ("png", "svg"))}


def test_the_package_errors_survive_pickling():
    """A campaign's releases are fitted in other processes: what one raises comes back pickled. ParameterError
    came back as a TypeError (a traceback from `quickrelease campaign`, release_time = "1e308 s"): each error
    pickles whole, with its message and fields."""
    import pickle

    from quickrelease.errors import CaseFileError, ParameterError

    err = pickle.loads(pickle.dumps(ParameterError("x.t", "not increasing", "strictly increasing times", "s")))
    assert type(err) is ParameterError and str(err) == "x.t = not increasing s is outside strictly increasing times"
    assert (err.name, err.value, err.valid, err.unit) == ("x.t", "not increasing", "strictly increasing times", "s")
    assert str(pickle.loads(pickle.dumps(ParameterError("alpha0", 2.0, "(0, pi/2)")))) == "alpha0 = 2 is outside (0, pi/2)"
    assert str(pickle.loads(pickle.dumps(CaseFileError("c.toml: bad")))) == "c.toml: bad"
