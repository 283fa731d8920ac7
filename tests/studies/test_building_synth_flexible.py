"""``synth`` of a layer under a flexible superstructure (``[building] flexible = true``): the record against the
independent solve_ivp reference (tests/building/isolator_reference.py, ``simulate_2dof``), the truth in the fit's
names, the predicted precision with the storey's rows, and the case file written beside the record read back."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from quickrelease.cli import app
from quickrelease.io.building_case import load_building
from quickrelease.io.case import load_case
from quickrelease.studies.synth import predicted_building_errors, synthesize_building

sys.path.insert(0, str(Path(__file__).parents[1] / "building"))
import isolator_reference as ref  # noqa: E402

G = 9.80665
PENDULUM = """title = "A pendulum under a flexible storey"
[building]
model = "pendulum"
mass = "1000 t"
radius = "3 m"
friction_slow = 0.01
friction_fast = 0.025
rate = "40 s/m"
damping_ratio = 0.02
displacement = "0.3 m"
flexible = true
superstructure_mass = "700 t"
superstructure_period = "0.6 s"
superstructure_damping_ratio = 0.03
"""


def _case(tmp_path, text=PENDULUM):
    path = tmp_path / "case.toml"
    path.write_text(text)
    return load_case(path, require_test=False)


def test_synth_of_a_flexible_pendulum_is_the_reference_motion(tmp_path):
    """Base and roof channels (noise-free) to 1e-6 of d0 (displacements) and of the largest value (accelerations) of
    the reference's; the truth names the layer's model, flexible, and the storey; the fit's parameters hold the
    storey's period and damping."""
    syn = synthesize_building(_case(tmp_path), ["x", "a", "a_roof"], rate=100.0, release_time=1.0, duration=9.0,
                              seed=3)
    t = syn.truth
    assert t["model"] == "pendulum" and t["flexible"] is True and t["superstructure_mass_kg"] == 7.0e5
    m, ms = 1.0e6, 7.0e5
    k = m * G / 3.0
    system = ref.pendulum(m, 3.0, 0.01, 0.025, rate=40.0, damping=2 * 0.02 * math.sqrt(k * m))
    ks = ms * (2 * math.pi / 0.6) ** 2
    motion = ref.simulate_2dof(system, ms, ks, 2 * 0.03 * math.sqrt(ks * ms), 0.3, syn.t - 1.0, 8.0)
    assert motion.slip_times.size >= 1  # the storey breaks the held base away
    np.testing.assert_allclose(syn.clean["x"], motion.x, rtol=0, atol=1e-6 * 0.3)
    for name, want in (("a", motion.a), ("a_roof", motion.as_)):
        np.testing.assert_allclose(syn.clean[name], want, rtol=0, atol=1e-6 * np.max(np.abs(want)))
    p = syn.fit_parameters()
    assert p["superstructure_period"] == 0.6 and p["superstructure_damping_ratio"] == 0.03
    assert p["period"] == pytest.approx(2 * math.pi * math.sqrt(3.0 / G), rel=1e-12)
    pred = predicted_building_errors(syn)
    assert "superstructure_period" in pred.names and 0 < pred.std_errors["superstructure_period"] < 0.01


def test_synth_cli_writes_a_flexible_case_that_reads_back(tmp_path, monkeypatch):
    """``quickrelease synth ... --case-out``: the case written beside the record says ``flexible = true`` with the
    storey's keys, and reads back as the same flexible building."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.toml").write_text(PENDULUM)
    r = CliRunner().invoke(app, ["synth", "p.toml", "--channels", "x,a_roof", "--rate", "100 Hz", "--duration", "6 s",
                                 "--out", "r.csv", "--case-out", "back.toml"])
    assert r.exit_code == 0, r.output
    text = (tmp_path / "back.toml").read_text()
    assert "flexible = true" in text and "superstructure_period" in text
    data = load_building(load_case(tmp_path / "back.toml", require_test=False))
    assert data.flexible and data.model == "pendulum" and data.superstructure_mass == 7.0e5
    assert data.isolation.superstructure_period == 0.6 and {c.kind for c in data.channels} == {"x", "a_roof"}


def test_planning_a_test_of_a_flexible_building_says_the_clearance_takes_it_rigid(tmp_path):
    """``plan_case`` with a flexible pendulum building: the clearance check runs on the layer (the whole mass, the
    pendulum's own motion: the same as the rigid case's) and says the superstructure's mode is left out."""
    from quickrelease.studies.planning import plan_case

    examples = Path(__file__).parents[2] / "examples"
    plan = (examples / "plan.toml").read_text()
    head = plan[:plan.index("[building]")].replace('file = "device_checked.toml"',
                                                   f'file = "{(examples / "device_checked.toml").as_posix()}"')
    head = head[:head.index("[friction]")] + '[friction]\nF1 = "420 N"\nF2 = "805 N"\n\n' + head[head.index("[fuse]"):]
    body = PENDULUM[PENDULUM.index("[building]"):].replace('displacement = "0.3 m"\n', "")
    results = {}
    for name, text in (("flexible", body), ("rigid", "\n".join(line for line in body.splitlines()
                                                                 if not line.startswith(("flexible", "superstructure"))))):
        path = tmp_path / f"{name}.toml"
        path.write_text(head + text + "\n[plan]\nsamples = 2\nseed = 0\n")
        results[name] = plan_case(load_case(path), clearance_samples=2)
    assert any("flexible pendulum building taken as rigid" in n for n in results["flexible"].notes)
    assert not any("taken as rigid" in n for n in results["rigid"].notes)
    assert results["flexible"].clearance.min_gap == results["rigid"].clearance.min_gap
