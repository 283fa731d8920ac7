"""The building in a case file (issue 10, items 2, 5 and 8): ``[building]`` with its models, ``[building.record]``
read by :func:`quickrelease.io.building_case.load_building`, and synthetic building records (``synth``).

References: hand calculations (the bilinear push curve, the start values), and the independent solve_ivp
simulation of tests/building_reference.py for the synthetic records.
"""

import math

import numpy as np
import pytest
from building_reference import reference, reference_2dof
from typer.testing import CliRunner

from quickrelease.building.model import TwoDOF
from quickrelease.cli import app
from quickrelease.errors import QuickReleaseError
from quickrelease.io.building_case import load_building
from quickrelease.io.case import CaseFileError, load_case
from quickrelease.io.records import RecordError
from quickrelease.studies.planning import building_isolation, pushed_displacement
from quickrelease.studies.synth import synthesize_building

G = 9.80665
runner = CliRunner()

LINEAR = """[building]
mass = "650 t"
period = "2.0 s"
damping_ratio = 0.05
friction_coefficient = 0.02
displacement = "0.15 m"
"""
BILINEAR = """[building]
model = "bilinear"
mass = "400 t"
k1 = "40 MN/m"
k2 = "4 MN/m"
yield_force = "80 kN"
damping_ratio = 0.03
friction = "20 kN"
displacement = "150 mm"
"""
TWO_DOF = """[building]
model = "2dof"
weight = "6.37 MN"
period = "2.0 s"
superstructure_mass = "500 t"
superstructure_period = "0.5 s"
superstructure_damping_ratio = 0.02
displacement = "0.1 m"
"""


def _case(tmp_path, text, name="case.toml"):
    path = tmp_path / name
    path.write_text(text)
    return load_case(path, require_test=False)


def test_the_three_models_parse_and_give_start_values(tmp_path):
    lin = _case(tmp_path, LINEAR).building
    assert (lin.model, lin.mass, lin.period, lin.friction_force) == ("linear", 650e3, 2.0, 0.02 * 650e3 * G)
    iso = building_isolation(lin)
    assert iso.model == "linear" and iso.stiffness == pytest.approx(650e3 * math.pi**2, rel=1e-15)
    bil = _case(tmp_path, BILINEAR)
    iso = building_isolation(bil.building)
    assert (iso.model, iso.stiffness, iso.k2, iso.yield_force, iso.friction) == ("bilinear", 4e7, 4e6, 8e4, 2e4)
    data = load_building(bil)
    # hand calculation: T1 = 2 pi sqrt(m / k1) = 2 pi sqrt(0.01 s^2) = 0.2 pi s
    assert data.start == pytest.approx({"period": 0.2 * math.pi, "stiffness_ratio": 0.1, "yield_force": 8e4,
                                        "damping_ratio": 0.03, "friction": 2e4, "d0": 0.15}, rel=1e-15)
    assert data.isolation == iso and data.channels == [] and data.d0 == 0.15
    two = _case(tmp_path, TWO_DOF)
    data = load_building(two)
    assert data.model == "2dof" and isinstance(data.isolation, TwoDOF) and data.mass == pytest.approx(6.37e6 / G,
                                                                                                        rel=1e-15)
    assert data.superstructure_mass == 5e5
    assert data.start == {"period": 2.0, "d0": 0.1, "superstructure_period": 0.5, "superstructure_damping_ratio": 0.02}
    # planning takes the 2-DOF building as rigid on its isolation layer, with the whole mass
    assert building_isolation(two.building).mass == data.mass


def test_bilinear_push_curve_gives_d0():
    """P - F_s = R(d0) on the bilinear push curve: below the yield force d0 = (P - F_s) / k1, beyond it
    d_y + (P - F_s - F_y) / k2 (hand calculation with F_y = 80 kN, k1 = 40 MN/m, k2 = 4 MN/m, F_s = 20 kN)."""
    from dataclasses import replace

    from quickrelease.io.case import BuildingSpec

    b = BuildingSpec(model="bilinear", mass=4e5, k1=4e7, k2=4e6, yield_force=8e4, friction=2e4)
    assert pushed_displacement(80e3, b) == pytest.approx(60e3 / 4e7, rel=1e-14)          # elastic: 1.5 mm
    assert pushed_displacement(620e3, b) == pytest.approx(2e-3 + 520e3 / 4e6, rel=1e-14)  # 2 mm + 130 mm
    assert pushed_displacement(620e3, replace(b, displacement=0.1)) == 0.1


BAD_BUILDING = [
    (LINEAR + 'k1 = "40 MN/m"\n', r"\[building\] k1 = '40 MN/m' with model = 'linear': k1 belongs to model = "
                                  r"'bilinear'"),
    (LINEAR + "superstructure_damping_ratio = 0.02\n", r"superstructure_damping_ratio = 0.02 with model = 'linear'"),
    (BILINEAR + 'period = "2 s"\n', r"\[building\] period = '2 s' with model = 'bilinear'"),
    (BILINEAR.replace('k2 = "4 MN/m"', 'k2 = "40 MN/m"'), r"\[building\] k2 = '40 MN/m': expected a post-yield "
                                                          r"stiffness in \(0, k1\) = \(0, 4e\+07\) N/m"),
    (BILINEAR.replace('mass = "400 t"\n', ""), r"missing key \[building\] mass \(or weight\) for model = 'bilinear'"),
    (BILINEAR.replace('k1 = "40 MN/m"', 'k1 = "40 kN"'), r"\[building\] k1 = '40 kN': has dimension "
                                                         r"\[mass\] \* \[length\] / \[time\] \*\* 2; expected a "
                                                         r"stiffness"),
    (TWO_DOF.replace('"500 t"', '"700 t"'), r"superstructure_mass = '700 t': expected a mass in \(0, \[building\] "
                                           r"mass\)"),
    (LINEAR.replace('model', 'x') + 'model = "trilinear"\n', r"\[building\] model = 'trilinear': expected 'linear', "
                                                             r"'bilinear', '2dof', 'pendulum' or 'boucwen'"),
    (LINEAR + "[building.record]\nfile = 'r.csv'\ntime = 't'\n[building.record.channels]\nu = 'u_m'\n",
     r"\[building.record\] channels.u: unknown channel 'u'; valid: x, v, a, x_roof, v_roof, a_roof"),
    (LINEAR + "[building.record]\nfile = 'r.csv'\ntime = 't'\n[building.record.channels]\n"
              "x = { column = 'x', unit = 'mm/s' }\n",
     r"\[building.record\] channels.x.unit = 'mm/s': has dimension \[length\] / \[time\]; expected a length"),
    (LINEAR + "[building.record]\nfile = 'r.csv'\ntime = 't'\n[building.record.channels]\n"
              "a = { column = 'a', time = 't2' }\n", r"channels.a: time = 't2' without file"),
    (LINEAR + "[building.record]\nfile = 'r.csv'\ntime = 't'\nrate = 5\n[building.record.channels]\nx = 'x'\n",
     r"\[building.record\]: unknown key 'rate'"),
]


#: Design values left out: the case parses (a fit needs the mass only), and what needs them names the key.
NO_DESIGN = [
    (LINEAR.replace('period = "2.0 s"\n', ""), ["period"], r"missing key \[building\] period for model = 'linear'"),
    (BILINEAR.replace('k2 = "4 MN/m"\n', ""), ["k2"], r"missing key \[building\] k2 for model = 'bilinear'"),
    (TWO_DOF.replace('superstructure_period = "0.5 s"\n', ""), ["superstructure_period"],
     r"missing key \[building\] superstructure_period for model = '2dof'"),
]


@pytest.mark.parametrize("text, missing, message", NO_DESIGN)
def test_design_values_are_optional_until_needed(tmp_path, text, missing, message):
    from quickrelease.io.building_case import spec_building

    spec = _case(tmp_path, text).building
    assert spec.missing_design() == missing
    with pytest.raises(CaseFileError, match=message + r": the building's model needs the design values"):
        spec_building(spec)


@pytest.mark.parametrize("text, message", BAD_BUILDING)
def test_bad_building_tables_are_one_line(tmp_path, text, message):
    with pytest.raises(CaseFileError, match=message) as err:
        _case(tmp_path, text)
    assert "\n" not in str(err.value) and str(err.value).startswith(str(tmp_path / "case.toml"))


def test_a_building_case_needs_a_test_only_for_the_device(tmp_path):
    (tmp_path / "case.toml").write_text(LINEAR)
    with pytest.raises(CaseFileError, match=r"missing table \[test\]"):
        load_case(tmp_path / "case.toml")
    case = load_case(tmp_path / "case.toml", require_test=False)
    assert not case.has_test and math.isnan(case.alpha0)
    with pytest.raises(CaseFileError, match=r"missing key \[building\] mass \(or weight\): the building's record"):
        load_building(_case(tmp_path, LINEAR.replace('mass = "650 t"\n', "").replace(
            "friction_coefficient = 0.02\n", "")))


RECORD = LINEAR + """[building.record]
file = "main.csv"
time = "t_s"
release_time = "1.0 s"
[building.record.channels]
x = { column = "x_mm", unit = "mm", noise = "0.05 mm" }
a = { column = "a_g", unit = "g0", file = "acc.csv", time = { column = "t_ms", unit = "ms" }, offset = false }
a_roof = { column = "a_roof", unit = "m/s^2", scale = -1 }
"""


def _write_record(tmp_path, nan_rows=(7, 8), acc_rows=150):
    t = np.arange(400) / 200.0
    x = 150.0 * np.cos(t)
    lines = ["t_s,x_mm,a_roof"] + [f"{float(ti)!r},{'' if i in nan_rows else repr(float(xi))},{float(-xi / 1e3)!r}"
                                   for i, (ti, xi) in enumerate(zip(t, x, strict=True))]
    (tmp_path / "main.csv").write_text("\n".join(lines) + "\n")
    ta = np.arange(acc_rows) * 10.0
    (tmp_path / "acc.csv").write_text("t_ms,a_g\n" + "".join(f"{float(ti)!r},{0.1 * math.sin(ti / 1e3)!r}\n" for ti in ta))
    return t, x


def test_the_record_in_si_with_own_time_axes_and_missing_rows(tmp_path):
    t, x = _write_record(tmp_path)
    data = load_building(_case(tmp_path, RECORD))
    ch = {c.name: c for c in data.channels}
    assert [c.kind for c in data.channels] == ["x", "a", "a_roof"] and data.release_time == 1.0
    # x: mm -> m, rows 7 and 8 (empty) skipped and reported
    assert ch["x"].t.size == 398 and 7 / 200.0 not in ch["x"].t and ch["x"].noise == pytest.approx(5e-5)
    np.testing.assert_allclose(ch["x"].values, np.delete(x, [7, 8]) / 1e3, rtol=1e-15)
    assert any("main.csv: column 'x_mm': 2 missing sample(s) skipped" in n for n in data.notes)
    # a: its own file, time in ms at 100 Hz, in g0
    assert ch["a"].t.size == 150 and ch["a"].t[1] == pytest.approx(0.01, rel=1e-15) and not ch["a"].offset
    assert ch["a"].values[1] == pytest.approx(0.1 * math.sin(0.01) * G, rel=1e-14)
    # a_roof: the sign reversed by scale = -1; an offset by default
    np.testing.assert_allclose(ch["a_roof"].values, x / 1e3, rtol=1e-15)
    assert ch["a_roof"].offset and ch["x"].offset


@pytest.mark.parametrize("change, message", [
    (lambda p: (p / "main.csv").unlink(), r"main.csv: record file not found"),
    (lambda p: (p / "acc.csv").write_text("t_ms,other\n0,1\n10,2\n"), r"acc.csv: no column 'a_g' for channel a"),
    (lambda p: (p / "acc.csv").write_text("t_ms,a_g\n" + "".join(f"{i},0.1\n" for i in (0, 10, 5, 20))),
     r"acc.csv: column 't_ms': time is not increasing at row 3"),
    (lambda p: (p / "acc.csv").write_text("t_ms,a_g\n" + "".join(f"{i},{'' if i else 1}\n" for i in range(12))),
     r"acc.csv: column 'a_g' \(channel a\): 1 valid sample\(s\), fewer than 10"),
    (lambda p: (p / "acc.csv").write_text("t_ms,a_g\n0,1\n10,oops\n"),
     r"acc.csv: column 'a_g': non-numeric value 'oops' at row 2"),
])
def test_bad_records_are_one_line_naming_file_and_column(tmp_path, change, message):
    _write_record(tmp_path)
    case = _case(tmp_path, RECORD)
    change(tmp_path)
    with pytest.raises(RecordError, match=message) as err:
        load_building(case)
    assert "\n" not in str(err.value)


# -- synthetic building records against the independent solve_ivp reference ------------------------------------

@pytest.mark.parametrize("text", [LINEAR, BILINEAR])
def test_noise_free_synthetic_records_match_solve_ivp(tmp_path, text):
    case = _case(tmp_path, text)
    syn = synthesize_building(case, ["x", "v", "a", "a_roof"], rate=200.0, release_time=1.37, duration=8.0, seed=3,
                              offsets={"x": 2e-3})
    b = case.building
    m = b.mass
    if b.model == "linear":
        k1 = k2 = m * (2 * math.pi / b.period) ** 2
        fp = math.inf
    else:  # the elastic-plastic element's yield force F_y (1 - k2 / k1)
        k1, k2, fp = b.k1, b.k2, b.yield_force * (1 - b.k2 / b.k1)
    c = 2 * b.damping_ratio * math.sqrt(k1 * m)
    ref, t_stop = reference(m, k1, k2, fp, c, b.friction_force, b.displacement, syn.t - 1.37, with_rates=True)
    for row, name in enumerate(("x", "v", "a")):
        scale = np.max(np.abs(ref[row]))
        assert np.max(np.abs(syn.clean[name] - ref[row])) < 1e-9 * scale, name
    np.testing.assert_array_equal(syn.clean["a_roof"], syn.clean["a"])  # a rigid superstructure
    assert syn.truth["stop_time_s"] == pytest.approx(t_stop, rel=1e-9)
    assert np.all(syn.clean["x"][syn.t < 1.37] == b.displacement)  # the pre-release segment at the pushed state
    # offsets and noise as asked: the recorded x is the truth + 2 mm + N(0, 0.05 mm)
    dx = syn.data["x"] - syn.clean["x"] - 2e-3
    assert abs(np.mean(dx)) < 5 * 5e-5 / math.sqrt(dx.size) and np.std(dx) == pytest.approx(5e-5, rel=0.05)


def test_synth_cli_round_trip_and_bad_input(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "b.toml").write_text(BILINEAR)
    r = runner.invoke(app, ["synth", "b.toml", "--channels", "x,a", "--rate", "100 Hz", "--duration", "6 s",
                            "--offset", "x=1 mm", "--noise", "a=0.002 g0", "--out", "r.csv", "--case-out", "c.toml",
                            "--json"])
    assert r.exit_code == 0, r.output
    case = load_case(tmp_path / "c.toml", require_test=False)  # the written case parses, with the truth
    spec = case.building
    assert (spec.k1, spec.k2, spec.yield_force, spec.friction, spec.displacement, spec.mass) == \
        (4e7, 4e6, 8e4, 2e4, 0.15, 4e5)
    data = load_building(case)
    syn = synthesize_building(_case(tmp_path, BILINEAR, "b3.toml"), ["x", "a"], rate=100.0, duration=6.0,
                              offsets={"x": 1e-3}, noise={"a": 0.002 * G})
    for ch in data.channels:  # the CSV holds the record to 10 significant digits
        np.testing.assert_allclose(ch.values, syn.data[ch.name], rtol=1e-9, atol=1e-12)
    # bad input: one line on stderr, exit 2, nothing written
    for args, message in [(["--channels", "x,u"], "unknown channel 'u'"),
                          (["--rate", "1 Hz"], "rate = 1 Hz is outside"),
                          (["--noise", "x=1 g0"], "--noise x = '1 g0' has dimension")]:
        r = runner.invoke(app, ["synth", "b.toml", "--out", "new.csv", "--case-out", "new.toml", *args])
        assert r.exit_code == 2 and message in r.stderr and r.stderr.count("\n") == 1, (args, r.stderr)
        assert not (tmp_path / "new.csv").exists() and not (tmp_path / "new.toml").exists()


def test_synth_refuses_a_push_the_sliders_hold(tmp_path):
    case = _case(tmp_path, LINEAR.replace('"0.15 m"', '"0.01 m"'))  # k d0 = 64 kN < F_s = 127 kN
    with pytest.raises(QuickReleaseError, match=r"case.toml: \[building\] d0 = 0.01 m: the sliders' friction F_s = "
                                                r"127486 N holds the building there \(restoring force 64152.4 N"):
        synthesize_building(case, ["x"], rate=200.0)


def test_an_edited_building_record_is_another_run(tmp_path):
    """The run folder's fingerprint takes the building's record files by their content, as the device's."""
    from quickrelease.io.runfolder import case_inputs, fingerprint

    _write_record(tmp_path)
    case = _case(tmp_path, RECORD)
    before = fingerprint(case_inputs(case))
    assert case_inputs(case)["building"]["record"]["channels"]["a"]["file"]["name"] == "acc.csv"
    with open(tmp_path / "acc.csv", "a") as fh:
        fh.write("1500.0,0.0\n")
    assert fingerprint(case_inputs(case)) != before


def test_the_shipped_whole_test_example(tmp_path):
    """examples/building.toml: a valid device case (for `run`) and a building case whose record has an LVDT in
    mm at 200 Hz and an accelerometer in g0 at 100 Hz in its own file; the truth of make_records.py."""
    import json
    from pathlib import Path

    from quickrelease import preset
    from quickrelease.studies.planning import member_checks

    path = Path(__file__).parents[2] / "examples" / "building.toml"
    case = load_case(path)
    assert case.has_test and case.alpha0 == 0.2 and case.building.mass == 8e5
    # the push of [test] holds the pushed building: P = k d0 + F_s (to 1e-4)
    k = 8e5 * math.pi**2
    assert case.push_force == pytest.approx(k * 0.1825 + 0.02 * 8e5 * G, rel=1e-4)
    data = load_building(case)
    x, a = data.channels
    assert (x.name, a.name) == ("x", "a") and np.median(np.diff(x.t)) == pytest.approx(5e-3)
    assert np.median(np.diff(a.t)) == pytest.approx(1e-2) and x.t[-1] == a.t[-1] == 60.0
    # before the release (2.05 s) the layer rests at d0 + 0.8 mm offset, the base at 0.004 g0 offset
    assert np.mean(x.values[x.t < 2.0]) == pytest.approx(0.1825 + 0.8e-3, abs=2e-5)
    assert np.mean(a.values[a.t < 2.0]) == pytest.approx(0.004 * G, abs=1e-3)
    assert any("missing sample(s) skipped" in note for note in data.notes)
    # `run` plans the clearance on it: the member checks' summary is valid JSON though the paper's device
    # has no W2 for the head's check (its demand unknown, not NaN)
    json.dumps(member_checks(1598e3, 0.2, preset("paper")).summary(), allow_nan=False)


def test_clearance_with_a_bilinear_building_reaches_its_first_return():
    """A bilinear isolation pushed far past its yield returns on its soft branch (T2 = 2 pi sqrt(m / k2) = 4 s
    here), later than 1.5 t_F and its initial period (0.63 s): the clearance covers the largest approach, which
    the independent solve_ivp reference puts at d0 - min x."""
    from quickrelease import preset
    from quickrelease.device.solvers import FirstIntegral
    from quickrelease.io.case import BuildingSpec
    from quickrelease.studies.planning import clearance

    d = preset("paper")
    release = FirstIntegral(2900.0, 0.2, 419.85, 804.57, d.m1, d.m2, d.L1, 2 / 3)
    m, k1, k2, Fy, d0 = 4e5, 4e7, 1e6, 8e4, 0.15
    b = BuildingSpec(model="bilinear", mass=m, k1=k1, k2=k2, yield_force=Fy, damping_ratio=0.02, friction=5e3)
    clear = clearance(release, b, d0)
    t = np.linspace(0.0, 6.0, 60001)
    x, _ = reference(m, k1, k2, Fy * (1 - k2 / k1), 2 * 0.02 * math.sqrt(k1 * m), 5e3, d0, t)
    assert t[np.argmin(x)] > 1.5 * release.stop_time()  # the first return comes after the device has stopped
    assert clear.max_approach == pytest.approx(d0 - np.min(x), rel=1e-6)


def test_planning_says_it_takes_the_2dof_building_as_rigid(tmp_path):
    from quickrelease.studies.planning import plan_case

    path = tmp_path / "case.toml"
    path.write_text('[test]\nforce = "1598 kN"\nenergy = "2.90 kJ"\nalpha0 = 0.2\n[friction]\nF1 = "420 N"\n'
                    'F2 = "805 N"\n' + TWO_DOF.replace('displacement = "0.1 m"\n', ""))
    plan = plan_case(load_case(path))
    assert any("2dof building taken as rigid" in note for note in plan.notes)
    # d0 = (P - 0) / k with k = m (2 pi / T)^2 of the whole mass (no friction given)
    assert plan.clearance.d0 == pytest.approx(1598e3 / (6.37e6 / G * math.pi**2), rel=1e-12)


# -- the 2dof building (issue 10, items 1 and 5) ---------------------------------------------------------------
TWO_DOF_FRICTION = TWO_DOF.replace("displacement", 'damping_ratio = 0.05\nfriction_coefficient = 0.01\ndisplacement')


def test_a_2dof_case_loads_to_its_twodof_building(tmp_path):
    """Hand values: m = W / g, m_s = 500 t, k = m (2 pi / 2 s)^2 = m pi^2, k_s = m_s (2 pi / 0.5 s)^2 = 16 pi^2 m_s,
    F_s = mu W = 0.01 x 6.37 MN; planning still takes the building as rigid on its isolation layer."""
    case = _case(tmp_path, TWO_DOF_FRICTION)
    b = load_building(case).isolation
    m = 6.37e6 / G
    assert isinstance(b, TwoDOF)
    assert (b.mass, b.superstructure_mass, b.period, b.superstructure_period) == pytest.approx((m, 5e5, 2.0, 0.5),
                                                                                             rel=1e-15)
    assert (b.damping_ratio, b.superstructure_damping_ratio) == (0.05, 0.02)
    assert b.friction == pytest.approx(0.01 * 6.37e6, rel=1e-15)
    assert b.stiffness == pytest.approx(m * math.pi**2, rel=1e-14)
    assert b.superstructure_stiffness == pytest.approx(16 * math.pi**2 * 5e5, rel=1e-14)
    rigid = building_isolation(case.building)
    assert rigid.model == "linear" and rigid.mass == b.mass and rigid.stiffness == pytest.approx(b.stiffness)


def test_synth_of_a_2dof_building_against_solve_ivp(tmp_path):
    """Noise-free 2dof record: every channel (base x, v, a; roof x_roof, v_roof, a_roof) against the independent
    event-driven solve_ivp of tests/building_reference.py, to 1e-9 of the channel's peak; the base and the roof
    rest at d0 before the release and part after it (the roof is not the base)."""
    case = _case(tmp_path, TWO_DOF_FRICTION)
    names = ["x", "v", "a", "x_roof", "v_roof", "a_roof"]
    syn = synthesize_building(case, names, rate=100.0, release_time=0.5, duration=5.0)
    m, ms = 6.37e6 / G, 5e5
    k, ks = m * (2 * math.pi / 2.0) ** 2, ms * (2 * math.pi / 0.5) ** 2
    ref, _ = reference_2dof(m, ms, k, 2 * 0.05 * math.sqrt(k * m), ks, 2 * 0.02 * math.sqrt(ks * ms), 0.01 * 6.37e6,
                            0.1, syn.t - 0.5)
    for name, key in zip(names, ("xb", "vb", "ab", "xs", "vs", "as"), strict=True):
        peak = np.max(np.abs(ref[key]))
        assert np.max(np.abs(syn.clean[name] - ref[key])) < 1e-9 * peak, name
    assert syn.clean["x"][0] == syn.clean["x_roof"][0] == 0.1
    assert np.max(np.abs(syn.clean["a_roof"] - syn.clean["a"])) > 0.1 * np.max(np.abs(syn.clean["a"]))
    assert syn.truth["superstructure_period_s"] == 0.5 and syn.truth["model"] == "2dof"
    # pushed where the sliders hold it (k d0 = m pi^2 x 0.01 m = 64.1 kN <= F_s = 0.1 W = 637 kN): refused
    held = _case(tmp_path, TWO_DOF_FRICTION.replace("0.01", "0.1").replace('"0.1 m"', '"0.01 m"'), "held.toml")
    with pytest.raises(QuickReleaseError, match=r"F_s = 637000 N holds the building there \(restoring force 64108.9 N"):
        synthesize_building(held, ["x", "a_roof"], rate=100.0)


def test_synth_cli_writes_a_2dof_record_and_its_case(tmp_path, monkeypatch):
    """``synth --building`` on a 2dof case: the base's x and the roof's a_roof columns, the written case
    parses back to the same building (superstructure keys included) and reads the record; bad input still
    fails before anything is written."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "two.toml").write_text(TWO_DOF_FRICTION)
    r = runner.invoke(app, ["synth", "two.toml", "--building", "--channels", "x,a_roof", "--rate", "100 Hz",
                            "--duration", "5 s", "--out", "r.csv", "--case-out", "c.toml"])
    assert r.exit_code == 0, r.output
    header = (tmp_path / "r.csv").read_text().splitlines()[0]
    assert header == "t_s,x_m,a_roof_m_s2"
    case = load_case(tmp_path / "c.toml", require_test=False)
    data = load_building(case)
    assert data.isolation == load_building(_case(tmp_path, TWO_DOF_FRICTION, "two2.toml")).isolation
    assert [ch.name for ch in data.channels] == ["x", "a_roof"]
    r = runner.invoke(app, ["synth", "two.toml", "--channels", "x,a_roof", "--rate", "10 Hz", "--out", "new.csv",
                            "--case-out", "new.toml"])
    assert r.exit_code == 2 and "rate = 10 Hz is outside" in r.stderr and "higher mode T_2" in r.stderr, r.stderr
    assert r.stderr.count("\n") == 1
    assert not (tmp_path / "new.csv").exists() and not (tmp_path / "new.toml").exists()
