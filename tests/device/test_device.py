import math

import pytest

from quickrelease import DEVICE_KEYS, Device, DeviceFileError, ParameterError, load_device, preset, preset_names


def test_paper_preset_is_table_2_in_si(paper_device):
    d = paper_device
    expected = dict(m1=576.78, m2=531.69, L1=2.477, L2=1.062, L3=0.561, L4=0.433, A1=14910e-6, A2=40780e-6,
                    A3=1414e-6, A4=531e-6, I2=791175e-9, E=205970e6, G=80000e6, kappa=0.20)
    for key, value in expected.items():
        assert getattr(d, key) == pytest.approx(value, rel=1e-15), key
    assert d.mass_ratio == pytest.approx(576.78 / 531.69, rel=1e-15)
    assert "paper" in preset_names()


def test_unknown_preset_names_the_valid_ones():
    with pytest.raises(ParameterError, match="preset = nope is outside the presets paper"):
        preset("nope")


def _write(tmp_path, body):
    path = tmp_path / "dev.toml"
    path.write_text(body)
    return path


def _full(**overrides):
    entries = {k: "1" for k in DEVICE_KEYS}
    entries.update(overrides)
    return "\n".join(f"{k} = {v}" for k, v in entries.items())


def test_device_file_with_units(tmp_path):
    path = _write(tmp_path, _full(m1='"0.57678 t"', A4='"531 mm^2"', E='"205.97 GPa"', I2='"791175 cm^4"'))
    d = load_device(path)
    assert d.m1 == pytest.approx(576.78)
    assert d.A4 == pytest.approx(531e-6)
    assert d.E == pytest.approx(205.97e9)
    assert d.I2 == pytest.approx(791175e-8)
    assert d.name == "dev"


def test_missing_key_is_named(tmp_path):
    body = "\n".join(f"{k} = 1" for k in DEVICE_KEYS if k != "A3")
    with pytest.raises(DeviceFileError, match=r"dev.toml: missing key 'A3'"):
        load_device(_write(tmp_path, body))


def test_unknown_key_is_named(tmp_path):
    with pytest.raises(DeviceFileError, match=r"dev.toml: unknown key 'L5'"):
        load_device(_write(tmp_path, _full(L5="1")))


@pytest.mark.parametrize("value", ["0", "-2.0", '"-3 kg"'])
def test_non_positive_entry_is_named(tmp_path, value):
    with pytest.raises(DeviceFileError, match=r"dev.toml: m2 = .* must be positive"):
        load_device(_write(tmp_path, _full(m2=value)))


def test_wrong_dimension_is_named(tmp_path):
    with pytest.raises(DeviceFileError, match=r"dev.toml: L1 = '2 kg' has dimension \[mass\]; expected a length"):
        load_device(_write(tmp_path, _full(L1='"2 kg"')))


def test_malformed_toml(tmp_path):
    with pytest.raises(DeviceFileError, match=r"dev.toml: not valid TOML"):
        load_device(_write(tmp_path, "m1 = = 3"))


def test_missing_file(tmp_path):
    with pytest.raises(DeviceFileError, match="cannot read the device file"):
        load_device(tmp_path / "absent.toml")


@pytest.mark.parametrize("key", ["m1", "L2", "A4", "E", "kappa"])
def test_constructor_rejects_non_positive(paper_device, key):
    with pytest.raises(ParameterError, match=rf"^{key} = -1 .*is outside \(0, inf\)"):
        paper_device.replace(**{key: -1.0})
    with pytest.raises(ParameterError):
        paper_device.replace(**{key: math.nan})


def test_device_errors_are_value_errors(paper_device):
    with pytest.raises(ValueError):
        paper_device.replace(m1=0.0)
    assert isinstance(Device(**{k: 1.0 for k in DEVICE_KEYS}), Device)


def test_example_device_file_loads(paper_device):
    from pathlib import Path

    d = load_device(Path(__file__).parents[2] / "examples" / "device.toml")
    assert d.name == "my-device"
    assert all(getattr(d, k) == getattr(paper_device, k) for k in DEVICE_KEYS)
