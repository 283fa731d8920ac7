"""Absurd but finite design values of the isolators in a case file (issue 24's keys) are refused when the file
is read: one line naming the key, its value and the valid range; the commands exit 2 and write nothing.

The ranges, written here by hand: radius [0.01, 1000] m, rate [0, 1e4] s/m, yield_displacement [1e-5, 1] m,
friction_slow and friction_fast [0, 1], shape [0.5, 25], damping_exponent [0.05, 2], the pushed displacement
[1e-6, 10] m (displacement = "1e308 m" was fitted); with the mass m = 1000 t:
post_yield_stiffness in [m (2 pi / 100 s)^2, m (2 pi / 0.1 s)^2] = [3947.84, 3.94784e9] N/m,
characteristic_strength in (0, m g] = (0, 9.80665e6] N (Qd > 0), damping_coefficient in [0, 10 m g] = [0, 9.80665e7].
"""

import re

import pytest
from typer.testing import CliRunner

from quickrelease.cli import app
from quickrelease.errors import CaseFileError
from quickrelease.io.case import load_case

PENDULUM = """[building]
model = "pendulum"
mass = "1000 t"
radius = "2.5 m"
friction_slow = 0.02
friction_fast = 0.06
rate = "30 s/m"
damping = "power"
damping_coefficient = "100 kN"
damping_exponent = 0.5
displacement = "250 mm"
"""
BOUCWEN = """[building]
model = "boucwen"
mass = "1000 t"
post_yield_stiffness = "5 MN/m"
characteristic_strength = "300 kN"
yield_displacement = "10 mm"
shape = 1.0
damping = "power"
damping_coefficient = "100 kN"
damping_exponent = 0.5
displacement = "150 mm"
"""
# key -> (case, absurd values, the range the message must show)
RANGES = {
    "radius": (PENDULUM, ("1e308", "1e-300", "1001.0"), "[0.01, 1000] m"),
    "friction_slow": (PENDULUM, ("1e308", "1.01"), "[0, 1]"),
    "friction_fast": (PENDULUM, ("1e308",), "[0, 1]"),
    "rate": (PENDULUM, ("1e308", "10001.0"), "[0, 10000] s/m"),
    "damping_coefficient": (PENDULUM, ("1e308", "9.81e7"), "[0, 9.80665e+07]"),
    "damping_exponent": (BOUCWEN, ("1e308",), "[0.05, 2]"),
    "post_yield_stiffness": (BOUCWEN, ("1e308", "3947.0", "3.95e9"), "[3947.84, 3.94784e+09] N/m"),
    "characteristic_strength": (BOUCWEN, ("1e308", "9.81e6"), "(0, 9.80665e+06] N"),
    "yield_displacement": (BOUCWEN, ("1e308", "1e-300", "1.01"), "[1e-05, 1] m"),
    "shape": (BOUCWEN, ("1e308", "25.01"), "[0.5, 25]"),
    "displacement": (PENDULUM, ("1e308", "10.01", "1e-7"), "[1e-06, 10] m"),
}
CASES = [(key, value) for key, (_, values, _) in RANGES.items() for value in values]


def _write(folder, key, value):
    text = re.sub(rf"^{key} = .*$", f"{key} = {value}", RANGES[key][0], flags=re.M)
    path = folder / "case.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(("key", "value"), CASES)
def test_an_absurd_design_value_is_named_with_its_range(tmp_path, key, value):
    with pytest.raises(CaseFileError) as info:
        load_case(_write(tmp_path, key, value), require_test=False)
    message = str(info.value)
    assert "\n" not in message
    assert f"[building] {key} = {float(value)!r}" in message, message
    assert RANGES[key][2] in message, message


@pytest.mark.parametrize("key", ["radius", "rate", "post_yield_stiffness", "characteristic_strength",
                                 "yield_displacement", "damping_coefficient"])
def test_the_values_at_the_ends_of_the_ranges_are_taken(tmp_path, key):
    """The bounds themselves are valid (the ranges are closed): the file loads."""
    ends = {"radius": ("0.01", "1000.0"), "rate": ("0.0", "10000.0"), "post_yield_stiffness": ("3948.0", "3.9478e9"),
            "characteristic_strength": ("0.001", "9.8066e6"), "yield_displacement": ("1e-5", "1.0"),
            "damping_coefficient": ("0.0", "9.8066e7")}[key]
    for value in ends:
        load_case(_write(tmp_path, key, value), require_test=False)


@pytest.mark.parametrize(("command", "key", "value"), [(("synth", "--building"), "radius", "1e308"),
                                                       (("building",), "post_yield_stiffness", "1e308")])
def test_the_commands_exit_2_with_one_line_and_write_nothing(tmp_path, monkeypatch, command, key, value):
    monkeypatch.chdir(tmp_path)
    _write(tmp_path, key, value)
    r = CliRunner().invoke(app, [*command, "case.toml", "--out", "out"])
    assert r.exit_code == 2, r.output
    assert r.stderr.startswith("error: ") and r.stderr.count("\n") == 1, r.stderr
    assert f"[building] {key} = 1e+308" in r.stderr and "Traceback" not in r.output
    assert not (tmp_path / "out").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]
