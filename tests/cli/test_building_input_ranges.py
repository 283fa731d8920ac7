"""Bad values of a building's case and campaign files that were accepted (h28b's probes, issue 24): a release time
outside the record, a noise level above the record's range, a test without a visible name, a record problem that
did not name the campaign's test, a folder as a campaign's record (a TypeError traceback), a period of 1e308 s.
Each is one line on stderr naming the parameter, its value and its valid range, exit 2, nothing written; every
refusal comes before any fit, so these tests cost no fit (the records are short and need not be a building's)."""

import os

import numpy as np
import pytest
from typer.testing import CliRunner

from quickrelease.cli import app
from quickrelease.errors import CaseFileError
from quickrelease.studies._laws import iter_tests

runner = CliRunner()

T0, DT, N = -1.5, 0.02, 400  # the records' first time stamp [s], step [s] and samples: they end at 6.48 s
T_END = T0 + (N - 1) * DT
CHANNEL = "x = { column = 'x_mm', unit = 'mm', noise = '0.2 mm' }"


def _record(path, scale=1.0) -> float:
    """A record of x [mm] on [T0, T_END]; returns the channel's range, largest less smallest value [mm]."""
    t = T0 + DT * np.arange(N)
    x = scale * (150.0 * np.exp(-0.2 * np.clip(t, 0, None)) * np.cos(np.pi * np.clip(t, 0, None)) + 2.0)
    np.savetxt(path, np.column_stack([t, x]), delimiter=",", header="t_s,x_mm", comments="", fmt="%.10g")
    return float(x.max() - x.min())


def _case(folder, record_extra="", channel=CHANNEL, building="period = '2.2 s'\n"):
    path = folder / "case.toml"
    path.write_text("[building]\nmodel = 'linear'\nmass = '650 t'\n" + building + "[building.record]\nfile = 'x.csv'\n"
                    "time = 't_s'\n" + record_extra + "[building.record.channels]\n" + channel + "\n",
                    encoding="utf-8")
    return path


def _campaign(folder, tests=("", "", ""), channel=CHANNEL):
    text = ("[building]\nmodel = 'linear'\nmass = '650 t'\n[building.record]\ntime = 't_s'\n"
            "[building.record.channels]\n" + channel + "\n")
    for i, extra in enumerate(tests):
        entry = {"name": f"'R{i + 1}'", "displacement": f"'{100 + 50 * i} mm'", "record": f"'R{i + 1}.csv'"}
        for line in filter(None, extra.split("\n")):
            key, value = line.split(" = ", 1)
            entry[key] = value
        text += "[[tests]]\n" + "".join(f"{k} = {v}\n" for k, v in entry.items())
    path = folder / "camp.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _refused(command, path, out, *words):
    r = runner.invoke(app, [command, str(path), "--out", str(out)])
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, (r.exit_code, r.output, r.exception)
    assert all(w in lines[0] for w in words), (words, lines[0])
    assert "Traceback" not in r.output and not out.exists()
    return lines[0]


@pytest.mark.parametrize("value, shown", [("'-5 s'", "-5 s"), ("'6.5 s'", "6.5 s"), ("'1e308 s'", "1e+308 s"),
                                          ("'-1.6 s'", "-1.6 s")])
def test_a_release_time_outside_the_record_is_refused(tmp_path, value, shown):
    """The release must lie within the record's time span, its first to its last time stamp (here [-1.5, 6.48] s,
    written by the test); just outside either end is refused, the ends themselves are not (next test)."""
    _record(tmp_path / "x.csv")
    _refused("building", _case(tmp_path, f"release_time = {value}\n"), tmp_path / "out", "case.toml",
             f"release_time = {shown}: ", f"within the time span of the record x.csv, [{T0:g}, {T_END:g}] s")


def test_a_release_time_within_the_record_is_taken(tmp_path):
    from quickrelease.io.building_case import load_building
    from quickrelease.io.case import load_case

    _record(tmp_path / "x.csv")
    for value, expected in (("'-1.5 s'", T0), ("'6.48 s'", T_END), ("'0.2 s'", 0.2)):
        data = load_building(load_case(_case(tmp_path, f"release_time = {value}\n"), require_test=False))
        assert data.release_time == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("noise", ["'1e308 mm'", "'10 km'", "'1.01 * RANGE mm'"])
def test_a_noise_level_above_the_channels_range_is_refused(tmp_path, noise):
    """A noise standard deviation above the channel's range in the record (largest less smallest value, computed
    here from the values written) is no sensor's: refused, the range named; at the range itself it is taken."""
    span = _record(tmp_path / "x.csv")
    noise = noise.replace("1.01 * RANGE", f"{1.01 * span!r}")
    line = _refused("building", _case(tmp_path, channel=f"x = {{ column = 'x_mm', unit = 'mm', noise = {noise} }}"),
                    tmp_path / "out", "x.csv", "column 'x_mm' (channel x): noise = ")
    assert f"expected a noise standard deviation in (0, {span:.6g}] mm" in line, line
    from quickrelease.io.building_case import load_building
    from quickrelease.io.case import load_case

    path = _case(tmp_path, channel=f"x = {{ column = 'x_mm', unit = 'mm', noise = '{0.999 * span!r} mm' }}")
    (channel,) = load_building(load_case(path, require_test=False)).channels
    assert channel.noise == pytest.approx(0.999e-3 * span, rel=1e-12)


def test_a_noise_level_below_the_float_resolution_is_refused(tmp_path):
    """1e-300 mm would weigh rounding errors (and overflowed the covariance: a LinAlgError traceback): a noise level
    is at least 1e-14 times the channel's largest value, as the device's fit requires."""
    _record(tmp_path / "x.csv")
    largest = 152.0e-3  # m: 150 mm + the 2 mm zero at the release, the record's largest value
    _refused("building", _case(tmp_path, channel="x = { column = 'x_mm', unit = 'mm', noise = '1e-300 mm' }"),
             tmp_path / "out", "x.csv: column 'x_mm' (channel x): noise = 1e-303 m: ",
             f"at least {1e-14 * largest:.3g} m")


def test_a_campaigns_noise_level_names_the_test(tmp_path):
    spans = [_record(tmp_path / f"R{i}.csv", scale) for i, scale in ((1, 1.0), (2, 0.001), (3, 1.0))]
    _refused("campaign", _campaign(tmp_path, channel="x = { column = 'x_mm', unit = 'mm', noise = '2 mm' }"),
             tmp_path / "out", "camp.toml: test R2: ", "R2.csv: column 'x_mm' (channel x): noise = 2 mm",
             f"(0, {spans[1]:.6g}] mm")


@pytest.mark.parametrize("name", ["''", "'   '", '" \\t\\n "', "{ a = 1 }", "true", "[1, 2]"])
def test_a_test_without_a_visible_name_is_refused(tmp_path, name):
    """Empty, blank (spaces, a tab, a line break) or not a string: refused. A name with a line break or an escape
    among other characters is a name (tests/cli/test_text.py: shown harmless in every output)."""
    for i in (1, 2, 3):
        _record(tmp_path / f"R{i}.csv")
    _refused("campaign", _campaign(tmp_path, tests=(f"name = {name}", "", "")), tmp_path / "out", "camp.toml: ",
             "tests[0] name = ", "expected a test name")


def test_non_ascii_and_numbered_test_names_are_names():
    tests = [{"name": "Prüfung 1 — 試験"}, {"name": 2}, {}]
    assert [name for name, _, _ in iter_tests(tests, "c.toml", "R")] == ["Prüfung 1 — 試験", "2", "R3"]
    with pytest.raises(CaseFileError, match=r"c.toml: tests\[1\] name = ' \\n': expected a test name"):
        list(iter_tests([{}, {"name": " \n"}], "c.toml", "R"))


@pytest.mark.parametrize("what", ["missing column", "folder", "FIFO", "release_time"])
def test_a_record_problem_in_a_campaign_names_the_test(tmp_path, what):
    """The record's file and column, and which test's record it is (before: file and column only); a folder as a
    record ended in a TypeError traceback (the run folder's fingerprint opened it)."""
    for i in (1, 3):
        _record(tmp_path / f"R{i}.csv")
    tests = ["", "", ""]
    if what == "missing column":
        (tmp_path / "R2.csv").write_text("t_s,y_mm\n0,1\n0.1,2\n", encoding="utf-8")
        words = ("R2.csv: no column 'x_mm' for channel x",)
    elif what == "folder":
        (tmp_path / "R2.csv").mkdir()
        words = ("R2.csv: not a regular file (a folder)",)
    elif what == "FIFO":
        os.mkfifo(tmp_path / "R2.csv")
        words = ("R2.csv: not a regular file (a FIFO)",)
    else:
        _record(tmp_path / "R2.csv")
        tests[1] = "release_time = '-5 s'"
        words = ("release_time = -5 s: expected a release instant within the time span of the record R2.csv",)
    line = _refused("campaign", _campaign(tmp_path, tests=tests), tmp_path / "out", "camp.toml: test R2: ", *words)
    assert line.count("test R2") == 1, line


@pytest.mark.parametrize("building, words", [
    ("period = '1e308 s'\n", "[building] period = '1e308 s': expected period in [0.01, 1000] s"),
    ("period = '1 ms'\n", "[building] period = '1 ms': expected period in [0.01, 1000] s"),
    ("model = 'boucwen'\npost_yield_stiffness = '1.6 MN/m'\ncharacteristic_strength = '1e20 N'\n",
     "[building] characteristic_strength = '1e20 N': expected characteristic_strength in (0, 6.37432e+06] N"),
    # k = m (2 pi / T)^2 at T = 1000 s and 0.01 s, m = 650 t: 25.661 and 2.5661e11 N/m
    ("model = 'bilinear'\nk1 = '1e308 N/m'\nk2 = '4 MN/m'\nyield_force = '80 kN'\n",
     "[building] k1 = '1e308 N/m': expected k1 in [25.661, 2.5661e+11] N/m"),
    ("model = 'bilinear'\nk1 = '40 MN/m'\nk2 = '1e-300 N/m'\nyield_force = '80 kN'\n",
     "[building] k2 = '1e-300 N/m': expected k2 in [25.661, 2.5661e+11] N/m"),
])
def test_design_values_out_of_range_name_their_range(tmp_path, building, words):
    """A period of 1e308 s made the stiffness 0 N/m, refused in a line naming neither file nor key; the Bouc-Wen
    bearings' Qd is > 0 (its ``0 N`` is refused), so its range is (0, m g], m g = 650 t x 9.80665 m/s^2."""
    _record(tmp_path / "x.csv")
    text = _case(tmp_path, building=building).read_text(encoding="utf-8")
    if "model" in building:
        text = text.replace("model = 'linear'\n", "")
    (tmp_path / "case.toml").write_text(text, encoding="utf-8")
    _refused("building", tmp_path / "case.toml", tmp_path / "out", "case.toml: ", words)
