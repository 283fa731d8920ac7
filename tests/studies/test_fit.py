"""Friction from measured time histories: records, synthetic records, the fit, campaigns (issue: records)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import mp_identify
from typer.testing import CliRunner

from quickrelease.cli import app
from quickrelease.device.solvers import FirstIntegral
from quickrelease.io.case import FitOptions, load_case
from quickrelease.io.records import RecordError, detect_release, load_record, release_channels
from quickrelease.studies.fit import fit_record
from quickrelease.studies.synth import predicted_errors, synthesize

EXAMPLES = Path(__file__).parents[2] / "examples"
runner = CliRunner()


@pytest.fixture(scope="module")
def paper():
    return load_case(EXAMPLES / "paper.toml")


def realistic(case, seed, release_time=0.43, **kw):
    """Paper case, 500 Hz, u and v (0.5 mm) and head acceleration (0.05 m/s^2), offsets, unknown release."""
    return synthesize(case, ["u", "v", "a_head"], rate=500.0, offsets={"u": 1.2e-3, "v": -2.5e-3},
                      release_time=release_time, seed=seed, **kw)


def write_case(tmp_path, record_file, channels, extra="", test=None):
    test = test or 'energy = "2900 J"\nalpha0 = 0.2'
    lines = ["[device]", 'preset = "paper"', "[test]", test, "[record]", f'file = "{record_file}"', 'time = "t_s"',
             "[record.channels]"] + [f"{k} = {v}" for k, v in channels.items()]
    path = tmp_path / "case.toml"
    path.write_text("\n".join(lines) + "\n" + extra)
    return path


SI_CHANNELS = {"u": '{ column = "u_m" }', "v": '{ column = "v_m" }', "a_head": '{ column = "a_head_m_s2" }'}


# -- records made as an instrument would, independently of the fit's channel model (issue 9, item 21) -----

#: The truth of the instrument records: Table 7's inputs and the friction they identify (rounded).
TRUE_F1, TRUE_F2 = 419.85, 804.57


@pytest.fixture(scope="module")
def paper_motion(paper):
    """Eq. 4 (c = 2/3) integrated by solve_ivp (DOP853, rtol 1e-12) to the stop event alpha_dot = 0: the
    motion of the paper's release, written out here from the paper, sharing nothing with the package's
    solvers or its channel model."""
    from scipy.integrate import solve_ivp

    d = paper.device
    k, m2, L1 = 2 / 3 * d.m1 / d.m2, d.m2, d.L1

    def rhs(t, y):
        a, ad = y
        s, co = np.sin(a), np.cos(a)
        den = k + s * s
        return [ad, -ad * ad * s * co / den - (2 * TRUE_F2 * s + TRUE_F1 * co) / (m2 * L1 * den)]

    def stop(t, y):
        return y[1]

    stop.terminal, stop.direction = True, -1
    ad0 = math.sqrt(2900.0 / (m2 * L1**2 * (k + math.sin(0.2) ** 2)))  # E_S = M alpha_dot0^2 (Eq. 5, 9)
    sol = solve_ivp(rhs, (0.0, 10.0), [0.2, ad0], method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True,
                    events=stop)
    return sol, float(sol.t_events[0][0]), rhs, L1


def instrument_channels(motion, release_time, rate=500.0, tail=0.5, oversample=32, displacement_filter=True):
    """u, v and the head acceleration (Table 4) as a data acquisition records them, from the continuous signals
    on a grid ``oversample`` times finer than the record. The accelerometer's channel goes through a
    2nd-order CIC decimator (two cascaded moving averages over a sampling interval: a triangular impulse
    response of +-1 interval, scipy.signal.lfilter), the displacement channels through a 4th-order
    Butterworth anti-alias filter at 0.8 of the Nyquist frequency (zero phase, as a linear-phase ADC filter is
    once its delay is removed; ``displacement_filter=False``: point samples); then every ``oversample``-th
    value is kept. The device rests before the release and after the stop; the acceleration is 0 there (no
    impulse at the release: a real release takes milliseconds)."""
    from scipy import signal

    sol, t_stop, rhs, L1 = motion
    n = int((release_time + t_stop + tail) * rate) * oversample
    tf = np.arange(n) / (rate * oversample)
    a, ad = sol.sol(np.clip(tf - release_time, 0.0, t_stop))
    moving = (tf > release_time) & (tf < release_time + t_stop)
    add = rhs(0.0, (a, ad))[1]
    acc = np.where(moving, L1 * (np.cos(a) * ad**2 + np.sin(a) * add), 0.0)
    box = np.ones(oversample) / oversample
    # CIC-2 of a centred window: the triangle of 2 * oversample - 1 taps, centred by shifting its delay
    cic = signal.lfilter(np.convolve(box, box), [1.0], np.concatenate([acc, np.zeros(oversample - 1)]))
    out = {"a_head": cic[oversample - 1:][::oversample]}
    sos = signal.butter(4, 0.8 * rate / 2, fs=rate * oversample, output="sos")
    for name, x in (("u", L1 * (math.cos(0.2) - np.cos(a))), ("v", L1 * (np.sin(a) - math.sin(0.2)))):
        out[name] = (signal.sosfiltfilt(sos, x) if displacement_filter else x)[::oversample]
    return tf[::oversample], {k: out[k] for k in ("u", "v", "a_head")}


INSTRUMENT_NOISE = {"u": 0.5e-3, "v": 0.5e-3, "a_head": 0.05}
INSTRUMENT_OFFSETS = {"u": 1.2e-3, "v": -2.5e-3, "a_head": 0.0}


def instrument_record(t, clean, seed, missing=0.0):
    """White noise (0.5 mm, 0.05 m/s^2) and offsets on u and v added to the sampled channels; a share
    ``missing`` of the samples lost (NaN)."""
    rng = np.random.default_rng(seed)
    data = {}
    for name, values in clean.items():
        x = values + INSTRUMENT_OFFSETS[name] + rng.normal(0.0, INSTRUMENT_NOISE[name], t.size)
        if missing:
            x[rng.uniform(0.0, 1.0, t.size) < missing] = np.nan
        data[name] = x
    return data


def as_record(t, data):
    from quickrelease.io.records import Channel, ChannelSpec, Record

    channels = {}
    for name, values in data.items():
        ok = np.nonzero(np.isfinite(values))[0]
        spec = ChannelSpec(name=name, column=name, unit="", factor=1.0, noise=INSTRUMENT_NOISE[name],
                           offset=name != "a_head")
        channels[name] = Channel(spec=spec, t=t[ok], values=values[ok], index=ok, missing=int(values.size - ok.size))
    return Record(file=Path("<instrument>"), t=t, channels=channels)


# -- the model of the channels --------------------------------------------------------------------------

def test_channels_follow_the_release_and_rest_before_and_after(paper):
    d = paper.device
    fi = FirstIntegral(2900.0, 0.2, 419.85, 804.57, d.m1, d.m2, d.L1, 2 / 3)
    t = np.array([0.0, 0.29, 0.3 + 0.5, 0.3 + fi.stop_time() + 0.01, 5.0])
    ch = release_channels(["alpha", "u", "v", "u_dot", "a_head"], t, 0.3, fi)
    assert ch["alpha"][0] == 0.2 and ch["u"][0] == 0.0 and ch["a_head"][1] == 0.0
    assert ch["alpha"][-1] == pytest.approx(fi.alpha_final, abs=1e-15) and ch["u_dot"][-1] == 0.0
    assert ch["a_head"][-2] == 0.0  # friction balances inertia at rest
    alpha, alpha_dot = fi.state_at(np.array([0.5]))
    assert ch["u"][2] == pytest.approx(d.L1 * (math.cos(0.2) - math.cos(alpha[0])), rel=1e-13)
    assert ch["u_dot"][2] == pytest.approx(d.L1 * math.sin(alpha[0]) * alpha_dot[0], rel=1e-13)


def test_window_averaged_rates_are_continuous_and_agree_with_point_values_away_from_jumps(paper):
    d = paper.device
    fi = FirstIntegral(2900.0, 0.2, 419.85, 804.57, d.m1, d.m2, d.L1, 2 / 3)
    t = np.linspace(0.35, 1.2, 40)
    point = release_channels(["u_dot", "a_head"], t, 0.3, fi)
    avg = release_channels(["u_dot", "a_head"], t, 0.3, fi, window=1e-4)
    np.testing.assert_allclose(avg["u_dot"], point["u_dot"], rtol=1e-6)
    np.testing.assert_allclose(avg["a_head"], point["a_head"], rtol=1e-5, atol=1e-6)
    # a sample straddling the stop moves continuously as the stop moves (the point value jumps)
    t_stop = 0.3 + fi.stop_time()
    shifted = [release_channels(["a_head"], np.array([t_stop]), 0.3 + dt, fi, window=2e-3)["a_head"][0]
               for dt in (-1e-7, 0.0, 1e-7)]
    assert abs(shifted[0] - shifted[2]) < 1e-3


# -- round trips -------------------------------------------------------------------------------------------

def test_round_trip_through_a_csv_file_within_one_percent(paper, paper_motion, tmp_path):
    """An instrument record (solve_ivp motion, Table 4, anti-alias filter, noise, offsets, 1% lost samples)
    written to CSV and fitted through the case file, noise levels estimated from the pre-release segment."""
    t, clean = instrument_channels(paper_motion, 0.43)
    data = instrument_record(t, clean, seed=3, missing=0.01)
    columns = {"t_s": t, "u_m": data["u"], "v_m": data["v"], "a_head_m_s2": data["a_head"]}
    np.savetxt(tmp_path / "rec.csv", np.column_stack(list(columns.values())), delimiter=",",
               header=",".join(columns), comments="", fmt="%.17g")
    case = load_case(write_case(tmp_path, "rec.csv", SI_CHANNELS))
    fit = fit_record(case)
    assert fit.converged
    for name, truth in (("F1", TRUE_F1), ("F2", TRUE_F2)):
        assert fit.estimates[name] == pytest.approx(truth, rel=0.01)
        lo, hi = fit.ci95[name]
        assert lo < truth < hi
    assert fit.release_time == pytest.approx(0.43, abs=2e-4)  # unknown instant, a tenth of a sample
    assert fit.offsets()["u"] == pytest.approx(1.2e-3, abs=2e-4)
    assert fit.noise_source["u"] == "pre-release segment" and fit.noise["u"] == pytest.approx(5e-4, rel=0.2)
    assert fit.chi2_reduced == pytest.approx(1.0, abs=0.15)
    # the intervals are labelled 95%: +- the Student t quantile (scipy.stats) times the standard error
    from scipy.stats import t as student

    q = student.ppf(0.975, sum(fit.samples.values()) - len(fit.names))
    lo, hi = fit.ci95["release_time"]
    assert 0.5 * (hi - lo) == pytest.approx(q * fit.std_errors["release_time"], rel=1e-9)
    # missing samples are reported and skipped, never interpolated
    lost = sum(int(np.isnan(v).sum()) for v in data.values())
    assert lost > 0 and sum(fit.samples.values()) == 3 * t.size - lost


@pytest.mark.slow
def test_coverage_of_the_95_percent_intervals(paper, paper_motion):
    """The 95% intervals of fits to 100 instrument records (made independently of the fit's channel model:
    see instrument_channels) cover the truth.

    Design, sized against a 90% interval sold as 95%: each interval gives zeta = 1.96 (estimate - truth) /
    half-width, standard normal for a true 95% interval, and zeta^2 is pooled over 5 parameters (F1, F2,
    release time, offsets of u and v) and 100 noise seeds: 500 values, about 300 independent ones (F1 and F2
    are nearly collinear), so mean zeta^2 = 1 +- 0.08 for true 95% intervals. A 90% interval sold as 95% is
    1.645/1.96 as wide: mean zeta^2 = 1.42 +- 0.12. The count of hits adds a binomial check: 475 +- 5 of 500
    for 95% intervals, 450 +- 7 for 90% ones. Measured on this machine: mean zeta^2 = 1.13 and 1.09 to 1.27
    over four other sets of 100 seeds (synth's records included), i.e. the fit's intervals cover ~93.5%
    (its linearised covariance is ~7% narrow, mostly in the release time and the offsets); the band's upper
    edge, 1.35, sits between that and the 90% alternative, and the 90% quantile planted in fit.py (1.60 here)
    fails both checks. 100 fits: ~30 s of CPU."""
    from scipy.stats import norm

    z975 = norm.ppf(0.975)
    names = ("F1", "F2", "release_time", "offset_u", "offset_v")
    zeta2, hits = [], 0
    channels = {}
    for seed in range(100):
        release_time = 0.4 + 0.29e-3 * (seed % 7)  # the release moves across the sampling grid
        if release_time not in channels:
            channels[release_time] = instrument_channels(paper_motion, release_time)
        t, clean = channels[release_time]
        fit = fit_record(paper, as_record(t, instrument_record(t, clean, seed=seed)))
        assert fit.converged
        assert abs(fit.F1 / TRUE_F1 - 1) < 0.01 and abs(fit.F2 / TRUE_F2 - 1) < 0.01
        truth = {"F1": TRUE_F1, "F2": TRUE_F2, "release_time": release_time, "offset_u": 1.2e-3, "offset_v": -2.5e-3}
        for name in names:
            lo, hi = fit.ci95[name]
            zeta2.append((z975 * (fit.estimates[name] - truth[name]) / (0.5 * (hi - lo))) ** 2)
            hits += lo <= truth[name] <= hi
    mean = float(np.mean(zeta2))
    assert 0.8 < mean < 1.35, mean
    assert 460 <= hits, hits


@pytest.mark.slow
def test_predicted_errors_are_the_fit_errors_at_the_truth(paper):
    syn = realistic(paper, seed=0, release_time=0.4011)
    pred = predicted_errors(paper, syn)
    fit = fit_record(paper, syn.record())
    assert pred["F1_se_N"] == pytest.approx(fit.std_errors["F1"], rel=0.1)
    assert pred["correlation_F1_F2"] == pytest.approx(fit.correlation[0, 1], abs=0.01)
    from quality import figure_faults  # the figure of such a fit: residual axes with units, lines in legends

    from quickrelease.report.plots import fit_figure

    assert figure_faults(fit_figure(fit)) == []


@pytest.mark.slow
def test_energy_and_mass_factor_can_be_estimated(paper):
    case = paper.replace(mass_model=0.7, stored_energy=3100.0)  # the truth the record is made with
    syn = realistic(case, seed=5)
    fit = fit_record(paper, syn.record(), options=FitOptions(estimate_energy=True, estimate_mass_factor=True))
    assert fit.converged and set(fit.names) >= {"energy", "mass_factor"}
    truth = {"energy": 3100.0, "mass_factor": 0.7, "F1": syn.truth["F1"], "F2": syn.truth["F2"]}
    for name, value in truth.items():
        assert abs(fit.estimates[name] - value) < 3 * fit.std_errors[name], name
    # four unknowns that trade off (E_S and c against the friction) cost precision: F1 is known far less well
    fixed = fit_record(case, syn.record())
    assert fit.std_errors["F1"] > 10 * fixed.std_errors["F1"]
    assert abs(fixed.F1 - syn.truth["F1"]) < 3 * fixed.std_errors["F1"]


def test_units_and_scale_of_the_columns(paper, tmp_path):
    syn = realistic(paper, seed=7)
    cols = syn.columns()
    lines = ["time_ms,u_mm,v_mm,acc_g"]
    for k in range(syn.t.size):
        lines.append(f"{float(1e3 * cols['t_s'][k])!r},{float(1e3 * cols['u_m'][k])!r},"
                     f"{float(1e3 * cols['v_m'][k])!r},{float(-cols['a_head_m_s2'][k] / 9.80665)!r}")
    (tmp_path / "rec.csv").write_text("\n".join(lines) + "\n")
    path = write_case(tmp_path, "rec.csv", {"u": '{ column = "u_mm", unit = "mm" }',
                                            "v": '{ column = "v_mm", unit = "mm" }',
                                            "a_head": '{ column = "acc_g", unit = "g0", scale = -1 }'})
    path.write_text(path.read_text().replace('time = "t_s"', 'time = { column = "time_ms", unit = "ms" }'))
    fit = fit_record(load_case(path))
    reference = fit_record(paper, syn.record())
    assert fit.F1 == pytest.approx(reference.F1, rel=2e-3) and fit.F2 == pytest.approx(reference.F2, rel=2e-3)


def test_parquet_records(paper, tmp_path):
    pytest.importorskip("pyarrow")
    syn = realistic(paper, seed=8)
    syn.to_pandas().to_parquet(tmp_path / "rec.parquet")
    fit = fit_record(load_case(write_case(tmp_path, "rec.parquet", SI_CHANNELS)))
    assert fit.F1 == pytest.approx(syn.truth["F1"], rel=0.01)


def test_video_angle_alone_and_acceleration_alone(paper):
    video = synthesize(paper, ["alpha"], rate=25.0, release_time=0.5, seed=1)
    fit = fit_record(paper, video.record())
    assert fit.F1 == pytest.approx(video.truth["F1"], rel=0.2) and fit.converged
    accel = synthesize(paper, ["a_head"], rate=500.0, release_time=0.5, seed=1)
    fit = fit_record(paper, accel.record())
    assert fit.start_source.startswith("stop observations")  # the case's [observations] give the start
    assert fit.F2 == pytest.approx(accel.truth["F2"], rel=0.05)


def test_start_without_stop_observations_scans_the_final_angle(paper):
    case = paper.replace(alpha_final=None, stop_time=None, F1=419.85, F2=804.57)
    syn = synthesize(case, ["a_head"], rate=500.0, release_time=0.5, seed=2)
    fit = fit_record(case, syn.record())
    assert fit.start_source == "scan over alpha_F with t_F read off the record"
    assert fit.F1 == pytest.approx(419.85, rel=0.05) and fit.F2 == pytest.approx(804.57, rel=0.02)


def test_release_detection_within_a_few_samples(paper):
    syn = realistic(paper, seed=9, release_time=0.777)
    assert detect_release(syn.record()) == pytest.approx(0.777, abs=3 / 500)


# -- stop observations only: the delta method, checked against the uq sensitivities -------------------------

def test_stop_observations_with_scatter_give_delta_method_errors(tmp_path):
    from quickrelease.studies.uq import sensitivities

    text = (EXAMPLES / "paper.toml").read_text().replace(
        'alpha_final = "0.7378 rad"', 'alpha_final = { value = "0.7378 rad", std = "0.01 rad" }').replace(
        'stop_time = "1.05 s"', 'stop_time = { value = "1.05 s", std = "0.006 s" }')
    path = tmp_path / "stop.toml"
    path.write_text(text)
    case = load_case(path)
    fit = fit_record(case)
    ift, _ = sensitivities(case)
    for name in ("F1", "F2"):
        expected = math.hypot(ift[name]["alpha_final"] * 0.01, ift[name]["stop_time"] * 0.006)
        assert fit.std_errors[name] == pytest.approx(expected, rel=1e-3)
    assert fit.F1 == pytest.approx(419.8499, rel=1e-6)
    assert any("only the stop observations" in w for w in fit.warnings)
    assert any("poorly determined" in w for w in fit.warnings)


# -- bad records --------------------------------------------------------------------------------------------

def _csv(tmp_path, text, name="rec.csv"):
    (tmp_path / name).write_text(text)
    return name


@pytest.fixture()
def good_rows(paper):
    syn = realistic(paper, seed=11)
    return syn


def _rows(syn, cols=("t_s", "u_m"), t=None):
    c = syn.columns()
    t = c["t_s"] if t is None else t
    lines = [",".join(cols)] + [",".join(repr(float(x)) for x in row)
                                for row in zip(t, *(c[k] for k in cols[1:]), strict=True)]
    return "\n".join(lines) + "\n"


def test_no_time_column(tmp_path, good_rows):
    name = _csv(tmp_path, _rows(good_rows).replace("t_s,", "time,", 1))
    with pytest.raises(RecordError, match=r"rec.csv: no time column 't_s' \(columns: time, u_m\)"):
        load_record(load_case(write_case(tmp_path, name, {"u": '"u_m"'})).record)


def test_time_not_increasing(tmp_path, good_rows):
    t = good_rows.t.copy()
    t[50], t[51] = t[51], t[50]
    name = _csv(tmp_path, _rows(good_rows, t=t))
    with pytest.raises(RecordError, match=r"rec.csv: column 't_s': time is not increasing at row 52"):
        load_record(load_case(write_case(tmp_path, name, {"u": '"u_m"'})).record)


def test_channel_of_the_wrong_length(tmp_path, good_rows):
    name = _csv(tmp_path, _rows(good_rows))
    short = _csv(tmp_path, _rows(good_rows, cols=("t_s", "v_m")).rsplit("\n", 50)[0] + "\n", "v.csv")
    path = write_case(tmp_path, name, {"u": '"u_m"', "v": f'{{ column = "v_m", file = "{short}" }}'})
    with pytest.raises(RecordError, match=r"v.csv: column 'v_m' has \d+ rows, the time column 't_s' of rec.csv has"):
        load_record(load_case(path).record)


def test_channel_with_the_wrong_units(tmp_path, good_rows):
    name = _csv(tmp_path, _rows(good_rows))
    from quickrelease.io.case import CaseFileError

    with pytest.raises(CaseFileError, match=r"case.toml \[record\] channels.u.unit = 'mm/s': has dimension "
                                            r"\[length\] / \[time\]; expected a length \(e.g. in m\)"):
        load_case(write_case(tmp_path, name, {"u": '{ column = "u_m", unit = "mm/s" }'}))


def test_all_missing_channel(tmp_path, good_rows):
    text = _rows(good_rows, cols=("t_s", "u_m", "v_m"))
    lines = text.splitlines()
    lines = [lines[0]] + [",".join(line.split(",")[:2]) + "," for line in lines[1:]]
    name = _csv(tmp_path, "\n".join(lines) + "\n")
    with pytest.raises(RecordError, match=r"rec.csv: column 'v_m' \(channel v\): all values missing"):
        load_record(load_case(write_case(tmp_path, name, {"u": '"u_m"', "v": '"v_m"'})).record)


def test_non_numeric_values(tmp_path, good_rows):
    name = _csv(tmp_path, _rows(good_rows).replace("\n0.02,", "\nabc,", 1))
    with pytest.raises(RecordError, match=r"rec.csv: column 't_s': non-numeric value 'abc' at row 11"):
        load_record(load_case(write_case(tmp_path, name, {"u": '"u_m"'})).record)


def test_record_that_ends_before_the_stop(tmp_path, good_rows):
    keep = good_rows.t < 0.43 + 0.8  # the device stops 1.05 s after the release
    name = _csv(tmp_path, _rows(good_rows, cols=("t_s", "u_m", "v_m")).splitlines()[0] + "\n" + "\n".join(
        _rows(good_rows, cols=("t_s", "u_m", "v_m")).splitlines()[1:][: int(keep.sum())]) + "\n")
    with pytest.raises(RecordError, match=r"rec.csv: the record ends at 1.228 s, before the device stops"):
        fit_record(load_case(write_case(tmp_path, name, {"u": '"u_m"', "v": '"v_m"'})))


def test_rows_without_time_are_dropped_and_reported(tmp_path, good_rows):
    text = _rows(good_rows).splitlines()
    text[20] = "," + text[20].split(",")[1]
    record = load_record(load_case(write_case(tmp_path, _csv(tmp_path, "\n".join(text) + "\n"), {"u": '"u_m"'})).record)
    assert record.dropped_rows == 1 and record.t.size == good_rows.t.size - 1
    assert "1 row(s) without a time value dropped" in record.notes[0]


def test_bad_record_on_the_command_line_is_one_line_exit_2(tmp_path, good_rows):
    name = _csv(tmp_path, _rows(good_rows).replace("t_s,", "time,", 1))
    result = runner.invoke(app, ["fit", str(write_case(tmp_path, name, {"u": '"u_m"'}))])
    assert result.exit_code == 2
    assert result.output.count("\n") == 1 and "no time column 't_s'" in result.output


# -- the command line and the shipped example ---------------------------------------------------------------

def test_fit_example_json_keys_and_truth():
    result = runner.invoke(app, ["fit", str(EXAMPLES / "fit.toml"), "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    for key in ("F1_N", "F2_N", "F1_ci95_N", "F2_ci95_N", "release_time_s", "residual_rms", "converged"):
        assert key in data
    assert data["converged"] is True
    assert set(data["residual_rms"]) == {"u", "v", "a_head"}
    # the record was made with the friction identified from Table 7's inputs (examples/make_records.py)
    for key, truth in zip(("F1", "F2"), mp_identify(2900, 0.2, 0.7378, 1.05), strict=True):
        lo, hi = data[f"{key}_ci95_N"]
        assert lo < truth < hi
    assert data["release_time_s"] == pytest.approx(0.62, abs=2e-4)


@pytest.mark.slow
def test_synth_then_fit_on_the_command_line(tmp_path):
    rec, case = tmp_path / "rec.csv", tmp_path / "fit_case.toml"
    result = runner.invoke(app, ["synth", str(EXAMPLES / "paper.toml"), "--channels", "u,v", "--rate", "200 Hz",
                                 "--noise", "u=1 mm,v=1 mm", "--offset", "u=2 mm", "--release-time", "0.3 s",
                                 "--out", str(rec), "--case-out", str(case), "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["noise"] == {"u": 1e-3, "v": 1e-3} and data["offsets"]["u"] == 2e-3
    assert data["predicted"]["F1_se_N"] > 0
    out = tmp_path / "out"
    result = runner.invoke(app, ["fit", str(case), "--out", str(out)])
    assert result.exit_code == 0, result.output
    fit = json.loads((out / "fit.json").read_text())
    assert abs(fit["F1_N"] - 419.8499) < 4 * fit["F1_se_N"]
    report = (out / "report.html").read_text()
    assert 'id="fit-F1"' in report and '<figure id="fit_channels"><svg' in report
    from quality import report_number_faults

    assert report_number_faults(report) == []
    assert (out / "figures" / "fit_channels.png").stat().st_size > 20_000


# -- campaigns ------------------------------------------------------------------------------------------------

def test_campaign_recovers_the_load_law(tmp_path):
    result = runner.invoke(app, ["campaign", str(EXAMPLES / "campaign.toml"), "--json", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    laws = {(law["friction"], law["variable"]): law for law in data["laws"]}
    f1p = laws[("F1", "force")]
    # the synthetic records follow F1 = 150 N + 0.17 N/kN P, F2 = 805 N (examples/make_records.py)
    assert abs(f1p["b_N_per_N"] - 0.17e-3) < 3 * f1p["b_se_N_per_N"] and f1p["significant_5pct"]
    assert abs(f1p["a_N"] - 150.0) < 3 * f1p["a_se_N"]
    assert not laws[("F2", "force")]["significant_5pct"]
    joint = data["joint"]["F1"]["terms"]
    assert joint["force"]["significant_5pct"] and not joint["alpha0"]["significant_5pct"]
    assert len(data["tests"]) == 6 and all(t["method"] == "fit to record" for t in data["tests"])
    report = (tmp_path / "report.html").read_text()
    assert '<figure id="campaign_friction"><svg' in report and "T6" in report
    import hashlib

    prov = json.loads((tmp_path / "campaign.json").read_text(encoding="utf-8"))["provenance"]
    assert prov["input"]["sha256"] == hashlib.sha256((EXAMPLES / "campaign.toml").read_bytes()).hexdigest()


def test_campaign_law_arithmetic():
    from quickrelease.studies.campaign import CampaignTest, fit_law

    class FakeCase:
        def __init__(self, P):
            self.push_force, self.alpha0, self.stored_energy, self.source = P, 0.2, 1.0, "x"

    xs = np.array([1.0, 2.0, 3.0, 4.0])
    ys = 2.0 + 0.5 * xs + np.array([0.1, -0.1, -0.1, 0.1])
    tests = [CampaignTest(name=f"T{i}", case=FakeCase(x), F1=y, F2=1.0, F1_se=None, F2_se=None, method="x")
             for i, (x, y) in enumerate(zip(xs, ys, strict=True))]
    law = fit_law(tests, "F1", "force")
    slope, intercept = np.polyfit(xs, ys, 1)
    assert law.slope == pytest.approx(slope) and law.intercept == pytest.approx(intercept)
    resid = ys - (intercept + slope * xs)
    s2 = resid @ resid / 2
    assert law.slope_se == pytest.approx(math.sqrt(s2 / np.sum((xs - xs.mean()) ** 2)))
    mean, lo, hi = law.band(xs.mean())
    assert mean == pytest.approx(ys.mean()) and hi - mean == pytest.approx(4.302652729749464 * math.sqrt(s2 / 4))


def test_campaign_errors(tmp_path):
    from quickrelease.io.case import CaseFileError
    from quickrelease.studies.campaign import run_campaign

    path = tmp_path / "c.toml"
    path.write_text('[[tests]]\nname = "A"\nforce = "1 MN"\nalpha0 = 0.2\nalpha_final = 0.6\nstop_time = 1\n'
                    '[[tests]]\nname = "B"\nforce = "1 MN"\nalpha0 = 0.2\nalpha_final = 0.6\nstop_time = 1\n')
    with pytest.raises(Exception, match="2 test\\(s\\): a friction law needs at least 3"):
        run_campaign(path)
    path.write_text('[[tests]]\nname = "A"\nforse = "1 MN"\n')
    with pytest.raises(CaseFileError, match="test A: unknown key 'forse'"):
        run_campaign(path)


def test_a_channel_in_its_own_file_at_its_own_rate(paper, tmp_path):
    """The accelerometer logged by another acquisition: its own file, time column (ms) and rate (200 Hz
    beside the 250 Hz displacements), its own length; the fit evaluates it on its own time axis."""
    disp = synthesize(paper, ["u", "v"], rate=250.0, offsets={"u": 1.2e-3, "v": -2.5e-3}, release_time=0.43, seed=11)
    acc = synthesize(paper, ["a_head"], rate=200.0, release_time=0.43, seed=12, duration=2.2)
    disp.to_pandas().to_csv(tmp_path / "disp.csv", index=False)
    (tmp_path / "acc.csv").write_text("t_acc_ms,acc_g\n" + "".join(
        f"{float(1e3 * t)!r},{float(a / 9.80665)!r}\n" for t, a in zip(acc.t, acc.data["a_head"], strict=True)))
    path = write_case(tmp_path, "disp.csv", {
        "u": '{ column = "u_m" }', "v": '{ column = "v_m" }',
        "a_head": '{ column = "acc_g", unit = "g0", file = "acc.csv", time = { column = "t_acc_ms", unit = "ms" } }'})
    case = load_case(path)
    record = load_record(case.record)
    a = record.channels["a_head"]
    assert a.t.size == acc.t.size != record.t.size and a.sampling_interval(record.t) == pytest.approx(5e-3)
    fit = fit_record(case, record)
    assert fit.F1 == pytest.approx(disp.truth["F1"], rel=0.02) and fit.F2 == pytest.approx(disp.truth["F2"], rel=0.01)
    # the accelerometer's residuals are its noise: the model was evaluated at its own instants and window
    assert fit.residual_rms["a_head"] == pytest.approx(acc.noise["a_head"], rel=0.1)
    assert fit.residual_rms["u"] == pytest.approx(disp.noise["u"], rel=0.1)
    # a time column beside a channel in the record's own file is refused, naming the key
    bad = write_case(tmp_path, "disp.csv", {"u": '{ column = "u_m", time = "t_s" }'})
    with pytest.raises(Exception, match=r"\[record\] channels.u: time = 't_s' without file"):
        load_case(bad)


@pytest.mark.slow
def test_iterations_from_a_poor_start_do_not_grow_with_the_sampling_rate(paper, monkeypatch):
    """Issue 9 item 11: a start 10% off in F1 and F2 and 3 ms off in the release put the model's stop tens of
    ms (hundreds of samples) from the record's; the acceleration's jump at the stop, spread over +-Delta,
    then moved a few samples per iteration, so model evaluations grew with the rate (u, v, a_head: 1e4
    rows 47, 3e4 119, 1e5 364; a_head alone: 5e3 rows 106, 2e4 406). From the same start, 4x the rate must
    cost about the same number of evaluations, and both fits must reach the minimum found from the truth,
    which is within 4 standard errors of it. The acceleration alone checks that the coarse stages widen
    the window (decimating alone left its jumps between samples: 25 and 107 evaluations)."""
    import quickrelease.studies.fit as fit_module

    start = fit_module._start

    def poor_start(problem):
        x, how = start(problem)
        x = x.copy()
        x[0] *= 1.1
        x[1] *= 0.9
        x[problem.index["release_time"]] += 3e-3
        return x, how

    for channels in (["u", "v", "a_head"], ["a_head"]):
        nfev = {}
        for rows in (5_000, 20_000):
            syn = synthesize(paper, channels, rate=rows / 2.2, duration=2.2, release_time=0.5, seed=1)
            record = syn.record()
            good = fit_record(paper, record)
            with monkeypatch.context() as m:
                m.setattr(fit_module, "_start", poor_start)
                fit = fit_record(paper, record)
            assert fit.converged
            nfev[rows] = fit.nfev
            for name in ("F1", "F2", "release_time"):
                if name != "release_time":
                    assert abs(fit.estimates[name] - syn.truth[name]) < 4 * fit.std_errors[name], (channels, rows)
                assert fit.estimates[name] == pytest.approx(good.estimates[name], abs=0.05 * fit.std_errors[name])
        assert nfev[20_000] <= 1.5 * nfev[5_000] + 5, (channels, nfev)


def test_a_heavy_device_fits_as_the_paper_device(paper, paper_motion):
    """scipy's step tolerance (xtol) compares the step's norm with xtol times the norm of all the parameters in
    their own units: a friction force of 4e6 N beside a release instant known to a few microseconds. The same instrument
    record (solve_ivp motion at 5 kHz: the coarse stages run) fitted for the paper's device and for one with its
    masses and E_S 1e4 times larger (the same motion under friction 1e4 times larger): F / 1e4, the release
    instant and the offsets where the paper device's fit put them (measured: within 1e-6 standard errors), the
    standard errors of F 1e4 times larger, and the truth within 4 of them. The step test does not bite here: the
    forces, the release and the offsets move together, so no step is small for F and still large for the
    release (with xtol raised to 1e-5 in every solve both fits ended on it, within 6e-6 standard errors of each
    other). A guard: the record fit keeps scipy's tolerances in the parameters' own units."""
    from dataclasses import replace

    t, clean = instrument_channels(paper_motion, 0.43, rate=5000.0)
    record = as_record(t, instrument_record(t, clean, seed=5))
    k = 1e4
    heavy = replace(paper, device=replace(paper.device, m1=paper.device.m1 * k, m2=paper.device.m2 * k),
                    stored_energy=paper.stored_energy * k)
    light, big = fit_record(paper, record), fit_record(heavy, record)
    assert light.converged and big.converged and light.names == big.names
    for name in light.names:
        unit = k if name in ("F1", "F2") else 1.0
        se = light.std_errors[name]
        assert abs(big.estimates[name] / unit - light.estimates[name]) < 1e-3 * se, name
        assert big.std_errors[name] / unit == pytest.approx(se, rel=1e-3), name
    for name, truth in (("F1", TRUE_F1), ("F2", TRUE_F2)):
        assert abs(light.estimates[name] - truth) < 4 * light.std_errors[name], name
    assert abs(light.release_time - 0.43) < 4 * light.std_errors["release_time"]
