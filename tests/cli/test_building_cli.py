"""``quickrelease building`` and the whole test in ``quickrelease run`` (issue 10, items 7 and 8).

The records are made by an independent simulation of the building (tests/building_reference.py: solve_ivp
with events, no code shared with the package), written to CSV in the case-file grammar: the isolation
layer's displacement in mm, its acceleration in g0 in a file of its own with its own clock and rate.
"""

import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pytest
from building_reference import reference, reference_2dof
from typer.testing import CliRunner

from quickrelease.cli import app

pytestmark = pytest.mark.usefixtures("few_band_draws")  # the bands' width is not looked at here

runner = CliRunner()

G0 = 9.80665
#: The truth: a building like the schema's example (650 t, T = 2 s, 3% damping, sliders at 40 kN, d0 = 0.15 m).
M, T, ZETA, FS, D0 = 6.5e5, 2.0, 0.03, 4.0e4, 0.15
K = M * (2 * math.pi / T) ** 2
T_RELEASE = 2.0
NOISE_X, NOISE_A = 1e-4, 0.01  # m, m/s^2


def _write_record(folder, duration=20.0, t_release=T_RELEASE, seed=0, flat=False, k2=None, fy=math.inf):
    """x [mm] at 100 Hz in x.csv, a [g0] at 50 Hz on its own clock in acc.csv; returns nothing."""
    rng = np.random.default_rng(seed)
    tx = np.arange(0.0, duration, 0.01)
    ta = np.arange(0.0, duration, 0.02) + 0.0037
    k2 = K if k2 is None else k2
    fp = fy * (1 - k2 / K) if math.isfinite(fy) else math.inf
    c = 2 * ZETA * math.sqrt(K * M)
    if flat:  # the building never released: it rests at d0
        x, a = np.full(tx.size, D0), np.zeros(ta.size)
    else:
        x = reference(M, K, k2, fp, c, FS, D0, tx - t_release)[0]
        a = reference(M, K, k2, fp, c, FS, D0, ta - t_release, with_rates=True)[0][2]
    x = x + 0.002 + rng.normal(0, NOISE_X, tx.size)  # the LVDT's zero is 2 mm off
    a = a + rng.normal(0, NOISE_A, ta.size)
    np.savetxt(folder / "x.csv", np.column_stack([tx, 1e3 * x]), delimiter=",", header="t_s,x_iso_mm", comments="",
               fmt="%.10g")
    np.savetxt(folder / "acc.csv", np.column_stack([ta, a / G0]), delimiter=",", header="t_acc_s,a_base_g",
               comments="", fmt="%.10g")


def _building_toml(model="linear", x_unit="mm", period="2.3 s", extra="", displacement="0.15 m"):
    """[building] with design values (start values, a little off the truth) and its record."""
    return f'''
[building]
model = "{model}"
mass = "650 t"
period = "{period}"
damping_ratio = 0.05
friction = "30 kN"
displacement = "{displacement}"
{extra}
[building.record]
file = "x.csv"
time = "t_s"
[building.record.channels]
x = {{ column = "x_iso_mm", unit = "{x_unit}" }}
a = {{ column = "a_base_g", unit = "g0", file = "acc.csv", time = "t_acc_s" }}
'''


def _case(folder, body, device=False):
    head = 'title = "Snap-back of a test building"\n'
    if device:
        head += '[test]\nforce = "1598 kN"\nalpha0 = "0.2 rad"\n[friction]\nF1 = "420 N"\nF2 = "805 N"\n'
    path = folder / "case.toml"
    path.write_text(head + body)
    return path


def run(*args):
    return runner.invoke(app, [str(a) for a in args])


def _one_line_error(r, *fragments):
    assert r.exit_code == 2, r.output
    assert r.stderr.startswith("error: ") and r.stderr.count("\n") == 1, r.stderr
    assert "Traceback" not in r.output
    for fragment in fragments:
        assert fragment in r.stderr, (fragment, r.stderr)


def _check_truth(data):
    """The estimates against the truth the record was made with: period within 1%, damping and friction within
    5% (the issue's round-trip tolerances), each inside its reported 95% interval. (Not: the truth inside the
    interval. With an acceleration channel the misfit jumps where a reversal passes a sample, the fit can end
    beside such a jump and the Jacobian's interval is then too narrow: a fault of the fit, reported.)"""
    for key, truth, rel in (("period_s", T, 0.01), ("damping_ratio", ZETA, 0.05), ("friction_N", FS, 0.05)):
        value, (lo, hi) = data[key], data[f"{key}_ci95"]
        assert abs(value - truth) < rel * truth, (key, value, truth)
        assert lo < value < hi


@pytest.mark.slow
def test_building_command_json_folder_and_refusals(tmp_path):
    _write_record(tmp_path, duration=14.0)
    case = _case(tmp_path, _building_toml())
    out = tmp_path / "out"
    r = run("building", case, "--out", out, "--json")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    for key in ("model", "period_s", "period_s_ci95", "damping_ratio", "damping_ratio_ci95", "friction_N",
                "friction_N_ci95", "aic", "bic", "residual_rms", "converged", "warnings", "notes", "comparison",
                "decay_check"):
        assert key in data, key
    assert data["model"] == "linear" and data["converged"] is True
    _check_truth(data)
    assert set(data["residual_rms"]) == {"x", "a"}
    assert data["residual_rms"]["x"] == pytest.approx(NOISE_X, rel=0.15)
    assert data["residual_rms"]["a"] == pytest.approx(NOISE_A, rel=0.15)
    assert data["d0_m"] == pytest.approx(D0, abs=5 * NOISE_X)
    # the model-free decay agrees with the fit on a linear + Coulomb record
    rows = {row["parameter"]: row for row in data["decay_check"]["rows"]}
    assert set(rows) == {"period", "damping_ratio", "friction"}
    assert abs(rows["friction"]["decay"] - FS) < 0.1 * FS
    assert any("interpolated" in n for n in data["notes"])  # the loop's common time axis is said
    # the folder: exactly what the command wrote
    files = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    stems = ("building_fit", "building_decay", "building_amplitude", "building_hysteresis", "building_effective")
    assert files == sorted(["manifest.json", "report.html", "summary.json", "timeseries.csv", "timeseries.nc"]
                           + [f"figures/{s}.{e}" for s in stems for e in ("png", "svg")])
    written = json.loads((out / "summary.json").read_text())
    prov = written.pop("provenance")  # what made the file: the version and the case file as read
    assert written == data and prov["input"]["name"] == Path(case).name
    assert prov["input"]["sha256"] == hashlib.sha256(Path(case).read_bytes()).hexdigest()
    html = (out / "report.html").read_text()
    assert 'id="building-model">linear<' in html and "Decay cross-check" in html
    # the engineering quantities against the identified model's curve, and the spread as the standards judge it
    assert 'id="building-effective"' in html and "keff_vs_model" in html and "edc_spread" in html
    curve, judged = data["effective_curve"], data["effective_judgement"]
    assert len(curve["amplitude_m"]) == len(curve["keff_N_m_lo"]) == 41 and curve["level"] == 0.95
    assert judged["passed"] is True and len(judged["cycles"]) == len(data["effective"])
    assert all(f'id="{s}"' in html for s in stems)
    # another run's inputs into the same folder: refused before the work, one line; the folder untouched
    before = (out / "summary.json").read_text()
    r = run("building", case, "--out", out, "--model", "bilinear")
    _one_line_error(r, "another run", "--overwrite")
    assert (out / "summary.json").read_text() == before
    # a folder with files quickrelease did not write: refused even with --overwrite
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    _one_line_error(run("building", case, "--out", foreign, "--overwrite"), "did not write")
    # --out naming a file
    _one_line_error(run("building", case, "--out", tmp_path / "x.csv"), "is a file")


def test_building_table_output(tmp_path):
    # 7 s after the release: three whole cycles (the per-cycle table needs two after the release's)
    _write_record(tmp_path, duration=9.0, seed=2)
    r = run("building", _case(tmp_path, _building_toml()))
    assert r.exit_code == 0, r.output
    assert "period T" in r.stdout and "slider friction F_s" in r.stdout and "Decay cross-check" in r.stdout
    assert "period_s" not in r.stdout and "friction_N" not in r.stdout  # human names, not JSON keys
    assert "Engineering quantities per cycle" in r.stdout and "keff_vs_model" in r.stdout


@pytest.mark.parametrize("what, fragments", [
    ("flat", ("no release",)),
    ("short", ("too short", "one cycle")),
    ("units", ("channels.x.unit", "kg", "length")),
    ("model", ("--model", "3dof")),
])
def test_building_bad_input_is_one_line(tmp_path, what, fragments):
    if what == "flat":
        _write_record(tmp_path, duration=6.0, flat=True)
    else:  # short: 1.2 s after the release, less than the period of 2 s
        _write_record(tmp_path, duration=T_RELEASE + (1.2 if what == "short" else 6.0))
    body = _building_toml(x_unit="kg" if what == "units" else "mm")
    args = ("--model", "3dof") if what == "model" else ()
    out = tmp_path / "out"
    _one_line_error(run("building", _case(tmp_path, body), "--out", out, *args), *fragments)
    assert not out.exists()  # nothing half-written


def test_building_2dof_without_the_superstructure_mass_is_one_line(tmp_path):
    """--model 2dof on a case whose [building] has no superstructure_mass: one line naming it, exit 2, never a
    traceback (the record fixes the parameters per unit mass: the roof mass must be given)."""
    _write_record(tmp_path, duration=8.0)
    out = tmp_path / "out"
    r = run("building", _case(tmp_path, _building_toml()), "--model", "2dof", "--out", out)
    _one_line_error(r, "superstructure_mass")
    assert not out.exists()


@pytest.mark.slow
@pytest.mark.parametrize("yield_force, warned", [(5.0 * K * D0, True), (0.3 * K * D0, False)])
def test_bilinear_that_never_yields_is_named_in_a_warning(yield_force, warned):
    """A bilinear spring whose yield force is never reached after the release moves as a linear one: the record
    cannot tell k2 and F_y, and the analysis says so in a warning naming yield_force (the command exits 0
    with it). A spring that does yield gets no such warning. (The bilinear parameters are held at the truth:
    the multi-start bilinear fit costs tens of seconds, and the warning depends on the fitted spring only.)"""
    from quickrelease.building.isolation_fit import BuildingChannel, fit_isolation
    from quickrelease.studies.building_analysis import _bilinear_yield_warning

    rng = np.random.default_rng(1)
    t = np.arange(0.0, 8.0, 0.01)
    k2 = 0.1 * K
    x = reference(M, K, k2, yield_force * (1 - k2 / K), 2 * ZETA * math.sqrt(K * M), FS, D0, t - T_RELEASE)[0]
    channel = BuildingChannel("x", "x", t, x + rng.normal(0, NOISE_X, t.size), offset=False)
    truth = {"period": T, "stiffness_ratio": 0.1, "yield_force": yield_force, "damping_ratio": ZETA, "friction": FS}
    fit = fit_isolation([channel], M, "bilinear", fixed=truth)
    warnings = _bilinear_yield_warning(fit)
    assert bool(warnings) is warned, warnings
    if warned:
        assert warnings[0].startswith("yield_force:") and "never yields" in warnings[0] and "k2" in warnings[0]


@pytest.mark.slow
def test_whole_test_run_uses_the_identified_building_for_the_clearance(tmp_path):
    """A case with the device part and a building record: run identifies the building, and the clearance
    check uses it (period 2 s, d0 = 0.15 m from the record, not the assumed 2.3 s and 0.17 m), saying so."""
    from quickrelease.io.case import load_case
    from quickrelease.workflow import run_case, write_results

    _write_record(tmp_path, duration=12.0)
    case = load_case(_case(tmp_path, _building_toml(displacement="0.17 m"), device=True))
    result = run_case(case, state_diagram=False)
    assert result.building is not None and result.building.model == "linear"
    used = result.plan.case.building
    assert used.period == pytest.approx(T, rel=0.01) and used.friction_force == pytest.approx(FS, rel=0.05)
    assert result.plan.clearance.d0 == pytest.approx(D0, abs=1e-3)
    assert any(n.startswith("clearance checked with the building identified") for n in result.plan.notes)
    # the loop's force is -m a at the displacement's times: against the reference acceleration there
    loop = result.building.loop
    a_ref = reference(M, K, K, math.inf, 2 * ZETA * math.sqrt(K * M), FS, D0, loop["t"] - T_RELEASE,
                      with_rates=True)[0][2]
    assert float(np.median(np.abs(loop["force"] + M * a_ref))) < M * NOISE_A
    paths = write_results(result, tmp_path / "out", figures=False)
    data = json.loads(paths["building"].read_text())
    _check_truth(data)
    html = paths["report"].read_text()
    assert 'id="building-model"' in html and 'id="building_fit"' in html and "identified from its record" in html


def test_plan_json_with_a_skipped_member_check(tmp_path):
    """Regression: the paper's device has no W2, so the heads' check is skipped with an unknown demand (NaN);
    ``plan --json`` (and ``run`` with a [building], which writes plan.json) then died with a traceback
    ("Out of range float values are not JSON compliant"). The skipped check's demand is null."""
    case = _case(tmp_path, _building_toml().split("[building.record]")[0], device=True)
    r = run("plan", case, "--json")
    assert r.exit_code == 0, r.output
    checks = {c["member"] + " " + c["check"]: c for c in json.loads(r.stdout)["members"]["checks"]}
    skipped = checks["E2 axial + bending + shear (von Mises)"]
    assert skipped["demand"] is None and skipped["note"].startswith("skipped")



def test_covariance_of_a_jacobian_with_columns_of_very_different_scales():
    """Regression: ``pinv(J^T J)`` with a relative cut-off read the column of a parameter in small units (the
    building example's friction, 1e5 N, beside offsets of 1e-3 m) as rank deficiency and gave it a variance
    of 0, a zero-width interval. Against the identity ``(J^T J)^-1 = D^-1 (A^T A)^-1 D^-1`` for ``J = A D``."""
    from quickrelease._lsq import jacobian_covariance

    rng = np.random.default_rng(3)
    U, _ = np.linalg.qr(rng.normal(size=(400, 4)))
    V, _ = np.linalg.qr(rng.normal(size=(4, 4)))
    A = U @ np.diag([2.2, 1.0, 0.4, 0.02]) @ V.T  # the example's singular values (columns at unit norm)
    scales = np.array([1.4, 2.4e6, 1.5e6, 3.8e3])  # the example's column norms: friction, damping, d0, offset
    J = A * scales
    exact = np.linalg.inv(A.T @ A) / np.outer(scales, scales)
    cov = jacobian_covariance(J)
    assert np.allclose(np.sqrt(np.diag(cov)), np.sqrt(np.diag(exact)), rtol=1e-9, atol=0)
    assert np.allclose(cov, exact, rtol=1e-9, atol=1e-12 * np.abs(exact).max())


@pytest.mark.slow
def test_building_2dof_command_fits_a_flexible_building(tmp_path):
    """A record of a flexible building (base LVDT in mm at 100 Hz, roof accelerometer in g0 at 200 Hz on its own
    clock; made by the independent 2-DOF solve_ivp of tests/building_reference.py) through
    ``quickrelease building --model 2dof --json`` from design values 10% off: the isolation and storey periods
    within 1%, damping and friction within 5% of the truth."""
    m, ms, T1, Ts, z, zs, mu = 6.5e5, 5.0e5, 2.0, 0.5, 0.04, 0.03, 0.02
    k, ks = m * (2 * math.pi / T1) ** 2, ms * (2 * math.pi / Ts) ** 2
    c, cs, fs = 2 * z * math.sqrt(k * m), 2 * zs * math.sqrt(ks * ms), mu * m * G0
    rng = np.random.default_rng(3)
    tx = np.arange(0.0, 14.0, 0.01)
    ta = np.arange(0.0, 14.0, 0.005) + 0.0013
    x = reference_2dof(m, ms, k, c, ks, cs, fs, D0, tx - T_RELEASE)[0]["xb"] + rng.normal(0, NOISE_X, tx.size)
    a = reference_2dof(m, ms, k, c, ks, cs, fs, D0, ta - T_RELEASE)[0]["as"] + rng.normal(0, NOISE_A, ta.size)
    np.savetxt(tmp_path / "x.csv", np.column_stack([tx, 1e3 * x]), delimiter=",", header="t_s,x_iso_mm",
               comments="", fmt="%.10g")
    np.savetxt(tmp_path / "roof.csv", np.column_stack([ta, a / G0]), delimiter=",", header="t_r_s,a_roof_g",
               comments="", fmt="%.10g")
    body = f'''
[building]
model = "2dof"
mass = "650 t"
period = "2.2 s"
damping_ratio = 0.05
friction = "{0.9 * fs} N"
displacement = "0.15 m"
superstructure_mass = "500 t"
superstructure_period = "0.55 s"
superstructure_damping_ratio = 0.02
[building.record]
file = "x.csv"
time = "t_s"
[building.record.channels]
x = {{ column = "x_iso_mm", unit = "mm" }}
a_roof = {{ column = "a_roof_g", unit = "g0", file = "roof.csv", time = "t_r_s" }}
'''
    r = run("building", _case(tmp_path, body), "--json")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    assert data["model"] == "2dof" and data["converged"]
    est = data["fit"]["estimates"]
    for key, truth, rel in (("period", T1, 0.01), ("superstructure_period", Ts, 0.01), ("damping_ratio", z, 0.05),
                            ("friction", fs, 0.05)):
        assert abs(est[key] / truth - 1) < rel, (key, est[key], truth)


@pytest.mark.slow  # (1.1-1.5 s of fits: the README's quick run stays under 3 minutes; CI runs it)
def test_a_long_building_fit_tells_a_pipe_what_runs(monkeypatch):
    """Piped (stderr no terminal), a run that goes past PROGRESS_AFTER seconds prints ``progress:`` lines on
    stderr naming the model and the start with counts, and stdout stays the one JSON object."""
    import quickrelease.cli as cli

    monkeypatch.setattr(cli, "PROGRESS_AFTER", 0.0)
    monkeypatch.setattr(cli, "PROGRESS_EVERY", 0.0)
    r = runner.invoke(app, ["building", str(Path(__file__).parents[2] / "examples" / "building.toml"), "--json"])
    assert r.exit_code == 0, r.output
    json.loads(r.stdout)
    lines = r.stderr.strip().splitlines()
    assert any(line.startswith("progress: fitting the linear isolation model: linear: global search, run 1 of 3")
               for line in lines), lines
    assert any("linear: start 1 of " in line for line in lines)
