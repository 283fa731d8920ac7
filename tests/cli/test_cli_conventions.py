"""The command line's conventions (issue 11): help texts keep the case file's table names, --version, -h,
``python -m quickrelease``, choices listed as choices, optional dependencies checked before the work,
tables for people."""

import json
import re
import subprocess
import sys
from importlib.metadata import version

import pytest
import typer
from typer.testing import CliRunner

import quickrelease
from quickrelease.cli import app
from quickrelease.report import display

runner = CliRunner()
WIDE = {"COLUMNS": "200"}  # a wide terminal: long help lines are not wrapped inside a bracketed name


def _commands():
    group = typer.main.get_command(app)
    return sorted(group.commands.items())


def _bracketed(text):
    return set(re.findall(r"\[\[?[A-Za-z_][A-Za-z_.]*\]\]?", text or ""))


@pytest.mark.parametrize("name", [n for n, _ in _commands()])
def test_help_keeps_every_bracketed_name(name):
    """Rich markup swallowed [observations], [record], [[tests]]: every bracketed name in a command's own
    help strings must appear in its rendered help."""
    command = dict(_commands())[name]
    wanted = _bracketed(command.help)
    for param in command.params:
        wanted |= _bracketed(getattr(param, "help", None))
    r = runner.invoke(app, [name, "--help"], env=WIDE)
    assert r.exit_code == 0, r.output
    missing = {w for w in wanted if w not in r.output}
    assert not missing, f"{name} --help lost {missing}"


def test_the_commands_that_name_case_tables_show_them():
    """The bracketed names the issue listed, by command (a check that the test above has something to check)."""
    expected = {"uq": "[observations]", "fit": "[record]", "campaign": "[[tests]]", "building": "[building]"}
    for name, token in expected.items():
        r = runner.invoke(app, [name, "--help"], env=WIDE)
        assert token in r.output, (name, r.output)


def test_version_and_short_help():
    r = runner.invoke(app, ["--version"])
    assert r.exit_code == 0 and r.output.strip() == f"quickrelease {version('quickrelease')}"
    assert runner.invoke(app, ["-h"], env=WIDE).output == runner.invoke(app, ["--help"], env=WIDE).output
    r = runner.invoke(app, ["simulate", "-h"], env=WIDE)
    assert r.exit_code == 0 and "--alpha0" in r.output


def test_python_dash_m():
    r = subprocess.run([sys.executable, "-m", "quickrelease", "--version"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == f"quickrelease {version('quickrelease')}"


def test_package_exposes_only_dunder_version():
    assert quickrelease.__version__ == version("quickrelease")
    assert not hasattr(quickrelease, "version") and not hasattr(quickrelease, "PackageNotFoundError")


@pytest.mark.parametrize("command, option, choices", [
    ("simulate", "--method", "energy|rk|explicit"),
    ("uq", "--backend", "numpy|dask|gpu"),
    ("sweep", "--backend", "numpy|dask|gpu"),
    ("building", "--model", "linear|bilinear|2dof"),
    ("simulate", "--mass-model", "distributed|lumped|C"),
])
def test_choices_are_listed(command, option, choices):
    r = runner.invoke(app, [command, "--help"], env=WIDE)
    line = next(ln for ln in r.output.splitlines() if option in ln)
    assert choices in line


def test_a_bad_choice_is_one_line_exit_2():
    r = runner.invoke(app, ["simulate", "--alpha0", "0.2", "--energy", "2900", "--method", "euler"])
    assert r.exit_code == 2
    assert len(r.stderr.strip().splitlines()) == 1 and "--method" in r.stderr and "euler" in r.stderr


def test_simulate_says_when_friction_defaults_to_zero():
    r = runner.invoke(app, ["simulate", "--alpha0", "0.2", "--energy", "2900", "--f1", "420", "--json"])
    assert r.exit_code == 0
    assert "--f2 not given" in r.stderr and "--f1 not given" not in r.stderr
    assert json.loads(r.stdout)["F2_N"] == 0.0
    r = runner.invoke(app, ["simulate", "--alpha0", "0.2", "--energy", "2900", "--f1", "420", "--f2", "800"])
    assert "not given" not in r.stderr


def test_zarr_output_without_zarr_fails_before_the_work(tmp_path, monkeypatch):
    import importlib.util

    from quickrelease.studies import sweep as sweep_module

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "zarr" else real(name, *a))
    monkeypatch.setattr(sweep_module, "_base", lambda case: pytest.fail("the sweep started before the check"))
    out = tmp_path / "s.zarr"
    r = runner.invoke(app, ["sweep", "examples/paper.toml", "--grid", "alpha0=0.1:0.3:3", "--out", str(out)])
    assert r.exit_code == 2, r.output
    assert r.stderr.strip().count("\n") == 0 and "zarr" in r.stderr and "pip install" in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_tables_for_people():
    """Hand-written expectations: SI prefixes from the key's unit suffix, 5 significant digits."""
    assert display.value_text("push_force_N", 1.598e6) == "1598 kN"
    assert display.value_text("stored_energy_J", 2915.4185625) == "2915.4 J"
    assert display.value_text("F1_N", 419.8499016) == "419.85 N"
    assert display.value_text("feasible_stop_time_s", [0.9906441799358865, 1.2139]) == "[0.99064, 1.2139] s"
    assert display.value_text("peak_v_ddot_m_s2", 3.44193) == "3.4419 m/s²"
    assert display.value_text("alpha_dot0_rad_s", 1.0825) == "1.0825 rad/s"
    assert display.value_text("boundary", None) == "-"
    assert display.label("push_force_N") == "push force P"
    assert display.label("some_new_key_s") == "some new key"
    r = runner.invoke(app, ["simulate", "--alpha0", "0.2", "--force", "1598 kN", "--f1", "420", "--f2", "800"])
    assert "1598 kN" in r.stdout and "push_force_N" not in r.stdout and "1.598e+06" not in r.stdout


def test_tables_follow_the_terminal_width():
    r = runner.invoke(app, ["simulate", "--alpha0", "0.2", "--force", "1598 kN", "--f1", "420", "--f2", "800"],
                      env={"COLUMNS": "60"})
    assert max(len(line) for line in r.stdout.splitlines()) <= 60


def test_every_command_writes_with_out(tmp_path):
    """One output vocabulary (issue 22, item 26): --out on every command that writes, a folder or, where the
    command writes one file (sweep, synth, simulate, identify, bench), that file; sweep's and synth's former
    --file (-f) still works, with a note."""
    for name in ("run", "report", "demo", "uq", "sweep", "synth", "fit", "building", "campaign", "plan", "simulate",
                 "identify", "bench"):
        r = runner.invoke(app, [name, "--help"], env=WIDE)
        assert "--out" in r.output, name
        assert "--file" not in r.output, name
    r = runner.invoke(app, ["synth", "examples/paper.toml", "-c", "u", "--rate", "100 Hz", "-o", str(tmp_path / "a.csv")])
    assert r.exit_code == 0 and (tmp_path / "a.csv").is_file() and "note" not in r.stderr
    r = runner.invoke(app, ["synth", "examples/paper.toml", "-c", "u", "--rate", "100 Hz", "--file", str(tmp_path / "b.csv")])
    assert r.exit_code == 0 and (tmp_path / "b.csv").is_file() and "--file is now --out" in r.stderr


@pytest.mark.slow
def test_long_commands_show_a_spinner_on_a_terminal_only(tmp_path):
    """On a terminal, a long command says what it is doing on stderr; its results (stdout) stay clean."""
    import os
    import pty

    master, slave = pty.openpty()
    try:
        r = subprocess.run([sys.executable, "-m", "quickrelease", "sweep", "examples/paper.toml", "--grid",
                            "alpha0=0.1:0.3:3", "--out", str(tmp_path / "s.nc"), "--json"],
                           stdout=subprocess.PIPE, stderr=slave, timeout=600, env={**os.environ, "COLUMNS": "100"})
        os.close(slave)
        seen = b""
        while True:
            try:
                chunk = os.read(master, 65536)
            except OSError:
                break
            if not chunk:
                break
            seen += chunk
    finally:
        os.close(master)
    assert r.returncode == 0
    assert json.loads(r.stdout)["dims"] == {"alpha0": 3}  # stdout is the JSON alone
    assert b"sweeping the grid" in seen


def test_short_flags_are_lower_case():
    group = typer.main.get_command(app)
    shorts = {opt for _, cmd in group.commands.items() for p in cmd.params for opt in p.opts
              if opt.startswith("-") and not opt.startswith("--")}
    assert shorts and all(opt == opt.lower() for opt in shorts), sorted(shorts)
