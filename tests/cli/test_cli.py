import json
import subprocess
import sys

import pytest
from conftest import mp_identify
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
    assert (data["F1_N"], data["F2_N"]) == pytest.approx(mp_identify(2900, 0.2, 0.7378, 1.05), rel=1e-10)


def test_identify_json_names_the_boundary():
    """Issue 9 item 15: the summary carries ``boundary``; simulate's own output with F2 = 0 is identified on it."""
    import quickrelease as qr

    r = qr.simulate(500.0, 0.6, 300.0, 0.0, n_points=2)
    assert r.stopped_by == "friction"
    out = run("identify", "--energy", "500 J", "--alpha0", "0.6", "--alpha-final", f"{r.alpha_final!r} rad",
              "--stop-time", f"{r.stop_time!r} s", "--json")
    assert out.exit_code == 0, out.output
    data = json.loads(out.stdout)
    assert data["boundary"] == "F2 = 0" and data["F2_N"] == 0.0
    assert data["F1_N"] == pytest.approx(300.0, rel=1e-9)
    inner = run("identify", "--energy", "2.90 kJ", "--alpha0", "0.2", "--alpha-final", "0.7378 rad",
                "--stop-time", "1.05 s", "--json")
    assert json.loads(inner.stdout)["boundary"] is None


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
    (["simulate", "--energy", "3 kJ", "--alpha0", "0.2", "--method", "euler"], "'euler' is not one of 'energy', 'rk', 'explicit'"),
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
    assert "Traceback" not in r.output and "None" not in r.stderr  # click 8.2.0 printed "(env var: 'None')"


@pytest.mark.slow
def test_demo_prints_the_comparison(tmp_path):
    r = run("demo", "--out", str(tmp_path / "demo"))
    assert r.exit_code == 0, r.output
    assert (tmp_path / "demo" / "report.html").exists()
    assert f"{tmp_path / 'demo' / 'report.html'}" in r.stdout
    assert "0.4056 kN" in r.stdout and "0.4198 kN" in r.stdout
    assert "2.9154 kJ" in r.stdout
    from quality import html_faults, table_faults  # the report holds Table 7 too, and is valid HTML

    assert table_faults(r.stdout) == []

    report = (tmp_path / "demo" / "report.html").read_text(encoding="utf-8")
    table7 = report[report.index('<h2 id="table7">'):report.index("</table>", report.index('<h2 id="table7">'))]
    assert "0.4056 kN" in table7 and "0.4198 kN" in table7 and "2.9154 kJ" in table7 and "2.90 kJ" in table7
    assert html_faults(report) == []
    table = json.loads((tmp_path / "demo" / "table7.json").read_text(encoding="utf-8"))
    assert table["provenance"]["input"]["name"] == "paper case (built in)"


@pytest.mark.slow
def test_installed_script_runs():
    r = subprocess.run([sys.executable, "-m", "quickrelease.cli", "simulate", "--energy", "2900", "--alpha0", "0.2",
                        "--f1", "400", "--f2", "800", "--json"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["stopped_by"] == "friction"


EXAMPLES = __import__("pathlib").Path(__file__).parents[2] / "examples"


def test_simulate_case_file_with_override():
    base = json.loads(run("simulate", str(EXAMPLES / "larger_push.toml"), "--json").stdout)
    assert base["method"] == "rk" and base["stored_energy_J"] > 6000
    over = run("simulate", str(EXAMPLES / "larger_push.toml"), "--f1", "1 kN", "--method", "energy", "--json")
    data = json.loads(over.stdout)
    assert data["F1_N"] == 1000.0 and data["F2_N"] == pytest.approx(804.57) and data["method"] == "energy"
    assert data["stop_time_s"] < base["stop_time_s"]


def test_identify_case_file():
    data = json.loads(run("identify", str(EXAMPLES / "paper.toml"), "--json").stdout)
    assert data["F1_N"] == pytest.approx(mp_identify(2900, 0.2, 0.7378, 1.05)[0], rel=1e-10)
    assert data["push_force_N"] == 1598e3
    data = json.loads(run("identify", str(EXAMPLES / "paper.toml"), "--stop-time", "1.1 s", "--json").stdout)
    assert data["F1_N"] > 500


def test_simulate_case_without_friction_says_what_to_do():
    r = run("simulate", str(EXAMPLES / "paper.toml"))
    assert r.exit_code == 2 and "quickrelease run" in r.stderr


def test_run_and_report_commands(tmp_path):
    r = run("run", str(EXAMPLES / "paper.toml"), "--out", str(tmp_path / "o"))
    assert r.exit_code == 0, r.output
    assert (tmp_path / "o" / "report.html").exists() and (tmp_path / "o" / "figures" / "fig13_response.png").exists()
    assert "Wrote 16 files" in r.stdout  # 15 results and the manifest (issue 22, item 26)
    from quality import table_faults

    assert table_faults(r.stdout) == []
    r = run("report", str(EXAMPLES / "larger_push.toml"), "--out", str(tmp_path / "r"))
    assert r.exit_code == 0, r.output
    assert table_faults(r.stdout) == []
    # the report and the manifest that fingerprints it (a later run into the folder checks it)
    assert sorted(p.name for p in (tmp_path / "r").iterdir()) == ["manifest.json", "report.html"]


def test_case_file_error_is_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[test]\nforce = "1598 m"\nalpha0 = 0.2\n[friction]\nF1 = 1\nF2 = 1\n')
    r = run("run", str(bad), "--out", str(tmp_path / "o"))
    assert r.exit_code == 2
    assert r.stderr == f"error: {bad}: [test] force = '1598 m': has dimension [length]; expected a force (e.g. in N)\n"
