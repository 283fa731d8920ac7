"""The device's record refused where it is read, before any fit (issue 24's loose ends, after h29b's building
checks): a ``[record] release_time`` outside the record's time span (it went on to the fit, which blamed the record
for starting in motion, or for too few samples before the release), and a record problem of a device campaign's
test named with the campaign file and the test (before: the test alone, and only after the tests before it were
fitted). Each is one line on stderr naming the file, the key or column, the value and what is valid, exit 2,
nothing written. The records are short and need not be a release: the refusals come before any fit."""

import numpy as np
import pytest
from typer.testing import CliRunner

from quickrelease.cli import app
from quickrelease.io.case import load_case

runner = CliRunner()

T0, DT, N = -0.5, 0.01, 200  # the records' first time stamp [s], step [s] and samples: they end at 1.49 s
T_END = T0 + (N - 1) * DT
HEAD = "[device]\npreset = 'paper'\n[test]\nmass_model = 'distributed'\n"
CHANNELS = "[record.channels]\nu = { column = 'u_m', noise = '0.5 mm' }\nv = { column = 'v_m', noise = '0.5 mm' }\n"


def _record(path, scale=1.0, columns=("u_m", "v_m")):
    """A record of u and v [m] on [T0, T_END] (a decaying swing of 0.2 m after 0 s, times scale)."""
    t = T0 + DT * np.arange(N)
    s = np.clip(t, 0.0, None)
    x = scale * 0.2 * np.exp(-s) * np.cos(4.0 * s)
    np.savetxt(path, np.column_stack([t, x, 0.5 * x]), delimiter=",", header="t_s," + ",".join(columns),
               comments="", fmt="%.10g")


def _refused(args, out, *words):
    r = runner.invoke(app, [*args, "--out", str(out)])
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, (r.exit_code, r.output, r.exception)
    assert all(w in lines[0] for w in words), (words, lines[0])
    assert "Traceback" not in r.output and not out.exists()
    return lines[0]


def _case(folder, release_time: str) -> str:
    _record(folder / "x.csv")
    path = folder / "case.toml"
    path.write_text(HEAD + "force = '1598 kN'\nalpha0 = '0.2 rad'\n[record]\nfile = 'x.csv'\ntime = 't_s'\n"
                    f"release_time = {release_time}\n" + CHANNELS, encoding="utf-8")
    return str(path)


@pytest.mark.parametrize("value, shown", [("'-5 s'", "-5 s"), ("'1e308 s'", "1e+308 s"), ("'1.5 s'", "1.5 s"),
                                          ("'-0.51 s'", "-0.51 s")])
def test_a_device_release_time_outside_the_record_is_refused_at_load(tmp_path, value, shown):
    """The record's span is [-0.5, 1.49] s (written here): just outside either end is refused."""
    _refused(["fit", _case(tmp_path, value)], tmp_path / "out", "case.toml: ", f"release_time = {shown}: ",
             f"expected a release instant within the time span of the record x.csv, [{T0:g}, {T_END:g}] s")


def test_a_device_release_time_within_the_record_is_taken(tmp_path):
    from quickrelease.studies.fit import load_case_record

    for value, expected in (("'-0.5 s'", T0), ("'1.49 s'", T_END), ("'0.2 s'", 0.2)):
        record = load_case_record(load_case(_case(tmp_path, value)))
        assert record.release_time == pytest.approx(expected, abs=1e-12)


def _campaign(folder, r2: str = "", r2_record=None) -> str:
    """Three tests of the paper's device, T1 to T3 on records R1.csv to R3.csv; T2's entry takes ``r2``."""
    text = HEAD + "[record]\ntime = 't_s'\n" + CHANNELS
    for i in (1, 2, 3):
        if i != 2 or r2_record is None:
            _record(folder / f"R{i}.csv")
        text += (f"[[tests]]\nname = 'T{i}'\nforce = '{1000 + 300 * i} kN'\nalpha0 = '0.2 rad'\n"
                 f"record = 'R{i}.csv'\n" + (r2 + "\n" if i == 2 else ""))
    if r2_record is not None:
        r2_record(folder / "R2.csv")
    path = folder / "c.toml"
    path.write_text(text, encoding="utf-8")
    return str(path)


@pytest.mark.parametrize("what", ["missing column", "noise above the range", "release_time"])
def test_a_record_problem_in_a_device_campaign_names_the_test(tmp_path, what):
    """The campaign file, the test, the record's file and its column (or key), at once: every test's record is read
    before the first fit (before: "test T2: ..." without the campaign file, after T1's fit, and here T1's record,
    not a release, failed its fit first)."""
    if what == "missing column":
        path = _campaign(tmp_path, r2_record=lambda p: _record(p, columns=("u_m", "w_m")))
        words = ("R2.csv: no column 'v_m' for channel v",)
    elif what == "noise above the range":  # u's range 0.2 um, below its noise 0.5 mm
        path = _campaign(tmp_path, r2_record=lambda p: _record(p, scale=1e-6))
        words = ("R2.csv: column 'u_m' (channel u): noise = 0.0005 m: expected a noise standard deviation in (0, ",)
    else:
        path = _campaign(tmp_path, "release_time = '-5 s'")
        words = ("release_time = -5 s: expected a release instant within the time span of the record R2.csv, "
                 f"[{T0:g}, {T_END:g}] s",)
    line = _refused(["campaign", path], tmp_path / "out", "c.toml: test T2: ", *words)
    assert line.count("test T2") == 1, line


def test_an_infeasible_stop_observation_in_a_device_campaign_is_one_line(tmp_path):
    """A test's stop time outside the interval its alpha0 and alpha_final allow (InfeasibleObservationError) was
    re-raised with the test's name as ``type(exc)(message)``: a TypeError traceback (its constructor takes the
    stop time and the interval). Now one line, the campaign file and the test in front."""
    path = tmp_path / "c.toml"
    path.write_text(HEAD + "".join(f"[[tests]]\nname = '{n}'\nforce = '{f} MN'\nalpha0 = 0.2\nalpha_final = 0.6\n"
                                   f"stop_time = {t}\n" for n, f, t in (("A", 1.0, 100), ("B", 1.2, 1), ("C", 1.4, 1))),
                    encoding="utf-8")
    _refused(["campaign", str(path)], tmp_path / "out", "c.toml: test A: t_F = 100 s is outside the feasible interval")
