"""The new isolation systems with a flexible superstructure (issue 24): the 2dof model's layer is linear, so a storey
(its period or damping) under a rigid pendulum or Bouc-Wen layer (without ``flexible = true``) is refused in one
line naming the file or option, exit 2, nothing written, by synth, plan and building; its dampers may be fluid
dampers (``damping = "power"``, on the flexible integrator). (A rigid layer's case may give ``superstructure_mass`` alone: the mass that
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


def test_a_power_damper_with_the_2dof_model_synthesizes_the_reference_motion(tmp_path, monkeypatch):
    """model = "2dof" with damping = "power" (once refused: the 2dof model's dampers were viscous) is the linear layer
    with fluid dampers under the superstructure, on the flexible integrator: synth writes its record, whose noisy
    x and a scatter about the reference's motion (solve_ivp of the 2-DOF equations, tests/building/
    isolator_reference.py) at their noise levels (x 0.05 mm, a 0.002 g0 by default; a wrong storey, damper law or
    release would leave residuals far above them)."""
    import math
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "building"))
    import isolator_reference as ref

    monkeypatch.chdir(tmp_path)
    (tmp_path / "c.toml").write_text(HEAD + TWODOF_POWER, encoding="utf-8")
    r = runner.invoke(app, ["synth", "c.toml", "--building", "--out", "o.csv", "--seed", "3", "--duration", "10 s"])
    assert r.exit_code == 0, r.output
    data = np.loadtxt(tmp_path / "o.csv", delimiter=",", skiprows=1)
    t, x, a = data[:, 0], data[:, 1], data[:, 2]
    m, ms = 8.0e5, 6.0e5
    k, ks = m * (2 * math.pi / 2.0) ** 2, ms * (2 * math.pi / 0.5) ** 2
    system = ref.linear(m, k, damping=2.0e5, damping_exponent=0.5)
    vc = 1e-8 * math.sqrt(2.0 * system.stored(0.2, 0.0) / m)
    want = ref.simulate_2dof(system, ms, ks, 2 * 0.02 * math.sqrt(ks * ms), 0.2, t - 2.0, float(t[-1]) - 2.0,
                             creep_speed=vc)
    assert abs(np.std(x - want.x) / 0.05e-3 - 1.0) < 0.05
    assert abs(np.std(a - want.a) / (0.002 * 9.80665) - 1.0) < 0.05


@pytest.mark.parametrize("text, key, model", [(BOUCWEN_SUPERSTRUCTURE, "superstructure_period", "boucwen"),
                                              (PENDULUM_SUPERSTRUCTURE, "superstructure_period", "pendulum")],
                         ids=["boucwen", "pendulum"])
def test_a_superstructure_under_a_new_model_is_one_line(text, key, model, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "c.toml").write_text(text, encoding="utf-8")
    line = one_line(runner.invoke(app, ["synth", "c.toml", "--out", "o.csv"]))
    assert "c.toml" in line and f"[building] {key}" in line and f"model = '{model}'" in line and "2dof" in line
    assert not (tmp_path / "o.csv").exists()
