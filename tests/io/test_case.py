from pathlib import Path

import pytest

from quickrelease import DeviceFileError, preset, strain_energy
from quickrelease.io.case import CaseFileError, load_case

EXAMPLES = Path(__file__).parents[2] / "examples"
BASE = """
title = "t"
[test]
force = "1598 kN"
alpha0 = "0.2 rad"
[friction]
F1 = "400 N"
F2 = "0.8 kN"
"""


def write(tmp_path, text, name="case.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_paper_example_matches_the_builtin_case():
    from importlib import resources

    builtin = load_case(resources.files("quickrelease") / "data" / "cases" / "paper.toml")
    example = load_case(EXAMPLES / "paper.toml")
    assert builtin.replace(source="x") == example.replace(source="x")
    assert example.stored_energy == 2900.0 and example.push_force == 1598e3 and example.energy_given
    assert example.alpha_final == 0.7378 and example.stop_time == 1.05
    assert example.mass_factor == pytest.approx(2 / 3)


def test_larger_push_example():
    case = load_case(EXAMPLES / "larger_push.toml")
    assert case.device.name == "my-device"
    assert case.alpha0 == pytest.approx(14.32 * 3.141592653589793 / 180)
    assert case.stored_energy == pytest.approx(strain_energy(2200e3, case.alpha0, preset()).total)
    assert (case.F1, case.F2) == (419.85, pytest.approx(804.57))
    assert case.method == "rk" and case.t_end == 2.0


def test_units_and_defaults(tmp_path):
    case = load_case(write(tmp_path, BASE))
    assert case.push_force == 1598e3 and case.F2 == 800.0
    assert case.method == "energy" and case.mass_model == "distributed" and case.device == preset("paper")
    assert case.stored_energy == pytest.approx(2915.4186, abs=1e-4)


def test_inline_device(tmp_path):
    keys = {k: "1" for k in ("m1", "m2", "L1", "L2", "L3", "L4", "A1", "A2", "A3", "A4", "I2", "E", "G", "kappa")}
    keys["m1"] = '"0.6 t"'
    body = BASE + "[device]\n" + "\n".join(f"{k} = {v}" for k, v in keys.items())
    case = load_case(write(tmp_path, body))
    assert case.device.m1 == pytest.approx(600.0)


def test_device_file_relative_to_case(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "dev.toml").write_text((EXAMPLES / "device.toml").read_text())
    case = load_case(write(tmp_path, BASE + '[device]\nfile = "sub/dev.toml"\n'))
    assert case.device.name == "my-device"


@pytest.mark.parametrize("body,message", [
    # missing key
    (BASE.replace('alpha0 = "0.2 rad"\n', ""),
     r"case.toml: missing key \[test\] alpha0 \(an angle in \(0, pi/2\), e.g. '0.2 rad' or '11.46 deg'\)$"),
    (BASE.replace('F2 = "0.8 kN"\n', ""), r"case.toml: missing key \[friction\] F2 \(give both F1 and F2\)$"),
    # unknown key
    (BASE.replace("[friction]", "[friction]\nF3 = 1"), r"case.toml: unknown key \[friction\] 'F3'; valid: F1, F2, correlation, case$"),
    (BASE.replace('title = "t"', 'titel = "t"'), r"case.toml: unknown key 'titel'; valid top-level entries: "),
    # wrong unit dimension
    (BASE.replace('"1598 kN"', '"1598 m"'),
     r"case.toml: \[test\] force = '1598 m': has dimension \[length\]; expected a force \(e.g. in N\)$"),
    # negative value
    (BASE.replace('"400 N"', '"-400 N"'),
     r"case.toml: \[friction\] F1 = '-400 N': expected a force >= 0, e.g. '420 N'$"),
    (BASE.replace('"0.2 rad"', '"2 rad"'),
     r"case.toml: \[test\] alpha0 = '2 rad': expected an angle in \(0, pi/2\), e.g. '0.2 rad' or '11.46 deg'$"),
    # malformed TOML
    (BASE + "\n[test\n", r"case.toml: not valid TOML \("),
    # other shapes
    (BASE.replace("[friction]", "[simulation]\nmethod = \"euler\"\n[friction]"),
     r"case.toml: \[simulation\] method = 'euler': expected 'energy', 'rk' or 'explicit'$"),
    (BASE.replace('force = "1598 kN"\n', ""), r"case.toml: missing key \[test\] force or energy"),
    ('[test]\nforce = 1\nalpha0 = 0.2\n', r"missing table \[friction\] \(to simulate\), \[observations\] \(to identify\) or \[record\] \(to fit\)"),
    (BASE + '[observations]\nalpha_final = "0.1 rad"\nstop_time = "1 s"\n',
     r"\[observations\] alpha_final = '0.1 rad': expected an angle greater than alpha0 = 0.2 rad$"),
    (BASE + '[device]\npreset = "other"\n', r"case.toml \[device\]: preset = other is outside the presets paper"),
])
def test_case_file_errors(tmp_path, body, message):
    with pytest.raises(CaseFileError, match=message) as info:
        load_case(write(tmp_path, body))
    assert "\n" not in str(info.value)


def test_inline_device_error_names_file_and_key(tmp_path):
    with pytest.raises(DeviceFileError, match=r"case.toml \[device\]: missing key 'm1'"):
        load_case(write(tmp_path, BASE + "[device]\nm2 = 1\n"))


def test_unreadable_case(tmp_path):
    with pytest.raises(CaseFileError, match="cannot read the case file"):
        load_case(tmp_path / "none.toml")
