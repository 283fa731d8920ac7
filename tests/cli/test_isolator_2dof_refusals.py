"""The new isolation systems with a flexible superstructure (issue 24): the 2dof model's dampers are viscous and its
layer linear, so a power-law damper with model = "2dof", or a storey (its period or damping) under a rigid pendulum
or Bouc-Wen layer (without ``flexible = true``), is refused in one line naming the file or option, exit 2, nothing
written, by synth, plan and building. (A rigid layer's case may give ``superstructure_mass`` alone: the mass that
``--flexible`` and ``--compare``'s flexible variant use.)"""

import numpy as np
import pytest
from typer.testing import CliRunner

from quickrelease.cli import app

runner = CliRunner()
HEAD = ('[device]\npreset = "paper"\n[test]\nforce = "1598 kN"\nenergy = "2.90 kJ"\nalpha0 = "0.2 rad"\n'
        'mass_model = "distributed"\n[friction]\nF1 = "419.85 N"\nF2 = "804.57 N"\n')
TWODOF_POWER = ('[building]\nmodel = "2dof"\nmass = "800 t"\nperiod = "2.0 s"\nsuperstructure_mass = "600 t"\n'
                'superstructure_period = "0.5 s"\nsuperstructure_damping_ratio = 0.02\ndamping = "power"\n'
                'damping_coefficient = "200 kN"\ndamping_exponent = 0.5\ndisplacement = "200 mm"\n')
BOUCWEN_SUPERSTRUCTURE = ('[building]\nmodel = "boucwen"\nmass = "800 t"\npost_yield_stiffness = "1.6 MN/m"\n'
                          'characteristic_strength = "400 kN"\nyield_displacement = "25 mm"\nshape = 1.0\n'
                          'superstructure_mass = "600 t"\nsuperstructure_period = "0.5 s"\ndisplacement = "200 mm"\n')
PENDULUM_SUPERSTRUCTURE = ('[building]\nmodel = "pendulum"\nmass = "800 t"\nradius = "2.5 m"\n'
                           'friction_coefficient = 0.03\nsuperstructure_period = "0.5 s"\ndisplacement = "200 mm"\n')


def one_line(r) -> str:
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, (r.exit_code, r.stderr, r.stdout)
    assert "Traceback" not in r.stderr
    return lines[0]


@pytest.mark.parametrize("command", [["synth", "--building", "--out", "o.csv"], ["plan", "--out", "o"]],
                         ids=["synth", "plan"])
def test_a_power_damper_with_the_2dof_model_is_one_line(command, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "c.toml").write_text(HEAD + TWODOF_POWER, encoding="utf-8")
    line = one_line(runner.invoke(app, [command[0], "c.toml", *command[1:]]))
    assert "c.toml" in line and "damping = 'power'" in line and "model = '2dof'" in line and "viscous" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.toml"]


@pytest.mark.parametrize("text, key, model", [(BOUCWEN_SUPERSTRUCTURE, "superstructure_period", "boucwen"),
                                              (PENDULUM_SUPERSTRUCTURE, "superstructure_period", "pendulum")],
                         ids=["boucwen", "pendulum"])
def test_a_superstructure_under_a_new_model_is_one_line(text, key, model, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "c.toml").write_text(text, encoding="utf-8")
    line = one_line(runner.invoke(app, ["synth", "c.toml", "--out", "o.csv"]))
    assert "c.toml" in line and f"[building] {key}" in line and f"model = '{model}'" in line and "2dof" in line
    assert not (tmp_path / "o.csv").exists()


def test_building_model_2dof_on_a_power_damped_case_is_one_line(tmp_path, monkeypatch):
    """--model 2dof over a case whose [building] has fluid dampers: the damper law named, nothing written."""
    monkeypatch.chdir(tmp_path)
    t = np.arange(0.0, 6.0, 0.01)
    x = np.where(t < 1.0, 0.2, 0.2 * np.exp(-0.3 * (t - 1.0)) * np.cos(2 * np.pi / 2.0 * (t - 1.0)))
    (tmp_path / "r.csv").write_text("t_s,x_m\n" + "".join(f"{a:.4f},{b:.6f}\n" for a, b in zip(t, x, strict=True)),
                                    encoding="utf-8")
    text = ('[building]\nmodel = "linear"\nmass = "800 t"\nperiod = "2.0 s"\n'
            'damping = "power"\ndamping_coefficient = "200 kN"\ndamping_exponent = 0.5\n'
            '[building.record]\nfile = "r.csv"\ntime = "t_s"\n[building.record.channels]\n'
            'x = { column = "x_m", unit = "m" }\n')
    (tmp_path / "c.toml").write_text(text, encoding="utf-8")
    line = one_line(runner.invoke(app, ["building", "c.toml", "--model", "2dof", "--out", "o"]))
    assert "damping" in line and "power" in line and "2dof" in line
    assert not (tmp_path / "o").exists()
