import json
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from quickrelease.cli import app

runner = CliRunner()


def run(*args):
    return runner.invoke(app, list(args))


def test_simulate_json_keys_and_values():
    r = run("simulate", "--force", "1598 kN", "--alpha0", "0.2", "--f1", "419.85 N", "--f2", "0.80457 kN", "--json")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    for key in ["stored_energy_J", "alpha0_rad", "alpha_dot0_rad_s", "alpha_final_rad", "stop_time_s", "stopped_by",
                "peak_u_dot_m_s", "peak_v_dot_m_s", "method", "mass_factor"]:
        assert key in data
    assert data["stored_energy_J"] == pytest.approx(2915.4186, abs=1e-3)
    assert data["method"] == "energy" and data["mass_factor"] == pytest.approx(2 / 3)
    assert data["stopped_by"] == "friction"


def test_simulate_units_and_methods_agree():
    out = {}
    for method in ["energy", "rk", "explicit"]:
        r = run("simulate", "--energy", "2.9 kJ", "--alpha0", "11.459156 deg", "--f1", "420", "--f2", "800",
                "--method", method, "--dt", "0.05 ms", "--json")
        assert r.exit_code == 0, r.output
        out[method] = json.loads(r.stdout)["stop_time_s"]
    assert out["rk"] == pytest.approx(out["energy"], rel=1e-8)
    assert out["explicit"] == pytest.approx(out["energy"], rel=1e-4)


def test_identify_json():
    r = run("identify", "--energy", "2.90 kJ", "--alpha0", "0.2", "--alpha-final", "0.7378 rad",
            "--stop-time", "1.05 s", "--json")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    for key in ["F1_N", "F2_N", "F1_max_N", "F2_max_N", "F2_ratio", "stored_energy_J", "stop_time_residual_s"]:
        assert key in data
    assert data["F1_N"] == pytest.approx(419.850, abs=1e-3)
    assert data["F2_N"] == pytest.approx(804.568, abs=1e-3)


def test_identify_lumped_is_infeasible():
    r = run("identify", "--energy", "2.90 kJ", "--alpha0", "0.2", "--alpha-final", "0.7378",
            "--stop-time", "1.05", "--mass-model", "lumped")
    assert r.exit_code == 2
    assert r.stderr.strip().startswith("error: t_F = 1.05 s is outside the feasible interval")
    assert r.stderr.count("\n") == 1


@pytest.mark.parametrize("args,fragment", [
    (["simulate", "--force", "1598 m", "--alpha0", "0.2"], "expected a force"),
    (["simulate", "--force", "1598 kN", "--alpha0", "2"], "alpha0 = 2 rad is outside (0, pi/2)"),
    (["simulate", "--energy", "-3 kJ", "--alpha0", "0.2"], "E_S = -3000 J is outside (0, inf)"),
    (["simulate", "--energy", "3 kJ", "--alpha0", "0.2", "--f1", "-1"], "F1 = -1 N is outside [0, inf)"),
    (["simulate", "--energy", "3 kJ", "--alpha0", "0.2", "--mass-model", "heavy"], "mass_model = heavy"),
    (["simulate", "--energy", "3 kJ", "--alpha0", "0.2", "--method", "euler"], "method = euler"),
    (["simulate", "--energy", "3 kJ", "--force", "1 kN", "--alpha0", "0.2"], "exactly one"),
    (["simulate", "--energy", "3 blorps", "--alpha0", "0.2"], "unknown unit"),
    (["identify", "--energy", "3 kJ", "--alpha0", "0.2", "--alpha-final", "0.1", "--stop-time", "1"],
     "alpha_final = 0.1 rad is outside (alpha0, pi/2)"),
    (["simulate", "--device", "/nonexistent.toml", "--energy", "3 kJ", "--alpha0", "0.2"], "cannot read"),
])
def test_errors_are_one_line_exit_2(args, fragment):
    r = run(*args)
    assert r.exit_code == 2, r.output
    assert fragment in r.stderr
    assert r.stderr.startswith("error: ") and r.stderr.count("\n") == 1
    assert "Traceback" not in r.output


def test_demo_prints_the_comparison():
    r = run("demo")
    assert r.exit_code == 0, r.output
    assert "0.4056 kN" in r.stdout and "0.4198 kN" in r.stdout
    assert "2.9154 kJ" in r.stdout


def test_installed_script_runs():
    r = subprocess.run([sys.executable, "-m", "quickrelease.cli", "simulate", "--energy", "2900", "--alpha0", "0.2",
                        "--f1", "400", "--f2", "800", "--json"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["stopped_by"] == "friction"
