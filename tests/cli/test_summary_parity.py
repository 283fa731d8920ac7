"""``Response.summary()`` is what ``quickrelease simulate --json`` prints, ``Identification.summary()`` what
``quickrelease identify --json`` prints: the same keys, the same values (issue 11), the push force P and the
device's name included."""

import json
import math

import pytest
from typer.testing import CliRunner

import quickrelease as qr
from quickrelease.cli import app

FLAGS = ["--alpha0", "0.2", "--f1", "419.85 N", "--f2", "804.57 N"]


def _cli_json(*args: str, command: str = "simulate") -> dict:
    r = CliRunner().invoke(app, [command, *args, "--json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


@pytest.mark.parametrize(("flags", "api"), [
    (["--force", "1598 kN"], {"push_force": "1598 kN"}),
    (["--energy", "2.90 kJ"], {"stored_energy": 2900.0}),
    (["--force", "1598 kN", "--method", "rk", "--mass-model", "lumped"],
     {"push_force": 1.598e6, "method": "rk", "mass_model": "lumped"}),
])
def test_api_summary_is_the_cli_json(flags, api):
    printed = _cli_json(*flags, *FLAGS)
    summary = qr.simulate(alpha0=0.2, F1=419.85, F2=804.57, **api).summary()
    assert list(summary) == list(printed)  # same keys, same order
    for key, value in printed.items():
        assert summary[key] == pytest.approx(value, rel=1e-12) if isinstance(value, float) else \
            summary[key] == value, key
    assert printed["device"] == "paper"
    assert printed["push_force_N"] == (1.598e6 if "--force" in flags else None)


def test_push_force_alone_stores_the_energy_of_eq2():
    r = qr.simulate(alpha0=0.2, F1=419.85, F2=804.57, push_force=1.598e6)
    assert r.push_force == 1.598e6 and r.summary()["push_force_N"] == 1.598e6
    # the paper's E_S of the 1598 kN push at 0.2 rad: 2.90 kJ (Section 5, rounded to 3 digits; ours 2915 J)
    assert r.stored_energy == pytest.approx(2.90e3, rel=6e-3)
    assert r.stored_energy == qr.strain_energy(1.598e6, 0.2).total
    given = qr.simulate(2900.0, 0.2, 419.85, 804.57, push_force=1.598e6)  # both: E_S simulated, P recorded
    assert given.stored_energy == 2900.0 and given.summary()["push_force_N"] == 1.598e6
    assert qr.simulate(2900.0, 0.2).summary()["push_force_N"] is None
    padded = qr.simulate(alpha0=0.2, F1=419.85, F2=804.57, push_force=1.598e6, t_end=2.0)
    assert padded.summary()["push_force_N"] == 1.598e6 and math.isclose(padded.t[-1], 2.0)


def test_neither_energy_nor_force_is_one_clear_error():
    with pytest.raises(qr.ParameterError, match="stored_energy/push_force"):
        qr.simulate(alpha0=0.2)
    with pytest.raises(TypeError, match="alpha0"):
        qr.simulate(2900.0)
    with pytest.raises(qr.UnitError):
        qr.simulate(alpha0=0.2, push_force="3 m")


@pytest.mark.parametrize(("flags", "api"), [
    (["--force", "1598 kN"], {"push_force": "1598 kN"}),
    (["--energy", "2.90 kJ"], {"stored_energy": 2900.0}),
])
def test_identification_summary_is_the_cli_json(flags, api):
    printed = _cli_json(*flags, "--alpha0", "0.2", "--alpha-final", "0.7378", "--stop-time", "1.05 s",
                        command="identify")
    summary = qr.identify_friction(0.2, 0.7378, 1.05, **api).summary()
    assert list(summary) == list(printed)
    for key, value in printed.items():
        if isinstance(value, float):
            assert summary[key] == pytest.approx(value, rel=1e-12), key
        elif key == "feasible_stop_time_s":
            assert summary[key] == pytest.approx(value, rel=1e-12)
        else:
            assert summary[key] == value, key
    assert printed["device"] == "paper"
